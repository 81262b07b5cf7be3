"""python-control blocks, actuator dynamics, compiled loops vs python-control interconnections,
and the compensation comparison."""

from __future__ import annotations

import control
import numpy as np
import pytest

from pimodel import PIOperator
from pimodel.blocks import (
    adaptive_compensator_block,
    estimator_block,
    inverse_pi_block,
    pi_block,
    pid_block,
    radius_estimator,
)
from pimodel.experiments.compensation import STAGE, compensation_table, identified_models, reference
from pimodel.loops.actuators import (
    creep_lags,
    creep_per_decade,
    second_order_mode,
    stage_dynamics,
)
from pimodel.loops.compiled import PID, loop_system, run_loop
from pimodel.loops.simulation import simulate
from pimodel.signals import sinusoid, triangle

DT = 1e-4


def test_pi_block_equals_operator():
    op = PIOperator([1.0, 0.5, 0.25], [0.0, 0.3, 0.8], initial_state=[0.1, 0.0, -0.2])
    t, v = sinusoid(2, 5, fs=1000, duration=1)
    res = simulate(pi_block(op, 1e-3), t, {"v": v})
    np.testing.assert_allclose(res["y"], op.simulate(v), rtol=0, atol=1e-12)
    np.testing.assert_allclose([res[f"z[{i}]"][-1] for i in (1, 2, 3)],
                               op.simulate(v[:-1], return_state=True)[1], atol=1e-12)


def test_exact_inverse_compensation_follows_reference():
    t, yd = sinusoid(8, 3, fs=1000, duration=1)
    sys = control.interconnect([inverse_pi_block(STAGE, 1e-3), pi_block(STAGE, 1e-3, output="y")],
                               inputs=["y_d"], outputs=["y"])
    np.testing.assert_allclose(simulate(sys, t, {"y_d": yd})["y"], yd, atol=1e-9)
    fast = run_loop(yd, STAGE, 1e-3, feedforward=STAGE)
    np.testing.assert_allclose(fast.y, yd, atol=1e-9)


def test_estimator_block_equals_batch_estimator_and_converges():
    t, v = triangle(2, 1, fs=1000, duration=6)
    y = STAGE.simulate(v)
    kw = dict(gains=20.0, initial_radii=[0, 0.3, 0.4, 0.8])
    blk = estimator_block(STAGE.weights, 1e-3, linear_play=True, **kw)
    res = simulate(blk, t, {"v": v, "y": y})
    batch = radius_estimator(STAGE.weights, dt=1e-3, linear_play=True, **kw).run(v, y)
    R = np.column_stack([res[f"r_hat[{i}]"] for i in range(1, 5)])
    np.testing.assert_allclose(R, batch.history, atol=1e-12)
    np.testing.assert_allclose(res["y_hat"], batch.model_output, atol=1e-12)
    err0 = np.max(np.abs(R[0] - STAGE.radii))
    assert np.max(np.abs(R[-1] - STAGE.radii)) < 0.2 * err0


