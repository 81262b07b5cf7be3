"""Adaptive estimation of the play radii (Al Janaideh & Tan, Sec. III), robust form.

The law runs in the C core (``fmu/src/pim_estimator.c``, the same code the RadiusEstimator FMU
compiles); :mod:`pimodel.estimator_reference` is its NumPy specification. Per sample k, with
input ``v[k]`` (input unit, e.g. V) and measured output ``y[k]`` (output unit, e.g. um):

1. model ``zhat_j[k] = clamp(zhat_j[k-1], v[k] - rhat_j[k], v[k] + rhat_j[k])``,
   ``yhat[k] = sum_j p_j zhat_j[k]``, ``e[k] = yhat[k] - y[k]`` (paper eqs. 7-8);
2. monotone segments of v: direction ``s``, last reversal ``v_rev`` (declared once v has moved
   back from the running extreme by more than ``threshold``; samples within the threshold are
   not used), and whether each play was surely saturated at that reversal (the segment that
   ended there travelled ``>= 2 rhat_j + guard``; no measured output enters this test, so the
   choice of samples does not correlate with the noise). Holds keep ``s`` and are used (the
   play states do not move during a hold);
3. principal case from the input travel ``d = |v[k] - v_rev|``: play j on its envelope iff
   ``d >= 2 rhat_j[k]`` (no noisy output slope is differenced). Samples where an interior play
   was not saturated at the reversal (minor loops, the first segment) are not used, nor samples
   with ``d`` closer than ``guard`` to a breakpoint ``2 rhat_j`` (misclassification there biases
   the estimate under noise). Slope check: the measured output change over the
   ``slope_window`` samples before k (y[k] not used) must agree with the case model's change
   within ``slope_tol * min p`` per unit of travel, else the regime read from rhat is wrong
   (an overestimated radius whose play is already on its envelope) and the sample is skipped;
   without it an overestimate can run away.
   ``e_delta[k] = ybar - y[k] = s phi^T (r - rhat)`` with
   ``ybar = sum_on p_j (v - s rhat_j) + sum_interior p_j (v_rev + s rhat_j)`` and
   ``phi_j = +p_j`` (on envelope) or ``-p_j`` (interior), i.e. ``sgn(i - j) p_j`` (eq. 19);
4. ``rhat[k+1] = Proj(rhat[k] + dt * gain_j(t) * e_delta[k] * s * phi_j)`` with
   ``gain_j(t) = gains_j / (1 + t / anneal_time)`` (constant when ``anneal_time`` is None),
   optionally clipped to ``max_step`` per sample; ``Proj`` is the projection (weighted by
   ``1/gains``) onto ``0 <= rhat_1 <= ... <= rhat_n``, with ``rhat_1 = 0`` held when
   ``known_linear_play``.

The discrete law is stable when ``dt * gains_j * |phi|^2 < 2`` (e.g. the piezo stage with
``|p|^2 = 43.5`` and gains 20 needs ``dt < 2.3 ms``); :func:`pimodel.identify` scales its
default gains by ``1 / sum p^2``.
"""

from __future__ import annotations

import ctypes
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from . import _native
from .checks import as_signal, as_vector, integer_in, positive_scalar

_lib = _native.lib
_F64 = _native.F64
_F64N = _native.F64_OR_NULL
_lib.pim_est_sizeof.restype = ctypes.c_size_t
_lib.pim_est_init.restype = ctypes.c_char_p
_lib.pim_est_init.argtypes = [ctypes.c_void_p, ctypes.c_size_t, _F64, _F64, _F64, ctypes.c_double,
                              ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_double,
                              ctypes.c_double, ctypes.c_int]
_lib.pim_est_step.restype = ctypes.c_int
_D = ctypes.POINTER(ctypes.c_double)
_lib.pim_est_step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, _F64N, _D, _D,
                              _D]
_lib.pim_est_run.restype = ctypes.c_long
_lib.pim_est_run.argtypes = [ctypes.c_void_p, ctypes.c_size_t, _F64, _F64, _F64N, _F64, _F64,
                             _F64, _F64N]
_lib.pim_est_get_state.restype = None
_lib.pim_est_get_state.argtypes = [ctypes.c_void_p, _F64]
_lib.pim_est_set_state.restype = ctypes.c_char_p
_lib.pim_est_set_state.argtypes = [ctypes.c_void_p, _F64]
_lib.pim_est_set_slope_check.restype = ctypes.c_char_p
_lib.pim_est_set_slope_check.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_double]
EST_WINDOW = 64  # PIM_EST_WIN in pim_estimator.h
_lib.pim_project_ordered.restype = None
_lib.pim_project_ordered.argtypes = [ctypes.c_size_t, _F64, _F64, ctypes.c_int]

MAX_PLAYS = 64


def project_ordered(x, weights=None, *, fix_first: bool = False) -> np.ndarray:
    """Weighted projection of ``x`` onto ``0 <= x_1 <= ... <= x_n`` (C core)."""
    out = np.array(as_vector(x, "x"), dtype=float)
    w = np.ones_like(out) if weights is None else as_vector(weights, "weights", length=out.size)
    _lib.pim_project_ordered(out.size, out, np.ascontiguousarray(w), int(fix_first))
    return out


