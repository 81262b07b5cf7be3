"""The nearest monotone PI model, for the inverse feedforward only.

The diagnosis fits its nominal PI weights by least squares on a fine radius grid, so they are
signed. A PI operator ``y = sum_i w_i z_i`` (radii ``r_1 < ... < r_n``) is monotone when every
partial sum ``S_m = w_1 + ... + w_m`` is positive: at a distance ``l`` from a branch's
last reversal the plays with ``2 r_i < l`` move and the branch's slope is ``S_m``,
``m = #{i: 2 r_i < l}``; within one sample the slope of ``y[k]``
in ``v[k]`` is such a partial sum too (the moving plays are always the smallest radii). A
partial sum ``S_m <= 0`` makes the branch turn back (fold): the per-sample root of
:func:`pimodel.diagnosis.reference_inverse.solve_static` then vanishes where the branch folds, and
the inverse jumps to a far root (on the shared real record: 14.8 V in one sample, where the
reference input moves 0.19 V).

The projection keeps the branch curve of the model, not its slopes. The branch curve, sampled
at the radii, is ``Phi_0 = 0``, ``Phi_j = sum_{m <= j} S_m (r_{m+1} - r_m)`` (half the
output change at a branch length ``2 r_{j+1}``). :func:`monotone_weights` replaces it by the
curve ``Phi'`` with slopes ``S'_m >= f`` (``f = FLOOR_SHARE`` times the median partial sum)
that is closest in the maximum norm: with ``g = Phi - f r``, the non-decreasing sequence
closest to ``g`` is ``(max_{i <= j} g_i + min_{i >= j} g_i) / 2`` (L-infinity isotonic
regression), raised to ``>= 0`` so that ``Phi'_0 = 0``; then ``Phi' = that + f r``. The last
slope ``S_n`` (branches longer than the input span) is kept, or raised to ``f``. The folds are
flattened into the neighbouring cells; a fold's area is conserved as far as the floor allows,
so the projected branches end where the original ones end.

Bound: with ``d_m = z_m - z_{m+1}`` (``|d_m| <= r_{m+1} - r_m``), ``y' - y = sum_{m<n} (S'_m -
S_m) d_m + (S'_n - S_n) z_n``. The memory of the plays, ``z`` against ``r``, has slopes -1, +1
or 0 between its corners, so on a memory of ``c`` pieces ``|y' - y| <= 2 c max_j |Phi'_j -
Phi_j| + sum over the cells holding a corner of ``|S'_m - S_m| (r_{m+1} - r_m)`` (+ the
last term): :func:`monotone_error` gives ``E = max_j |Phi'_j - Phi_j|``. On major loops (one
reversal in the memory) the outputs differ by at most ``2 E`` plus one cell's
``|S'_m - S_m| (r_{m+1} - r_m)`` (held on the shared real record by a test).

A model whose partial sums are all positive is returned unchanged, so the inverse stays exact
(round trip to 1e-9) wherever it was.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .rate import SCALED

__all__ = [
    "FLOOR_SHARE",
    "is_monotone",
    "monotone_error",
    "monotone_model",
    "monotone_weights",
]

FLOOR_SHARE = 0.25  # the projected slopes' floor, a share of the median partial sum


def _check(weights, radii) -> tuple[np.ndarray, np.ndarray]:
    w, r = np.asarray(weights, float), np.asarray(radii, float)
    if w.ndim != 1 or w.size == 0 or w.shape != r.shape or not np.all(np.isfinite(w)):
        raise ValueError(f"weights: expected {r.size} finite values like radii, got shape "
                         f"{w.shape}")
    if np.any(r < 0) or np.any(np.diff(r) < 0):
        raise ValueError("radii: expected non-negative, ascending values")
    return w, r


def is_monotone(weights) -> bool:
    """True when every partial sum ``w_1 + ... + w_m`` is positive (every branch rises).

    Parameters
    ----------
    weights : array_like
        Play weights, in the order of ascending radii.

    Returns
    -------
    bool

    Examples
    --------
    >>> is_monotone([1.0, -0.5, 0.2]), is_monotone([1.0, -1.5, 2.0])
    (True, False)
    """
    return bool(np.all(np.cumsum(np.asarray(weights, float)) > 0))


def monotone_weights(weights, radii, *, floor_share: float = FLOOR_SHARE) -> np.ndarray:
    """Weights of the monotone PI model nearest in branch shape (module docstring).

    Parameters
    ----------
    weights : array_like
        Play weights ``w_i`` [output / input units], signed.
    radii : array_like
        Play radii ``r_i`` [input units], ascending (plays of equal radii are merged into
        the last of them).
    floor_share : float
        The projected partial sums are at least ``floor_share`` times the median partial sum.

    Returns
    -------
    numpy.ndarray
        ``weights`` itself (a copy) when :func:`is_monotone`; else the weights whose partial
        sums are all at least the floor and whose branch curve is the closest such curve in
        the maximum norm.

    Raises
    ------
    ValueError
        Lengths differ, radii not ascending, ``floor_share`` not in (0, 1], or a
        median partial sum that is not positive (no monotone model is near).

    Examples
    --------
    >>> w = monotone_weights([-0.1, 1.1, 0.0, 0.0], [0.0, 1.0, 2.0, 3.0])
    >>> is_monotone(w), round(float(np.sum(w)), 6)  # monotone; the last slope is kept
    (True, 1.0)
    >>> monotone_weights([1.0, 0.5], [0.0, 1.0]).tolist()  # monotone already: unchanged
    [1.0, 0.5]
    """
    w, r = _check(weights, radii)
    if not 0 < floor_share <= 1:
        raise ValueError(f"floor_share: expected a value in (0, 1], got {floor_share!r}")
    if is_monotone(w):
        return w.copy()
    last = np.append(np.diff(r) > 0, True)  # plays of equal radii act as one: the last holds it
    if not np.all(last):
        out = np.zeros_like(w)
        out[last] = monotone_weights(np.add.reduceat(w, np.flatnonzero(np.diff(
            r, prepend=-1.0) > 0)), r[last], floor_share=floor_share)
        return out
    S = np.cumsum(w)
    f = floor_share * float(np.median(S))
    if not f > 0:
        raise ValueError(f"weights: the median partial sum is {float(np.median(S))!r}; no "
                         "monotone model is near")
    x = np.concatenate(([0.0], np.cumsum(np.diff(r))))  # r_j - r_1 at the nodes
    phi = np.concatenate(([0.0], np.cumsum(S[:-1] * np.diff(r))))
    g = phi - f * x
    h = (np.maximum.accumulate(g) + np.minimum.accumulate(g[::-1])[::-1]) / 2
    phi_new = np.maximum(h, 0.0) + f * x
    S_new = np.append(np.diff(phi_new) / np.diff(r), max(S[-1], f))
    return np.diff(S_new, prepend=0.0)


def monotone_error(weights, projected, radii) -> float:
    """Largest distance ``max_j |Phi'_j - Phi_j|`` of two models' branch curves.

    Parameters
    ----------
    weights, projected : array_like
        Two weight vectors on the same radii (the model and :func:`monotone_weights`).
    radii : array_like
        Play radii [input units].

    Returns
    -------
    float
        [output units]; the forward outputs on a memory of ``c`` pieces differ by at most
        about ``2 c`` times this (module docstring).

    Examples
    --------
    >>> r = [0.0, 1.0, 2.0, 3.0]
    >>> w = [-0.1, 1.1, 0.0, 0.0]
    >>> round(monotone_error(w, monotone_weights(w, r), r), 3)
    0.35
    """
    w, r = _check(weights, radii)
    p, _ = _check(projected, radii)
    d = np.cumsum(np.cumsum(p - w)[:-1] * np.diff(r))
    return float(np.max(np.abs(d))) if d.size else 0.0


def monotone_model(model):
    """The model with its hysteresis weights made monotone, where that makes it invertible.

    Parameters
    ----------
    model : DiagnosedModel
        A diagnosis' model (the inverse passes its static part: no dynamics, no delay).

    Returns
    -------
    DiagnosedModel
        A copy with :func:`monotone_weights` of its weights when the model inverts as a plain
        PI (no creep, asymmetry or rate; drift is not inverted), or as the PI of plays whose
        radii scale with the rate (the rate's ``"scaled"`` family, :mod:`.rate`: one factor
        for every radius on a sample, so the radii keep their order and a sample's slope is
        again a partial sum of ``w``), and the weights fold; ``model`` itself otherwise. With
        creep, asymmetry or a first-order rate family the slope of a sample's map is not a
        partial sum of the weights (for example ``S(w) - G S(w0)`` with creep, or the rate
        term's share of the reference weights ``w0``), so the projection would not make it
        monotone and would change terms the effect fitted; those models are inverted as they
        are.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0, 1.0, 2.0], [-0.1, 1.1, 0.0], 0.0, dt=1e-3)
    >>> is_monotone(monotone_model(m).weights)
    True
    """
    if set(model.effects) & {"creep", "asymmetry"} or is_monotone(model.weights) or (
            "rate" in model.effects and model.params.get("rate_family") != SCALED):
        return model
    return replace(model, weights=monotone_weights(model.weights, model.radii))
