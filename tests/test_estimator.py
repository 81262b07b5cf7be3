"""Adaptive radius estimator: the paper's convergence cases, C vs NumPy reference, streaming vs
batch, projection, bad input. Accuracy is checked on the final estimate (noise-free) or on the
average of the estimate over the last half of the record (noisy cases), as stated per test."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pimodel import PIOperator
from pimodel.identification.adaptive.radius_estimator import (
    RadiusEstimator,
    estimate_radii,
    project_ordered,
    run_tail_average,
    stream_tail_average,
)
from pimodel.identification.adaptive.settings import default_settings
from pimodel.reference.radius_estimator import estimate_radii_reference, project_ordered_reference
from pimodel.signals import add_noise_snr, biased_staircase, sinusoid, triangle
from pimodel.stages.long_records import noisy_output_chunks, record_length

P = np.array([0.3, 0.5, 0.8, 0.3, 0.2])
R = np.array([0.4, 1.0, 1.5, 2.0, 3.6])
WRONG = [1.0, 2.0, 3.0, 4.0, 5.0]
STAGE_P = np.array([6.3460, 1.6735, 1.1552, 0.4477])
STAGE_R = np.array([0.0, 0.1945, 0.4826, 0.5707])


def max_rel_error(est, truth):
    nz = truth > 0
    return float(np.max(np.abs(est[nz] / truth[nz] - 1)))


STARTS = {
    "below": [0.1, 0.2, 0.3, 0.4, 0.5],
    "zero": [0.0] * 5,
    "all equal 2": [2.0] * 5,
    "mixed": [0.2, 1.5, 1.6, 3.0, 3.2],
    "far above": [5.0, 10.0, 15.0, 20.0, 25.0],
    "0.8 x truth": list(0.8 * R),
    "(1..5)": WRONG,
}


@pytest.mark.parametrize("start", list(STARTS))
def test_noise_free_any_start_within_1_percent_with_defaults(start):
    """v = 30 sin(2 pi t), 1 kHz, 150 s, default settings (chosen from the record): the final
    estimate is within 1 % of every radius from every start, and the health report is clean."""
    t, v = sinusoid(30, 1, fs=1000, duration=150)
    y = PIOperator(P, R).simulate(v)
    res = estimate_radii(v, y, P, dt=1e-3, initial_radii=STARTS[start])
    assert max_rel_error(res.radii, R) < 0.01
    assert max_rel_error(res.radii_mean, R) < 0.05  # mean of the last half, transient included
    assert res.health.ok, res.health.messages
    assert res.settings["law"] == "data"


def test_paper_law_kept_and_health_flags_its_wrong_fixed_point():
    """law="paper" is the paper's regime-from-the-estimate rule: it converges from above the
    truth, and from below it stops at a wrong fixed point (plays 2-5 near 1.6, the issue's
    table); the health report says the model does not fit the data. The batch refinement
    (the default, ``polish=True``) then still finds the truth."""
    t, v = sinusoid(30, 1, fs=1000, duration=150)
    y = PIOperator(P, R).simulate(v)
    kw = dict(dt=1e-3, gains=10, law="paper", polish=False)
    good = estimate_radii(v, y, P, initial_radii=WRONG, **kw)
    assert max_rel_error(good.radii, R) < 0.01
    bad = estimate_radii(v, y, P, initial_radii=STARTS["below"], **kw)
    assert max_rel_error(bad.radii, R) > 0.2
    assert not bad.health.ok and not bad.health.fit_ok
    with pytest.warns(UserWarning, match="the model does not fit the data"):
        estimate_radii(v, y, P, initial_radii=STARTS["below"], warn=True, **kw)
    kw["polish"] = True
    polished = estimate_radii(v, y, P, initial_radii=STARTS["below"], **kw)
    assert max_rel_error(polished.online_radii, R) > 0.2
    assert max_rel_error(polished.radii, R) < 0.01 and polished.health.ok


def run_noisy_with_defaults(snr_db, seed, start, *, fs, duration):
    """The paper sinusoid at ``snr_db``, made and consumed in 1 M-sample chunks; settings from
    the first chunk (RadiusEstimator.for_record); returns (final, mean of the last half)."""
    chunks = noisy_output_chunks(PIOperator(P, R), lambda t: 30 * np.sin(2 * np.pi * t), fs=fs,
                                 duration=duration, snr_db=snr_db,
                                 rng=np.random.default_rng(seed))
    first = next(chunks)
    est = RadiusEstimator.for_record(*first, P, dt=1 / fs, initial_radii=STARTS[start])
    return stream_tail_average(est, itertools.chain([first], chunks),
                               total=record_length(fs, duration))


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("start", ["below", "zero", "mixed"])
def test_paper_sinusoid_snr20_within_5_percent_with_defaults(start):
    """SNR 20 dB, 10 kHz for 2000 s (20 M samples), default settings: the mean of the estimate
    over the last half of the record is within 5 % of every radius."""
    _, avg = run_noisy_with_defaults(20, 0, start, fs=10_000, duration=2000)
    assert max_rel_error(avg, R) < 0.05


@pytest.mark.slow
@pytest.mark.parametrize("start", ["below", "zero"])
def test_paper_sinusoid_snr10_within_10_percent_with_defaults(start):
    """SNR 10 dB, 10 kHz for 6000 s (60 M samples, chunked), default settings, from below the
    truth: the mean of the estimate over the last half is within 10 % of every radius."""
    _, avg = run_noisy_with_defaults(10, 0, start, fs=10_000, duration=6000)
    assert max_rel_error(avg, R) < 0.10


@pytest.mark.slow
def test_paper_sinusoid_snr10_within_10_percent_over_20000_s_for_the_worst_seed():
    """SNR 10 dB, 10 kHz for 20000 s (200 M samples, chunked), default settings, from below:
    seed 3, whose mean of the last half misses 10 % at 6000 s (13.9 %: r_1 wanders with a
    correlation time of several hundred seconds), is within 10 % (seeds 0-9: 1.3-5.2 %)."""
    _, avg = run_noisy_with_defaults(10, 3, "below", fs=10_000, duration=20_000)
    assert max_rel_error(avg, R) < 0.10


@pytest.mark.parametrize("start", ["below", "mixed"])
def test_biased_staircase_snr20_within_5_percent_with_defaults(start):
    """Periodic biased stair-step (-15..25, steps 0.5 held 5 ms), 1 kHz, 2000 s, SNR 20 dB,
    default settings: mean of the last half within 5 %."""
    t, v = biased_staircase(20, 5, step=0.5, hold=0.005, fs=1000, duration=2000)
    y = add_noise_snr(PIOperator(P, R).simulate(v), 20, np.random.default_rng(0))
    est = RadiusEstimator.for_record(v, y, P, dt=1e-3, initial_radii=STARTS[start])
    _, avg = run_tail_average(est, v, y)
    assert max_rel_error(avg, R) < 0.05


@pytest.mark.parametrize("start", ["below", "zero", "(1..5)"])
def test_biased_staircase_noise_free_within_1_percent(start):
    """Stair-step (steps 0.25 held 5 ms), 1 kHz, 300 s, default settings: final within 1 %."""
    t, v = biased_staircase(20, 5, step=0.25, hold=0.005, fs=1000, duration=300)
    y = PIOperator(P, R).simulate(v)
    res = estimate_radii(v, y, P, dt=1e-3, initial_radii=STARTS[start])
    assert max_rel_error(res.radii, R) < 0.01


def test_paper_law_overestimated_radii_do_not_run_away():
    """Paper law: a start far above the truth on a small travel (the regime read from rhat is
    wrong where the true play is already on its envelope): the slope check keeps it converging;
    without it the estimate runs away above the input travel and freezes there."""
    t, v = triangle(1, 1, fs=1000, duration=60)
    y = PIOperator(STAGE_P, STAGE_R).simulate(v)
    kw = dict(dt=1e-3, gains=20, initial_radii=[0, 0.3, 0.4, 0.8], linear_play=True,
              law="paper", polish=False)
    res = estimate_radii(v, y, STAGE_P, **kw)
    assert max_rel_error(res.radii, STAGE_R) < 0.01
    bad = estimate_radii(v, y, STAGE_P, slope_window=0, **kw)
    assert max_rel_error(bad.radii, STAGE_R) > 0.5


def test_piezo_stage_triangle_with_linear_play():
    """The paper's stage, 1 Hz triangle of 2 V, gains 20, r_1 = 0 known: final estimate."""
    t, v = triangle(2, 1, fs=1000, duration=60)
    y = PIOperator(STAGE_P, STAGE_R).simulate(v)
    res = estimate_radii(v, y, STAGE_P, dt=1e-3, gains=20, initial_radii=[0, 0.5, 0.6, 0.9],
                         linear_play=True)
    assert res.radii[0] == 0.0
    assert max_rel_error(res.radii, STAGE_R) < 0.01
    assert np.all(res.history[:, 0] == 0.0)


