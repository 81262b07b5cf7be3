"""Plain NumPy specification of the radius estimator (one Python step per sample).

Implements exactly the laws of :mod:`pimodel.identification.adaptive.radius_estimator` /
``fmu/src/pim_estimator.c``
(``law="data"`` and ``law="paper"``); a test holds the two equal to 1e-12. Slow on purpose: it
is the readable version.
"""

from __future__ import annotations

import numpy as np

from .._native import LIMITS

__all__ = [
    "BranchProfile",
    "estimate_radii_reference",
    "project_ordered_reference",
]

BINS = LIMITS["PIM_EST_BINS"]  # the C core's, so that the two stay equal


def project_ordered_reference(x: np.ndarray, w: np.ndarray, fix_first: bool) -> np.ndarray:
    """Weighted projection onto ``0 <= x_1 <= ... <= x_n`` by pooling adjacent violators.

    The specification of :func:`pimodel.identification.adaptive.radius_estimator.project_ordered`.

    Parameters
    ----------
    x : array_like of float, shape (n,)
        The point to project.
    w : array_like of float, shape (n,)
        Positive weights of the norm.
    fix_first : bool
        Also hold ``x_1 = 0``.

    Returns
    -------
    numpy.ndarray of float, shape (n,)
        The projection (a new array).

    Examples
    --------
    >>> project_ordered_reference([0.5, 0.2, 1.0], np.ones(3), False)
    array([0.35, 0.35, 1.  ])
    """
    x = np.array(x, dtype=float)
    start = 1 if fix_first else 0
    if fix_first:
        x[0] = 0.0
    blocks: list[list[float]] = []  # [value, weight, count]
    for i in range(start, x.size):
        blocks.append([x[i], w[i], 1])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            v2, w2, c2 = blocks.pop()
            v1, w1, c1 = blocks[-1]
            blocks[-1] = [(w1 * v1 + w2 * v2) / (w1 + w2), w1 + w2, c1 + c2]
    out = [max(v, 0.0) for v, _, c in blocks for _ in range(c)]
    x[start:] = out
    return x


