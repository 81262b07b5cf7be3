"""FMUs: validation (fmpy, fmutool), equality with the Python operators, sub-stepping, state
rollback, several instances, bad parameters -> fmi2Error with a logged message, the
python-control wrapper and the co-simulation study."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.validation import validate_fmu

from pimodel import PIOperator, RadiusEstimator, estimate_radii
from pimodel.fmu import MODELS
from pimodel.fmu.block import fmu_block
from pimodel.fmu.cosim import cosimulate_adaptive_loop
from pimodel.fmu.unit import FMUUnit
from pimodel.loops.actuators import stage_dynamics
from pimodel.loops.compiled import loop_system, run_loop
from pimodel.loops.simulation import simulate
from pimodel.signals import sinusoid, triangle

P, R = [1.0, 0.5, 0.3], [0.0, 0.2, 0.6]
STAGE = PIOperator([6.3460, 1.6735, 1.1552, 0.4477], [0.0, 0.1945, 0.4826, 0.5707])
TS = 1e-3


def arr(prefix, values):
    return {f"{prefix}[{i + 1}]": float(x) for i, x in enumerate(values)}


@pytest.fixture(scope="session")
def fmus(built_fmus) -> Path:
    return built_fmus


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("name", list(MODELS))
def test_fmpy_validate_reports_no_problem(fmus, name):
    assert validate_fmu(str(fmus / f"{name}.fmu")) == []


@pytest.mark.parametrize("name", list(MODELS))
def test_fmutool_check_passes(fmus, name):
    exe = shutil.which("fmutool", path=str(Path(sys.executable).parent))
    if exe is None:
        pytest.skip("fmutool (fmu-manipulation-toolbox) is not installed")
    out = subprocess.run([exe, "-input", str(fmus / f"{name}.fmu"), "-check"],
                         capture_output=True, text=True, timeout=120)
    text = out.stdout + out.stderr
    assert out.returncode == 0, text
    assert "No semantic error" in text and "compliant with FMI-2.0" in text


def test_simulate_fmu_matches_operator(fmus):
    """fmpy.simulate_fmu with output_interval = Ts; the output recorded at t_{k+1} is y[k]."""
    t = np.arange(2000) * TS
    v = 2 * np.sin(2 * np.pi * 3 * t) * np.exp(-t)
    inp = np.array(list(zip(t, v, strict=True)), dtype=[("time", float), ("v", float)])
    res = fmpy.simulate_fmu(str(fmus / "PIHysteresis.fmu"), input=inp, output=["y"],
                            start_values={"Ts": TS, "n": 3, **arr("p", P), **arr("r", R)},
                            stop_time=t[-1] + TS, output_interval=TS)
    np.testing.assert_allclose(res["y"][1:], PIOperator(P, R).simulate(v), rtol=0, atol=1e-12)


@pytest.mark.parametrize("m", [1, 5, 2.5])
def test_substepping_matches_operator(fmus, m):
    """Communication step m*Ts: every sample k*Ts in [t, t+h) is processed with the input set
    at t; m = 2.5 alternates 3 and 2 samples per step."""
    unit = FMUUnit(fmus / "PIHysteresis.fmu", {"Ts": TS, "n": 3, **arr("p", P), **arr("r", R)})
    t, v = sinusoid(2, 3, fs=1 / TS, duration=2)
    held, out = np.empty(t.size), []
    steps = int(t.size / m)
    for j in range(steps):
        a, b = int(np.ceil(j * m - 1e-9)), int(np.ceil((j + 1) * m - 1e-9))
        unit.set({"v": v[int(np.ceil(j * m - 1e-9))]})
        unit.step(m * TS)
        held[a:b] = v[int(np.ceil(j * m - 1e-9))]
        out.append((b - 1, unit.get(["y"])[0]))
    unit.close()
    n_used = out[-1][0] + 1
    y = PIOperator(P, R).simulate(held[:n_used])
    idx, vals = zip(*out, strict=True)
    np.testing.assert_allclose(vals, y[list(idx)], rtol=0, atol=1e-12)


@pytest.mark.parametrize("suffix", ["", "_fmi3"])
def test_input_beyond_the_safe_bound_takes_the_checked_path(fmus, suffix):
    """PIHysteresis steps without a rollback copy only while no sample can overflow (|v| below
    a bound from the weights and radii); an input beyond it still gets the checked step: an
    overflow is refused and rolled back, and the run goes on equal to Python."""
    rng = np.random.default_rng(29)
    p = [1e10, *rng.uniform(0.1, 1.0, 2)]
    r = [0.0, *np.sort(rng.uniform(0.0, 1.0, 2))]
    unit = FMUUnit(fmus / f"PIHysteresis{suffix}.fmu", {"Ts": TS, "n": 3, **arr("p", p),
                                                        **arr("r", r)})
    v = rng.uniform(-2.0, 2.0, 50)
    ys = []
    for j, x in enumerate(v):
        if j == 20:  # 1e300 * 1e10 overflows: refused, states and output kept
            y_before = unit.get(["y"])[0]
            unit.set({"v": 1e300})
            with pytest.raises(ValueError, match="the outputs overflowed .* not taken"):
                unit.step(TS)
            assert unit.get(["y"])[0] == y_before
        unit.set({"v": x})
        unit.step(TS)
        ys.append(unit.get(["y"])[0])
    unit.close()
    want = PIOperator(p, r).simulate(v)
    assert np.max(np.abs(np.array(ys) - want)) <= 1e-12 * np.max(np.abs(want))


def test_estimator_fmu_matches_python(fmus):
    t, v = triangle(2, 1, fs=1 / TS, duration=4)
    y = STAGE.simulate(v)
    kw = dict(gains=20.0, initial_radii=[0, 0.3, 0.4, 0.8], linear_play=True)
    ref = estimate_radii(v, y, STAGE.weights, dt=TS, polish=False, **kw)
    unit = FMUUnit(fmus / "RadiusEstimator.fmu", {
        "Ts": TS, "n": 4, "gain": 20.0, "linear_play": True, **arr("p", STAGE.weights),
        **arr("r", kw["initial_radii"])})
    names = [f"r_hat[{i + 1}]" for i in range(4)] + ["y_hat", "e"]
    out = []
    for a, b in zip(v, y, strict=True):
        unit.set({"v": a, "y": b})
        unit.step(TS)
        out.append(unit.get(names))
    unit.close()
    out = np.array(out)
    np.testing.assert_allclose(out[:, :4], np.vstack((ref.history[1:], ref.radii)), atol=1e-12)
    np.testing.assert_allclose(out[:, 4], ref.model_output, atol=1e-12)
    np.testing.assert_allclose(out[:, 5], ref.error, atol=1e-12)


def test_old_variable_name_known_linear_warns_and_works(fmus):
    start = {"Ts": TS, "n": 2, "p[1]": 1.0, "p[2]": 0.5, "r[1]": 0.3, "r[2]": 0.5}
    with pytest.warns(DeprecationWarning, match="'known_linear' is now 'linear_play'"):
        unit = FMUUnit(fmus / "RadiusEstimator.fmu", {**start, "known_linear": True})
    np.testing.assert_array_equal(unit.get(["r_hat[1]", "r_hat[2]"]), [0.0, 0.5])  # held at 0
    unit.close()
    unit = FMUUnit(fmus / "RadiusEstimator.fmu", start)
    np.testing.assert_array_equal(unit.get(["r_hat[1]", "r_hat[2]"]), [0.3, 0.5])
    unit.close()


def test_inverse_fmu_fixed_and_adaptive_match_python(fmus):
    t, yd = sinusoid(8, 2, fs=1 / TS, duration=1)
    fixed = FMUUnit(fmus / "InversePI.fmu", {"Ts": TS, "n": 4, **arr("p", STAGE.weights),
                                              **arr("r", STAGE.radii)})
    adapt = FMUUnit(fmus / "InversePI.fmu", {"Ts": TS, "n": 4, "adaptive": True,
                                              **arr("p", STAGE.weights)})
    vf, va = [], []
    for x in yd:
        fixed.set({"y_d": x})
        fixed.step(TS)
        vf.append(fixed.get(["v"])[0])
        adapt.set({"y_d": x, **arr("r_hat", STAGE.radii)})
        adapt.step(TS)
        va.append(adapt.get(["v"])[0])
    fixed.close()
    adapt.close()
    expected = STAGE.inverse().simulate(yd)
    np.testing.assert_allclose(vf, expected, atol=1e-12)
    np.testing.assert_allclose(va, expected, atol=1e-12)


def test_state_rollback_reset_and_instances(fmus):
    start = {"Ts": TS, "n": 3, **arr("p", P), **arr("r", R)}
    a, b = FMUUnit(fmus / "PIHysteresis.fmu", start, instance_name="a"), \
        FMUUnit(fmus / "PIHysteresis.fmu", start, instance_name="b")
    t, v = sinusoid(2, 3, fs=1 / TS, duration=0.3)
    for x in v[:100]:
        a.set({"v": x})
        a.step(TS)
    saved = a.get_state()
    first = []
    for x in v[100:]:
        a.set({"v": x})
        a.step(TS)
        first.append(a.get(["y"])[0])
    a.set_state(saved)
    second = []
    for x in v[100:]:
        a.set({"v": x})
        a.step(TS)
        second.append(a.get(["y"])[0])
    assert first == second
    b.set({"v": 1.0})  # the other instance is independent
    b.step(TS)
    np.testing.assert_allclose(b.get(["y"]), PIOperator(P, R).simulate([1.0]), atol=1e-12)
    # serialisation round trip
    fmu = a.fmu
    state = fmu.getFMUState()
    blob = fmu.serializeFMUState(state)
    restored = fmu.deSerializeFMUstate(blob)
    fmu.setFMUState(restored)
    fmu.freeFMUState(state)
    fmu.freeFMUState(restored)
    a.fmu.reset()  # back to instantiated, default parameters: initialise anew
    a.fmu.setupExperiment(startTime=0.0)
    a.fmu.enterInitializationMode()
    a.set(start)
    a.fmu.exitInitializationMode()
    a.time = 0.0
    a.set({"v": 1.0})
    a.step(TS)
    np.testing.assert_allclose(a.get(["y"]), PIOperator(P, R).simulate([1.0]), atol=1e-12)
    a.close()
    b.close()


@pytest.mark.parametrize(
    ("name", "start", "message"),
    [
        ("PIHysteresis", {"n": 65}, "parameter n = 65 out of range"),
        ("PIHysteresis", {"n": 1, "r[1]": -0.5}, "negative"),
        ("PIHysteresis", {"n": 2, "r[1]": 0.5, "r[2]": 0.2}, "not sorted"),
        ("PIHysteresis", {"n": 2, "p[2]": 0.0}, "not positive"),
        ("PIHysteresis", {"Ts": 0.0}, "the sample time must be > 0"),
        ("PIHysteresis", {"Ts": -1e-3}, "the sample time must be > 0"),
        ("RadiusEstimator", {"n": 2, "p[1]": -1.0}, "not positive"),
        ("RadiusEstimator", {"gain": -1.0}, "parameter gain"),
        ("InversePI", {"n": 2, "r[1]": 0.1, "r[2]": 0.3}, "not invertible"),
    ],
)
def test_bad_parameters_give_fmi2error_with_log(fmus, name, start, message):
    with pytest.raises(ValueError, match=message):
        FMUUnit(fmus / f"{name}.fmu", start)


def test_nan_input_gives_fmi2error(fmus):
    unit = FMUUnit(fmus / "PIHysteresis.fmu", {"n": 1})
    unit.set({"v": float("nan")})
    with pytest.raises(ValueError, match="input v = nan is not finite"):
        unit.step(TS)
    with pytest.raises(fmpy.fmi1.FMICallException):
        fmpy.simulate_fmu(str(fmus / "PIHysteresis.fmu"), start_values={"Ts": -1.0},
                          stop_time=0.01, output_interval=TS)


def test_fmu_block_in_python_control(fmus):
    start = {"Ts": TS, "n": 3, **arr("p", P), **arr("r", R)}
    blk = fmu_block(fmus / "PIHysteresis.fmu", TS, start=start, name="plant_fmu")
    t, v = sinusoid(2, 3, fs=1 / TS, duration=0.5)
    res = simulate(blk, t, {"v": v})
    np.testing.assert_allclose(res["y"], PIOperator(P, R).simulate(v), atol=1e-12)


def test_cosimulation_equals_native_interconnection(fmus):
    """Plant FMU + stage dynamics + estimator FMU + adaptive inverse FMU in a fixed-step master
    equals the native loop (compiled run_loop and the python-control interconnection)."""
    dt = 1e-4
    t, yd = sinusoid(8, 20, fs=1 / dt, duration=0.05)
    G = stage_dynamics(dt, fn_hz=1000, damping=0.05)
    kw = dict(gains=20.0, initial_radii=[0, 0.3, 0.4, 0.8], linear_play=True)
    co = cosimulate_adaptive_loop(fmus, yd, dt, STAGE, weights=STAGE.weights, gain=20.0,
                                  initial_radii=kw["initial_radii"], dynamics=G)
    est = RadiusEstimator(STAGE.weights, dt=dt, **kw)
    native = run_loop(yd, STAGE, dt, dynamics=G, feedforward="adaptive", estimator=est)
    np.testing.assert_allclose(co.y, native.y, rtol=0, atol=1e-12)
    np.testing.assert_allclose(co.radii, native.radii, rtol=0, atol=1e-12)
    sys_ = loop_system(STAGE, dt, dynamics=G, feedforward="adaptive",
                       estimator_options=dict(weights=STAGE.weights, **kw))
    ref = simulate(sys_, t[:200], {"y_d": yd[:200]})
    np.testing.assert_allclose(co.y[:200], ref["y"], rtol=0, atol=1e-9)


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_fmpy_compile_rebuilds_from_sources(fmus, tmp_path):
    if shutil.which("cmake") is None:
        pytest.skip("cmake not on PATH (fmpy compile needs it)")
    src = tmp_path / "PIHysteresis.fmu"
    shutil.copy(fmus / "PIHysteresis.fmu", src)
    exe = Path(sys.executable).parent / "fmpy"
    out = subprocess.run([str(exe), "compile", str(src)], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    res = fmpy.simulate_fmu(str(src), start_values={"Ts": TS, "n": 3, **arr("p", P),
                                                    **arr("r", R), "v": 1.0},
                            stop_time=5 * TS, output_interval=TS, output=["y"])
    np.testing.assert_allclose(res["y"][-1], PIOperator(P, R).simulate([1.0])[0], atol=1e-12)


def test_cli_fmu_build(tmp_path):
    from pimodel.cli import main

    assert main(["fmu", "build", "--out", str(tmp_path), "--which", "PIHysteresis"]) == 0
    assert (tmp_path / "PIHysteresis.fmu").exists()
    assert main(["fmu", "build", "--out", str(tmp_path), "--which", "Nope"]) == 2
