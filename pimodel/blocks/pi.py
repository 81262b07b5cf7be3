"""python-control blocks: discrete-time ``NonlinearIOSystem`` objects for the PI operator, its
exact inverse, the radius estimator, the adaptive inverse compensator and a PID controller.

Each block is a self-sufficient python-control system:

- **Semantics** (python-control's for discrete systems): the output is ``outfcn(t, x[k], u[k])``
  and ``updfcn`` returns ``x[k+1]``. The PI operator has direct feedthrough (``y[k]`` depends on
  ``v[k]``), so its state is ``x[k] = z[k-1]``, the play states after the previous sample:
  ``y[k] = sum_i p_i clamp(x_i[k], v[k] - r_i, v[k] + r_i)`` and ``x[k+1]`` is that clamp.
- **Parameters** travel in python-control's ``params`` dict under the key
  ``"<block name>.<setting>"`` (python-control's ``"sysname.signal"`` notation), e.g.
  ``{"plant.radii": [0, 0.2, 0.5]}``; the values given at construction are the defaults
  (``sys.params``). One params dict is shared by an ``interconnect``, hence the prefix.
  ``control.input_output_response(sys, t, u, params=...)`` changes them without rebuilding.
- **Initial state**: ``initial_state(sys, params)`` returns the block's own initial state (or
  an interconnection's, assembled from its blocks); pass it as ``initial_state=`` to
  ``control.input_output_response``. python-control's default, all zeros, is the block's own
  only when its initial state is zero: a block that starts at ``t = 0`` from an all-zero state
  that is not its own warns (:class:`InitialStateWarning`); the estimator checks its whole
  state at its first sample.
- **Names**: vectors are 1-based, ``z[1]..z[n]``, ``r_hat[1]..r_hat[n]`` (as the FMUs and the
  paper); block states carry no block prefix (``interconnect`` adds ``"<block>_"``).
"""

from __future__ import annotations

import inspect
import math
import warnings

import control
import numpy as np

from .. import _native
from ..checks import as_vector, positive_scalar
from ..identification.adaptive.radius_estimator import (
    EST_BINS,
    EST_WINDOW,
    RadiusEstimator,
)
from ..operators.base import check_finite
from ..operators.pi import PIOperator
from .framework import (
    Block,
    BlockSettings,
    InitialStateWarning,
    signal_labels,
    warn_if_zero_start,
)

__all__ = [
    "adaptive_compensator_block",
    "estimator_block",
    "estimator_state_labels",
    "inverse_pi_block",
    "pi_block",
    "pid_block",
    "radius_estimator",
]



def _pi_and_offset(op, dt) -> tuple[PIOperator, float, float]:
    """``(operator, offset, dt)`` of a PIOperator, or of a model that holds one with its output
    offset and sample time (``pimodel.load_model``'s Model, ``identify``'s result)."""
    inner = getattr(op, "operator", None)
    if isinstance(op, PIOperator):
        pi, offset = op, 0.0
    elif isinstance(inner, PIOperator):
        pi, offset = inner, float(getattr(op, "offset", 0.0))
    else:
        raise TypeError(f"op: expected a PIOperator or a model holding one (load_model, "
                        f"identify), got {type(op).__name__}")
    if dt is None:
        dt = getattr(op, "dt", None)
        if dt is None:
            raise ValueError("dt: expected the sample time [s]; the model has none")
    return pi, offset, positive_scalar(dt, "dt")


def _operator_settings(op: PIOperator, name: str, offset: float = 0.0):
    """Build function for a PI operator's params: weights, radii, initial play state, output
    offset."""
    n = op.n

    def build(s: dict) -> _Stepper:
        for key in ("weights", "radii"):
            size = as_vector(s[key], key).size
            if size != n:
                raise ValueError(f"{key}: expected {n} plays (the block's states), got {size}")
        new = PIOperator(s["weights"], s["radii"], initial_state=s["initial_state"],
                         signed_weights=op.signed_weights)
        if not np.array_equal(new.radii, as_vector(s["radii"], "radii")):
            raise ValueError("radii: expected non-decreasing radii (they fix the state order)")
        c = s["offset"]
        if isinstance(c, bool) or not isinstance(c, (int, float, np.floating)) \
                or not math.isfinite(c):
            raise ValueError(f"offset: expected a finite number, got {c!r}")
        return _Stepper(new, float(c))

    return BlockSettings(name, {"weights": op.weights.copy(), "radii": op.radii.copy(),
                            "initial_state": op.initial_state.copy(), "offset": offset},
                         build)


