"""Joint online estimation of the weights and radii (the paper's future work).

Reads the regimes from the data, not from the estimate: the gradient laws that read them from
the current estimate have attracting wrong fixed points once the weights are free too (merged
plays; see the README). Discrete-time semantics, per sample k with input ``v[k]`` (input unit)
and measured output ``y[k]`` (output unit):

1. reversals as in the radius estimator (:class:`pimodel.identification.branches.ReversalScanner`,
   threshold
   ``h``); a branch runs from one reversal extreme ``v_rev`` up to the next, its samples have
   travel ``x[k] = |v[k] - v_rev|`` and signed output ``Y[k] = s y[k]`` (``s`` = +1 rising,
   -1 falling);
2. branch shape (Madelung memory of the PI operator): where ``x <= T_prev``, the travel of the
   branch that ended at ``v_rev``, ``Y[k] = c_b + g(x[k])`` with
   ``g(x) = sum_j p_j max(0, x - 2 r_j)`` and ``c_b`` constant on the branch, whatever came
   before (major or minor loop). Only these samples are used;
3. when a branch ends (at the sample where the next reversal is declared, i.e. ``v`` has moved
   back by more than ``h``) it is centred, ``Y - c_b`` with ``c_b = mean(Y - ghat(x))``
   (``ghat`` the estimate in force), and added to ``bins`` equal-width bins of x on
   ``[0, travel_range]`` (count, sum x, sum Y); the older statistics are multiplied by
   ``forgetting`` per branch. Before any estimate exists the branches are kept raw, and the
   first update, after ``min(refit_every, FIRST_FIT_BRANCHES)`` branches, fits their offsets and
   the shape together;
4. every ``refit_every`` branches the estimate is updated:
   ``c + sum_j p_j max(0, x - 2 r_j)`` (with ``p_1 x`` for a linear play) is fitted to the bin
   means weighted by the counts, with every ``p_j >= 0``
   (:func:`pimodel.identification.piecewise_linear.fit_hinges`:
   hinges from dynamic programming and from the previous estimate, coordinate sweeps over a
   grid, then continuous least squares; the better start is kept).

``weights[k]``, ``radii[k]`` are the estimate in force at sample k (held between updates), so
the estimate after sample k uses ``v[0..k]``, ``y[0..k]`` only. The statistics are sufficient
for the fit, so memory is bounded (the bins and one running branch of raw samples) and the
result does not depend on how the record is cut into chunks. With ``forgetting = 1`` every used
sample counts equally (the estimate converges like least squares, as 1/sqrt(samples) under
white output noise).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from ... import _native
from ...checks import as_signal, as_vector, integer_in, positive_scalar
from ..branches import ReversalScanner
from ..piecewise_linear import fit_hinges, fit_segmented
from ..slopes import plays_from_slopes
from .settings import noise_level

FIT_NOISE_FACTOR = 2.0   # estimate_jointly warns when its branch fit RMS exceeds
FIT_RANGE_SHARE = 1e-3   # FIT_NOISE_FACTOR sigma_y + FIT_RANGE_SHARE ptp(y)

__all__ = [
    "branch_shape",
    "estimate_jointly",
    "JointEstimate",
    "JointEstimator",
    "stream_jointly",
]

FIRST_FIT_BRANCHES = 50


@dataclass
class JointEstimate:
    """Result of :class:`JointEstimator` runs: the final estimate and its update history.

    Parameters
    ----------
    weights : numpy.ndarray of float, shape (n,)
        The estimate of ``p_j`` in force after the last sample.
    radii : numpy.ndarray of float, shape (n,)
        The estimate of ``r_j`` (input unit), non-decreasing.
    update_index : numpy.ndarray of int, shape (U,)
        ``update_index[u]`` is the sample at which update u was made (the estimate
        ``weight_history[u]``, ``radius_history[u]`` is in force from the next sample on).
    weight_history : numpy.ndarray of float, shape (U, n)
        Weights after each update.
    radius_history : numpy.ndarray of float, shape (U, n)
        Radii after each update.
    fit_rms : float
        RMS of the samples of the branches added since the previous update about the estimate
        in force when each ended, each branch with its own offset (output unit): a prediction
        check, and an estimate of the output noise once the model fits (NaN before).
    branches_used : int
        Branches added to the statistics.
    samples_used : int
        Samples of those branches.
    samples_outside : int
        Usable samples beyond ``travel_range`` (not used).

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = 2 * np.sin(np.linspace(0, 12 * np.pi, 1200))    # six periods
    >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
    >>> res = estimate_jointly(v, y, 2, linear_play=True, refit_every=2)
    >>> res.weights.round(3), res.radii.round(3), res.weight_history.shape[1]
    (array([1. , 0.5]), array([0. , 0.4]), 2)
    """

    weights: np.ndarray
    radii: np.ndarray
    update_index: np.ndarray
    weight_history: np.ndarray
    radius_history: np.ndarray
    fit_rms: float
    branches_used: int
    samples_used: int
    samples_outside: int


def branch_shape(x: np.ndarray, weights: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """``g(x) = sum_j p_j max(0, x - 2 r_j)``: the output change along a branch after a travel
    ``x`` (input unit) from a reversal, in the output unit.

    Parameters
    ----------
    x : numpy.ndarray of float, shape (N,)
        Travels from the reversal (input unit, >= 0).
    weights : numpy.ndarray of float, shape (n,)
        Play weights ``p_j``.
    radii : numpy.ndarray of float, shape (n,)
        Play radii ``r_j`` (input unit).

    Returns
    -------
    numpy.ndarray of float, shape (N,)
        ``g(x)`` (output unit).

    Examples
    --------
    >>> branch_shape(np.array([0.0, 0.5, 1.0]), np.array([1.0, 0.5]), np.array([0.0, 0.4]))
    array([0. , 0.5, 1.1])
    """
    x, weights, radii = (np.ascontiguousarray(a, dtype=float) for a in (x, weights, radii))
    # the hinge matrix max(0, x - 2 r) built in one pass in C (pim_joint_hinges, the values of
    # np.maximum(0.0, x[:, None] - 2.0 * radii[None, :])), then the same BLAS product
    return _native.joint_hinges(x, radii) @ weights


class JointEstimator:
    """Streaming joint estimator of weights and radii (see the module docstring for the law).

    Parameters
    ----------
    n_plays : int
        Number of plays, 1 to 64 (e.g. from :func:`pimodel.identify_slopes`).
    linear_play : bool, optional
        Whether ``r_1 = 0`` (the branch starts with slope ``p_1``).
    initial_weights : array_like of float, shape (n,), optional
        The weights reported before the first update (the law itself needs no start);
        default all 1.
    initial_radii : array_like of float, shape (n,), optional
        The radii reported before the first update; default ``0, 1, ..., n - 1``.
    travel_range : float, optional
        The x range of the bins (input unit); default the travel of the first usable branch.
        Samples beyond it are counted in ``samples_outside``.
    bins : int, optional
        Number of bins (at least ``4 (n + 1)``). Default 2048.
    refit_every : int, optional
        Branches between updates (>= 1). Default 10.
    forgetting : float, optional
        Per-branch factor on the older statistics, in (0, 1]. Default 1 (no forgetting).
    threshold : float, optional
        Reversal threshold (input unit). Default 0.

    Raises
    ------
    ValueError
        A bad ``n_plays``, ``bins``, ``refit_every``, ``forgetting``, ``travel_range``, or a
        negative or wrong-length start (the message names the argument).

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = 2 * np.sin(np.linspace(0, 12 * np.pi, 1200))    # six periods
    >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
    >>> est = JointEstimator(2, linear_play=True, refit_every=2)
    >>> _ = est.run(v, y)
    >>> res = est.finish()
    >>> res.weights.round(3), res.radii.round(3)
    (array([1. , 0.5]), array([0. , 0.4]))
    """

    def __init__(self, n_plays: int, *, linear_play: bool = False, initial_weights=None,
                 initial_radii=None, travel_range: float | None = None, bins: int = 2048,
                 refit_every: int = 10, forgetting: float = 1.0, threshold: float = 0.0):
        self.n = integer_in(n_plays, "n_plays", 1, 64)
        self.linear_play = bool(linear_play)
        self.weights = self._start(initial_weights, "initial_weights", np.ones(self.n))
        default_r = np.arange(self.n, dtype=float)
        self.radii = np.sort(self._start(initial_radii, "initial_radii", default_r))
        if self.linear_play:
            self.radii[0] = 0.0
        if not (isinstance(forgetting, (int, float, np.number)) and np.isfinite(forgetting)
                and 0 < forgetting <= 1):
            raise ValueError(f"forgetting: expected a number in (0, 1], got {forgetting!r}")
        self.bins = integer_in(bins, "bins", 4 * (self.n + 1), 10_000_000)
        self.refit_every = integer_in(refit_every, "refit_every", 1)
        self.forgetting = float(forgetting)
        self.travel_range = None if travel_range is None else positive_scalar(
            travel_range, "travel_range")
        self._scanner = ReversalScanner(threshold)
        self._stats = np.zeros((3, self.bins))  # count, sum x, sum Y
        self._k = 0                    # samples seen
        self._buf_v: list[np.ndarray] = []  # raw samples since the last reversal extreme
        self._buf_y: list[np.ndarray] = []
        self._buf_start = 0            # absolute index of _buf_v[0]
        self._from_reversal = False    # the buffered branch starts at a reversal
        self._prev_travel = 0.0
        self._pending: list[tuple[np.ndarray, np.ndarray]] = []  # (x, Y) before the first fit
        self._since_update = 0         # branches added since the last update
        self._sse, self._sse_count = 0.0, 0
        self._updates: list[tuple[int, np.ndarray, np.ndarray]] = []
        self.branches_used = 0
        self.samples_used = 0
        self.samples_outside = 0
        self.fit_rms = float("nan")

    @staticmethod
    def _start(value, name, default):
        if value is None:
            return default
        arr = as_vector(value, name, length=default.size)
        if np.any(arr < 0):
            raise ValueError(f"{name}: every value must be >= 0")
        return arr.copy()

    # -- streaming -------------------------------------------------------------------------
    def step(self, v: float, y: float) -> tuple[np.ndarray, np.ndarray]:
        """Process sample k; returns the estimate ``(weights, radii)`` in force after it.

        Parameters
        ----------
        v : float
            Input sample ``v[k]`` (input unit).
        y : float
            Measured output ``y[k]`` (output unit).

        Returns
        -------
        weights : numpy.ndarray of float, shape (n,)
            Weights in force after sample k (copies).
        radii : numpy.ndarray of float, shape (n,)
            Radii in force after sample k (input unit).

        Raises
        ------
        ValueError
            If ``v`` or ``y`` is not finite.

        Examples
        --------
        >>> JointEstimator(2, linear_play=True).step(0.0, 0.0)   # the start, before any update
        (array([1., 1.]), array([0., 1.]))
        """
        self._consume(as_signal([v], "v", min_length=1), as_signal([y], "y", min_length=1))
        return self.weights.copy(), self.radii.copy()

    def run(self, v, y) -> JointEstimate:
        """Process the next samples (arrays, any length >= 1); returns everything so far.

        Parameters
        ----------
        v : array_like of float, shape (N,)
            Next input samples (input unit).
        y : array_like of float, shape (N,)
            Next measured outputs (output unit).

        Returns
        -------
        JointEstimate
            As :meth:`result` (the branch still running is not yet used).

        Raises
        ------
        ValueError
            Non-finite samples or unequal lengths.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> v = 2 * np.sin(np.linspace(0, 12 * np.pi, 1200))    # six periods
        >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
        >>> est = JointEstimator(2, linear_play=True, refit_every=2)
        >>> est.run(v, y).radii.round(3)
        array([0. , 0.4])
        """
        x = as_signal(v, "v", min_length=1)
        m = as_signal(y, "y", min_length=1)
        if x.size != m.size:
            raise ValueError(f"v and y: expected equal lengths, got {x.size} and {m.size}")
        self._consume(x, m)
        return self.result()

    def finish(self) -> JointEstimate:
        """End of record: update with the branches completed since the last update (the branch
        still running is left out: its end, hence its travel, is unknown).

        Returns
        -------
        JointEstimate
            The final estimate and its history.

        Warns
        -----
        RuntimeWarning
            If the record held no usable branch (the estimate is then the start).

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> v = 2 * np.sin(np.linspace(0, 12 * np.pi, 1200))    # six periods
        >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
        >>> est = JointEstimator(2, linear_play=True, refit_every=2)
        >>> _ = est.run(v, y)
        >>> res = est.finish()
        >>> res.update_index.size >= 2, bool(res.fit_rms < 1e-6)
        (True, True)
        """
        if self._pending or self._since_update:
            self._update(self._k - 1)
        if not self._updates:
            warnings.warn("JointEstimator: no usable branch (a branch between two reversals, "
                          "after a first one) in the record; the estimate is the start",
                          RuntimeWarning, stacklevel=2)
        return self.result()

    def _consume(self, x: np.ndarray, m: np.ndarray) -> None:
        ext, decl = self._scanner.scan_with_declaration(x)
        self._buf_v.append(x)
        self._buf_y.append(m)
        self._k += x.size
        if ext.size == 0:
            return
        bv, by = np.concatenate(self._buf_v), np.concatenate(self._buf_y)
        for e, d in zip(ext, decl, strict=True):
            b = int(e) - self._buf_start
            self._close_branch(bv[:b + 1], by[:b])
            bv, by = bv[b:], by[b:]
            self._buf_start = int(e)
            if self._updates:  # an estimate exists
                due = self._since_update >= self.refit_every
            else:
                due = len(self._pending) >= min(self.refit_every, FIRST_FIT_BRANCHES)
            if due:
                self._update(int(d))
        self._buf_v, self._buf_y = [bv], [by]

    def _close_branch(self, v: np.ndarray, y: np.ndarray) -> None:
        """Branch samples v[0..-2] with outputs y; v[-1] is the next reversal extreme."""
        travel = abs(float(v[-1] - v[0]))
        s = 1.0 if v[-1] > v[0] else -1.0
        if self._from_reversal and travel > 0:
            if self.travel_range is None:
                self.travel_range = travel
            x, Y, outside = _native.joint_select(v[:-1], y, s, self._prev_travel * (1 + 1e-12),
                                                 self.travel_range)
            self.samples_outside += outside
            if x.size >= 2:
                if self._updates:  # an estimate exists
                    self._add_branch(x, Y)
                else:
                    self._pending.append((x, Y))
        self._from_reversal = True
        self._prev_travel = travel

    def _update(self, k: int) -> None:
        if not self._updates:
            self._first_fit()
        self._fit_bins()
        self.fit_rms = float(np.sqrt(self._sse / self._sse_count)) if self._sse_count else \
            float("nan")
        self._sse, self._sse_count, self._since_update = 0.0, 0, 0
        self._updates.append((k, self.weights.copy(), self.radii.copy()))

    def _first_fit(self) -> None:
        """Before any estimate exists: offsets fitted jointly with the shape on the raw samples of
        the pending branches."""
        x = np.concatenate([b[0] for b in self._pending])
        Y = np.concatenate([b[1] for b in self._pending])
        groups = np.concatenate([np.full(b[0].size, i) for i, b in enumerate(self._pending)])
        fit = fit_segmented(x, Y, groups, segments=self._segments(), increasing=True)
        p, r = plays_from_slopes(fit.slopes, np.sort(fit.breakpoints),
                                 linear_play=self.linear_play)
        self.weights, self.radii = np.maximum(p, 0.0), np.maximum(r, 0.0)
        for x, Y in self._pending:
            self._add_branch(x, Y)
        self._pending = []

    def _segments(self) -> int:
        return self.n if self.linear_play else self.n + 1

    def _add_branch(self, x: np.ndarray, Y: np.ndarray) -> None:
        """Centre a finished branch on the estimate in force and add it to the bins: the errors
        and their mean in numpy, the binning in the C core (``pim_joint_add``; NumPy reference
        :func:`pimodel.reference.joint.joint_add_reference`), the same statistics to the bit."""
        e = Y - branch_shape(x, self.weights, self.radii)
        self._sse += _native.joint_add(x, Y, e, float(np.mean(e)), self._stats,
                                       self.travel_range, self.forgetting)
        self._sse_count += x.size
        self.branches_used += 1
        self.samples_used += x.size
        self._since_update += 1

    def _fit_bins(self) -> None:
        xb, yb, wb = self.binned()
        hinges = self.n - 1 if self.linear_play else self.n
        if xb.size < 2 * self.n + 2:
            return  # too few distinct travels to place the hinges yet
        start = 2 * self.radii[1:] if self.linear_play else 2 * self.radii
        b, a, c, _ = fit_hinges(xb, yb, wb, hinges, linear_term=self.linear_play, start=start)
        self.weights = a.copy()
        self.radii = np.concatenate(([0.0], b / 2)) if self.linear_play else b / 2

    def binned(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The fit's data: mean travel ``x`` (input unit), mean centred signed output ``Y``
        (output unit) and sample count of each occupied bin.

        Returns
        -------
        x : numpy.ndarray of float, shape (B,)
            Mean travel per occupied bin (input unit).
        Y : numpy.ndarray of float, shape (B,)
            Mean centred signed output per bin (output unit).
        count : numpy.ndarray of float, shape (B,)
            (Forgetting-weighted) sample count per bin.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> v = 2 * np.sin(np.linspace(0, 12 * np.pi, 1200))    # six periods
        >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
        >>> est = JointEstimator(2, linear_play=True, refit_every=2)
        >>> res = stream_jointly(est, [(v, y)])
        >>> x, Y, count = est.binned()
        >>> bool(np.allclose(Y, branch_shape(x, res.weights, res.radii), atol=1e-4))
        True
        """
        cnt, sx, sy = self._stats
        ok = cnt > 0
        return sx[ok] / cnt[ok], sy[ok] / cnt[ok], cnt[ok]

    def result(self) -> JointEstimate:
        """Everything so far as a :class:`JointEstimate`.

        Returns
        -------
        JointEstimate
            The estimate in force, the update history and the usage counts.

        Examples
        --------
        >>> res = JointEstimator(2).result()      # no sample yet: the start, no update
        >>> res.weights, res.update_index.size
        (array([1., 1.]), 0)
        """
        idx = np.array([u[0] for u in self._updates], dtype=np.int64)
        n = self.n
        W = np.array([u[1] for u in self._updates]).reshape(-1, n)
        R = np.array([u[2] for u in self._updates]).reshape(-1, n)
        return JointEstimate(self.weights.copy(), self.radii.copy(), idx, W, R, self.fit_rms,
                             self.branches_used, self.samples_used, self.samples_outside)


