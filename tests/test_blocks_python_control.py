"""Every block, and the interconnections of the README, driven by plain
``control.input_output_response`` with ``initial_state=pimodel.blocks.initial_state(sys,
params)``: equal to ``pimodel.loops.simulation.simulate`` and to the C core (1e-12), from non-zero
initial states and with non-default params."""

from __future__ import annotations

import doctest
import warnings

import control
import numpy as np
import pytest

import pimodel.blocks.framework
import pimodel.blocks.pi
import pimodel.loops.simulation
from pimodel import PIOperator
from pimodel.blocks import (
    InitialStateWarning,
    adaptive_compensator_block,
    estimator_block,
    initial_state,
    inverse_pi_block,
    pi_block,
    pid_block,
    radius_estimator,
)
from pimodel.loops.actuators import stage_dynamics
from pimodel.loops.compiled import PID, loop_system, run_loop
from pimodel.loops.simulation import simulate
from pimodel.signals import sinusoid, triangle

DT = 1e-4
STAGE = PIOperator([6.3460, 1.6735, 1.1552, 0.4477], [0.0, 0.1945, 0.4826, 0.5707])
TOL = 1e-12


def plain(sys, t, U, params):
    """python-control alone: the documented initial state and params."""
    res = control.input_output_response(sys, t, U, initial_state=initial_state(sys, params),
                                        params=params)
    return np.asarray(res.outputs).reshape(sys.noutputs, -1), res


def close(a, b):
    np.testing.assert_allclose(a, b, rtol=0, atol=TOL)


def test_pi_block_plain_python_control_equals_simulate_and_core():
    op = PIOperator([1.0, 0.5, 0.25], [0.0, 0.3, 0.8], initial_state=[0.4, -0.1, 0.6])
    t, v = sinusoid(2, 5, fs=1000, duration=0.5)
    params = {"plant.weights": [2.0, 0.3, 0.7], "plant.radii": [0.0, 0.2, 0.5],
              "plant.initial_state": [0.3, 0.2, -0.4]}
    blk = pi_block(op, 1e-3, name="plant")
    y, _ = plain(blk, t, v, params)
    core = PIOperator([2.0, 0.3, 0.7], [0.0, 0.2, 0.5], initial_state=[0.3, 0.2, -0.4])
    close(y[0], core.simulate(v))
    close(simulate(blk, t, {"v": v}, params=params)["y"], y[0])
    # without params: the construction values, own initial state 0.1 + ... != 0
    y0, _ = plain(blk, t, v, None)
    close(y0[0], op.simulate(v))
    assert abs(y0[0][0] - PIOperator(op.weights, op.radii).simulate(v)[0]) > 0.05


def test_inverse_block_plain_python_control_equals_core():
    op = PIOperator([1.0, 0.5, 0.25], [0.0, 0.3, 0.8], initial_state=0.3)
    model = PIOperator([1.2, 0.4, 0.3], [0.0, 0.25, 0.6], initial_state=[0.5, 0.1, -0.2])
    t, yd = sinusoid(3, 5, fs=1000, duration=0.5)
    params = {"ff.weights": model.weights, "ff.radii": model.radii,
              "ff.initial_state": model.initial_state}
    blk = inverse_pi_block(op, 1e-3, name="ff")
    v, _ = plain(blk, t, yd, params)
    close(v[0], model.inverse().simulate(yd))
    close(simulate(blk, t, {"y_d": yd}, params=params)["v"], v[0])
    close(model.simulate(v[0]), yd)  # the consistent initial state: PI[PI^-1[y_d]] = y_d


