"""Issue 32, numerical range, state on error and limits (docs/reliability.md): one rule for
every operator and model — a result float64 cannot hold raises a ValueError naming the
argument, nothing returns inf or NaN from finite input, and a step that raises leaves the state
as it was."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pimodel import PIOperator
from pimodel._native import LIMITS
from pimodel.diagnosis.model import DiagnosedModel
from pimodel.identification.adaptive.joint import estimate_jointly
from pimodel.operators import (
    AsymmetricPI,
    Cascade,
    CreepOperator,
    GeneralizedPI,
    RateDependentPI,
)
from pimodel.operators.pi import INVERSE_WEIGHT_MAX, INVERSE_WEIGHT_MIN
from pimodel.signals import triangle

HUGE = np.finfo(float).max


def _operators(rng):
    """One operator of every streaming type (and inverse), drawn from ``rng``, weights summing
    above 2 so that an input near float64's maximum overflows the output."""
    p = rng.uniform(1.0, 2.0, 3)
    r = np.concatenate(([0.0], np.sort(rng.uniform(0.05, 1.0, 2))))
    pi = PIOperator(p, r)
    asym = AsymmetricPI(rng.uniform(1.0, 2.0), p, r, ascending=(1.0, 0.0),
                        descending=(rng.uniform(1.0, 2.0), rng.uniform(-0.5, 0.5)))
    rd = RateDependentPI(p, r, rate_gain=rng.uniform(0.01, 0.1), dt=1e-3)
    creep = CreepOperator(rng.uniform(0.01, 0.1, 2), rng.uniform(0.05, 1.0, 2), dt=1e-3)
    ops = [pi, pi.inverse(), GeneralizedPI(p, r), asym, asym.inverse(), rd, rd.inverse(),
           creep, creep.inverse()]
    return ops + [Cascade(PIOperator(p, r), CreepOperator([0.05], [0.1], dt=1e-3))]


def _states(op):
    stages = op.stages if isinstance(op, Cascade) else (op,)
    return [s.state for s in stages]


@pytest.mark.parametrize("seed", range(4))
def test_every_operator_keeps_its_state_when_a_step_raises(seed):
    """Property (issue 32, cases 3-4): after a few ordinary samples, a sample near float64's
    maximum either gives a finite output or raises ValueError with every state unchanged; the
    next ordinary step then equals a twin's that never saw the bad sample."""
    rng = np.random.default_rng(seed)
    for op, twin in zip(_operators(rng), _operators(np.random.default_rng(seed)), strict=True):
        for x in rng.uniform(-1, 1, 5):
            op.step(x)
            twin.step(x)
        before = _states(op)
        bad = float(rng.choice([1.0, -1.0]) * rng.uniform(0.5, 1.0) * HUGE)
        try:
            out = op.step(bad)
        except ValueError as err:
            assert "sample" in str(err)
            for a, b in zip(before, _states(op), strict=True):
                np.testing.assert_array_equal(a, b)
            x = float(rng.uniform(-1, 1))
            assert op.step(x) == twin.step(x), type(op).__name__
        else:
            assert np.isfinite(out), type(op).__name__


@given(st.floats(1e300, HUGE), st.integers(0, 2**32 - 1))
@settings(max_examples=30)
def test_simulate_is_finite_or_raises(big, seed):
    """Property (case 4): ``simulate([0, big, 0])`` returns finite samples or raises a
    ValueError naming the signal, for every operator type and inverse."""
    for op in _operators(np.random.default_rng(seed)):
        try:
            out = op.simulate([0.0, big, 0.0])
        except ValueError as err:
            assert str(err).startswith(("v:", "y_d:", "u:"))
        else:
            assert np.all(np.isfinite(out)), type(op).__name__


def test_case4_simulate_huge_sample_raises_for_each_named_type():
    """Case 4 as filed: ``simulate([0, 1e308, 0])`` no longer returns inf or NaN."""
    ops = _operators(np.random.default_rng(4))
    for op in (ops[0], ops[2], ops[3], ops[5], ops[-1]):  # the forward PI-type operators
        with pytest.raises(ValueError, match="sample 1"):
            op.simulate([0.0, 1e308, 0.0])
    with pytest.raises(ValueError, match="v: sample 1 .*rate"):
        RateDependentPI([1.0, 0.5], [0.0, 0.3], rate_gain=0.1, dt=1e-3).simulate(
            [0.0, 1e306, 0.0])


@pytest.mark.parametrize("w", [1e154, 1e160, 1e-155, 1e-160, 1e-300])
def test_case2_inverse_weights_outside_the_range_are_refused(w):
    rng = np.random.default_rng(2)
    op = PIOperator(w * rng.uniform(0.9, 1.1, 3), [0.0, 0.3, 0.6])
    with pytest.raises(ValueError, match=r"partial sums P_i .* representable only for P_i"):
        op.inverse()


@pytest.mark.parametrize("scale", [INVERSE_WEIGHT_MIN * 8, 1.0, INVERSE_WEIGHT_MAX / 8])
def test_case2_inverse_round_trip_holds_inside_the_range(scale):
    """At both ends of the documented range the inverse's weights keep their digits."""
    rng = np.random.default_rng(22)
    op = PIOperator(scale * rng.uniform(0.3, 1.0, 3), [0.0, 0.3, 0.6])
    v = 3 * np.sin(np.linspace(0, 10, 200)) + rng.normal(0, 0.1, 200)
    back = op.inverse().simulate(op.simulate(v))
    assert np.max(np.abs(back - v)) < 1e-9


