"""python-control blocks for the generalized PI, rate-dependent PI and creep operators (and
their exact inverses): discrete-time ``NonlinearIOSystem`` objects on the C core.

The blocks follow the contract of :mod:`pimodel.blocks`:

- **Semantics** (python-control's for discrete systems): ``outfcn(t, x[k], u[k])`` gives the
  output at step k, ``updfcn`` returns ``x[k+1]``. Every operator here has direct feedthrough,
  so the state is the operator's state after the previous sample (``x[k] = z[k-1]``).
- **Parameters** travel in ``params`` under ``"<block name>.<setting>"`` (defaults: the
  operator's values, listed in ``sys.params``); ``control.input_output_response(sys, t, u,
  params=...)`` changes them without rebuilding. Unknown settings of the block raise.
- **Initial state**: each block carries ``_own_state(params)``, the hook
  ``pimodel.blocks.initial_state(sys, params)`` reads; :func:`block_initial_state` returns the
  same for these blocks. Pass it as ``initial_state=`` to ``control.input_output_response``.
- **Names**: vectors are 1-based (``z[1]..z[n]``, ``x[1]..x[m]``).

Blocks: :func:`generalized_pi_block` (also the inverse, which is again a
:class:`~pimodel.operators.generalized.GeneralizedPI`), :func:`asymmetric_pi_block` (forward or
exact
inverse), :func:`rate_dependent_pi_block`,
:func:`rate_dependent_inverse_block`, :func:`creep_block` (forward or inverse).
"""

from __future__ import annotations

from collections.abc import Callable

import control
import numpy as np

from .. import _native
from ..checks import positive_scalar
from ..operators.asymmetric import AsymmetricPI
from ..operators.creep import CreepOperator
from ..operators.generalized import GeneralizedPI
from ..operators.rate_dependent import RateDependentPI
from .framework import Block, BlockSettings, signal_labels, stepped_block

__all__ = [
    "asymmetric_pi_block",
    "block_initial_state",
    "creep_block",
    "generalized_pi_block",
    "rate_dependent_inverse_block",
    "rate_dependent_pi_block",
]


def block_initial_state(sys: control.InputOutputSystem, params: dict | None = None) -> np.ndarray:
    """The own initial state of a block from this module (params merged as python-control does).

    Parameters
    ----------
    sys : control.NonlinearIOSystem
        A block made by this module.
    params : dict, optional
        Params of the simulation (e.g. ``"<name>.initial_state"``).

    Returns
    -------
    numpy.ndarray
        ``sys.nstates`` values, labelled by ``sys.state_labels``.

    Raises
    ------
    TypeError
        For a system that is not one of these blocks.

    Examples
    --------
    >>> from pimodel.operators.creep import CreepOperator
    >>> blk = creep_block(CreepOperator([0.05], [0.1], dt=1e-3, initial_state=2.0))
    >>> block_initial_state(blk).tolist()
    [2.0]
    """
    own = getattr(sys, "_own_state", None)
    if own is None:
        raise TypeError("sys: expected a block of pimodel.blocks.operators, got "
                        f"{type(sys).__name__}")
    return np.asarray(own({**sys.params, **(params or {})}), float).reshape(sys.nstates).copy()


def _make_block(settings: BlockSettings, step: Callable, *, n_states: int, labels: list[str],
                dt: float, name: str, input: str, output: str) -> Block:
    """``step(op, x, u) -> (y, x_next)``; the block checks the state size."""

    def checked(op, x, u, t):
        if not np.isfinite(u):
            raise ValueError(f"{input}: input sample is {u!r}; expected a finite number")
        return step(op, x, u)

    return stepped_block(settings, checked, own_state=lambda params: _state_of(
        settings.get(params)), states=labels, dt=dt, name=name, input=input, output=output)


def _state_of(op) -> np.ndarray:
    return np.asarray(op.initial_state, float).copy()


# -- generalized PI --------------------------------------------------------------------------

def _gpi_step(op: GeneralizedPI, x: np.ndarray, v: float):
    y, bad = _native.gpi_run(op.weights, op.radii, x, op.input_envelope.code,
                             op.input_envelope.coefficients, op.output_envelope.code,
                             op.output_envelope.coefficients, np.array([v]))
    if bad:
        raise ValueError(f"v: input {v!r} leaves the domain of an envelope of {op!r}")
    return float(y[0]), x


