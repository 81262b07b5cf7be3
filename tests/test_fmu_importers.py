"""What an FMI importer sees of the pimodel FMUs (issue 29): the record's exact sample time on
its own time grid, the default experiment, units, only the FMI functions exported, and the
output at the start time."""

from __future__ import annotations

import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from pimodel.diagnosis.model import DiagnosedModel
from pimodel.fmu import MODELS, build_fmus
from pimodel.fmu.description import model_description
from pimodel.fmu.model_fmu import build_model_fmus
from pimodel.fmu.units import UNITS
from pimodel.operators import PIOperator
from pimodel.records import Record, sample_time

RATES = [pytest.param(2e-4, id="2e-4 s"), pytest.param(1 / 3000, id="1/3 ms")]


def _clock(ts: float, n: int) -> np.ndarray:
    """A logger's clock that adds its interval at every sample (rounding accumulates)."""
    return np.concatenate(([0.0], np.cumsum(np.full(n - 1, ts))))


@pytest.mark.parametrize("ts", RATES)
def test_sample_time_is_exact_on_a_regular_clock(ts):
    for t in (np.arange(12_000) * ts, _clock(ts, 12_000), np.arange(50) * ts + 3.0):
        assert sample_time(t) == ts
        assert Record(t, np.zeros(t.size), np.zeros(t.size)).dt == ts
    # the median of the accumulated clock is not the rate (the 1.9999999999997797e-4)
    assert float(np.median(np.diff(_clock(ts, 12_000)))) != ts


def test_sample_time_of_a_jittering_clock_is_the_median():
    rng = np.random.default_rng(4)
    t = np.arange(5000) * 2e-4 + rng.uniform(-2e-6, 2e-6, 5000)
    assert sample_time(t) == float(np.median(np.diff(t)))
    with pytest.raises(ValueError, match="t: expected at least 2"):
        sample_time([1.0])


def _drive(fmu: Path, t: np.ndarray, v: np.ndarray) -> tuple[float, np.ndarray]:
    """y at the start time, then y after each step [t[k], t[k+1]) on the record's grid."""
    md = read_model_description(fmu)
    refs = {x.name: x.valueReference for x in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="grid")
    slave.instantiate()
    try:
        slave.setupExperiment(startTime=float(t[0]))
        slave.enterInitializationMode()
        slave.setReal([refs["v"]], [float(v[0])])
        slave.exitInitializationMode()
        y0 = slave.getReal([refs["y"]])[0]
        ends = np.append(t[1:], t[-1] + (t[-1] - t[-2]))
        y = np.empty(t.size)
        for k in range(t.size):
            slave.setReal([refs["v"]], [float(v[k])])
            slave.doStep(float(t[k]), float(ends[k] - t[k]))
            y[k] = slave.getReal([refs["y"]])[0]
        slave.terminate()
    finally:
        slave.freeInstance()
    return y0, y


@pytest.mark.slow
@pytest.mark.parametrize("ts", RATES)
def test_exported_model_on_the_records_grid_equals_simulate(ts, tmp_path):
    """A model made from a record whose clock accumulates its interval: its Ts is exact, and
    its FMU driven by fmpy on the record's own times equals model.simulate to 1e-12 past
    sample 9083 (where the median Ts shifted a sample); the output at the start time is the
    response to the start input."""
    rng = np.random.default_rng(29)
    t = _clock(ts, 12_000)
    v = np.cumsum(rng.normal(0.0, 0.05, t.size)) + 2.0 * np.sin(np.linspace(0, 40, t.size))
    rec = Record(t, v, np.zeros(t.size))
    radii = np.sort(rng.uniform(0.0, 1.5, 6))
    radii[0] = 0.0
    model = DiagnosedModel(radii, rng.uniform(-0.2, 1.0, 6), 0.3, dt=rec.dt)
    assert model.dt == ts
    (fmu,) = build_model_fmus(model, tmp_path, stop_time=len(rec) * rec.dt)
    y0, y = _drive(fmu, rec.t, rec.v)
    ref = model.simulate(rec.v)
    assert np.max(np.abs(y - ref)) < 1e-12
    assert abs(y0 - ref[0]) < 1e-12 and abs(ref[0]) > 1e-3
    stop, step = _experiment(fmu)
    assert step == ts and stop == pytest.approx(12_000 * ts, rel=1e-12)


