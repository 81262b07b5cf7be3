"""FMI 3.0 versions of the units: validation (fmpy, fmutool), real arrays, equality with the
Python operators and with the FMI 2.0 units, sub-stepping, rollback, bad parameters ->
fmi3Error with a logged message, the python-control wrapper and the co-simulation master."""

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
from pimodel.fmu import MODELS, build_fmus
from pimodel.fmu.block import fmu_block
from pimodel.fmu.build import NMAX
from pimodel.fmu.cosim import cosimulate_adaptive_loop
from pimodel.fmu.unit import FMUUnit
from pimodel.loops.actuators import stage_dynamics
from pimodel.loops.compiled import run_loop
from pimodel.loops.simulation import simulate
from pimodel.signals import sinusoid, triangle

P, R = [1.0, 0.5, 0.3], [0.0, 0.2, 0.6]
STAGE = PIOperator([6.3460, 1.6735, 1.1552, 0.4477], [0.0, 0.1945, 0.4826, 0.5707])
TS = 1e-3


@pytest.fixture(scope="module")
def fmus(built_fmus) -> Path:
    return built_fmus


def path(fmus, name):
    return fmus / f"{name}_fmi3.fmu"


@pytest.mark.parametrize("name", list(MODELS))
def test_fmi3_validates(fmus, name):
    assert validate_fmu(str(path(fmus, name))) == []
    md = fmpy.read_model_description(str(path(fmus, name)))
    assert md.fmiVersion == "3.0"
    p = next(v for v in md.modelVariables if v.name in ("p", "c"))  # weights / creep gains
    n_plays = next(v for v in md.modelVariables if v.name == "n_plays")
    assert n_plays.causality == "structuralParameter" and int(n_plays.start) == NMAX
    # a real array, not scalars, sized by the structural parameter
    assert [d.valueReference for d in p.dimensions] == [n_plays.valueReference]
    assert p.shape == (NMAX,)
    exe = shutil.which("fmutool", path=str(Path(sys.executable).parent))
    if exe is None:
        pytest.skip("fmutool (fmu-manipulation-toolbox) is not installed")
    out = subprocess.run([exe, "-input", str(path(fmus, name)), "-check"], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0 and "No semantic error against the FMI-3" in out.stdout + \
        out.stderr, out.stdout + out.stderr


def test_simulate_fmu_with_arrays_matches_operator(fmus):
    """fmpy.simulate_fmu, arrays as start values; the output recorded at t_{k+1} is y[k]."""
    t = np.arange(2000) * TS
    v = 2 * np.sin(2 * np.pi * 3 * t) * np.exp(-t)
    inp = np.array(list(zip(t, v, strict=True)), dtype=[("time", float), ("v", float)])
    res = fmpy.simulate_fmu(str(path(fmus, "PIHysteresis")), input=inp, output=["y"],
                            start_values={"Ts": TS, "n": 3, "p": np.array(P + [1.0] * (NMAX - 3)),
                                          "r": np.array(R + [0.6] * (NMAX - 3))},
                            stop_time=t[-1] + TS, output_interval=TS)
    np.testing.assert_allclose(res["y"][1:], PIOperator(P, R).simulate(v), rtol=0, atol=1e-12)


def test_substepping_equals_fmi2(fmus):
    """Communication steps of 2.5 Ts give the same outputs in FMI 3 and FMI 2 (same rule)."""
    start = {"Ts": TS, "n": 3, "p": P, "r": R}
    u3 = FMUUnit(path(fmus, "PIHysteresis"), start)
    u2 = FMUUnit(fmus / "PIHysteresis.fmu", {"Ts": TS, "n": 3, **{f"p[{i + 1}]": x for i, x in
                                                                   enumerate(P)},
                                              **{f"r[{i + 1}]": x for i, x in enumerate(R)}})
    t, v = sinusoid(2, 3, fs=1 / TS, duration=1)
    a, b = [], []
    for x in v[::3]:
        for unit, out in ((u3, a), (u2, b)):
            unit.set({"v": x})
            unit.step(2.5 * TS)
            out.append(unit.get(["y"])[0])
    u3.close()
    u2.close()
    assert np.max(np.abs(np.array(a) - b)) < 1e-12
    assert np.ptp(a) > 1.0


def test_estimator_and_inverse_match_python(fmus):
    t, v = triangle(2, 1, fs=1 / TS, duration=4)
    y = STAGE.simulate(v)
    kw = dict(gains=20.0, initial_radii=[0, 0.3, 0.4, 0.8], linear_play=True)
    ref = estimate_radii(v, y, STAGE.weights, dt=TS, polish=False, **kw)
    est = FMUUnit(path(fmus, "RadiusEstimator"), {
        "Ts": TS, "n": 4, "gain": 20.0, "linear_play": True, "p": STAGE.weights,
        "r": kw["initial_radii"]})
    out = []
    for a, b in zip(v, y, strict=True):
        est.set({"v": a, "y": b})
        est.step(TS)
        out.append(est.get(["r_hat[1]", "r_hat[2]", "r_hat[3]", "r_hat[4]", "e"]))
    est.close()
    out = np.array(out)
    np.testing.assert_allclose(out[:, :4], np.vstack((ref.history[1:], ref.radii)), atol=1e-12)
    np.testing.assert_allclose(out[:, 4], ref.error, atol=1e-12)

    _, yd = sinusoid(8, 2, fs=1 / TS, duration=1)
    inv = FMUUnit(path(fmus, "InversePI"), {"Ts": TS, "n": 4, "adaptive": True,
                                            "p": STAGE.weights})
    vs = []
    for x in yd:
        inv.set({"y_d": x, "r_hat": STAGE.radii})
        inv.step(TS)
        vs.append(inv.get(["v"])[0])
    inv.close()
    np.testing.assert_allclose(vs, STAGE.inverse().simulate(yd), atol=1e-12)


def test_rollback_and_serialisation(fmus):
    a = FMUUnit(path(fmus, "PIHysteresis"), {"Ts": TS, "n": 3, "p": P, "r": R})
    _, v = sinusoid(2, 3, fs=1 / TS, duration=0.2)
    for x in v[:100]:
        a.set({"v": x})
        a.step(TS)
    saved = a.get_state()
    runs = []
    for _ in range(2):
        ys = []
        for x in v[100:]:
            a.set({"v": x})
            a.step(TS)
            ys.append(a.get(["y"])[0])
        runs.append(ys)
        a.set_state(saved)
    assert runs[0] == runs[1]
    blob = a.fmu.serializeFMUState(saved[0])
    restored = a.fmu.deserializeFMUState(blob)
    a.fmu.setFMUState(restored)
    a.free_state(saved)
    a.fmu.freeFMUState(restored)
    a.close()


@pytest.mark.parametrize(
    ("name", "start", "message"),
    [
        ("PIHysteresis", {"n": 65}, "parameter n = 65 out of range"),
        ("PIHysteresis", {"n": 2, "r": [0.5, 0.2]}, "not sorted"),
        ("PIHysteresis", {"n": 1, "r": [-0.5]}, "negative"),
        ("PIHysteresis", {"n": 2, "p": [1.0, 0.0]}, "not positive"),
        ("PIHysteresis", {"Ts": 0.0}, "the sample time must be > 0"),
        ("RadiusEstimator", {"gain": -1.0}, "parameter gain"),
        ("InversePI", {"n": 2, "r": [0.1, 0.3]}, "not invertible"),
    ],
)
def test_bad_parameters_give_fmi3error_with_log(fmus, name, start, message):
    with pytest.raises(ValueError, match=message):
        FMUUnit(path(fmus, name), start)


def test_nan_input_and_late_parameter_give_error(fmus):
    unit = FMUUnit(path(fmus, "PIHysteresis"), {"n": 1})
    unit.set({"v": float("nan")})
    with pytest.raises(ValueError, match="input v = nan is not finite"):
        unit.step(TS)
    with pytest.raises(fmpy.fmi1.FMICallException):
        unit.set({"p": [2.0]})  # parameters are fixed after initialisation
    assert "cannot set parameter p (value reference 100) after initialization" in unit.log[-1]
    unit.close()


def test_short_array_gives_logged_error(fmus):
    unit = FMUUnit(path(fmus, "PIHysteresis"), {"n": 1})
    with pytest.raises(fmpy.fmi1.FMICallException):
        unit.fmu.getFloat64([100], nValues=16)  # p has 64 values
    assert "nValues = 16 is too small: at least 64 values needed" in unit.log[-1]
    unit.close()


def test_fmu_block_and_cosimulation(fmus):
    blk = fmu_block(path(fmus, "RadiusEstimator"), TS, name="est3",
                    start={"Ts": TS, "n": 2, "p": [1.0, 0.5], "r": [0.0, 0.3]})
    assert blk.output_labels == ["y_hat", "e", *[f"r_hat[{i}]" for i in range(1, NMAX + 1)],
                                 "health"]
    assert blk.input_labels == ["v", "y"]
    dt = 1e-4
    _, yd = sinusoid(8, 20, fs=1 / dt, duration=0.05)
    G = stage_dynamics(dt, fn_hz=1000, damping=0.05)
    r0 = [0, 0.3, 0.4, 0.8]
    co = cosimulate_adaptive_loop(fmus, yd, dt, STAGE, weights=STAGE.weights, gain=20.0,
                                  initial_radii=r0, dynamics=G, fmi_version="3.0")
    est = RadiusEstimator(STAGE.weights, dt=dt, gains=20.0, initial_radii=r0,
                          linear_play=True)
    native = run_loop(yd, STAGE, dt, dynamics=G, feedforward="adaptive", estimator=est)
    np.testing.assert_allclose(co.y, native.y, rtol=0, atol=1e-12)
    plant = fmu_block(path(fmus, "PIHysteresis"), TS, name="plant3",
                      start={"Ts": TS, "n": 3, "p": P, "r": R})
    t, v = sinusoid(2, 3, fs=1 / TS, duration=0.3)
    res = simulate(plant, t, {"v": v})
    np.testing.assert_allclose(res["y"], PIOperator(P, R).simulate(v), atol=1e-12)


def test_fmpy_compile_rebuilds_fmi3_from_sources(fmus, tmp_path):
    if shutil.which("cmake") is None:
        pytest.skip("cmake not on PATH (fmpy compile needs it)")
    src = tmp_path / "PIHysteresis_fmi3.fmu"
    shutil.copy(path(fmus, "PIHysteresis"), src)
    out = subprocess.run([str(Path(sys.executable).parent / "fmpy"), "compile", str(src)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    unit = FMUUnit(src, {"Ts": TS, "n": 3, "p": P, "r": R})
    unit.set({"v": 1.0})
    unit.step(TS)
    np.testing.assert_allclose(unit.get(["y"]), PIOperator(P, R).simulate([1.0]), atol=1e-12)
    unit.close()


def test_cli_builds_fmi3(tmp_path):
    from pimodel.cli import main

    assert main(["fmu", "build", "--out", str(tmp_path), "--which", "InversePI",
                 "--fmi-version", "3.0"]) == 0
    assert validate_fmu(str(tmp_path / "InversePI_fmi3.fmu")) == []


def test_bad_build_and_cosim_version(tmp_path):
    with pytest.raises(ValueError, match="fmi_version: expected one of"):
        build_fmus(tmp_path, fmi_version="4.0")
    with pytest.raises(ValueError, match="fmi_version: expected one of"):
        cosimulate_adaptive_loop(tmp_path, [0.0, 1.0], 1e-3, STAGE, weights=STAGE.weights,
                                 gain=1.0, initial_radii=STAGE.radii, fmi_version="1.0")


