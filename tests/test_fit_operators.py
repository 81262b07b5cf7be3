"""Identification of the generalized, rate-dependent and creep operators on records from
generators written independently of the models: ``pimodel.stages.pi_stage`` (another module's PI +
quadratic asymmetry + creep lags discretised by python-control) and plain loops in this file."""

from __future__ import annotations

import control
import numpy as np
import pytest

from pimodel import PIOperator
from pimodel.identification.extended_operators import (
    fit_asymmetric,
    fit_creep,
    fit_generalized,
    fit_rate_dependent,
)
from pimodel.loops.actuators import creep_per_decade
from pimodel.stages.pi_stage import STAGE_RADII, STAGE_WEIGHTS, Truth, excitation


def _scored_rms(pred, y, v):
    k0 = int(max(np.argmax(v), np.argmin(v)))
    return float(np.sqrt(np.mean((pred[k0:] - y[k0:]) ** 2)))


# -- generalized: asymmetry from pimodel.stages.pi_stage (quadratic output term)
# ----------------------

@pytest.mark.parametrize(("asymmetry", "seed"), [(0.06, 0), (-0.04, 1)])
def test_generalized_fit_recovers_truth_asymmetry(asymmetry, seed):
    t, v = excitation("train", seed=seed)
    tv, vv = excitation("validate", seed=seed + 10)
    truth = Truth(asymmetry=asymmetry, noise_um=0.005)
    y = truth.simulate(t, v, np.random.default_rng(seed))
    yv = truth.simulate(tv, vv, np.random.default_rng(seed + 1))
    nominal = fit_generalized(v, y, input_envelope="identity", output_envelope="identity")
    fit = fit_generalized(v, y, input_envelope="identity", output_envelope="poly2")
    e_nom = _scored_rms(nominal.model.simulate(vv), yv, vv)
    e_gen = _scored_rms(fit.model.simulate(vv), yv, vv)
    # measured: 10-15x smaller on the validation record; demand 4x
    assert e_gen < e_nom / 4
    assert e_gen < 0.003 * np.ptp(yv)  # 0.13 % measured
    # truth: y = w + a w^2 / half, half = sum(p) / 2; the fitted c2 within 5 %
    c2_true = asymmetry / (0.5 * sum(STAGE_WEIGHTS))
    c2 = fit.model.output_envelope.coefficients[2]
    assert abs(c2 - c2_true) < 0.05 * abs(c2_true)
    # and the fitted model has its exact inverse
    np.testing.assert_allclose(fit.model.inverse().simulate(fit.model.simulate(vv)), vv,
                               atol=1e-9)


# -- generalized: saturating, asymmetric loops from a plain-loop generator ------------------

def saturating_generator(v, p, r, A, B, C, D, e2):
    """Plays on A tanh(B v + C) + D (relaxed start), output w + e2 w^2: a plain loop."""
    g0 = A * np.tanh(B * v[0] + C) + D
    z = [g0] * len(p)
    out = []
    for x in v:
        g = A * np.tanh(B * x + C) + D
        z = [min(max(zi, g - ri), g + ri) for zi, ri in zip(z, r, strict=True)]
        w = sum(pi * zi for pi, zi in zip(p, z, strict=True))
        out.append(w + e2 * w * w)
    return np.array(out)


@pytest.mark.slow
def test_generalized_fit_on_saturating_loops():
    fs = 1000
    tt = np.arange(3 * fs) / fs
    v = 10 * np.sin(2 * np.pi * tt) * np.minimum(1, 0.3 + tt / 2)
    vv = np.concatenate((8 * np.sin(2 * np.pi * 2 * tt[:2000]),
                         4 * np.sin(2 * np.pi * 3 * tt[:1000]) + 3))
    p, r = [1.0, 0.6, 0.4, 0.3, 0.2], [0.0, 0.15, 0.35, 0.6, 0.9]
    args = (3.0, 0.25, 0.3, 0.5, 0.02)
    y = saturating_generator(v, p, r, *args) + np.random.default_rng(0).normal(0, 0.01, v.size)
    yv = saturating_generator(vv, p, r, *args)
    nominal = fit_generalized(v, y, input_envelope="identity", output_envelope="identity")
    fit = fit_generalized(v, y, input_envelope="tanh", output_envelope="poly2")
    e_nom = _scored_rms(nominal.model.simulate(vv), yv, vv)
    e_gen = _scored_rms(fit.model.simulate(vv), yv, vv)
    assert e_gen < e_nom / 5  # measured about 24x
    assert e_gen < 0.015 * np.ptp(yv)  # 0.6 % measured


# -- distinct ascending / descending envelopes: plain-loop generator -------------------------

def two_envelope_generator(v, p, r, up, down):
    """Generalized plays with loading envelope ``up`` and unloading ``down`` (different tanh
    shapes, so not exactly representable by the model) plus a direct tanh term."""
    z = [0.5 * (up(v[0]) + down(v[0]))] * len(p)
    out = []
    for x in v:
        z = [max(up(x) - ri, min(down(x) + ri, zi)) for zi, ri in zip(z, r, strict=True)]
        out.append(1.2 * np.tanh(0.3 * x) + sum(pi * zi for pi, zi in zip(p, z, strict=True)))
    return np.array(out)


