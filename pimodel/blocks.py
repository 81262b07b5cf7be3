"""python-control blocks: discrete-time ``NonlinearIOSystem``s for the PI operator, its exact
inverse, the radius estimator and the adaptive inverse compensator.

python-control semantics for discrete systems: the output is ``outfcn(t, x[k], u[k])`` and
``updfcn`` returns ``x[k+1]``. The PI operator has direct feedthrough (``y[k]`` depends on
``v[k]``), so its state is ``x[k] = z[k-1]`` (the play states after the previous sample):
``y[k] = sum_i p_i clamp(x_i[k], v[k] - r_i, v[k] + r_i)`` and ``x[k+1]`` is that clamp.
Signal and state names carry the block name, so several blocks can share an ``interconnect``.
"""

from __future__ import annotations

import ctypes

import control
import numpy as np

from . import _native
from .checks import as_vector, positive_scalar
from .estimator import RadiusEstimator
from .operator import PIOperator

_native.lib.pim_adaptive_inverse_step.restype = ctypes.c_double
_native.lib.pim_adaptive_inverse_step.argtypes = [ctypes.c_size_t, _native.F64, _native.F64,
                                                  _native.F64, ctypes.c_double]


def _clamp(z, v, r):
    return np.maximum(v - r, np.minimum(v + r, z))


def pi_block(op: PIOperator, dt: float, *, name: str = "pi", input: str = "v",
             output: str = "y") -> control.NonlinearIOSystem:
    """PI operator block: input ``input`` (v[k]), output ``output`` (y[k] = PI[v][k]); states
    ``{name}_z1..n`` start at ``op.initial_state``."""
    if not isinstance(op, PIOperator):
        raise TypeError(f"op: expected a PIOperator, got {type(op).__name__}")
    dt = positive_scalar(dt, "dt")
    p, r = op.weights.copy(), op.radii.copy()

    def upd(t, x, u, params):
        return _clamp(x, u[0], r)

    def out(t, x, u, params):
        return np.array([p @ _clamp(x, u[0], r)])

    sys = control.nlsys(upd, out, inputs=[input], outputs=[output],
                        states=[f"{name}_z{i + 1}" for i in range(op.n)], dt=dt, name=name)
    sys.x0 = op.initial_state.copy()
    return sys


def inverse_pi_block(op: PIOperator, dt: float, *, name: str = "pi_inv", input: str = "y_d",
                     output: str = "v") -> control.NonlinearIOSystem:
    """Exact inverse of ``op`` as a feedforward compensator: input the desired output
    ``y_d[k]``, output ``v[k] = PI^-1[y_d][k]`` (states start consistent with ``op``)."""
    return pi_block(op.inverse(), dt, name=name, input=input, output=output)


def estimator_block(weights, dt: float, *, gains=10.0, initial_radii=None,
                    known_linear_play: bool = False, name: str = "estimator",
                    inputs=("v", "y"), radius_prefix: str = "r_hat",
                    **options) -> control.NonlinearIOSystem:
    """Radius estimator block (the C estimator of :class:`~pimodel.RadiusEstimator`).

    Inputs ``v[k]`` and measured ``y[k]``; outputs ``r_hat[0..n-1]`` (the radii held in the
    state, i.e. the estimate used at step k: no feedthrough), ``y_hat[k]`` and ``e[k]``
    (feedthrough); states: the estimator's flat state. ``options`` as for RadiusEstimator.
    """
    est = RadiusEstimator(weights, dt=dt, gains=gains, initial_radii=initial_radii,
                          known_linear_play=known_linear_play, **options)
    n = est.n
    x0 = est.state

    def upd(t, x, u, params):
        est.state = x
        est.step(u[0], u[1])
        return est.state

    def out(t, x, u, params):
        est.state = x
        _, yh, e, _ = est.step(u[0], u[1])
        return np.concatenate((x[:n], [yh, e]))

    outputs = [f"{radius_prefix}[{i}]" for i in range(n)] + [f"{name}_y_hat", f"{name}_e"]
    states = [f"{name}_s{i}" for i in range(x0.size)]
    sys = control.nlsys(upd, out, inputs=list(inputs), outputs=outputs, states=states,
                        dt=est.dt, name=name)
    sys.x0 = x0
    return sys


