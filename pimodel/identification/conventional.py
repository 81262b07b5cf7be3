"""The conventional baseline: radii preset on a grid, weights by bounded least squares.

Radii ``r_i = (i - 1) / (n - 1) * span`` (``r_1 = 0``, so the model is invertible); weights
``p >= 0`` (``p_1 >= 1e-9`` times the slope scale, keeping the inverse defined) and an output
offset minimise ``sum_k (sum_i p_i z_i[k] + c - y[k])^2`` with the play outputs ``z_i[k]`` of the
preset radii started from zero state (``scipy.optimize.lsq_linear``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from ..checks import as_signal, integer_in
from ..operators.pi import PIOperator

__all__ = [
    "ConventionalFit",
    "fit_conventional",
]


@dataclass
class ConventionalFit:
    """Result of :func:`fit_conventional`.

    The model is ``y[k] = operator.simulate(v)[k] + offset``.

    Parameters
    ----------
    operator : PIOperator
        The fitted operator (plays whose weight came out 0 are dropped, the first one kept).
    offset : float
        Output offset (output unit).
    rms : float
        RMS of the fit residual on the record (output unit).
    span : float
        The largest preset radius (input unit).

    Examples
    --------
    >>> from pimodel import fit_conventional
    >>> v = np.sin(np.linspace(0, 4 * np.pi, 2000))
    >>> fit = fit_conventional(v, 2 * v + 1, 3)
    >>> round(fit.offset, 6), fit.operator.n
    (1.0, 1)
    """

    operator: PIOperator
    offset: float
    rms: float
    span: float


def fit_conventional(v, y, n_plays: int, *, span: float | None = None) -> ConventionalFit:
    """Conventional PI fit: weights for ``n_plays`` preset radii spread over ``[0, span]``.

    ``y`` is modelled as ``PI[v] + offset`` with radii ``r_i = (i - 1) / (n - 1) * span``
    (module docstring); the weights are bounded least squares, ``p_1 > 0``, ``p_i >= 0``.

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples (input unit).
    y : array_like of float, shape (N,)
        Measured output samples (output unit).
    n_plays : int
        Number of preset plays, ``>= 1``.
    span : float, optional
        Largest radius (input unit). Default: half the input range, ``(max v - min v) / 2``,
        the largest radius the record can still excite.

    Returns
    -------
    ConventionalFit
        The operator, offset, fit RMS and span.

    Raises
    ------
    ValueError
        If ``v`` or ``y`` is not a finite signal of at least 2 samples, their lengths differ,
        ``n_plays < 1``, or ``span`` is not ``> 0`` (e.g. a constant input).

    Examples
    --------
    >>> from pimodel import PIOperator, fit_conventional
    >>> v = 2 * np.sin(np.linspace(0, 6 * np.pi, 3000))
    >>> y = PIOperator([1.0, 0.5, 0.25], [0.0, 0.5, 1.0]).simulate(v)
    >>> fit = fit_conventional(v, y, 3, span=1.0)   # preset radii 0, 0.5, 1: the true ones
    >>> fit.operator.weights.round(6), round(fit.rms, 6)
    (array([1.  , 0.5 , 0.25]), 0.0)
    """
    v = as_signal(v, "v", min_length=2)
    y = as_signal(y, "y", min_length=2)
    if v.size != y.size:
        raise ValueError(f"v and y: expected equal lengths, got {v.size} and {y.size}")
    n = integer_in(n_plays, "n_plays", 1)
    span = float(np.ptp(v)) / 2 if span is None else float(span)
    if not np.isfinite(span) or span <= 0:
        raise ValueError(f"span: expected a radius span > 0 (input units), got {span!r}; "
                         "is the input constant?")
    radii = np.linspace(0.0, span, n) if n > 1 else np.zeros(1)
    plays = PIOperator(np.ones(n), radii).play_outputs(v)
    A = np.column_stack((plays, np.ones(v.size)))
    scale = float(np.ptp(y) / max(np.ptp(v), 1e-300))
    lb = np.concatenate(([1e-9 * scale], np.zeros(n - 1), [-np.inf]))
    sol = lsq_linear(A, y, bounds=(lb, np.inf), method="bvls" if n < 40 else "trf")
    p = np.maximum(sol.x[:n], 0.0)
    keep = p > 0
    keep[0] = True
    op = PIOperator(p[keep], radii[keep])
    resid = A @ sol.x - y
    return ConventionalFit(op, float(sol.x[-1]), float(np.sqrt(np.mean(resid**2))), span)
