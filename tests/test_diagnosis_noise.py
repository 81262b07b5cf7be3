"""Noise floor of the diagnosis: measured from repeated input periods when the input repeats,
else from a flexible local model; fast unmodelled dynamics are not counted as noise."""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from pimodel.diagnosis.noise import measure_noise_floor, robust_std
from pimodel.operators.pi import PIOperator

FS = 10_000.0


def _multisine(n: int, seed: int) -> np.ndarray:
    """Random-phase multisine, 50 Hz to 3 kHz, one period of ``n`` samples, peak 1."""
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, 1 / FS)
    spec = np.where((f >= 50) & (f <= 3000), np.exp(2j * np.pi * rng.uniform(size=f.size)), 0)
    x = np.fft.irfft(spec, n)
    return x / np.max(np.abs(x))


def _fast_mode(x: np.ndarray) -> np.ndarray:
    """A light 2.5 kHz mode (the unmodelled fast dynamics), unit static gain."""
    w, zeta, dt = 2 * np.pi * 2500, 0.05, 1 / FS
    r = np.exp(-zeta * w * dt)
    a = [1, -2 * r * np.cos(w * np.sqrt(1 - zeta**2) * dt), r * r]
    return lfilter([sum(a)], a, x)


def _stage(v):
    return PIOperator([4.0, 1.5, 1.0], [0.0, 0.2, 0.5]).simulate(v)


def test_repeated_periods_ignore_fast_dynamics():
    sigma = 0.004
    v = np.tile(_multisine(2000, 1), 3)
    h = _stage(v)
    y = _fast_mode(h) + np.random.default_rng(2).normal(0, sigma, v.size)
    nf = measure_noise_floor([(v, y)], [h])
    assert nf["method"] == "repeated periods"
    assert 0.8 * sigma < nf["value"] < 1.25 * sigma
    # the old estimate (first differences of the residual) takes the mode for noise
    assert robust_std(np.diff(y - h)) / np.sqrt(2) > 5 * sigma


def test_local_model_ignores_fast_dynamics():
    sigma = 0.004
    v = _multisine(8000, 3) * np.linspace(1.0, 0.6, 8000)  # no repeated period
    h = _stage(v)
    y = _fast_mode(h) + np.random.default_rng(4).normal(0, sigma, v.size)
    nf = measure_noise_floor([(v, y)], [h])
    assert nf["method"] == "local model"
    assert 0.8 * sigma < nf["value"] < 1.4 * sigma
    assert robust_std(np.diff(y - h)) / np.sqrt(2) > 5 * sigma


def test_local_model_ignores_slow_structure():
    # a smooth unmodelled term (a dead-zone-like static map of a slow input) is no noise
    sigma = 0.003
    t = np.arange(20_000) / FS
    v = np.sin(2 * np.pi * 3 * t) * np.exp(-t / 1.5)
    h = _stage(v)
    y = h + 0.3 * np.sign(v) * np.maximum(np.abs(v) - 0.3, 0) + np.random.default_rng(5).normal(
        0, sigma, v.size)
    nf = measure_noise_floor([(v, y)], [h])
    assert nf["method"] == "local model"
    assert 0.8 * sigma < nf["value"] < 1.3 * sigma
