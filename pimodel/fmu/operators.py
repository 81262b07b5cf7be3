"""Parameter values of the pimodel FMU units (``pimodel.fmu.build.MODELS``) for the Python
operators: :func:`unit_parameters` maps a
:class:`~pimodel.operators.generalized.GeneralizedPI`,
:class:`~pimodel.operators.asymmetric.AsymmetricPI`,
:class:`~pimodel.operators.rate_dependent.RateDependentPI` or
:class:`~pimodel.operators.creep.CreepOperator` (or the inverse of one of them) to the unit that
runs it and the values of its variables, by the FMI 2 names (``"p[2]"``) that :class:`FMUUnit` also
accepts for FMI 3. The unit at sample time ``Ts`` then gives ``u[k] -> y[k]`` exactly as the
operator's ``simulate`` (the tests hold them equal to 1e-12).

Limits: the units take one initial state ``z0`` for all plays (lags), so an operator whose
initial states differ raises ValueError; the object that ``GeneralizedPI.inverse()`` returns
is exported as its forward operator (its ``forward`` attribute) with ``inverse = true``; a
GeneralizedPI with signed weights built otherwise has no unit (ValueError).
"""

from __future__ import annotations

import numpy as np

from ..blocks.framework import labelled_values
from ..operators.asymmetric import AsymmetricPI, AsymmetricPIInverse
from ..operators.creep import CreepOperator
from ..operators.generalized import GeneralizedPI
from ..operators.pi import PIOperator
from ..operators.rate_dependent import RateDependentPI, RateDependentPIInverse
from .spec import ENVELOPE_KINDS, NMAX

__all__ = ["unit_parameters"]


def _uniform(state: np.ndarray, what: str) -> float:
    z = np.asarray(state, float)
    if not np.all(z == z[0]):
        raise ValueError(f"{what}: the FMU takes one initial state z0 for all elements, got "
                         f"{z.tolist()}")
    return float(z[0])




def _envelope(prefix: str, env) -> dict:
    c = env.coefficients
    return {f"{prefix}_kind": ENVELOPE_KINDS[env.kind],
            **{f"{prefix}_c{j}": float(c[j]) for j in range(4)}}


