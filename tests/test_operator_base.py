"""The streaming-state contract the operator classes share (pimodel/operators/base.py): stepping
equals simulating, simulate leaves the streaming state alone, reset restores it, a failed step
changes nothing, parameters are read-only copies, and each class documents its own members."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel import PIOperator
from pimodel.operators.asymmetric import AsymmetricPI
from pimodel.operators.creep import CreepOperator
from pimodel.operators.envelopes import Envelope
from pimodel.operators.generalized import GeneralizedPI
from pimodel.operators.rate_dependent import RateDependentPI

FORWARD = {
    "PIOperator": lambda: PIOperator([1.0, 0.5, 0.3], [0.0, 0.2, 0.5], initial_state=0.1),
    "GeneralizedPI": lambda: GeneralizedPI([1.0, 0.5], [0.0, 0.2],
                                           input_envelope=Envelope.tanh(2.0, 0.5),
                                           initial_state=[0.1, -0.1]),
    "AsymmetricPI": lambda: AsymmetricPI(0.5, [1.0, 0.6], [0.0, 0.3], ascending=(1.0, 0.0),
                                         descending=(1.3, 0.2), shape=Envelope.tanh(1.0, 0.4),
                                         initial_state=[0.05, -0.1]),
    "RateDependentPI": lambda: RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01,
                                               dt=1e-3, initial_state=0.1, initial_input=0.2),
    "CreepOperator": lambda: CreepOperator([0.05, 0.03], [0.01, 0.2], dt=1e-3,
                                           initial_state=[0.1, 0.2]),
}
OPERATORS = {**FORWARD, **{f"{k}.inverse": (lambda mk=mk: mk().inverse())
                           for k, mk in FORWARD.items()}}
V = 0.8 * np.sin(np.linspace(0.0, 9.0, 40))


@pytest.mark.parametrize("name", OPERATORS)
def test_streaming_contract(name):
    op = OPERATORS[name]()
    start = op.state
    y = op.simulate(V)
    np.testing.assert_array_equal(op.state, start)  # simulate leaves the streaming state
    stepped = np.array([op.step(float(vk)) for vk in V])
    np.testing.assert_allclose(stepped, y, rtol=0, atol=1e-12)
    y_half, z_half = op.simulate(V[:20], return_state=True)
    np.testing.assert_allclose(op.simulate(V[20:], state=z_half), y[20:], rtol=0, atol=1e-12)
    assert not np.array_equal(op.state, start)
    op.reset()
    np.testing.assert_array_equal(op.state, start)
    op.state = z_half  # the setter takes what simulate returned
    np.testing.assert_array_equal(op.state, z_half)
    with pytest.raises(ValueError, match="state: expected"):
        op.state = np.zeros(7)


@pytest.mark.parametrize("name", ["GeneralizedPI", "AsymmetricPI"])
def test_a_failed_step_leaves_the_state(name):
    """A sample outside an envelope's domain (tanh saturates) raises and moves nothing."""
    op = FORWARD[name]()
    inv = op.inverse()
    inv.step(0.3)
    before = inv.state
    with pytest.raises(ValueError, match="y_d: sample 0|v: sample 0"):
        inv.step(50.0)
    np.testing.assert_array_equal(inv.state, before)


@pytest.mark.parametrize("name", FORWARD)
def test_parameters_are_read_only_copies(name):
    op = FORWARD[name]()
    names = ["weights", "radii", "base_radii", "gains", "time_constants", "initial_state"]
    if name == "RateDependentPI":
        names.remove("initial_state")  # a new array per call (plays, v[-1], rate)
    arrays = [getattr(op, a) for a in names if hasattr(op, a)]
    assert len(arrays) >= 2
    for arr in arrays:
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 1.0


def test_the_callers_arrays_stay_writeable():
    gains, taus = np.array([0.05, 0.03]), np.array([0.01, 0.2])
    CreepOperator(gains, taus, dt=1e-3)
    gains[0] = 0.06  # raised "read-only" before: the operator froze the caller's array
    taus[0] = 0.02


@pytest.mark.parametrize("cls", [PIOperator, GeneralizedPI, AsymmetricPI, RateDependentPI,
                                 CreepOperator])
def test_each_class_documents_its_own_members(cls):
    """The shared properties are made in each class (autodoc lists no inherited members)."""
    own = vars(cls)
    for member in ("state", "reset", "step", "simulate", "__repr__"):
        assert member in own, member
        doc = getattr(cls, member).__doc__
        assert member == "__repr__" or (doc and doc.strip()), member
    params = [m for m in ("weights", "radii", "base_radii", "gains", "n", "m") if m in own]
    assert len(params) >= 2
    assert all(isinstance(own[m], property) and own[m].__doc__ for m in params)
