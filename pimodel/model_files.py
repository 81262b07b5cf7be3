"""JSON form of the operators: :func:`model_to_dict`, :func:`model_from_dict`, :func:`load_model`
and :func:`save_model`.

Format: one JSON object with a ``"type"``; the other keys are the operator's ``to_dict()``
(constructor arguments)::

    {"type": "GeneralizedPI", "weights": [...], "radii": [...], "initial_state": [...],
     "signed_weights": false, "input_envelope": {"kind": "tanh", "coefficients": [...]},
     "output_envelope": {...}}
    {"type": "AsymmetricPI", "direct_weight": 0.5, "weights": [...], "radii": [...],
     "ascending": [a_l, d_l], "descending": [a_r, d_r], "shape": {...}, "initial_state": [...]}
    {"type": "RateDependentPI", "weights": [...], "base_radii": [...], "rate_gain": ..., "dt": ...,
     "rate_time_constant": ..., "initial_state": [...], "initial_input": ...}
    {"type": "CreepOperator", "gains": [...], "time_constants": [...], "dt": ...,
     "initial_state": [...], "inverted": false}
    {"type": "PIOperator", "weights": [...], "radii": [...], "initial_state": [...]}
    {"type": "Inverse", "operator": {...}}          the exact inverse of the operator
    {"type": "Cascade", "stages": [{...}, ...]}     operators in series, first applied first
    {"type": "DiagnosedModel", ...}                 a diagnosis' model (its ``to_dict()``;
                                                    pimodel.diagnosis.model.DiagnosedModel)
"""

from __future__ import annotations

import json
from pathlib import Path

from .operators.asymmetric import AsymmetricPI, AsymmetricPIInverse
from .operators.cascade import Cascade
from .operators.creep import CreepOperator
from .operators.envelopes import Envelope
from .operators.generalized import GeneralizedPI
from .operators.pi import PIOperator
from .operators.rate_dependent import RateDependentPI, RateDependentPIInverse

__all__ = ["load_model", "model_from_dict", "model_to_dict", "save_model"]


def _envelope(d, where: str) -> Envelope:
    if not isinstance(d, dict) or set(d) != {"kind", "coefficients"}:
        raise ValueError(f"{where}: expected {{'kind': ..., 'coefficients': [...]}}, got {d!r}")
    return Envelope(d["kind"], d["coefficients"])


def _build(kind: str, d: dict, where: str):
    if kind == "GeneralizedPI":
        return GeneralizedPI(d["weights"], d["radii"],
                             input_envelope=_envelope(d["input_envelope"],
                                                      f"{where}.input_envelope"),
                             output_envelope=_envelope(d["output_envelope"],
                                                       f"{where}.output_envelope"),
                             initial_state=d.get("initial_state", 0.0),
                             signed_weights=bool(d.get("signed_weights", False)))
    if kind == "AsymmetricPI":
        return AsymmetricPI(d["direct_weight"], d["weights"], d["radii"],
                            ascending=d.get("ascending", (1.0, 0.0)),
                            descending=d.get("descending", (1.0, 0.0)),
                            shape=_envelope(d["shape"], f"{where}.shape") if "shape" in d
                            else None, initial_state=d.get("initial_state", 0.0))
    if kind == "RateDependentPI":
        return RateDependentPI(d["weights"], d["base_radii"], rate_gain=d["rate_gain"],
                               dt=d["dt"], rate_time_constant=d.get("rate_time_constant", 0.0),
                               initial_state=d.get("initial_state", 0.0),
                               initial_input=d.get("initial_input", 0.0))
    if kind == "CreepOperator":
        return CreepOperator(d["gains"], d["time_constants"], dt=d["dt"],
                             initial_state=d.get("initial_state", 0.0),
                             inverted=bool(d.get("inverted", False)))
    if kind == "PIOperator":
        return PIOperator(d["weights"], d["radii"], initial_state=d.get("initial_state", 0.0))
    if kind == "Inverse":
        return model_from_dict(d["operator"], where=f"{where}.operator").inverse()
    if kind == "Cascade":
        stages = d["stages"]
        if not isinstance(stages, list) or not stages:
            raise ValueError(f"{where}.stages: expected a non-empty list of operators")
        return Cascade(*(model_from_dict(s, where=f"{where}.stages[{i}]")
                         for i, s in enumerate(stages)))
    if kind == "DiagnosedModel":
        from .diagnosis.model import DiagnosedModel

        return DiagnosedModel.from_dict(d)
    raise ValueError(f"{where}.type: unknown model type {kind!r}; expected one of {TYPES}")