def generalized_pi_block(op: GeneralizedPI, dt: float, *, name: str = "gpi", input: str = "v",
                         output: str = "y") -> control.NonlinearIOSystem:
    """Generalized PI operator (or its inverse, ``op.inverse()``) as a python-control block.

    ``y[k] = g(sum_i p_i z_i[k])``, ``z_i[k] = clamp(z_i[k-1], h(v[k]) - r_i, h(v[k]) + r_i)``
    (:mod:`pimodel.operators.generalized`); the state is ``x[k] = z[k-1]`` (envelope units).

    Parameters
    ----------
    op : GeneralizedPI
        The operator; for the feedforward pass ``op.inverse()`` with ``input="y_d"``,
        ``output="v"``.
    dt : float
        Sample time [s] (the operator is rate independent; dt only times the block).
    name, input, output : str
        Block name (params prefix) and signal names.

    Returns
    -------
    control.NonlinearIOSystem
        States ``z[1]..z[n]``.

    Notes
    -----
    Params: ``"<name>.weights"``, ``"<name>.radii"`` (n values each), ``"<name>.initial_state"``
    (scalar or n), ``"<name>.input_envelope"``, ``"<name>.output_envelope"``
    (:class:`~pimodel.operators.envelopes.Envelope`).

    Examples
    --------
    >>> import control, numpy as np
    >>> from pimodel.operators.envelopes import Envelope
    >>> op = GeneralizedPI([1.0, 0.5], [0.0, 0.3], output_envelope=Envelope.poly2(0, 1, 0.1))
    >>> blk = generalized_pi_block(op, 1e-3)
    >>> t = np.arange(3) * 1e-3
    >>> res = control.input_output_response(blk, t, [0.0, 1.0, 0.5],
    ...                                     initial_state=block_initial_state(blk))
    >>> bool(np.allclose(res.outputs, op.simulate([0.0, 1.0, 0.5])))
    True
    """
    if not isinstance(op, GeneralizedPI):
        raise TypeError(f"op: expected a GeneralizedPI, got {type(op).__name__}")
    dt = positive_scalar(dt, "dt")
    n = op.n
    signed = op.pi.signed_weights

    def build(s: dict) -> GeneralizedPI:
        new = GeneralizedPI(s["weights"], s["radii"], input_envelope=s["input_envelope"],
                            output_envelope=s["output_envelope"],
                            initial_state=s["initial_state"], signed_weights=signed)
        if new.n != n:
            raise ValueError(f"weights, radii: expected {n} plays (the block's states), got "
                             f"{new.n}")
        if not np.array_equal(new.radii, np.asarray(s["radii"], float)):
            raise ValueError("radii: expected non-decreasing radii (they fix the state order)")
        return new

    settings = BlockSettings(name, {"weights": op.weights.copy(), "radii": op.radii.copy(),
                              "initial_state": op.initial_state.copy(),
                              "input_envelope": op.input_envelope,
                              "output_envelope": op.output_envelope}, build)
    return _make_block(settings, _gpi_step, n_states=n, labels=signal_labels("z", n), dt=dt,
                       name=name, input=input, output=output)


# -- asymmetric generalized PI ---------------------------------------------------------------

def asymmetric_pi_block(op: AsymmetricPI, dt: float, *, inverse: bool = False,
                        name: str | None = None, input: str | None = None,
                        output: str | None = None) -> control.NonlinearIOSystem:
    """Asymmetric generalized PI operator (or, with ``inverse=True``, its exact inverse) as a
    python-control block; semantics of :mod:`pimodel.operators.asymmetric`.

    Parameters
    ----------
    op : AsymmetricPI
        The forward operator.
    dt : float
        Sample time [s].
    inverse : bool
        Build the feedforward ``y_d -> v`` (state: the forward play states).
    name, input, output : str, optional
        Defaults ``"asym"``, ``"v"``, ``"y"`` (inverse: ``"asym_inv"``, ``"y_d"``, ``"v"``).

    Returns
    -------
    control.NonlinearIOSystem
        States ``z[1]..z[n]`` (the forward play states after the previous sample).

    Notes
    -----
    Params: ``"<name>.direct_weight"``, ``"<name>.weights"``, ``"<name>.radii"`` (n values),
    ``"<name>.ascending"``, ``"<name>.descending"`` (``(a, d)`` each), ``"<name>.shape"``
    (Envelope), ``"<name>.initial_state"`` (scalar or n).

    Examples
    --------
    >>> import control, numpy as np
    >>> op = AsymmetricPI(0.5, [1.0], [0.2], ascending=(1.0, 0.0), descending=(1.5, 0.1))
    >>> blk = asymmetric_pi_block(op, 1e-3, inverse=True)
    >>> yd = np.sin(np.linspace(0, 4, 40))
    >>> res = control.input_output_response(blk, np.arange(40) * 1e-3, yd,
    ...                                     initial_state=block_initial_state(blk))
    >>> bool(np.allclose(op.simulate(res.outputs), yd, atol=1e-12))
    True
    """
    if not isinstance(op, AsymmetricPI):
        raise TypeError(f"op: expected an AsymmetricPI, got {type(op).__name__}")
    dt = positive_scalar(dt, "dt")
    name = name or ("asym_inv" if inverse else "asym")
    input = input or ("y_d" if inverse else "v")
    output = output or ("v" if inverse else "y")
    n = op.n

    def build(s: dict) -> AsymmetricPI:
        new = AsymmetricPI(s["direct_weight"], s["weights"], s["radii"],
                           ascending=s["ascending"], descending=s["descending"],
                           shape=s["shape"], initial_state=s["initial_state"])
        if new.n != n or not np.array_equal(new.radii, np.asarray(s["radii"], float)):
            raise ValueError(f"radii: expected {n} non-decreasing radii (they fix the states)")
        return new

    def step(o: AsymmetricPI, x: np.ndarray, u: float):
        out, bad = _native.asym_run(o._c, o.weights, o.radii, x, np.array([u]),
                                    inverse=inverse)
        if bad:
            raise ValueError(f"{input}: sample {u!r} is outside the range of {o.shape!r}")
        return float(out[0]), x

    settings = BlockSettings(name, {"direct_weight": op.direct_weight, "weights": op.weights.copy(),
                              "radii": op.radii.copy(), "ascending": op.ascending,
                              "descending": op.descending, "shape": op.shape,
                              "initial_state": op.initial_state.copy()}, build)
    return _make_block(settings, step, n_states=n, labels=signal_labels("z", n), dt=dt, name=name,
                       input=input, output=output)