def unit_parameters(op, *, Ts: float | None = None) -> tuple[str, dict]:
    """The FMU unit that runs ``op`` and the values of its parameters.

    Parameters
    ----------
    op : GeneralizedPI, AsymmetricPI, RateDependentPI, CreepOperator, an inverse of these,
        a PIOperator (unit PIHysteresis, input ``v``; no ``inverse`` variable) or a
        :class:`~pimodel.diagnosis.model.DiagnosedModel` (unit DiagnosedModel, input ``v``,
        ``Ts`` its ``dt``; :func:`pimodel.diagnosis.native_model.fmu_parameters`) or its
        :class:`~pimodel.diagnosis.model.DiagnosedInverse` (unit DiagnosedInverse, input
        ``y_d``, output ``v``; :func:`pimodel.diagnosis.native_inverse.inverse_fmu_parameters`)
        The operator (inverses: ``AsymmetricPIInverse``, ``RateDependentPIInverse``, an
        inverted ``CreepOperator``, the result of ``GeneralizedPI.inverse()``).
    Ts : float, optional
        Sample time [s] for the rate-independent operators (default 1e-3); the rate-dependent
        and creep operators, a DiagnosedModel and its inverse use their own ``dt`` (a
        different ``Ts`` raises ValueError).

    Returns
    -------
    (str, dict)
        Unit name (a key of ``MODELS``) and ``{variable name: value}``.

    Raises
    ------
    ValueError
        Non-uniform initial states, more than 64 plays, a signed-weight GeneralizedPI, or a
        ``Ts`` that differs from the operator's ``dt``.
    TypeError
        Another kind of object.

    Examples
    --------
    >>> from pimodel.operators.creep import CreepOperator
    >>> name, params = unit_parameters(CreepOperator([0.05], [0.1], dt=1e-3).inverse())
    >>> name, params["inverse"], params["tau[1]"]
    ('CreepOperator', True, 0.1)
    """
    from ..diagnosis.model import DiagnosedInverse, DiagnosedModel

    if isinstance(op, DiagnosedModel):
        from ..diagnosis.native_model import fmu_parameters

        if Ts is not None and Ts != op.dt:
            raise ValueError(f"Ts: {Ts!r} differs from the model's dt = {op.dt!r}")
        return fmu_parameters(op)
    if isinstance(op, DiagnosedInverse):
        from ..diagnosis.native_inverse import inverse_fmu_parameters

        if Ts is not None and Ts != op.model.dt:
            raise ValueError(f"Ts: {Ts!r} differs from the model's dt = {op.model.dt!r}")
        return inverse_fmu_parameters(op)
    inverse = False
    if isinstance(op, GeneralizedPI) and isinstance(getattr(op, "forward", None),
                                                    GeneralizedPI):
        op, inverse = op.forward, True
    if isinstance(op, (AsymmetricPIInverse, RateDependentPIInverse)):
        op, inverse = op.forward, True
    if isinstance(op, (RateDependentPI, CreepOperator)):
        if Ts is not None and Ts != op.dt:
            raise ValueError(f"Ts: {Ts!r} differs from the operator's dt = {op.dt!r}")
        Ts = op.dt
    Ts = 1e-3 if Ts is None else float(Ts)
    if isinstance(op, GeneralizedPI):
        if op.pi.signed_weights:
            raise ValueError("op: a GeneralizedPI with signed weights has no FMU unit; export "
                             "the forward operator (or its inverse()) instead")
        name = "GeneralizedPI"
        params = {**labelled_values("p", op.weights), **labelled_values("r", op.radii),
                  **_envelope("in", op.input_envelope), **_envelope("out", op.output_envelope),
                  "z0": _uniform(op.initial_state, "initial_state")}
    elif isinstance(op, AsymmetricPI):
        name = "AsymmetricPI"
        params = {**labelled_values("p", op.weights), **labelled_values("r", op.radii),
                  "p0": op.direct_weight,
                  "a_l": op.ascending[0], "d_l": op.ascending[1], "a_r": op.descending[0],
                  "d_r": op.descending[1], **_envelope("shape", op.shape),
                  "z0": _uniform(op.initial_state, "initial_state")}
    elif isinstance(op, RateDependentPI):
        name = "RateDependentPI"
        params = {**labelled_values("p", op.weights), **labelled_values("r", op.base_radii),
                  "rate_gain": op.rate_gain, "rate_time_constant": op.rate_time_constant,
                  "v0": op.initial_input, "z0": _uniform(op.initial_state[:op.n],
                                                         "initial_state")}
    elif isinstance(op, CreepOperator):
        name, inverse = "CreepOperator", op.inverted
        params = {**labelled_values("c", op.gains), **labelled_values("tau", op.time_constants),
                  "z0": _uniform(op.initial_state, "initial_state")}
    elif isinstance(op, PIOperator):
        if op.signed_weights:
            raise ValueError("op: a PIOperator with signed weights (e.g. an inverse) has no FMU "
                             "unit here; use the InversePI unit with the forward parameters")
        return "PIHysteresis", {"Ts": Ts, "n": op.n, **labelled_values("p", op.weights),
                                **labelled_values("r", op.radii),
                                "z0": _uniform(op.initial_state, "initial_state")}
    else:
        raise TypeError(f"op: no FMU unit for {type(op).__name__}; supported: GeneralizedPI, "
                        "AsymmetricPI, RateDependentPI, CreepOperator, their inverses and "
                        "PIOperator")
    n = op.m if isinstance(op, CreepOperator) else op.n
    if n > NMAX:
        raise ValueError(f"op: {n} plays (lags), the FMU units take at most {NMAX}")
    return name, {"Ts": Ts, "n": n, "inverse": inverse, **params}