def test_case3_pi_step_that_raises_keeps_the_state():
    op = PIOperator([1.0, 1.0], [0.0, 0.3])
    op.step(0.2)
    before = op.state
    with pytest.raises(ValueError, match="v: sample 0 .*overflow"):
        op.step(1e308)
    np.testing.assert_array_equal(op.state, before)
    assert op.step(0.5) == PIOperator([1.0, 1.0], [0.0, 0.3]).simulate([0.2, 0.5])[1]


def test_asymmetric_inverse_with_near_equal_envelope_slopes():
    """Regression (tests/test_operator_extra_properties.py::test_asymmetric_round_trip): the
    envelopes ``3 s`` and ``(3 - 4e-16) s - 1`` cross at ``|s| ~ 1e15``; the inverse solved from
    that distant kink and lost the sample (v = -1.875 came back as -2)."""
    rng = np.random.default_rng(32)
    for _ in range(300):
        n = int(rng.integers(1, 4))
        op = AsymmetricPI(rng.uniform(0.02, 2), rng.uniform(0, 1, n),
                          np.sort(rng.uniform(0, 1, n)), ascending=(3.0, 0.0),
                          descending=(2.9999999999999996, -1.0),
                          initial_state=rng.uniform(-2, 2))
        v = np.round(rng.uniform(-3, 3, 8) * 8) / 8
        np.testing.assert_allclose(op.inverse().simulate(op.simulate(v)), v, rtol=0, atol=1e-9)


def test_case4_diagnosed_model_and_inverse_refuse_unrepresentable_samples():
    m = DiagnosedModel([0.0, 0.5], [1.5, 0.8], 0.1, dt=1e-3)
    with pytest.raises(ValueError, match="v: sample 1"):
        m.simulate([0.0, 1e308, 0.0])
    for big in (3e307, 1e308):  # the C root bracket overflowed: a finite, wrong input before
        with pytest.raises(ValueError, match="y_d: sample 1 .*range"):
            m.inverse().simulate([0.0, big, 0.0])
    y_d = np.array([0.1, 1e300, 0.1])
    v = m.inverse().simulate(y_d)
    assert np.all(np.isfinite(v))
    assert abs(m.simulate(v)[1] / y_d[1] - 1) < 1e-9


def test_case11_diagnosed_model_takes_the_fmu_play_and_lag_limits():
    most = LIMITS["PIM_DIAG_MAX_PLAYS"]
    DiagnosedModel(np.linspace(0, 1, most), np.full(most, 1.0 / most), 0.0, dt=1e-3)
    for n in (most + 1, 10_000):
        with pytest.raises(ValueError, match=f"radii: {n} plays; .* at most {most}"):
            DiagnosedModel(np.linspace(0, 1, n), np.full(n, 1.0 / n), 0.0, dt=1e-3)
    lags = LIMITS["PIM_DIAG_MAX_LAGS"] + 1
    with pytest.raises(ValueError, match=f"creep_lag_gains: {lags} creep lags"):
        DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3, effects=("creep",),
                       params={"creep_lag_gains": [0.01] * lags,
                               "creep_time_constants_s": [1.0] * lags})


def test_case7_estimate_jointly_warns_on_a_fit_far_outside_the_noise():
    stage = PIOperator([6.346, 1.6735, 1.1552, 0.4477], [0, 0.1945, 0.4826, 0.5707])
    _, v = triangle(1.0, 1, fs=1000.0, duration=3)
    y = stage.simulate(v)
    with pytest.warns(RuntimeWarning, match="does not fit the data.*linear_play=True"):
        bad = estimate_jointly(v, y, 4)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        good = estimate_jointly(v, y, 4, linear_play=True)
    assert good.fit_rms < 1e-3 * np.ptp(y) < bad.fit_rms


def test_asymmetric_inverse_takes_the_c_play_limit():
    most = LIMITS["PIM_MAX_PLAYS"]
    rng = np.random.default_rng(11)
    for n, ok in ((most, True), (most + 1, False)):
        op = AsymmetricPI(1.0, rng.uniform(0.1, 1, n), np.sort(rng.uniform(0, 1, n)))
        if ok:
            v = rng.uniform(-1, 1, 20)
            np.testing.assert_allclose(op.inverse().simulate(op.simulate(v)), v, atol=1e-9)
        else:
            with pytest.raises(ValueError, match=f"forward: {n} plays; .* at most {most}"):
                op.inverse()


def test_pi_block_step_refuses_an_overflowing_sample():
    from pimodel.blocks.pi import _Stepper

    stepper = _Stepper(PIOperator([1.0, 1.0], [0.0, 0.3]))
    x = np.zeros(2)
    y, z = stepper.step(x, 0.5)
    assert np.isfinite(y) and np.all(np.isfinite(z))
    with pytest.raises(ValueError, match="v: sample 0 .*overflow"):
        stepper.step(z, 1e308)