# pim_pi_step on raw pointers: the blocks call it a few times per sample, and numpy's checked
# argument conversion (pimodel._native.pi_step) costs more than the step itself.
_raw_pi_step = _native.raw_pi_step


class _Stepper:
    """A PI operator ready for the C step: raw pointers to its (read-only, kept alive) arrays."""

    def __init__(self, op: PIOperator, offset: float = 0.0):
        self.op = op
        self.offset = offset
        self.n = op.n
        self.initial_state = op.initial_state
        self._p, self._r = _native.address(op.weights), _native.address(op.radii)
        self._z = np.empty(op.n)
        self._zp = _native.address(self._z)

    def step(self, x, v) -> tuple[float, np.ndarray]:
        """``(y[k], z[k])`` from the play states ``x = z[k-1]`` and the input ``v = v[k]``."""
        v = float(v)
        if not math.isfinite(v):
            raise ValueError(f"v: input sample is {v!r}; expected a finite number")
        self._z[:] = x
        y = _raw_pi_step(self.n, self._p, self._r, self._zp, v)
        if not math.isfinite(y):  # the numerical-range rule (pimodel.operators.base)
            check_finite(np.array([y]), np.array([v]), "v", state=self._z)
        return y, self._z.copy()


def pi_block(op, dt: float | None = None, *, name: str = "pi", input: str = "v",
             output: str = "y") -> control.NonlinearIOSystem:
    """PI operator as a discrete python-control block (C core step).

    ``y[k] = sum_i p_i z_i[k] + offset`` with
    ``z_i[k] = clamp(z_i[k-1], v[k] - r_i, v[k] + r_i)``; the state is ``x[k] = z[k-1]``
    (direct feedthrough from ``v[k]``).

    Parameters
    ----------
    op : PIOperator or Model
        Weights, radii and initial play state (signed weights allowed if ``op`` allows them);
        a model that holds a PIOperator (``pimodel.load_model``, ``identify``) adds its
        ``offset`` (0 for a bare operator).
    dt : float, optional
        Sample time [s] (default: the model's ``dt``).
    name : str
        Block name; prefix of its params and (in an interconnection) of its states.
    input, output : str
        Signal names of ``v[k]`` and ``y[k]``.

    Returns
    -------
    control.NonlinearIOSystem
        Inputs ``[input]``, outputs ``[output]``, states ``z[1]..z[n]``.

    Notes
    -----
    Params (defaults from ``op``):

    ``"<name>.weights"``
        weights ``p_i`` (n values)
    ``"<name>.radii"``
        radii ``r_i`` (n values, non-decreasing, >= 0)
    ``"<name>.initial_state"``
        play states before the first sample ``z_i[-1]`` (scalar or n)
    ``"<name>.offset"``
        output offset added to ``y[k]``

    State layout (``sys.state_labels``):

    ``z[i]``
        state of play i after the previous sample (``z_i[k-1]``)

    The own initial state is ``"<name>.initial_state"`` (:func:`initial_state`).

    Examples
    --------
    >>> import control, numpy as np
    >>> from pimodel import PIOperator
    >>> from pimodel.blocks import pi_block, initial_state
    >>> pb = pi_block(PIOperator([1.0, 0.5], [0.0, 0.3]), 1e-3, name="plant")
    >>> t = np.arange(3) * 1e-3
    >>> res = control.input_output_response(pb, t, [0.0, 1.0, 0.5], initial_state=initial_state(pb),
    ...                                     params={"plant.radii": [0.0, 0.1]})
    >>> res.outputs.round(3).tolist()
    [0.0, 1.45, 0.8]
    """
    op, offset, dt = _pi_and_offset(op, dt)
    settings = _operator_settings(op, name, offset)

    def upd(t, x, u, params):
        cur = settings.get(params)
        return cur.step(x, u[0])[1]

    def out(t, x, u, params):
        cur = settings.get(params)
        warn_if_zero_start(name, t, x, cur.initial_state)
        return np.array([cur.step(x, u[0])[0] + cur.offset])

    return Block(upd, out, own_state=lambda params: settings.get(params).initial_state,
                  aliases={f"{name}_z{i}": f"z[{i}]" for i in range(1, op.n + 1)},
                  inputs=[input], outputs=[output], states=signal_labels("z", op.n), dt=dt,
                  name=name, params=settings.params)


