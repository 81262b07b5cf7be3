"""The discrete filters the candidate effects are built of, at rest around their first input.

``lag`` (a creep lag: exact first-order discretisation), ``mode_coefficients`` and ``mode`` (the
unit-gain second-order mode, zero-order hold, on the C core's biquad: ``mode_rows``) and
``shift`` (a delay of whole or fractional samples). :mod:`.effects` builds its columns from
them, :mod:`.lti` its elements, :mod:`.model` and the C core's forms their predictions.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import cont2discrete, lfilter

from .._native import biquad_rows

__all__ = ["lag", "mode", "mode_coefficients", "mode_rows", "shift"]


def lag(x: np.ndarray, tau: float, dt: float, start: float | None = None) -> np.ndarray:
    """First-order lag (exact discretisation), at rest around x[0] (or ``start``); works
    column-wise.

    ``out[k] = a out[k-1] + (1 - a) x[k]`` with ``a = exp(-dt / tau)`` and ``out[-1] = x[0]``
    (``out[-1] = start`` when given: a lag whose memory before the first sample is known).

    Parameters
    ----------
    x : numpy.ndarray
        Signal ``x[k]``, 1-D or (N, m) (each column filtered).
    tau : float
        Time constant [s].
    dt : float
        Sample time [s].
    start : float, optional
        ``out[-1]``, the lag's state before the first sample (1-D ``x`` only); default
        ``x[0]``.

    Returns
    -------
    numpy.ndarray
        The lagged signal, shape of ``x``, units of ``x``.

    Examples
    --------
    >>> np.round(lag(np.array([0.0, 1.0, 1.0, 1.0]), 1e-3, 1e-3), 4).tolist()
    [0.0, 0.6321, 0.8647, 0.9502]
    >>> np.round(lag(np.zeros(3), 1e-3, 1e-3, start=1.0), 4).tolist()
    [0.3679, 0.1353, 0.0498]
    """
    a = np.exp(-dt / tau)
    if start is not None and x.ndim != 1:
        raise ValueError(f"start: given for a 1-D signal only, got x of shape {x.shape}")
    x0 = x[0] if start is None else start
    zi = np.atleast_1d(a * x0)[None, :] if x.ndim > 1 else [a * x0]
    out, _ = lfilter([1 - a], [1, -a], x, axis=0, zi=zi)
    return out


def mode_coefficients(fn: float, zeta: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """ZOH discretisation ``(b, a)`` of the unit-gain mode ``w^2 / (s^2 + 2 zeta w s + w^2)``.

    Underdamped modes use the closed form (the discrete step response equals the sampled
    continuous one); others fall back to :func:`scipy.signal.cont2discrete`.

    Parameters
    ----------
    fn : float
        Natural frequency [Hz].
    zeta : float
        Damping ratio [-].
    dt : float
        Sample time [s].

    Returns
    -------
    b, a : numpy.ndarray
        Numerator and denominator in powers of ``z^-1`` (``a[0] = 1``), for
        :func:`scipy.signal.lfilter`.

    Examples
    --------
    >>> b, a = mode_coefficients(100.0, 0.1, 1e-3)
    >>> round(float(b.sum() / a.sum()), 6)  # unit static gain
    1.0
    """
    w = 2 * np.pi * fn
    if zeta >= 1.0:
        num, den, _ = cont2discrete(([w * w], [1.0, 2 * zeta * w, w * w]), dt, method="zoh")
        b, a = np.ravel(num), np.ravel(den)
        return b / a[0], a / a[0]
    sigma, wd = zeta * w, w * np.sqrt(1 - zeta * zeta)

    def step(t):
        return 1 - np.exp(-sigma * t) * (np.cos(wd * t) + sigma / wd * np.sin(wd * t))

    a1, a2 = -2 * np.exp(-sigma * dt) * np.cos(wd * dt), np.exp(-2 * sigma * dt)
    s1, s2 = step(dt), step(2 * dt)
    return np.array([0.0, s1, s2 + a1 * s1 - s1]), np.array([1.0, a1, a2])


def mode(x: np.ndarray, fn: float, zeta: float, dt: float) -> np.ndarray:
    """Unit-gain second-order mode (zero-order-hold discretisation, as a DAC drives the stage),
    at rest around x[0]; works column-wise: ``out[k]`` depends on ``x[0..k-1]``.

    Parameters
    ----------
    x : numpy.ndarray
        Signal ``x[k]``, 1-D or (N, m) (each column filtered).
    fn : float
        Natural frequency [Hz].
    zeta : float
        Damping ratio [-].
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        The filtered signal, shape and units of ``x``.

    Examples
    --------
    >>> y = mode(np.r_[0.0, np.ones(300)], 50.0, 0.7, 1e-3)  # a unit step
    >>> round(float(y[1]), 6), round(float(y[-1]), 3)
    (0.0, 1.0)
    """
    if x.ndim == 1:
        return mode_rows(x[None, :], fn, zeta, dt)[0]
    return mode_rows(np.ascontiguousarray(x.T), fn, zeta, dt).T


def mode_rows(xt: np.ndarray, fn: float, zeta: float, dt: float) -> np.ndarray:
    """:func:`mode` applied to each row of ``xt`` (signals as rows, C-contiguous).

    Parameters
    ----------
    xt : numpy.ndarray
        Signals as rows, shape (m, N).
    fn : float
        Natural frequency [Hz].
    zeta : float
        Damping ratio [-].
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        The filtered rows, shape (m, N).

    Examples
    --------
    >>> x = np.r_[0.0, np.ones(20)]
    >>> bool(np.allclose(mode_rows(x[None, :], 50.0, 0.7, 1e-3)[0], mode(x, 50.0, 0.7, 1e-3)))
    True
    """
    # the C core's biquad (scipy.signal.lfilter's form and start, tests/test_diagnosis_filter)
    return biquad_rows(*mode_coefficients(fn, zeta, dt), xt)


def shift(x: np.ndarray, d: float, axis: int = 0) -> np.ndarray:
    """``x`` delayed by ``d >= 0`` samples (along ``axis``; held at ``x[0]`` before the start);
    a fractional part interpolates linearly between the two neighbouring whole delays.

    Parameters
    ----------
    x : numpy.ndarray
        Signal ``x[k]``, 1-D or (N, m) (rows are samples).
    d : float
        Delay [samples], ``d >= 0``.
    axis : int
        The time axis of ``x`` (0: rows are samples; -1: signals as rows, shape (m, N)).

    Returns
    -------
    numpy.ndarray
        ``x[k - d]``, shape of ``x``.

    Examples
    --------
    >>> shift(np.arange(4.0), 1).tolist(), shift(np.arange(4.0), 0.5).tolist()
    ([0.0, 0.0, 1.0, 2.0], [0.0, 0.5, 1.5, 2.5])
    >>> shift(np.arange(4.0)[None, :], 1, axis=-1).tolist()
    [[0.0, 0.0, 1.0, 2.0]]
    """
    n = int(np.floor(d))
    f = float(d) - n
    if f > 1e-12:
        lo, hi = shift(x, n, axis), shift(x, n + 1, axis)  # hi is new, lo too unless n == 0
        if hi.dtype.kind != "f":
            return (1.0 - f) * lo + f * hi
        # (1 - f) lo + f hi in place: the same products and sum as the expression (no three
        # more temporaries of x's size; a delay search shifts the play rows at every point)
        lo = (1.0 - f) * lo if lo is x else np.multiply(lo, 1.0 - f, out=lo)
        return np.add(lo, np.multiply(hi, f, out=hi), out=lo)
    if n == 0:
        return x
    out = np.empty_like(x)  # the layout of x (signals as rows stay rows)
    xt, ot = np.moveaxis(x, axis, 0), np.moveaxis(out, axis, 0)
    lead = min(n, xt.shape[0])
    ot[:lead] = xt[:1]
    ot[lead:] = xt[:xt.shape[0] - n]
    return out
