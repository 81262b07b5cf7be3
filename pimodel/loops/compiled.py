"""Compiled closed-loop paths (C core ``fmu/src/pim_loops.c``) and their python-control twins.

The standard loops: open loop with a linear feedforward gain, exact-inverse feedforward,
adaptive-inverse feedforward (estimator + adaptive compensator), each optionally with PID
feedback, around the Hammerstein plant ``v -> PI -> h -> G(z) -> y``. Per sample k (see
``pim_loops.h``): ``v[k] = ff[k] + u[k]``, ``u[k] = PID(y_d - y)[k]`` with ``y[k] = C xd[k]``
(the plant needs ``D = 0`` under feedback), ``h[k] = PI[v][k]``, ``xd[k+1] = A xd[k] + B h[k]``;
in adaptive mode the estimator takes ``(v[k], y[k])``. :func:`run_loop` is the fast path;
:func:`loop_system` builds the same loop from the blocks in :mod:`pimodel.blocks` for
``control.input_output_response`` (a test holds the two equal).
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from .. import _native
from ..blocks.pi import (
    adaptive_compensator_block,
    estimator_block,
    inverse_pi_block,
    pi_block,
    pid_block,
)
from ..checks import as_signal, positive_scalar
from ..identification.adaptive.radius_estimator import RadiusEstimator
from ..operators.pi import PIOperator

__all__ = [
    "loop_system",
    "LoopResult",
    "PID",
    "run_loop",
]

MAX_PLAYS, MAX_DYN = _native.LOOP_MAX_PLAYS, _native.LOOP_MAX_DYN
_Loop = _native.Loop


@dataclass(frozen=True)
class PID:
    """PID gains (backward Euler, derivative filter time constant ``tf`` [s], default 10 dt).

    Parameters
    ----------
    kp : float
        Proportional gain (input unit per output unit).
    ki : float, optional
        Integral gain (input unit per output unit and second). Default 0.
    kd : float, optional
        Derivative gain (input unit seconds per output unit). Default 0.
    tf : float, optional
        Derivative filter time constant [s]; default 10 dt of the loop.

    Examples
    --------
    >>> import control
    >>> from pimodel import PIOperator
    >>> plant = PIOperator([1.0, 0.5], [0.0, 0.3])
    >>> ref = np.sin(np.linspace(0, 4 * np.pi, 200))       # desired output, 200 samples
    >>> G = control.ss([[0.9]], [[0.1]], [[1.0]], [[0.0]], 1e-3)  # lag after the hysteresis
    >>> res = run_loop(ref, plant, 1e-3, dynamics=G, feedforward=plant, pid=PID(0.5, ki=50.0))
    >>> res.y.shape
    (200,)
    """

    kp: float
    ki: float = 0.0
    kd: float = 0.0
    tf: float | None = None


@dataclass
class LoopResult:
    """Signals of a loop run: reference ``ref``, output ``y``, actuator input ``v``, tracking
    error ``error = ref - y``, and the radii history (adaptive mode).

    Parameters
    ----------
    t : numpy.ndarray of float, shape (N,)
        Sample times ``k dt`` [s].
    ref : numpy.ndarray of float, shape (N,)
        Reference (desired output) ``y_d[k]`` (output unit).
    y : numpy.ndarray of float, shape (N,)
        Plant output ``y[k]`` (output unit).
    v : numpy.ndarray of float, shape (N,)
        Actuator input ``v[k]`` (input unit).
    error : numpy.ndarray of float, shape (N,)
        ``ref[k] - y[k]`` (output unit).
    radii : numpy.ndarray of float, shape (N, n), optional
        Adaptive mode: the estimate ``r_hat`` per sample; else None.

    Examples
    --------
    >>> res = LoopResult(np.arange(3) * 1e-3, np.array([0.0, 1.0, 2.0]),
    ...                  np.array([0.0, 0.9, 2.0]), np.zeros(3), np.array([0.0, 0.1, 0.0]))
    >>> res.tracking()["max_percent"]
    5.0
    """

    t: np.ndarray
    ref: np.ndarray
    y: np.ndarray
    v: np.ndarray
    error: np.ndarray
    radii: np.ndarray | None = None

    def tracking(self, start: int = 0) -> dict[str, float]:
        """Max and RMS tracking error from sample ``start``, also in % of the reference range.

        Parameters
        ----------
        start : int, optional
            First sample scored (e.g. after a transient). Default 0.

        Returns
        -------
        dict of str to float
            ``max``, ``rms`` (output unit), ``max_percent``, ``rms_percent`` (of the
            peak-to-peak of ``ref`` from ``start``).

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> plant = PIOperator([1.0, 0.5], [0.0, 0.3])
        >>> ref = np.sin(np.linspace(0, 4 * np.pi, 200))       # desired output, 200 samples
        >>> stats = run_loop(ref, plant, 1e-3).tracking()     # gain feedforward only
        >>> round(stats["max"], 6), round(stats["max_percent"], 2)
        (0.15, 7.5)
        """
        e = self.error[start:]
        rng = float(np.ptp(self.ref[start:])) or 1.0
        mx, rms = float(np.max(np.abs(e))), float(np.sqrt(np.mean(e**2)))
        return {"max": mx, "rms": rms, "max_percent": 100 * mx / rng,
                "rms_percent": 100 * rms / rng}


def _fill(arr, values):
    for i, x in enumerate(np.ravel(values)):
        arr[i] = float(x)


def _check_dynamics(dynamics, dt, pid):
    if dynamics is None:
        return None
    if not isinstance(dynamics, control.StateSpace):
        dynamics = control.ss(dynamics)
    if dynamics.dt is None or dynamics.dt in (0, True) or abs(dynamics.dt - dt) > 1e-12 * dt:
        raise ValueError(f"dynamics: expected a discrete system with dt = {dt}, got dt = "
                         f"{dynamics.dt}")
    if dynamics.ninputs != 1 or dynamics.noutputs != 1:
        raise ValueError("dynamics: expected a single-input single-output system")
    if dynamics.nstates > MAX_DYN:
        raise ValueError(f"dynamics: at most {MAX_DYN} states, got {dynamics.nstates}")
    if pid is not None and abs(float(dynamics.D[0, 0])) > 0:
        raise ValueError("dynamics: D must be 0 inside a feedback loop (algebraic loop)")
    return dynamics


def run_loop(ref, plant: PIOperator, dt: float, *, dynamics=None, feedforward="none",
             ff_gain: float | None = None, estimator: RadiusEstimator | None = None,
             pid: PID | None = None) -> LoopResult:
    """Run a standard loop on the reference ``ref[k]`` (desired output) in the C core.

    Semantics per sample k: module docstring (``v[k] = ff[k] + u[k]``, ``y[k] = C xd[k]``
    with dynamics, else ``y[k] = PI[v][k]``).

    Parameters
    ----------
    ref : array_like of float, shape (N,)
        Reference (desired output) ``y_d[k]`` (output unit).
    plant : PIOperator
        The plant's hysteresis (at most 64 plays), from its initial state.
    dt : float
        Sample time [s].
    dynamics : control.StateSpace or LTI system, optional
        Discrete SISO system after the hysteresis (``dt`` equal to the loop's; ``D = 0`` under
        feedback); default none (``y = h``).
    feedforward : {"none", "adaptive"} or PIOperator, optional
        ``"none"`` (``v = ff_gain * ref``), a :class:`PIOperator` model (its exact inverse), or
        ``"adaptive"`` (with ``estimator``). Default ``"none"``.
    ff_gain : float, optional
        Gain of ``"none"``; default ``1 / sum p`` of the plant.
    estimator : RadiusEstimator, optional
        ``"adaptive"``: the estimator (``linear_play=True``) whose weights define the
        compensator's model; its state is copied, not advanced.
    pid : PID, optional
        Feedback gains (needs ``dynamics``); default open loop.

    Returns
    -------
    LoopResult
        The signals (``radii`` in adaptive mode).

    Raises
    ------
    TypeError
        If ``plant`` is not a :class:`PIOperator`.
    ValueError
        Bad ``dynamics`` (not discrete at ``dt``, not SISO, more than 16 states, ``D != 0``
        under feedback), PID without dynamics, an unknown ``feedforward``, a missing or
        unsuitable estimator, or estimated radii that are not invertible.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> plant = PIOperator([1.0, 0.5], [0.0, 0.3])
    >>> ref = np.sin(np.linspace(0, 4 * np.pi, 200))       # desired output, 200 samples
    >>> res = run_loop(ref, plant, 1e-3, feedforward=plant)   # exact-inverse feedforward
    >>> bool(np.max(np.abs(res.error)) < 1e-12)
    True
    """
    r = as_signal(ref, "ref", min_length=1)
    dt = positive_scalar(dt, "dt")
    if not isinstance(plant, PIOperator):
        raise TypeError(f"plant: expected a PIOperator, got {type(plant).__name__}")
    if plant.n > MAX_PLAYS:
        raise ValueError(f"plant: at most {MAX_PLAYS} plays")
    dyn = _check_dynamics(dynamics, dt, pid)
    if pid is not None and dyn is None:
        raise ValueError("pid: feedback needs plant dynamics with D = 0 (a static PI plant "
                         "would make an algebraic loop)")
    L = _Loop()
    L.n = plant.n
    _fill(L.p, plant.weights)
    _fill(L.r, plant.radii)
    _fill(L.z, plant.initial_state)
    if dyn is not None:
        L.nx = dyn.nstates
        _fill(L.A, dyn.A)
        _fill(L.B, dyn.B[:, 0])
        _fill(L.C, dyn.C[0])
        L.D = float(dyn.D[0, 0])
    nm = 0
    if isinstance(feedforward, PIOperator):
        inv = feedforward.inverse()
        L.ff_mode, L.ni = 1, inv.n
        _fill(L.pinv, inv.weights)
        _fill(L.rinv, inv.radii)
        _fill(L.zinv, inv.initial_state)
    elif feedforward == "adaptive":
        if not isinstance(estimator, RadiusEstimator):
            raise ValueError("estimator: feedforward='adaptive' needs a RadiusEstimator")
        if not estimator.linear_play:
            raise ValueError("estimator: the adaptive inverse needs linear_play=True")
        nm = estimator.n
        L.ff_mode, L.nm = 2, nm
        _fill(L.pm, estimator.weights)
        _native.loop_take_estimator(L, estimator._buf)
    elif feedforward == "none":
        L.ff_mode = 0
        L.ff_gain = 1.0 / float(plant.weights.sum()) if ff_gain is None else float(ff_gain)
    else:
        raise ValueError(f"feedforward: expected 'none', 'adaptive' or a PIOperator, got "
                         f"{feedforward!r}")
    if pid is not None:
        L.pid_on, L.kp, L.ki, L.kd = 1, pid.kp, pid.ki, pid.kd
        L.tf = 10 * dt if pid.tf is None else pid.tf
    L.dt = dt
    N = r.size
    y, v, e = np.empty(N), np.empty(N), np.empty(N)
    R = np.empty((N, nm)) if nm else None
    if _native.loop_run(L, r, y, v, e, R) != 0:
        raise ValueError("adaptive inverse failed: estimated radii not invertible")
    return LoopResult(np.arange(N) * dt, r, y, v, e, R)


def loop_system(plant: PIOperator, dt: float, *, dynamics=None, feedforward="none",
                ff_gain: float | None = None, estimator_options: dict | None = None,
                pid: PID | None = None) -> control.InterconnectedSystem:
    """The same loop as :func:`run_loop`, interconnected from python-control blocks.

    Input ``y_d``; outputs ``y``, ``v``, ``e`` (tracking error). For ``"adaptive"`` pass
    ``estimator_options`` (weights, gains, initial_radii, linear_play, ... as for
    ``estimator_block``). Blocks: ``plant`` (PI, ``v -> h``), ``dynamics`` (``h -> y``), ``ff``
    (feedforward ``y_d -> v_ff``), ``est`` (adaptive: radii ``r_hat[i]``, ``est_y_hat``,
    ``est_e``), ``err``, ``pid``, ``sum_v``; their params are ``"plant.radii"``,
    ``"est.gains"``, ``"pid.ki"`` ... (:mod:`pimodel.blocks`), and the loop's initial state is
    :func:`pimodel.blocks.initial_state` ``(loop)``.

    Parameters
    ----------
    plant : PIOperator
        The plant's hysteresis.
    dt : float
        Sample time [s].
    dynamics : control.StateSpace or LTI system, optional
        As for :func:`run_loop`.
    feedforward : {"none", "adaptive"} or PIOperator, optional
        As for :func:`run_loop`.
    ff_gain : float, optional
        Gain of ``"none"``; default ``1 / sum p`` of the plant.
    estimator_options : dict, optional
        ``"adaptive"``: ``weights`` and the keywords of
        :func:`pimodel.blocks.estimator_block`.
    pid : PID, optional
        Feedback gains (needs ``dynamics``).

    Returns
    -------
    control.InterconnectedSystem
        Discrete (``dt``), input ``y_d``, outputs ``y``, ``v``, ``e``.

    Raises
    ------
    ValueError
        Bad ``dynamics`` (as for :func:`run_loop`).

    Examples
    --------
    >>> import control
    >>> from pimodel.blocks import initial_state
    >>> from pimodel import PIOperator
    >>> plant = PIOperator([1.0, 0.5], [0.0, 0.3])
    >>> ref = np.sin(np.linspace(0, 4 * np.pi, 200))       # desired output, 200 samples
    >>> loop = loop_system(plant, 1e-3, feedforward=plant)
    >>> t = np.arange(ref.size) * 1e-3
    >>> out = control.input_output_response(loop, t, ref, initial_state(loop))
    >>> bool(np.allclose(out.outputs[0], run_loop(ref, plant, 1e-3, feedforward=plant).y))
    True
    """
    blocks: list = [pi_block(plant, dt, name="plant", input="v", output="h")]
    dyn = _check_dynamics(dynamics, dt, pid)
    if dyn is not None:
        blocks.append(control.ss(dyn.A, dyn.B, dyn.C, dyn.D, dt, inputs=["h"], outputs=["y"],
                                 name="dynamics"))
    else:
        blocks.append(control.ss([], [], [], [[1.0]], dt, inputs=["h"], outputs=["y"],
                                 name="dynamics"))
    if isinstance(feedforward, PIOperator):
        blocks.append(inverse_pi_block(feedforward, dt, name="ff", input="y_d", output="v_ff"))
    elif feedforward == "adaptive":
        opts = dict(estimator_options or {})
        w = opts.pop("weights")
        blocks.append(estimator_block(w, dt, name="est", inputs=("v", "y"),
                                      outputs=("est_y_hat", "est_e"), **opts))
        blocks.append(adaptive_compensator_block(w, dt, name="ff", input="y_d", output="v_ff"))
    else:
        gain = 1.0 / float(plant.weights.sum()) if ff_gain is None else float(ff_gain)
        blocks.append(control.ss([], [], [], [[gain]], dt, inputs=["y_d"], outputs=["v_ff"],
                                 name="ff"))
    blocks.append(control.summing_junction(["y_d", "-y"], "e", name="err", dt=dt))
    if pid is not None:
        blocks.append(pid_block(pid.kp, pid.ki, pid.kd, tf=pid.tf, dt=dt, input="e",
                                output="u"))
        blocks.append(control.summing_junction(["v_ff", "u"], "v", name="sum_v", dt=dt))
    else:
        blocks.append(control.summing_junction(["v_ff"], "v", name="sum_v", dt=dt))
    return control.interconnect(blocks, inputs=["y_d"], outputs=["y", "v", "e"], name="loop",
                                dt=dt, check_unused=False)
