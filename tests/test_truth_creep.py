"""The truth's creep is the exact zero-order-hold discretisation of its four lags at 10 kHz:
the step response equals the analytic lag sum and tiny input changes stay tiny (the former
single polynomial transfer function failed both, docs/design-notes.md)."""

import numpy as np
import pytest

from pimodel.stages.pi_stage import CREEP_DECADES, CREEP_T_MIN, Truth, creep_lag_filters
from pimodel.stages.stepper import stage_stepper

FS = 10_000.0
PERCENT = 1.5


def _creep_only(percent=PERCENT):
    """A stage whose PI is a unit gain, so its output is the creep of its input."""
    return Truth(weights=(1.0,), radii=(0.0,), creep_percent_per_decade=percent, noise_um=0.0)


def _analytic_step(t):
    """``1 + sum_i g_i (1 - exp(-t / tau_i))``: the lags' response ``t`` seconds after a unit
    step (independent of the code under test: written from creep_per_decade's definition)."""
    tau = CREEP_T_MIN * 10.0 ** np.arange(CREEP_DECADES)
    return 1.0 + np.sum(PERCENT / 100.0 * (1.0 - np.exp(-np.asarray(t)[..., None] / tau)), -1)


def test_step_response_at_10_khz_equals_the_analytic_lag_sum():
    times = np.array([0.1, 1.0, 3.0, 60.0])
    n = int(round(times[-1] * FS)) + 2
    t = np.arange(n) / FS
    v = np.ones(n)
    v[0] = 0.0  # the step at sample 1; y[k] is the response (k - 1) dt after it
    y = _creep_only().simulate(t, v, np.random.default_rng(0))
    k = np.round(times * FS).astype(int) + 1
    exact = _analytic_step(times)
    assert np.all(np.abs(y[k] - exact) < 1e-9 * exact)
    assert y[0] == 0.0 and y[1] == 1.0  # direct feedthrough, the lags act from the next sample


def test_a_tiny_input_change_stays_tiny_at_10_khz():
    t = np.arange(30_000) / FS  # 3 s, the length of the standard records
    v = np.sin(2 * np.pi * 5 * t)
    bumped = v.copy()
    bumped[10] += 1e-12
    truth = _creep_only()
    diff = truth.simulate(t, bumped, np.random.default_rng(0)) - truth.simulate(
        t, v, np.random.default_rng(0))
    assert np.max(np.abs(diff)) < 1.2e-12  # the feedthrough 1e-12 plus the lags' sum_i g_i


def test_stepper_equals_simulate_with_creep_at_10_khz():
    truth = Truth(creep_percent_per_decade=PERCENT, mode_hz=1500.0, noise_um=0.0)
    t = np.arange(8000) / FS
    v = np.where(t < 0.3, np.sin(2 * np.pi * 20 * t), 0.4)
    stage = stage_stepper(truth, 1 / FS)
    stepped = np.array([stage.step(tk, vk) for tk, vk in zip(t, v, strict=True)])
    y = truth.simulate(t, v, np.random.default_rng(0))
    assert np.max(np.abs(stepped - y)) < 1e-12 * np.ptp(y)


@pytest.mark.parametrize("percent", [-1.0, float("nan")])
def test_bad_creep_rate_is_refused(percent):
    with pytest.raises(ValueError, match="percent_per_decade"):
        creep_lag_filters(percent, 1e-4)
    with pytest.raises(ValueError, match="percent_per_decade"):
        _creep_only(percent).simulate(np.arange(3) * 1e-4, np.ones(3), np.random.default_rng(0))
