"""The steppers of the true stages equal the generators' batch simulation (noise off), for every
effect, on inputs the generators' own excitations make; and the integral loop around them."""

import numpy as np
import pytest

from pimodel.diagnosis.feedforward import integral_loop
from pimodel.stages.pi_stage import EFFECTS, Truth, excitation, random_truth
from pimodel.stages.preisach_stage import AltTruth, excitations, random_alt_truth
from pimodel.stages.stepper import noise_free, stage_stepper


def _stepped(truth, t, v):
    stage = stage_stepper(truth, float(t[1] - t[0]), input_range=float(np.ptp(v)),
                          length=t.size)
    return np.array([stage.step(tk, vk) for tk, vk in zip(t, v, strict=True)])


@pytest.mark.parametrize("effect", [*EFFECTS, "asymmetry+creep+delay+drift"])
def test_truth_stepper_equals_simulate(effect):
    truth = noise_free(random_truth(effect.split("+"), 3))
    t, v = excitation("validate", fs=5000.0, seed=4)
    t, v = t[:6000], v[:6000]  # sines at 5 and 40 Hz, then the first steps
    y = truth.simulate(t, v, np.random.default_rng(0))
    assert np.max(np.abs(_stepped(truth, t, v) - y)) < 1e-10 * np.ptp(y)


@pytest.mark.parametrize("effect", [*EFFECTS, "bouc_wen", "dead_zone",
                                    "creep+dynamics+delay+drift+rate+asymmetry"])
def test_alt_truth_stepper_equals_simulate(effect):
    truth = noise_free(random_alt_truth(effect.split("+"), 2))
    _, (t, v) = excitations(2)
    t, v = t[:5000], v[:5000]  # the triangles and the start of the decaying minor loops
    y = truth.simulate(t, v, np.random.default_rng(0))
    assert np.max(np.abs(_stepped(truth, t, v) - y)) < 1e-10 * np.ptp(y)


def test_stepper_refuses_what_it_cannot_step():
    with pytest.raises(ValueError, match="second input"):
        stage_stepper(AltTruth(second_input=0.3), 2e-4)
    with pytest.raises(ValueError, match="dt"):
        stage_stepper(Truth(), 0.0)
    with pytest.raises(ValueError, match="Truth or an AltTruth"):
        stage_stepper(object(), 1e-4)
    stage = stage_stepper(AltTruth(creep=0.01), 2e-4, length=2)
    stage.step(0.0, 0.0)
    stage.step(2e-4, 0.1)
    with pytest.raises(ValueError, match="length"):
        stage.step(4e-4, 0.2)


def test_integral_loop_tracks_better_than_its_feedforward():
    """On the 5 Hz sine (loop gain about 5 at the compensation study's crossover) the integral
    loop cuts the error of a poor feedforward at least 2x."""
    truth = noise_free(random_truth(["asymmetry", "delay"], 1))
    t, v = excitation("validate", fs=5000.0, seed=1)
    t, v = t[:2500], v[:2500]  # the 5 Hz sine
    y_d = truth.simulate(t, v, np.random.default_rng(0))
    ff = 0.8 * v  # a poor feedforward, so the loop has work to do
    stage = stage_stepper(truth, float(t[1] - t[0]), input_range=float(np.ptp(v)))
    v1, y1 = integral_loop(stage.step, t, ff, y_d, 20.0)
    assert np.max(np.abs(truth.simulate(t, v1, np.random.default_rng(0)) - y1)) < 1e-9
    e_open = truth.simulate(t, ff, np.random.default_rng(0)) - y_d
    sine = slice(1000, None)
    assert np.sqrt(np.mean((y1 - y_d)[sine] ** 2)) < 0.5 * np.sqrt(np.mean(e_open[sine] ** 2))


def test_integral_loop_refuses_bad_input():
    t = np.arange(10) * 1e-3
    with pytest.raises(ValueError, match="ff, y_d"):
        integral_loop(lambda tk, vk: vk, t, np.zeros(9), np.zeros(10), 1.0)
    with pytest.raises(ValueError, match="finite"):
        integral_loop(lambda tk, vk: vk, t, np.full(10, np.nan), np.zeros(10), 1.0)