def estimate_jointly(v, y, n_plays: int, **options) -> JointEstimate:
    """Joint weights and radii from a record ``(v[k], y[k])`` (see :class:`JointEstimator` for
    the options).

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples (input unit).
    y : array_like of float, shape (N,)
        Measured output (output unit).
    n_plays : int
        Number of plays, 1 to 64.
    **options
        Keywords of :class:`JointEstimator` (``linear_play``, ``refit_every``, ...).

    Returns
    -------
    JointEstimate
        After :meth:`JointEstimator.finish`.

    Raises
    ------
    ValueError
        Bad samples or options (named).

    Warns
    -----
    RuntimeWarning
        When the branch fit RMS exceeds ``FIT_NOISE_FACTOR sigma_y + FIT_RANGE_SHARE ptp(y)``
        (a fit far outside the noise, e.g. a local optimum of the radii).

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = 2 * np.sin(np.linspace(0, 12 * np.pi, 1200))    # six periods
    >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
    >>> res = estimate_jointly(v, y, 2, linear_play=True, refit_every=2)
    >>> res.weights.round(3), res.radii.round(3)
    (array([1. , 0.5]), array([0. , 0.4]))
    """
    est = JointEstimator(n_plays, **options)
    est.run(v, y)
    res = est.finish()
    _warn_if_poor_fit(res, est.linear_play, as_signal(y, "y"))
    return res


