"""``DiagnosedInverse.block()`` (issue 19): the causal feedforward as a python-control block.

It equals ``DiagnosedInverse.simulate`` delayed by its latency ``A`` (the samples the batch
prefilter reads ahead: one for the dynamics' approximate inverse, the delay's whole samples and
one more for a fractional delay) to 1e-9; its per-sample solver equals the batch solver; and
``inverse.block() -> model.block()`` in ``control.interconnect`` tracks the reference delayed by
``A`` with the batch's tracking error. The same for a filter before the hysteresis (a Wiener
model: the filter's inverse after the solver, one more sample of latency)."""

from __future__ import annotations

import control
import numpy as np
import pytest

from pimodel.blocks import initial_state
from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.reference_inverse import StaticInverse, inverse_latency, solve_static

DT = 1e-3
RADII = [0.0, 0.15, 0.4, 0.7, 1.0]
PARAMS = {
    "creep": {"creep_lag_gains": [0.04, 0.02], "creep_time_constants_s": [0.003, 0.03]},
    "asymmetry": {"asymmetry_quadratic": 0.04, "asymmetry_cubic": 0.01, "center": 0.4,
                  "half_range": 1.5},
    "rate": {"rate_gains": [0.2, 0.1], "rate_family": "radius", "rate_time_constant_s": 0.0},
    "dynamics": {"mode_hz": 40.0, "mode_damping": 0.3, "lti_elements": [["mode", 130.0, 0.1]],
                 "lti_gains": [0.2]},
    "delay": {"delay_samples": 2.5},
}
STATIC_CASES = {"nominal": {}, "creep": {}, "asymmetry": {}, "creep_asymmetry": {},
                "rate_radius": {}, "rate_weight_filtered": {"rate_family": "weight",
                                                            "rate_time_constant_s": 3e-3}}


def model(effects, **extra) -> DiagnosedModel:
    params = {"rate_scale": 5.0}
    for e in effects:
        params.update(PARAMS[e])
    params.update(extra)
    return DiagnosedModel(RADII, [1.0, 0.3, 0.25, 0.2, 0.1], 0.1, dt=DT, effects=tuple(effects),
                          reference_weights=[0.9, 0.3, 0.3, 0.2, 0.1], reference_offset=0.05,
                          params=params)


def reference(m: DiagnosedModel, n: int = 700, rest: int = 12) -> np.ndarray:
    """A reachable reference: the model's output for an input at rest over its first ``rest``
    samples, with minor loops."""
    t = np.arange(n) * DT
    v = 0.8 * np.sin(2 * np.pi * 2.0 * t) + 0.2 * np.sin(2 * np.pi * 9.0 * t)
    v[:rest] = 0.0
    v[rest:] = v[rest:] - v[rest]
    return m.simulate(v, input_range=2 * RADII[-1])


@pytest.mark.parametrize("case", list(STATIC_CASES))
def test_per_sample_solver_resumes_from_its_state_and_inverts(case):
    """The batch inverse is this solver run over the record: a run stopped, its state copied
    and resumed gives the same input, and where the inverse is exact (not rate) the model
    maps it back onto the reference."""
    effects = {"nominal": (), "creep_asymmetry": ("creep", "asymmetry"),
               "rate_radius": ("rate",), "rate_weight_filtered": ("rate",)}.get(case, (case,))
    m = model(effects, **STATIC_CASES[case])
    y_d = reference(m)
    rng = 2 * RADII[-1]
    want = solve_static(m, y_d, rng)
    inv = StaticInverse(m, rng, float(np.ptp(y_d)))
    x = inv.initial_state()
    half = y_d.size // 2
    first = [inv.step(x, y) for y in y_d[:half]]
    resumed = StaticInverse(m, rng, float(np.ptp(y_d)))
    x2 = x.copy()
    got = np.array(first + [resumed.step(x2, y) for y in y_d[half:]])
    assert np.max(np.abs(got - want)) < 1e-12
    if "rate" not in effects:
        assert np.max(np.abs(m.simulate(got, input_range=rng) - y_d)) < 1e-9
    assert inv.labels()[:3] == ["started", "v_prev", "guess"] and len(inv.labels()) == inv.size


@pytest.mark.parametrize(("effects", "extra", "latency"), [
    ((), {}, 0), (("creep",), {}, 0), (("dynamics",), {}, 1),
    (("dynamics",), {"lti_elements": [["direct"]], "lti_gains": [0.1]}, 0),
    (("delay",), {"delay_samples": 3}, 3), (("delay",), {}, 3),
    (("dynamics", "delay"), {}, 4)])
def test_latency_is_the_batch_prefilters_advance(effects, extra, latency):
    assert inverse_latency(model(effects, **extra)) == latency


@pytest.mark.parametrize("effects", [("dynamics", "delay", "creep"), ("delay",),
                                     ("dynamics", "asymmetry"), ("creep", "rate")],
                         ids=lambda e: "+".join(e))