# -- rate-dependent PI -----------------------------------------------------------------------

def _rdpi_settings(op: RateDependentPI, name: str) -> BlockSettings:
    n = op.n

    def build(s: dict) -> RateDependentPI:
        new = RateDependentPI(s["weights"], s["base_radii"], rate_gain=s["rate_gain"], dt=op.dt,
                              rate_time_constant=s["rate_time_constant"],
                              initial_state=s["initial_state"],
                              initial_input=s["initial_input"])
        if new.n != n:
            raise ValueError(f"weights, base_radii: expected {n} plays, got {new.n}")
        if not np.array_equal(new.base_radii, np.asarray(s["base_radii"], float)):
            raise ValueError("base_radii: expected non-decreasing radii (they fix the state "
                             "order)")
        return new

    return BlockSettings(name, {"weights": op.weights.copy(), "base_radii": op.base_radii.copy(),
                          "rate_gain": op.rate_gain,
                          "rate_time_constant": op.rate_time_constant,
                          "initial_state": op.initial_state[:n].copy(),
                          "initial_input": op.initial_input}, build)


def _rdpi_step(op: RateDependentPI, x: np.ndarray, v: float, *, inverse: bool = False):
    n = op.n
    if x.size != n + 2:
        raise ValueError(f"state: expected {n + 2} values, got {x.size}")
    z, hist = x[:n].copy(), x[n:].copy()
    run = _native.rdpi_inverse_run if inverse else _native.rdpi_run
    out = run(op.weights, op.base_radii, op.rate_gain, op.rate_decay, op.dt, z, hist,
              np.array([v]))
    return float(out[0]), np.concatenate((z, hist))


def rate_dependent_pi_block(op: RateDependentPI, *, name: str = "rdpi", input: str = "v",
                            output: str = "y") -> control.NonlinearIOSystem:
    """Rate-dependent PI operator as a python-control block (sample time ``op.dt``).

    Semantics of :mod:`pimodel.operators.rate_dependent`; the state is ``z[1..n]`` (plays after the
    previous sample), ``v_prev`` (``v[k-1]``) and ``rate`` (``rate[k]``, input unit / s).

    Parameters
    ----------
    op : RateDependentPI
        The operator (its ``dt`` is the block's sample time).
    name, input, output : str
        Block name (params prefix) and signal names.

    Returns
    -------
    control.NonlinearIOSystem
        States ``z[1]..z[n]``, ``v_prev``, ``rate``.

    Notes
    -----
    Params: ``"<name>.weights"``, ``"<name>.base_radii"``, ``"<name>.rate_gain"``,
    ``"<name>.rate_time_constant"``, ``"<name>.initial_state"`` (play states, scalar or n),
    ``"<name>.initial_input"``.

    Examples
    --------
    >>> import control, numpy as np
    >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.3], rate_gain=1e-3, dt=1e-3)
    >>> blk = rate_dependent_pi_block(op)
    >>> v = np.sin(np.linspace(0, 3, 50))
    >>> res = control.input_output_response(blk, np.arange(50) * 1e-3, v,
    ...                                     initial_state=block_initial_state(blk))
    >>> bool(np.allclose(res.outputs, op.simulate(v), atol=1e-12))
    True
    """
    if not isinstance(op, RateDependentPI):
        raise TypeError(f"op: expected a RateDependentPI, got {type(op).__name__}")
    return _make_block(_rdpi_settings(op, name), _rdpi_step, n_states=op.n + 2,
                       labels=signal_labels("z", op.n) + ["v_prev", "rate"], dt=op.dt, name=name,
                       input=input, output=output)


