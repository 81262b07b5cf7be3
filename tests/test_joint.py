"""Joint online estimation of weights and radii (beyond the paper): the paper's convergence
cases with the weights unknown too, from a wrong start, seeds fixed. Accuracy is checked on the
final estimate (the law is a cumulative least-squares fit, so its final value already averages
the whole record). Also: streaming equals batch whatever the chunking, the reversal scanner,
and bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from pimodel import JointEstimator, PIOperator, estimate_jointly, identify, stream_jointly
from pimodel.identification.branches import ReversalScanner, find_reversals
from pimodel.identification.play_reduction import reduce_plays
from pimodel.signals import biased_staircase, sinusoid
from pimodel.stages.long_records import noisy_output_chunks

P = np.array([0.3, 0.5, 0.8, 0.3, 0.2])
R = np.array([0.4, 1.0, 1.5, 2.0, 3.6])
WRONG_P = np.ones(5)
WRONG_R = [1.0, 2.0, 3.0, 4.0, 5.0]


def max_rel_error(est, truth):
    return float(np.max(np.abs(np.asarray(est) / truth - 1)))


def sine(t):
    """``30 sin(2 pi t)``, computed in place (the same values as ``30 * np.sin(2 * np.pi * t)``
    without two temporary arrays: the long records below call it on 2.6 G samples)."""
    out = t * (2 * np.pi)
    np.sin(out, out=out)
    out *= 30
    return out


def staircase_at(step: float, fs: float):
    """The biased stair-step of :func:`pimodel.signals.biased_staircase` (-15..25, held 5 ms)
    as a function of time, for chunked records."""
    _, one = biased_staircase(20, 5, step=step, hold=0.005, fs=fs, duration=2 * 40 / step * 0.005)
    return lambda t: one[np.round(t * fs).astype(np.int64) % one.size]


def joint_run(input_at, *, fs, duration, snr_db, seed, refit_every):
    est = JointEstimator(5, initial_weights=WRONG_P, initial_radii=WRONG_R,
                         refit_every=refit_every)
    chunks = noisy_output_chunks(PIOperator(P, R), input_at, fs=fs, duration=duration,
                                 snr_db=snr_db, rng=np.random.default_rng(seed))
    return stream_jointly(est, chunks)


def test_sinusoid_noise_free_within_1_percent():
    """v = 30 sin(2 pi t), 1 kHz, 20 s: weights and radii within 1 % (final estimate), and the
    estimate reported before the first update is the wrong start."""
    _, v = sinusoid(30, 1, fs=1000, duration=20)
    y = PIOperator(P, R).simulate(v)
    est = JointEstimator(5, initial_weights=WRONG_P, initial_radii=WRONG_R, refit_every=10)
    w0, r0 = est.step(v[0], y[0])
    assert np.array_equal(w0, WRONG_P) and np.array_equal(r0, WRONG_R)
    est.run(v[1:], y[1:])
    res = est.finish()
    assert max_rel_error(res.weights, P) < 0.01
    assert max_rel_error(res.radii, R) < 0.01
    assert max_rel_error(res.radius_history[0], R) < 0.01  # the first update is already there
    assert res.fit_rms < 1e-3 * np.ptp(y)


def test_staircase_noise_free_within_1_percent():
    _, v = biased_staircase(20, 5, step=0.25, hold=0.005, fs=1000, duration=100)
    y = PIOperator(P, R).simulate(v)
    res = estimate_jointly(v, y, 5, initial_weights=WRONG_P, initial_radii=WRONG_R)
    assert max_rel_error(res.weights, P) < 0.01
    assert max_rel_error(res.radii, R) < 0.01


def test_linear_play_known():
    """With a linear play (r_1 = 0) the estimate keeps r_1 = 0 and finds the rest."""
    p, r = np.array([1.0, 0.6, 0.4]), np.array([0.0, 0.5, 1.2])
    _, v = sinusoid(5, 1, fs=1000, duration=10)
    y = PIOperator(p, r).simulate(v)
    res = estimate_jointly(v, y, 3, linear_play=True)
    assert res.radii[0] == 0.0
    assert np.allclose(res.weights, p, rtol=0.01) and np.allclose(res.radii, r, rtol=0.01)


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_sinusoid_snr20_weights_and_radii_within_5_percent(seed):
    """SNR 20 dB on y, 10 kHz for 30000 s (300 M samples, made and consumed in 1 M chunks):
    every weight and every radius within 5 % (the radii are within 5 % from about 40 M samples
    on; the weights, slope differences, need the longer record)."""
    res = joint_run(sine, fs=10_000, duration=30_000, snr_db=20, seed=seed, refit_every=10_000)
    assert max_rel_error(res.radii, R) < 0.05
    assert max_rel_error(res.weights, P) < 0.05
    assert res.update_index.size >= 5
    assert max_rel_error(res.radius_history[0], R) > 0.0  # an estimate, not the truth


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_sinusoid_snr10_radii_within_10_percent(seed):
    """SNR 10 dB on y, 10 kHz for 20000 s (200 M samples in 1 M chunks)."""
    res = joint_run(sine, fs=10_000, duration=20_000, snr_db=10, seed=seed, refit_every=8000)
    assert max_rel_error(res.radii, R) < 0.10


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_sinusoid_snr10_weights_within_10_percent_on_a_long_record():
    """SNR 10 dB, 10 kHz for 100000 s (1 G samples in 1 M chunks), seed 0: every weight and
    every radius within 10 % (seeds 1 and 2 are in the study ``joint_estimation``)."""
    res = joint_run(sine, fs=10_000, duration=100_000, snr_db=10, seed=0, refit_every=20_000)
    assert max_rel_error(res.radii, R) < 0.10
    assert max_rel_error(res.weights, P) < 0.10


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_biased_staircase_snr20_within_5_percent(seed):
    """Biased stair-step (-15..25, steps 0.25 held 5 ms), 1 kHz, 40000 s (40 M samples in 1 M
    chunks), SNR 20 dB."""
    res = joint_run(staircase_at(0.25, 1000), fs=1000, duration=40_000, snr_db=20, seed=seed,
                    refit_every=10_000)
    assert max_rel_error(res.radii, R) < 0.05
    assert max_rel_error(res.weights, P) < 0.05


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_streaming_equals_batch_whatever_the_chunks():
    _, v = sinusoid(30, 1, fs=1000, duration=12)
    y = PIOperator(P, R).simulate(v) + np.random.default_rng(3).normal(0, 0.5, v.size)
    batch = estimate_jointly(v, y, 5, refit_every=4)
    cuts = np.sort(np.random.default_rng(4).choice(np.arange(1, v.size), 40, replace=False))
    chunked = stream_jointly(JointEstimator(5, refit_every=4),
                             zip(np.split(v, cuts), np.split(y, cuts), strict=True))
    est = JointEstimator(5, refit_every=4)
    for a, b in zip(v[:3000], y[:3000], strict=True):
        est.step(a, b)
    est.run(v[3000:], y[3000:])
    stepped = est.finish()
    for other in (chunked, stepped):
        assert np.array_equal(other.update_index, batch.update_index)
        assert np.allclose(other.weight_history, batch.weight_history, rtol=1e-9, atol=1e-12)
        assert np.allclose(other.radius_history, batch.radius_history, rtol=1e-9, atol=1e-12)
    assert batch.update_index.size == 23 // 4 + 1  # 22-23 usable branches, plus finish()


def test_estimate_is_causal():
    """The estimate in force at sample k uses samples up to k only: the update indices are
    declaration samples, and cutting the record just after one gives the same estimate."""
    _, v = sinusoid(30, 1, fs=1000, duration=8)
    y = PIOperator(P, R).simulate(v)
    full = estimate_jointly(v, y, 5, refit_every=3)
    k = int(full.update_index[1])
    est = JointEstimator(5, refit_every=3)
    part = est.run(v[:k + 1], y[:k + 1])
    assert part.update_index.size == 2
    assert np.allclose(part.radius_history[-1], full.radius_history[1])


def test_reversal_scanner_matches_find_reversals_in_chunks():
    rng = np.random.default_rng(7)
    v = np.cumsum(rng.normal(size=5000))
    whole = find_reversals(v, 2.0)
    sc = ReversalScanner(2.0)
    parts = [sc.scan(c) for c in np.array_split(v, 17)]
    assert np.concatenate(parts).tolist() == list(whole)
    ext, decl = ReversalScanner(2.0).scan_with_declaration(v)
    assert np.all(decl > ext)
    assert np.all(np.abs(v[decl] - v[ext]) > 2.0)


def test_identify_joint_on_a_synthetic_record():
    _, v = sinusoid(30, 1, fs=1000, duration=20)
    y = PIOperator(P, R).simulate(v) + 2.0
    idn = identify(v, y, dt=1e-3, n_plays=5, method="joint")
    assert idn.method == "joint"
    assert np.allclose(idn.radii, R, rtol=0.01) and np.allclose(idn.weights, P, rtol=0.01)
    assert abs(idn.offset - 2.0) < 0.05
    assert idn.to_json()["settings"]["updates"] >= 1


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"n_plays": 0}, "n_plays"),
    ({"n_plays": 2.5}, "n_plays"),
    ({"n_plays": "five"}, "n_plays"),
    ({"n_plays": None}, "n_plays"),
    ({"n_plays": 3, "refit_every": float("nan")}, "refit_every"),
    ({"n_plays": 3, "forgetting": "1"}, "forgetting"),
    ({"n_plays": 3, "bins": 5}, "bins"),
    ({"n_plays": 3, "refit_every": 0}, "refit_every"),
    ({"n_plays": 3, "forgetting": 0.0}, "forgetting"),
    ({"n_plays": 3, "forgetting": 1.5}, "forgetting"),
    ({"n_plays": 3, "initial_weights": [1, 2]}, "initial_weights"),
    ({"n_plays": 3, "initial_radii": [0, 1, -1]}, "initial_radii"),
    ({"n_plays": 3, "travel_range": -1.0}, "travel_range"),
    ({"n_plays": 3, "threshold": -0.1}, "threshold"),
])
def test_bad_settings_name_the_argument(kwargs, match):
    with pytest.raises(ValueError, match=match):
        JointEstimator(**kwargs)


def test_bad_samples_name_the_argument():
    est = JointEstimator(3)
    with pytest.raises(ValueError, match="v and y"):
        est.run([0.0, 1.0, 2.0], [0.0, 1.0])
    with pytest.raises(ValueError, match="y"):
        est.run([0.0, 1.0], [0.0, np.nan])
    with pytest.raises(ValueError, match="v"):
        est.step(np.inf, 0.0)


def test_no_reversal_gives_no_update_and_says_so():
    v = np.linspace(0, 10, 1000)
    with pytest.warns(RuntimeWarning, match="no usable branch"):
        res = estimate_jointly(v, 2 * v, 3, initial_weights=[1, 1, 1], initial_radii=[0, 1, 2])
    assert res.update_index.size == 0 and res.branches_used == 0
    assert np.array_equal(res.radii, [0, 1, 2])


TWO_P, TWO_R = np.array([1.0, 0.5]), np.array([0.5, 1.5])


def two_play_record(snr_db=None, seed=0):
    _, v = sinusoid(5, 1, fs=1000, duration=10)
    y = PIOperator(TWO_P, TWO_R).simulate(v)
    if snr_db is not None:
        rng = np.random.default_rng(seed)
        y = y + rng.normal(0.0, np.std(y) * 10 ** (-snr_db / 20), y.size)
    return v, y


@pytest.mark.parametrize("n_plays", [4, 5, 6])
def test_identify_joint_more_plays_than_the_data_show(n_plays):
    """More plays asked of a noise-free two-play record than it shows: the plays the data do not
    resolve (a play split in two at one radius, or a weight near 0) are merged or dropped with
    a warning, and exactly the two true plays remain (within 0.1 %), whichever way the near-tie
    of the split falls on this machine."""
    v, y = two_play_record()
    with pytest.warns(RuntimeWarning, match="the data resolve 2"):
        idn = identify(v, y, dt=1e-3, n_plays=n_plays, method="joint")
    assert idn.operator.n == 2
    assert max_rel_error(idn.weights, TWO_P) < 1e-3
    assert max_rel_error(idn.radii, TWO_R) < 1e-3
    assert idn.rms_error < 1e-6 * idn.output_range


@pytest.mark.parametrize(("weights", "radii"), [
    ([0.9485, 0.0515, 0.5], [0.4998, 0.5038, 1.5]),       # the split seen on another machine
    ([0.5, 0.5, 0.5, 1e-9], [0.497, 0.503, 1.5, 3.0]),    # split and a weight near 0
    ([1.0, 0.25, 0.25], [0.5, 1.49, 1.51]),               # the other play split
])
def test_reduce_plays_merges_splits_of_other_machines(weights, radii):
    """The splits a near-tie can give elsewhere, fed to :func:`reduce_plays` with this record's
    binned branch data: each is reduced to the two true plays (within 0.5 %)."""
    v, y = two_play_record()
    est = JointEstimator(2, threshold=0.05)
    est.run(v, y)
    est.finish()
    red = reduce_plays(*est.binned(), np.array(weights), np.array(radii), linear_play=False)
    assert red.changed and red.weights.size == 2
    assert max_rel_error(red.weights, TWO_P) < 5e-3
    assert max_rel_error(red.radii, TWO_R) < 5e-3


def test_reduce_plays_keeps_resolved_plays():
    """The true plays are kept as they are: no merge, no drop."""
    v, y = two_play_record()
    est = JointEstimator(2, threshold=0.05)
    est.run(v, y)
    res = est.finish()
    red = reduce_plays(*est.binned(), res.weights, res.radii, linear_play=False)
    assert not red.changed and red.describe() == ""
    assert max_rel_error(red.radii, TWO_R) < 1e-3


@pytest.mark.parametrize(("seed", "n_plays"), [(0, 3), (1, 3), (2, 3), (3, 3), (0, 5), (2, 5)])
def test_identify_joint_surplus_plays_noisy(seed, n_plays):
    """The same at 40 dB SNR from several noise seeds: the true plays are found within 1 %
    (weights summed over the plays within 5 % of each true radius), and whatever the data keep
    beyond them carries under 2 % of the total weight."""
    v, y = two_play_record(snr_db=40, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        warnings.simplefilter("ignore", UserWarning)
        idn = identify(v, y, dt=1e-3, n_plays=n_plays, method="joint")
    claimed = np.zeros(idn.weights.size, bool)
    for p, r in zip(TWO_P, TWO_R, strict=True):
        near = np.abs(idn.radii / r - 1) < 0.05
        assert near.any()
        claimed |= near
        w = idn.weights[near].sum()
        assert abs(w / p - 1) < 0.01
        assert abs(np.average(idn.radii[near], weights=idn.weights[near]) / r - 1) < 0.01
    assert idn.weights[~claimed].sum() < 0.02 * idn.weights.sum()