def test_block_equals_simulate_delayed_by_its_latency(effects):
    m = model(effects)
    inv = m.inverse()
    y_d = reference(m)
    want = inv.simulate(y_d)
    blk = inv.block(reference_range=float(np.ptp(inv.prefilter(y_d))))
    a = blk.latency
    assert a == inverse_latency(m)
    t = np.arange(y_d.size) * DT
    res = control.input_output_response(blk, t, y_d, initial_state=initial_state(blk))
    v = res.outputs
    assert np.max(np.abs(v[a:] - want[:y_d.size - a])) < 1e-9
    assert np.all(v[:a] == v[0]) and abs(v[0] - want[0]) < 1e-9  # at rest before
    assert np.ptp(want) > 0.5


def test_inverse_block_then_model_block_tracks_as_the_batch():
    """control.interconnect(inverse.block -> model.block): the tracking error against the
    reference delayed by the latency equals the batch error (simulate, then the model)."""
    m = model(("dynamics", "delay", "creep"))
    inv = m.inverse()
    y_d = reference(m)
    v_batch = inv.simulate(y_d)
    e_batch = m.simulate(v_batch, input_range=2 * RADII[-1]) - y_d
    ff = inv.block(reference_range=float(np.ptp(inv.prefilter(y_d))))
    loop = control.interconnect([ff, m.block()], inputs=["y_d"], outputs=["y", "v"])
    t = np.arange(y_d.size) * DT
    res = control.input_output_response(loop, t, y_d, initial_state=initial_state(loop))
    a = ff.latency
    e_loop = res.outputs[0][a:] - y_d[:y_d.size - a]
    assert np.max(np.abs(e_loop - e_batch[:y_d.size - a])) < 1e-9
    assert np.sqrt(np.mean(e_batch**2)) < 0.1 * np.ptp(y_d)  # it does track


def test_block_errors():
    m = model(("dynamics",))
    with pytest.raises(ValueError, match="dt: 0.002 differs"):
        m.inverse().block(2e-3)
    with pytest.raises(ValueError, match="reference_range: expected a finite value >= 0"):
        m.inverse().block(reference_range=-1.0)
    inv = StaticInverse(model(("rate",), **STATIC_CASES["rate_radius"]))
    with pytest.raises(ValueError, match=r"z0: expected 5 finite play outputs, got shape \(4,\)"):
        inv.initial_state(np.zeros(4))
    with pytest.raises(ValueError, match="z0: expected 5 finite play outputs"):
        inv.initial_state([0.0, np.nan, 0.0, 0.0, 0.0])
    x = inv.initial_state([0.0, -0.1, -0.2, 0.0, 0.0])  # the rate source starts there too
    assert x[3:8].tolist() == [0.0, -0.1, -0.2, 0.0, 0.0]
    assert x[inv.size - inv.source.size:][3:8].tolist() == [0.0, -0.1, -0.2, 0.0, 0.0]


WIENER = {"lowpass": [["lowpass", 1 / (2 * np.pi * 60.0)]],
          "mode": [["mode", 90.0, 0.4]],
          "lowpass+mode": [["lowpass", 1 / (2 * np.pi * 150.0)], ["mode", 90.0, 1.2]],
          "lowpass_direct": [["lowpass_direct", 1 / (2 * np.pi * 60.0)]]}


def wiener_model(elements, effects=()) -> DiagnosedModel:
    """A Wiener model (filter before the plays) with further effects of ``PARAMS``."""
    params = {"rate_scale": 5.0, "dynamics_position": "before", "wiener_elements": elements}
    for e in effects:
        params.update(PARAMS[e])
    return DiagnosedModel(RADII, [1.0, 0.3, 0.25, 0.2, 0.1], 0.1, dt=DT,
                          effects=("dynamics", *effects),
                          reference_weights=[0.9, 0.3, 0.3, 0.2, 0.1], reference_offset=0.05,
                          params=params)


@pytest.mark.parametrize(("kind", "effects", "latency"), [
    ("lowpass", (), 1), ("lowpass_direct", ("creep",), 1), ("mode", ("creep",), 1),
    ("lowpass+mode", ("delay",), 4), ("mode", ("delay", "asymmetry"), 4)],
    ids=lambda x: "+".join(x) if isinstance(x, tuple) else str(x))
