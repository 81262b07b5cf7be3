"""Property tests (hypothesis) of the generalized, rate-dependent and creep operators: exact
round trips, monotonicity, rate (in)dependence, wiping-out memory, Lipschitz bounds."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pimodel import PIOperator
from pimodel.operators.creep import CreepOperator
from pimodel.operators.envelopes import Envelope
from pimodel.operators.generalized import GeneralizedPI
from pimodel.operators.rate_dependent import RateDependentPI

V_MAX = 5.0
finite = st.floats(-V_MAX, V_MAX, allow_nan=False, allow_infinity=False)
signals = st.lists(finite, min_size=1, max_size=150).map(np.array)


@st.composite
def pi_parts(draw, max_n: int = 6, linear_play: bool = True):
    n = draw(st.integers(1, max_n))
    p = np.array(draw(st.lists(st.floats(0.05, 3), min_size=n, max_size=n))) / n
    r = np.sort(np.array(draw(st.lists(st.floats(0, 2), min_size=n, max_size=n))))
    if linear_play:
        r[0] = 0.0
    return p, r


@st.composite
def input_envelopes(draw):
    """tanh (kept off deep saturation on |v| <= V_MAX) or an increasing quadratic."""
    if draw(st.booleans()):
        a1 = draw(st.floats(0.05, 0.6))
        a2 = draw(st.floats(-0.8, 0.8))
        return Envelope.tanh(draw(st.floats(0.5, 4)), a1, a2, draw(st.floats(-1, 1)))
    c1 = draw(st.floats(0.3, 3))
    c2 = draw(st.floats(-0.9, 0.9)) * c1 / (2 * V_MAX)  # c1 + 2 c2 v > 0 on |v| <= V_MAX
    return Envelope.poly2(draw(st.floats(-1, 1)), c1, c2)


@st.composite
def generalized(draw):
    p, r = draw(pi_parts())
    h = draw(input_envelopes())
    # |h(v)| <= H on the input range, so |sum p z| <= P (H + r_n): the output quadratic
    # stays increasing there
    H = float(np.max(np.abs(h.reference(np.array([-V_MAX, V_MAX]))))) + 5.0
    W = p.sum() * (H + r[-1]) + 1.0
    c1 = draw(st.floats(0.3, 3))
    g = Envelope.poly2(draw(st.floats(-1, 1)), c1, draw(st.floats(-0.9, 0.9)) * c1 / (2 * W))
    return GeneralizedPI(p, r, input_envelope=h, output_envelope=g)


def _slope_bound(env: Envelope, lo: float, hi: float) -> float:
    x = np.linspace(lo, hi, 2001)
    return float(np.max(np.diff(env.reference(x)) / np.diff(x))) * 1.01 + 1e-12


# -- GeneralizedPI ---------------------------------------------------------------------------

@given(generalized(), signals)
def test_generalized_round_trip(op, v):
    np.testing.assert_allclose(op.inverse().simulate(op.simulate(v)), v, rtol=0, atol=1e-9)


@given(generalized(), signals)
def test_generalized_inverse_of_inverse_is_operator(op, v):
    np.testing.assert_allclose(op.inverse().inverse().simulate(v), op.simulate(v), atol=1e-9)


@given(generalized(), signals)
def test_generalized_monotone(op, v):
    """Increasing envelopes and positive weights: an increasing input gives a non-decreasing
    output (each play is a monotone operator)."""
    y = op.simulate(np.sort(v))
    assert np.all(np.diff(y) >= -1e-12 * max(1.0, float(np.max(np.abs(y)))))


@given(generalized(), signals, st.data())
def test_generalized_rate_independent(op, v, data):
    reps = np.array(data.draw(st.lists(st.integers(1, 4), min_size=len(v), max_size=len(v))))
    np.testing.assert_allclose(op.simulate(np.repeat(v, reps)), np.repeat(op.simulate(v), reps),
                               atol=1e-12)


def assert_wiping_out(op, amp, frac_down):
    """A minor loop that returns to its start point leaves no trace (return-point memory)."""
    low = amp - frac_down * 2 * amp
    ramp = np.linspace(-amp, amp, 150)
    minor = np.concatenate((np.linspace(amp, low, 40)[1:], np.linspace(low, amp, 40)[1:]))
    after = np.linspace(amp, -amp, 150)[1:]
    y1 = op.simulate(np.concatenate((ramp, minor, after)))
    y2 = op.simulate(np.concatenate((ramp, after)))
    np.testing.assert_allclose(y1[-len(after):], y2[-len(after):], atol=1e-9)


@given(generalized(), st.floats(1, V_MAX), st.floats(0.05, 0.95))
def test_generalized_wiping_out(op, amp, frac_down):
    assert_wiping_out(op, amp, frac_down)


@given(generalized(), st.lists(st.tuples(finite, finite), min_size=1, max_size=100))
def test_generalized_lipschitz(op, pairs):
    """|y1 - y2|[k] <= L_g P L_h max_{j<=k} |v1 - v2|[j] (play eq. 3 through the envelopes)."""
    v1, v2 = (np.array(a) for a in zip(*pairs, strict=True))
    L_h = _slope_bound(op.input_envelope, -V_MAX, V_MAX)
    u = op.input_envelope.reference(np.array([-V_MAX, V_MAX]))
    w_lo = op.weights.sum() * (min(u.min(), 0) - op.radii[-1])
    w_hi = op.weights.sum() * (max(u.max(), 0) + op.radii[-1])
    L_g = _slope_bound(op.output_envelope, w_lo, w_hi)
    bound = L_g * op.weights.sum() * L_h * np.maximum.accumulate(np.abs(v1 - v2))
    assert np.all(np.abs(op.simulate(v1) - op.simulate(v2)) <= bound + 1e-9)


@given(pi_parts(linear_play=False), signals)
def test_generalized_with_identity_envelopes_is_pi(parts, v):
    p, r = parts
    np.testing.assert_allclose(GeneralizedPI(p, r).simulate(v), PIOperator(p, r).simulate(v),
                               atol=1e-12)


# -- RateDependentPI -------------------------------------------------------------------------

@st.composite
def rate_dependent(draw):
    p, r = draw(pi_parts())
    dt = draw(st.sampled_from([1e-4, 1e-3]))
    tau = draw(st.sampled_from([0.0, 3 * dt, 20 * dt]))
    op = RateDependentPI(p, r, rate_gain=1.0, dt=dt, rate_time_constant=tau)
    # keep the rounding-error gain below 0.9 (module docstring): the inverse is exact there
    kappa_per_beta = op.rate_sensitivity
    beta = min(draw(st.floats(0, 0.9)) / kappa_per_beta, 10.0) if kappa_per_beta > 0 else 1.0
    return RateDependentPI(p, r, rate_gain=beta, dt=dt, rate_time_constant=tau)


@given(rate_dependent(), signals)
def test_rate_dependent_round_trip(op, v):
    assert op.rate_sensitivity < 1
    np.testing.assert_allclose(op.inverse().simulate(op.simulate(v)), v, rtol=0, atol=1e-9)


@given(rate_dependent(), signals)
def test_rate_dependent_inverse_cancels_operator_from_the_other_side(op, yd):
    # the forward operator applied to the inverse's output gives y_d back
    np.testing.assert_allclose(op.simulate(op.inverse().simulate(yd)), yd, atol=1e-9)


@given(pi_parts(linear_play=False), signals)
def test_rate_dependent_without_rate_gain_is_pi(parts, v):
    p, r = parts
    op = RateDependentPI(p, r, rate_gain=0.0, dt=1e-3)
    np.testing.assert_allclose(op.simulate(v), PIOperator(p, r).simulate(v), atol=1e-12)


@settings(max_examples=50)
@given(pi_parts(), st.floats(1e-4, 5e-3), st.floats(0.5, 3), st.integers(5, 60))
def test_rate_dependent_constant_rate_is_pi_with_scaled_radii(parts, beta, amp, half):
    """A triangle wave at constant rate, started in motion (``v[-1] = -step``, ``rate[0] =
    step / dt``), is the PI operator with radii alpha (1 + beta rate)."""
    p, r = parts
    dt = 1e-3
    step = amp / half
    leg = np.arange(half + 1) * step
    v = np.concatenate((leg, amp - leg[1:], -leg[1:], -amp + leg[1:]))
    op = RateDependentPI(p, r, rate_gain=beta, dt=dt)
    pi = PIOperator(p, op.radii_at_rate(step / dt))
    moving = np.concatenate((np.zeros(len(p)), [-step, step / dt]))
    np.testing.assert_allclose(op.simulate(v, state=moving), pi.simulate(v), atol=1e-9)
    # and the loops widen with the rate: slower triangle = narrower radii
    assert np.all(op.radii_at_rate(step / dt) >= r)


# -- CreepOperator ---------------------------------------------------------------------------

@st.composite
def creeps(draw):
    m = draw(st.integers(1, 5))
    dt = draw(st.sampled_from([1e-4, 1e-3]))
    tau = np.array(draw(st.lists(st.floats(2 * dt, 50.0), min_size=m, max_size=m)))
    c = np.array(draw(st.lists(st.floats(0.0, 0.2), min_size=m, max_size=m)))
    return CreepOperator(c, tau, dt=dt)


creep_signals = st.lists(st.floats(-50, 50, allow_nan=False), min_size=1, max_size=300).map(
    np.array)


@given(creeps(), creep_signals)
def test_creep_round_trip(cr, u):
    np.testing.assert_allclose(cr.inverse().simulate(cr.simulate(u)), u, rtol=0, atol=1e-9)
    np.testing.assert_allclose(cr.simulate(cr.inverse().simulate(u)), u, rtol=0, atol=1e-9)


@given(creeps())
def test_creep_inverse_is_stable_and_minimum_phase(cr):
    a = cr.poles
    assert np.sum(cr.gains * (1 - a) / (1 + a)) < 1  # the closed-form condition (docstring)
    assert np.max(np.abs(cr.zeros())) < 1
    np.testing.assert_allclose(np.sort(np.abs(np.linalg.eigvals(cr.inverse().state_space()[0]))),
                               np.sort(np.abs(cr.zeros())), atol=1e-12)


@given(creeps(), st.floats(-5, 5))
def test_creep_step_creeps_monotonically_to_static_gain(cr, h):
    """Positive gains: a held step rises (in magnitude) monotonically toward (1 + sum c) h."""
    n = int(20 * cr.time_constants.max() / cr.dt) + 1
    y = cr.simulate(np.full(min(n, 200000), h))
    assert y[0] == h
    assert np.all(np.diff(y) * np.sign(h) >= -1e-12)
    assert abs(y[-1]) <= abs(cr.static_gain() * h) + 1e-12
    if n <= 200000:
        assert abs(y[-1] - cr.static_gain() * h) <= 1e-6 * max(1.0, abs(h))


@given(creeps(), creep_signals, st.floats(-3, 3))
def test_creep_is_linear(cr, u, a):
    np.testing.assert_allclose(cr.simulate(a * u + 1.0), a * cr.simulate(u) + cr.simulate(
        np.ones_like(u)), atol=1e-9 * max(1.0, float(np.max(np.abs(u)))))


# -- AsymmetricPI (distinct ascending/descending envelopes) ---------------------------------

@st.composite
def asymmetric(draw):
    from pimodel.operators.asymmetric import AsymmetricPI

    p, r = draw(pi_parts(linear_play=False))
    shape = draw(st.sampled_from([None, Envelope.tanh(3.0, 0.3, 0.2), Envelope.poly2(0, 1, 0.05)]))
    env = st.tuples(st.floats(0.2, 3), st.floats(-1, 1))
    return AsymmetricPI(draw(st.floats(0.02, 2)), p, r, ascending=draw(env),
                        descending=draw(env), shape=shape,
                        initial_state=draw(st.floats(-2, 2)))


@given(asymmetric(), signals)
def test_asymmetric_round_trip(op, v):
    np.testing.assert_allclose(op.inverse().simulate(op.simulate(v)), v, rtol=0, atol=1e-9)


@given(asymmetric(), signals)
def test_asymmetric_monotone_and_rate_independent(op, v):
    y = op.simulate(np.sort(v))
    assert np.all(np.diff(y) >= -1e-12 * max(1.0, float(np.max(np.abs(y)))))
    reps = np.arange(len(v)) % 3 + 1
    np.testing.assert_allclose(op.simulate(np.repeat(v, reps)), np.repeat(op.simulate(v), reps),
                               atol=1e-12)


@given(asymmetric(), st.floats(1, V_MAX), st.floats(0.05, 0.95))
def test_asymmetric_wiping_out(op, amp, frac_down):
    assert_wiping_out(op, amp, frac_down)


@given(pi_parts(linear_play=False), st.floats(0.05, 2), signals)
def test_asymmetric_with_equal_envelopes_is_generalized_pi(parts, p0, v):
    from pimodel.operators.asymmetric import AsymmetricPI

    p, r = parts
    shape = Envelope.tanh(2.0, 0.3)
    asym = AsymmetricPI(p0, p, r, shape=shape)
    gpi = GeneralizedPI(np.concatenate(([p0], p)), np.concatenate(([0.0], r)),
                        input_envelope=shape)
    np.testing.assert_allclose(asym.simulate(v), gpi.simulate(v), atol=1e-12)