TYPES = ("GeneralizedPI", "AsymmetricPI", "RateDependentPI", "CreepOperator", "PIOperator",
         "Inverse", "Cascade", "DiagnosedModel")


def model_from_dict(d: dict, *, where: str = "model"):
    """Rebuild an operator, an inverse or a :class:`~pimodel.operators.cascade.Cascade` from its
    JSON form.

    Parameters
    ----------
    d : dict
        The JSON object (module docstring).
    where : str
        Name of ``d`` in error messages.

    Returns
    -------
    object
        The operator (with ``simulate``, ``step``, ``reset`` and, where it exists,
        ``inverse``).

    Raises
    ------
    ValueError
        Not an object, a missing or unknown ``type``, a missing key, or bad parameters (the
        message names the place, e.g. ``model.stages[1].gains``).

    Examples
    --------
    >>> op = model_from_dict({"type": "CreepOperator", "gains": [0.05],
    ...                       "time_constants": [0.1], "dt": 1e-3})
    >>> op.m
    1
    """
    if not isinstance(d, dict) or "type" not in d:
        raise ValueError(f"{where}: expected a JSON object with a 'type', got {d!r:.80}")
    try:
        return _build(d["type"], d, where)
    except KeyError as err:
        raise ValueError(f"{where}: missing key {err.args[0]!r} for type {d['type']!r}") \
            from None
    except (TypeError, ValueError) as err:
        if str(err).startswith(where):
            raise ValueError(str(err)) from None
        raise ValueError(f"{where} ({d['type']}): {err}") from None


def model_to_dict(model) -> dict:
    """The JSON form of an operator, an inverse or a Cascade (inverse of :func:`model_from_dict`).

    Parameters
    ----------
    model : object
        A GeneralizedPI, AsymmetricPI, RateDependentPI, CreepOperator, PIOperator, one of
        their inverses, or a Cascade of these.

    Returns
    -------
    dict

    Raises
    ------
    TypeError
        Another kind of object.

    Examples
    --------
    >>> from pimodel.operators.creep import CreepOperator
    >>> model_to_dict(CreepOperator([0.05], [0.1], dt=1e-3).inverse())["inverted"]
    True
    """
    if isinstance(model, Cascade):
        return {"type": "Cascade", "stages": [model_to_dict(s) for s in model.stages]}
    if isinstance(model, (AsymmetricPIInverse, RateDependentPIInverse)):
        return {"type": "Inverse", "operator": model_to_dict(model.forward)}
    if isinstance(model, GeneralizedPI) and isinstance(getattr(model, "forward", None),
                                                       GeneralizedPI):
        return {"type": "Inverse", "operator": model_to_dict(model.forward)}
    if isinstance(model, PIOperator):
        return {"type": "PIOperator", "weights": model.weights.tolist(),
                "radii": model.radii.tolist(), "initial_state": model.initial_state.tolist()}
    if callable(getattr(model, "to_dict", None)):
        return model.to_dict()
    raise TypeError(f"model: no JSON form for {type(model).__name__}")


def load_model(path):
    """Read a model JSON file and rebuild it (:func:`model_from_dict`).

    Parameters
    ----------
    path : str or Path
        A file written by :func:`save_model` (or by hand in the same form).

    Returns
    -------
    object
        The operator, inverse or :class:`~pimodel.operators.cascade.Cascade`.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        Not JSON, or not a valid model (the message names the file and the place).

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
    try:
        return model_from_dict(d)
    except ValueError as err:
        raise ValueError(f"{p}: {err}") from None


def save_model(model, path) -> Path:
    """Write :func:`model_to_dict` of ``model`` as JSON to ``path`` and return the path.

    Parameters
    ----------
    model : object
        An operator, an inverse or a :class:`~pimodel.operators.cascade.Cascade` of them.
    path : str or Path
        The JSON file to write (overwritten).

    Returns
    -------
    Path
        ``path``.

    Examples
    --------
    >>> import json, os, tempfile
    >>> from pimodel.operators.creep import CreepOperator
    >>> path = save_model(CreepOperator([0.05], [0.1], dt=1e-3),
    ...                   os.path.join(tempfile.mkdtemp(), "creep.json"))
    >>> json.loads(path.read_text())["type"]
    'CreepOperator'
    """
    p = Path(path)
    p.write_text(json.dumps(model_to_dict(model), indent=2) + "\n")
    return p
