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

from .branches import split_branches
from .checks import as_signal
from .segmented import SegmentedFit, fit_segmented, polish_fit


@dataclass
class SlopeIdentification:
    """Result of :func:`identify_slopes` (weights in output/input units, radii in input units)."""

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
    xs, Ys, gs = [], [], []
    for g, b in enumerate(keep):
        sl = slice(b.start, b.stop)
        xs.append(np.abs(v[sl] - v[b.start]))
        Ys.append(b.direction * y[sl])
        gs.append(np.full(b.stop - b.start, g))
    x, Y, groups = np.concatenate(xs), np.concatenate(Ys), np.concatenate(gs)
    if x.size > max_points:
        sel = np.linspace(0, x.size - 1, max_points).astype(int)
        x, Y, groups = x[sel], Y[sel], groups[sel]
    return x, Y, groups, len(keep)


def plays_from_slopes(slopes: np.ndarray, breakpoints: np.ndarray, *,
                      linear_play: bool) -> tuple[np.ndarray, np.ndarray]:
    """Weights and radii from a branch fit's slopes ``s_1..s_m`` and breakpoints ``b_1..b_{m-1}``
    (Lemma 1): with a linear play ``p = (s_1, s_2 - s_1, ...)``, ``r = (0, b_1/2, ...)``;
    without one the first segment is flat and ``p = (s_2 - s_1, ...)``, ``r = (b_1/2, ...)``."""
    if linear_play:
        return np.diff(np.concatenate(([0.0], slopes))), np.concatenate(([0.0], breakpoints / 2))
    return np.diff(slopes), breakpoints / 2


def identify_slopes(v, y, *, max_segments: int = 8, n_plays: int | None = None,
                    linear_play: bool | None = None, threshold: float | None = None,
                    min_travel_fraction: float = 0.5, max_points: int = 500_000,
                    ) -> SlopeIdentification:
    """Number of plays, weights and radius guesses from a record's loop slopes.

    ``v``, ``y``: input and output samples (at least one full reversal). ``n_plays`` fixes the
    number of plays instead of choosing it by BIC; ``linear_play`` forces the presence (True) or
    absence (False) of a play with ``r_1 = 0`` (default: present when the smallest slope exceeds
    5 % of the largest). ``threshold``: reversal threshold (default 1 % of the input range).
    Branches shorter than ``min_travel_fraction`` of the longest are ignored (minor loops).
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
