"""Adaptive estimation of the play radii (Al Janaideh & Tan, Sec. III), robust form.

The law runs in the C core (``fmu/src/pim_estimator.c``, the same code the RadiusEstimator FMU
compiles); :mod:`pimodel.reference.radius_estimator` is its NumPy specification. Per sample k, with
input ``v[k]`` (input unit, e.g. V) and measured output ``y[k]`` (output unit, e.g. um):

1. model ``zhat_j[k] = clamp(zhat_j[k-1], v[k] - rhat_j[k], v[k] + rhat_j[k])``,
   ``yhat[k] = sum_j p_j zhat_j[k]``, ``e[k] = yhat[k] - y[k]`` (paper eqs. 7-8);
2. monotone segments of v: direction ``s``, last reversal ``v_rev`` (declared once v has moved
   back from the running extreme by more than ``threshold``; samples within the threshold are
   not used), the travel ``t_prev`` of the segment that ended there, and whether each play was
   surely saturated at that reversal. Holds keep ``s``;
3. principal case at the input travel ``d = |v[k] - v_rev|``: which plays are on their
   envelope. Two laws decide it:

   ``law="data"`` (default): from the measured branches. Along a branch, for ``d <= t_prev``,
   the output change is ``s (y - y_rev) = F(d) = sum_j p_j max(0, d - 2 r_j)`` whatever the
   earlier history (Madelung's rule), with slopes ``P_i = p_1 + ... + p_i``. The increments
   ``s (y[k] - y[k-1])`` are pooled over all branches in 256 bins of travel (the bin width is
   set from the first segment and doubled as the travel grows), and at every reversal the
   non-decreasing count ``i_b`` of plays on their envelope that best fits the pooled slopes
   (least squares against the levels ``P_i``, an exact dynamic programme over bins) gives the
   breakpoints ``edge_j`` (refitted also whenever the profile reaches a new bin). Play j is
   on its envelope iff ``d >= edge_j``; within the band ``g = max(guard, one bin width)`` of
   ``edge_j`` the estimate decides (``d >= 2 rhat_j``) if ``2 rhat_j`` lies in the band and
   ``d`` is at least ``guard`` from it, else the sample is skipped. An interior play must be
   surely saturated at the reversal (``edge_j + g <= t_prev``). While the profile does not yet
   cover ``t_prev`` (the first branches), a play whose breakpoint has not been profiled follows
   the paper's rule. Far from the truth the regime no longer depends on the estimate, so the
   law has one fixed point, the truth, from any start.

   ``law="paper"``: the paper's rule, from the estimate: on iff ``d >= 2 rhat_j[k]``, a play
   saturated at the reversal iff ``t_prev >= 2 rhat_j + guard``, samples within ``guard`` of a
   breakpoint ``2 rhat_j`` skipped, and the slope check (the measured output change over the
   ``slope_window`` samples before k must agree with the case model's within
   ``slope_tol * min p`` per unit of travel). It converges from starts above the truth but
   can lock onto wrong fixed points from below, equal or mixed starts (plays merge).

   Then ``e_delta[k] = ybar - y[k] = s phi^T (r - rhat)`` with
   ``ybar = sum_on p_j (v - s rhat_j) + sum_interior p_j (v_rev + s rhat_j)`` and
   ``phi_j = +p_j`` (on envelope) or ``-p_j`` (interior), i.e. ``sgn(i - j) p_j`` (eq. 19);
4. ``rhat[k+1] = Proj(rhat[k] + dt * gain_j(t) * e_delta[k] * s * phi_j)`` with
   ``gain_j(t) = gains_j / (1 + t / anneal_time)`` (constant when ``anneal_time`` is None),
   optionally clipped to ``max_step`` per sample; ``Proj`` is the projection (weighted by
   ``1/gains``) onto ``0 <= rhat_1 <= ... <= rhat_n``, with ``rhat_1 = 0`` held when
   ``linear_play``.

The discrete law is stable when ``dt * gains_j * |p|^2 < 2``
(:func:`pimodel.identification.adaptive.settings.stability_bound`; a larger gain gives a warning).
:func:`estimate_radii` picks gains, guard, threshold and slope check from the record when they
are left at None (:func:`pimodel.identification.adaptive.settings.default_settings`) and reports
the health
of the result (:mod:`pimodel.identification.adaptive.health`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from ... import _native
from ...checks import (
    as_signal,
    as_vector,
    integer_in,
    positive_scalar,
    scalar_or_vector,
)
from .health import EstimatorHealth, estimator_health, refined_health
from .polish import refine_radii
from .settings import check_gains, check_weights, default_settings

__all__ = [
    "estimate_radii",
    "project_ordered",
    "RadiusEstimate",
    "RadiusEstimator",
    "run_tail_average",
    "stream_tail_average",
]

_lib = _native.lib
EST_WINDOW = _native.LIMITS["PIM_EST_WIN"]
EST_BINS = _native.LIMITS["PIM_EST_BINS"]
LAWS = {"data": _native.LIMITS["PIM_LAW_DATA"], "paper": _native.LIMITS["PIM_LAW_PAPER"]}

MAX_PLAYS = _native.LIMITS["PIM_MAX_PLAYS"]


def project_ordered(x, weights=None, *, fix_first: bool = False) -> np.ndarray:
    """Weighted projection of ``x`` onto ``0 <= x_1 <= ... <= x_n`` (C core).

    Minimises ``sum_j w_j (x'_j - x_j)^2`` over the ordered set (pool-adjacent-violators, then
    clipping at 0); :func:`pimodel.reference.radius_estimator.project_ordered_reference` is the
    NumPy
    specification.

    Parameters
    ----------
    x : array_like of float, shape (n,)
        The point to project (e.g. radii, input unit).
    weights : array_like of float, shape (n,), optional
        Positive weights ``w_j`` of the norm (default all 1).
    fix_first : bool, optional
        Also hold ``x_1 = 0`` (a linear play).

    Returns
    -------
    numpy.ndarray of float, shape (n,)
        The projection (a new array).

    Raises
    ------
    ValueError
        If ``x`` or ``weights`` is not a finite vector, or their lengths differ.

    Examples
    --------
    >>> project_ordered([0.5, 0.2, 1.0])
    array([0.35, 0.35, 1.  ])
    >>> project_ordered([0.5, 0.2, 1.0], fix_first=True)
    array([0. , 0.2, 1. ])
    """
    out = np.array(as_vector(x, "x"), dtype=float)
    w = np.ones_like(out) if weights is None else as_vector(weights, "weights", length=out.size)
    _lib.pim_project_ordered(out.size, out, np.ascontiguousarray(w), int(fix_first))
    return out


@dataclass
class RadiusEstimate:
    """Result of :func:`estimate_radii` and :meth:`RadiusEstimator.run`.

    Parameters
    ----------
    radii : numpy.ndarray of float, shape (n,)
        The estimate after the last sample, ``rhat[N]`` (input unit).
    history : numpy.ndarray of float, shape (N, n)
        ``history[k]`` is the estimate used at step k (before that step's update), so
        ``history[0]`` is the (projected) initial guess.
    error : numpy.ndarray of float, shape (N,)
        ``e[k] = yhat[k] - y[k]`` (output unit).
    modified_error : numpy.ndarray of float, shape (N,)
        ``e_delta[k]`` (output unit; 0 where the sample was not used).
    model_output : numpy.ndarray of float, shape (N,)
        ``yhat[k]``, the model with the current estimate (output unit).
    used : numpy.ndarray of bool, shape (N,)
        Whether sample k adapted the radii.
    dt : float
        Sample time [s].
    radii_mean : numpy.ndarray of float, shape (n,), optional
        Mean of ``history`` over the last half of the record (None below
        ``MIN_MEAN_SAMPLES`` samples): under output noise the constant-gain iterate keeps
        fluctuating and the mean is the estimate to use.
    health : EstimatorHealth, optional
        From :func:`estimate_radii`: whether the estimate can be trusted, see
        :mod:`pimodel.identification.adaptive.health`.
    settings : dict, optional
        The settings :func:`estimate_radii` used (gains, threshold, guard, slope window, law,
        polish).
    online_radii : numpy.ndarray of float, shape (n,), optional
        From :func:`estimate_radii` with ``polish=True``: the online law's own estimate
        (``radii_mean`` when there is one, else the final iterate), before the batch
        refinement; ``radii`` is then the refined estimate. None otherwise.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = np.sin(np.linspace(0, 20, 2000))          # 2 s at dt = 1 ms
    >>> y = PIOperator([1.0, 1.0], [0.0, 0.3]).simulate(v)
    >>> res = RadiusEstimator([1.0, 1.0], dt=1e-3).run(v, y)
    >>> res.history.shape, res.radii.round(2)
    ((2000, 2), array([0. , 0.3]))
    """

    radii: np.ndarray
    history: np.ndarray
    error: np.ndarray
    modified_error: np.ndarray
    model_output: np.ndarray
    used: np.ndarray
    dt: float
    radii_mean: np.ndarray | None = None
    health: EstimatorHealth | None = None
    settings: dict | None = None
    online_radii: np.ndarray | None = None

    def fmu_start_values(self) -> dict:
        """The RadiusEstimator FMU's start values for the settings this run used.

        With them (and the same weights, initial radii, ``Ts`` and ``linear_play``) the FMU
        gives :func:`estimate_radii`'s online iterate (``polish=False``) to 1e-12; this is how
        the self-tuned settings of :func:`estimate_radii` reach the FMU.

        Returns
        -------
        dict
            ``gain``, ``guard``, ``threshold``, ``slope_window``, ``law`` (0 data, 1 paper).

        Raises
        ------
        ValueError
            When the run has no ``settings`` (it came from :meth:`RadiusEstimator.run`) or
            per-play gains differ (the FMU has one gain).

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> v = np.sin(np.linspace(0, 20, 2000))          # 2 s at dt = 1 ms
        >>> y = PIOperator([1.0, 1.0], [0.0, 0.3]).simulate(v)
        >>> estimate_radii(v, y, [1.0, 1.0], dt=1e-3).fmu_start_values()["slope_window"]
        8
        """
        if self.settings is None:
            raise ValueError("settings: this result has none; use estimate_radii")
        g = np.atleast_1d(np.asarray(self.settings["gains"], float))
        if np.ptp(g) > 0:
            raise ValueError(f"settings: the FMU has one gain, got per-play gains {g.tolist()}")
        return {"gain": float(g[0]), "guard": float(self.settings["guard"]),
                "threshold": float(self.settings["threshold"]),
                "slope_window": int(self.settings["slope_window"]),
                "law": LAWS[self.settings["law"]]}

    def mean_radii(self, last_seconds: float) -> np.ndarray:
        """Average of the estimate over the last ``last_seconds`` of the record.

        Parameters
        ----------
        last_seconds : float
            Length of the averaged tail [s] (at least one sample).

        Returns
        -------
        numpy.ndarray of float, shape (n,)
            Mean of ``history`` over that tail (input unit).

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> v = np.sin(np.linspace(0, 20, 2000))          # 2 s at dt = 1 ms
        >>> y = PIOperator([1.0, 1.0], [0.0, 0.3]).simulate(v)
        >>> res = RadiusEstimator([1.0, 1.0], dt=1e-3).run(v, y)
        >>> res.mean_radii(0.5).round(2)
        array([0. , 0.3])
        """
        k = max(1, int(round(last_seconds / self.dt)))
        return self.history[-k:].mean(axis=0)


MIN_MEAN_SAMPLES = 1000  # radii_mean needs a record at least this long


def _renamed_linear_play(linear_play: bool, known_linear_play: bool | None, where: str) -> bool:
    """``linear_play``, or the deprecated ``known_linear_play`` when that was given."""
    if known_linear_play is None:
        return linear_play
    warnings.warn(f"{where}: known_linear_play is deprecated; use linear_play",
                  DeprecationWarning, stacklevel=3)
    return bool(known_linear_play)


class RadiusEstimator:
    """Streaming radius estimator: :meth:`step` takes one sample ``(v[k], y[k])``.

    See the module docstring for the exact discrete-time law.

    Parameters
    ----------
    weights : array_like of float, shape (n,)
        Play weights ``p_j > 0`` (known, e.g. from the loop slopes), n <= 64.
    dt : float
        Sample time [s].
    gains : float or array_like of float, optional
        Adaptation gains (scalar or per play, >= 0; the paper's Lambda diagonal). Above the
        stability bound ``2 / (dt |p|^2)`` a ``UserWarning`` is issued. Default 10.
    initial_radii : array_like of float, shape (n,), optional
        Start of the estimate (projected onto the ordered set); default all 0.
    linear_play : bool, optional
        Hold ``rhat_1 = 0``.
    threshold : float, optional
        Reversal threshold (input unit). Default 0.
    max_step : float, optional
        Per-sample clip of the update (input unit); default no clip.
    anneal_time : float, optional
        Gain annealing time constant [s]; default constant gains.
    guard : float, optional
        Breakpoint guard band (input unit). Default 0.
    slope_window : int, optional
        Samples of the slope check (0 disables it; ``law="paper"`` only). Default 8.
    slope_tol : float, optional
        Tolerance of the slope check, in units of the smallest weight. Default 0.5.
    initial_state : float, optional
        Model play state ``zhat_j[-1]`` (input unit). Default 0.
    law : {"data", "paper"}, optional
        ``"data"`` (default): regime from the measured branches; ``"paper"``: regime from the
        estimate.
    known_linear_play : bool, optional
        Deprecated name of ``linear_play`` (DeprecationWarning).

    Raises
    ------
    ValueError
        Bad weights (non-positive, more than 64), gains, initial radii, ``dt``, threshold,
        guard, slope check settings or ``law`` (the message names the argument).

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel import PIOperator
    >>> p, r = [0.3, 0.5, 0.8, 0.3, 0.2], [0.4, 1, 1.5, 2, 3.6]
    >>> v = 30 * np.sin(2 * np.pi * np.arange(0, 150, 1e-3))
    >>> est = RadiusEstimator(p, dt=1e-3, gains=10, initial_radii=[0] * 5)
    >>> np.round(est.run(v, PIOperator(p, r).simulate(v)).radii, 2)
    array([0.4, 1. , 1.5, 2. , 3.6])
    """

    def __init__(self, weights, *, dt: float, gains=10.0, initial_radii=None,
                 linear_play: bool = False, threshold: float = 0.0,
                 max_step: float | None = None, anneal_time: float | None = None,
                 guard: float = 0.0, slope_window: int = 8, slope_tol: float = 0.5,
                 initial_state: float = 0.0, law: str = "data",
                 known_linear_play: bool | None = None):
        linear_play = _renamed_linear_play(linear_play, known_linear_play, "RadiusEstimator")
        p = as_vector(weights, "weights")
        n = p.size
        if n > MAX_PLAYS:
            raise ValueError(f"weights: at most {MAX_PLAYS} plays are supported, got {n}")
        check_weights(p)
        g = scalar_or_vector(gains, "gains", n)
        if np.any(g < 0):
            raise ValueError("gains: every gain must be >= 0")
        if law not in LAWS:
            raise ValueError(f"law: expected one of {sorted(LAWS)}, got {law!r}")
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
        check_gains(g, p, self.dt)
        self.n = n
        self.law = law
        self.weights = p
        self.gains = np.ascontiguousarray(g, dtype=float)
        self.linear_play = bool(linear_play)
        self._buf = _native.estimator_buffer()
        msg = _lib.pim_est_init(self._buf, n, p, self.gains, np.ascontiguousarray(r0), self.dt,
                                float(initial_state), float(threshold), ms, at, float(guard),
                                int(self.linear_play))
        if msg:
            raise ValueError(msg.decode())
        if int(slope_window) != slope_window:
            raise ValueError(f"slope_window: expected an integer, got {slope_window!r}")
        msg = _lib.pim_est_set_slope_check(self._buf, int(slope_window), float(slope_tol))
        if msg:
            raise ValueError(msg.decode())
        _lib.pim_est_set_law(self._buf, LAWS[law])
        self._state_size = 4 * n + 17 + 2 * EST_WINDOW + 2 * EST_BINS
        self._initial = self.state

    @classmethod
    def for_record(cls, v, y, weights, *, dt: float, **options) -> RadiusEstimator:
        """An estimator with the settings :func:`default_settings` picks from ``(v, y)``.

        ``v``, ``y`` may be the first part of a longer record (e.g. the first chunk of a
        stream); ``options`` (e.g. ``initial_radii``, ``law``) override or add keywords.

        Examples
        --------
        >>> import numpy as np
        >>> v = 30 * np.sin(2 * np.pi * np.arange(0, 5, 1e-3))
        >>> est = RadiusEstimator.for_record(v, 2 * v, [1.0, 1.0], dt=1e-3)
        >>> float(est.gains[0])
        10.0
        """
        auto = default_settings(v, y, weights, dt=dt)
        kw = {k: auto[k] for k in ("gains", "guard", "threshold", "slope_window")}
        kw.update(options)
        return cls(weights, dt=dt, **kw)

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
        """Back to the state right after construction.

        Examples
        --------
        >>> est = RadiusEstimator([1.0, 1.0], dt=1e-3, initial_radii=[0.2, 0.1])
        >>> _ = est.step(0.5, 1.0)
        >>> est.reset()
        >>> est.radii
        array([0.15, 0.15])
        """
        self.state = self._initial

    def step(self, v: float, y: float) -> tuple[np.ndarray, float, float, float]:
        """Process sample k: returns ``(rhat[k+1], yhat[k], e[k], e_delta[k])``.

        Parameters
        ----------
        v : float
            Input sample ``v[k]`` (input unit).
        y : float
            Measured output ``y[k]`` (output unit).

        Returns
        -------
        radii : numpy.ndarray of float, shape (n,)
            ``rhat[k+1]``, the estimate after this sample's update.
        model_output : float
            ``yhat[k]``, the model output with ``rhat[k]``.
        error : float
            ``e[k] = yhat[k] - y[k]``.
        modified_error : float
            ``e_delta[k]`` (0 when the sample was not used).

        Raises
        ------
        ValueError
            If ``v`` or ``y`` is not finite.

        Examples
        --------
        >>> est = RadiusEstimator([1.0, 1.0], dt=1e-3, initial_radii=[0.2, 0.1])
        >>> est.radii                       # the start, projected onto the ordered set
        array([0.15, 0.15])
        >>> rhat, yhat, e, e_delta = est.step(0.5, 1.0)
        >>> rhat, yhat, round(e, 12)
        (array([0.15, 0.15]), 0.7, -0.3)
        """
        rc, yh, e, ed = _native.estimator_step(self._buf, float(v), float(y))
        if rc < 0:
            raise ValueError(f"v, y: samples must be finite, got v={v!r}, y={y!r}")
        return self.radii, yh, e, ed

    def run(self, v, y) -> RadiusEstimate:
        """Process whole arrays from the current state (batch, C loop).

        Parameters
        ----------
        v : array_like of float, shape (N,)
            Input samples ``v[k]`` (input unit), N >= 2.
        y : array_like of float, shape (N,)
            Measured output ``y[k]`` (output unit).

        Returns
        -------
        RadiusEstimate
            History, errors and the final estimate; the estimator's state has advanced by N
            samples (no ``health``: see :func:`estimate_radii`).

        Raises
        ------
        ValueError
            Non-finite samples or unequal lengths.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> v = np.sin(np.linspace(0, 20, 2000))          # 2 s at dt = 1 ms
        >>> y = PIOperator([1.0, 1.0], [0.0, 0.3]).simulate(v)
        >>> RadiusEstimator([1.0, 1.0], dt=1e-3).run(v, y).radii.round(2)
        array([0. , 0.3])
        """
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
        mean = R[N // 2:].mean(axis=0) if N >= MIN_MEAN_SAMPLES else None
        return RadiusEstimate(self.radii, R, e, ed, yhat, used.astype(bool), self.dt, mean)


def estimate_radii(v, y, weights, *, dt: float, gains=None, initial_radii=None,
                   linear_play: bool = False, threshold: float | None = None,
                   max_step: float | None = None, anneal_time: float | None = None,
                   guard: float | None = None, slope_window: int | None = None,
                   slope_tol: float = 0.5, initial_state: float = 0.0, law: str = "data",
                   warn: bool = False, known_linear_play: bool | None = None,
                   polish: bool = True) -> RadiusEstimate:
    """Estimate the play radii from a record ``(v[k], y[k])``, k = 0..N-1, sampled every ``dt``.

    Runs :class:`RadiusEstimator` over the arrays (the C batch loop); see the module docstring
    for the law.

    Parameters
    ----------
    v, y : array_like
        Input [input unit] and measured output [output unit], equal lengths >= 2.
    weights : array_like
        Known play weights p_j > 0.
    dt : float
        Sample time [s].
    gains, threshold, guard, slope_window : optional
        None (default): chosen from the record by
        :func:`pimodel.identification.adaptive.settings.default_settings` (noise level, input
        range, dt).
    initial_radii : array_like, optional
        Start (default all 0); any start converges under ``law="data"``.
    linear_play, max_step, anneal_time, slope_tol, initial_state, law
        As for :class:`RadiusEstimator`.
    warn : bool
        Issue a ``UserWarning`` when the health report fails.
    known_linear_play : bool, optional
        Deprecated name of ``linear_play``.
    polish : bool, optional
        Default True: refine the online estimate in batch
        (:func:`pimodel.identification.adaptive.polish.refine_radii`: Gauss-Newton least
        squares over the whole record, from the online estimate or the branch profile,
        whichever fits better); ``radii`` is then the refined estimate and ``online_radii`` the
        online one. False: ``radii`` is the online law's final iterate, exactly what the
        RadiusEstimator FMU gives with the same settings.

    Returns
    -------
    RadiusEstimate
        With ``radii`` (refined, or the final iterate with ``polish=False``), ``radii_mean``
        (mean of the online iterate over the last half), ``online_radii``, ``health`` and the
        ``settings`` used.

    Raises
    ------
    ValueError
        Bad arrays or parameters (the message names the argument).

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel import PIOperator
    >>> p, r = [0.3, 0.5, 0.8, 0.3, 0.2], [0.4, 1, 1.5, 2, 3.6]
    >>> v = 30 * np.sin(2 * np.pi * np.arange(0, 150, 1e-3))
    >>> res = estimate_radii(v, PIOperator(p, r).simulate(v), p, dt=1e-3,
    ...                      initial_radii=[2] * 5)
    >>> np.round(res.radii, 2), res.health.ok
    (array([0.4, 1. , 1.5, 2. , 3.6]), True)
    """
    linear_play = _renamed_linear_play(linear_play, known_linear_play, "estimate_radii")
    x = as_signal(v, "v", min_length=2)
    m = as_signal(y, "y", min_length=2)
    if x.size != m.size:
        raise ValueError(f"v and y: expected equal lengths, got {x.size} and {m.size}")
    auto = (default_settings(x, m, weights, dt=dt) if x.size >= 3 and any(
            a is None for a in (gains, threshold, guard, slope_window)) else
            {"gains": 10.0, "guard": 0.0, "threshold": 0.0, "slope_window": 8})
    settings = {"gains": auto["gains"] if gains is None else gains,
                "threshold": auto["threshold"] if threshold is None else threshold,
                "guard": auto["guard"] if guard is None else guard,
                "slope_window": auto["slope_window"] if slope_window is None else slope_window}
    est = RadiusEstimator(weights, dt=dt, initial_radii=initial_radii,
                          linear_play=linear_play, max_step=max_step,
                          anneal_time=anneal_time, slope_tol=slope_tol,
                          initial_state=initial_state, law=law, **settings)
    res = est.run(x, m)
    res.health = estimator_health(x, est.weights, res.history, linear_play=linear_play,
                                  y=m, error=res.error, warn=warn and not polish)
    res.settings = {**settings, "law": law, "polish": bool(polish)}
    if polish and x.size >= 3:
        res.online_radii = res.radii if res.radii_mean is None else res.radii_mean
        try:  # weights far outside float64's comfortable range can defeat the least squares
            refined = refine_radii(x, m, est.weights, res.online_radii,
                                   linear_play=linear_play, initial_state=initial_state)
            health = refined_health(x, m, est.weights, refined, linear_play=linear_play,
                                    initial_state=initial_state, warn=warn)
        except (ValueError, np.linalg.LinAlgError) as exc:
            refined, why = None, str(exc)
        else:
            why = "non-finite radii"
        if refined is None or not np.all(np.isfinite(refined)):
            warnings.warn(f"weights: the batch refinement failed for these weights ({why}); "
                          "keeping the online estimate (polish=False)", RuntimeWarning,
                          stacklevel=2)
            res.radii = res.online_radii
        else:
            res.radii, res.health = refined, health
    return res


def stream_tail_average(estimator: RadiusEstimator, chunks: Iterable[tuple], *, total: int,
                        tail: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Run ``estimator`` over a record given as ``(v, y)`` chunks (``total`` samples in all) and
    return ``(final radii, mean of rhat[k] over the last tail fraction of the samples)``.

    Averaging the iterates (Polyak-Ruppert) is how the estimate reaches the accuracy the data
    allow under heavy output noise; the constant-gain iterate itself keeps fluctuating. Memory
    is bounded by the chunk size, so records of 10^8 samples are fine
    (:mod:`pimodel.stages.long_records` makes such chunks).

    Parameters
    ----------
    estimator : RadiusEstimator
        Runs from its current state and is advanced by ``total`` samples.
    chunks : iterable of tuple of array_like
        ``(v, y)`` pieces of the record, in order, of equal lengths each.
    total : int
        Number of samples in all the chunks (>= 2).
    tail : float, optional
        Fraction of the samples, at the end, averaged (0 < tail <= 1). Default 0.5.

    Returns
    -------
    radii : numpy.ndarray of float, shape (n,)
        The final estimate (input unit).
    tail_mean : numpy.ndarray of float, shape (n,)
        Mean of the estimate ``rhat[k]`` used at the samples of the tail (input unit).

    Raises
    ------
    ValueError
        If ``tail`` is outside (0, 1], a chunk's ``v`` and ``y`` differ in length, or the chunks
        do not hold exactly ``total`` samples.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = np.sin(np.linspace(0, 20, 2000))          # 2 s at dt = 1 ms
    >>> y = PIOperator([1.0, 1.0], [0.0, 0.3]).simulate(v)
    >>> chunks = [(v[:1000], y[:1000]), (v[1000:], y[1000:])]
    >>> final, mean = stream_tail_average(RadiusEstimator([1.0, 1.0], dt=1e-3), chunks,
    ...                                   total=2000)
    >>> final.round(2), mean.round(2)
    (array([0. , 0.3]), array([0. , 0.3]))
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
                     chunk: int = 1_000_000,
                     progress: Callable[[float], None] | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`stream_tail_average` over whole arrays ``v``, ``y``, processed in chunks.

    Parameters
    ----------
    estimator : RadiusEstimator
        Runs from its current state and is advanced by ``len(v)`` samples.
    v : array_like of float, shape (N,)
        Input samples (input unit), N >= 2.
    y : array_like of float, shape (N,)
        Measured output (output unit).
    tail : float, optional
        Fraction of the samples, at the end, averaged (0 < tail <= 1). Default 0.5.
    chunk : int, optional
        Samples per chunk (bounds the memory). Default 10^6.
    progress : callable, optional
        Called before each chunk with the share of the samples done (0 <= share < 1).

    Returns
    -------
    radii : numpy.ndarray of float, shape (n,)
        The final estimate (input unit).
    tail_mean : numpy.ndarray of float, shape (n,)
        Mean of the estimate over the tail (input unit).

    Raises
    ------
    ValueError
        Non-finite samples, unequal lengths, or ``tail`` outside (0, 1].

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = np.sin(np.linspace(0, 20, 2000))          # 2 s at dt = 1 ms
    >>> y = PIOperator([1.0, 1.0], [0.0, 0.3]).simulate(v)
    >>> final, mean = run_tail_average(RadiusEstimator([1.0, 1.0], dt=1e-3), v, y, chunk=500)
    >>> mean.round(2)
    array([0. , 0.3])
    """
    x = as_signal(v, "v", min_length=2)
    m = as_signal(y, "y", min_length=2)
    if x.size != m.size:
        raise ValueError(f"v and y: expected equal lengths, got {x.size} and {m.size}")
    progress = progress or (lambda share: None)

    def chunks():
        for a in range(0, x.size, chunk):
            progress(a / x.size)
            yield x[a:a + chunk], m[a:a + chunk]

    return stream_tail_average(estimator, chunks(), total=x.size, tail=tail)
