"""Optimal continuous piecewise-linear (segmented) regression through the origin.

Fits ``Y(x) = c_b + sum_i (s_i - s_{i-1}) max(0, x - b_{i-1})`` (``b_0 = 0``, ``s_0 = 0``) with
a free offset ``c_b`` per group b (branch). Breakpoints are first located by dynamic programming
over binned data (Bellman's optimal segmentation, exact for the binned discontinuous problem),
then moved one at a time to the best of a grid of positions for the continuous fit (coordinate
sweeps, which leave the local minima the dynamic programme's start can fall into on noisy
data), then refined by continuous least squares (scipy ``least_squares``), with slope
increments constrained >= 0 when ``increasing`` (a PI operator's loop branches are convex:
weights are positive).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares, lsq_linear

__all__ = [
    "fit_binned",
    "fit_hinges",
    "fit_segmented",
    "polish_fit",
    "SegmentedFit",
]


@dataclass
class SegmentedFit:
    """A fitted continuous piecewise-linear function of ``m`` segments (module docstring).

    Parameters
    ----------
    slopes : numpy.ndarray of float, shape (m,)
        Slopes ``s_1..s_m``, one per segment, ascending ``x``.
    breakpoints : numpy.ndarray of float, shape (m - 1,)
        Breakpoints ``b_1..b_{m-1}`` (``x`` units).
    offsets : numpy.ndarray of float, shape (groups,)
        Offset ``c_b`` of each group.
    sse : float
        Sum of squared residuals.
    n_points : int
        Number of points fitted.

    Examples
    --------
    >>> from pimodel.identification.piecewise_linear import fit_segmented
    >>> x = np.linspace(0.0, 2.0, 201)
    >>> fit = fit_segmented(x, x + np.maximum(0.0, x - 1.0), segments=2)
    >>> fit.segments, fit.slopes.round(6), fit.breakpoints.round(6)
    (2, array([1., 2.]), array([1.]))
    """

    slopes: np.ndarray       # s_1..s_m, one per segment (ascending x)
    breakpoints: np.ndarray  # b_1..b_{m-1} (x units)
    offsets: np.ndarray      # c_b per group
    sse: float
    n_points: int

    @property
    def segments(self) -> int:
        """Number of segments ``m``."""
        return self.slopes.size

    def bic(self, sse_floor: float = 0.0) -> float:
        """Bayesian information criterion of the fit.

        ``BIC = N ln(SSE/N) + k ln N`` with ``k = 2m - 1 + groups`` (slopes, breakpoints,
        offsets).

        Parameters
        ----------
        sse_floor : float, optional
            Lower bound on ``SSE/N`` (keeps the logarithm finite on exact fits).

        Returns
        -------
        float
            The BIC; lower is better.

        Examples
        --------
        >>> from pimodel.identification.piecewise_linear import SegmentedFit
        >>> fit = SegmentedFit(np.array([1.0]), np.array([]), np.array([0.0]), 1.0, 100)
        >>> round(fit.bic(), 6)     # 100 ln(0.01) + 2 ln(100)
        -451.306678
        """
        k = 2 * self.segments - 1 + self.offsets.size
        mse = max(self.sse / self.n_points, sse_floor)
        return float(self.n_points * np.log(mse) + k * np.log(self.n_points))


def _design(x: np.ndarray, groups: np.ndarray, n_groups: int, bps: np.ndarray) -> np.ndarray:
    cols = [x] + [np.maximum(0.0, x - b) for b in bps]
    onehot = np.zeros((x.size, n_groups))
    onehot[np.arange(x.size), groups] = 1.0
    return np.column_stack(cols + [onehot])


def _dp_breakpoints(x: np.ndarray, Y: np.ndarray, m: int, bins: int) -> np.ndarray:
    """Breakpoints of the optimal m-segment (discontinuous) linear fit on binned data."""
    edges, seg = _segment_costs(x, Y, bins)
    return np.array([edges[c] for c in _best_cuts(seg, m)])


def _segment_costs(x: np.ndarray, Y: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """The bin edges (quantiles of ``x``, ``bins`` at most) and ``seg[i, j]``: the residual sum
    of squares of one straight line over bins ``i..j-1`` (inf for ``j <= i``)."""
    order = np.argsort(x)
    xs, ys = x[order], Y[order]
    edges = np.unique(np.quantile(xs, np.linspace(0, 1, bins + 1)))
    idx = np.clip(np.searchsorted(edges, xs, side="right") - 1, 0, edges.size - 2)
    G = edges.size - 1
    S = np.zeros((6, G))
    for row, val in enumerate((np.ones_like(xs), xs, ys, xs * xs, xs * ys, ys * ys)):
        S[row] = np.bincount(idx, weights=val, minlength=G)
    C = np.concatenate((np.zeros((6, 1)), np.cumsum(S, axis=1)), axis=1)

    D = C[:, None, :] - C[:, :, None]  # D[:, i, j]: sums over bins i..j-1
    n, sx, sy, sxx, sxy, syy = D
    with np.errstate(divide="ignore", invalid="ignore"):
        var_x = sxx - sx * sx / n
        cov = sxy - sx * sy / n
        var_y = syy - sy * sy / n
        explained = np.where(var_x > 1e-300, cov * cov / var_x, 0.0)
        seg = np.maximum(var_y - explained, 0.0)
    seg = np.where(n < 2, 0.0, seg)
    seg[np.tril_indices(G + 1)] = np.inf  # j <= i: empty
    return edges, seg


def _best_cuts(seg: np.ndarray, m: int) -> list[int]:
    """The inner bin edges of the lowest-cost ``m``-segment cut of bins ``0..G`` (``seg[i, j]``:
    the cost of one segment over bins ``i..j-1``, inf for ``j <= i``), sorted: the dynamic
    programme over the number of segments, every end bin at once (column ``j`` holds
    ``cost[s - 1, i] + seg[i, j]`` for ``i < j`` and inf below, so the first minimum over the
    column is the first minimum over ``i < j``, as a loop over ``j`` finds it: the same sums,
    the same index, a NaN included)."""
    G = seg.shape[0] - 1
    cost = np.full((m + 1, G + 1), np.inf)
    arg = np.zeros((m + 1, G + 1), dtype=int)
    cost[0, 0] = 0.0
    cols = np.arange(1, G + 1)
    before = np.arange(G + 1)[:, None] < cols  # start bin i before end bin j
    for s in range(1, m + 1):
        cand = np.where(before, cost[s - 1, :, None] + seg[:, 1:], np.inf)
        arg[s, 1:] = np.argmin(cand, axis=0)
        cost[s, 1:] = cand[arg[s, 1:], cols - 1]
    cuts, j = [], G
    for s in range(m, 0, -1):
        j = arg[s, j]
        cuts.append(j)
    return sorted(cuts)[1:]  # the leading 0 dropped


def _bin(x, Y, bins):
    """Equal-width bins in x: mean x, mean Y and count of the non-empty bins."""
    edges = np.linspace(0.0, float(x.max()) * (1 + 1e-12) + 1e-300, bins + 1)
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, bins - 1)
    cnt = np.bincount(idx, minlength=bins).astype(float)
    sx = np.bincount(idx, weights=x, minlength=bins)
    sy = np.bincount(idx, weights=Y, minlength=bins)
    ok = cnt > 0
    return sx[ok] / cnt[ok], sy[ok] / cnt[ok], cnt[ok]


def _sweep_breakpoints(xb, yb, wb, bps, *, linear_term: bool = True, candidates: int = 512,
                       sweeps: int = 20):
    """Coordinate sweeps: each breakpoint (hinge) in turn moves to the grid position that
    minimises the weighted SSE of the fit ``c + [s x] + sum_j a_j max(0, x - b_j)`` with the
    others fixed (closed form per candidate: projection of the candidate column off the span of
    the others; ``linear_term`` adds the ``s x`` column); stops when none moves."""
    sw = np.sqrt(wb)
    y = yb * sw
    grid = np.unique(np.quantile(xb, np.linspace(0.0, 1.0, candidates + 2)[1:-1]))
    C = np.maximum(0.0, xb[:, None] - grid[None, :]) * sw[:, None]
    bps = np.array(bps, float)
    base = [np.ones_like(xb)] + ([xb] if linear_term else [])

    def basis(others):
        cols = base + [np.maximum(0.0, xb - b) for b in others]
        return np.linalg.qr(np.column_stack(cols) * sw[:, None])[0]

    for _ in range(sweeps):
        moved = False
        for j in range(bps.size):
            Q = basis(np.delete(bps, j))
            r0 = y - Q @ (Q.T @ y)
            here = np.maximum(0.0, xb - bps[j]) * sw
            here -= Q @ (Q.T @ here)
            Cp = C - Q @ (Q.T @ C)
            norms = np.einsum("ij,ij->j", Cp, Cp)
            tiny = 1e-12 * max(float(norms.max()), 1e-300)
            gain = np.where(norms > tiny, (Cp.T @ r0) ** 2 / np.maximum(norms, tiny), 0.0)
            k = int(np.argmax(gain))
            hn = float(here @ here)
            now = float(here @ r0) ** 2 / hn if hn > tiny else 0.0
            if gain[k] > now * (1 + 1e-9) + 1e-12 * float(r0 @ r0):
                bps[j] = grid[k]
                moved = True
        if not moved:
            break
    return np.sort(bps)


def fit_hinges(xb, yb, wb, hinges: int, *, linear_term: bool,
               start: np.ndarray | None = None, bins: int = 300, increasing: bool = True,
               linear_nonneg: bool = True):
    """Weighted fit of ``Y(x) = c + [a_0 x] + sum_j a_j max(0, x - b_j)`` to binned data.

    A PI operator's branch has this shape with ``a_j = p_j`` and ``b_j = 2 r_j``. The hinges
    start from the dynamic programme (and from ``start`` when given: the better of the two is
    kept), move by coordinate sweeps over a grid, and are refined by continuous least squares.

    Parameters
    ----------
    xb : numpy.ndarray of float, shape (B,)
        Mean ``x`` of each bin.
    yb : numpy.ndarray of float, shape (B,)
        Mean ``Y`` of each bin.
    wb : numpy.ndarray of float, shape (B,)
        Weight of each bin (e.g. its sample count).
    hinges : int
        Number of hinges ``b_j``.
    linear_term : bool
        Whether the model has the ``a_0 x`` term.
    start : numpy.ndarray of float, optional
        Hinge positions to start from as well (e.g. the previous estimate).
    bins : int, optional
        Bins of the dynamic programme.
    increasing : bool, optional
        Constrain the hinge coefficients ``a_j >= 0``.
    linear_nonneg : bool, optional
        Constrain ``a_0 >= 0``.

    Returns
    -------
    b : numpy.ndarray of float, shape (hinges,)
        Hinges, ascending.
    a : numpy.ndarray of float
        Coefficients, ``a_0`` first when ``linear_term``.
    c : float
        Offset.
    sse : float
        Weighted sum of squared residuals.

    Examples
    --------
    >>> from pimodel.identification.piecewise_linear import fit_hinges
    >>> x = np.linspace(0.0, 4.0, 401)
    >>> y = 0.5 + 1.0 * x + 0.5 * np.maximum(0.0, x - 1.0) + 0.25 * np.maximum(0.0, x - 3.0)
    >>> b, a, c, sse = fit_hinges(x, y, np.ones_like(x), 2, linear_term=True)
    >>> b.round(6), a.round(6), round(c, 6)
    (array([1., 3.]), array([1.  , 0.5 , 0.25]), 0.5)
    """
    sw = np.sqrt(wb)
    lead = 2 if linear_term else 1
    lb = np.full(lead + hinges, -np.inf)
    if increasing:
        lb[lead:] = 0.0
    if linear_term and linear_nonneg:
        lb[1] = 0.0

    def solve(b):
        cols = [np.ones_like(xb)] + ([xb] if linear_term else [])
        A = np.column_stack(cols + [np.maximum(0.0, xb - h) for h in b]) * sw[:, None]
        sol = lsq_linear(A, yb * sw, bounds=(lb, np.inf), method="bvls")
        return sol.x, A @ sol.x - yb * sw

    def refine(b):
        b = _sweep_breakpoints(xb, yb, wb, b, linear_term=linear_term)
        xmax = float(xb.max())
        sol = least_squares(lambda h: solve(np.sort(h))[1], b, bounds=(0.0, xmax),
                            x_scale=max(xmax, 1e-12) / 10, max_nfev=100 * (hinges + 1))
        b = np.sort(sol.x)
        coef, r = solve(b)
        return b, coef, float(r @ r)

    if hinges > 0:
        dp = _dp_breakpoints(xb, yb, hinges + 1, min(bins, xb.size))
        if dp.size != hinges:
            dp = np.quantile(xb, np.linspace(0, 1, hinges + 2)[1:-1])
        starts = [dp] if start is None else [dp, np.sort(np.asarray(start, float))]
        b, coef, sse = min((refine(s) for s in starts), key=lambda f: f[2])
    else:
        coef, r = solve(np.empty(0))
        b, sse = np.empty(0), float(r @ r)
    return b, coef[1:], float(coef[0]), sse


def fit_binned(xb, yb, wb, segments: int, increasing: bool = True, bins: int = 300):
    """Continuous piecewise-linear fit of ``segments`` segments on binned data.

    :func:`fit_hinges` with a free first slope and ``segments - 1`` hinges.

    Parameters
    ----------
    xb : numpy.ndarray of float, shape (B,)
        Mean ``x`` of each bin.
    yb : numpy.ndarray of float, shape (B,)
        Mean ``Y`` of each bin.
    wb : numpy.ndarray of float, shape (B,)
        Weight of each bin.
    segments : int
        Number of segments ``m >= 1``.
    increasing : bool, optional
        Constrain the slope increments ``>= 0``.
    bins : int, optional
        Bins of the dynamic programme.

    Returns
    -------
    breakpoints : numpy.ndarray of float, shape (m - 1,)
        Breakpoints, ascending.
    coef : numpy.ndarray of float, shape (m + 1,)
        ``(s_1, s_2 - s_1, ..., s_m - s_{m-1}, offset)``.

    Examples
    --------
    >>> from pimodel.identification.piecewise_linear import fit_binned
    >>> x = np.linspace(0.0, 2.0, 201)
    >>> b, coef = fit_binned(x, 1.0 + x + np.maximum(0.0, x - 1.0), np.ones_like(x), 2)
    >>> b.round(6), coef.round(6)
    (array([1.]), array([1., 1., 1.]))
    """
    b, a, c, _ = fit_hinges(xb, yb, wb, segments - 1, linear_term=True, bins=bins,
                            increasing=increasing, linear_nonneg=False)
    return b, np.concatenate((a, [c]))


def fit_segmented(x, Y, groups=None, *, segments: int, increasing: bool = True,
                  bins: int = 300, iterations: int = 3) -> SegmentedFit:
    """Continuous piecewise-linear fit with ``segments`` segments and an offset per group.

    The per-group offsets and the shared curve are fitted alternately (``iterations`` times):
    offsets start at each group's first samples; the curve is fitted on the offset-corrected
    data averaged into ``bins`` equal-width bins of x, which keeps the fit fast on long records.

    Parameters
    ----------
    x : array_like of float, shape (N,)
        Abscissae (e.g. input travel since the reversal), ``>= 0``.
    Y : array_like of float, shape (N,)
        Ordinates.
    groups : array_like of int, shape (N,), optional
        Group (branch) of each point, ``0..G-1``; one group when omitted.
    segments : int
        Number of segments ``m >= 1``.
    increasing : bool, optional
        Constrain the slope increments ``>= 0`` (convex curve).
    bins : int, optional
        Equal-width bins of ``x``.
    iterations : int, optional
        Rounds of offsets and curve.

    Returns
    -------
    SegmentedFit
        Slopes, breakpoints, offsets, SSE.

    See Also
    --------
    polish_fit : refines the result on the unbinned data.

    Examples
    --------
    >>> from pimodel.identification.piecewise_linear import fit_segmented
    >>> x = np.tile(np.linspace(0.0, 2.0, 101), 2)
    >>> groups = np.repeat([0, 1], 101)
    >>> Y = 2.0 * x + np.maximum(0.0, x - 0.5) + np.where(groups == 1, 3.0, 0.0)
    >>> fit = fit_segmented(x, Y, groups, segments=2)
    >>> fit.slopes.round(6), fit.offsets.round(6)
    (array([2., 3.]), array([0., 3.]))
    """
    x = np.asarray(x, float)
    Y = np.asarray(Y, float)
    groups = np.zeros(x.size, dtype=int) if groups is None else np.asarray(groups, dtype=int)
    n_groups = int(groups.max()) + 1
    offsets = np.array([np.mean(Y[groups == g][:5]) for g in range(n_groups)])
    for _ in range(max(1, iterations)):
        xb, yb, wb = _bin(x, Y - offsets[groups], bins)
        bps, coef = fit_binned(xb, yb, wb, segments, increasing, bins)
        curve = _design(x, np.zeros(x.size, dtype=int), 1, bps)[:, :segments] @ coef[:segments]
        resid = Y - curve
        offsets = np.bincount(groups, resid, n_groups) / np.bincount(groups, minlength=n_groups)
    r = Y - curve - offsets[groups]
    slopes = np.cumsum(coef[:segments])
    return SegmentedFit(slopes, bps, offsets, float(r @ r), x.size)


def polish_fit(x, Y, groups, fit: SegmentedFit, *, increasing: bool = True,
               max_points: int = 100_000) -> SegmentedFit:
    """Refine a binned fit on the unbinned data.

    The breakpoints and slopes are refined with the offsets held, then the offsets are
    re-estimated; this removes the small bias that binning leaves near breakpoints.

    Parameters
    ----------
    x : array_like of float, shape (N,)
        Abscissae.
    Y : array_like of float, shape (N,)
        Ordinates.
    groups : array_like of int, shape (N,)
        Group of each point, as given to :func:`fit_segmented`.
    fit : SegmentedFit
        The fit to refine.
    increasing : bool, optional
        Constrain the slope increments ``>= 0``.
    max_points : int, optional
        The breakpoints are refined on at most this many evenly spaced points.

    Returns
    -------
    SegmentedFit
        The refined fit.

    Examples
    --------
    >>> from pimodel.identification.piecewise_linear import fit_segmented, polish_fit
    >>> x = np.linspace(0.0, 2.0, 2001)
    >>> Y = x + np.maximum(0.0, x - 0.7321)
    >>> groups = np.zeros(x.size, dtype=int)
    >>> fit = polish_fit(x, Y, groups, fit_segmented(x, Y, groups, segments=2, bins=20))
    >>> fit.breakpoints.round(3)
    array([0.732])
    """
    x = np.asarray(x, float)
    Y = np.asarray(Y, float)
    groups = np.asarray(groups, dtype=int)
    m = fit.segments
    Yc = Y - fit.offsets[groups]
    sel = np.linspace(0, x.size - 1, min(x.size, max_points)).astype(int)
    xs, ys = x[sel], Yc[sel]
    ones = np.zeros(xs.size, dtype=int)

    def solve(bps, xx, yy, g1):
        A = _design(xx, g1, 1, bps)[:, :m]
        lb = np.full(m, -np.inf)
        if increasing:
            lb[1:] = 0.0
        sol = lsq_linear(A, yy, bounds=(lb, np.inf), method="bvls")
        return sol.x, A @ sol.x - yy

    bps = fit.breakpoints
    if m > 1:
        xmax = float(x.max())
        sol = least_squares(lambda b: solve(np.sort(b), xs, ys, ones)[1], bps,
                            bounds=(0.0, xmax), x_scale=max(xmax, 1e-12) / 10,
                            max_nfev=50 * m, xtol=1e-12, ftol=1e-12)
        bps = np.sort(sol.x)
    coef, _ = solve(bps, x, Yc, np.zeros(x.size, dtype=int))
    curve = _design(x, np.zeros(x.size, dtype=int), 1, bps)[:, :m] @ coef
    n_groups = fit.offsets.size
    offsets = np.bincount(groups, Y - curve, n_groups) / np.bincount(groups, minlength=n_groups)
    r = Y - curve - offsets[groups]
    return SegmentedFit(np.cumsum(coef), bps, offsets, float(r @ r), x.size)
