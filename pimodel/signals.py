"""Excitation signals and measurement noise for studies and tests.

All generators return ``(t, v)`` with ``t[k] = k / fs`` [s] and the input ``v[k]`` in the input
unit (V for the piezo stage).
"""

from __future__ import annotations

import numpy as np

from .checks import positive_scalar


def _time(fs: float, duration: float) -> np.ndarray:
    fs = positive_scalar(fs, "fs")
    duration = positive_scalar(duration, "duration")
    return np.arange(int(round(duration * fs))) / fs


def sinusoid(amplitude: float = 30.0, freq: float = 1.0, *, fs: float = 1000.0,
             duration: float = 10.0, offset: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``v = offset + amplitude sin(2 pi freq t)`` (the paper's simulation: 30 sin(2 pi t))."""
    t = _time(fs, duration)
    return t, offset + amplitude * np.sin(2 * np.pi * positive_scalar(freq, "freq") * t)


def triangle(amplitude: float = 2.0, freq: float = 1.0, *, fs: float = 1000.0,
             duration: float = 3.0, offset: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric triangle starting at ``offset`` rising, peak ``offset +- amplitude``."""
    t = _time(fs, duration)
    phase = (t * positive_scalar(freq, "freq") + 0.25) % 1.0
    return t, offset + amplitude * (4 * np.abs(phase - 0.5) - 1) * -1


def biased_staircase(amplitude: float = 20.0, offset: float = 5.0, *, step: float = 1.0,
                     hold: float = 0.01, fs: float = 1000.0,
                     duration: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """Periodic stair-step between ``offset - amplitude`` and ``offset + amplitude``: steps of
    ``step`` held ``hold`` seconds each, rising then falling (a biased stair-step input)."""
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
    """Triangle major loops then nested minor loops: each minor loop reverses at the given
    fractions of the amplitude (``+-f amplitude``), at the same input rate as the major loop."""
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
    """``y`` plus white Gaussian noise at ``SNR = 10 log10(var(y) / var(noise))`` dB."""
    sigma = np.sqrt(np.var(y) / 10 ** (snr_db / 10))
    return y + rng.normal(0.0, sigma, np.shape(y))
