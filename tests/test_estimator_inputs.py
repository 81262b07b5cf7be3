"""Issue 27: estimate_radii with its defaults on the inputs users apply (offset sines,
multisines, band-limited random, stair steps, decaying loops), random stages of 3-7 plays
drawn here, starts below, at zero and far above the truth; the batch refinement and the
Cramer-Rao bound of the radii."""

import numpy as np
import pytest

from pimodel import PIOperator, estimate_radii
from pimodel.experiments.estimator_map import (
    INPUT_KINDS,
    STARTS,
    input_signal,
    random_stage,
    run_cell,
    start_radii,
)
from pimodel.identification.adaptive.polish import (
    play_sensitivity,
    polish_radii,
    profile_radii,
    radius_bound,
)

FS = 1000.0
T = np.arange(int(20 * FS)) / FS  # 20 s at 1 kHz: long enough noise-free


@pytest.mark.parametrize("kind", INPUT_KINDS)
def test_noise_free_any_input_any_start_within_one_percent(kind):
    rng = np.random.default_rng(2700 + INPUT_KINDS.index(kind))
    for _ in range(2):
        p, r = random_stage(rng)
        v = input_signal(kind, T, seed=int(rng.integers(1000)))
        y = PIOperator(p, r).simulate(v)
        for start in STARTS:
            res = estimate_radii(v, y, p, dt=1 / FS, initial_radii=start_radii(start, r))
            err = np.max(np.abs(res.radii - r)) / r[-1]
            assert err < 0.01, (kind, start, p.size, err, res.online_radii, r)
            assert res.health.ok, res.health.messages


def test_sensitivity_is_the_derivative_of_the_play_output():
    rng = np.random.default_rng(3)
    v = input_signal("random", T[:5000], seed=3)
    r = np.array([0.05, 0.12, 0.2])
    z, s = play_sensitivity(v, r)
    h = 1e-7
    z2, _ = play_sensitivity(v, r + h)
    fd = (z2 - z) / h
    # the pattern can change at a few samples where a play just touches its envelope
    assert np.mean(np.abs(fd - s) < 1e-5) > 0.999
    assert set(np.unique(s)) <= {-1.0, 0.0, 1.0} and rng is not None


def test_profile_start_is_close_whatever_the_history():
    rng = np.random.default_rng(11)
    p, r = random_stage(rng, n=6)
    v = input_signal("multisine", T, seed=11)
    guess = profile_radii(v, PIOperator(p, r).simulate(v), p)
    assert np.max(np.abs(guess - r)) < 0.05 * r[-1]


@pytest.mark.parametrize("kind", ["offset sine", "random"])
def test_least_squares_with_true_pattern_meets_the_bound(kind):
    """Polishing from the truth under 20 dB noise: the normalised errors (error / Cramer-Rao
    sd) over 10 seeds have an RMS near 1 (an efficient estimate), also on band-limited random
    input with its many small reversals. The noise streams are independent of the input's
    (``input_signal`` draws the random input from ``default_rng(5)``)."""
    rng = np.random.default_rng(5)
    p, r = random_stage(rng, n=4)
    v = input_signal(kind, T, seed=5)
    y0 = PIOperator(p, r).simulate(v)
    sigma = float(np.std(y0) / 10)
    sd = radius_bound(v, p, r, sigma=sigma).sd
    z = []
    for seed in range(10):
        y = y0 + np.random.default_rng([seed, 1]).normal(0, sigma, y0.size)
        z.append((polish_radii(v, y, p, r) - r) / sd)
    rms = float(np.sqrt(np.mean(np.square(z))))
    assert 0.5 < rms < 2.0, rms


def test_bound_is_infinite_without_excitation():
    v = input_signal("centred sine", T[:3000])  # range 1: travel never above 2 r = 1.2
    b = radius_bound(v, [1.0, 1.0], [0.1, 0.6], sigma=0.01)
    assert not b.exciting and np.isinf(b.sd[1])


def test_refined_health_flags_an_unexcited_radius():
    v = input_signal("centred sine", T[:3000])
    p, r = np.array([1.0, 1.0]), np.array([0.1, 0.6])
    res = estimate_radii(v, PIOperator(p, r).simulate(v), p, dt=1 / FS)
    assert not res.health.ok and not res.health.excitation_ok


def test_polish_false_is_the_online_iterate():
    rng = np.random.default_rng(7)
    p, r = random_stage(rng, n=3)
    v = input_signal("triangle", T[:5000])
    y = PIOperator(p, r).simulate(v)
    res = estimate_radii(v, y, p, dt=1 / FS, polish=False)
    assert res.online_radii is None and res.settings["polish"] is False
    assert np.max(np.abs(res.history[-1] - res.radii)) < 0.1  # the last iterate, one update on


# Record length [s] at 1 kHz per input kind where the 5 % property holds with margin at
# 20 dB over these seeds and starts (docs/estimator.md, "20 dB on every input: record
# length"). Stair steps need the refinement's split moves (a local minimum with two plays
# nearly merged: 4.2 % at 120 s without them).
TWENTY_DB_SECONDS = {"centred sine": 120.0, "offset sine": 60.0, "triangle": 120.0,
                     "multisine": 120.0, "random": 20.0, "stair steps": 120.0,
                     "decaying loops": 20.0}


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(TWENTY_DB_SECONDS))
def test_twenty_db_within_five_percent_over_ten_seeds(kind):
    """Random stages of 3-7 plays (seed 0-9), output noise at 20 dB, the three starts in turn:
    the refined estimate's largest radius error is within 5 % of the largest radius."""
    errs = []
    for seed in range(10):
        cell = run_cell(kind, 20.0, STARTS[seed % 3], seed, duration=TWENTY_DB_SECONDS[kind])
        errs.append(cell["polished"])
    assert max(errs) < 0.05, errs
