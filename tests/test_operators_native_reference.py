"""The C core of the generalized, rate-dependent and creep operators equals the NumPy/SciPy
references of :mod:`pimodel.reference.extended_operators` to 1e-12 (relative to the signal
scale)."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel.operators.creep import CreepOperator
from pimodel.operators.envelopes import Envelope
from pimodel.operators.generalized import GeneralizedPI
from pimodel.operators.rate_dependent import RateDependentPI
from pimodel.reference.extended_operators import (
    creep_inverse_reference,
    creep_reference,
    gpi_reference,
    rdpi_inverse_reference,
    rdpi_reference,
)


def _close(a, b, tol=1e-12):
    assert np.max(np.abs(a - b)) <= tol * max(1.0, float(np.max(np.abs(b))))


ENVELOPES = [
    Envelope.identity(),
    Envelope.tanh(3.0, 0.4, 0.2, -0.5),
    Envelope.poly2(0.1, 1.0, 0.03),
    Envelope.poly2(0.0, 2.0, -0.05),
]


@pytest.mark.parametrize("env", ENVELOPES + [e.inverse() for e in ENVELOPES[1:]])
def test_envelope_equals_reference(env):
    x = np.linspace(-1.9, 1.9, 401)
    np.testing.assert_allclose(env(x), env.reference(x), rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("env", ENVELOPES[1:])
def test_envelope_inverse_is_inverse(env):
    x = np.linspace(-3, 3, 301)
    np.testing.assert_allclose(env.inverse()(env(x)), x, atol=1e-11)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("n", [1, 4, 70])  # 70 > PIM_MAX_PLAYS exercises the general path
def test_generalized_equals_reference(seed, n):
    rng = np.random.default_rng(seed)
    p = rng.uniform(0.1, 2, n) / n
    r = np.sort(rng.uniform(0, 1, n))
    z0 = rng.uniform(-0.5, 0.5, n)
    h, g = Envelope.tanh(2.0, 0.5, 0.1, 0.2), Envelope.poly2(0.0, 1.0, 0.01)
    v = 2 * np.sin(np.linspace(0, 40, 3000)) + rng.normal(0, 0.1, 3000)
    op = GeneralizedPI(p, r, input_envelope=h, output_envelope=g, initial_state=z0)
    _close(op.simulate(v), gpi_reference(v, op.weights, op.radii, h, g, op.initial_state))


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("tau", [0.0, 5e-3])
def test_rate_dependent_equals_reference(seed, tau):
    rng = np.random.default_rng(seed)
    n, dt = 5, 1e-3
    p = rng.uniform(0.2, 2, n)
    a = np.concatenate(([0.0], np.sort(rng.uniform(0.05, 1, n - 1))))
    op = RateDependentPI(p, a, rate_gain=2e-4, dt=dt, rate_time_constant=tau,
                         initial_state=rng.uniform(-0.2, 0.2, n), initial_input=0.1)
    t = np.arange(1500) * dt
    v = 2 * np.sin(2 * np.pi * 3 * t) + rng.normal(0, 0.02, t.size)
    y = op.simulate(v)
    lam = op.rate_decay
    kw = dict(lam=lam, state=op.initial_state[:n], v_prev=0.1, rate=0.0)
    _close(y, rdpi_reference(v, op.weights, op.base_radii, 2e-4, dt, **kw))
    _close(op.inverse().simulate(y),
           rdpi_inverse_reference(y, op.weights, op.base_radii, 2e-4, dt, **kw), tol=1e-11)


@pytest.mark.parametrize("seed", range(4))
def test_creep_equals_reference(seed):
    rng = np.random.default_rng(seed)
    m, dt = 3, 1e-3
    c = rng.uniform(0.01, 0.1, m)
    tau = np.sort(rng.uniform(0.005, 2, m))
    x0 = rng.uniform(-1, 1, m)
    u = np.cumsum(rng.normal(0, 0.1, 5000))
    cr = CreepOperator(c, tau, dt=dt, initial_state=x0)
    y = cr.simulate(u)
    _close(y, creep_reference(u, c, tau, dt, x0))
    y0 = CreepOperator(c, tau, dt=dt).simulate(u[:1500])
    _close(CreepOperator(c, tau, dt=dt).inverse().simulate(y0),
           creep_inverse_reference(y0, c, tau, dt), tol=1e-10)


def test_streaming_equals_batch():
    rng = np.random.default_rng(5)
    v = np.cumsum(rng.normal(0, 0.1, 300))
    ops = [GeneralizedPI([1.0, 0.5], [0.0, 0.3], input_envelope=Envelope.tanh(4.0, 0.3)),
           RateDependentPI([1.0, 0.5], [0.0, 0.3], rate_gain=1e-4, dt=1e-3),
           CreepOperator([0.05], [0.1], dt=1e-3)]
    for op in ops + [op.inverse() for op in ops]:
        batch = op.simulate(v)
        stream = np.array([op.step(x) for x in v])
        np.testing.assert_allclose(stream, batch, rtol=0, atol=1e-12)
        saved = op.state
        a = [op.step(x) for x in v[:20]]
        op.state = saved
        assert [op.step(x) for x in v[:20]] == a
        op.reset()
        np.testing.assert_allclose([op.step(x) for x in v[:5]], batch[:5], atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("shape", [Envelope.identity(), Envelope.tanh(3.0, 0.3, 0.2, 0.1)])
def test_asymmetric_equals_reference(seed, shape):
    from pimodel.operators.asymmetric import AsymmetricPI
    from pimodel.reference.extended_operators import asym_inverse_reference, asym_reference

    rng = np.random.default_rng(seed)
    n = 5
    kw = dict(ascending=(rng.uniform(0.5, 1.5), rng.uniform(-0.3, 0.3)),
              descending=(rng.uniform(0.5, 1.5), rng.uniform(-0.3, 0.3)))
    p, r = rng.uniform(0.1, 1, n), np.sort(rng.uniform(0, 1, n))
    z0 = rng.uniform(-0.5, 0.5, n)
    op = AsymmetricPI(0.4, p, r, shape=shape, initial_state=z0, **kw)
    v = 3 * np.sin(np.linspace(0, 25, 1500)) + rng.normal(0, 0.1, 1500)
    y = op.simulate(v)
    args = (0.4, op.weights, op.radii, kw["ascending"], kw["descending"], shape)
    _close(y, asym_reference(v, *args, state=op.initial_state))
    _close(op.inverse().simulate(y), asym_inverse_reference(y, *args, state=op.initial_state),
           tol=1e-10)
