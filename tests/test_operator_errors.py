"""Bad input to the operators gives clear errors naming the argument."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel import PIOperator, TimeDependentPI


@pytest.mark.parametrize(
    ("weights", "radii", "match"),
    [
        ([1, 1], [0, -0.1], "radii: radius 2 \\(counted from 1\\) is -0.1"),
        ([1, 1], [0, np.nan], "radii: sample 1 is nan"),
        ([1, 1], [0, np.inf], "radii: sample 1 is inf"),
        ([1, 0], [0, 1], "weights: weight 2 \\(counted from 1\\) is 0"),
        ([1, -2], [0, 1], "weights: weight 2 \\(counted from 1\\) is -2"),
        ([1, 2, 3], [0, 1], "same length, got 3 weights and 2 radii"),
        ([], [], "weights: expected at least 1"),
        ([[1, 2]], [[0, 1]], "expected a 1-D array"),
        (["a"], [0], "weights: expected a 1-D array of numbers"),
    ],
)
def test_bad_parameters(weights, radii, match):
    with pytest.raises(ValueError, match=match):
        PIOperator(weights, radii)


def test_unsorted_radii_are_sorted_with_their_weights_and_state():
    op = PIOperator([3.0, 1.0, 2.0], [1.0, 0.0, 0.5], initial_state=[0.3, 0.1, 0.2])
    np.testing.assert_array_equal(op.radii, [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(op.weights, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(op.initial_state, [0.1, 0.2, 0.3])
    v = np.sin(np.linspace(0, 10, 100))
    same = PIOperator([1.0, 2.0, 3.0], [0.0, 0.5, 1.0], initial_state=[0.1, 0.2, 0.3])
    np.testing.assert_array_equal(op.simulate(v), same.simulate(v))


def test_signed_weights_need_positive_partial_sums():
    PIOperator([1.0, -0.5], [0.0, 1.0], signed_weights=True)
    with pytest.raises(ValueError, match="partial sum p_1\\+...\\+p_2"):
        PIOperator([1.0, -1.5], [0.0, 1.0], signed_weights=True)


def test_input_errors():
    op = PIOperator([1.0], [0.5])
    with pytest.raises(ValueError, match="v: sample 2 is nan"):
        op.simulate([0.0, 1.0, np.nan])
    with pytest.raises(ValueError, match="v: expected at least 1 sample"):
        op.simulate([])
    with pytest.raises(ValueError, match="v: expected a 1-D array"):
        op.simulate(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="v: input sample is nan"):
        op.step(float("nan"))
    with pytest.raises(ValueError, match="initial_state: expected a scalar or 1 values"):
        PIOperator([1.0], [0.5], initial_state=[1.0, 2.0])
    with pytest.raises(ValueError, match="initial_state: expected a scalar or 1 values"):
        op.state = [1.0, 2.0]


def test_inverse_not_invertible():
    with pytest.raises(ValueError, match="smallest radius is 0.1.*linear play"):
        PIOperator([1.0, 1.0], [0.1, 0.5]).inverse()
    assert not PIOperator([1.0, 1.0], [0.1, 0.5]).is_invertible
    assert PIOperator([1.0, 1.0], [0.0, 0.5]).is_invertible


def test_time_dependent_errors():
    tdpi = TimeDependentPI([1.0, 1.0])
    with pytest.raises(ValueError, match=r"radii_per_sample: expected shape \(3, 2\)"):
        tdpi.simulate([0, 1, 2], np.zeros((3, 3)))
    with pytest.raises(ValueError, match="radii_per_sample: every radius must be finite"):
        tdpi.simulate([0, 1, 2], -np.ones((3, 2)))


def test_inverse_whose_weights_overflow_float64_is_refused():
    """Found by the API fuzz in CI: weights of 1e-300 give inverse weights -p_i / (P_i P_(i-1))
    beyond float64; the inverse must say so instead of carrying -inf."""
    op = PIOperator([1e-300] * 4, [0.0, 0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="PIOperator.inverse: not representable in float64"):
        op.inverse()
    with pytest.raises(ValueError, match="PIOperator.inverse: not representable in float64"):
        PIOperator([1e-300] * 4, [0.0] * 4).inverse()
