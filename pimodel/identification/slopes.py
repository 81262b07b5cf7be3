"""Number and weights of plays from the loop slopes (Lemma 1, Remark 1).

On a branch that starts at a reversal where every play was on the opposite envelope, the output
is piecewise linear in the input travel ``x = |v - v_reversal|`` with slopes
``0, P_1, ..., P_n`` (``r_1 > 0``) or ``P_1, ..., P_n`` (``r_1 = 0``), ``P_i = p_1 + ... + p_i``,
and breakpoints at ``x = 2 r_j``. :func:`identify_slopes` pools the major branches (descending
ones mirrored), fits an optimal continuous segmented regression for each number of segments
``m = 1..max_segments`` and picks ``m`` by the Bayesian information criterion (BIC); the chosen
fit is then polished on the unbinned data.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from ..checks import as_signal
from .branches import split_branches
from .piecewise_linear import SegmentedFit, fit_segmented, polish_fit

__all__ = [
    "identify_slopes",
    "plays_from_slopes",
    "SlopeIdentification",
]


@dataclass
class SlopeIdentification:
    """Result of :func:`identify_slopes`.

    Parameters
    ----------
    n_plays : int
        Number of plays.
    weights : numpy.ndarray of float, shape (n_plays,)
        Weights ``p_i`` (output unit per input unit), from the slope increments.
    radii_guess : numpy.ndarray of float, shape (n_plays,)
        Radii ``r_i`` (input unit), half the breakpoints: a starting point for the estimator.
    linear_play : bool
        Whether the first play has ``r_1 = 0``.
    slopes : numpy.ndarray of float, shape (m,)
        The branch fit's slopes ``s_1..s_m``.
    breakpoints : numpy.ndarray of float, shape (m - 1,)
        The branch fit's breakpoints (input travel).
    rms : float
        RMS of the branch fit residual (output unit).
    r2 : float
        Coefficient of determination of the branch fit.
    bic : dict of int to float, optional
        BIC of each number of segments tried.
    branches_used : int, optional
        Number of branches pooled in the fit.

    Examples
    --------
    >>> from pimodel import PIOperator, identify_slopes
    >>> v = np.sin(np.linspace(0, 6 * np.pi, 3000))
    >>> s = identify_slopes(v, PIOperator([1.0, 0.5], [0.0, 0.3]).simulate(v), max_segments=3)
    >>> s.n_plays, s.linear_play, s.to_json()["criterion"][:3]
    (2, True, 'BIC')
    """

    n_plays: int
    weights: np.ndarray
    radii_guess: np.ndarray
    linear_play: bool
    slopes: np.ndarray
    breakpoints: np.ndarray
    rms: float
    r2: float
    bic: dict[int, float] = field(default_factory=dict)
    branches_used: int = 0

    def to_json(self) -> dict:
        """The result as JSON-ready built-in types.

        Returns
        -------
        dict
            ``n_plays``, ``weights``, ``radii_guess``, ``linear_play``, ``slopes``,
            ``breakpoints``, ``fit_rms``, ``fit_r2``, ``bic`` (keys as strings),
            ``branches_used`` and the ``criterion`` used.

        Examples
        --------
        >>> import json
        >>> from pimodel import PIOperator, identify_slopes
        >>> v = np.sin(np.linspace(0, 6 * np.pi, 3000))
        >>> s = identify_slopes(v, PIOperator([1.0], [0.0]).simulate(v), max_segments=2)
        >>> json.loads(json.dumps(s.to_json()))["n_plays"]
        1
        """
        return {
            "n_plays": self.n_plays,
            "weights": self.weights.tolist(),
            "radii_guess": self.radii_guess.tolist(),
            "linear_play": self.linear_play,
            "slopes": self.slopes.tolist(),
            "breakpoints": self.breakpoints.tolist(),
            "fit_rms": self.rms,
            "fit_r2": self.r2,
            "bic": {str(k): v for k, v in self.bic.items()},
            "branches_used": self.branches_used,
            "criterion": "BIC = N ln(SSE/N) + k ln N, k = 2m - 1 + branches",
        }


def _pool_branches(v, y, threshold, min_travel_fraction, max_points):
    branches = [b for b in split_branches(v, threshold) if b.from_reversal]
    if not branches:
        raise ValueError(
            "v: no input reversal found; slope identification needs at least one full reversal "
            f"(reversal threshold {threshold:.3g})"
        )
    travel = np.array([abs(v[b.stop - 1] - v[b.start]) for b in branches])
    keep = [b for b, tr in zip(branches, travel, strict=True)
            if tr >= min_travel_fraction * travel.max()]
    # the pooled samples (branch after branch), thinned to max_points evenly spaced ones: the
    # indices into the pool are placed branch by branch, so the pool is never built whole
    sizes = np.array([b.stop - b.start for b in keep])
    ends = np.cumsum(sizes)
    total = int(ends[-1])
    sel = np.linspace(0, total - 1, max_points).astype(int) if total > max_points else None
    xs, Ys, gs = [], [], []
    for g, b in enumerate(keep):
        if sel is None:
            idx = slice(b.start, b.stop)
        else:
            lo, hi = np.searchsorted(sel, [ends[g] - sizes[g], ends[g]])
            idx = b.start + (sel[lo:hi] - (ends[g] - sizes[g]))
        xs.append(np.abs(v[idx] - v[b.start]))
        Ys.append(b.direction * y[idx])
        gs.append(np.full(xs[-1].size, g))
    x, Y, groups = np.concatenate(xs), np.concatenate(Ys), np.concatenate(gs)
    return x, Y, groups, len(keep)


def plays_from_slopes(slopes: np.ndarray, breakpoints: np.ndarray, *,
                      linear_play: bool) -> tuple[np.ndarray, np.ndarray]:
    """Weights and radii from a branch fit's slopes and breakpoints (Lemma 1).

    With a linear play ``p = (s_1, s_2 - s_1, ...)`` and ``r = (0, b_1/2, ...)``; without one
    the first segment is flat and ``p = (s_2 - s_1, ...)``, ``r = (b_1/2, ...)``.

    Parameters
    ----------
    slopes : numpy.ndarray of float, shape (m,)
        Slopes ``s_1..s_m`` of the branch (output unit per input unit), ascending travel.
    breakpoints : numpy.ndarray of float, shape (m - 1,)
        Breakpoints ``b_1..b_{m-1}`` (input travel, ``2 r_j``).
    linear_play : bool
        Whether the first segment is a play with ``r_1 = 0`` (else it is flat).

    Returns
    -------
    weights : numpy.ndarray of float
        ``p_i``; ``m`` of them with a linear play, ``m - 1`` without.
    radii : numpy.ndarray of float
        ``r_i``, same length.

    Examples
    --------
    >>> from pimodel.identification.slopes import plays_from_slopes
    >>> plays_from_slopes(np.array([1.0, 1.5]), np.array([0.6]), linear_play=True)
    (array([1. , 0.5]), array([0. , 0.3]))
    """
    if linear_play:
        return np.diff(np.concatenate(([0.0], slopes))), np.concatenate(([0.0], breakpoints / 2))
    return np.diff(slopes), breakpoints / 2


def identify_slopes(v, y, *, max_segments: int = 8, n_plays: int | None = None,
                    linear_play: bool | None = None, threshold: float | None = None,
                    min_travel_fraction: float = 0.5, max_points: int = 500_000,
                    ) -> SlopeIdentification:
    """Number of plays, weights and radius guesses from a record's loop slopes.

    The branches that start at a reversal are pooled (module docstring) and fitted with
    ``m = 1..max_segments`` segments; ``m`` is chosen by BIC unless ``n_plays`` is given.

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples (input unit), with at least one full reversal; ``N >= 10``.
    y : array_like of float, shape (N,)
        Output samples (output unit).
    max_segments : int, optional
        Largest number of segments tried, ``>= 1``.
    n_plays : int, optional
        Fix the number of plays instead of choosing it by BIC.
    linear_play : bool, optional
        Force the presence (True) or absence (False) of a play with ``r_1 = 0``. Default:
        present when the smallest slope exceeds 5 % of the largest.
    threshold : float, optional
        Reversal threshold (input unit; default 1 % of the input range).
    min_travel_fraction : float, optional
        Branches that travel less than this fraction of the longest are ignored (minor loops).
    max_points : int, optional
        The pooled branches are subsampled evenly to at most this many points.

    Returns
    -------
    SlopeIdentification
        Number of plays, weights, radius guesses, the fit and its BIC table.

    Raises
    ------
    ValueError
        If ``v`` or ``y`` is not a finite signal of at least 10 samples, their lengths differ,
        the input is constant or has no reversal, the output is constant or does not increase
        with the input, or ``max_segments`` or ``n_plays`` is below 1.

    Warns
    -----
    UserWarning
        When segments with no slope change were merged.

    Examples
    --------
    >>> from pimodel import PIOperator, identify_slopes
    >>> v = np.sin(np.linspace(0, 6 * np.pi, 6000))
    >>> y = PIOperator([1.0, 0.5, 0.25], [0.0, 0.2, 0.5]).simulate(v)
    >>> s = identify_slopes(v, y, max_segments=4)
    >>> s.n_plays, s.weights.round(4), s.radii_guess.round(4)
    (3, array([1.  , 0.5 , 0.25]), array([0. , 0.2, 0.5]))
    """
    v = as_signal(v, "v", min_length=10)
    y = as_signal(y, "y", min_length=10)
    if v.size != y.size:
        raise ValueError(f"v and y: expected equal lengths, got {v.size} and {y.size}")
    span = float(np.ptp(v))
    if span == 0:
        raise ValueError("v: the input is constant; slope identification needs reversals")
    if np.ptp(y) == 0:
        raise ValueError("y: the output is constant; there is no loop to identify")
    if max_segments < 1:
        raise ValueError(f"max_segments: expected >= 1, got {max_segments}")
    thr = 0.01 * span if threshold is None else float(threshold)
    x, Y, groups, used = _pool_branches(v, y, thr, min_travel_fraction, max_points)

    fits: dict[int, SegmentedFit] = {}
    var = float(np.var(Y - np.bincount(groups, Y)[groups] / np.bincount(groups)[groups]))
    floor = 1e-10 * max(var, 1e-300)
    if n_plays is not None:
        if n_plays < 1:
            raise ValueError(f"n_plays: expected >= 1, got {n_plays}")
        orders = [n_plays, n_plays + 1]  # with or without a linear play
    else:
        orders = list(range(1, max_segments + 1))
    for m in orders:
        fits[m] = fit_segmented(x, Y, groups, segments=m, increasing=True)
    bic = {m: f.bic(floor) for m, f in fits.items()}

    def has_linear(f: SegmentedFit) -> bool:
        if linear_play is not None:
            return linear_play
        return bool(f.slopes[0] > 0.05 * f.slopes[-1])

    if n_plays is not None:
        # m = n with a linear play, m = n + 1 without: keep the variant consistent with the fit
        cands = [m for m in orders if (m == n_plays) == has_linear(fits[m])]
        best = min(cands or orders, key=lambda m: bic[m])
    else:
        best = min(bic, key=bic.get)
    fit = polish_fit(x, Y, groups, fits[best])
    lin = has_linear(fit)
    s = fit.slopes
    weights, radii = plays_from_slopes(s, fit.breakpoints, linear_play=lin)
    keep = weights > 1e-9 * max(abs(s[-1]), 1e-300)
    if not np.all(keep):
        warnings.warn(f"slope identification: {int((~keep).sum())} segment(s) with no slope "
                      "change were merged", stacklevel=2)
    weights, radii = weights[keep], radii[keep]
    if weights.size == 0:
        raise ValueError("y: no increasing slope found; the loop does not look like PI "
                         "hysteresis (is the output decreasing with the input?)")
    resid_var = fit.sse / fit.n_points
    return SlopeIdentification(
        n_plays=int(weights.size), weights=weights, radii_guess=radii, linear_play=lin,
        slopes=s, breakpoints=fit.breakpoints, rms=float(np.sqrt(resid_var)),
        r2=float(1 - resid_var / var) if var > 0 else 1.0, bic=bic, branches_used=used,
    )
