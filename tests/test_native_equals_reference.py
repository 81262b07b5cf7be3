"""The compiled C core equals the plain NumPy reference implementations to 1e-12."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from pimodel import PIOperator, TimeDependentPI, estimate_radii
from pimodel.reference.operators import pi_inverse_reference, pi_reference, tdpi_reference
from pimodel.reference.radius_estimator import estimate_radii_reference


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("n", [1, 3, 10, 70])  # 70 > PIM_MAX_PLAYS exercises the general path
def test_pi_run_equals_reference(seed, n):
    rng = np.random.default_rng(seed)
    p = rng.uniform(0.1, 2, n)
    r = np.sort(rng.uniform(0, 3, n))
    z0 = rng.uniform(-1, 1, n)
    v = np.cumsum(rng.normal(0, 0.5, 3000))
    op = PIOperator(p, r, initial_state=z0)
    y, ref = op.simulate(v), pi_reference(v, p, r, z0)
    # 1e-12 relative to the output scale: the two sum the plays in different orders
    assert np.max(np.abs(y - ref)) <= 1e-12 * max(1.0, np.max(np.abs(ref)))


def test_play_outputs_and_final_state_consistent():
    rng = np.random.default_rng(1)
    op = PIOperator([1.0, 0.5, 0.2], [0.0, 0.3, 1.1])
    v = np.cumsum(rng.normal(0, 0.3, 500))
    z = op.play_outputs(v)
    y, zf = op.simulate(v, return_state=True)
    np.testing.assert_allclose(z @ op.weights, y, atol=1e-12)
    np.testing.assert_array_equal(z[-1], zf)


@pytest.mark.parametrize("seed", range(3))
def test_time_dependent_equals_reference(seed):
    rng = np.random.default_rng(seed)
    n, N = 5, 2000
    p = rng.uniform(0.1, 1, n)
    R = np.abs(np.cumsum(rng.normal(0, 0.01, (N, n)), axis=0)) + np.linspace(0, 2, n)
    v = 3 * np.sin(np.linspace(0, 20, N))
    y = TimeDependentPI(p).simulate(v, R, initial_state=0.2)
    np.testing.assert_allclose(y, tdpi_reference(v, p, R, 0.2), rtol=0, atol=1e-12)


def test_time_dependent_with_constant_radii_is_pi():
    p, r = np.array([1.0, 0.4, 0.3]), np.array([0.0, 0.5, 1.5])
    v = 4 * np.sin(np.linspace(0, 30, 3000))
    R = np.tile(r, (v.size, 1))
    np.testing.assert_allclose(TimeDependentPI(p).simulate(v, R), PIOperator(p, r).simulate(v),
                               atol=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_inverse_parameters_equal_reference(seed):
    rng = np.random.default_rng(seed)
    n = rng.integers(1, 12)
    p = rng.uniform(0.05, 3, n)
    r = np.concatenate(([0.0], np.sort(rng.uniform(0, 4, n - 1))))
    inv = PIOperator(p, r).inverse()
    pinv, rinv = pi_inverse_reference(p, r)
    np.testing.assert_allclose(inv.weights, pinv, rtol=1e-12)
    np.testing.assert_allclose(inv.radii, rinv, rtol=1e-12, atol=1e-14)


def test_streaming_equals_batch():
    rng = np.random.default_rng(3)
    op = PIOperator([2.0, 0.7, 0.4], [0.0, 0.2, 0.9], initial_state=[0.1, -0.2, 0.3])
    v = np.cumsum(rng.normal(0, 0.2, 400))
    ys = np.array([op.step(x) for x in v])
    np.testing.assert_allclose(ys, op.simulate(v), atol=1e-12)
    np.testing.assert_allclose(op.output(), ys[-1], atol=1e-12)
    # state round trip: save, run, restore, rerun
    saved = op.state
    a = [op.step(x) for x in v[:50]]
    op.state = saved
    b = [op.step(x) for x in v[:50]]
    assert a == b
    op.reset()
    np.testing.assert_array_equal(op.state, op.initial_state)


@pytest.mark.parametrize("law", ["data", "paper"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_radius_estimator_equals_reference(seed, law):
    """Both radius laws, random weights, radii and start, a noisy stair-step with holds and
    minor loops (bins merged as the travel grows), with and without a linear play: the C core
    and the NumPy specification agree to 1e-12 on every output."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 6))
    p = rng.uniform(0.1, 1.0, n)
    r = np.sort(rng.uniform(0.0, 3.0, n))
    linear = bool(seed % 2)
    if linear:
        r[0] = 0.0
    k = np.arange(3000)
    v = 0.25 * np.round(40 * np.sin(2 * np.pi * k / 900) * (1 + 0.3 * np.sin(k / 170)))
    y = PIOperator(p, r).simulate(v) + rng.normal(0, 0.05, v.size)
    kw = dict(dt=1e-3, gains=rng.uniform(1, 20, n), initial_radii=rng.uniform(0, 4, n),
              linear_play=linear, guard=float(rng.uniform(0, 0.2)), law=law)
    a = estimate_radii(v, y, p, threshold=0.0, slope_window=4, polish=False, **kw)
    hist, yhat, e, ed, used, final = estimate_radii_reference(v, y, p, threshold=0.0,
                                                              slope_window=4, **kw)
    np.testing.assert_allclose(a.history, hist, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.modified_error, ed, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(a.used, used)
    np.testing.assert_allclose(a.radii, final, rtol=0, atol=1e-12)
    assert used.any()


@pytest.mark.parametrize("seed", range(3))
def test_rdpi_sat_plays_equals_sat_run_per_play(seed):
    """``pim_rdpi_sat_plays`` (every play on the one rate in one pass, the diagnosis' scaled
    rate shape) gives exactly the plays ``pim_rdpi_sat_run`` gives one play at a time."""
    from pimodel import _native

    rng = np.random.default_rng(seed)
    n, N, dt = int(rng.integers(1, 30)), 4000, 1e-4
    alpha = np.sort(rng.uniform(0, 0.5, n))
    v = np.cumsum(rng.normal(0, 0.01, N))
    beta, lam = rng.uniform(0, 0.01), float(np.exp(-dt / rng.uniform(1e-4, 1e-2)))
    for sat in (0.0, rng.uniform(10, 100)):
        z0, hist0 = rng.uniform(-0.5, 0.5, n), np.array([v[0], rng.uniform(0, 5)])
        z, hist = z0.copy(), hist0.copy()
        plays = _native.rdpi_sat_plays(alpha, beta, sat, lam, dt, z, hist, v)
        # the same plays written as rows (the diagnosis' layout), state updated alike
        zr, hr = z0.copy(), hist0.copy()
        rows = _native.rdpi_sat_plays(alpha, beta, sat, lam, dt, zr, hr, v, rows=True)
        assert rows.shape == (n, N) and rows.flags.c_contiguous
        np.testing.assert_array_equal(rows, plays.T)
        assert np.array_equal(zr, z) and np.array_equal(hr, hist)
        for i in range(n):
            zi, hi = z0[i:i + 1].copy(), hist0.copy()
            ref = _native.rdpi_sat_run(np.ones(1), alpha[i:i + 1].copy(), beta, sat, lam, dt,
                                       zi, hi, v)
            np.testing.assert_array_equal(plays[:, i], ref)
            assert zi[0] == z[i] and np.array_equal(hi, hist)


@pytest.mark.parametrize("seed", range(4))
def test_joint_branch_statistics_equal_reference(seed):
    """``pim_joint_select`` picks exactly the reference's samples, ``branch_shape`` on the hinge
    matrix of ``pim_joint_hinges`` equals the reference's to the bit, ``pim_joint_add`` bins
    them exactly as the reference does, with and without forgetting (its sum of squares to
    1e-12)."""
    from pimodel import _native
    from pimodel.identification.adaptive.joint import branch_shape
    from pimodel.reference.joint import (
        branch_shape_reference,
        joint_add_reference,
        joint_select_reference,
    )

    rng = np.random.default_rng(seed)
    N, n, bins = int(rng.integers(2, 6000)), int(rng.integers(1, 9)), int(rng.integers(40, 3000))
    v = np.cumsum(rng.normal(0, 0.1, N))
    y = rng.normal(0, 5, N)
    span = float(np.ptp(np.abs(v - v[0])))
    for s, keep, travel in ((1.0, span, span), (-1.0, 0.7 * span, 0.4 * span),
                            (1.0, 0.3 * span, 2 * span)):
        x, Y, outside = _native.joint_select(v, y, s, keep, travel)
        xr, Yr, outside_r = joint_select_reference(v, y, s, keep, travel)
        assert np.array_equal(x, xr) and np.array_equal(Y, Yr) and outside == outside_r
        if x.size < 1:
            continue
        w, r = rng.uniform(0, 2, n), np.sort(rng.uniform(0, 0.6 * travel, n))
        g = branch_shape(x, w, r)
        assert np.array_equal(g, branch_shape_reference(x, w, r))
        nan = x.copy()
        nan[::7] = np.nan  # a NaN travel gives a NaN shape, as numpy's maximum does
        np.testing.assert_array_equal(branch_shape(nan, w, r), branch_shape_reference(nan, w, r))
        e = Y - g
        c = float(np.mean(e))
        for forgetting in (1.0, float(rng.uniform(0.5, 1.0))):
            stats = np.abs(rng.normal(0, 3, (3, bins)))
            ref = stats.copy()
            sse = _native.joint_add(x, Y, e, c, stats, travel, forgetting)
            sse_r = joint_add_reference(x, Y, e, c, ref, travel, forgetting)
            assert np.array_equal(stats, ref)
            assert sse == pytest.approx(sse_r, rel=1e-12, abs=1e-12)


def _joint_records():
    from pimodel.signals import biased_staircase, sinusoid

    p, r = np.array([0.3, 0.5, 0.8, 0.3, 0.2]), np.array([0.4, 1.0, 1.5, 2.0, 3.6])
    _, s = biased_staircase(20, 5, step=0.25, hold=0.005, fs=1000, duration=24)
    ys = PIOperator(p, r).simulate(s) + np.random.default_rng(5).normal(0, 0.2, s.size)
    yield s, ys, 5, {"refit_every": 5, "threshold": 0.1}
    yield s, ys, 5, {"refit_every": 4, "threshold": 0.1, "forgetting": 0.97,
                     "initial_weights": np.ones(5), "initial_radii": [1.0, 2.0, 3.0, 4.0, 5.0]}
    p2, r2 = np.array([1.0, 0.6, 0.4]), np.array([0.0, 0.5, 1.2])
    _, v2 = sinusoid(5, 1, fs=1000, duration=6)
    y2 = PIOperator(p2, r2).simulate(v2) + np.random.default_rng(6).normal(0, 0.01, v2.size)
    yield v2, y2, 3, {"linear_play": True, "bins": 500, "refit_every": 3}


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_joint_estimator_on_the_core_equals_it_on_the_reference(monkeypatch):
    """The joint estimator with its per-branch statistics in C (``pim_joint.h``) gives the
    estimate it gives with the NumPy reference (the implementation before the C core): every
    update's weights and radii to the bit, the same updates and counts, the fit RMS (a sum of
    squares in another order) to 1e-12."""
    from pimodel import _native, estimate_jointly
    from pimodel.identification.adaptive import joint
    from pimodel.reference import joint as reference

    for v, y, n, options in _joint_records():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            core = estimate_jointly(v, y, n, **options)
            with monkeypatch.context() as m:
                m.setattr(_native, "joint_select", reference.joint_select_reference)
                m.setattr(_native, "joint_add", reference.joint_add_reference)
                m.setattr(joint, "branch_shape", reference.branch_shape_reference)
                ref = estimate_jointly(v, y, n, **options)
        assert core.update_index.size >= 3
        assert np.array_equal(core.update_index, ref.update_index)
        assert (core.branches_used, core.samples_used, core.samples_outside) == \
            (ref.branches_used, ref.samples_used, ref.samples_outside)
        assert np.array_equal(core.weight_history, ref.weight_history)
        assert np.array_equal(core.radius_history, ref.radius_history)
        assert core.fit_rms == pytest.approx(ref.fit_rms, rel=1e-12)