def _warn_if_poor_fit(res: JointEstimate, linear_play: bool, y: np.ndarray) -> None:
    """RuntimeWarning when the branch fit RMS is far outside the noise of ``y``: above
    ``FIT_NOISE_FACTOR sigma_y + FIT_RANGE_SHARE ptp(y)`` (``sigma_y`` from
    :func:`.settings.noise_level`), as ``identify`` warns through its health check."""
    if y.size < 3 or not np.isfinite(res.fit_rms):
        return
    bound = FIT_NOISE_FACTOR * noise_level(y) + FIT_RANGE_SHARE * float(np.ptp(y))
    if res.fit_rms > bound:
        hint = ("" if linear_play else "; if the stage has a linear play (r_1 = 0), pass "
                "linear_play=True, or use identify(method='joint'), which takes r_1 from the "
                "branch slopes")
        warnings.warn(f"estimate_jointly: the model does not fit the data: branch fit RMS "
                      f"{res.fit_rms:.3g} exceeds the noise bound {bound:.3g} (a local optimum "
                      f"of the radii, or dynamics the PI model lacks){hint}",
                      RuntimeWarning, stacklevel=3)


def stream_jointly(estimator: JointEstimator, chunks: Iterable[tuple]) -> JointEstimate:
    """Run ``estimator`` over a record given as ``(v, y)`` chunks (bounded memory), then
    :meth:`JointEstimator.finish`.

    The result does not depend on how the record is cut into chunks.

    Parameters
    ----------
    estimator : JointEstimator
        Runs from its current state.
    chunks : iterable of tuple of array_like
        ``(v, y)`` pieces of the record, in order.

    Returns
    -------
    JointEstimate
        After :meth:`JointEstimator.finish`.

    Raises
    ------
    ValueError
        Bad samples in a chunk.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = 2 * np.sin(np.linspace(0, 12 * np.pi, 1200))    # six periods
    >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
    >>> est = JointEstimator(2, linear_play=True, refit_every=2)
    >>> stream_jointly(est, [(v[:600], y[:600]), (v[600:], y[600:])]).radii.round(3)
    array([0. , 0.4])
    """
    for v, y in chunks:
        estimator.run(v, y)
    return estimator.finish()
