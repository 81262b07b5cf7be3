"""Adaptive radius estimator: the paper's convergence cases, C vs NumPy reference, streaming vs
batch, projection, bad input. Accuracy is checked on the final estimate (noise-free) or on the
average of the estimate over the last half of the record (noisy cases), as stated per test."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pimodel import PIOperator
from pimodel.estimator import (
    RadiusEstimator,
    estimate_radii,
    project_ordered,
    run_tail_average,
    stream_tail_average,
)
from pimodel.estimator_reference import estimate_radii_reference, project_ordered_reference
from pimodel.long_records import noisy_output_chunks, record_length
from pimodel.signals import add_noise_snr, biased_staircase, sinusoid, triangle

P = np.array([0.3, 0.5, 0.8, 0.3, 0.2])
R = np.array([0.4, 1.0, 1.5, 2.0, 3.6])
WRONG = [1.0, 2.0, 3.0, 4.0, 5.0]
STAGE_P = np.array([6.3460, 1.6735, 1.1552, 0.4477])
STAGE_R = np.array([0.0, 0.1945, 0.4826, 0.5707])


def max_rel_error(est, truth):
    nz = truth > 0
    return float(np.max(np.abs(est[nz] / truth[nz] - 1)))


def test_paper_sinusoid_noise_free_within_1_percent():
    """v = 30 sin(2 pi t), gains 10, 1 kHz, 150 s, from a wrong start: final estimate."""
    t, v = sinusoid(30, 1, fs=1000, duration=150)
    y = PIOperator(P, R).simulate(v)
    res = estimate_radii(v, y, P, dt=1e-3, gains=10, initial_radii=WRONG)
    assert max_rel_error(res.radii, R) < 0.01
    # the estimate improves over time (not stuck at the start)
    assert max_rel_error(res.history[5000], R) > max_rel_error(res.radii, R)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_paper_sinusoid_snr20_within_5_percent(seed):
    """SNR 20 dB on y; 10 kHz for 2000 s (20 M samples), gain 1, guard 0.2 V, slope check off
    (a sample-to-sample slope is meaningless at this noise); the average of the estimate over
    the last half of the record is within 5 % of every radius."""
    t, v = sinusoid(30, 1, fs=10_000, duration=2000)
    y = add_noise_snr(PIOperator(P, R).simulate(v), 20, np.random.default_rng(seed))
    est = RadiusEstimator(P, dt=1e-4, gains=1.0, initial_radii=WRONG, guard=0.2, slope_window=0)
    _, avg = run_tail_average(est, v, y)
    assert max_rel_error(avg, R) < 0.05


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_paper_sinusoid_snr10_within_10_percent(seed):
    """SNR 10 dB on y; 10 kHz for 6000 s (60 M samples, made and consumed in 1 M chunks), gain
    0.3, guard 0.2 V, slope check off; the average of the estimate over the last half of the
    record is within 10 % of every radius. (Gain 1 over 2000 s missed: 6.6-20.3 %, from a
    noise-driven drift of r_2 and r_3 and an unfinished r_1 transient.)"""
    fs, duration = 10_000, 6000
    chunks = noisy_output_chunks(PIOperator(P, R), lambda t: 30 * np.sin(2 * np.pi * t), fs=fs,
                                 duration=duration, snr_db=10, rng=np.random.default_rng(seed))
    est = RadiusEstimator(P, dt=1 / fs, gains=0.3, initial_radii=WRONG, guard=0.2,
                          slope_window=0)
    _, avg = stream_tail_average(est, chunks, total=record_length(fs, duration))
    assert max_rel_error(avg, R) < 0.10


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_biased_staircase_snr20_within_5_percent(seed):
    """Periodic biased stair-step (-15..25, steps 0.5 held 5 ms), 1 kHz, 2000 s, SNR 20 dB."""
    t, v = biased_staircase(20, 5, step=0.5, hold=0.005, fs=1000, duration=2000)
    y = add_noise_snr(PIOperator(P, R).simulate(v), 20, np.random.default_rng(seed))
    est = RadiusEstimator(P, dt=1e-3, gains=1.0, initial_radii=WRONG, guard=0.2, slope_window=0)
    _, avg = run_tail_average(est, v, y)
    assert max_rel_error(avg, R) < 0.05


def test_biased_staircase_noise_free_within_1_percent():
    t, v = biased_staircase(20, 5, step=0.25, hold=0.005, fs=1000, duration=300)
    y = PIOperator(P, R).simulate(v)
    res = estimate_radii(v, y, P, dt=1e-3, gains=10, initial_radii=WRONG)
    assert max_rel_error(res.radii, R) < 0.01


def test_overestimated_radii_do_not_run_away():
    """A start far above the truth on a small travel (the regime read from rhat is wrong where
    the true play is already on its envelope): the slope check keeps the estimate converging;
    without it the estimate runs away above the input travel and freezes there."""
    t, v = triangle(1, 1, fs=1000, duration=60)
    y = PIOperator(STAGE_P, STAGE_R).simulate(v)
    kw = dict(dt=1e-3, gains=20, initial_radii=[0, 0.3, 0.4, 0.8], known_linear_play=True)
    res = estimate_radii(v, y, STAGE_P, **kw)
    assert max_rel_error(res.radii, STAGE_R) < 0.01
    bad = estimate_radii(v, y, STAGE_P, slope_window=0, **kw)
    assert max_rel_error(bad.radii, STAGE_R) > 0.5


def test_piezo_stage_triangle_with_known_linear_play():
    """The paper's stage, 1 Hz triangle of 2 V, gains 20, r_1 = 0 known: final estimate."""
    t, v = triangle(2, 1, fs=1000, duration=60)
    y = PIOperator(STAGE_P, STAGE_R).simulate(v)
    res = estimate_radii(v, y, STAGE_P, dt=1e-3, gains=20, initial_radii=[0, 0.5, 0.6, 0.9],
                         known_linear_play=True)
    assert res.radii[0] == 0.0
    assert max_rel_error(res.radii, STAGE_R) < 0.01
    assert np.all(res.history[:, 0] == 0.0)