def test_estimator_block_plain_python_control_equals_core():
    t, v = triangle(2, 1, fs=1000, duration=3)
    y = STAGE.simulate(v) + 0.01 * np.sin(50 * t)
    settings = dict(gains=15.0, initial_radii=[0.0, 0.5, 0.6, 0.9], linear_play=True,
                    guard=0.01, slope_window=4, initial_state=0.2)
    blk = estimator_block(STAGE.weights, 1e-3, name="est", gains=5.0, initial_radii=[0, 0.1,
                                                                                        0.2, 0.3])
    params = {f"est.{k}": val for k, val in settings.items()}
    out, res = plain(blk, t, [v, y], params)
    batch = radius_estimator(STAGE.weights, dt=1e-3, **settings).run(v, y)
    close(out[:4].T, batch.history)
    close(out[4], batch.model_output)
    close(out[5], batch.error)
    sim = simulate(blk, t, {"v": v, "y": y}, params=params)
    close(np.column_stack([sim[f"r_hat[{i}]"] for i in range(1, 5)]), batch.history)
    assert np.max(np.abs(batch.radii - STAGE.radii)) < 0.5 * np.max(np.abs(batch.history[0]
                                                                          - STAGE.radii))
    # the documented state layout: the radii first, as labelled
    assert res.state_labels[:4] == [f"r_hat[{i}]" for i in range(1, 5)]
    close(res.states[:4, 1:].T, batch.history[1:])
    if "started" in res.state_labels:  # the layout documented in estimator_block
        assert res.states[res.state_labels.index("started"), -1] == 1.0
        assert res.state_labels[4:6] == ["z_hat[1]", "z_hat[2]"]


def adaptive_reference(w, radii, yd, z0):
    """NumPy/PIOperator spec of the adaptive compensator: inverse rebuilt each sample with the
    state consistent with the forward model's, forward model advanced with v."""
    zm = np.array(z0, float)
    v = np.empty(yd.size)
    for k in range(yd.size):
        model = PIOperator(w, radii[k], initial_state=zm)
        v[k] = model.inverse().simulate([yd[k]])[0]
        _, zm = model.simulate([v[k]], return_state=True)
    return v


def test_adaptive_compensator_plain_python_control_equals_reference():
    t, yd = sinusoid(8, 5, fs=1000, duration=0.3)
    n = 4
    radii = np.column_stack([np.zeros(t.size)] + [r * (1 + 0.06 * np.sin(7 * t + i))
                                                  for i, r in enumerate(STAGE.radii[1:])])
    assert np.all(np.diff(radii, axis=1) >= 0)  # an estimator's radii are ordered
    blk = adaptive_compensator_block(STAGE.weights, 1e-3, name="comp", initial_state=0.1)
    w = STAGE.weights * [1.1, 0.9, 1.2, 0.8]
    params = {"comp.weights": w, "comp.initial_state": [0.3, 0.2, 0.1, -0.1]}
    v, _ = plain(blk, t, np.vstack([yd, radii.T]), params)
    close(v[0], adaptive_reference(w, radii, yd, params["comp.initial_state"]))
    sim = simulate(blk, t, {"y_d": yd, **{f"r_hat[{i + 1}]": radii[:, i] for i in range(n)}},
                   params=params)
    close(sim["v"], v[0])


def test_pid_block_params():
    t = np.arange(50) * 1e-3
    e = np.sin(40 * t)
    blk = pid_block(1.0, 2.0, 0.0, dt=1e-3, name="c")
    params = {"c.kp": 0.5, "c.ki": 30.0, "c.kd": 0.01, "c.tf": 5e-3}
    u, _ = plain(blk, t, e, params)
    integ, d, prev, ref = 0.0, 0.0, 0.0, []
    for ek in e:  # the difference equations of the docstring
        integ += 1e-3 * ek
        d = (5e-3 * d + 0.01 * (ek - prev)) / (5e-3 + 1e-3)
        prev = ek
        ref.append(0.5 * ek + 30.0 * integ + d)
    close(u[0], ref)


def readme_loop(dt, plant, model):
    """The interconnection of the README's python-control section."""
    return control.interconnect(
        [inverse_pi_block(model, dt, input="y_d", output="v"),
         pi_block(plant, dt, input="v", output="h", name="plant"),
         stage_dynamics(dt, fn_hz=1000, damping=0.05, input="h", output="y")],
        inputs=["y_d"], outputs=["y", "v"])


def test_readme_interconnection_equals_simulate_and_compiled_loop():
    t, yd = sinusoid(8, 20, fs=1 / DT, duration=0.05)
    plant = PIOperator(STAGE.weights, STAGE.radii, initial_state=0.2)
    loop = readme_loop(DT, plant, STAGE)
    true = PIOperator(STAGE.weights * 1.05, [0.0, 0.15, 0.5, 0.6],
                      initial_state=[0.3, 0.25, 0.1, 0.0])
    model = PIOperator(STAGE.weights, STAGE.radii, initial_state=0.3)
    params = {"plant.weights": true.weights, "plant.radii": true.radii,
              "plant.initial_state": true.initial_state, "pi_inv.initial_state": 0.3}
    out, _ = plain(loop, t, yd, params)
    fast = run_loop(yd, true, DT, dynamics=stage_dynamics(DT, fn_hz=1000, damping=0.05),
                    feedforward=model)
    close(out[0], fast.y)
    close(out[1], fast.v)
    sim = simulate(loop, t, {"y_d": yd}, params=params)
    close(sim["y"], out[0])
    assert np.max(np.abs(fast.y - yd)) > 0.01  # the model error shows: a real comparison


