"""FMI 3 arrays sized by the structural parameter ``n_plays``: every FMI 3 unit, configured
through fmpy's ``FMU3Slave`` (``fmi3EnterConfigurationMode``, ``setUInt64``, via
:class:`~pimodel.fmu.unit.FMUUnit`) with ``n_plays`` = its number of plays (not the default 64),
takes per-play arrays of exactly that many values and equals Python; configuration-mode rules
and errors. fmpy's ``simulate_fmu`` (0.3.32) never enters configuration mode, hence the slave
API here (docs/fmu.md)."""

from __future__ import annotations

import sys
from pathlib import Path

import fmpy
import numpy as np
import pytest

from pimodel import PIOperator, estimate_radii
from pimodel.fmu import MODELS
from pimodel.fmu.build import NMAX
from pimodel.fmu.operators import unit_parameters
from pimodel.fmu.unit import FMUUnit
from pimodel.signals import sinusoid, triangle

sys.path.insert(0, str(Path(__file__).parent))
import test_diagnosed_block_fmu as diag  # noqa: E402
import test_fmu_operators as ops  # noqa: E402
import test_inverse_native as inv  # noqa: E402

TS = 1e-3
STAGE = PIOperator([6.3460, 1.6735, 1.1552, 0.4477], [0.0, 0.1945, 0.4826, 0.5707])


@pytest.fixture(scope="module")
def fmus(built_fmus) -> Path:
    return built_fmus


def path(fmus: Path, name: str) -> Path:
    return fmus / f"{name}_fmi3.fmu"


def run(fmu: Path, start: dict, inputs: list[dict], outputs: list[str]) -> np.ndarray:
    """One doStep of Ts per input dict; the outputs after each."""
    unit = FMUUnit(fmu, start)
    try:
        assert all(unit._size(unit.vars[a]) == start["n_plays"]
                   for a in ("p", "c", "r", "tau", "r_hat") if a in unit.vars)
        out = []
        for values in inputs:
            unit.set(values)
            unit.step(start.get("Ts", TS))
            out.append(unit.get(outputs))
    finally:
        unit.close()
    return np.array(out)


def case(name: str) -> tuple[dict, list[dict], list[str], np.ndarray]:
    """(start values with n_plays = n, inputs per step, outputs, Python's outputs)."""
    if name == "PIHysteresis":
        p, r = [1.0, 0.5, 0.3], [0.0, 0.2, 0.6]
        _, v = sinusoid(2, 3, fs=1 / TS, duration=0.5)
        start = {"n_plays": 3, "Ts": TS, "n": 3, "p": p, "r": r}
        return start, [{"v": x} for x in v], ["y"], PIOperator(p, r).simulate(v)[:, None]
    if name == "RadiusEstimator":
        _, v = triangle(2, 1, fs=1 / TS, duration=1)
        y = STAGE.simulate(v)
        r0 = [0, 0.3, 0.4, 0.8]
        ref = estimate_radii(v, y, STAGE.weights, dt=TS, polish=False, gains=20.0,
                             initial_radii=r0, linear_play=True)
        start = {"n_plays": 4, "Ts": TS, "n": 4, "gain": 20.0, "linear_play": True,
                 "p": STAGE.weights, "r": r0}
        want = np.column_stack((np.vstack((ref.history[1:], ref.radii)), ref.error))
        return (start, [{"v": a, "y": b} for a, b in zip(v, y, strict=True)],
                ["r_hat", "e"], want)
    if name == "InversePI":  # adaptive: the array input r_hat of n_plays values
        _, yd = sinusoid(8, 2, fs=1 / TS, duration=0.5)
        start = {"n_plays": 4, "Ts": TS, "n": 4, "adaptive": True, "p": STAGE.weights}
        return (start, [{"y_d": x, "r_hat": STAGE.radii} for x in yd], ["v"],
                STAGE.inverse().simulate(yd)[:, None])
    if name in ops.UNITS:
        op = ops.operator(name)
        unit_name, params = unit_parameters(op)
        assert unit_name == name
        x = ops.signal(300)
        start = {"n_plays": params["n"], **params}
        return start, [{"u": xj} for xj in x], ["y"], op.simulate(x)[:, None]
    if name == "DiagnosedModel":
        m = diag.model("all")
        _, params = unit_parameters(m)
        t, v = diag.signal(600, t0=0.0)
        start = {"n_plays": len(diag.RADII), **params}
        assert params["n"] == len(diag.RADII)
        return (start, [{"v": x} for x in v], ["y"],
                m.simulate(v, t, input_range=diag.RANGE)[:, None])
    effects, extra = inv.CASES["nominal"]
    m = inv.model(effects, **extra)
    y_d = inv.reference(m, n=300)
    _, params = unit_parameters(m.inverse())
    want, _ = inv.python_stream(m, y_d, None)
    start = {"n_plays": len(inv.RADII), **params}
    assert params["n"] == len(inv.RADII)
    return start, [{"y_d": y} for y in y_d], ["v"], want[:, None]


@pytest.mark.parametrize("name", list(MODELS))
def test_unit_with_n_plays_equals_python(fmus, name):
    start, inputs, outputs, want = case(name)
    assert start["n_plays"] == start["n"] < NMAX
    got = run(path(fmus, name), start, inputs, outputs)
    assert got.shape == want.shape
    assert np.max(np.abs(got - want)) < 1e-12 * max(1.0, float(np.max(np.abs(want))))
    assert np.ptp(want) > 0.1  # the output moved


def test_arrays_move_n_plays_values(fmus):
    unit = FMUUnit(path(fmus, "PIHysteresis"), {"n_plays": 5, "n": 2, "p": [1.0, 0.5]})
    p = unit.fmu.getFloat64([100], nValues=5)
    assert len(p) == 5 and list(p[:2]) == [1.0, 0.5]
    with pytest.raises(fmpy.fmi1.FMICallException):
        unit.fmu.getFloat64([100], nValues=4)
    assert "nValues = 4 is too small: at least 5 values needed" in unit.log[-1]
    assert unit.fmu.getUInt64([18]) == [5]
    unit.close()


@pytest.mark.parametrize(
    ("start", "message"),
    [({"n_plays": 0}, "n_plays = 0 out of range: 1 <= n_plays <= 64"),
     ({"n_plays": NMAX + 1}, f"n_plays = {NMAX + 1} out of range"),
     ({"n_plays": 2, "n": 3}, "parameter n = 3 exceeds n_plays = 2")])
def test_bad_n_plays_gives_logged_error(fmus, start, message):
    with pytest.raises(ValueError, match=message):
        FMUUnit(path(fmus, "PIHysteresis"), start)


def test_n_plays_is_set_in_configuration_mode_only(fmus):
    unit = FMUUnit(path(fmus, "InversePI"), {"n": 1})
    with pytest.raises(fmpy.fmi1.FMICallException):
        unit.fmu.setUInt64([18], [3])
    assert "structural parameter n_plays (value reference 18) can be set in configuration " \
           "mode only" in unit.log[-1]
    with pytest.raises(fmpy.fmi1.FMICallException):
        unit.fmu.enterConfigurationMode()  # in step mode
    assert "fmi3EnterConfigurationMode is not allowed now: the FMU is in step mode" \
        in unit.log[-1]
    unit.close()