@pytest.mark.parametrize("seed", [0, 1])
def test_c_core_equals_numpy_reference(seed):
    rng = np.random.default_rng(seed)
    t, v = sinusoid(30, 1, fs=1000, duration=4)
    v = v + np.where(t > 2, 3 * np.sin(2 * np.pi * 7 * t), 0)  # minor loops
    v[1500:1600] = v[1500]  # a hold
    y = PIOperator(P, R).simulate(v) + rng.normal(0, 1.0, v.size)
    kw = dict(dt=1e-3, gains=[10, 5, 10, 2, 10], initial_radii=WRONG, guard=0.1,
              max_step=0.02, anneal_time=1.5, threshold=0.01, slope_window=4, slope_tol=8.0)
    a = estimate_radii(v, y, P, **kw)
    hist, yhat, e, ed, used, final = estimate_radii_reference(v, y, P, **kw)
    np.testing.assert_allclose(a.history, hist, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.model_output, yhat, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.error, e, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.modified_error, ed, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(a.used, used)
    np.testing.assert_allclose(a.radii, final, rtol=0, atol=1e-12)
    assert 0.3 < used.mean() < 1.0  # some samples are skipped (hold, guard, minor loops)


def test_streaming_equals_batch_and_state_round_trip():
    t, v = sinusoid(30, 1, fs=500, duration=3)
    y = PIOperator(P, R).simulate(v) + np.random.default_rng(5).normal(0, 0.5, v.size)
    batch = estimate_radii(v, y, P, dt=2e-3, gains=10, initial_radii=WRONG)
    est = RadiusEstimator(P, dt=2e-3, gains=10, initial_radii=WRONG)
    rows = [est.step(a, b) for a, b in zip(v, y, strict=True)]
    np.testing.assert_allclose([r[1] for r in rows], batch.model_output, atol=1e-12)
    np.testing.assert_allclose([r[3] for r in rows], batch.modified_error, atol=1e-12)
    np.testing.assert_allclose(rows[-1][0], batch.radii, atol=1e-12)
    saved = est.state
    a = est.run(v[:300], y[:300]).radii
    est.state = saved
    b = est.run(v[:300], y[:300]).radii
    np.testing.assert_array_equal(a, b)
    est.reset()
    np.testing.assert_array_equal(est.radii, project_ordered(WRONG))


@given(st.lists(st.floats(-5, 5), min_size=1, max_size=12), st.booleans(), st.data())
def test_projection_is_ordered_and_matches_reference(x, fix_first, data):
    w = np.array(data.draw(st.lists(st.floats(0.1, 10), min_size=len(x), max_size=len(x))))
    out = project_ordered(x, w, fix_first=fix_first)
    assert np.all(out >= 0) and np.all(np.diff(out) >= -1e-12)
    if fix_first:
        assert out[0] == 0.0
    np.testing.assert_allclose(out, project_ordered_reference(np.array(x), w, fix_first),
                               atol=1e-12)
    # a feasible point is its own projection
    np.testing.assert_allclose(project_ordered(out, w, fix_first=fix_first), out, atol=1e-12)


def test_estimates_stay_ordered_under_heavy_noise():
    t, v = sinusoid(30, 1, fs=1000, duration=10)
    y = add_noise_snr(PIOperator(P, R).simulate(v), 0, np.random.default_rng(0))
    res = estimate_radii(v, y, P, dt=1e-3, gains=50, initial_radii=WRONG)
    assert np.all(res.history >= 0)
    assert np.all(np.diff(res.history, axis=1) >= 0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(v=[0, 1, np.nan], y=[0, 1, 2]), "v: sample 2 is nan"),
        (dict(v=[0, 1, 2], y=[0, 1]), "v and y: expected equal lengths, got 3 and 2"),
        (dict(v=[0], y=[0]), "v: expected at least 2 sample"),
        (dict(initial_radii=[0, 1]), "initial_radii: expected 5 values"),
        (dict(gains=-1.0), "gains: every gain must be >= 0"),
        (dict(gains=[1, 2]), "gains: expected a scalar or 5 values"),
        (dict(dt=0.0), "dt: expected a finite number > 0"),
        (dict(dt=-1e-3), "dt: expected a finite number > 0"),
        (dict(weights=[0.3, -0.5, 0.8, 0.3, 0.2]), "weights: every weight must be > 0"),
        (dict(guard=-1.0), "guard: expected a finite number >= 0"),
    ],
)
def test_bad_input(kwargs, match):
    args = dict(v=np.sin(np.arange(10.0)), y=np.sin(np.arange(10.0)), weights=P, dt=1e-3,
                gains=10.0, initial_radii=WRONG)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        estimate_radii(args.pop("v"), args.pop("y"), args.pop("weights"), **args)


def test_step_rejects_nan():
    est = RadiusEstimator(P, dt=1e-3, initial_radii=WRONG)
    with pytest.raises(ValueError, match="samples must be finite"):
        est.step(np.nan, 0.0)
    with pytest.raises(ValueError, match="state: expected 153 values"):
        est.state = np.zeros(3)