def test_asymmetric_fit_on_distinct_envelopes():
    def up(x):
        return 2.5 * np.tanh(0.3 * x) - 0.2

    def down(x):
        return 3.2 * np.tanh(0.28 * x) + 0.3

    fs = 1000
    tt = np.arange(3 * fs) / fs
    v = 10 * np.sin(2 * np.pi * tt) * np.minimum(1, 0.3 + tt / 2)
    vv = np.concatenate((8 * np.sin(2 * np.pi * 2 * tt[:2000]),
                         4 * np.sin(2 * np.pi * 3 * tt[:1000]) + 3))
    p, r = [1.0, 0.6, 0.4, 0.3], [0.0, 0.2, 0.5, 0.9]
    y = two_envelope_generator(v, p, r, up, down)
    y = y + np.random.default_rng(0).normal(0, 0.01, v.size)
    yv = two_envelope_generator(vv, p, r, up, down)
    sym = fit_generalized(v, y, input_envelope="tanh", output_envelope="poly2")
    fit = fit_asymmetric(v, y, shape="tanh")
    e_sym = _scored_rms(sym.model.simulate(vv), yv, vv)
    e_asym = _scored_rms(fit.model.simulate(vv), yv, vv)
    assert e_asym < 0.8 * e_sym  # measured 2.2x
    assert e_asym < 0.01 * np.ptp(yv)  # 0.46 % measured
    assert fit.model.descending[0] > 1.1  # the unloading envelope is the steeper one
    np.testing.assert_allclose(fit.model.inverse().simulate(fit.model.simulate(vv)), vv,
                               atol=1e-9)


# -- rate-dependent: plain-loop generator with the analytic rate of a sine ------------------

def rate_generator(t, amp, f, p, alpha, beta):
    """Radii alpha (1 + beta |dv/dt|) with the exact derivative of v = amp sin(2 pi f t)."""
    v = amp * np.sin(2 * np.pi * f * t)
    vdot = np.abs(amp * 2 * np.pi * f * np.cos(2 * np.pi * f * t))
    z = np.zeros(len(p))
    y = np.empty(t.size)
    for k in range(t.size):
        rad = alpha * (1 + beta * vdot[k])
        z = np.clip(z, v[k] - rad, v[k] + rad)
        y[k] = p @ z
    return v, y


@pytest.mark.parametrize("rate_time_constant", [0.0, 5e-4])
def test_rate_dependent_fit_from_several_rates(rate_time_constant):
    dt = 1e-4
    p, alpha, beta = np.array([1.0, 0.6, 0.4, 0.3]), np.array([0, 0.1, 0.25, 0.45]), 2e-3
    rng = np.random.default_rng(0)
    recs = []
    for f, dur in ((1, 1.5), (20, 0.1), (60, 2 / 60)):
        v, y = rate_generator(np.arange(int(dur / dt) + 1) * dt, 1.0, f, p, alpha, beta)
        recs.append((v, y + rng.normal(0, 0.003, y.size)))
    fit = fit_rate_dependent(recs, dt=dt, rate_time_constant=rate_time_constant)
    static = fit_rate_dependent(recs, dt=dt, max_rate_gain=1e-12)
    if rate_time_constant == 0:
        assert abs(fit.model.rate_gain - beta) < 0.1 * beta  # 2 % measured
    # validation at other rates and amplitude, inside and beyond the training rates
    for f, gain in ((40, 3), (100, 1.5)):
        v, y = rate_generator(np.arange(int(3 / f / dt) + 1) * dt, 0.8, f, p, alpha, beta)
        errs = []
        for m in (fit.model, static.model):
            state = np.concatenate((np.full(m.n, v[0]), [v[0], 0.0]))
            errs.append(_scored_rms(m.simulate(v, state=state), y, v))
        # measured: 40 Hz 14x (raw rate) / 5x (filtered); 100 Hz 8x / 1.9x
        assert errs[0] < errs[1] / gain
    if rate_time_constant > 0:
        # the filtered rate keeps the identified model's inverse numerically exact
        assert fit.settings["rate_sensitivity"] < 1
        v = recs[1][0]
        np.testing.assert_allclose(fit.model.inverse().simulate(fit.model.simulate(v)), v,
                                   atol=1e-9)


# -- creep: pimodel.stages.pi_stage's creep lags on step/hold records
# -----------------------------------