@pytest.mark.parametrize("law", ["data", "paper"])
@pytest.mark.parametrize("seed", [0, 1])
def test_c_core_equals_numpy_reference(seed, law):
    rng = np.random.default_rng(seed)
    t, v = sinusoid(30, 1, fs=1000, duration=4)
    v = v + np.where(t > 2, 3 * np.sin(2 * np.pi * 7 * t), 0)  # minor loops
    v[1500:1600] = v[1500]  # a hold
    y = PIOperator(P, R).simulate(v) + rng.normal(0, 1.0, v.size)
    kw = dict(dt=1e-3, gains=[10, 5, 10, 2, 10], initial_radii=WRONG, guard=0.1,
              max_step=0.02, anneal_time=1.5, threshold=0.01, slope_window=4, slope_tol=8.0,
              law=law)
    a = estimate_radii(v, y, P, polish=False, **kw)
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
    batch = RadiusEstimator(P, dt=2e-3, gains=10, initial_radii=WRONG).run(v, y)
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
        (dict(law="fast"), "law: expected one of"),
    ],
)
def test_bad_input(kwargs, match):
    args = dict(v=np.sin(np.arange(10.0)), y=np.sin(np.arange(10.0)), weights=P, dt=1e-3,
                gains=10.0, initial_radii=WRONG)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        estimate_radii(args.pop("v"), args.pop("y"), args.pop("weights"), **args)


