"""Settings of the radius estimator chosen from the record: noise level, input range, sampling.

:func:`default_settings` is what :func:`pimodel.estimate_radii` uses when ``gains``, ``guard``,
``threshold`` or ``slope_window`` are left at ``None``, so a noisy record needs no setting the
noise-free one would not use:

- noise level ``sigma`` of a signal: ``1.4826 * median |x[k+1] - 2 x[k] + x[k-1]| / sqrt(6)``
  (a second difference of white noise has variance ``6 sigma^2``; the signal's own second
  difference is negligible at the sampling rates the estimator needs, and the median ignores
  corners and steps);
- gains: ``min(G_CLEAN / |p|^2, G_NOISE * A / (sqrt(dt) * sigma_y * |p|), 0.5 / (dt |p|^2))``
  with the input range ``A``: the normalised rate ``gain * |p|^2`` is 20 /s on a clean record;
  with noise the gain falls as the noise-to-range ratio grows, so that the stationary spread
  of the constant-gain iterate, about ``sqrt(dt * gain / 2) * sigma_y``, stays a small part
  of ``A``, but only as ``1 / sigma_y`` (not ``1 / sigma_y^2``) so that the transient from a
  poor start still ends within the record lengths the paper uses (calibrated on the paper's
  case: gain 0.4 at 10 dB and 1.3 at 20 dB, 10 kHz); the last term keeps the discrete law far
  inside its stability bound ``dt * gain * |p|^2 < 2``;
- guard: 0 on a clean output, ``A / 300`` on a noisy one (``sigma_y > 1e-4 * range(y)``);
- threshold: ``3 sigma_v`` on a noisy input (``sigma_v > 1e-4 A``), else 0;
- slope_window (paper's law only): 8 on a clean output, 0 (off) on a noisy one.
"""

from __future__ import annotations

import warnings

import numpy as np

from ...checks import as_signal, as_vector, positive_scalar

__all__ = [
    "check_gains",
    "check_weights",
    "default_settings",
    "noise_level",
    "stability_bound",
]

G_CLEAN = 20.0  # normalised adaptation rate gain * |p|^2 on a clean record [1/s]
G_NOISE = 1.0e-3  # gain * sqrt(dt) * sigma_y * |p| / A on a noisy record
STEP_BOUND = 0.5  # dt * gain * |p|^2 never above this (stability needs < 2)


def noise_level(x) -> float:
    """Robust standard deviation of white noise on a sampled signal ``x[k]`` (same unit).

    Parameters
    ----------
    x : array_like
        The samples, at least 3.

    Returns
    -------
    float
        ``1.4826 * median |x[k+1] - 2 x[k] + x[k-1]| / sqrt(6)``.

    Examples
    --------
    >>> import numpy as np
    >>> round(noise_level(np.random.default_rng(0).normal(0, 2.0, 100_000)), 1)
    2.0
    """
    s = as_signal(x, "x", min_length=3)
    return float(1.4826 * np.median(np.abs(np.diff(s, 2))) / np.sqrt(6.0))


def check_weights(weights) -> np.ndarray:
    """The play weights as the radius estimator accepts them: a finite vector, every ``p_j > 0``.

    Parameters
    ----------
    weights : array_like
        Play weights p_j (output per input unit).

    Returns
    -------
    numpy.ndarray of float64, shape (n,)
        The weights.

    Raises
    ------
    ValueError
        Naming ``weights``, if they are not a finite non-empty vector or a weight is not > 0.

    Examples
    --------
    >>> check_weights([0.5, 1.0])
    array([0.5, 1. ])
    >>> check_weights([0.5, 0.0])
    Traceback (most recent call last):
    ...
    ValueError: weights: every weight must be > 0, got [0.5, 0.0]
    """
    p = as_vector(weights, "weights")
    if np.any(p <= 0):
        raise ValueError(f"weights: every weight must be > 0, got {p.tolist()}")
    return p


def _norm2(weights) -> float:
    """``|p|^2`` of positive weights; ValueError naming ``weights`` when a weight is not > 0
    (:func:`check_weights`) or ``|p|^2`` leaves the float64 range."""
    p = check_weights(weights)
    pp = float(p @ p)
    if not 0.0 < pp < np.inf:
        raise ValueError(f"weights: |p|^2 = {pp!r} is outside the float64 range; expected "
                         "weights between about 1e-150 and 1e150 (rescale the output units)")
    return pp