@dataclass
class RadiusEstimate:
    """Result of :func:`estimate_radii`.

    ``history[k]`` is the estimate used at step k (before that step's update), so
    ``history[0]`` is the (projected) initial guess and ``radii`` the estimate after the last
    sample. ``error[k] = yhat[k] - y[k]``, ``modified_error[k]`` is ``e_delta[k]`` (0 where
    the sample was not used), ``used[k]`` whether sample k adapted the radii.
    """

    radii: np.ndarray
    history: np.ndarray
    error: np.ndarray
    modified_error: np.ndarray
    model_output: np.ndarray
    used: np.ndarray
    dt: float

    def mean_radii(self, last_seconds: float) -> np.ndarray:
        """Average of the estimate over the last ``last_seconds`` of the record."""
        k = max(1, int(round(last_seconds / self.dt)))
        return self.history[-k:].mean(axis=0)


class RadiusEstimator:
    """Streaming radius estimator: :meth:`step` takes one sample ``(v[k], y[k])``.

    Parameters: ``weights`` p_j > 0 (known, e.g. from the loop slopes), ``dt`` sample time [s],
    ``gains`` (scalar or per play, >= 0; the paper's Lambda diagonal), ``initial_radii``
    (projected onto the ordered set), ``known_linear_play`` (hold rhat_1 = 0), ``threshold``
    (reversal threshold, input unit), ``max_step`` (per-sample clip of the update, input unit),
    ``guard`` (breakpoint guard band, input unit), ``slope_window`` and ``slope_tol`` (the slope
    check: samples, 0 to disable; tolerance in units of the smallest weight),
    ``anneal_time`` (gain annealing time constant [s]), ``initial_state`` (model play state).
    See the module docstring for the exact discrete-time law.
    """

    def __init__(self, weights, *, dt: float, gains=10.0, initial_radii=None,
                 known_linear_play: bool = False, threshold: float = 0.0,
                 max_step: float | None = None, anneal_time: float | None = None,
                 guard: float = 0.0, slope_window: int = 8, slope_tol: float = 0.5,
                 initial_state: float = 0.0):
        p = as_vector(weights, "weights")
        n = p.size
        if n > MAX_PLAYS:
            raise ValueError(f"weights: at most {MAX_PLAYS} plays are supported, got {n}")
        if np.any(p <= 0):
            raise ValueError("weights: every weight must be > 0")
        g = as_vector(gains, "gains")
        g = np.full(n, g[0]) if g.size == 1 else g
        if g.size != n:
            raise ValueError(f"gains: expected a scalar or {n} values, got {g.size}")
        if np.any(g < 0):
            raise ValueError("gains: every gain must be >= 0")
        if initial_radii is None:
            r0 = np.zeros(n)
        else:
            r0 = as_vector(initial_radii, "initial_radii")
            if r0.size != n:
                raise ValueError(
                    f"initial_radii: expected {n} values (one per weight), got {r0.size}"
                )
            if np.any(r0 < 0):
                raise ValueError("initial_radii: every radius must be >= 0")
        self.dt = positive_scalar(dt, "dt")
        if threshold < 0 or not np.isfinite(threshold):
            raise ValueError(f"threshold: expected a finite number >= 0, got {threshold!r}")
        ms = 0.0 if max_step is None else positive_scalar(max_step, "max_step")
        at = 0.0 if anneal_time is None else positive_scalar(anneal_time, "anneal_time")
        if not np.isfinite(guard) or guard < 0:
            raise ValueError(f"guard: expected a finite number >= 0, got {guard!r}")
        self.n = n
        self.weights = p
        self.gains = np.ascontiguousarray(g, dtype=float)
        self.known_linear_play = bool(known_linear_play)
        self._buf = ctypes.create_string_buffer(_lib.pim_est_sizeof())
        msg = _lib.pim_est_init(self._buf, n, p, self.gains, np.ascontiguousarray(r0), self.dt,
                                float(initial_state), float(threshold), ms, at, float(guard),
                                int(self.known_linear_play))
        if msg:
            raise ValueError(msg.decode())
        if int(slope_window) != slope_window:
            raise ValueError(f"slope_window: expected an integer, got {slope_window!r}")
        msg = _lib.pim_est_set_slope_check(self._buf, int(slope_window), float(slope_tol))
        if msg:
            raise ValueError(msg.decode())
        self._state_size = 3 * n + 10 + 2 * EST_WINDOW
        self._initial = self.state

    @property
    def radii(self) -> np.ndarray:
        """Current estimate rhat (after the last step)."""
        return self.state[: self.n].copy()

    @property
    def state(self) -> np.ndarray:
        """Everything needed to resume, as a flat array of ``3 n + 138`` floats."""
        s = np.empty(self._state_size)
        _lib.pim_est_get_state(self._buf, s)
        return s

    @state.setter
    def state(self, value) -> None:
        s = as_vector(value, "state", length=self._state_size)
        msg = _lib.pim_est_set_state(self._buf, np.ascontiguousarray(s))
        if msg:
            raise ValueError(msg.decode())

    def reset(self) -> None:
        """Back to the state right after construction."""
        self.state = self._initial

    def step(self, v: float, y: float) -> tuple[np.ndarray, float, float, float]:
        """Process sample k: returns ``(rhat[k+1], yhat[k], e[k], e_delta[k])``."""
        yh, e, ed = ctypes.c_double(), ctypes.c_double(), ctypes.c_double()
        rc = _lib.pim_est_step(self._buf, float(v), float(y), None, ctypes.byref(yh),
                               ctypes.byref(e), ctypes.byref(ed))
        if rc < 0:
            raise ValueError(f"v, y: samples must be finite, got v={v!r}, y={y!r}")
        return self.radii, yh.value, e.value, ed.value

    def run(self, v, y) -> RadiusEstimate:
        """Process whole arrays from the current state (batch, C loop)."""
        x = as_signal(v, "v", min_length=2)
        m = as_signal(y, "y", min_length=2)
        if x.size != m.size:
            raise ValueError(f"v and y: expected equal lengths, got {x.size} and {m.size}")
        N = x.size
        R = np.empty((N, self.n))
        yhat, e, ed, used = (np.empty(N) for _ in range(4))
        bad = _lib.pim_est_run(self._buf, N, x, m, R, yhat, e, ed, used)
        if bad >= 0:  # unreachable after validation; kept as a guard
            raise ValueError(f"v, y: sample {bad} is not finite")
        return RadiusEstimate(self.radii, R, e, ed, yhat, used.astype(bool), self.dt)