def test_gains_beyond_the_stability_bound_warn():
    """gains=1e6 at dt=1e-3 is far above 2 / (dt |p|^2) = 1802: a warning names both."""
    t, v = sinusoid(30, 1, fs=1000, duration=3)
    y = PIOperator(P, R).simulate(v)
    with pytest.warns(UserWarning, match=r"gains: 1e\+06 exceeds the stability bound .* = 1802"):
        estimate_radii(v, y, P, dt=1e-3, gains=1e6)


def test_defaults_follow_the_noise_level():
    """Clean record: gain 20 / |p|^2, no guard; noisy: smaller gain, a guard, slope check off;
    the estimated noise level is within 10 % of the true one."""
    t, v = sinusoid(30, 1, fs=1000, duration=20)
    y = PIOperator(P, R).simulate(v)
    clean = default_settings(v, y, P, dt=1e-3)
    assert clean["gains"] == pytest.approx(20 / (P @ P))
    assert clean["guard"] == 0.0 and clean["threshold"] == 0.0
    noisy = default_settings(v, y + np.random.default_rng(0).normal(0, 2.0, y.size), P, dt=1e-3)
    assert noisy["noise_y"] == pytest.approx(2.0, rel=0.1)
    assert noisy["gains"] < clean["gains"] / 5
    assert noisy["guard"] > 0 and noisy["slope_window"] == 0


def test_health_flags_a_small_input():
    """An input range of 4 against 2 r_n = 7.2 (Lemma 2, Prop. 2): the health report says the
    record cannot excite all plays."""
    t, v = sinusoid(2, 1, fs=1000, duration=5)
    y = PIOperator(P, R).simulate(v)
    res = estimate_radii(v, y, P, dt=1e-3, initial_radii=WRONG)
    assert not res.health.ok
    assert not res.health.excitation_ok
    assert any("input range" in m for m in res.health.messages)


def test_step_rejects_nan():
    est = RadiusEstimator(P, dt=1e-3, initial_radii=WRONG)
    with pytest.raises(ValueError, match="samples must be finite"):
        est.step(np.nan, 0.0)
    with pytest.raises(ValueError, match="state: expected 677 values"):
        est.state = np.zeros(3)


def test_known_linear_play_is_a_deprecated_name_of_linear_play():
    with pytest.warns(DeprecationWarning, match="known_linear_play is deprecated"):
        est = RadiusEstimator([1.0, 0.5], dt=1e-3, initial_radii=[0.2, 0.3],
                              known_linear_play=True)
    assert est.linear_play and est.radii[0] == 0.0
    v = np.sin(np.linspace(0, 20, 2000))
    y = PIOperator([1.0, 0.5], [0.0, 0.3]).simulate(v)
    with pytest.warns(DeprecationWarning, match="known_linear_play is deprecated"):
        res = estimate_radii(v, y, [1.0, 0.5], dt=1e-3, known_linear_play=True)
    assert res.radii[0] == 0.0


@pytest.mark.parametrize("weights", [[0.0], [1.0, 0.0], [-1.0]])
def test_settings_from_the_record_reject_non_positive_weights(weights):
    """Found by the API fuzz: weights [0] reached the default-settings formula (a division by
    |p|^2) before the weights were checked."""
    v = np.sin(np.linspace(0, 20, 500))
    with pytest.raises(ValueError, match="weights: every weight must be > 0"):
        estimate_radii(v, v, weights, dt=1e-3, slope_window=2)
    with pytest.raises(ValueError, match="weights: every weight must be > 0"):
        default_settings(v, v, weights, dt=1e-3)


def test_settings_from_the_record_reject_weights_whose_norm_underflows():
    """Found by the API fuzz: weights [5e-324] give |p|^2 = 0 (a division by zero before)."""
    v = np.sin(np.linspace(0, 20, 500))
    with pytest.raises(ValueError, match="weights: \\|p\\|\\^2 = 0.0 is outside the float64"):
        estimate_radii(v, v, [5e-324], dt=1e-3, slope_window=2)
