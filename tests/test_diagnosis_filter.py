"""The C core's biquad (``fmu/src/pim_filter.c``), the diagnosis' hot loop for the dynamics
candidate, held equal to its NumPy/SciPy reference: ``scipy.signal.lfilter`` started with
``lfilter_zi`` around each signal's first sample."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter, lfilter_zi

from pimodel._native import biquad_rows, biquad_rows_carry
from pimodel.diagnosis.effects import mode, mode_coefficients, mode_rows
from pimodel.diagnosis.lti import element_coefficients


def _reference(b, a, x):
    return lfilter(b, a, x, axis=-1, zi=lfilter_zi(b, a)[None, :] * x[:, :1])[0]


@pytest.mark.parametrize("element", [("mode", 300.0, 0.02), ("mode", 2500.0, 0.2),
                                     ("mode", 40.0, 1.5), ("lowpass", 3e-4)])
@pytest.mark.parametrize("rows", [1, 4, 7])  # the four-lane loop and the rest
def test_biquad_rows_equals_lfilter(element, rows):
    rng = np.random.default_rng(rows)
    x = np.cumsum(rng.normal(size=(rows, 3000)), axis=1) + rng.normal(size=(rows, 1)) * 5
    b, a = element_coefficients(element, 1e-4)
    ref = _reference(b, a, x)
    got = biquad_rows(b, a, x)
    assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(np.abs(ref))


@pytest.mark.parametrize("element", [("mode", 300.0, 0.02), ("lowpass", 3e-4)])
@pytest.mark.parametrize("rows", [1, 7])
def test_biquad_rows_carry_on_chunks_equals_the_whole_rows_to_the_bit(element, rows):
    """The chunks of rows filtered in turn, the state carried (the whole-record refit's
    streamed columns, pimodel.diagnosis.streamed), give the whole rows' bits."""
    rng = np.random.default_rng(rows)
    x = np.cumsum(rng.normal(size=(rows, 5000)), axis=1) + 3.0
    b, a = element_coefficients(element, 1e-4)
    state, parts = None, []
    for lo, hi in ((0, 1), (1, 1700), (1700, 1703), (1703, 5000)):
        y, state = biquad_rows_carry(b, a, x[:, lo:hi], state)
        parts.append(y)
        assert state.shape == (rows, 2)
    assert np.array_equal(np.concatenate(parts, axis=1), biquad_rows(b, a, x))


def test_constant_rows_pass_at_the_static_gain():
    b, a = mode_coefficients(500.0, 0.1, 1e-4)
    x = np.array([[2.0] * 50, [-3.0] * 50])
    assert np.allclose(biquad_rows(b, a, x), x, rtol=0, atol=1e-12)


def test_mode_helpers_use_it_on_rows_and_columns():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(400, 3))
    b, a = mode_coefficients(800.0, 0.05, 1e-4)
    ref = _reference(b, a, np.ascontiguousarray(x.T))
    assert np.max(np.abs(mode_rows(np.ascontiguousarray(x.T), 800.0, 0.05, 1e-4) - ref)) < 1e-12
    assert np.max(np.abs(mode(x, 800.0, 0.05, 1e-4) - ref.T)) < 1e-12
    assert np.max(np.abs(mode(x[:, 0], 800.0, 0.05, 1e-4) - ref[0])) < 1e-12


def test_lag_from_a_known_start_and_its_argument_check():
    """``lag(..., start=s)``: the lag's state before the first sample is ``s`` (its free
    response decays from there); equal to the default when ``s = x[0]``; 2-D ``x`` refused."""
    from pimodel.diagnosis.filters import lag

    x = np.sin(np.arange(50) * 0.3)
    np.testing.assert_array_equal(lag(x, 0.01, 1e-3, start=float(x[0])), lag(x, 0.01, 1e-3))
    a = np.exp(-1e-3 / 0.01)
    free = lag(x, 0.01, 1e-3, start=2.0) - lag(x, 0.01, 1e-3, start=0.0)
    np.testing.assert_allclose(free, 2.0 * a ** np.arange(1, 51), rtol=1e-12, atol=1e-15)
    with pytest.raises(ValueError, match="start: given for a 1-D signal only"):
        lag(np.zeros((5, 2)), 0.01, 1e-3, start=0.0)