@pytest.mark.parametrize("ff", ["none", "exact", "adaptive"])
def test_loop_system_plain_python_control_equals_compiled_loop(ff):
    t, yd = sinusoid(8, 20, fs=1 / DT, duration=0.04)
    G = stage_dynamics(DT, fn_hz=1000, damping=0.05)
    plant = PIOperator(STAGE.weights, STAGE.radii, initial_state=[0.2, 0.1, 0.0, -0.1])
    true = PIOperator(STAGE.weights, [0.0, 0.18, 0.5, 0.55], initial_state=[0.3, 0.2, 0.1, 0.0])
    params = {"plant.radii": true.radii, "plant.initial_state": true.initial_state,
              "pid.ki": 40.0, "pid.kp": 0.02}
    kw = {}
    if ff == "adaptive":
        r0 = [0.0, 0.3, 0.4, 0.8]
        kw["estimator_options"] = dict(weights=STAGE.weights, gains=5.0, initial_radii=[0] * 4,
                                       linear_play=True)
        params.update({"est.gains": 20.0, "est.initial_radii": r0, "est.guard": 0.01})
        feed = "adaptive"
        est = radius_estimator(STAGE.weights, dt=DT, gains=20.0, initial_radii=r0,
                               linear_play=True, guard=0.01)
    else:
        feed = STAGE if ff == "exact" else "none"
        est = None
    sys = loop_system(plant, DT, dynamics=G, feedforward=feed, pid=PID(0.0, 20.0), **kw)
    out, _ = plain(sys, t, yd, params)
    fast = run_loop(yd, true, DT, dynamics=G, feedforward=feed, estimator=est,
                    pid=PID(0.02, 40.0))
    close(out[0], fast.y)
    close(out[1], fast.v)
    close(simulate(sys, t, {"y_d": yd}, params=params)["y"], out[0])


def test_initial_state_of_interconnection_by_state_names():
    loop = readme_loop(DT, PIOperator(STAGE.weights, STAGE.radii, initial_state=0.2), STAGE)
    x0 = initial_state(loop, {"plant.initial_state": [0.1, 0.2, 0.3, 0.4]})
    lab = loop.state_labels
    assert [x0[lab.index(f"plant_z[{i}]")] for i in range(1, 5)] == [0.1, 0.2, 0.3, 0.4]
    inv = [x0[lab.index(f"pi_inv_z_inv[{i}]")] for i in range(1, 5)]
    np.testing.assert_allclose(inv, STAGE.inverse().initial_state, atol=1e-15)
    assert not np.any([x0[i] for i, s in enumerate(lab) if s.startswith("sys")])


def test_zero_state_that_is_not_the_blocks_own_warns():
    t = np.arange(5) * 1e-3
    est = estimator_block([1.0, 0.5], 1e-3, initial_radii=[0, 0.3], linear_play=True)
    with pytest.warns(InitialStateWarning, match=r"r_hat\[2\]"):
        control.input_output_response(est, t, [t, t])
    pb = pi_block(PIOperator([1, 0.5], [0, 0.3], initial_state=0.7), 1e-3)
    with pytest.warns(InitialStateWarning, match="initial_state"):
        control.input_output_response(pb, t, 0 * t)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = control.input_output_response(pb, t, 0 * t, initial_state=initial_state(pb))
        assert res.outputs[0] == pytest.approx(0.15, abs=1e-15)  # the example
        res = control.input_output_response(est, t, [t, t], initial_state=initial_state(est))
        assert res.outputs[1][0] == 0.3
        # all zeros is the own state of a block whose initial state is zero: no warning
        control.input_output_response(pi_block(PIOperator([1, 0.5], [0, 0.3]), 1e-3), t, t)