def estimate_radii(v, y, weights, *, dt: float, gains=10.0, initial_radii=None,
                   known_linear_play: bool = False, threshold: float = 0.0,
                   max_step: float | None = None, anneal_time: float | None = None,
                   guard: float = 0.0, slope_window: int = 8, slope_tol: float = 0.5,
                   initial_state: float = 0.0) -> RadiusEstimate:
    """Estimate the play radii from a record ``(v[k], y[k])``, k = 0..N-1, sampled every ``dt``.

    Runs :class:`RadiusEstimator` over the arrays (the C batch loop); see the module docstring
    for the law and its options. Returns a :class:`RadiusEstimate`.
    """
    est = RadiusEstimator(weights, dt=dt, gains=gains, initial_radii=initial_radii,
                          known_linear_play=known_linear_play, threshold=threshold,
                          max_step=max_step, anneal_time=anneal_time, guard=guard,
                          slope_window=slope_window, slope_tol=slope_tol,
                          initial_state=initial_state)
    return est.run(v, y)


def stream_tail_average(estimator: RadiusEstimator, chunks: Iterable[tuple], *, total: int,
                        tail: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Run ``estimator`` over a record given as ``(v, y)`` chunks (``total`` samples in all) and
    return ``(final radii, mean of rhat[k] over the last tail fraction of the samples)``.

    Averaging the iterates (Polyak-Ruppert) is how the estimate reaches the accuracy the data
    allow under heavy output noise; the constant-gain iterate itself keeps fluctuating. Memory
    is bounded by the chunk size, so records of 10^8 samples are fine
    (:mod:`pimodel.long_records` makes such chunks).
    """
    total = integer_in(total, "total", 2)
    if not 0 < tail <= 1:
        raise ValueError(f"tail: expected a fraction in (0, 1], got {tail!r}")
    start = int(total * (1 - tail))
    acc = np.zeros(estimator.n)
    a = 0
    for v, y in chunks:
        x = as_signal(v, "v")
        m = as_signal(y, "y")
        if x.size != m.size:
            raise ValueError(f"v and y: expected equal chunk lengths, got {x.size} and {m.size}")
        if a + x.size > total:
            raise ValueError(f"chunks: more than total={total} samples")
        if x.size == 1:  # a single sample: step it (history holds the estimate before it)
            hist = estimator.radii[None, :]
            estimator.step(x[0], m[0])
        else:
            hist = estimator.run(x, m).history
        lo = max(start - a, 0)
        if lo < x.size:
            acc += hist[lo:].sum(axis=0)
        a += x.size
    if a != total:
        raise ValueError(f"chunks: expected {total} samples in all, got {a}")
    return estimator.radii, acc / (total - start)


def run_tail_average(estimator: RadiusEstimator, v, y, *, tail: float = 0.5,
                     chunk: int = 1_000_000) -> tuple[np.ndarray, np.ndarray]:
    """:func:`stream_tail_average` over whole arrays ``v``, ``y``, processed in chunks."""
    x = as_signal(v, "v", min_length=2)
    m = as_signal(y, "y", min_length=2)
    if x.size != m.size:
        raise ValueError(f"v and y: expected equal lengths, got {x.size} and {m.size}")
    chunks = ((x[a:a + chunk], m[a:a + chunk]) for a in range(0, x.size, chunk))
    return stream_tail_average(estimator, chunks, total=x.size, tail=tail)