def inverse_pi_block(op, dt: float | None = None, *, name: str = "pi_inv", input: str = "y_d",
                     output: str = "v") -> control.NonlinearIOSystem:
    """Exact inverse of ``op`` as a feedforward compensator block.

    Input the desired output ``y_d[k]``; output ``v[k] = PI^-1[y_d - offset][k]``, the exact
    inverse (itself a PI operator with signed weights, Krejci & Kuhnen) stepped by the C core.

    Parameters
    ----------
    op : PIOperator or Model
        The **forward** model to invert (``r_1 = 0``); its initial state gives the inverse's.
        A model that holds a PIOperator (``pimodel.load_model``, ``identify``) gives its
        ``offset`` too (subtracted from ``y_d``; 0 for a bare operator): no second input.
    dt : float, optional
        Sample time [s] (default: the model's ``dt``).
    name, input, output : str
        Block name and signal names.

    Returns
    -------
    control.NonlinearIOSystem
        Inputs ``[input]``, outputs ``[output]``, states ``z_inv[1]..z_inv[n]``.

    Notes
    -----
    Params are those of the forward model; the inverse is recomputed when they change:

    ``"<name>.weights"``
        forward weights ``p_i``
    ``"<name>.radii"``
        forward radii ``r_i`` (non-decreasing, ``r_1 = 0``)
    ``"<name>.initial_state"``
        forward play states before the first sample
    ``"<name>.offset"``
        the forward model's output offset

    State layout: ``z_inv[i]``, the state of play i of the inverse operator after the previous
    sample. The own initial state is the inverse state consistent with the forward one, so
    ``PI[PI^-1[y_d]] = y_d`` from the first sample.

    Examples
    --------
    >>> import control, numpy as np
    >>> from pimodel import PIOperator
    >>> from pimodel.blocks import inverse_pi_block, pi_block, initial_state
    >>> op = PIOperator([1.0, 0.5], [0.0, 0.3], initial_state=0.2)
    >>> ic = control.interconnect([inverse_pi_block(op, 1e-3), pi_block(op, 1e-3)],
    ...                           inputs=["y_d"], outputs=["y"])
    >>> t = np.arange(4) * 1e-3
    >>> res = control.input_output_response(ic, t, [0.3, 1.0, -0.4, 0.2],
    ...                                     initial_state=initial_state(ic))
    >>> np.allclose(res.outputs, [0.3, 1.0, -0.4, 0.2])
    True
    """
    op, offset, dt = _pi_and_offset(op, dt)
    op.inverse()  # ValueError now when op is not invertible
    forward = _operator_settings(op, name, offset)
    inverse_of = {}

    def inv(params) -> _Stepper:
        model = forward.get(params)
        if inverse_of.get("model") is not model:
            inverse_of.update(model=model, inverse=_Stepper(model.op.inverse(), model.offset))
        return inverse_of["inverse"]

    def upd(t, x, u, params):
        cur = inv(params)
        return cur.step(x, u[0] - cur.offset)[1]

    def out(t, x, u, params):
        cur = inv(params)
        warn_if_zero_start(name, t, x, cur.initial_state)
        return np.array([cur.step(x, u[0] - cur.offset)[0]])

    try:
        inv(forward.params)
    except ValueError as err:
        raise ValueError(f"op: {err}") from err
    return Block(upd, out, own_state=lambda params: inv(params).initial_state,
                  aliases={f"{name}_z{i}": f"z_inv[{i}]" for i in range(1, op.n + 1)},
                  inputs=[input], outputs=[output], states=signal_labels("z_inv", op.n), dt=dt,
                  name=name, params=forward.params)


# -- radius estimator ------------------------------------------------------------------------

def _estimator_signature() -> dict[str, object]:
    """RadiusEstimator's keyword settings and defaults (new settings flow through)."""
    sig = inspect.signature(RadiusEstimator.__init__).parameters
    out = {k: p.default for k, p in sig.items()
           if p.kind is inspect.Parameter.KEYWORD_ONLY and k != "dt"}
    out.pop("known_linear_play", None)  # deprecated alias of linear_play
    return out


