"""python-control blocks of the generalized, rate-dependent and creep operators: equal to the
operators (C core) to 1e-12 through plain ``control.input_output_response``, params change
settings without rebuilding, 1-based state labels, inverse feedforward in series."""

from __future__ import annotations

import control
import numpy as np
import pytest

from pimodel.blocks.operators import (
    asymmetric_pi_block,
    block_initial_state,
    creep_block,
    generalized_pi_block,
    rate_dependent_inverse_block,
    rate_dependent_pi_block,
)
from pimodel.operators.asymmetric import AsymmetricPI
from pimodel.operators.creep import CreepOperator
from pimodel.operators.envelopes import Envelope
from pimodel.operators.generalized import GeneralizedPI
from pimodel.operators.rate_dependent import RateDependentPI

DT = 1e-3
T = np.arange(400) * DT
V = 1.5 * np.sin(2 * np.pi * 3 * T) + 0.3 * np.sin(2 * np.pi * 17 * T)

GPI = GeneralizedPI([1.0, 0.5, 0.3], [0.0, 0.2, 0.6], input_envelope=Envelope.tanh(3, 0.4, 0.1),
                    output_envelope=Envelope.poly2(0.1, 1.0, 0.05), initial_state=0.2)
RDPI = RateDependentPI([1.0, 0.5, 0.3], [0.0, 0.2, 0.6], rate_gain=2e-4, dt=DT,
                       rate_time_constant=2e-3, initial_state=0.1, initial_input=0.05)
ASYM = AsymmetricPI(0.4, [1.0, 0.5], [0.1, 0.4], ascending=(1.0, 0.0), descending=(1.4, 0.2),
                    shape=Envelope.tanh(3, 0.3), initial_state=0.1)
CREEP = CreepOperator([0.03, 0.02], [0.01, 0.2], dt=DT, initial_state=0.3)


def _response(sys, u, params=None):
    res = control.input_output_response(sys, T[:len(u)], u,
                                        initial_state=block_initial_state(sys, params),
                                        params=params)
    return res.outputs


@pytest.mark.parametrize(("block", "op"), [
    (generalized_pi_block(GPI, DT), GPI),
    (generalized_pi_block(GPI.inverse(), DT, name="inv", input="y_d", output="v"),
     GPI.inverse()),
    (rate_dependent_pi_block(RDPI), RDPI),
    (asymmetric_pi_block(ASYM, DT), ASYM),
    (asymmetric_pi_block(ASYM, DT, inverse=True), ASYM.inverse()),
    (creep_block(CREEP), CREEP),
    (creep_block(CREEP.inverse()), CREEP.inverse()),
])
def test_block_equals_operator(block, op):
    np.testing.assert_allclose(_response(block, V), op.simulate(V), rtol=0, atol=1e-12)


def test_rate_dependent_inverse_block_equals_inverse():
    blk = rate_dependent_inverse_block(RDPI)
    yd = RDPI.simulate(V)
    np.testing.assert_allclose(_response(blk, yd), RDPI.inverse().simulate(yd), atol=1e-12)
    np.testing.assert_allclose(_response(blk, yd), V, atol=1e-9)


def test_state_labels_and_params():
    blk = rate_dependent_pi_block(RDPI, name="plant")
    assert blk.state_labels == ["z[1]", "z[2]", "z[3]", "v_prev", "rate"]
    assert sorted(blk.params) == sorted(f"plant.{k}" for k in (
        "weights", "base_radii", "rate_gain", "rate_time_constant", "initial_state",
        "initial_input"))
    assert creep_block(CREEP).state_labels == ["x[1]", "x[2]"]
    assert generalized_pi_block(GPI, DT).state_labels == ["z[1]", "z[2]", "z[3]"]
    # a changed setting is used without rebuilding, and equals the operator built with it
    other = RateDependentPI(RDPI.weights, RDPI.base_radii, rate_gain=5e-4, dt=DT,
                            rate_time_constant=2e-3, initial_state=0.1, initial_input=0.05)
    np.testing.assert_allclose(_response(blk, V, {"plant.rate_gain": 5e-4}), other.simulate(V),
                               atol=1e-12)
    g2 = Envelope.poly2(0.0, 1.0, 0.02)
    gblk = generalized_pi_block(GPI, DT, name="g")
    want = GeneralizedPI(GPI.weights, GPI.radii, input_envelope=GPI.input_envelope,
                         output_envelope=g2, initial_state=0.2).simulate(V)
    np.testing.assert_allclose(_response(gblk, V, {"g.output_envelope": g2}), want, atol=1e-12)
    with pytest.raises(ValueError, match=r"unknown setting\(s\) \['plant.beta'\]"):
        _response(blk, V, {"plant.beta": 1.0})
    with pytest.raises(ValueError, match="block 'creep'.*zero of modulus"):
        _response(creep_block(CREEP), V, {"creep.gains": [30.0, 30.0]})


def test_feedforward_in_series_cancels_the_operator():
    """inverse block -> operator block (interconnected by signal names) tracks y_d exactly."""
    yd = 0.8 * np.sin(2 * np.pi * 2 * T)
    ff = creep_block(CREEP.inverse(), name="ff", input="y_d", output="u")
    plant = creep_block(CREEP, name="plant", input="u", output="y")
    loop = control.interconnect([ff, plant], inplist=["y_d"], outlist=["y"])
    x0 = np.concatenate((block_initial_state(ff), block_initial_state(plant)))
    res = control.input_output_response(loop, T, yd, initial_state=x0)
    np.testing.assert_allclose(res.outputs, yd, atol=1e-12)


def test_block_errors():
    with pytest.raises(TypeError, match="op: expected a GeneralizedPI"):
        generalized_pi_block(RDPI, DT)
    with pytest.raises(TypeError, match="op: expected a RateDependentPI"):
        rate_dependent_pi_block(GPI)
    with pytest.raises(TypeError, match="op: expected a CreepOperator"):
        creep_block(GPI)
    with pytest.raises(ValueError, match="smallest base radius"):
        rate_dependent_inverse_block(RateDependentPI([1.0], [0.1], rate_gain=0.0, dt=DT))
    with pytest.raises(TypeError, match="sys: expected a block of pimodel.blocks.operators"):
        block_initial_state(control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], DT))
