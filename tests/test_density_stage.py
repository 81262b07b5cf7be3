"""The third stage generator (``pimodel.stages.density_stage``): each effect has the shape its
docstring states, checked against closed forms with the noise off."""

import numpy as np
import pytest

from pimodel.stages.density_stage import (
    FS,
    INPUT_KINDS,
    N_PLAYS,
    V_MAX,
    DensityStage,
    density_input,
    density_records,
    random_density_stage,
)

QUIET = {"noise": 0.0, "quantum": 1e-12}


def _ramp_hold(up_s=0.5, hold_s=3.0, level=80.0):
    n_up, n_hold = int(up_s * FS), int(hold_s * FS)
    v = np.concatenate((np.linspace(0, level, n_up), np.full(n_hold, level)))
    return np.arange(v.size) / FS, v


def test_rising_input_follows_the_play_sum():
    """From rest, a rising input gives ``a v + sum w_i max(v - r_i, 0)`` (the play law)."""
    rng = np.random.default_rng(3)
    stage = DensityStage(a_lin=rng.uniform(0.04, 0.08), density_r0=rng.uniform(8, 20), **QUIET)
    v = np.sort(rng.uniform(0, V_MAX, 500))
    h = stage.hysteresis(v, 1 / FS)
    want = stage.a_lin * v + np.maximum(v[:, None] - stage.radii[None, :], 0) @ stage.weights
    assert np.max(np.abs(h - want)) < 1e-9 * stage.span
    assert stage.radii.size == N_PLAYS and np.all(stage.weights > 0)


def test_loop_is_open_and_rate_widens_it():
    t = np.arange(int(2 * FS)) / FS
    v = V_MAX / 2 * (1 - np.cos(2 * np.pi * 1.0 * t))
    width = {}
    for beta in (None, 0.8):
        h = DensityStage(rate_beta=beta, **QUIET).hysteresis(v, 1 / FS)
        up = np.interp(V_MAX / 2, v[int(0.1 * FS):int(0.5 * FS)], h[int(0.1 * FS):int(0.5 * FS)])
        down = np.interp(V_MAX / 2, v[int(1.5 * FS):int(1.9 * FS)][::-1],
                         h[int(1.5 * FS):int(1.9 * FS)][::-1])
        width[beta] = down - up
    assert width[None] > 0.05 * DensityStage().span
    assert width[0.8] > 1.05 * width[None]


def test_delay_thermal_and_gain_have_their_closed_forms():
    t, v = _ramp_hold()
    base = DensityStage(**QUIET).simulate(t, v, np.random.default_rng(0))
    late = DensityStage(delay_s=2 / FS, **QUIET).simulate(t, v, np.random.default_rng(0))
    assert np.max(np.abs(late[2:] - base[:-2])) < 1e-9
    d, tau = 0.3, 20.0
    warm = DensityStage(thermal=(d, tau), **QUIET).simulate(t + 5.0, v, np.random.default_rng(0))
    assert np.max(np.abs(warm - base - d * (1 - np.exp(-(t + 5.0) / tau)))) < 1e-9
    gained = DensityStage(**QUIET).simulate(t, v, np.random.default_rng(0), gain=1.05)
    assert np.max(np.abs(gained - 1.05 * base)) < 1e-9


def test_creep_keeps_moving_during_a_hold_and_the_mode_settles_to_gain_one():
    t, v = _ramp_hold()
    base = DensityStage(**QUIET).simulate(t, v, np.random.default_rng(0))
    crept = DensityStage(creep=(0.01, 0.01, 0.01, 0.01), **QUIET).simulate(
        t, v, np.random.default_rng(0))
    hold = crept[int(0.6 * FS):]
    assert np.all(np.diff(hold) > 0)  # creep goes on through the hold
    assert 0.002 * base[-1] < hold[-1] - hold[0] < 0.04 * base[-1]
    moded = DensityStage(mode=(150.0, 0.1, 120.0), **QUIET).simulate(
        t, v, np.random.default_rng(0))
    assert abs(moded[-1] - base[-1]) < 1e-6 * base[-1]
    assert np.max(np.abs(moded - base)) > 0.001 * base[-1]  # but it moves differently


def test_clipping_and_asymmetry():
    t, v = _ramp_hold(level=V_MAX)
    stage = DensityStage(clip=0.8, **QUIET)
    y = stage.simulate(t, v, np.random.default_rng(0))
    base = stage.hysteresis(np.array([0.0]), 1 / FS)[0]
    assert y.max() <= base + 0.8 * stage.span + 1e-9 and np.sum(y >= y.max() - 1e-9) > FS
    up = DensityStage(asymmetry=0.1, **QUIET).simulate(t, v, np.random.default_rng(0))
    plain = DensityStage(**QUIET).simulate(t, v, np.random.default_rng(0))
    assert up[-1] > plain[-1] + 0.01 * stage.span  # the quadratic map bends the top end


@pytest.mark.parametrize("kind", INPUT_KINDS)
def test_inputs_stay_in_range_and_differ_by_seed(kind):
    t, v = density_input(kind, seed=4, duration=2.0)
    assert t.size == v.size == int(2 * FS)
    assert v.min() >= 0.04 * V_MAX and v.max() <= 0.96 * V_MAX
    assert np.ptp(v) > 0.85 * V_MAX
    assert not np.allclose(v, density_input(kind, seed=5, duration=2.0)[1])


def test_records_share_one_clock_and_the_sensor_gain_differs():
    tr, va = density_records([], 2, duration=1.0)
    assert tr.t[0] == 0 and abs(va.t[0] - tr.t[-1] - 2.0) < 1e-9
    assert tr.v[0] == 0 and va.v[0] == 0  # each record starts at rest
    _, va_gain = density_records(["sensor_gain"], 2, duration=1.0)
    ratio = np.median(va_gain.y[va.y > 1] / va.y[va.y > 1])
    assert 1.03 < ratio < 1.09


def test_bad_names_raise():
    with pytest.raises(ValueError, match="kind"):
        density_input("square", 0)
    with pytest.raises(ValueError, match="effects"):
        random_density_stage(["hum"], 0)
    with pytest.raises(ValueError, match="kind"):
        density_records([], 0, kind="square")


def test_sim_to_real_holds_its_cases_at_full_size_only():
    """The study's density cases: a clean stage on every input kind, the single effects, the
    pairs and the outside effects (expected "unexplained"); none in the quick size, whose
    table tests/test_studies.py holds."""
    from pimodel.experiments.studies import load_study

    study = load_study("sim_to_real")
    full = [c for c in study.cases(False) if c["generator"] == "density"]
    assert not [c for c in study.cases(True) if c["generator"] == "density"]
    assert {c["kind"] for c in full if not c["effects"]} == {"mixed", *INPUT_KINDS}
    assert len({c["seed"] for c in full}) == 10
    outside = [c for c in full if set(c["effects"]) & {"clipping", "second_input",
                                                         "sensor_gain"}]
    assert outside and all(study.expected(c) == ["unexplained"] for c in outside)
    assert study.expected({"effects": ["creep", "delay"]}) == ["creep", "delay"]
