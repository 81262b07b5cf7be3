"""Keep only the plays the data resolve: merge plays that coincide, drop plays that do nothing.

A branch fit ``Y(x) = c + [a_0 x] + sum_j a_j max(0, x - b_j)`` (``a_j = p_j``, ``b_j = 2 r_j``,
``a_0`` the linear play) asked for more hinges than the data show splits one hinge in two (two
close ``b_j`` whose weights add up to the true one) or parks a hinge with a weight near 0. Which
of the two splits comes out hangs on rounding, so it differs between machines. The data decide:
a reduction (two adjacent hinges merged at their weight-weighted mean, weights added; or one
play dropped) is accepted when the Bayesian information criterion on the binned branch data
does not rise, ``N ln(SSE_reduced / SSE) <= k ln N`` (``N`` occupied bins, ``k = 2``
parameters removed, the SSE floored at ``1e-12`` of the output variance so that rounding-level
differences of a noise-free record count as equal). The best reduction is taken, the remaining
hinges refitted, and the search repeats until no reduction passes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import lsq_linear

from .piecewise_linear import fit_hinges

__all__ = [
    "PlayReduction",
    "reduce_plays",
]

SSE_FLOOR = 1e-12  # relative to the weighted output variance times the total weight
REMOVED_PARAMETERS = 2  # a merge or a drop removes one weight and one radius


@dataclass
class PlayReduction:
    """Result of :func:`reduce_plays`: the resolved plays and what was merged or dropped.

    Parameters
    ----------
    weights : numpy.ndarray of float
        Weights of the plays kept (output per input unit).
    radii : numpy.ndarray of float
        Radii of the plays kept, ascending (input unit).
    merged : list of tuple of float
        Radius pairs ``(r_a, r_b)`` merged into one play.
    dropped : list of tuple of float
        ``(radius, weight)`` of the plays removed.

    Examples
    --------
    >>> red = PlayReduction(np.array([1.0]), np.array([0.5]), merged=[(0.499, 0.501)])
    >>> red.changed
    True
    """

    weights: np.ndarray
    radii: np.ndarray
    merged: list[tuple[float, float]] = field(default_factory=list)
    dropped: list[tuple[float, float]] = field(default_factory=list)

    @property
    def changed(self) -> bool:
        return bool(self.merged or self.dropped)

    def describe(self) -> str:
        """One sentence listing the merges and drops (empty when nothing changed).

        Returns
        -------
        str
            The merges and drops, separated by ``"; "``.

        Examples
        --------
        >>> PlayReduction(np.array([1.0]), np.array([0.5]), dropped=[(2.0, 0.01)]).describe()
        'play at radius 2 with weight 0.01 dropped (no resolved slope change there)'
        """
        parts = [f"plays at radii {a:.4g} and {b:.4g} merged (not resolved apart by the data)"
                 for a, b in self.merged]
        parts += [f"play at radius {r:.4g} with weight {w:.3g} dropped (no resolved slope "
                  "change there)" for r, w in self.dropped]
        return "; ".join(parts)


def _solve(xb, sw, yw, hinges, linear):
    """Weighted least squares of the coefficients for fixed hinges (hinge weights >= 0)."""
    cols = [np.ones_like(xb)] + ([xb] if linear else [])
    A = np.column_stack(cols + [np.maximum(0.0, xb - h) for h in hinges]) * sw[:, None]
    lb = np.full(A.shape[1], -np.inf)
    lb[1:] = 0.0
    sol = lsq_linear(A, yw, bounds=(lb, np.inf), method="bvls")
    r = A @ sol.x - yw
    return sol.x[1:], float(r @ r)


def _candidates(hinges, weights):
    """Every single reduction: (description, hinges after it)."""
    out = []
    for j in range(hinges.size):
        out.append((("drop", j), np.delete(hinges, j)))
    for j in range(hinges.size - 1):
        a, b = weights[j], weights[j + 1]
        mid = (a * hinges[j] + b * hinges[j + 1]) / (a + b) if a + b > 0 else \
            0.5 * (hinges[j] + hinges[j + 1])
        out.append((("merge", j), np.concatenate((hinges[:j], [mid], hinges[j + 2:]))))
    return out


def reduce_plays(xb: np.ndarray, yb: np.ndarray, wb: np.ndarray, weights: np.ndarray,
                 radii: np.ndarray, *, linear_play: bool) -> PlayReduction:
    """Merge or drop the plays of a branch fit that the binned data do not resolve.

    Parameters
    ----------
    xb, yb, wb : numpy.ndarray
        Binned branch data: mean travel ``x`` (input unit), mean centred signed output ``Y``
        (output unit) and sample count of each occupied bin.
    weights, radii : numpy.ndarray
        The fitted plays (``radii`` ascending; with ``linear_play`` the first play is the
        linear one, ``radii[0] = 0``, and is kept).
    linear_play : bool
        Whether the first play is a linear play (``r_1 = 0``).

    Returns
    -------
    PlayReduction
        The plays the data resolve, refitted, and the list of merges and drops.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.linspace(0, 10, 400)
    >>> Y = 1.0 * np.maximum(0, x - 1) + 0.5 * np.maximum(0, x - 3)
    >>> red = reduce_plays(x, Y, np.ones_like(x), np.array([0.6, 0.4, 0.5]),
    ...                    np.array([0.499, 0.501, 1.5]), linear_play=False)
    >>> red.weights.size, len(red.merged)
    (2, 1)
    """
    xb, yb, wb = (np.asarray(a, float) for a in (xb, yb, wb))
    sw, yw = np.sqrt(wb), yb * np.sqrt(wb)
    lead = 1 if linear_play else 0
    hinges = 2.0 * np.asarray(radii, float)[lead:]
    coef, sse = _solve(xb, sw, yw, hinges, linear_play)
    n_bins = xb.size
    mean = float(wb @ yb) / float(wb.sum())
    floor = SSE_FLOOR * max(float(wb @ (yb - mean) ** 2), 1e-300)
    penalty = REMOVED_PARAMETERS * np.log(max(n_bins, 2))
    merged: list[tuple[float, float]] = []
    dropped: list[tuple[float, float]] = []
    while hinges.size > 0:
        w = coef[lead:]
        trials = [(d, h) + _solve(xb, sw, yw, h, linear_play)[::-1]
                  for d, h in _candidates(hinges, w)]
        (kind, j), h_new, sse_new, _ = min(trials, key=lambda t: t[2])
        if n_bins * np.log(max(sse_new, floor) / max(sse, floor)) > penalty:
            break
        if kind == "drop":
            dropped.append((hinges[j] / 2, float(w[j])))
        else:
            merged.append((hinges[j] / 2, hinges[j + 1] / 2))
        hinges = h_new
        if hinges.size:
            b = fit_hinges(xb, yb, wb, hinges.size, linear_term=linear_play, start=hinges)[0]
            sse_fit = _solve(xb, sw, yw, b, linear_play)[1]
            sse_kept = _solve(xb, sw, yw, hinges, linear_play)[1]
            if sse_fit <= sse_kept:
                hinges = b
        coef, sse = _solve(xb, sw, yw, hinges, linear_play)
    w = coef[lead:]
    keep = w > 0
    for h, wj in zip(hinges[~keep], w[~keep], strict=True):
        dropped.append((h / 2, float(wj)))
    hinges, w = hinges[keep], w[keep]
    if linear_play and coef[0] <= 0:
        dropped.append((0.0, float(coef[0])))
    elif linear_play:
        return PlayReduction(np.concatenate(([coef[0]], w)),
                             np.concatenate(([0.0], hinges / 2)), merged, dropped)
    return PlayReduction(w, hinges / 2, merged, dropped)
