"""Model files: one JSON format for every model, one schema, and the object they hold.

Modules:

schema      -- check_model_dict: types, ranges, finiteness, required and unknown keys, lengths
codec       -- model_to_dict / model_from_dict: an operator's JSON form
file_model  -- Model (operator + offset, sample time, units, provenance) and ModelInverse
files       -- load_model / save_model / provenance
fmu_limits  -- check_fmu_limits: the FMU's play limits ("at most N plays")

A file: ``{"type": "PIOperator", "weights": [...], "radii": [...], "offset": 0.3, "dt": 0.005,
"units": {"time": "s", "input": "V", "output": "um"}, "provenance": {"record": "lab.csv",
"method": "adaptive", "date": "...", "pimodel_version": "..."}, "report": {...},
"format_version": 2}`` (docs/model-files.md lists every type's keys).

Examples
--------
>>> import os, tempfile
>>> from pimodel import PIOperator
>>> path = save_model(Model(PIOperator([1.0], [0.0]), offset=0.5),
...                   os.path.join(tempfile.mkdtemp(), "m.json"))
>>> load_model(path).simulate([1.0]).tolist()
[1.5]
"""

from __future__ import annotations

from .codec import model_from_dict, model_to_dict
from .file_model import Model, ModelInverse
from .files import load_model, provenance, save_model
from .schema import FORMAT_VERSION, check_model_dict

__all__ = ["FORMAT_VERSION", "Model", "ModelInverse", "check_model_dict", "load_model",
           "model_from_dict", "model_to_dict", "provenance", "save_model"]