def stability_bound(weights, dt: float) -> float:
    """Largest stable gain ``2 / (dt * |p|^2)`` of the discrete law (a gain per play above it
    makes ``rhat`` diverge: each step overshoots the fixed point).

    Parameters
    ----------
    weights : array_like
        Play weights p_j > 0.
    dt : float
        Sample time [s].

    Returns
    -------
    float
        The bound [input unit^2 / (output unit^2 s)].

    Examples
    --------
    >>> round(stability_bound([0.3, 0.5, 0.8, 0.3, 0.2], 1e-3), 1)
    1801.8
    """
    return 2.0 / (positive_scalar(dt, "dt") * _norm2(weights))


def check_gains(gains, weights, dt: float) -> None:
    """Warn (``UserWarning``) when a gain exceeds :func:`stability_bound`.

    Parameters
    ----------
    gains : float or array_like
        The estimator's gains (scalar or per play).
    weights : array_like
        Play weights p_j > 0.
    dt : float
        Sample time [s].

    Returns
    -------
    None
        Nothing; a gain above ``2 / (dt |p|^2)`` gives a ``UserWarning`` naming it and the bound.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     check_gains(1e6, [0.3, 0.5, 0.8, 0.3, 0.2], 1e-3)
    >>> "exceeds the stability bound" in str(caught[0].message)
    True
    """
    g = np.atleast_1d(np.asarray(gains, float))
    bound = stability_bound(weights, dt)
    if np.any(g > bound):
        warnings.warn(f"gains: {float(g.max()):.4g} exceeds the stability bound 2 / (dt |p|^2) "
                      f"= {bound:.4g} (dt = {dt:g}); the estimate will diverge. Use gains below "
                      f"{bound:.4g}, e.g. gains=None for the record's default.", UserWarning,
                      stacklevel=3)


def default_settings(v, y, weights, *, dt: float) -> dict:
    """Estimator settings from the record ``(v[k], y[k])`` (see the module docstring).

    Parameters
    ----------
    v, y : array_like
        Input and measured output, sampled every ``dt``.
    weights : array_like
        Play weights p_j > 0.
    dt : float
        Sample time [s].

    Returns
    -------
    dict
        ``gains``, ``guard``, ``threshold``, ``slope_window`` (keywords of
        :class:`pimodel.RadiusEstimator`) and the estimated ``noise_y``, ``noise_v``.

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel import PIOperator
    >>> v = 30 * np.sin(2 * np.pi * np.arange(0, 10, 1e-3))
    >>> p = [0.3, 0.5, 0.8, 0.3, 0.2]
    >>> y = PIOperator(p, [0.4, 1, 1.5, 2, 3.6]).simulate(v)
    >>> s = default_settings(v, y, p, dt=1e-3)
    >>> round(s["gains"], 2), s["guard"]
    (18.02, 0.0)
    """
    x = as_signal(v, "v", min_length=3)
    m = as_signal(y, "y", min_length=3)
    pp = _norm2(weights)
    dt = positive_scalar(dt, "dt")
    span_v = float(np.ptp(x))
    sig_y, sig_v = noise_level(m), noise_level(x)
    noisy = sig_y > 1e-4 * float(np.ptp(m))
    if not dt * pp > 0.0:  # the step bound's dt |p|^2 underflows
        raise ValueError(f"dt: dt |p|^2 = {dt!r} * {pp!r} underflows to 0; expected a sample "
                         "time and weights whose product float64 holds (rescale the time or "
                         "output units)")
    gains = min(G_CLEAN / pp, STEP_BOUND / (dt * pp))
    if noisy:
        gains = min(gains, float(G_NOISE * span_v / (np.sqrt(dt) * sig_y * np.sqrt(pp))))
    return {"gains": gains, "guard": span_v / 300 if noisy else 0.0,
            "threshold": 3.0 * sig_v if sig_v > 1e-4 * span_v else 0.0,
            "slope_window": 0 if noisy else 8, "noise_y": sig_y, "noise_v": sig_v}
