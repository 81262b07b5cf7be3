"""Excitation signals and measurement noise for studies and tests.

All generators return ``(t, v)`` with ``t[k] = k / fs`` [s] and the input ``v[k]`` in the input
unit (V for the piezo stage).
"""

from __future__ import annotations

import numpy as np

from .checks import positive_scalar

__all__ = [
    "add_noise_snr",
    "biased_staircase",
    "major_minor_loops",
    "sinusoid",
    "triangle",
]


def _time(fs: float, duration: float) -> np.ndarray:
    fs = positive_scalar(fs, "fs")
    duration = positive_scalar(duration, "duration")
    return np.arange(int(round(duration * fs))) / fs


def sinusoid(amplitude: float = 30.0, freq: float = 1.0, *, fs: float = 1000.0,
             duration: float = 10.0, offset: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Sinusoid ``v[k] = offset + amplitude sin(2 pi freq t[k])``.

    The paper's simulation input is ``30 sin(2 pi t)``, the default.

    Parameters
    ----------
    amplitude : float, optional
        Peak deviation from ``offset`` (input unit).
    freq : float, optional
        Frequency [Hz], ``> 0``.
    fs : float, optional
        Sampling rate [Hz], ``> 0``.
    duration : float, optional
        Record length [s], ``> 0``; ``round(duration * fs)`` samples.
    offset : float, optional
        Mean value (input unit).

    Returns
    -------
    t : numpy.ndarray of float, shape (N,)
        Sample times ``k / fs`` [s].
    v : numpy.ndarray of float, shape (N,)
        The input ``v[k]`` (input unit).

    Raises
    ------
    ValueError
        If ``fs``, ``duration`` or ``freq`` is not a finite number ``> 0``.

    Examples
    --------
    >>> from pimodel.signals import sinusoid
    >>> t, v = sinusoid(2.0, 1.0, fs=4.0, duration=1.0)
    >>> t, v.round(12)
    (array([0.  , 0.25, 0.5 , 0.75]), array([ 0.,  2.,  0., -2.]))
    """
    t = _time(fs, duration)
    return t, offset + amplitude * np.sin(2 * np.pi * positive_scalar(freq, "freq") * t)


def triangle(amplitude: float = 2.0, freq: float = 1.0, *, fs: float = 1000.0,
             duration: float = 3.0, offset: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric triangle wave that starts at ``offset`` rising, peaks ``offset +- amplitude``.

    Parameters
    ----------
    amplitude : float, optional
        Peak deviation from ``offset`` (input unit).
    freq : float, optional
        Frequency [Hz], ``> 0``.
    fs : float, optional
        Sampling rate [Hz], ``> 0``.
    duration : float, optional
        Record length [s], ``> 0``; ``round(duration * fs)`` samples.
    offset : float, optional
        Centre value (input unit).

    Returns
    -------
    t : numpy.ndarray of float, shape (N,)
        Sample times ``k / fs`` [s].
    v : numpy.ndarray of float, shape (N,)
        The input ``v[k]`` (input unit).

    Raises
    ------
    ValueError
        If ``fs``, ``duration`` or ``freq`` is not a finite number ``> 0``.

    Examples
    --------
    >>> from pimodel.signals import triangle
    >>> t, v = triangle(1.0, 1.0, fs=8.0, duration=1.0)
    >>> v.round(12)
    array([ 0. ,  0.5,  1. ,  0.5,  0. , -0.5, -1. , -0.5])
    """
    t = _time(fs, duration)
    phase = (t * positive_scalar(freq, "freq") + 0.25) % 1.0
    return t, offset + amplitude * (4 * np.abs(phase - 0.5) - 1) * -1


def biased_staircase(amplitude: float = 20.0, offset: float = 5.0, *, step: float = 1.0,
                     hold: float = 0.01, fs: float = 1000.0,
                     duration: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """Periodic stair-step between ``offset - amplitude`` and ``offset + amplitude``.

    Steps of ``step`` held ``hold`` seconds each, rising then falling (the paper's biased
    stair-step input).

    Parameters
    ----------
    amplitude : float, optional
        Half the distance between the lowest and the highest level (input unit).
    offset : float, optional
        Centre level (input unit).
    step : float, optional
        Height of one step (input unit), ``> 0``.
    hold : float, optional
        Time each level is held [s], ``> 0`` (at least one sample).
    fs : float, optional
        Sampling rate [Hz], ``> 0``.
    duration : float, optional
        Record length [s], ``> 0``; ``round(duration * fs)`` samples.

    Returns
    -------
    t : numpy.ndarray of float, shape (N,)
        Sample times ``k / fs`` [s].
    v : numpy.ndarray of float, shape (N,)
        The input ``v[k]`` (input unit).

    Raises
    ------
    ValueError
        If ``fs``, ``duration`` or ``step``, ``hold`` is not a finite number ``> 0``.

    Examples
    --------
    >>> from pimodel.signals import biased_staircase
    >>> t, v = biased_staircase(1.0, 0.0, step=1.0, hold=0.5, fs=2.0, duration=3.0)
    >>> v
    array([-1.,  0.,  1.,  0., -1.,  0.])
    """
    t = _time(fs, duration)
    step = positive_scalar(step, "step")
    m = max(1, int(round(2 * amplitude / step)))
    levels = offset - amplitude + step * np.concatenate((np.arange(m + 1), np.arange(m - 1, 0, -1)))
    per_level = max(1, int(round(positive_scalar(hold, "hold") * fs)))
    idx = (np.arange(t.size) // per_level) % levels.size
    return t, levels[idx]


def major_minor_loops(amplitude: float = 2.0, freq: float = 1.0, *, fs: float = 1000.0,
                      minor_fractions=(0.6, 0.3), periods_major: int = 2,
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Triangle major loops, then nested minor loops, at one input rate.

    The input starts at 0, makes ``periods_major`` major loops between ``+-amplitude``, then
    one loop between ``+-f amplitude`` for each ``f`` in ``minor_fractions``, and returns to 0;
    every segment moves at the major loop's rate ``4 amplitude freq`` per second.

    Parameters
    ----------
    amplitude : float, optional
        Peak of the major loops (input unit).
    freq : float, optional
        Frequency of the major loops [Hz], ``> 0``.
    fs : float, optional
        Sampling rate [Hz].
    minor_fractions : sequence of float, optional
        Reversal points of the minor loops, as fractions of ``amplitude``.
    periods_major : int, optional
        Number of major loops.

    Returns
    -------
    t : numpy.ndarray of float, shape (N,)
        Sample times ``k / fs`` [s].
    v : numpy.ndarray of float, shape (N,)
        The input (input unit).

    Raises
    ------
    ValueError
        If ``freq`` is not a finite number ``> 0``.

    Examples
    --------
    >>> from pimodel.signals import major_minor_loops
    >>> t, v = major_minor_loops(1.0, 1.0, fs=1000.0, minor_fractions=(0.5,))
    >>> float(v.max()), float(v.min()), t.size
    (1.0, -1.0, 2501)
    """
    rate = 4 * amplitude * positive_scalar(freq, "freq")  # input units per second
    pts = [0.0]
    for _ in range(periods_major):
        pts += [amplitude, -amplitude]
    for f in minor_fractions:
        pts += [f * amplitude, -f * amplitude]
    pts += [0.0]
    pieces = []
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        n = max(2, int(round(abs(b - a) / rate * fs)))
        pieces.append(np.linspace(a, b, n + 1)[1:])
    v = np.concatenate(([0.0], *pieces))
    return np.arange(v.size) / fs, v


def add_noise_snr(y: np.ndarray, snr_db: float, rng: np.random.Generator) -> np.ndarray:
    """``y`` plus white Gaussian noise at a given signal-to-noise ratio.

    The noise standard deviation is ``sigma = sqrt(var(y) / 10^(snr_db / 10))``, so that
    ``SNR = 10 log10(var(y) / sigma^2)`` dB over the whole record.

    Parameters
    ----------
    y : array_like of float
        The clean signal.
    snr_db : float
        Signal-to-noise ratio [dB].
    rng : numpy.random.Generator
        Source of the noise (seed it for reproducible records).

    Returns
    -------
    numpy.ndarray of float
        ``y`` plus noise, same shape as ``y``.

    See Also
    --------
    pimodel.stages.long_records.noisy_output_chunks : the same noise level for records made in
    chunks.

    Examples
    --------
    >>> from pimodel.signals import add_noise_snr
    >>> y = np.sin(np.linspace(0, 20, 100_000))
    >>> noisy = add_noise_snr(y, 20.0, np.random.default_rng(0))
    >>> bool(abs(10 * np.log10(np.var(y) / np.var(noisy - y)) - 20.0) < 0.1)
    True
    """
    sigma = np.sqrt(np.var(y) / 10 ** (snr_db / 10))
    return y + rng.normal(0.0, sigma, np.shape(y))
