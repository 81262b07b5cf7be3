"""Chunked long records and the streaming tail average: equal to the whole-array versions."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel import PIOperator
from pimodel.identification.adaptive.radius_estimator import (
    RadiusEstimator,
    run_tail_average,
    stream_tail_average,
)
from pimodel.stages.long_records import noisy_output_chunks, record_length

P = np.array([0.3, 0.5, 0.8, 0.3, 0.2])
R = np.array([0.4, 1.0, 1.5, 2.0, 3.6])


def sine(t):
    return 30 * np.sin(2 * np.pi * t)


def test_chunks_equal_whole_record_simulation_and_noise_level():
    fs, duration = 1000, 20
    chunks = list(noisy_output_chunks(PIOperator(P, R), sine, fs=fs, duration=duration,
                                      snr_db=10, rng=np.random.default_rng(3), chunk=777))
    v = np.concatenate([c[0] for c in chunks])
    y = np.concatenate([c[1] for c in chunks])
    t = np.arange(record_length(fs, duration)) / fs
    clean = PIOperator(P, R).simulate(sine(t))
    np.testing.assert_array_equal(v, sine(t))
    noise = y - clean
    snr = 10 * np.log10(np.var(clean) / np.var(noise))
    assert abs(snr - 10) < 0.2  # 20k samples: the sample variance is within ~1 % of sigma^2
    assert abs(np.mean(noise)) < 4 * np.std(noise) / np.sqrt(noise.size)


def test_stream_tail_average_equals_run_tail_average():
    fs = 1000
    chunks = list(noisy_output_chunks(PIOperator(P, R), sine, fs=fs, duration=30, snr_db=20,
                                      rng=np.random.default_rng(0), chunk=4001))
    v = np.concatenate([c[0] for c in chunks])
    y = np.concatenate([c[1] for c in chunks])
    kw = dict(dt=1 / fs, gains=1.0, initial_radii=[1, 2, 3, 4, 5], guard=0.2, slope_window=0)
    final_a, avg_a = stream_tail_average(RadiusEstimator(P, **kw), chunks, total=v.size,
                                         tail=0.3)
    final_b, avg_b = run_tail_average(RadiusEstimator(P, **kw), v, y, tail=0.3, chunk=10**6)
    full = RadiusEstimator(P, **kw).run(v, y)
    np.testing.assert_array_equal(final_a, final_b)
    np.testing.assert_allclose(avg_a, avg_b, rtol=1e-12)
    np.testing.assert_allclose(avg_a, full.history[int(v.size * 0.7):].mean(axis=0), rtol=1e-12)


def test_single_sample_chunks_average_the_estimate_before_each_step():
    v = 30 * np.sin(2 * np.pi * np.arange(3000) / 1000)
    y = PIOperator(P, R).simulate(v)
    kw = dict(dt=1e-3, gains=10.0, initial_radii=[1, 2, 3, 4, 5])
    _, avg = stream_tail_average(RadiusEstimator(P, **kw), zip(v[:, None], y[:, None], strict=True),
                                 total=v.size, tail=0.5)
    full = RadiusEstimator(P, **kw).run(v, y)
    np.testing.assert_allclose(avg, full.history[1500:].mean(axis=0), rtol=1e-12)


@pytest.mark.parametrize("kwargs, match", [
    (dict(fs=0), "fs"),
    (dict(duration=-1), "duration"),
    (dict(fs=1, duration=1), "at least 2 samples"),
    (dict(chunk=1), "chunk"),
    (dict(snr_db=np.nan), "snr_db"),
])
def test_bad_record_arguments(kwargs, match):
    args = dict(fs=1000, duration=1, snr_db=10, rng=np.random.default_rng(0)) | kwargs
    with pytest.raises(ValueError, match=match):
        next(noisy_output_chunks(PIOperator(P, R), sine, **args))


def test_bad_input_function_and_chunk_totals():
    with pytest.raises(ValueError, match="input_at"):
        next(noisy_output_chunks(PIOperator(P, R), lambda t: 1.0, fs=100, duration=1,
                                 snr_db=10, rng=np.random.default_rng(0)))
    est = RadiusEstimator(P, dt=1e-3)
    v = np.linspace(0, 1, 10)
    with pytest.raises(ValueError, match="expected 20 samples in all, got 10"):
        stream_tail_average(est, [(v, v)], total=20)
    with pytest.raises(ValueError, match="more than total=5"):
        stream_tail_average(est, [(v, v)], total=5)
    with pytest.raises(ValueError, match="equal chunk lengths"):
        stream_tail_average(est, [(v, v[:5])], total=10)
    with pytest.raises(ValueError, match="tail"):
        stream_tail_average(est, [(v, v)], total=10, tail=0)
