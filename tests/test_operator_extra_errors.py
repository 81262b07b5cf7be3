"""Bad input to the generalized, rate-dependent and creep operators gives clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel.operators.creep import CreepOperator
from pimodel.operators.envelopes import Envelope
from pimodel.operators.generalized import GeneralizedPI
from pimodel.operators.rate_dependent import RateDependentPI


@pytest.mark.parametrize(
    ("kind", "coefficients", "match"),
    [
        ("cubic", (0, 1, 0), "kind: expected one of"),
        ("tanh", (1, 1, 0), "coefficients: expected 4 values, got 3"),
        ("tanh", (-1, 1, 0, 0), "c0 \\(tanh amplitude\\) must be > 0"),
        ("tanh", (1, 0, 0, 0), "c1 \\(tanh input gain\\) must be > 0"),
        ("poly2", (0, 0, 0), "c1 must be > 0 when c2 == 0"),
        ("poly2", (0, np.nan, 0), "coefficients: sample 1 is nan"),
    ],
)
def test_bad_envelopes(kind, coefficients, match):
    with pytest.raises(ValueError, match=match):
        Envelope(kind, coefficients)


def test_envelope_domain_errors_name_the_sample():
    with pytest.raises(ValueError, match="x: sample 2 is 30.0, outside the domain"):
        Envelope.poly2(0, 1, -0.02)([0.0, 1.0, 30.0])
    with pytest.raises(ValueError, match="x: sample 0 is 2.5, outside the domain"):
        Envelope.tanh(2, 1).inverse()([2.5])


def test_generalized_errors():
    op = GeneralizedPI([1.0, 0.5], [0.0, 0.2], input_envelope=Envelope.poly2(0, 1, -0.05))
    with pytest.raises(ValueError, match="v: sample 1 \\(20.0\\) leaves the domain"):
        op.simulate([0.0, 20.0])
    with pytest.raises(ValueError, match="v: sample 0 is nan"):
        op.simulate([np.nan])
    with pytest.raises(TypeError, match="input_envelope: expected a "
                       "pimodel.operators.envelopes.Envelope"):
        GeneralizedPI([1.0], [0.0], input_envelope=np.tanh)
    with pytest.raises(ValueError, match=r"radii: radius 2 \(counted from 1\) is -0.1"):
        GeneralizedPI([1.0, 1.0], [0.0, -0.1])
    with pytest.raises(ValueError, match="smallest radius is 0.1"):
        GeneralizedPI([1.0], [0.1]).inverse()
    inv = GeneralizedPI([1.0], [0.0], output_envelope=Envelope.tanh(1.0, 1.0)).inverse()
    with pytest.raises(ValueError, match="v: sample 0 \\(1.5\\) leaves the domain"):
        inv.simulate([1.5])  # beyond the saturation level: no input reaches it


def test_rate_dependent_errors():
    with pytest.raises(ValueError, match="rate_gain: expected a finite number >= 0"):
        RateDependentPI([1.0], [0.0], rate_gain=-1.0, dt=1e-3)
    with pytest.raises(ValueError, match="dt: expected a finite number > 0"):
        RateDependentPI([1.0], [0.0], rate_gain=1.0, dt=0)
    with pytest.raises(ValueError, match="rate_time_constant: expected a finite number >= 0"):
        RateDependentPI([1.0], [0.0], rate_gain=1.0, dt=1e-3, rate_time_constant=np.inf)
    with pytest.raises(ValueError, match="smallest base radius is 0.2"):
        RateDependentPI([1.0], [0.2], rate_gain=1.0, dt=1e-3).inverse()
    op = RateDependentPI([1.0, 1.0], [0.0, 0.3], rate_gain=1e-3, dt=1e-3)
    with pytest.raises(ValueError, match="state: expected 4 finite values"):
        op.state = [0.0, 0.0]
    with pytest.raises(ValueError, match="y_d: sample 1 is inf"):
        op.inverse().simulate([0.0, np.inf])


def test_creep_errors():
    with pytest.raises(ValueError, match="time_constants: tau\\[2\\] is 0.0"):
        CreepOperator([0.1, 0.1], [1.0, 0.0], dt=1e-3)
    with pytest.raises(ValueError, match="time_constants: expected 2 values, got 1"):
        CreepOperator([0.1, 0.1], [1.0], dt=1e-3)
    with pytest.raises(ValueError, match=r"zero of modulus 1\.5.*\(not minimum phase\)"):
        CreepOperator([3.0], [1e-4], dt=1e-4)
    with pytest.raises(ValueError, match="initial_state: expected a scalar or 2 values"):
        CreepOperator([0.1, 0.1], [1.0, 2.0], dt=1e-3, initial_state=[1, 2, 3])


def test_fit_errors():
    from pimodel.identification.extended_operators import (
        fit_creep,
        fit_generalized,
        fit_rate_dependent,
    )

    v = np.sin(np.linspace(0, 10, 200))
    with pytest.raises(ValueError, match="v and y: expected equal lengths, got 200 and 199"):
        fit_generalized(v, v[:-1])
    with pytest.raises(ValueError, match="v: the input is constant"):
        fit_generalized(np.ones(50), np.ones(50))
    with pytest.raises(ValueError, match="input_envelope: expected 'tanh' or 'identity'"):
        fit_generalized(v, v, input_envelope="sigmoid")
    with pytest.raises(ValueError, match="n_plays: expected an integer from 2 to 64"):
        fit_generalized(v, v, n_plays=1)
    with pytest.raises(ValueError, match="records: expected at least one"):
        fit_rate_dependent([], dt=1e-3)
    with pytest.raises(ValueError, match=r"y\[1\]: sample 3 is nan"):
        bad = v.copy()
        bad[3] = np.nan
        fit_rate_dependent([(v, v), (v, bad)], dt=1e-3)
    with pytest.raises(ValueError, match="u: expected at least 10 sample"):
        fit_creep(v[:9], v[:9], dt=1e-3)
    with pytest.raises(ValueError, match=r"time_constants: tau\[1\] is -1.0; expected > 0"):
        fit_creep(v, v, dt=1e-3, time_constants=[-1.0])


def test_asymmetric_errors():
    from pimodel.operators.asymmetric import AsymmetricPI

    with pytest.raises(ValueError, match="direct_weight: expected a finite number > 0"):
        AsymmetricPI(0.0, [1.0], [0.1])
    with pytest.raises(ValueError, match="ascending slope a_l: expected a finite number > 0"):
        AsymmetricPI(1.0, [1.0], [0.1], ascending=(-1.0, 0.0))
    with pytest.raises(ValueError, match="descending: expected 2 values"):
        AsymmetricPI(1.0, [1.0], [0.1], descending=(1.0,))
    with pytest.raises(ValueError, match="weights: weight 2 is negative"):
        AsymmetricPI(1.0, [1.0, -1.0], [0.1, 0.2])
    with pytest.raises(TypeError, match="shape: expected a pimodel.operators.envelopes.Envelope"):
        AsymmetricPI(1.0, [1.0], [0.1], shape=np.tanh)
    op = AsymmetricPI(1.0, [0.5], [0.1], shape=Envelope.tanh(1.0, 1.0))
    # the output saturates at p0 + 0.5 (1 + 0.1) = 1.55: a larger y_d has no input
    with pytest.raises(ValueError, match="y_d: sample 1 \\(2.0\\) has no input"):
        op.inverse().simulate([0.0, 2.0])


def test_to_dict_is_json_and_rebuilds_the_operator():
    import json

    from pimodel.operators.asymmetric import AsymmetricPI

    v = np.sin(np.linspace(0, 9, 300)) * 2
    gpi = GeneralizedPI([1.0, 0.5], [0.0, 0.3], input_envelope=Envelope.tanh(3, 0.3))
    d = json.loads(json.dumps(gpi.to_dict()))
    again = GeneralizedPI(d["weights"], d["radii"], initial_state=d["initial_state"],
                          input_envelope=Envelope(**d["input_envelope"]),
                          output_envelope=Envelope(**d["output_envelope"]))
    np.testing.assert_array_equal(again.simulate(v), gpi.simulate(v))
    rd = RateDependentPI([1.0, 0.5], [0.0, 0.3], rate_gain=1e-3, dt=1e-3)
    d = json.loads(json.dumps(rd.to_dict()))
    d.pop("type")
    again = RateDependentPI(d.pop("weights"), d.pop("base_radii"), **d)
    np.testing.assert_array_equal(again.simulate(v), rd.simulate(v))
    asym = AsymmetricPI(0.5, [1.0], [0.2], descending=(1.5, 0.1), shape=Envelope.tanh(2, 0.5))
    d = json.loads(json.dumps(asym.to_dict()))
    again = AsymmetricPI(d["direct_weight"], d["weights"], d["radii"], ascending=d["ascending"],
                         descending=d["descending"], shape=Envelope(**d["shape"]),
                         initial_state=d["initial_state"])
    np.testing.assert_array_equal(again.simulate(v), asym.simulate(v))
    cr = CreepOperator([0.05], [0.1], dt=1e-3)
    d = json.loads(json.dumps(cr.to_dict()))
    again = CreepOperator(d["gains"], d["time_constants"], dt=d["dt"],
                          initial_state=d["initial_state"], inverted=d["inverted"])
    np.testing.assert_array_equal(again.simulate(v), cr.simulate(v))