def radius_estimator(weights, *, dt: float, **settings) -> RadiusEstimator:
    """A :class:`~pimodel.RadiusEstimator` built from the blocks' setting names.

    Parameters
    ----------
    weights : array_like
        Known weights.
    dt : float
        Sample time [s].
    **settings
        Estimator settings; ``linear_play`` goes to the estimator's keyword for it, the others
        pass through unchanged (so settings the estimator gains later work here too).

    Returns
    -------
    RadiusEstimator

    Examples
    --------
    >>> from pimodel.blocks import radius_estimator
    >>> radius_estimator([1.0, 0.5], dt=1e-3, initial_radii=[0.1, 0.3], linear_play=True).radii
    array([0. , 0.3])
    """
    return RadiusEstimator(weights, dt=dt, **settings)


_EST_SCALARS = ("v_first", "v_start", "v_ext", "v_rev", "dir", "have_rev", "started", "time",
                "nseg", "head")
_EST_PROFILE = ("t_prev", "y_ext", "x_last", "y_last", "bin_width", "top_bin", "fitted")


def estimator_state_labels(est: RadiusEstimator) -> list[str]:
    """Labels of the estimator's flat state ``est.state`` (layout: :func:`estimator_block`).

    Parameters
    ----------
    est : RadiusEstimator

    Returns
    -------
    list of str
        One label per state entry; the estimator's own ``state_labels`` when it has them, and a
        layout this module does not know as ``r_hat[1..n]`` then ``internal[1..]``.

    Examples
    --------
    >>> from pimodel.blocks import estimator_state_labels, radius_estimator
    >>> estimator_state_labels(radius_estimator([1.0, 0.5], dt=1e-3))[:4]
    ['r_hat[1]', 'r_hat[2]', 'z_hat[1]', 'z_hat[2]']
    """
    size, n = est.state.size, est.n
    own = getattr(est, "state_labels", None)
    if own is not None and len(own) == size:
        return list(own)
    labels = (signal_labels("r_hat", n) + signal_labels("z_hat", n) + signal_labels("sat", n)
              + list(_EST_SCALARS)
              + signal_labels("v_buf", EST_WINDOW) + signal_labels("y_buf", EST_WINDOW)
              + list(_EST_PROFILE) + signal_labels("edge", n) + signal_labels("bin_sum", EST_BINS)
              + signal_labels("bin_travel", EST_BINS))
    if len(labels) != size:
        labels = signal_labels("r_hat", n) + signal_labels("internal", size - n)
    return labels