def rate_dependent_inverse_block(op: RateDependentPI, *, name: str = "rdpi_inv",
                                 input: str = "y_d", output: str = "v"
                                 ) -> control.NonlinearIOSystem:
    """Exact inverse of a rate-dependent PI operator as a block: ``y_d[k]`` in, ``v[k]`` out.

    The state is the forward operator's (``z[1..n]``, ``v_prev``, ``rate``), advanced with the
    ``v[k]`` the block outputs (:class:`~pimodel.operators.rate_dependent.RateDependentPIInverse`).

    Parameters
    ----------
    op : RateDependentPI
        The forward operator (``alpha_1 = 0``).
    name, input, output : str
        Block name (params prefix, same settings as :func:`rate_dependent_pi_block`) and
        signal names.

    Returns
    -------
    control.NonlinearIOSystem

    Examples
    --------
    >>> import control, numpy as np
    >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.3], rate_gain=1e-3, dt=1e-3)
    >>> inv = rate_dependent_inverse_block(op)
    >>> yd = np.sin(np.linspace(0, 3, 50))
    >>> res = control.input_output_response(inv, np.arange(50) * 1e-3, yd,
    ...                                     initial_state=block_initial_state(inv))
    >>> bool(np.allclose(op.simulate(res.outputs), yd, atol=1e-12))
    True
    """
    op.inverse()  # raises when not invertible
    return _make_block(_rdpi_settings(op, name),
                       lambda o, x, u: _rdpi_step(o, x, u, inverse=True), n_states=op.n + 2,
                       labels=signal_labels("z", op.n) + ["v_prev", "rate"], dt=op.dt, name=name,
                       input=input, output=output)


# -- creep -----------------------------------------------------------------------------------

def _creep_step(op: CreepOperator, x: np.ndarray, u: float):
    out = _native.creep_run(op.poles, op.gains, x, np.array([u]), inverse=op.inverted)
    return float(out[0]), x


def creep_block(op: CreepOperator, *, name: str | None = None, input: str | None = None,
                output: str | None = None) -> control.NonlinearIOSystem:
    """Creep operator (or its inverse, ``op.inverse()``) as a python-control block.

    Semantics of :mod:`pimodel.operators.creep`; the state is the lag states ``x[1..m]``. For linear
    analysis use ``control.ss(*op.state_space(), op.dt)`` instead (same system, no params).

    Parameters
    ----------
    op : CreepOperator
        Forward (``u -> y``) or inverse (``y_d -> u``) creep; sample time ``op.dt``.
    name, input, output : str, optional
        Defaults ``"creep"``, ``"u"``, ``"y"`` (inverse: ``"creep_inv"``, ``"y_d"``, ``"u"``).

    Returns
    -------
    control.NonlinearIOSystem
        States ``x[1]..x[m]``.

    Notes
    -----
    Params: ``"<name>.gains"``, ``"<name>.time_constants"`` (m values each),
    ``"<name>.initial_state"`` (scalar or m).

    Examples
    --------
    >>> import control, numpy as np
    >>> cr = CreepOperator([0.05], [0.01], dt=1e-3)
    >>> blk = creep_block(cr, name="creep")
    >>> res = control.input_output_response(blk, np.arange(3) * 1e-3, np.ones(3),
    ...                                     params={"creep.gains": [0.1]})
    >>> res.outputs.round(4).tolist()
    [1.0, 1.0095, 1.0181]
    """
    if not isinstance(op, CreepOperator):
        raise TypeError(f"op: expected a CreepOperator, got {type(op).__name__}")
    inv = op.inverted
    name = name or ("creep_inv" if inv else "creep")
    input = input or ("y_d" if inv else "u")
    output = output or ("u" if inv else "y")
    m = op.m

    def build(s: dict) -> CreepOperator:
        new = CreepOperator(s["gains"], s["time_constants"], dt=op.dt,
                            initial_state=s["initial_state"], inverted=inv)
        if new.m != m:
            raise ValueError(f"gains: expected {m} lags (the block's states), got {new.m}")
        return new

    settings = BlockSettings(name, {"gains": op.gains.copy(), "time_constants":
                              op.time_constants.copy(), "initial_state":
                              op.initial_state.copy()}, build)
    return _make_block(settings, _creep_step, n_states=m, labels=signal_labels("x", m), dt=op.dt,
                       name=name, input=input, output=output)