@pytest.mark.parametrize("seed", [0, 1, 2])
def test_creep_fit_from_holds(seed):
    dt = 1e-3
    rng = np.random.default_rng(seed)
    rate = rng.uniform(1, 2)
    v = np.repeat(rng.uniform(-1, 1, 8), int(3 / dt))
    t = np.arange(v.size) * dt
    y = Truth(creep_percent_per_decade=rate, noise_um=0.005).simulate(
        t, v, np.random.default_rng(seed))
    u = PIOperator(STAGE_WEIGHTS, STAGE_RADII).simulate(v)  # the known hysteresis output
    fit = fit_creep(u, y, dt=dt)
    assert fit.rms < 2 * 0.005  # at the noise level (measured 1.0x)
    # step response over the hold length within 2 % of the creep amplitude (0.1 % measured)
    T = np.arange(int(3 / dt)) * dt
    # (one polynomial TF: off by 1e-6 at this 1 kHz, 2e-2 at 10 kHz; notes/creep-discretization)
    _, s_true = control.step_response(control.c2d(creep_per_decade(rate), dt, "zoh"), T)
    s_fit = fit.model.simulate(np.ones(T.size), state=0.0)
    assert np.max(np.abs(s_fit - s_true)) < 0.02 * (s_true[-1] - 1)
    # the inverse compensates creep on another hold sequence, tried on the true creep
    vv = np.repeat(np.random.default_rng(100 + seed).uniform(-1, 1, 6), int(3 / dt))
    tv = np.arange(vv.size) * dt
    yd = PIOperator(STAGE_WEIGHTS, STAGE_RADII).simulate(vv)
    plant = Truth(creep_percent_per_decade=rate, noise_um=0.0, weights=(1.0,), radii=(0.0,))
    compensated = plant.simulate(tv, fit.model.inverse().simulate(yd, state=yd[0]),
                                 np.random.default_rng(0))
    uncompensated = plant.simulate(tv, yd, np.random.default_rng(0))
    e_c = np.sqrt(np.mean((compensated - yd) ** 2))
    e_u = np.sqrt(np.mean((uncompensated - yd) ** 2))
    assert e_c < e_u / 10  # measured 30-70x


# -- feedforward on the true system: augmented model's inverse against the nominal one -------

def _tracking_target(y):
    """Preamble over the whole range (wipes out initial states), sines, then holds."""
    fs = 10000.0
    yc, ya = 0.5 * (y.max() + y.min()), 0.4 * np.ptp(y)
    pre = np.concatenate((np.linspace(0, 1, 2000), np.linspace(1, -1, 4000),
                          np.linspace(-1, 0, 2000)))
    tt = np.arange(10000) / fs
    traj = 0.8 * np.sin(2 * np.pi * 5 * tt) + 0.15 * np.sin(2 * np.pi * 40 * tt)
    hold = np.repeat([0.5, -0.3, 0.7, 0.0], 5000)
    yd = yc + ya * np.concatenate((pre, traj, hold))
    return np.arange(yd.size) / fs, yd, pre.size


def _tracking_rms(truth, inverse, y_train):
    import dataclasses

    clean = dataclasses.replace(truth, noise_um=0.0)
    t, yd, k0 = _tracking_target(y_train)
    y = clean.simulate(t, inverse(yd), np.random.default_rng(0))
    return float(np.sqrt(np.mean((y[k0:] - yd[k0:]) ** 2)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_feedforward_asymmetry_cuts_tracking_error(seed):
    from pimodel.stages.pi_stage import random_truth

    truth = random_truth(["asymmetry"], seed)
    t, v = excitation("train", seed=seed)
    y = truth.simulate(t, v, np.random.default_rng(seed))
    nominal = fit_generalized(v, y, input_envelope="identity", output_envelope="identity")
    augmented = fit_generalized(v, y, input_envelope="identity", output_envelope="poly2")
    e_nom = _tracking_rms(truth, nominal.model.inverse().simulate, y)
    e_aug = _tracking_rms(truth, augmented.model.inverse().simulate, y)
    assert e_aug < e_nom / 2  # issue 19's criterion; measured 9-15x


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_feedforward_creep_cuts_tracking_error(seed):
    from pimodel.identification.extended_operators import fit_hysteresis_with_creep
    from pimodel.operators.cascade import Cascade
    from pimodel.operators.creep import CreepOperator
    from pimodel.stages.pi_stage import random_truth

    truth = random_truth(["creep"], seed)
    t, v = excitation("train", seed=seed)
    y = truth.simulate(t, v, np.random.default_rng(seed))
    nominal = fit_generalized(v, y, n_plays=16, input_envelope="identity",
                              output_envelope="identity").model
    hyst, creep = fit_hysteresis_with_creep(v, y, dt=t[1] - t[0]).model.stages

    def augmented_inverse(yd):
        # the true creep starts at rest: lag states at u[0] = y_d[0] / G(1)
        g = CreepOperator(creep.gains, creep.time_constants, dt=creep.dt,
                          initial_state=yd[0] / creep.static_gain())
        return Cascade(hyst, g).inverse().simulate(yd)

    e_nom = _tracking_rms(truth, nominal.inverse().simulate, y)
    e_aug = _tracking_rms(truth, augmented_inverse, y)
    assert e_aug < e_nom / 2  # issue 19's criterion; measured 3.2-4.5x
