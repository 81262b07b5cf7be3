"""Joint online estimation of the weights and radii (the paper's future work).

Reads the regimes from the data, not from the estimate: the gradient laws that read them from
the current estimate have attracting wrong fixed points once the weights are free too (merged
plays; see the README). Discrete-time semantics, per sample k with input ``v[k]`` (input unit)
and measured output ``y[k]`` (output unit):

1. reversals as in the radius estimator (:class:`pimodel.branches.ReversalScanner`, threshold
   ``h``); a branch runs from one reversal extreme ``v_rev`` up to the next, its samples have
   travel ``x[k] = |v[k] - v_rev|`` and signed output ``Y[k] = s y[k]`` (``s`` = +1 rising,
   -1 falling);
2. branch shape (Madelung memory of the PI operator): where ``x <= T_prev``, the travel of the
   branch that ended at ``v_rev``, ``Y[k] = c_b + g(x[k])`` with
   ``g(x) = sum_j p_j max(0, x - 2 r_j)`` and ``c_b`` constant on the branch, whatever came
   before (major or minor loop). Only these samples are used;
3. when a reversal is declared (the sample at which ``v`` has moved back by more than ``h``),
   the branch that ended is centred, ``Y - c_b`` with ``c_b = mean(Y - ghat(x))`` (``ghat`` the
   current estimate; the first update fits the offsets jointly instead), and added to
   ``bins`` equal-width bins of x on ``[0, travel_range]`` (count, sum x, sum Y, sum Y^2); the
   older statistics are multiplied by ``forgetting`` per branch;
4. after every ``refit_every`` branches the estimate is updated: the optimal continuous
   piecewise-linear curve with ``n`` segments (``n + 1`` without a linear play) is fitted to the
   bin means, weighted by counts (dynamic programming for the breakpoints, then continuous least
   squares with non-decreasing slopes), and ``p``, ``r`` follow from its slopes and breakpoints
   (:func:`pimodel.slopes.plays_from_slopes`).

``weights[k]``, ``radii[k]`` are the estimate in force at sample k (held between updates), so
the estimate after sample k uses ``v[0..k]``, ``y[0..k]`` only. The statistics are sufficient
for the fit, so memory is bounded (one branch of raw samples) and the result does not depend on
how the record is cut into chunks. With ``forgetting = 1`` every used sample counts equally
(the estimate converges like least squares, as 1/sqrt(samples) under white output noise).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from .branches import ReversalScanner
from .checks import as_signal, as_vector, positive_scalar
from .segmented import fit_binned, fit_segmented
from .slopes import plays_from_slopes


@dataclass
class JointEstimate:
    """Result of :class:`JointEstimator` runs: the final estimate and its update history.

    ``update_index[u]`` is the sample at which update u was made (the estimate
    ``weight_history[u]``, ``radius_history[u]`` is in force from the next sample on).
    ``fit_rms`` is the RMS of the used samples about the fitted branch shape (output unit), an
    estimate of the output noise once the model fits.
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
    ``x`` (input unit) from a reversal, in the output unit."""
    return np.maximum(0.0, x[:, None] - 2.0 * radii[None, :]) @ weights


class JointEstimator:
    """Streaming joint estimator of weights and radii (see the module docstring for the law).

    ``n_plays``: number of plays (e.g. from :func:`pimodel.identify_slopes`); ``linear_play``:
    whether ``r_1 = 0`` (the branch starts with slope ``p_1``); ``initial_weights``,
    ``initial_radii``: the estimate reported before the first update (the law itself needs no
    start); ``travel_range``: the x range of the bins (input unit, default: the travel of the
    first usable branch; samples beyond it are counted in ``samples_outside``); ``bins``: number
    of bins; ``refit_every``: branches between updates; ``forgetting``: per-branch factor in
    (0, 1]; ``threshold``: reversal threshold (input unit).
    """

    def __init__(self, n_plays: int, *, linear_play: bool = False, initial_weights=None,
                 initial_radii=None, travel_range: float | None = None, bins: int = 2048,
                 refit_every: int = 10, forgetting: float = 1.0, threshold: float = 0.0):
        if int(n_plays) != n_plays or not 1 <= n_plays <= 64:
            raise ValueError(f"n_plays: expected an integer from 1 to 64, got {n_plays!r}")
        self.n = int(n_plays)
        self.linear_play = bool(linear_play)
        self.weights = self._start(initial_weights, "initial_weights", np.ones(self.n), lo=0.0)
        default_r = np.arange(self.n, dtype=float)
        self.radii = np.sort(self._start(initial_radii, "initial_radii", default_r, lo=None))
        if self.linear_play:
            self.radii[0] = 0.0
        if int(bins) != bins or bins < 4 * (self.n + 1):
            raise ValueError(f"bins: expected an integer >= {4 * (self.n + 1)}, got {bins!r}")
        if int(refit_every) != refit_every or refit_every < 1:
            raise ValueError(f"refit_every: expected an integer >= 1, got {refit_every!r}")
        if not (np.isfinite(forgetting) and 0 < forgetting <= 1):
            raise ValueError(f"forgetting: expected a number in (0, 1], got {forgetting!r}")
        self.bins = int(bins)
        self.refit_every = int(refit_every)
        self.forgetting = float(forgetting)
        self.travel_range = None if travel_range is None else positive_scalar(
            travel_range, "travel_range")
        self._scanner = ReversalScanner(threshold)
        self._stats = np.zeros((4, self.bins))  # count, sum x, sum Y, sum Y^2
        self._k = 0                    # samples seen
        self._buf_v = np.empty(0)      # raw samples since the last reversal extreme
        self._buf_y = np.empty(0)
        self._buf_start = 0            # absolute index of _buf_v[0]
        self._from_reversal = False    # the buffered branch starts at a reversal
        self._prev_travel = 0.0
        self._pending: list[tuple[np.ndarray, np.ndarray]] = []  # (x, Y) of branches not yet added
        self._fitted = False
        self._updates: list[tuple[int, np.ndarray, np.ndarray]] = []
        self.branches_used = 0
        self.samples_used = 0
        self.samples_outside = 0
        self.fit_rms = float("nan")

    @staticmethod
    def _start(value, name, default, lo):
        if value is None:
            return default
        arr = as_vector(value, name, length=default.size)
        if lo is not None and np.any(arr <= lo):
            raise ValueError(f"{name}: every value must be > {lo}")
        if lo is None and np.any(arr < 0):
            raise ValueError(f"{name}: every radius must be >= 0")
        return arr.copy()

    # -- streaming -------------------------------------------------------------------------
    def step(self, v: float, y: float) -> tuple[np.ndarray, np.ndarray]:
        """Process sample k; returns the estimate ``(weights, radii)`` after it."""
        self.run(np.array([v], float), np.array([y], float), _min_length=1)
        return self.weights.copy(), self.radii.copy()

    def run(self, v, y, *, _min_length: int = 2) -> JointEstimate:
        """Process the next samples (arrays, any length); returns everything so far."""
        x = as_signal(v, "v", min_length=_min_length)
        m = as_signal(y, "y", min_length=_min_length)
        if x.size != m.size:
            raise ValueError(f"v and y: expected equal lengths, got {x.size} and {m.size}")
        ext, decl = self._scanner.scan_with_declaration(x)
        bv = np.concatenate((self._buf_v, x))
        by = np.concatenate((self._buf_y, m))
        for e, d in zip(ext, decl, strict=True):
            b = int(e) - self._buf_start
            self._close_branch(bv[:b + 1], by[:b])
            bv, by = bv[b:], by[b:]
            self._buf_start = int(e)
            if len(self._pending) >= self.refit_every:
                self._update(int(d))
        self._buf_v, self._buf_y = bv, by
        self._k += x.size
        return self.result()

    def _close_branch(self, v: np.ndarray, y: np.ndarray) -> None:
        """Branch samples v[0..-2] with outputs y; v[-1] is the next reversal extreme."""
        travel = abs(float(v[-1] - v[0]))
        s = 1.0 if v[-1] > v[0] else -1.0
        if self._from_reversal and travel > 0:
            xs = np.abs(v[:-1] - v[0])
            if self.travel_range is None:
                self.travel_range = travel
            keep = xs <= self._prev_travel * (1 + 1e-12)
            inside = keep & (xs <= self.travel_range)
            self.samples_outside += int(np.count_nonzero(keep & ~inside))
            if np.count_nonzero(inside) >= 2:
                self._pending.append((xs[inside], s * y[inside]))
        self._from_reversal = True
        self._prev_travel = travel

    def _update(self, k: int) -> None:
        if not self._fitted:
            self._first_fit()
        else:
            self._accumulate(self._pending)
        self._pending = []
        self._fit_bins()
        self._updates.append((k, self.weights.copy(), self.radii.copy()))

    def _first_fit(self) -> None:
        """Before any estimate exists: offsets fitted jointly with the shape on raw samples."""
        x = np.concatenate([b[0] for b in self._pending])
        Y = np.concatenate([b[1] for b in self._pending])
        groups = np.concatenate([np.full(b[0].size, i) for i, b in enumerate(self._pending)])
        fit = fit_segmented(x, Y, groups, segments=self._segments(), increasing=True)
        self._set_estimate(fit.slopes, fit.breakpoints)
        self._fitted = True
        self._accumulate(self._pending)

    def _segments(self) -> int:
        return self.n if self.linear_play else self.n + 1

    def _accumulate(self, branches: list[tuple[np.ndarray, np.ndarray]]) -> None:
        h = self.travel_range / self.bins
        for x, Y in branches:
            c = float(np.mean(Y - branch_shape(x, self.weights, self.radii)))
            Yc = Y - c
            idx = np.minimum((x / h).astype(np.int64), self.bins - 1)
            self._stats *= self.forgetting
            for row, w in enumerate((None, x, Yc, Yc * Yc)):
                self._stats[row] += np.bincount(idx, weights=w, minlength=self.bins)
            self.branches_used += 1
            self.samples_used += x.size

    def _fit_bins(self) -> None:
        cnt, sx, sy, syy = self._stats
        ok = cnt > 0
        xb, yb, wb = sx[ok] / cnt[ok], sy[ok] / cnt[ok], cnt[ok]
        m = self._segments()
        if xb.size < 2 * m + 1:
            return  # too few distinct travels to place the breakpoints yet
        bps, coef = fit_binned(xb, yb, wb, m, increasing=True)
        self._set_estimate(np.cumsum(coef[:m]), bps)
        curve = coef[m] + branch_shape(xb, self.weights, self.radii) + (
            coef[0] * xb if not self.linear_play else 0.0)
        sse = float(np.sum(syy[ok] - 2 * curve * sy[ok] + cnt[ok] * curve**2))
        self.fit_rms = float(np.sqrt(max(sse, 0.0) / max(wb.sum(), 1.0)))

    def _set_estimate(self, slopes: np.ndarray, breakpoints: np.ndarray) -> None:
        p, r = plays_from_slopes(slopes, np.sort(breakpoints), linear_play=self.linear_play)
        self.weights = np.maximum(p, 0.0)
        self.radii = np.maximum(r, 0.0)

    def result(self) -> JointEstimate:
        """Everything so far as a :class:`JointEstimate`."""
        idx = np.array([u[0] for u in self._updates], dtype=np.int64)
        n = self.n
        W = np.array([u[1] for u in self._updates]).reshape(-1, n)
        R = np.array([u[2] for u in self._updates]).reshape(-1, n)
        return JointEstimate(self.weights.copy(), self.radii.copy(), idx, W, R, self.fit_rms,
                             self.branches_used, self.samples_used, self.samples_outside)


def estimate_jointly(v, y, n_plays: int, **options) -> JointEstimate:
    """Joint weights and radii from a record ``(v[k], y[k])`` (see :class:`JointEstimator` for
    the options)."""
    est = JointEstimator(n_plays, **options)
    return est.run(v, y)


def stream_jointly(estimator: JointEstimator, chunks: Iterable[tuple]) -> JointEstimate:
    """Run ``estimator`` over a record given as ``(v, y)`` chunks (bounded memory)."""
    for v, y in chunks:
        estimator.run(v, y, _min_length=1)
    return estimator.result()
