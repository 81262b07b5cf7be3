"""Reading and writing model files: :func:`load_model`, :func:`save_model`, :func:`provenance`.

A model file is one JSON object (:mod:`.schema`): an operator's form with a ``"type"`` plus the
file's ``offset``, ``dt``, ``units``, ``provenance`` and ``report``. ``pimodel identify --json``,
``pimodel diagnose --export`` and :func:`save_model` write it; :func:`load_model`,
``pimodel simulate --model`` and ``pimodel fmu build --model`` read it. An identify JSON of
pimodel 0.1 (``method``, ``weights``, ``radii``, ``offset``, no ``type``) is converted on load
with a warning.
"""

from __future__ import annotations

import datetime
import json
import warnings
from pathlib import Path

from .file_model import Model

__all__ = ["LEGACY_IDENTIFY_KEYS", "load_model", "provenance", "save_model"]

LEGACY_IDENTIFY_KEYS = ("method", "n_plays", "weights", "radii", "offset", "fit")
"""The keys that mark an identify JSON written before the model file format (no ``type``)."""


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("pimodel")
    except Exception:  # not installed (a source tree on sys.path)
        return "unknown"


def provenance(**fields) -> dict:
    """Where a model came from: ``fields`` (``record``, ``columns``, ``method``, ``source``)
    plus ``date`` (UTC, ISO 8601) and ``pimodel_version``.

    Parameters
    ----------
    **fields
        Strings (``columns``: a list of strings); None values are left out.

    Returns
    -------
    dict

    Examples
    --------
    >>> sorted(provenance(method="adaptive"))
    ['date', 'method', 'pimodel_version']
    """
    out = {k: v for k, v in fields.items() if v is not None}
    out.setdefault("date", datetime.datetime.now(datetime.timezone.utc)
                   .isoformat(timespec="seconds"))
    out.setdefault("pimodel_version", _version())
    return out


def _legacy_identify(d: dict, path: Path) -> dict:
    warnings.warn(f"{path}: an identify JSON of an older pimodel (no 'type'); read as a "
                  "PIOperator with its offset. Rewrite it in the model file format with "
                  "pimodel.model_files.save_model(load_model(path), path)", UserWarning,
                  stacklevel=3)
    report = {k: v for k, v in d.items() if k not in ("weights", "radii", "offset")}
    out = {"type": "PIOperator", "weights": d["weights"], "radii": d["radii"],
           "offset": d["offset"], "report": report, "format_version": 1}
    if isinstance(d.get("method"), str):
        out["provenance"] = {"method": d["method"]}
    return out


def load_model(path) -> Model:
    """Read a model file, check it against the schema and rebuild it.

    Parameters
    ----------
    path : str or Path
        A file written by :func:`save_model`, ``pimodel identify --json`` or ``pimodel diagnose
        --export`` (or by hand in the same form; module docstring).

    Returns
    -------
    Model
        The operator with its offset, sample time, units and provenance; ``simulate`` and
        ``inverse`` include the offset; other attributes are the operator's.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        Not JSON, or not a valid model: the message names the file, the key and what was
        expected (:func:`.schema.check_model_dict`).

    Examples
    --------
    >>> import os, tempfile
    >>> from pimodel.operators.creep import CreepOperator
    >>> path = save_model(CreepOperator([0.05], [0.1], dt=1e-3),
    ...                   os.path.join(tempfile.mkdtemp(), "creep.json"))
    >>> load_model(path).gains
    array([0.05])
    """
    p = Path(path)
    try:
        d = json.loads(p.read_text())
    except json.JSONDecodeError as err:
        raise ValueError(f"{p}: not JSON ({err})") from None
    except UnicodeDecodeError as err:
        raise ValueError(f"{p}: not a UTF-8 text file (byte {err.start}); expected a model "
                         "JSON file") from None
    if isinstance(d, dict) and "type" not in d and all(k in d for k in LEGACY_IDENTIFY_KEYS):
        d = _legacy_identify(d, p)
    try:
        return Model.from_dict(d)
    except ValueError as err:
        raise ValueError(f"{p}: {err}") from None


def save_model(model, path, *, offset: float | None = None, dt: float | None = None,
               units: dict | None = None, source: dict | None = None,
               report: dict | None = None) -> Path:
    """Write ``model`` as a model file (module docstring) and return the path.

    Parameters
    ----------
    model : object
        A :class:`Model`, an operator, an inverse, a Cascade, a DiagnosedModel or the result of
        :func:`pimodel.identify` (its operator, offset, method and report).
    path : str or Path
        The JSON file to write (overwritten).
    offset, dt : float, optional
        Output offset and sample time (default: the Model's; an operator: 0 and none).
    units : dict, optional
        ``time``, ``input``, ``output`` unit names.
    source : dict, optional
        Provenance fields (``record``, ``columns``, ``method``, ``source``); ``date`` and
        ``pimodel_version`` are added (:func:`provenance`).
    report : dict, optional
        What the method reported.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        The result would not load (checked before writing: the message names the key).

    Examples
    --------
    >>> import json, os, tempfile
    >>> from pimodel.operators.creep import CreepOperator
    >>> path = save_model(CreepOperator([0.05], [0.1], dt=1e-3),
    ...                   os.path.join(tempfile.mkdtemp(), "creep.json"), offset=0.5)
    >>> d = json.loads(path.read_text())
    >>> d["type"], d["offset"], d["format_version"]
    ('CreepOperator', 0.5, 2)
    """
    if not isinstance(model, Model) and callable(getattr(model, "to_json", None)) \
            and hasattr(model, "operator") and hasattr(model, "offset"):  # identify's result
        model = Model(model.operator, offset=model.offset, report=model.to_json(),
                      provenance={"method": str(getattr(model, "method", ""))})
    m = model if isinstance(model, Model) else Model(model)
    m = Model(m.operator, offset=m.offset if offset is None else offset,
              dt=m.dt if dt is None else dt, units={**m.units, **(units or {})},
              provenance=provenance(**{**m.provenance, **(source or {})}),
              report=m.report if report is None else report)
    d = m.as_file_dict()
    Model.from_dict(json.loads(json.dumps(d)), where=f"{path}: model")
    p = Path(path)
    p.write_text(json.dumps(d, indent=2) + "\n")
    return p