def estimator_block(weights, dt: float, *, gains=10.0, initial_radii=None,
                    linear_play: bool = False, name: str = "estimator",
                    inputs=("v", "y"), outputs=("y_hat", "e"), radius_prefix: str = "r_hat",
                    known_linear_play: bool | None = None,
                    **options) -> control.NonlinearIOSystem:
    """Radius estimator block: the C estimator of :class:`~pimodel.RadiusEstimator`.

    Per sample k it takes ``v[k]`` and the measured ``y[k]`` and outputs ``r_hat[k]`` (the radii
    held in the state, i.e. the estimate used at step k: no feedthrough), the model output
    ``y_hat[k]`` and ``e[k] = y_hat[k] - y[k]`` (feedthrough); the state update is one step of
    the estimator (see :mod:`pimodel.identification.adaptive.radius_estimator` for the law).

    Parameters
    ----------
    weights : array_like
        Known weights ``p_j > 0`` (n values).
    dt : float
        Sample time [s].
    gains, initial_radii, linear_play, **options
        Settings of :class:`~pimodel.RadiusEstimator` (``linear_play=True`` holds
        ``r_hat[1] = 0``; ``options``: ``threshold``, ``guard``, ``slope_window``, ... any
        keyword the estimator takes).
    name : str
        Block name; prefix of its params.
    inputs : tuple of str
        Names of the ``v`` and ``y`` inputs.
    outputs : tuple of str
        Names of the ``y_hat`` and ``e`` outputs.
    radius_prefix : str
        Base name of the radius outputs ``r_hat[1]..r_hat[n]``.
    known_linear_play : bool, optional
        Deprecated name of ``linear_play``.

    Returns
    -------
    control.NonlinearIOSystem
        Inputs ``inputs``, outputs ``r_hat[1..n]`` then ``outputs``.

    Notes
    -----
    Params: every estimator setting under ``"<name>.<setting>"``: ``weights``, ``gains``,
    ``initial_radii``, ``linear_play``, ``threshold``, ``max_step``, ``anneal_time``,
    ``guard``, ``slope_window``, ``slope_tol``, ``initial_state`` (the model's initial play
    state), and any setting the estimator gains later (``sys.params`` lists them).
    ``initial_radii`` and ``initial_state`` define the own initial state; the others change the
    law from the next sample.

    State layout (``sys.state_labels``, ``4 n + 657`` values, the estimator's flat state):

    ``r_hat[j]``
        radius estimate used at the next sample (n)
    ``z_hat[j]``
        model play states (n)
    ``sat[j]``
        1 if play j was saturated at the last reversal (n)
    ``v_first``
        first input sample
    ``v_start``
        start of the current monotone segment
    ``v_ext``
        running extreme of the segment
    ``v_rev``
        input at the last reversal
    ``dir``
        segment direction +1 / -1 (0 before the first move)
    ``have_rev``
        1 once a reversal has been seen
    ``started``
        1 once a sample has been processed
    ``time``
        elapsed time k dt [s] (gain annealing)
    ``nseg``
        samples since the last reversal
    ``head``
        ring-buffer position
    ``v_buf[i]``
        last inputs (slope check ring buffer, 64)
    ``y_buf[i]``
        last outputs (slope check ring buffer, 64)
    ``t_prev``, ``y_ext``, ``x_last``, ``y_last``
        branch profile: travel of the segment that ended at the last reversal, output at the
        running extreme, travel and output of the last profiled point
    ``bin_width``, ``top_bin``, ``fitted``
        travel-bin width (0 before the first reversal), highest bin with data (-1: none),
        1 once the regime table has been fitted
    ``edge[j]``
        fitted breakpoint: travel where play j joins its envelope (n)
    ``bin_sum[i]``, ``bin_travel[i]``
        pooled output change and travel per travel bin (256 each)

    At its first sample (``started == 0``) the block warns (:class:`InitialStateWarning`) when
    the state differs from its own initial state.

    Examples
    --------
    >>> import control, numpy as np
    >>> from pimodel.blocks import estimator_block, initial_state
    >>> est = estimator_block([1.0, 0.5], 1e-3, initial_radii=[0, 0.3], linear_play=True)
    >>> t = np.arange(3) * 1e-3
    >>> res = control.input_output_response(est, t, [np.zeros(3), np.zeros(3)],
    ...                                     initial_state=initial_state(est))
    >>> float(res.outputs[1][0])
    0.3
    """
    if known_linear_play is not None:
        warnings.warn("estimator_block: known_linear_play is deprecated; use linear_play",
                      DeprecationWarning, stacklevel=2)
        linear_play = known_linear_play
    dt = positive_scalar(dt, "dt")
    inputs, outputs = list(inputs), list(outputs)
    if len(inputs) != 2 or len(outputs) != 2:
        raise ValueError(f"inputs, outputs: expected two names each, got {inputs}, {outputs}")
    defaults = _estimator_signature()
    unknown = set(options) - set(defaults)
    if unknown:
        raise ValueError(f"options: unknown estimator setting(s) {sorted(unknown)}; known: "
                         f"{sorted(defaults)}")
    defaults.update(options, gains=gains, initial_radii=initial_radii, linear_play=linear_play)
    defaults = {"weights": weights, **defaults}

    def build(s: dict):
        s = dict(s)
        est = radius_estimator(s.pop("weights"), dt=dt, **s)
        return est, est.state

    settings = BlockSettings(name, defaults, build)
    est0 = settings.value[0]
    n = est0.n
    labels = estimator_state_labels(est0)
    started = labels.index("started") if "started" in labels else None

    def run(t, x, u, params):
        est, own = settings.get(params)
        if est.n != n:
            raise ValueError(f"block {name!r}: params give {est.n} weights, the block has {n}")
        if started is not None and x[started] == 0 and not np.array_equal(x, own):
            bad = [lab for lab, a, b in zip(labels, x, own, strict=True) if a != b][:4]
            warnings.warn(f"block {name!r} starts from a state that is not its own initial "
                          f"state (differs in {bad}); pass "
                          "initial_state=pimodel.blocks.initial_state(sys, params)",
                          InitialStateWarning, stacklevel=3)
        est.state = x
        r = est.radii
        _, yh, e, _ = est.step(u[0], u[1])
        return r, yh, e, est.state

    def upd(t, x, u, params):
        return run(t, x, u, params)[3]

    def out(t, x, u, params):
        r, yh, e, _ = run(t, x, u, params)
        return np.concatenate((r, [yh, e]))

    aliases = {f"{name}_s{i}": lab for i, lab in enumerate(labels)}
    aliases.update({f"{name}_y_hat": outputs[0], f"{name}_e": outputs[1]})
    return Block(upd, out, own_state=lambda params: settings.get(params)[1], aliases=aliases,
                  inputs=inputs, outputs=signal_labels(radius_prefix, n) + outputs, states=labels,
                  dt=dt, name=name, params=settings.params)


