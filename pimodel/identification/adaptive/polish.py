"""Batch least-squares polish of the play radii, and the statistical bound of the record.

With the weights known, the PI output ``y[k] = sum_j p_j z_j[k]`` with
``z_j[k] = clamp(z_j[k-1], v[k] - r_j, v[k] + r_j)``, ``z_j[-1]`` the initial state, is
*affine in the radii for a fixed switching pattern*: after the play last moved at sample
``m <= k``, ``z_j[k] = v[m] - r_j`` (it was pushed up, lower envelope) or ``v[m] + r_j``
(pushed down), and ``z_j[k] = z_j[-1]`` before it first moved. So
``d z_j[k] / d r_j = s_j[k]`` with ``s_j[k] = -1``, ``+1`` or ``0`` (the last move was up,
down, or none yet): :func:`play_sensitivity`.

- :func:`polish_radii`: Gauss-Newton on ``sum_k (y[k] - yhat[k](r))^2`` over the samples
  ``k >= (1 - tail) N``, with the switching pattern of the current iterate, projected onto
  ``0 <= r_1 <= ... <= r_n`` and halved until the cost does not grow; it stops when the
  step is below ``1e-12`` of the range of v, the cost falls by less than ``1e-9`` of itself,
  no step of 8 halvings lowers it, or after ``iterations``.
  Noise-free, once the pattern is the true one, one step lands on the truth.
- :func:`radius_bound`: the Cramer-Rao bound for the radii from output samples with white
  Gaussian noise of standard deviation ``sigma`` (the covariance of least squares with the true
  switching pattern), ``sigma^2 (J^T J)^{-1}`` with ``J[k, j] = p_j s_j[k]`` at the true radii.
  ``J^T J`` nonsingular is the excitation condition for the radii (see :func:`radius_bound`).
"""

from __future__ import annotations

import numpy as np

from ... import _native
from ...checks import as_signal, as_vector
from ...operators.pi import PIOperator
from .settings import check_weights

__all__ = [
    "play_sensitivity",
    "polish_radii",
    "profile_radii",
    "radius_bound",
    "RadiusBound",
    "refine_radii",
]

PROFILE_BINS = 512  # bins of input travel in :func:`profile_radii`
REFINE_BINS = (512, 128, 32)  # profile starts of :func:`refine_radii` (coarse ones: noise)