@pytest.mark.parametrize("pid", [None, PID(0.0, 20.0), PID(0.01, 20.0, 1e-6)])
@pytest.mark.parametrize("ff", ["none", "exact"])
def test_compiled_loop_equals_python_control(ff, pid):
    t, yd = sinusoid(8, 20, fs=1 / DT, duration=0.05)
    G = stage_dynamics(DT, fn_hz=1000, damping=0.05)
    feed = STAGE if ff == "exact" else "none"
    fast = run_loop(yd, STAGE, DT, dynamics=G, feedforward=feed, pid=pid)
    ref = simulate(loop_system(STAGE, DT, dynamics=G, feedforward=feed, pid=pid), t, {"y_d": yd})
    np.testing.assert_allclose(fast.y, ref["y"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.v, ref["v"], rtol=0, atol=1e-9)


def test_compiled_adaptive_loop_equals_python_control():
    t, yd = sinusoid(8, 20, fs=1 / DT, duration=0.05)
    kw = dict(gains=20.0, initial_radii=[0, 0.3, 0.4, 0.8], linear_play=True)
    est = radius_estimator(STAGE.weights, dt=DT, **kw)
    fast = run_loop(yd, STAGE, DT, feedforward="adaptive", estimator=est)
    sys = loop_system(STAGE, DT, feedforward="adaptive",
                      estimator_options=dict(weights=STAGE.weights, **kw))
    ref = simulate(sys, t, {"y_d": yd})
    np.testing.assert_allclose(fast.y, ref["y"], rtol=0, atol=1e-9)


def test_adaptive_compensator_reaches_exact_inverse():
    """From wrong radii, the adaptive inverse's tracking error over the last second is within
    a factor 2 of the exact inverse's + 0.01 % of range (both on the static plant)."""
    dt = 1e-3
    t, yd = triangle(8, 1, fs=1 / dt, duration=60)
    est = radius_estimator(STAGE.weights, dt=dt, gains=20.0, initial_radii=[0, 0.4, 0.5, 0.9],
                           linear_play=True)
    adaptive = run_loop(yd, STAGE, dt, feedforward="adaptive", estimator=est)
    wrong = run_loop(yd, STAGE, dt, feedforward=PIOperator(STAGE.weights, [0, 0.4, 0.5, 0.9]))
    last = yd.size - 1000
    a, w = adaptive.tracking(last), wrong.tracking(last)
    assert a["max_percent"] < 0.01 and a["max_percent"] < 0.05 * w["max_percent"]
    np.testing.assert_allclose(adaptive.radii[-1], STAGE.radii, atol=0.01)
    first = adaptive.tracking(0)
    assert first["max_percent"] > 10 * a["max_percent"]  # it did have to adapt


def test_compensation_comparison():
    tab = compensation_table(identified_models())
    for setting in ("static", "mode"):
        none = tab["none (gain)"][setting]
        prop = tab["proposed n=4"][setting]
        assert prop["max"] * 10 <= none["max"] and prop["rms"] * 10 <= none["rms"]
        for n in (4, 7, 10):
            conv = tab[f"conventional n={n}"][setting]
            assert prop["max"] < conv["max"] and prop["rms"] < conv["rms"]
    assert tab["proposed n=4"]["mode+PID"]["max"] < tab["none (gain)"]["mode+PID"]["max"]
    assert tab["proposed n=4"]["mode+PID"]["rms"] < tab["none (gain)"]["mode+PID"]["rms"]


def test_reference_has_minor_loops():
    t, yd = reference(1000)
    assert np.ptp(yd) > 15


def test_actuators():
    G = stage_dynamics(DT, fn_hz=1000, damping=0.05, creep=creep_per_decade(1.5), delay=3e-4)
    assert G.dt == DT and float(G.D[0, 0]) == 0.0
    assert abs(control.dcgain(G) - 1.06) < 1e-9
    step = control.step_response(G, np.arange(0, 0.01, DT)).outputs
    assert np.all(np.abs(np.ravel(step)[:3]) < 1e-12)  # three samples of delay
    assert abs(control.dcgain(second_order_mode(500, 0.1, 2.0)) - 2.0) < 1e-12
    assert abs(control.dcgain(creep_lags([0.01, 0.02], [0.1, 1.0])) - 1.03) < 1e-12


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: second_order_mode(1000, -0.1), "damping: expected a finite number >= 0"),
        (lambda: second_order_mode(0, 0.1), "fn_hz: expected a finite number > 0"),
        (lambda: stage_dynamics(0.0), "dt: expected a finite number > 0"),
        (lambda: stage_dynamics(-1e-4), "dt: expected a finite number > 0"),
        (lambda: creep_lags([0.1], [1.0, 2.0]), "equal non-empty lengths"),
        (lambda: stage_dynamics(DT, delay=-1.0), "delay: expected a finite number >= 0"),
        (lambda: pi_block(STAGE, 0.0), "dt: expected a finite number > 0"),
        (lambda: pid_block(-1.0, dt=DT), "kp: expected a finite number >= 0"),
        (lambda: adaptive_compensator_block([1.0, -1.0], DT), "weights: every weight"),
        (lambda: estimator_block([1.0, 1.0], DT, initial_radii=[0.0]), "initial_radii"),
        (lambda: run_loop([0.0, 1.0], STAGE, DT, pid=PID(1.0)), "pid: feedback needs"),
        (lambda: run_loop([0.0, 1.0], STAGE, DT, dynamics=stage_dynamics(2 * DT)),
         "dynamics: expected a discrete system with dt"),
        (lambda: run_loop([0.0, 1.0], STAGE, DT, feedforward="magic"), "feedforward"),
        (lambda: run_loop([0.0, np.nan], STAGE, DT), "ref: sample 1 is nan"),
    ],
)
def test_bad_parameters(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_simulate_errors():
    blk = pi_block(STAGE, 1e-3)
    with pytest.raises(ValueError, match="t: expected times spaced exactly by dt"):
        simulate(blk, np.array([0.0, 0.002, 0.004]), {"v": np.zeros(3)})
    with pytest.raises(ValueError, match="are not inputs of"):
        simulate(blk, np.arange(3) * 1e-3, {"u": np.zeros(3)})