# -- adaptive compensator --------------------------------------------------------------------

def adaptive_compensator_block(weights, dt: float, *, name: str = "adaptive_inv",
                               input: str = "y_d", output: str = "v",
                               radius_prefix: str = "r_hat",
                               initial_state=0.0) -> control.NonlinearIOSystem:
    """Adaptive inverse compensator: inputs ``y_d[k]`` and the radii ``r_hat[1..n]`` (from an
    estimator block or the RadiusEstimator FMU, connected by name), output ``v[k]``.

    The state is the play state ``zm`` of a forward model with the current radii. At step k the
    exact inverse of ``(p, r_hat[k])`` is built with the inverse state consistent with ``zm``
    (``zinv_i = P_i zm_i + sum_{j>i} p_j zm_j``), stepped with ``y_d[k]`` to give ``v[k]``, and
    ``zm`` is advanced with ``v[k]`` (C core), so a change of radii never breaks the inverse's
    memory. The radii must keep ``r_hat[1] = 0`` (estimate with ``linear_play=True``).

    Parameters
    ----------
    weights : array_like
        Model weights ``p_j > 0``.
    dt : float
        Sample time [s].
    name, input, output : str
        Block name and signal names.
    radius_prefix : str
        Base name of the radius inputs.
    initial_state : float or array_like
        The forward model's play states before the first sample (scalar or n values).

    Returns
    -------
    control.NonlinearIOSystem
        Inputs ``[input, r_hat[1], ..., r_hat[n]]``, output ``[output]``, states
        ``zm[1]..zm[n]``.

    Notes
    -----
    Params: ``"<name>.weights"`` and ``"<name>.initial_state"``. State layout: ``zm[i]``, the
    forward model's play i after the previous sample.

    Examples
    --------
    >>> import control, numpy as np
    >>> from pimodel.blocks import adaptive_compensator_block, initial_state
    >>> comp = adaptive_compensator_block([1.0, 0.5], 1e-3)
    >>> t = np.arange(2) * 1e-3
    >>> u = [[0.0, 1.5], [0.0, 0.0], [0.3, 0.3]]
    >>> res = control.input_output_response(comp, t, u, initial_state=initial_state(comp))
    >>> res.outputs[0].round(3).tolist()
    [0.0, 1.1]
    """
    p = as_vector(weights, "weights")
    if np.any(p <= 0):
        raise ValueError("weights: every weight must be > 0")
    dt = positive_scalar(dt, "dt")
    n = p.size
    lib = _native.lib

    def build(s: dict):
        w = np.ascontiguousarray(as_vector(s["weights"], "weights", length=n))
        if np.any(w <= 0):
            raise ValueError("weights: every weight must be > 0")
        z0 = np.broadcast_to(as_vector(s["initial_state"], "initial_state"), (n,)).copy() \
            if np.size(s["initial_state"]) in (1, n) else None
        if z0 is None:
            raise ValueError(f"initial_state: expected a scalar or {n} values")
        return w, z0

    settings = BlockSettings(name, {"weights": p.copy(), "initial_state": initial_state}, build)

    def step(t, x, u, params):
        w, z0 = settings.get(params)
        zm = np.array(x, dtype=float)
        r = np.ascontiguousarray(u[1:], dtype=float)
        if not np.isfinite(u[0]):
            raise ValueError(f"{input}: input sample is {u[0]!r}; expected a finite number")
        v = lib.pim_adaptive_inverse_step(n, w, r, zm, float(u[0]))
        if np.isnan(v) or np.any(np.diff(r) < 0):
            raise ValueError(f"{name}: radii {r} not invertible (need {radius_prefix}[1] = 0, "
                             "sorted)")
        return v, zm, z0

    def upd(t, x, u, params):
        return step(t, x, u, params)[1]

    def out(t, x, u, params):
        v, _, z0 = step(t, x, u, params)
        warn_if_zero_start(name, t, x, z0)
        return np.array([v])

    return Block(upd, out, own_state=lambda params: settings.get(params)[1],
                  aliases={f"{name}_zm{i}": f"zm[{i}]" for i in range(1, n + 1)},
                  inputs=[input] + signal_labels(radius_prefix, n), outputs=[output],
                  states=signal_labels("zm", n), dt=dt, name=name, params=settings.params)


