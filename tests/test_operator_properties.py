"""Property tests (hypothesis) of the play and PI operators and the exact inverse."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pimodel import PIOperator, play_reference

finite = st.floats(-50, 50, allow_nan=False, allow_infinity=False)
signals = st.lists(finite, min_size=1, max_size=200).map(np.array)
radius = st.floats(0, 10, allow_nan=False)


@st.composite
def operators(draw, linear_play: bool = False, max_n: int = 8, min_gap: float = 0.0):
    """Random PI operators; ``min_gap`` > 0 keeps radii (and r_1 from 0) that far apart."""
    n = draw(st.integers(1, max_n))
    p = np.array(draw(st.lists(st.floats(0.01, 5), min_size=n, max_size=n)))
    if min_gap > 0:
        gaps = draw(st.lists(st.floats(min_gap, 2), min_size=n, max_size=n))
        r = np.cumsum(gaps)
    else:
        r = np.sort(np.array(draw(st.lists(st.floats(0, 8), min_size=n, max_size=n))))
    if linear_play:
        r[0] = 0.0
    return PIOperator(p, r)


def play(v, r, x=0.0):
    return PIOperator([1.0], [r], initial_state=x).simulate(v)


@given(signals, radius, finite)
def test_play_output_within_band(v, r, x):
    z = play(v, r, x)
    assert np.all(z >= v - r - 1e-12) and np.all(z <= v + r + 1e-12)


@given(signals, radius, finite)
def test_play_equals_reference(v, r, x):
    np.testing.assert_allclose(play(v, r, x), play_reference(v, r, x), rtol=0, atol=1e-12)


@given(st.lists(st.tuples(finite, finite), min_size=1, max_size=150), radius)
def test_play_lipschitz_in_input(pairs, r):
    """Eq. (3): |Gamma_r[v1] - Gamma_r[v2]|(t) <= max_s<=t |v1 - v2|(s)."""
    v1, v2 = (np.array(a) for a in zip(*pairs, strict=True))
    d = np.abs(play(v1, r) - play(v2, r))
    assert np.all(d <= np.maximum.accumulate(np.abs(v1 - v2)) + 1e-9)


@given(signals, radius, radius)
def test_play_lipschitz_in_radius(v, r1, r2):
    assert np.all(np.abs(play(v, r1) - play(v, r2)) <= abs(r1 - r2) + 1e-9)


@given(operators(), signals, st.data())
def test_rate_independence(op, v, data):
    """Repeating samples (a hold, or a slower time scale) does not change the output sequence."""
    reps = np.array(data.draw(st.lists(st.integers(1, 4), min_size=len(v), max_size=len(v))))
    y = op.simulate(v)
    y_slow = op.simulate(np.repeat(v, reps))
    np.testing.assert_allclose(y_slow, np.repeat(y, reps), atol=1e-9)


@given(operators(), signals, signals)
def test_reparametrised_monotone_segments(op, v, extra):
    """Inserting intermediate points on a monotone segment leaves the samples unchanged."""
    v = np.concatenate(([0.0], v))
    fine = [v[0]]
    for a, b in zip(v[:-1], v[1:], strict=True):
        fine.extend(np.linspace(a, b, 4)[1:])
    fine = np.array(fine)
    np.testing.assert_allclose(op.simulate(fine)[3::3], op.simulate(v)[1:], atol=1e-9)


@given(operators(), st.floats(1, 20), st.floats(0.05, 0.95))
def test_return_point_memory(op, amp, frac_down):
    """After a minor loop that returns to its start point, the output continues as if the minor
    loop had not happened (wiping-out / return-point memory of the PI operator)."""
    top = amp
    low = top - frac_down * 2 * amp
    ramp = np.linspace(-amp, top, 200)
    minor = np.concatenate((np.linspace(top, low, 50)[1:], np.linspace(low, top, 50)[1:]))
    after = np.linspace(top, -amp, 200)[1:]
    with_minor = np.concatenate((ramp, minor, after))
    without = np.concatenate((ramp, after))
    y1 = op.simulate(with_minor)
    y2 = op.simulate(without)
    np.testing.assert_allclose(y1[-len(after):], y2[-len(after):], atol=1e-9)


@settings(max_examples=40)
@given(operators(max_n=6, min_gap=0.1), st.booleans())
def test_lemma1_slopes_on_large_periodic_input(op, linear):
    if linear:
        op = PIOperator(op.weights, np.concatenate(([0.0], op.radii[1:])))
    amp = 2 * op.radii[-1] + 1.0
    v = np.concatenate((np.linspace(0, amp, 400), np.linspace(amp, -amp, 4000),
                        np.linspace(-amp, amp, 4000)))
    y = op.simulate(v)
    asc = slice(4400, None)
    slopes = np.diff(y[asc]) / np.diff(v[asc])
    expected = op.slopes()
    # every observed slope is one of Lemma 1's values, and every value is observed
    dist = np.min(np.abs(slopes[:, None] - expected[None, :]), axis=1)
    # a segment that straddles a breakpoint mixes two slopes; allow those few
    assert np.mean(dist < 1e-6) > 0.99
    for s in expected:
        assert np.any(np.abs(slopes - s) < 1e-6), f"slope {s} not observed"


@given(operators())
def test_lemma2_loop_width(op):
    """rho = 2 sum p r / sum p equals the largest horizontal loop width of the major loop."""
    amp = 2 * op.radii[-1] + 1.0
    up = np.linspace(-amp, amp, 2001)
    down = up[::-1]
    v = np.concatenate((np.linspace(0, -amp, 500), up, down, up))
    y = op.simulate(v)
    y_up = y[-len(up):]
    y_down = y[500 + len(up): 500 + 2 * len(up)][::-1]  # descending branch on the up grid
    grid = np.linspace(max(y_up.min(), y_down.min()), min(y_up.max(), y_down.max()), 400)
    v_up = np.interp(grid, y_up, up)
    v_down = np.interp(grid, y_down, up)
    width = np.max(v_up - v_down)
    rho = op.loop_width()
    assert abs(width - rho) <= 1e-6 + 2 * (up[1] - up[0])
    assert 2 * op.radii[0] - 1e-12 <= rho <= 2 * op.radii[-1] + 1e-12
    if op.radii[-1] > 0:
        assert 2 * op.radii[-1] < op.weights.sum() / op.weights[-1] * rho + 1e-9


@given(operators(linear_play=True), signals, finite)
def test_inverse_cancels_operator(op, v, x):
    op = PIOperator(op.weights, op.radii, initial_state=x)
    np.testing.assert_allclose(op.inverse().simulate(op.simulate(v)), v, rtol=0, atol=1e-10)


@given(operators(linear_play=True), signals)
def test_operator_cancels_inverse(op, yd):
    np.testing.assert_allclose(op.simulate(op.inverse().simulate(yd)), yd, rtol=0, atol=1e-9)


@given(operators(linear_play=True, min_gap=0.01))
def test_double_inverse_is_identity(op):
    back = op.inverse().inverse()
    np.testing.assert_allclose(back.weights, op.weights, rtol=1e-10)
    np.testing.assert_allclose(back.radii, op.radii, rtol=1e-10, atol=1e-12)


@given(operators(linear_play=True), signals)
def test_double_inverse_same_operator_with_equal_radii(op, v):
    """With repeated radii the parameters may regroup, but the operator is the same."""
    np.testing.assert_allclose(op.inverse().inverse().simulate(v), op.simulate(v), atol=1e-8)