class BranchProfile:
    """Pooled branch slopes over travel bins and the regime table fitted to them (data law).

    Parameters
    ----------
    p : numpy.ndarray of float, shape (n,)
        Play weights; the slope levels are ``P_0 = 0, P_i = p_1 + ... + p_i``.
    linear_play : bool
        Play 1 is always on its envelope (``r_1 = 0``).

    Examples
    --------
    Two branch pieces of slope 1 then 2 put play 2's breakpoint at travel 0.5:

    >>> prof = BranchProfile(np.array([1.0, 1.0]), False)
    >>> prof.width = 0.01                  # bin width (input unit), set by the law at first
    >>> prof.add(0.0, 0.5, 0.5)
    >>> prof.add(0.5, 1.0, 1.0)
    >>> prof.fit()
    >>> prof.edge
    array([0. , 0.5])
    """

    def __init__(self, p: np.ndarray, linear_play: bool):
        self.levels = np.concatenate([[0.0], np.cumsum(p)])  # P_0 = 0, P_i = p_1 + ... + p_i
        self.imin = 1 if linear_play else 0
        self.S = np.zeros(BINS)  # sum of s * output change per bin
        self.C = np.zeros(BINS)  # sum of travel per bin
        self.width = 0.0
        self.top = -1
        self.edge = np.full(p.size, -1.0)
        self.fitted = False

    def add(self, x0: float, x1: float, dy: float) -> None:
        """Spread the branch piece [x0, x1] with output change dy over the bins it covers.

        Bins are merged in pairs (the width doubles) until ``x1`` fits in the 256 bins.

        Parameters
        ----------
        x0 : float
            Travel at the start of the piece (input unit, >= 0).
        x1 : float
            Travel at its end (input unit, > x0).
        dy : float
            Signed output change ``s (y[k] - y[k-1])`` along the piece (output unit).

        Examples
        --------
        >>> prof = BranchProfile(np.array([1.0]), False)
        >>> prof.width = 0.1
        >>> prof.add(0.0, 0.2, 0.4)
        >>> prof.S[:3], prof.C[:3]
        (array([0.2, 0.2, 0. ]), array([0.1, 0.1, 0. ]))
        """
        while x1 >= BINS * self.width:  # merge bins in pairs
            self.S[: BINS // 2] = self.S[0::2] + self.S[1::2]
            self.C[: BINS // 2] = self.C[0::2] + self.C[1::2]
            self.S[BINS // 2:] = 0.0
            self.C[BINS // 2:] = 0.0
            self.width *= 2.0
            self.top = self.top // 2 if self.top >= 0 else -1
        w, span = self.width, x1 - x0
        b1 = min(int(x1 / w), BINS - 1)
        b0 = min(int(x0 / w), b1)
        for b in range(b0, b1 + 1):
            lo, hi = max(b * w, x0), min((b + 1) * w, x1)
            part = span if b0 == b1 else (hi - lo if hi > lo else 0.0)
            self.S[b] += dy * (part / span)
            self.C[b] += part
        self.top = max(self.top, b1)

    def fit(self) -> None:
        """Non-decreasing count per bin minimising sum C_b (S_b/C_b - P_i)^2; edges from it.

        An exact dynamic programme over the bins filled so far; sets ``edge[j]``, the travel
        at which play j + 1 reaches its envelope (-1 when it does not within the profile).

        Examples
        --------
        >>> prof = BranchProfile(np.array([1.0, 1.0]), False)
        >>> prof.width = 0.01
        >>> prof.add(0.0, 1.0, 1.0)           # slope 1 throughout: play 2 never on
        >>> prof.fit()
        >>> prof.edge
        array([ 0., -1.])
        """
        if self.top < 0:
            return
        P, n1 = self.levels, self.levels.size
        big = 1e300
        f = [big if i < self.imin else self.C[0] * P[i] * P[i] - 2.0 * self.S[0] * P[i]
             for i in range(n1)]
        back = np.zeros((self.top + 1, n1), dtype=int)
        for b in range(1, self.top + 1):
            best, arg = big, 0
            for i in range(n1):
                if f[i] < best:
                    best, arg = f[i], i
                back[b, i] = arg
                f[i] = big if i < self.imin else (best + self.C[b] * P[i] * P[i]
                                                  - 2.0 * self.S[b] * P[i])
        i = self.imin
        for k in range(self.imin, n1):
            if f[k] < f[i]:
                i = k
        self.edge[:] = -1.0
        for b in range(self.top, -1, -1):
            self.edge[:i] = b * self.width
            if b > 0:
                i = back[b, i]
        self.fitted = True


def estimate_radii_reference(v, y, weights, *, dt, gains, initial_radii, linear_play=False,
                             threshold=0.0, max_step=None, anneal_time=None, guard=0.0,
                             slope_window=8, slope_tol=0.5, initial_state=0.0, law="data"):
    """Returns ``(history, yhat, e, e_delta, used, final radii)`` as in the C batch loop.

    One Python step per sample (slow); the arguments are those of
    :class:`pimodel.identification.adaptive.radius_estimator.RadiusEstimator` with ``v``, ``y`` as
    in
    :meth:`pimodel.identification.adaptive.radius_estimator.RadiusEstimator.run` (no argument
    checks here).

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples ``v[k]`` (input unit).
    y : array_like of float, shape (N,)
        Measured output ``y[k]`` (output unit).
    weights : array_like of float, shape (n,)
        Play weights ``p_j > 0``.
    dt : float
        Sample time [s].
    gains : float or array_like of float
        Adaptation gains (scalar or per play).
    initial_radii : array_like of float, shape (n,)
        Start of the estimate (projected onto the ordered set).
    linear_play : bool, optional
        Hold ``rhat_1 = 0``.
    threshold : float, optional
        Reversal threshold (input unit).
    max_step : float, optional
        Per-sample clip of the update (input unit).
    anneal_time : float, optional
        Gain annealing time constant [s].
    guard : float, optional
        Breakpoint guard band (input unit).
    slope_window : int, optional
        Samples of the slope check (``law="paper"``).
    slope_tol : float, optional
        Slope check tolerance in units of the smallest weight.
    initial_state : float, optional
        Model play state before the first sample.
    law : {"data", "paper"}, optional
        The regime law (module docstring of
        :mod:`pimodel.identification.adaptive.radius_estimator`).

    Returns
    -------
    history : numpy.ndarray, shape (N, n)
        Estimate used at each step.
    yhat : numpy.ndarray, shape (N,)
        Model output.
    e : numpy.ndarray, shape (N,)
        ``yhat[k] - y[k]``.
    e_delta : numpy.ndarray, shape (N,)
        Modified error (0 where unused).
    used : numpy.ndarray of bool, shape (N,)
        True where the sample adapted the radii.
    radii : numpy.ndarray, shape (n,)
        Final estimate.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = np.sin(np.linspace(0, 20, 2000))
    >>> y = PIOperator([1.0, 1.0], [0.0, 0.3]).simulate(v)
    >>> out = estimate_radii_reference(v, y, [1.0, 1.0], dt=1e-3, gains=10.0,
    ...                                initial_radii=[0.0, 0.0])
    >>> out[-1].round(2)
    array([0. , 0.3])
    """
    p = np.asarray(weights, float)
    n = p.size
    g = np.broadcast_to(np.asarray(gains, float), (n,)).copy()
    w = 1.0 / np.maximum(g, 1e-300)
    rhat = project_ordered_reference(np.asarray(initial_radii, float), w, linear_play)
    zhat = np.full(n, float(initial_state))
    sat = np.zeros(n)
    prof = BranchProfile(p, linear_play)
    started = False
    direction = 0.0
    have_rev = False
    v_first = v_start = v_ext = v_rev = y_ext = 0.0
    t_prev = x_last = y_last = 0.0
    time = 0.0
    nseg = 0
    past_v: list[float] = []  # inputs and outputs before sample k
    past_y: list[float] = []
    N = len(v)
    hist, yhat, e, ed, used = np.empty((N, n)), np.empty(N), np.empty(N), np.zeros(N), np.zeros(N)
    for k in range(N):
        vk, yk = float(v[k]), float(y[k])
        hist[k] = rhat
        zhat = np.maximum(vk - rhat, np.minimum(vk + rhat, zhat))
        yhat[k] = sum(p[j] * zhat[j] for j in range(n))  # sequential sum, as in C
        e[k] = yhat[k] - yk
        usable = False
        if not started:
            started, v_first, v_start, v_ext, y_ext = True, vk, vk, vk, yk
        elif direction == 0.0:
            if abs(vk - v_first) > threshold:
                direction = 1.0 if vk > v_first else -1.0
                v_ext, y_ext = vk, yk
        elif direction * (vk - v_ext) >= 0.0:
            if direction * (vk - v_ext) > 0.0:
                v_ext, y_ext = vk, yk
            usable = have_rev
        elif abs(vk - v_ext) > threshold:
            t_prev = abs(v_ext - v_start)
            sat = (t_prev >= 2.0 * rhat + guard).astype(float)
            v_rev = v_start = v_ext
            have_rev = True
            direction = -direction
            x_last, y_last = 0.0, y_ext
            v_ext, y_ext = vk, yk
            nseg = 0
            usable = True
            if law == "data":
                if prof.width == 0.0:
                    prof.width = 2.2 * t_prev / BINS
                prof.fit()
        if usable:
            s, d = direction, abs(vk - v_rev)
            if law == "data":
                if d > x_last:
                    if d <= t_prev:
                        top = prof.top
                        prof.add(x_last, d, s * (yk - y_last))
                        if prof.top > top:  # the profile grew
                            prof.fit()
                    x_last, y_last = d, yk
                on = _regime_data(prof, rhat, sat, d, guard, t_prev)
            else:
                on = _regime_paper(rhat, sat, d, guard) if _slope_ok(
                    p, rhat, past_v, past_y, nseg, slope_window, slope_tol, v_rev,
                    direction) else None
            if on is not None:
                phi = np.where(on, p, -p)
                ybar = 0.0
                for j in range(n):  # sequential sum, as in C
                    ybar += p[j] * (vk - s * rhat[j]) if on[j] else p[j] * (v_rev + s * rhat[j])
                err = ybar - yk
                scale = 1.0 / (1.0 + time / anneal_time) if anneal_time else 1.0
                step = dt * g * scale * err * s * phi
                if max_step:
                    step = np.clip(step, -max_step, max_step)
                rhat = project_ordered_reference(rhat + step, w, linear_play)
                ed[k] = err
                used[k] = 1.0
        time += dt
        nseg += 1
        past_v.append(vk)
        past_y.append(yk)
    return hist, yhat, e, ed, used.astype(bool), rhat


def _regime_data(prof: BranchProfile, rhat, sat, d, guard, t_prev):
    """Plays on their envelope at travel d under the data law, or None (sample not used)."""
    if not prof.fitted:
        return None
    g = max(guard, prof.width)
    partial = (prof.top + 1.0) * prof.width < t_prev
    on = np.zeros(rhat.size, dtype=bool)
    for j, b in enumerate(prof.edge):
        if b < 0.0 and partial:  # breakpoint not profiled yet: the paper's rule
            if abs(d - 2.0 * rhat[j]) < guard:
                return None
            on[j] = d >= 2.0 * rhat[j]
            if not on[j] and sat[j] == 0.0:
                return None
            continue
        if b < 0.0:
            on[j] = False
        elif abs(d - b) >= g:
            on[j] = d >= b
        else:
            b2 = 2.0 * rhat[j]
            if abs(b2 - b) >= g or abs(d - b2) < guard:
                return None
            on[j] = d >= b2
        if not on[j] and (b < 0.0 or b + g > t_prev):
            return None
    if not on.all() and d >= (prof.top + 1.0) * prof.width:
        return None
    return on


def _regime_paper(rhat, sat, d, guard):
    """Plays on their envelope at travel d under the paper's law, or None."""
    if np.any(np.abs(d - 2.0 * rhat) < guard):
        return None
    on = d >= 2.0 * rhat
    if np.any(~on & (sat == 0.0)):
        return None
    return on


def _slope_ok(p, rhat, past_v, past_y, nseg, m, tol, v_rev, direction) -> bool:
    """The paper law's slope check over the m samples before k."""
    if m == 0:
        return True
    if nseg < m + 1:
        return False
    da, db = abs(past_v[-1 - m] - v_rev), abs(past_v[-1] - v_rev)
    if db - da <= 0:
        return True
    model = sum(p[j] * max(0.0, db - max(da, 2.0 * rhat[j])) for j in range(p.size))
    meas = direction * (past_y[-1] - past_y[-1 - m])
    return abs(meas - model) <= tol * p.min() * (db - da)