# -- PID -------------------------------------------------------------------------------------

def pid_block(kp: float, ki: float = 0.0, kd: float = 0.0, *, tf: float | None = None,
              dt: float, name: str = "pid", input: str = "e",
              output: str = "u") -> control.NonlinearIOSystem:
    """Discrete PID, backward Euler with filtered derivative (as the compiled loops).

    ``I[k] = I[k-1] + dt e[k]``, ``D[k] = (tf D[k-1] + kd (e[k] - e[k-1])) / (tf + dt)``,
    ``u[k] = kp e[k] + ki I[k] + D[k]``.

    Parameters
    ----------
    kp, ki, kd : float
        Gains (>= 0).
    tf : float, optional
        Derivative filter time constant [s]; default ``10 dt``.
    dt : float
        Sample time [s].
    name, input, output : str
        Block name and signal names.

    Returns
    -------
    control.NonlinearIOSystem
        Input ``[input]``, output ``[output]``, states ``I``, ``D``, ``e_prev``.

    Notes
    -----
    Params: ``"<name>.kp"``, ``"<name>.ki"``, ``"<name>.kd"``, ``"<name>.tf"``. State layout:
    ``I`` (integral ``I[k-1]``), ``D`` (filtered derivative ``D[k-1]``), ``e_prev``
    (``e[k-1]``); the own initial state is zero.

    Examples
    --------
    >>> import control, numpy as np
    >>> from pimodel.blocks import pid_block
    >>> pid = pid_block(1.0, 10.0, dt=0.1)
    >>> res = control.input_output_response(pid, np.arange(3) * 0.1, np.ones(3),
    ...                                     params={"pid.kp": 2.0})
    >>> res.outputs.round(3).tolist()
    [3.0, 4.0, 5.0]
    """
    dt = positive_scalar(dt, "dt")

    def build(s: dict):
        s = dict(s, tf=10 * dt if s["tf"] is None else s["tf"])
        for nm in ("kp", "ki", "kd", "tf"):
            val = s[nm]
            if not np.isscalar(val) or not np.isfinite(val) or val < 0:
                raise ValueError(f"{nm}: expected a finite number >= 0, got {val!r}")
        return float(s["kp"]), float(s["ki"]), float(s["kd"]), float(s["tf"])

    settings = BlockSettings(name, {"kp": kp, "ki": ki, "kd": kd, "tf": tf}, build)

    def nxt(x, e, params):
        p, i, d, f = settings.get(params)
        integ = x[0] + dt * e
        der = (f * x[1] + d * (e - x[2])) / (f + dt)
        return np.array([integ, der, e]), p * e + i * integ + der

    def upd(t, x, u, params):
        return nxt(x, u[0], params)[0]

    def out(t, x, u, params):
        return np.array([nxt(x, u[0], params)[1]])

    return Block(upd, out, own_state=lambda params: np.zeros(3),
                  aliases={f"{name}_{s}": s for s in ("I", "D", "e_prev")},
                  inputs=[input], outputs=[output], states=["I", "D", "e_prev"], dt=dt,
                  name=name, params=settings.params)