def play_sensitivity(v, radii, *, initial_state: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Play outputs and their derivatives with respect to the radii.

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples ``v[k]`` (input unit).
    radii : array_like of float, shape (n,)
        Radii ``r_j >= 0`` (input unit), any order.
    initial_state : float, optional
        ``z_j[-1]`` for every play (input unit). Default 0.

    Returns
    -------
    z : numpy.ndarray of float, shape (N, n)
        ``z_j[k]``, in the order of ``radii``.
    s : numpy.ndarray of float, shape (N, n)
        ``d z_j[k] / d r_j``: -1 after an upward move, +1 after a downward move, 0 before
        the first move.

    Examples
    --------
    >>> z, s = play_sensitivity([0.0, 1.0, 1.0, 0.2], [0.3])
    >>> z[:, 0], s[:, 0]
    (array([0. , 0.7, 0.7, 0.5]), array([ 0., -1., -1.,  1.]))
    """
    x = as_signal(v, "v")
    r = as_vector(radii, "radii")
    if np.any(r < 0):
        raise ValueError(f"radii: every radius must be >= 0, got {r.tolist()}")
    z = PIOperator(np.ones(r.size), np.maximum(r, 0.0), initial_state=initial_state)
    order = np.argsort(r, kind="stable")
    zz = np.empty((x.size, r.size))
    zz[:, order] = z.play_outputs(x)
    dz = np.diff(zz, axis=0, prepend=np.full((1, r.size), float(initial_state)))
    move = np.sign(-dz) + 0.0  # no -0.0
    k = np.where(move != 0, np.arange(x.size)[:, None], 0)
    last = np.maximum.accumulate(k, axis=0)
    s = np.take_along_axis(move, last, axis=0)
    return zz, s


def profile_radii(v, y, weights, *, bins: int = PROFILE_BINS) -> np.ndarray:
    """Radii from the branch profile, whatever the earlier history (a global start).

    Monotone segments of v start at reversals (sign changes of ``v[k] - v[k-1]``, holds
    ignored); along a segment with travel ``d = |v[k] - v_rev|`` no larger than the travel
    ``t_prev`` of the segment before, ``s (y[k] - y_rev) = sum_j p_j max(0, d - 2 r_j)``
    (Madelung's rule). The increments ``s (y[k] - y[k-1])`` over ``d[k] - d[k-1]`` are pooled
    in ``bins`` bins of d up to the largest travel, and the non-decreasing count ``i_b`` of
    plays on their envelope best fitting the pooled slopes against ``P_i = p_1 + .. + p_i``
    (weighted least squares, exact dynamic programme) gives ``2 r_j`` = the left edge of the
    first bin with ``i_b >= j`` (``r_j`` = the largest travel / 2 when no bin reaches j).

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel import PIOperator
    >>> v = 3 * np.sin(np.linspace(0, 40, 4000)) + np.sin(np.linspace(0, 97, 4000))
    >>> y = PIOperator([1.0, 0.5, 0.5], [0.0, 0.5, 1.2]).simulate(v)
    >>> bool(np.all(np.abs(profile_radii(v, y, [1.0, 0.5, 0.5]) - [0, 0.5, 1.2]) < 0.05))
    True
    """
    x = as_signal(v, "v", min_length=3)
    m = as_signal(y, "y", min_length=3)
    p = check_weights(weights)
    dv = np.diff(x)
    s = np.sign(dv)
    idx = np.where(s != 0, np.arange(s.size), 0)
    s = s[np.maximum.accumulate(idx)]  # holds keep the direction
    start = np.flatnonzero(np.diff(s, prepend=0) != 0)  # segment k starts at sample start[k]
    seg = np.cumsum(np.diff(s, prepend=0) != 0) - 1
    v_rev = x[start][seg]  # the sample before the segment's first step (index start = step k)
    t_seg = np.abs(np.diff(x[np.append(start, x.size - 1)]))
    t_prev = np.where(seg > 0, t_seg[np.maximum(seg - 1, 0)], 0.0)
    d1 = np.abs(x[1:] - v_rev)
    d0 = np.abs(x[:-1] - v_rev)
    ok = (d1 <= t_prev) & (d1 > d0)
    if not np.any(ok) or np.max(d1[ok]) <= 0:
        return np.zeros(p.size)
    top = float(np.max(d1[ok]))
    width = top / bins
    b = np.minimum(((d0[ok] + d1[ok]) / 2 / width).astype(int), bins - 1)
    num = np.bincount(b, s[ok] * np.diff(m)[ok], bins)
    den = np.bincount(b, d1[ok] - d0[ok], bins)
    slope = np.divide(num, den, out=np.zeros(bins), where=den > 0)
    levels = np.concatenate([[0.0], np.cumsum(p)])
    cost = den[:, None] * (slope[:, None] - levels[None, :]) ** 2  # (bins, n + 1)
    acc = np.empty_like(cost)
    arg = np.zeros(cost.shape, dtype=int)
    acc[0] = cost[0]
    for k in range(1, bins):  # acc[k, i]: best over bins <= k with count i at bin k
        best = np.minimum.accumulate(acc[k - 1])
        arg[k] = _running_argmin(acc[k - 1])
        acc[k] = cost[k] + best
    count = np.empty(bins, dtype=int)
    count[-1] = int(np.argmin(acc[-1]))
    for k in range(bins - 1, 0, -1):
        count[k - 1] = arg[k, count[k]]
    edges = np.array([width * np.argmax(count >= j) if np.any(count >= j) else top
                      for j in range(1, p.size + 1)])
    return edges / 2


def _running_argmin(a: np.ndarray) -> np.ndarray:
    """``out[i] = argmin(a[:i + 1])``."""
    out = np.zeros(a.size, dtype=int)
    for i in range(1, a.size):
        out[i] = i if a[i] < a[out[i - 1]] else out[i - 1]
    return out


def _project(r: np.ndarray, fix_first: bool) -> np.ndarray:
    """Projection onto ``0 <= r_1 <= ... <= r_n`` (the C core's, unit weights)."""
    out = np.array(r, dtype=float)
    _native.lib.pim_project_ordered(out.size, out, np.ones(out.size), int(fix_first))
    return out


def polish_radii(v, y, weights, radii, *, tail: float = 1.0, iterations: int = 30,
                 linear_play: bool = False, initial_state: float = 0.0) -> np.ndarray:
    """Gauss-Newton least-squares polish of the radii (see the module docstring).

    Parameters
    ----------
    v, y : array_like of float, shape (N,)
        Input (input unit) and measured output (output unit).
    weights : array_like of float, shape (n,)
        Known play weights ``p_j > 0``, in the order of ``radii``.
    radii : array_like of float, shape (n,)
        Start (e.g. the online estimate), non-decreasing after projection.
    tail : float, optional
        Fraction of the record, at its end, whose residuals are fitted (the model still runs
        over the whole record). Default 1 (all of it).
    iterations : int, optional
        Most Gauss-Newton steps. Default 30.
    linear_play : bool, optional
        Hold ``r_1 = 0``.
    initial_state : float, optional
        ``z_j[-1]`` of the model (input unit). Default 0.

    Returns
    -------
    numpy.ndarray of float, shape (n,)
        The polished radii (ordered, >= 0).

    Raises
    ------
    ValueError
        Bad arrays, ``tail`` outside (0, 1] or weights not > 0.

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel import PIOperator
    >>> v = 3 * np.sin(np.linspace(0, 40, 4000)) + np.sin(np.linspace(0, 97, 4000))
    >>> y = PIOperator([1.0, 0.5, 0.5], [0.0, 0.5, 1.2]).simulate(v)
    >>> polish_radii(v, y, [1.0, 0.5, 0.5], [0.1, 0.4, 1.0]).round(6)   # a local method
    array([0. , 0.5, 1.2])
    """
    x = as_signal(v, "v", min_length=2)
    m = as_signal(y, "y", min_length=2)
    if x.size != m.size:
        raise ValueError(f"v and y: expected equal lengths, got {x.size} and {m.size}")
    p = check_weights(weights)
    r = _project(as_vector(radii, "radii", length=p.size), linear_play)
    if not 0 < tail <= 1:
        raise ValueError(f"tail: expected a fraction in (0, 1], got {tail!r}")
    lo = int(x.size * (1 - tail))
    tol = 1e-12 * max(float(np.ptp(x)), 1e-300)
    free = np.arange(1 if linear_play else 0, p.size)

    def residual(rr):
        z, s = play_sensitivity(x, rr, initial_state=initial_state)
        return m[lo:] - z[lo:] @ p, s[lo:] * p

    res, J = residual(r)
    cost = float(res @ res)
    for _ in range(int(iterations)):
        Jf = J[:, free]
        step = np.zeros(p.size)
        step[free] = np.linalg.lstsq(Jf, res, rcond=None)[0]
        improved = False
        for _ in range(8):
            r_new = _project(r + step, linear_play)
            res_new, J_new = residual(r_new)
            c_new = float(res_new @ res_new)
            if c_new <= cost:
                improved = True
                break
            step /= 2
        if not improved:
            break
        moved = float(np.max(np.abs(r_new - r)))
        gain = cost - c_new
        r, res, J, cost = r_new, res_new, J_new, c_new
        if moved <= tol or gain <= 1e-9 * cost:
            break
    return r


def refine_radii(v, y, weights, online, *, tail: float = 1.0, linear_play: bool = False,
                 initial_state: float = 0.0) -> np.ndarray:
    """The batch refinement :func:`pimodel.estimate_radii` applies by default.

    Gauss-Newton (:func:`polish_radii`, whole record) from ``online`` (the online estimate)
    and from :func:`profile_radii` with 512, 128 and 32 bins (the coarse profiles are less
    noisy, the fine one more precise); the end that fits the record better (smaller sum of
    squared output errors) is kept. Then **split moves**: Gauss-Newton cannot separate two
    neighbouring plays whose switching patterns are the same (equal columns of J, e.g. both
    ``2 r_j`` between the same two levels of a stair-step input: only their weighted sum is
    determined), a local minimum with the plays nearly merged. For each such pair (patterns
    differing on at most 0.1 % of the samples, or radii closer than ``SPLIT_GAP`` of the
    input's range) the polish restarts from the pair pushed apart by ``SPLIT_STEPS`` of the
    range (``r_j - h``, ``r_{j+1} + h``); an end that fits better replaces the estimate, and
    the pairs are checked again (at most n rounds). ``tail``: the fraction of the record, at
    its end, whose residuals are fitted and compared (the model runs over the whole record;
    see :func:`polish_radii`).

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel import PIOperator
    >>> v = 3 * np.sin(np.linspace(0, 40, 4000)) + np.sin(np.linspace(0, 97, 4000))
    >>> y = PIOperator([1.0, 0.5, 0.5], [0.0, 0.5, 1.2]).simulate(v)
    >>> refine_radii(v, y, [1.0, 0.5, 0.5], [2.0, 2.0, 2.0]).round(6)
    array([0. , 0.5, 1.2])
    """
    x = as_signal(v, "v", min_length=3)
    m = as_signal(y, "y", min_length=3)
    p = check_weights(weights)
    starts = [_project(as_vector(online, "online", length=p.size), linear_play),
              *(_project(profile_radii(x, m, p, bins=b), linear_play) for b in REFINE_BINS)]

    lo = int(x.size * (1 - tail)) if 0 < tail <= 1 else 0  # polish_radii checks tail

    def polish(r):
        end = polish_radii(x, m, p, r, tail=tail, linear_play=linear_play,
                           initial_state=initial_state)
        z, s = play_sensitivity(x, end, initial_state=initial_state)
        return end, float(np.sum((m[lo:] - z[lo:] @ p) ** 2)), s[lo:]

    best, cost, s = min((polish(r) for r in starts), key=lambda e: e[1])
    span = float(np.ptp(x))
    for _ in range(p.size):
        improved = False
        for j in _merged_pairs(best, s, SPLIT_GAP * span):
            for h in SPLIT_STEPS:
                r = best.copy()
                r[j] -= h * span
                r[j + 1] += h * span
                end, c, s_end = polish(_project(r, linear_play))
                if c < cost:
                    best, cost, s, improved = end, c, s_end, True
            if improved:
                break
        if not improved:
            break
    return best


SPLIT_GAP = 0.005  # radii closer than this fraction of the input range: try a split
SPLIT_STEPS = (0.005, 0.02)  # split moves of :func:`refine_radii`, fractions of the range


def _merged_pairs(r: np.ndarray, s: np.ndarray, gap: float) -> list[int]:
    """0-based j of neighbours (j, j + 1) with (nearly) the same switching pattern."""
    same = np.mean(s[:, 1:] != s[:, :-1], axis=0) <= 1e-3
    return [int(j) for j in np.flatnonzero(same | (np.diff(r) < gap))]


class RadiusBound:
    """Result of :func:`radius_bound`.

    Parameters
    ----------
    covariance : numpy.ndarray of float, shape (n, n)
        ``sigma^2 (J^T J)^{-1}`` (input unit squared); ``inf`` on the diagonal when the record
        does not excite the radii.
    information : numpy.ndarray of float, shape (n, n)
        ``J^T J / sigma^2``.

    Examples
    --------
    >>> b = RadiusBound(np.diag([4.0, 1.0]), np.diag([0.25, 1.0]))
    >>> b.sd
    array([2., 1.])
    """

    def __init__(self, covariance: np.ndarray, information: np.ndarray):
        self.covariance = covariance
        self.information = information

    @property
    def sd(self) -> np.ndarray:
        """Standard deviations of the radii, ``sqrt(diag(covariance))``."""
        return np.sqrt(np.diag(self.covariance))

    @property
    def exciting(self) -> bool:
        """``J^T J`` is nonsingular (condition number below ``1e12``)."""
        return bool(np.all(np.isfinite(self.covariance)))


def radius_bound(v, weights, radii, *, sigma: float, tail: float = 1.0,
                 linear_play: bool = False, initial_state: float = 0.0) -> RadiusBound:
    """Cramer-Rao bound of the radii from ``y[k] = PI[v][k] + w[k]``, ``w`` white Gaussian.

    ``J[k, j] = p_j s_j[k]`` (:func:`play_sensitivity` at the true radii) over the samples
    ``k >= (1 - tail) N``; the bound is ``sigma^2 (J^T J)^{-1}``, which least squares with
    the true switching pattern attains. **Excitation condition:** the radii are identifiable
    from the record iff ``J^T J`` is nonsingular: every play must move on both of its
    envelopes (a reversal followed by travel above ``2 r_j``), and plays j and j + 1 must be
    told apart (the travel after some reversal ends between ``2 r_j`` and ``2 r_{j+1}``, or
    their last moves differ otherwise). For equal true radii J has equal columns: the bound
    is then infinite and the radii are not separately identifiable.

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples (input unit).
    weights, radii : array_like of float, shape (n,)
        Play weights (> 0) and the true (or estimated) radii.
    sigma : float
        Standard deviation of the output noise (output unit), > 0.
    tail : float, optional
        Fraction of the record, at its end, that the estimate uses. Default 1.
    linear_play : bool, optional
        ``r_1 = 0`` is known (not estimated): its variance is 0.
    initial_state : float, optional
        ``z_j[-1]`` (input unit). Default 0.

    Returns
    -------
    RadiusBound

    Examples
    --------
    >>> import numpy as np
    >>> v = np.sin(np.linspace(0, 60, 6000))
    >>> b = radius_bound(v, [1.0, 1.0], [0.1, 0.4], sigma=0.01)
    >>> bool(b.exciting), bool(np.all(b.sd < 1e-3))
    (True, True)
    """
    x = as_signal(v, "v", min_length=2)
    p = check_weights(weights)
    r = as_vector(radii, "radii", length=p.size)
    if not (np.isfinite(sigma) and sigma > 0):
        raise ValueError(f"sigma: expected a finite number > 0, got {sigma!r}")
    if not 0 < tail <= 1:
        raise ValueError(f"tail: expected a fraction in (0, 1], got {tail!r}")
    lo = int(x.size * (1 - tail))
    _, s = play_sensitivity(x, r, initial_state=initial_state)
    J = s[lo:] * p
    info = J.T @ J / sigma**2
    free = np.arange(1 if linear_play else 0, p.size)
    cov = np.zeros((p.size, p.size))
    sub = info[np.ix_(free, free)]
    if free.size and np.linalg.cond(sub) < 1e12:
        cov[np.ix_(free, free)] = np.linalg.inv(sub)
    elif free.size:
        cov[np.ix_(free, free)] = np.inf
    return RadiusBound(cov, info)
