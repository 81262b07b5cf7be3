"""JSON form of the operators: :func:`model_to_dict` and :func:`model_from_dict`.

One JSON object with a ``"type"``; the other keys are the operator's ``to_dict()``
(constructor arguments), checked by :func:`.schema.check_model_dict` first::

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

from ..operators.asymmetric import AsymmetricPI, AsymmetricPIInverse
from ..operators.cascade import Cascade
from ..operators.creep import CreepOperator
from ..operators.envelopes import Envelope
from ..operators.generalized import GeneralizedPI
from ..operators.pi import PIOperator
from ..operators.rate_dependent import RateDependentPI, RateDependentPIInverse
from .schema import TYPES, check_model_dict

__all__ = ["model_from_dict", "model_to_dict"]


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
                             signed_weights=d.get("signed_weights", False))
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
                             inverted=d.get("inverted", False))
    if kind == "PIOperator":
        return PIOperator(d["weights"], d["radii"], initial_state=d.get("initial_state", 0.0))
    if kind == "Inverse":
        return _operator(d["operator"], f"{where}.operator").inverse()
    if kind == "Cascade":
        return Cascade(*(_operator(s, f"{where}.stages[{i}]")
                         for i, s in enumerate(d["stages"])))
    if kind == "DiagnosedModel":
        from ..diagnosis.model import DiagnosedModel

        return DiagnosedModel.from_dict(d)
    raise ValueError(f"{where}.type: unknown model type {kind!r}; expected one of {TYPES}")


def _operator(d: dict, where: str):
    """Build a checked object; constructor errors name ``where`` and the type."""
    try:
        return _build(d["type"], d, where)
    except (TypeError, ValueError, OverflowError) as err:
        if str(err).startswith(where):
            raise ValueError(str(err)) from None
        raise ValueError(f"{where} ({d['type']}): {err}") from None


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
        ``inverse``); the file's offset, units and provenance are left out
        (:func:`pimodel.model_files.load_model` keeps them).

    Raises
    ------
    ValueError
        Anything :func:`.schema.check_model_dict` refuses, or parameters the operator refuses
        (the message names the place, e.g. ``model.stages[1].gains``).

    Examples
    --------
    >>> op = model_from_dict({"type": "CreepOperator", "gains": [0.05],
    ...                       "time_constants": [0.1], "dt": 1e-3})
    >>> op.m
    1
    """
    check_model_dict(d, where=where)
    return _operator(d, where)


def model_to_dict(model) -> dict:
    """The JSON form of an operator, an inverse or a Cascade (inverse of :func:`model_from_dict`).

    Parameters
    ----------
    model : object
        A GeneralizedPI, AsymmetricPI, RateDependentPI, CreepOperator, PIOperator, one of
        their inverses, a Cascade of these, a DiagnosedModel or a
        :class:`~pimodel.model_files.file_model.Model` (then with its offset and metadata).

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
    if callable(getattr(model, "as_file_dict", None)):
        return model.as_file_dict()
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
