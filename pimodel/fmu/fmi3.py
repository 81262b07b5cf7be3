"""Deprecated alias: the FMI 3.0 model descriptions are written by
:mod:`pimodel.fmu.description` (one writer for FMI 2.0 and 3.0), the instantiation token comes
from :mod:`pimodel.fmu.spec`. Kept one release for ``from pimodel.fmu.fmi3 import ...``.

Examples
--------
>>> from pimodel.fmu.description import model_description
>>> model_description3("PIHysteresis") == model_description("PIHysteresis", "3.0")
True
"""

from __future__ import annotations

import warnings

from .description import PLATFORM as _PLATFORMS
from .description import TYPES, model_description3
from .spec import token

__all__ = ["PLATFORM", "TYPES", "model_description3", "token"]

PLATFORM = _PLATFORMS["3.0"]

warnings.warn("pimodel.fmu.fmi3 is deprecated: use pimodel.fmu.description.model_description("
              "name, '3.0') and pimodel.fmu.spec.token", DeprecationWarning, stacklevel=2)