def test_wiener_block_equals_simulate_delayed_by_its_latency(kind, effects, latency):
    """The solver gives the filter's output, the inverse filter's sections the input; the
    batch's one-sample advance of that filter is one more sample of latency."""
    m = wiener_model(WIENER[kind], effects)
    inv = m.inverse()
    y_d = reference(m)
    want = inv.simulate(y_d)
    blk = inv.block(reference_range=float(np.ptp(inv.prefilter(y_d))))
    a = blk.latency
    assert a == inverse_latency(m) == latency
    t = np.arange(y_d.size) * DT
    res = control.input_output_response(blk, t, y_d, initial_state=initial_state(blk))
    v = res.outputs
    assert np.max(np.abs(v[a:] - want[:y_d.size - a])) < 1e-9
    assert np.all(v[:a] == v[0]) and abs(v[0] - want[0]) < 1e-9  # at rest before
    assert np.ptp(want) > 0.5
    assert len(blk.state_labels) == blk.nstates and "g[1]" in blk.state_labels


def test_wiener_inverse_block_then_model_block_tracks_as_the_batch():
    """control.interconnect(inverse.block -> model.block) of a Wiener model (both on their
    streams): the error against the reference delayed by the latency is the batch error, and
    the approximate inverse of the 90 Hz mode tracks a 2 Hz reference within 5 % of its
    range."""
    m = wiener_model(WIENER["mode"], ("creep",))
    inv = m.inverse()
    y_d = reference(m)
    v_batch = inv.simulate(y_d)
    e_batch = m.simulate(v_batch, input_range=2 * RADII[-1]) - y_d
    ff = inv.block(reference_range=float(np.ptp(inv.prefilter(y_d))))
    loop = control.interconnect([ff, m.block()], inputs=["y_d"], outputs=["y", "v"])
    t = np.arange(y_d.size) * DT
    res = control.input_output_response(loop, t, y_d, initial_state=initial_state(loop))
    a = ff.latency
    e_loop = res.outputs[0][a:] - y_d[:y_d.size - a]
    assert np.max(np.abs(e_loop - e_batch[:y_d.size - a])) < 1e-9
    assert np.sqrt(np.mean(e_batch**2)) < 0.05 * np.ptp(y_d)


@pytest.mark.parametrize("tau", [1e-3, 4e-3, 1e-2])
def test_strong_filtered_rate_inverse_stays_bounded(tau):
    """A filtered radius-family rate with strong gains: the exact inverse is unstable, and the
    solved input's rate fed back to the rate filter made the feedforward diverge (v up to 180
    for inputs within 1.2). With that feedback capped at RATE_FEEDBACK_CAP times the fresh
    rate it stays within the span of the input that made the reference."""
    from pimodel.diagnosis.reference_inverse import RATE_FEEDBACK_CAP

    assert RATE_FEEDBACK_CAP == 2.0
    m = DiagnosedModel([0.0, 0.1, 0.3, 0.6, 0.9, 1.2], [0.9, 0.35, 0.3, 0.2, 0.15, 0.1], 0.05,
                       dt=DT, effects=("rate",), params={
                           "rate_scale": 8.0, "rate_gains": [0.15, 0.05], "rate_family": "radius",
                           "rate_time_constant_s": tau})
    t = np.arange(600) * DT
    v_true = 0.9 * np.sin(2 * np.pi * 2.5 * t) + 0.25 * np.sin(2 * np.pi * 11.0 * t + 0.4)
    v_true[:10] = 0.0
    v_true[10:] -= v_true[10]
    y_d = m.simulate(v_true, input_range=2.4)
    v = m.inverse().simulate(y_d)
    assert np.max(np.abs(v)) < 2 * np.max(np.abs(v_true))
    assert np.sqrt(np.mean((m.simulate(v, input_range=2.4) - y_d) ** 2)) < 0.5 * np.ptp(y_d)


def test_unknown_start_memory_of_a_folding_model_is_that_of_its_projection():
    """A folding model is solved through its nearest monotone model; its start memory comes
    from that model too, so the stage is taken to sit at y_d[0] with the input 0: the first
    input is 0 (from the fitted model's memory it was 0.02 off)."""
    from pimodel.diagnosis.monotone import is_monotone, monotone_model

    m = DiagnosedModel([0.0, 0.1, 0.3, 0.6, 0.9, 1.2], [0.5, -0.6, 0.5, 0.3, 0.2, 0.1], 0.05,
                       dt=DT)
    assert not is_monotone(m.weights)
    projected = monotone_model(m)
    t = np.arange(400) * DT
    v_true = 0.9 * np.sin(2 * np.pi * 2.5 * t)
    y_d = m.simulate(v_true) - 0.3  # the stage does not rest at the model's output at rest
    inv = m.inverse()
    z0 = inv.initial_memory(float(y_d[0]))
    assert abs(projected.simulate(np.zeros(2))[0] - y_d[0]) > 0.1  # the memory matters
    v = inv.simulate(y_d, initial_state="unknown")
    assert abs(v[0]) < 1e-9 and np.max(np.abs(z0)) > 0.1
    # the projected model, from that memory at the input 0, puts out y_d[0]
    h = np.clip(z0, -projected.radii, projected.radii) @ projected.weights + projected.offset
    assert abs(h - y_d[0]) < 1e-9
