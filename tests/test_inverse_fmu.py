"""The DiagnosedInverse FMU unit (FMI 2 and 3, unit 9 of fmu/src/pim_unit.h): the causal
feedforward of a diagnosed model equals the Python stream of ``DiagnosedInverse.block()`` to
1e-9 through the generic unit, ``fmpy.simulate_fmu`` and the co-simulation master; chained
inverse FMU -> model FMU, the model follows the reference delayed by the latency; sub-stepping,
FMU state round trips, bad parameters give logged errors; ``pimodel fmu build --model`` writes
it beside the model's FMU and it passes ``fmpy validate`` and ``fmutool -check``."""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.validation import validate_fmu

from pimodel.diagnosis.native_inverse import NativeInverse
from pimodel.diagnosis.native_model import stream_simulate
from pimodel.fmu.model_fmu import cosimulate_chain
from pimodel.fmu.operators import unit_parameters
from pimodel.fmu.unit import FMUUnit

sys.path.insert(0, str(Path(__file__).parent))
from diagnosed_unit import step_through  # noqa: E402
from test_inverse_native import CASES as NATIVE_CASES  # noqa: E402
from test_inverse_native import DT, RADII, model, python_stream, reference  # noqa: E402

# the inverse's cases, and a rate through the saturating map rho / (1 + rho / S)
CASES = {**NATIVE_CASES, "rate_saturated": (("rate",), {"rate_family": "weight",
                                                         "rate_saturation": 0.5})}


def unit_path(folder: Path, fmi: str) -> Path:
    return folder / f"DiagnosedInverse{'_fmi3' if fmi == '3.0' else ''}.fmu"


def run_inverse_unit(path: Path, params: dict, y_d: np.ndarray, h: float) -> np.ndarray:
    """``v`` of the unit after each communication step ``h`` with ``y_d[k]`` held over it."""
    unit = FMUUnit(path, params)
    try:
        return np.array(step_through(unit, y_d, h, "y_d", "v"))
    finally:
        unit.close()


def run_restored(path: Path, params: dict, y_d: np.ndarray, k: int) -> tuple[list, list]:
    """``v`` over ``y_d[k:]`` after the first ``k`` samples, run on, then again from the FMU
    state saved after sample ``k - 1`` (steps of ``DT``)."""
    unit = FMUUnit(path, params)

    def run(ys):
        return step_through(unit, ys, DT, "y_d", "v")

    try:
        run(y_d[:k])
        state = unit.get_state()
        first = run(y_d[k:])
        unit.set_state(state)
        again = run(y_d[k:])
        unit.free_state(state)
    finally:
        unit.close()
    return first, again


@pytest.fixture(scope="module")
def fmus(built_fmus) -> Path:
    return built_fmus


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
@pytest.mark.parametrize("case", ["nominal", "all", "dynamics_delay_creep", "rate_weight",
                                  "rate_weight_filtered", "rate_saturated", "rate_scaled_creep",
                                  "delay_whole", "creep_common", "dynamics_delay_creep_common",
                                  "wiener_two_delay_creep", "creep_record", "all_record"])
def test_unit_equals_the_python_stream(fmus, fmi, case):
    effects, extra = CASES[case]
    m = model(effects, **extra)
    y_d = reference(m, n=400)
    name, params = unit_parameters(m.inverse())
    assert name == "DiagnosedInverse"
    got = run_inverse_unit(unit_path(fmus, fmi), params, y_d, DT)
    want, _ = python_stream(m, y_d, None)
    assert np.max(np.abs(got - want)) < 1e-9


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_unit_with_more_than_64_plays_and_a_start_memory(fmus, fmi):
    """An 80-play grid (plays 65..80 in the _hi arrays) and plays started at z0."""
    from pimodel.diagnosis.model import DiagnosedModel

    n = 80
    radii = np.linspace(0.0, 1.2, n)
    weights = np.full(n, 1.5 / n)
    weights[0] = 0.8
    m = DiagnosedModel(radii, weights, 0.1, dt=DT, effects=("creep", "delay"),
                       params={"creep_lag_gains": [0.04], "creep_time_constants_s": [0.01],
                               "delay_samples": 1.5})
    y_d = reference(m, n=300)
    _, params = unit_parameters(m.inverse())
    assert params["p_hi[16]"] == weights[79] and "p_hi[17]" not in params
    native = NativeInverse(m.inverse())
    got = run_inverse_unit(unit_path(fmus, fmi), params, y_d, DT)
    assert np.max(np.abs(got - native.run(y_d))) < 1e-9
    got = run_inverse_unit(unit_path(fmus, fmi), {**params, "z0": -0.2}, y_d, DT)
    want = native.run(y_d, z0=np.full(n, -0.2))  # z0: every play (and the rate source's)
    assert np.max(np.abs(got - want)) < 1e-9
    assert np.max(np.abs(want - native.run(y_d))) > 0.01  # the start memory matters