def adaptive_compensator_block(weights, dt: float, *, name: str = "adaptive_inv",
                               input: str = "y_d", output: str = "v",
                               radius_prefix: str = "r_hat",
                               initial_state=0.0) -> control.NonlinearIOSystem:
    """Adaptive inverse compensator: inputs ``y_d[k]`` and the radii ``r_hat[0..n-1]`` (from an
    estimator block), output ``v[k]``.

    State: the play states ``zm`` of a forward model with the current radii. At step k the exact
    inverse of ``(p, r_hat[k])`` is built with the inverse state consistent with ``zm``
    (``zinv_i = P_i zm_i + sum_{j>i} p_j zm_j``), stepped with ``y_d[k]`` to give ``v[k]``, and
    ``zm`` is advanced with ``v[k]``; so a change of radii never breaks the inverse's memory.
    The radii must keep ``r_hat[0] = 0`` (estimate with ``known_linear_play=True``).
    """
    p = np.ascontiguousarray(as_vector(weights, "weights"))
    if np.any(p <= 0):
        raise ValueError("weights: every weight must be > 0")
    dt = positive_scalar(dt, "dt")
    n = p.size
    lib = _native.lib

    def step(x, u):
        zm = np.array(x, dtype=float)
        r = np.ascontiguousarray(u[1:], dtype=float)
        v = lib.pim_adaptive_inverse_step(n, p, r, zm, float(u[0]))
        if np.isnan(v):
            raise ValueError(f"{name}: radii {r} not invertible (need r_hat[0] = 0, sorted)")
        return v, zm

    def upd(t, x, u, params):
        return step(x, u)[1]

    def out(t, x, u, params):
        return np.array([step(x, u)[0]])

    inputs = [input] + [f"{radius_prefix}[{i}]" for i in range(n)]
    sys = control.nlsys(upd, out, inputs=inputs, outputs=[output],
                        states=[f"{name}_zm{i + 1}" for i in range(n)], dt=dt, name=name)
    sys.x0 = np.broadcast_to(np.asarray(initial_state, float), (n,)).copy()
    return sys


def pid_block(kp: float, ki: float = 0.0, kd: float = 0.0, *, tf: float | None = None,
              dt: float, name: str = "pid", input: str = "e",
              output: str = "u") -> control.NonlinearIOSystem:
    """Discrete PID, backward Euler with filtered derivative (as the compiled loops):
    ``I[k] = I[k-1] + dt e[k]``, ``D[k] = (tf D[k-1] + kd (e[k] - e[k-1])) / (tf + dt)``,
    ``u[k] = kp e[k] + ki I[k] + D[k]``; ``tf`` defaults to ``10 dt``."""
    dt = positive_scalar(dt, "dt")
    tf = 10 * dt if tf is None else float(tf)
    for nm, val in (("kp", kp), ("ki", ki), ("kd", kd), ("tf", tf)):
        if not np.isfinite(val) or val < 0:
            raise ValueError(f"{nm}: expected a finite number >= 0, got {val!r}")

    def nxt(x, e):
        integ = x[0] + dt * e
        d = (tf * x[1] + kd * (e - x[2])) / (tf + dt)
        return np.array([integ, d, e])

    def upd(t, x, u, params):
        return nxt(x, u[0])

    def out(t, x, u, params):
        integ, d, _ = nxt(x, u[0])
        return np.array([kp * u[0] + ki * integ + d])

    return control.nlsys(upd, out, inputs=[input], outputs=[output],
                         states=[f"{name}_I", f"{name}_D", f"{name}_e_prev"], dt=dt, name=name)
