"""The limits of the C core that the diagnosed model's native forms respect, in one place.

The forward stream and the DiagnosedModel FMU unit (``fmu/src/pim_diagnosed.h``,
:mod:`.native_model`) and the feedforward and the DiagnosedInverse FMU unit
(``fmu/src/pim_diag_inverse.h``, :mod:`.native_inverse`) refuse larger models; the Python side
checks these first so that the error names the parameter. The values are the C core's
(:data:`pimodel._native.LIMITS`), never retyped.

Examples
--------
>>> from pimodel.diagnosis.limits import MAX_DELAY, NMAX
>>> 2 * NMAX, MAX_DELAY  # plays of a diagnosed unit, longest delay [samples]
(128, 4094)
"""

from __future__ import annotations

from .._native import LIMITS

__all__ = ["MAX_DELAY", "MAX_ELEMENTS", "MAX_LATENCY", "MAX_ORDER", "MAX_SECTIONS", "NMAX",
           "SECTION"]

NMAX = LIMITS["PIM_MAX_PLAYS"]  # array size per FMU variable (p[1..64]); diagnosed units: 2 NMAX
MAX_ELEMENTS = LIMITS["PIM_DIAG_MAX_ELEMENTS"]  # further elements of the linear part (and Wiener)
MAX_DELAY = LIMITS["PIM_DIAG_MAX_DELAY"] - 2  # samples: the delay line keeps two more
MAX_ORDER = LIMITS["PIM_DIAG_MAX_ORDER"]  # LTI order
SECTION = LIMITS["PIM_DIAG_SECTION"]  # coefficients per section of a further element
MAX_SECTIONS = LIMITS["PIM_DINV_MAX_SECTIONS"]  # prefilter sections of the feedforward
MAX_LATENCY = LIMITS["PIM_DINV_MAX_LATENCY"]  # samples