def _experiment(fmu: Path) -> tuple[float, float]:
    de = read_model_description(fmu).defaultExperiment
    return float(de.stopTime), float(de.stepSize)


@pytest.mark.parametrize("fmi_version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", list(MODELS))
def test_units_and_default_experiment(name, fmi_version):
    """Every unit attribute names a defined unit; the sample time is in s; the default
    experiment steps one Ts."""
    root = ET.fromstring(model_description(name, fmi_version))
    defined = {u.get("name") for u in root.iter("Unit")}
    assert defined <= set(UNITS)
    used = {e.get("unit") for e in root.iter() if e.get("unit")}
    assert used == defined
    ts = next(e for e in root.iter() if e.get("name") == "Ts")
    assert (ts if fmi_version == "3.0" else ts[0]).get("unit") == "s"
    de = root.find("DefaultExperiment")
    start = (ts.get("start") if fmi_version == "3.0" else ts[0].get("start"))
    assert float(de.get("stepSize")) == float(start)
    assert float(de.get("stopTime")) > float(de.get("startTime"))


def test_input_and_output_units_of_the_pi_family():
    root = ET.fromstring(model_description("PIHysteresis"))
    units = {sv.get("name"): sv[0].get("unit") for sv in root.iter("ScalarVariable")}
    assert (units["v"], units["y"], units["r[3]"], units["p[3]"]) == ("V", "um", "V", None)
    um = next(u for u in root.iter("Unit") if u.get("name") == "um")
    assert float(um[0].get("factor")) == 1e-6 and um[0].get("m") == "1"


def _dynamic_symbols(so: Path) -> list[str]:
    """The defined dynamic symbols of a shared object (nm -D, or readelf)."""
    tool = shutil.which("nm") or shutil.which("readelf")
    if tool is None:
        pytest.skip("neither nm nor readelf is on PATH")
    if tool.endswith("nm"):
        out = subprocess.run([tool, "-D", "--defined-only", str(so)], capture_output=True,
                             text=True, check=True).stdout
        return [line.split()[-1] for line in out.splitlines() if len(line.split()) == 3]
    out = subprocess.run([tool, "--dyn-syms", "-W", str(so)], capture_output=True, text=True,
                         check=True).stdout
    return [f[7] for f in (line.split() for line in out.splitlines())
            if len(f) >= 8 and f[6] != "UND" and f[3] in ("FUNC", "OBJECT")]


@pytest.mark.parametrize("fmi_version", ["2.0", "3.0"])
def test_only_fmi_functions_are_exported(fmi_version, tmp_path):
    prefix = "fmi2" if fmi_version == "2.0" else "fmi3"
    for fmu in build_fmus(tmp_path, ["PIHysteresis", "DiagnosedModel"],
                          fmi_version=fmi_version):
        with zipfile.ZipFile(fmu) as z:
            so = next(n for n in z.namelist() if n.endswith(".so"))
            z.extract(so, tmp_path)
        names = _dynamic_symbols(tmp_path / so)
        functions = [n for n in names if re.match(r"[A-Za-z_]\w*$", n)]
        assert f"{prefix}DoStep" in functions
        assert not [n for n in functions if not n.startswith(prefix)], functions


def test_output_at_the_start_time_is_the_response_to_the_start_input(tmp_path):
    """After initialization y is the operator's response to the start input (sample 0 on a
    copy); the first doStep then gives the same y[0] and the plays go on from rest."""
    op = PIOperator([1.0, 0.5, 0.25], [0.0, 0.3, 0.6])
    (fmu,) = build_model_fmus(op, tmp_path)
    v = np.array([0.7, 1.2, -0.4, 0.1])
    t = np.arange(v.size) * 1e-3
    y0, y = _drive(fmu, t, v)
    ref = op.simulate(v)
    assert abs(y0 - ref[0]) < 1e-12 and abs(ref[0]) > 0.1
    assert np.max(np.abs(y - ref)) < 1e-12