@pytest.mark.parametrize(
    ("start", "message"),
    [({"n": 2, "p[2]": float("nan")}, "weight p[2] = nan is not finite"),
     ({"n": 2, "r[2]": -0.1}, "radius r[2] = -0.1 is negative"),
     ({"n": 129}, "parameter n = 129 out of range: 1 <= n <= 128"),
     ({"reference_range": -1.0}, "parameter reference_range = -1: must be finite and >= 0"),
     ({"latency": -1}, "parameter latency = -1 out of range"),
     ({"delay_fraction": 1.0}, "parameter delay_fraction = 1 out of range"),
     ({"n_sections": 11}, "parameter n_sections = 11 out of range"),
     ({"n_sections": 1, "section[4]": 2.0}, "section[4] = 2: each section's a0 must be 1"),
     ({"n_sections": 1, "section[5]": -2.0, "section[6]": 1.0}, "pole at z = 1"),
     ({"n_sections": 1, "section[2]": float("inf")}, "section[2] = inf is not finite"),
     ({"n_post_sections": 11}, "parameter n_post_sections = 11 out of range"),
     ({"n_post_sections": 1, "latency": 1, "post_section[4]": 0.5},
      "post_section[4] = 0.5: each section's a0 must be 1"),
     ({"n_post_sections": 1, "latency": 1, "post_section[3]": float("nan")},
      "post_section[3] = nan is not finite"),
     ({"n_post_sections": 1}, "parameter latency = 0: post sections (n_post_sections = 1) need "
                              "a latency >= 1"),
     ({"rate_band_gain[1]": 0.1, "rate_scale": 0.0}, "parameter rate_scale = 0"),
     ({"n_lags": 1, "creep_tau[1]": 0.0}, "time constant creep_tau[1] = 0 is not positive"),
     ({"creep_start": 3}, "parameter creep_start = 3 out of range: 0 at rest at h0[0], 1 at "
                         "rest at creep_start_level, 2 at rest at h0[0] counted from the "
                         "record's start"),
     ({"creep_start": -1}, "parameter creep_start = -1 out of range"),
     ({"n_lags": 2, "creep_tau[1]": 0.1, "creep_tau[2]": 1.0, "creep_start": 1,
       "creep_start_level[2]": float("nan")},
      "creep start level creep_start_level[2] = nan is not finite")])
@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_bad_parameters_give_logged_errors(fmus, fmi, start, message):
    with pytest.raises(ValueError, match="initialisation failed") as err:
        FMUUnit(unit_path(fmus, fmi), start)
    assert message in str(err.value)


def test_unit_substeps_and_restores_its_state(fmus):
    """Steps of 2.5 Ts (pim_unit.h's held-input rule) and an FMU state saved and restored."""
    m = model(*CASES["all"][:1], **CASES["all"][1])
    y_d = reference(m, n=200)
    _, params = unit_parameters(m.inverse())
    path = unit_path(fmus, "2.0")
    seq, last, k_next = [], [], 0
    for j, y in enumerate(y_d):
        k_end = math.ceil((j + 1) * 2.5 - 1e-9)
        seq += [y] * (k_end - k_next)
        k_next = k_end
        last.append(k_end - 1)
    got = run_inverse_unit(path, params, y_d, 2.5 * DT)
    want, _ = python_stream(m, np.array(seq), None)
    assert np.max(np.abs(got - want[last])) < 1e-9
    first, again = run_restored(path, params, y_d[:90], 60)
    assert first == again