def test_params_changed_in_place_between_runs_are_seen():
    pb = pi_block(PIOperator([1.0, 0.5], [0.0, 0.3]), 1e-3, name="plant")
    t, v = sinusoid(1, 5, fs=1000, duration=0.2)
    radii = np.array([0.0, 0.1])
    params = {"plant.radii": radii}
    first = control.input_output_response(pb, t, v, params=params).outputs
    radii[1] = 0.4  # the same array, changed
    second = control.input_output_response(pb, t, v, params=params).outputs
    close(first, PIOperator([1.0, 0.5], [0.0, 0.1]).simulate(v))
    close(second, PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v))
    with pytest.raises(ValueError, match="read-only"):
        pb.params["plant.radii"][1] = 0.2  # the defaults cannot change behind the block


def test_params_are_checked_by_name():
    pb = pi_block(STAGE, 1e-3, name="plant")
    t = np.arange(3) * 1e-3
    with pytest.raises(ValueError, match=r"unknown setting\(s\) \['plant.radius'\]"):
        control.input_output_response(pb, t, t, params={"plant.radius": [0, 1, 2, 3]})
    with pytest.raises(ValueError, match="block 'plant'.*radius 2 .counted from 1. is -0.1"):
        control.input_output_response(pb, t, t, params={"plant.radii": [0, -0.1, 0.2, 0.3]})
    with pytest.raises(ValueError, match="weights: expected 4 plays"):
        control.input_output_response(pb, t, t, params={"plant.radii": [0, 0.1],
                                                        "plant.weights": [1, 1]})
    with pytest.raises(ValueError, match="unknown estimator setting"):
        estimator_block([1.0], 1e-3, gain=3.0)
    comp = adaptive_compensator_block([1.0, 0.5, 0.2], 1e-3)
    for radii in ([0.1, 0.2, 0.3], [0.0, 0.3, 0.1]):  # r_hat[1] != 0, unordered
        with pytest.raises(ValueError, match=r"not invertible \(need r_hat\[1\] = 0, sorted"):
            control.input_output_response(comp, t, [t, *(r + 0 * t for r in radii)])
    with pytest.raises(ValueError, match="not invertible"):
        inverse_pi_block(PIOperator([1.0, 0.5], [0.1, 0.3]), 1e-3)


def test_deprecated_names_still_work():
    t, v = sinusoid(2, 5, fs=1000, duration=0.05)
    with pytest.warns(DeprecationWarning, match="known_linear_play"):
        est = estimator_block([1.0, 0.5], 1e-3, initial_radii=[0.2, 0.3], known_linear_play=True)
    assert est.params["estimator.linear_play"] is True
    res = simulate(est, t, {"v": v, "y": v})
    with pytest.warns(DeprecationWarning, match="use 'y_hat'"):
        close(res["estimator_y_hat"], res["y_hat"])
    pb = pi_block(PIOperator([1, 0.5], [0, 0.3], initial_state=0.7), 1e-3)
    with pytest.warns(DeprecationWarning, match="initial_state"):
        assert pb.x0.tolist() == [0.7, 0.7]
    with pytest.warns(DeprecationWarning, match="x0"):
        res = simulate(pb, t, {"v": v}, x0=[0.7, 0.7])
    with pytest.warns(DeprecationWarning, match="use 'z\\[2\\]'"):
        close(res["pi_z2"], res["z[2]"])


@pytest.mark.parametrize("module", [pimodel.blocks.framework, pimodel.blocks.pi,
                                    pimodel.loops.simulation])
def test_docstring_examples_run(module):
    failures, tried = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert tried > 0 and failures == 0


def test_linearize_at_the_blocks_own_state_with_params():
    """python-control's analysis tools take the same state and params: at an interior play
    state the PI block is linear with D = p_1 (the linear play) and C_i = p_i for i > 1."""
    pb = pi_block(PIOperator([1.0, 0.5, 0.25], [0.0, 0.3, 0.8], initial_state=[0.0, 0.1, -0.2]),
                  1e-3, name="pi")
    params = {"pi.weights": [2.0, 0.5, 0.75]}
    lin = control.linearize(pb, initial_state(pb, params), 0.0, params=params)
    np.testing.assert_allclose(lin.D, [[2.0]], atol=1e-9)
    np.testing.assert_allclose(lin.C, [[0.0, 0.5, 0.75]], atol=1e-9)
    np.testing.assert_allclose(lin.A, np.diag([0.0, 1.0, 1.0]), atol=1e-9)
    np.testing.assert_allclose(lin.B, [[1.0], [0.0], [0.0]], atol=1e-9)
