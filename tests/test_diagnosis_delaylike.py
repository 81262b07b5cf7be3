"""A fitted ``dynamics`` that acts as a pure delay (``pimodel.diagnosis.delaylike``) gives way
to ``delay``: the gain check against an independent frequency response, and the
``pimodel.stages.pi_stage`` delay + drift case whose delay of one sample was named ``dynamics``
(three
fast modes) before the tie-break."""

from __future__ import annotations

import control
import numpy as np
import pytest

from pimodel.diagnosis import diagnose
from pimodel.diagnosis.delaylike import is_delay_like, lti_gain
from pimodel.stages.pi_stage import excitation, random_truth


def test_gain_equals_the_zoh_frequency_response_of_python_control():
    fn, zeta, dt = 1500.0, 0.3, 1e-4
    w = 2 * np.pi * fn
    d = control.sample_system(control.tf([w * w], [1.0, 2 * zeta * w, w * w]), dt, method="zoh")
    f = np.linspace(0.0, 0.25 * 0.5 / dt, 257)[1:]
    ref = np.abs(d(np.exp(2j * np.pi * f * dt)))
    assert np.max(np.abs(lti_gain({"mode_hz": fn, "mode_damping": zeta}, dt) - ref)) < 1e-9


def test_delay_like_is_flat_gain_only():
    dt = 1e-4
    assert is_delay_like({"mode_hz": 4500.0, "mode_damping": 0.6}, dt)
    assert not is_delay_like({"mode_hz": 1500.0, "mode_damping": 0.05}, dt)  # a resonance
    assert not is_delay_like({"mode_hz": 300.0, "mode_damping": 0.7}, dt)  # a roll-off
    # a further mode in parallel that adds a resonance in the band
    assert not is_delay_like({"mode_hz": 4500.0, "mode_damping": 0.6,
                              "lti_elements": [["mode", 900.0, 0.05]], "lti_gains": [0.2]}, dt)
    assert not is_delay_like({"dynamics_position": "before",
                              "wiener_elements": [["lowpass", 1e-5]]}, dt)


@pytest.mark.slow
def test_one_sample_delay_with_drift_is_named_delay():
    seed = 4  # sim_to_real's truth delay + drift case that came back drift + dynamics
    tt, vt = excitation("train", seed=2 * seed + 1)
    tv, vv = excitation("validate", seed=2 * seed + 2)
    tv = tv + tt[-1] + 1.0
    truth = random_truth(["delay", "drift"], seed, drift_clock="record")
    assert abs(truth.delay_s / 1e-4 - 1.0) < 0.05  # a delay of one sample
    v = diagnose([truth.record(tt, vt, seed, "train")],
                 [truth.record(tv, vv, 100 + seed, "validate")]).verdict
    assert sorted(v["effects"]) == ["delay", "drift"] and v["shrink"] >= 0.5
    assert abs(v["model"]["delay_samples"] - 1.0) < 0.1
