"""An amplifier's first-order bandwidth of 20-120 Hz before the hysteresis (bw49, issue 28's
blind check): the Wiener low-pass also in the form sampled at the end of each hold
(``"lowpass_direct"``, ``x[k] = a x[k-1] + (1 - a) v[k]``) and with corners below 50 Hz. The
stage here is written independently of the candidate library: SciPy's ``lfilter`` of that
difference equation, then the PI stage of ``pimodel.stages.pi_stage``."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from pimodel import Record
from pimodel.diagnosis import diagnose
from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.wiener import inverse_prefilter, prefilter
from pimodel.stages.pi_stage import excitation, random_truth

DT = 1e-4


def _amplifier(v, fc, dt=DT):
    """``u[k] = a u[k-1] + (1 - a) v[k]``, ``a = exp(-2 pi fc dt)``, at rest at ``v[0]``."""
    a = np.exp(-2 * np.pi * fc * dt)
    return lfilter([1 - a], [1, -a], v, zi=[a * v[0]])[0]


def test_lowpass_direct_is_the_low_pass_sampled_at_the_end_of_the_hold():
    t = np.arange(3000) * DT
    v = 0.3 + np.sin(2 * np.pi * 30 * t) + (t > 0.1)
    tau = 1 / (2 * np.pi * 35.0)
    x = prefilter(v, [("lowpass_direct", tau)], DT)
    assert np.max(np.abs(x - _amplifier(v, 35.0))) < 1e-9
    # the ZOH low-pass advanced one sample
    assert np.max(np.abs(x[:-1] - prefilter(v, [("lowpass", tau)], DT)[1:])) < 1e-9


def test_lowpass_direct_inverse_and_stream():
    from pimodel.diagnosis.native_model import stream_simulate

    tau = 1 / (2 * np.pi * 80.0)
    t = np.arange(20000) * DT
    v = np.sin(2 * np.pi * 3 * t) + 0.3 * np.sin(2 * np.pi * 11 * t)
    v_hat = inverse_prefilter(prefilter(v, [("lowpass_direct", tau)], DT),
                              [("lowpass_direct", tau)], DT)
    # what is left is the phase of the inverse's low-pass at 160 Hz: about 4 degrees at 11 Hz
    assert np.max(np.abs(v_hat - v)[:-2]) < 0.05
    m = DiagnosedModel([0.0, 0.2, 0.5], [2.0, 0.6, 0.3], 0.1, dt=DT, effects=("dynamics",),
                       params={"dynamics_position": "before",
                               "wiener_elements": [["lowpass_direct", tau]]})
    assert np.max(np.abs(stream_simulate(m, v[:3000]) - m.simulate(v[:3000]))) < 1e-12


def _records(fc: float, seed: int):
    truth = random_truth([], seed)
    tt, vt = excitation("train", seed=2 * seed + 1)
    tv, vv = excitation("validate", seed=2 * seed + 2)
    tv = tv + tt[-1] + 1.0
    return [[Record(t, v, truth.simulate(t, _amplifier(v, fc), np.random.default_rng(s)),
                    source=name)]
            for t, v, s, name in ((tt, vt, seed, "train"), (tv, vv, 100 + seed, "validate"))]


@pytest.mark.slow
@pytest.mark.parametrize("fc,seed", [(30.0, 0), (90.0, 1)])
def test_amplifier_bandwidth_sampled_at_the_end_of_the_hold_is_dynamics(fc, seed):
    train, validate = _records(fc, seed)
    v = diagnose(train, validate).verdict
    assert v["effects"] == ["dynamics"] and v["shrink"] >= 0.5
    m = v["model"]
    assert m["dynamics_position"] == "before"
    assert abs(m["lowpass_hz"] / fc - 1) < 0.2