@pytest.mark.parametrize("case", ["wiener_two_delay_creep", "all_record"])
def test_unit_restores_its_state_with_post_sections_and_a_record_start(fmus, case):
    """An FMU state saved and restored mid-record continues as the unbroken run, with post
    sections (the solver after them in the state check) and with the record start's L0
    (the filtered rate after it)."""
    effects, extra = CASES[case]
    m = model(effects, **extra)
    y_d = reference(m, n=150)
    _, params = unit_parameters(m.inverse())
    first, again = run_restored(unit_path(fmus, "2.0"), params, y_d, 80)
    assert first == again
    want, _ = python_stream(m, y_d, None)
    assert np.max(np.abs(np.array(again) - want[80:])) < 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_cli_builds_the_inverse_fmu_that_validates_and_runs_in_the_masters(tmp_path, fmi):
    """pimodel fmu build --model MODEL.json writes the model's FMU and its inverse's; the inverse
    FMU (its values as start values) equals the Python stream in fmpy.simulate_fmu and in the
    co-simulation master, and chained into the model FMU the model follows the reference
    delayed by the latency (as the batch inverse's response)."""
    from pimodel.cli import main

    m = model(("creep", "asymmetry", "delay"), delay_samples=2)
    path = m.save(tmp_path / "twin.json")
    out = tmp_path / "fmus"
    assert main(["fmu", "build", "--model", str(path), "--out", str(out),
                 "--fmi-version", fmi]) == 0
    suffix = "_fmi3" if fmi == "3.0" else ""
    fmu, forward = out / f"twin_1_DiagnosedInverse{suffix}.fmu", \
        out / f"twin_1_DiagnosedModel{suffix}.fmu"
    assert validate_fmu(str(fmu)) == []
    y_d = reference(m, n=500)
    want, _ = python_stream(m, y_d, None)
    t = np.arange(y_d.size) * DT
    inp = np.array(list(zip(t, y_d, strict=True)), dtype=[("time", float), ("y_d", float)])
    res = fmpy.simulate_fmu(str(fmu), input=inp, output=["v"], stop_time=t[-1] + DT,
                            output_interval=DT)
    assert np.max(np.abs(res["v"][1:] - want)) < 1e-9  # v recorded at t_{k+1} is v[k]
    assert np.max(np.abs(cosimulate_chain([fmu], y_d, DT) - want)) < 1e-9
    y = cosimulate_chain([fmu, forward], y_d, DT)
    a = NativeInverse(m.inverse()).latency
    assert a == 2
    assert np.max(np.abs(y - stream_simulate(m, want, input_range=2 * RADII[-1]))) < 1e-9
    # the model follows the batch inverse's response delayed by A (the reference rests over
    # its first A + 1 samples), which tracks y_d: the creep and asymmetry terms act undelayed
    # beside the delayed hysteresis term, so the inverse of the delayed model is approximate
    y_batch = m.simulate(m.inverse().simulate(y_d), input_range=2 * RADII[-1])
    assert np.max(np.abs(y[a:] - y_batch[:y_d.size - a])) < 1e-9
    assert np.sqrt(np.mean((y[a:] - y_d[:y_d.size - a]) ** 2)) < 0.01 * np.ptp(y_d)
    exe = shutil.which("fmutool", path=str(Path(sys.executable).parent))
    if exe is None:
        pytest.skip("fmutool (fmu-manipulation-toolbox) is not installed; fmpy checks passed")
    chk = subprocess.run([exe, "-input", str(fmu), "-check"], capture_output=True, text=True,
                         timeout=120)
    assert chk.returncode == 0 and f"No semantic error against the FMI-{fmi[0]}" in \
        chk.stdout + chk.stderr, chk.stdout + chk.stderr
