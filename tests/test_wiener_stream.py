"""A Wiener model (issue 19: ``dynamics_position == "before"``, ``wiener_elements`` of
:mod:`pimodel.diagnosis.wiener`) on the C core: the filter before the plays runs as sections in
series on ``v`` with a second set of plays on its output, so that the runner, the python-control
block and the DiagnosedModel FMU (FMI 2 and 3) each equal ``DiagnosedModel.simulate`` to 1e-12,
with every other effect beside it; malformed filters are refused with the element named
(ValueError in Python, a logged fmi2Error/fmi3Error in the FMU). The last test exports a model
that the diagnosis chose on a stage written in ``tests/test_diagnosis_wiener.py``."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import control
import fmpy
import numpy as np
import pytest
from fmpy.validation import validate_fmu

from pimodel.blocks import initial_state
from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.native_model import (
    NativeModel,
    fmu_parameters,
    prefilter_sections,
    state_labels,
    stream_simulate,
)
from pimodel.diagnosis.wiener import prefilter
from pimodel.fmu.model_fmu import cosimulate_chain
from pimodel.fmu.unit import FMUUnit

sys.path.insert(0, str(Path(__file__).parent))
from diagnosed_unit import run_unit, step_through, unit_file  # noqa: E402

DT = 1e-3
RADII = [0.0, 0.15, 0.4, 0.7, 1.0]
RANGE = 2 * RADII[-1]  # the stream's default input_range, passed to simulate as well
FILTERS = {  # elements of the filter before the plays
    "lowpass": [["lowpass", 4e-3]],
    "mode_underdamped": [["mode", 25.0, 0.2]],
    "mode_critical": [["mode", 30.0, 1.0]],
    "mode_overdamped": [["mode", 30.0, 1.6]],
    "lowpass_then_mode": [["lowpass", 3e-3], ["mode", 40.0, 0.4]],
    # sampled at the end of the hold: x[k] moves with v[k] (direct feedthrough)
    "lowpass_direct": [["lowpass_direct", 4e-3]],
    "lowpass_direct_then_mode": [["lowpass_direct", 3e-3], ["mode", 40.0, 0.4]],
}
OTHER_EFFECTS = {
    "creep_lag_gains": [0.04, -0.01], "creep_time_constants_s": [0.003, 0.03],
    "asymmetry_quadratic": 0.05, "asymmetry_cubic": -0.02, "center": 0.4, "half_range": 1.1,
    "rate_gains": [0.3, -0.2], "rate_scale": 5.0, "drift_per_s": 0.02, "drift_clock": "record",
    "delay_samples": 2.5,
}
RATE_FAMILIES = {"radius": {"rate_family": "radius", "rate_time_constant_s": 0.0},
                 "weight": {"rate_family": "weight", "rate_time_constant_s": 3e-3}}
ALL = ("dynamics", "creep", "asymmetry", "rate", "drift", "delay")


def model(case: str = "lowpass", effects: tuple = ("dynamics",),
          family: str = "weight") -> DiagnosedModel:
    """Signed weights, a reference fit unlike them and the case's filter before the plays."""
    params = {"dynamics_position": "before", "wiener_elements": FILTERS[case],
              **OTHER_EFFECTS, **RATE_FAMILIES[family]}
    return DiagnosedModel(RADII, [1.2, -0.4, 0.8, -0.3, 0.25], 0.3, dt=DT, effects=effects,
                          reference_weights=[1.0, -0.2, 0.7, -0.2, 0.2], reference_offset=0.1,
                          params=params)


def signal(n: int = 1500) -> tuple[np.ndarray, np.ndarray]:
    """Times from 0 and an input with minor loops and a step (it rings the filter)."""
    t = np.arange(n) * DT
    v = 0.2 + 1.5 * np.sin(2 * np.pi * 1.3 * t) + 0.3 * np.sin(2 * np.pi * 11 * t)
    v[n // 2:] += 0.5
    return t, v


def unfiltered(m: DiagnosedModel) -> DiagnosedModel:
    """The same model without the filter (the plays of v)."""
    return replace(m, effects=tuple(e for e in m.effects if e != "dynamics"))


@pytest.mark.parametrize(("effects", "family"), [(("dynamics",), "weight"), (ALL, "weight"),
                                                 (ALL, "radius")],
                         ids=["dynamics", "all-weight", "all-radius"])
@pytest.mark.parametrize("case", list(FILTERS))
def test_stream_equals_simulate(case, effects, family):
    m = model(case, effects, family)
    t, v = signal()
    want = m.simulate(v, t, input_range=RANGE)
    assert np.max(np.abs(stream_simulate(m, v, t, input_range=RANGE) - want)) < 1e-12
    # the filter changed the output (it is not dropped)
    assert np.max(np.abs(want - unfiltered(m).simulate(v, t, input_range=RANGE))) > 1e-2


def test_stream_without_delay_and_from_a_nonzero_start():
    """No delay (the term is y[k] of x_f[k]), the input starting away from 0: the filter starts
    at rest around v[0], its plays at rest at 0 like those of v."""
    m = model("lowpass_then_mode", ("dynamics", "creep", "asymmetry"))
    t, v = signal(800)
    v = v + 0.6
    want = m.simulate(v, t)
    assert np.max(np.abs(stream_simulate(m, v, t) - want)) < 1e-12
    # y[k] = sum_i w_i Gamma_{r_i}[F[v]][k] + offset + the terms of h0 (the plays of v)
    only = replace(m, effects=("dynamics",))
    x = prefilter(v, FILTERS["lowpass_then_mode"], DT)
    from pimodel.operators.pi import PIOperator

    ref = PIOperator(np.ones(5), RADII).play_outputs(x) @ m.weights + m.offset
    assert np.max(np.abs(stream_simulate(only, v, t) - ref)) < 1e-12


def test_block_equals_simulate_and_labels_its_states():
    m = model("lowpass_then_mode", ALL)
    t, v = signal(1000)
    blk = m.block()
    labels = state_labels(m)
    assert blk.state_labels == labels
    assert labels[-9:] == ["zf[1]", "zf[2]", "zf[3]", "zf[4]", "zf[5]", "f[1]", "f[2]", "f[3]",
                           "f[4]"]
    assert len(labels) == NativeModel(m).nstates
    res = control.input_output_response(blk, t, v, initial_state=initial_state(blk))
    assert np.max(np.abs(res.outputs - m.simulate(v, t, input_range=RANGE))) < 1e-12
    # the filter's parameters are block parameters; another number of elements is another
    # state layout
    other = [["lowpass", 6e-3], ["mode", 20.0, 1.2]]
    res = control.input_output_response(blk, t, v, params={"diagnosed.wiener_elements": other},
                                        initial_state=initial_state(blk))
    new = replace(m, params={**m.params, "wiener_elements": other})
    assert np.max(np.abs(res.outputs - new.simulate(v, t, input_range=RANGE))) < 1e-12
    with pytest.raises(ValueError, match="state layout changed"):
        control.input_output_response(blk, t, v, params={
            "diagnosed.wiener_elements": [["lowpass", 1e-3]]}, initial_state=initial_state(blk))


def test_sections_are_the_elements_zoh():
    m = model("lowpass_then_mode")
    b, a = prefilter_sections(m)
    assert b.shape == a.shape == (2, 3) and np.all(a[:, 0] == 1.0)
    assert b[0, 2] == a[0, 2] == 0.0  # the low-pass padded
    assert np.allclose(b.sum(axis=1) / a.sum(axis=1), 1.0, rtol=0, atol=1e-12)  # unit gains
    assert prefilter_sections(unfiltered(m)) is None
    after = replace(m, params={**m.params, "dynamics_position": "after", "mode_hz": 40.0,
                               "mode_damping": 0.3})
    assert prefilter_sections(after) is None


@pytest.mark.parametrize(("filt", "message"), [
    ([["lowpass", 1e-3]] * 9, "expected 1 to 8 elements"),
    ([], "wiener_elements = []: expected 1 to 8"),
    (None, "wiener_elements = None"),
    ([["lowpass", 1e-3], ["direct"]], "wiener_elements[1] = ['direct']: expected"),
    ([["mode", -30.0, 0.2]], "wiener_elements[0] = ['mode', -30.0, 0.2]"),
    ([["mode", 30.0]], "wiener_elements[0] = ['mode', 30.0]: expected"),
    ([["lowpass", 1e-3], ["lowpass", float("nan")]], "wiener_elements[1] = ['lowpass', nan]"),
    ([["notch", 1.0]], "wiener_elements[0] = ['notch', 1.0]"),
    (["mode"], "wiener_elements[0] = 'mode'")])
def test_bad_filters_are_named(filt, message):
    m = model()
    bad = replace(m, params={**m.params, "wiener_elements": filt})
    for call in (NativeModel, fmu_parameters, lambda x: x.block()):
        with pytest.raises(ValueError, match=re.escape(message)):
            call(bad)


# ---- the FMU unit -------------------------------------------------------------------------

@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
@pytest.mark.parametrize(("case", "effects", "family"),
                         [("mode_underdamped", ("dynamics",), "weight"),
                          ("lowpass_then_mode", ALL, "weight"),
                          ("mode_overdamped", ALL, "radius"),
                          ("lowpass_direct_then_mode", ALL, "weight")])
def test_unit_equals_simulate(built_fmus, fmi, case, effects, family):
    m = model(case, effects, family)
    name, params = fmu_parameters(m)
    assert name == "DiagnosedModel"
    assert params["n_wiener_elements"] == len(FILTERS[case])
    assert "lti_order" not in params and "n_lti_elements" not in params
    t, v = signal(1200)
    got = run_unit(unit_file(built_fmus, fmi), params, v, DT)
    assert np.max(np.abs(got - m.simulate(v, t, input_range=RANGE))) < 1e-12


def test_unit_starts_the_filtered_plays_at_z0(built_fmus):
    """z0 sets both play sets: a model of one play of radius 0.5, its filter at rest around
    v[0] = 0.1: the filtered play stays at z0 = 0.3 (within the radius), the output w z0."""
    m = DiagnosedModel([0.5], [2.0], 0.0, dt=DT, effects=("dynamics",),
                       params={"dynamics_position": "before",
                               "wiener_elements": [["lowpass", 2e-3]]})
    _, params = fmu_parameters(m)
    got = run_unit(unit_file(built_fmus, "2.0"), {**params, "z0": 0.3}, np.full(5, 0.1), DT)
    assert np.max(np.abs(got - 0.6)) < 1e-15


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_unit_state_round_trip_holds_the_filter(built_fmus, fmi):
    """get, serialize, deserialize and set the FMU state half-way: the continuation equals the
    first run bit for bit (the filter's sections and its plays are in the state)."""
    m = model("lowpass_then_mode", ("dynamics", "creep", "delay"))
    _, params = fmu_parameters(m)
    _, v = signal(400)
    unit = FMUUnit(unit_file(built_fmus, fmi), params)

    def run(xs):
        return step_through(unit, xs, DT)

    try:
        first = run(v[:200])
        handle, t_mid = unit.fmu.getFMUState(), unit.time
        blob = unit.fmu.serializeFMUState(handle)
        unit.fmu.freeFMUState(handle)
        second = run(v[200:])
        handle = unit.fmu.deserializeFMUState(blob)
        unit.fmu.setFMUState(handle)
        unit.fmu.freeFMUState(handle)
        unit.time = t_mid  # the runner's clock follows the restored FMU
        again = run(v[200:])
    finally:
        unit.close()
    assert again == second
    assert np.max(np.abs(np.r_[first, second] - m.simulate(v, input_range=RANGE))) < 1e-12


@pytest.mark.parametrize(
    ("start", "message"),
    [({"n_wiener_elements": 9}, "parameter n_wiener_elements = 9 out of range: 0 <= "
                                "n_wiener_elements <= 8"),
     ({"n_wiener_elements": -1}, "parameter n_wiener_elements = -1 out of range"),
     ({"n_wiener_elements": 1, "wiener_element_a[1]": 2.0},
      "parameter wiener_element_a[1] = 2: each section's denominator must be normalised"),
     ({"n_wiener_elements": 2, "wiener_element_a[4]": 0.5},
      "parameter wiener_element_a[4] = 0.5: each section's denominator must be normalised"),
     ({"n_wiener_elements": 1, "wiener_element_b[2]": float("nan")},
      "prefilter coefficient wiener_element_b[2] = nan is not finite"),
     ({"n_wiener_elements": 2, "wiener_element_a[5]": float("inf")},
      "prefilter coefficient wiener_element_a[5] = inf is not finite"),
     ({"n_wiener_elements": 1, "wiener_element_a[2]": -1.0},
      "wiener_element_a[1..3] = (1, -1, 0): the section has a pole at z = 1")])
@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_bad_filter_parameters_give_logged_errors(built_fmus, fmi, start, message):
    with pytest.raises(ValueError, match="initialisation failed") as err:
        FMUUnit(unit_file(built_fmus, fmi), start)
    assert message in str(err.value)


def _check_fmu(fmu: Path, fmi: str) -> None:
    """fmpy validate and (when installed) fmutool -check pass."""
    assert validate_fmu(str(fmu)) == []
    exe = shutil.which("fmutool", path=str(Path(sys.executable).parent))
    if exe is None:
        return
    chk = subprocess.run([exe, "-input", str(fmu), "-check"], capture_output=True, text=True,
                         timeout=120)
    assert chk.returncode == 0 and f"No semantic error against the FMI-{fmi[0]}" in \
        chk.stdout + chk.stderr, chk.stdout + chk.stderr


@pytest.mark.slow
@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_cli_builds_a_wiener_fmu_that_validates_and_runs_in_the_masters(tmp_path, fmi):
    """pimodel fmu build --model MODEL.json of a Wiener model with every effect: fmpy validate,
    fmutool -check, fmpy.simulate_fmu (the model's values as start values), the co-simulation
    master and the native block, each equal to simulate to 1e-12."""
    from pimodel.cli import main

    m = model("lowpass_then_mode", ALL, "radius")
    path = m.save(tmp_path / "stage.json")
    out = tmp_path / "fmus"
    assert main(["fmu", "build", "--model", str(path), "--out", str(out),
                 "--fmi-version", fmi]) == 0
    fmu = out / f"stage_1_DiagnosedModel{'_fmi3' if fmi == '3.0' else ''}.fmu"
    _check_fmu(fmu, fmi)
    t, v = signal(1000)
    want = m.simulate(v, t, input_range=RANGE)
    inp = np.array(list(zip(t, v, strict=True)), dtype=[("time", float), ("v", float)])
    res = fmpy.simulate_fmu(str(fmu), input=inp, output=["y"], stop_time=t[-1] + DT,
                            output_interval=DT)
    assert np.max(np.abs(res["y"][1:] - want)) < 1e-12  # y recorded at t_{k+1} is y[k]
    assert np.max(np.abs(cosimulate_chain([fmu], v, DT) - want)) < 1e-12
    blk = m.block()
    r = control.input_output_response(blk, t, v, initial_state=initial_state(blk))
    assert np.max(np.abs(r.outputs - want)) < 1e-12


def _diagnosed(stage: str):
    """The augmented model the diagnosis chose on a stage of tests/test_diagnosis_wiener.py,
    and the validate record."""
    from test_diagnosis_wiener import alt_driver_records, truth_driver_records

    from pimodel.diagnosis import diagnose

    if stage == "truth_lowpass":  # pimodel.stages.pi_stage PI behind a first-order driver
        train, validate, _ = truth_driver_records(0)
        return diagnose(train, validate).model(augmented=True), validate[0]
    # pimodel.stages.preisach_stage Preisach behind a second-order low-pass (seed 1: the diagnosis
    # fits a mode of damping above 1)
    train, validate = alt_driver_records(1)
    return diagnose(train, validate, initial_state="unknown").model(augmented=True), validate[0]


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("stage", ["truth_lowpass", "alt_mode"])
def test_diagnosed_wiener_model_exports_an_fmu_equal_to_simulate(tmp_path, stage):
    """A model the diagnosis chose (verdict dynamics before the hysteresis) on a stage written
    in tests/test_diagnosis_wiener.py: the C stream on the whole validate record, and the
    augmented model exported as FMU (FMI 2 and 3; fmpy validate, fmutool -check) in the
    co-simulation master and the block on its first samples, equal simulate to 1e-12."""
    from pimodel.fmu.model_fmu import build_model_fmus

    m, rec = _diagnosed(stage)
    assert m.dynamics_before and m.params["wiener_elements"]
    assert m.params["wiener_elements"][0][0] == ("lowpass" if stage == "truth_lowpass" else
                                                 "mode")
    rng = 2 * m.radii[-1]
    want = m.simulate(rec.v, rec.t, input_range=rng)
    assert np.max(np.abs(stream_simulate(m, rec.v, rec.t, input_range=rng) - want)) < 1e-12
    k = 4000
    v, t = rec.v[:k], rec.t[:k] - rec.t[0]
    want = m.simulate(v, t, input_range=rng)
    for fmi in ("2.0", "3.0"):
        (fmu,) = build_model_fmus(m, tmp_path / fmi, stem="augmented", fmi_version=fmi)
        _check_fmu(fmu, fmi)
        assert np.max(np.abs(cosimulate_chain([fmu], v, m.dt) - want)) < 1e-12
    blk = m.block()
    r = control.input_output_response(blk, t[:1000], v[:1000], initial_state=initial_state(blk))
    assert np.max(np.abs(r.outputs - want[:1000])) < 1e-12


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_diagnose_export_writes_a_wiener_fmu(tmp_path):
    """pimodel diagnose --export on the records of the first-order driver stage: the augmented
    model's FMU (a Wiener model) validates and equals the exported model's simulate to 1e-12
    in the co-simulation master; its inverse FMU equals the batch inverse one sample later
    (reference_range 0 both: the model's default, so the root rule's scale is the same)."""
    from test_diagnosis_wiener import truth_driver_records

    from pimodel.cli import main
    from pimodel.diagnosis.model import load_diagnosed_model
    from pimodel.records import save_record

    train, validate, _ = truth_driver_records(0)
    paths = [save_record(r, tmp_path / f"{name}.csv")
             for r, name in ((train[0], "train"), (validate[0], "validate"))]
    out = tmp_path / "export"
    assert main(["diagnose", "--train", str(paths[0]), "--validate", str(paths[1]), "--json",
                 str(tmp_path / "r.json"), "--export", str(out)]) == 0
    m = load_diagnosed_model(out / "augmented.json")
    assert m.dynamics_before
    fmu = out / "augmented_1_DiagnosedModel.fmu"
    _check_fmu(fmu, "2.0")
    v = validate[0].v[:3000]
    want = m.simulate(v, input_range=2 * m.radii[-1])
    assert np.max(np.abs(cosimulate_chain([fmu], v, m.dt) - want)) < 1e-12
    # its feedforward's FMU: the filter's inverse after the solve (post sections), the batch
    # inverse delayed by one sample; chained into the model FMU, the model follows the record
    inverse = out / "augmented_1_DiagnosedInverse.fmu"
    _check_fmu(inverse, "2.0")
    y_d = validate[0].y[:3000]
    v_ff = cosimulate_chain([inverse], y_d, m.dt)
    batch = m.inverse().simulate(y_d)
    assert np.max(np.abs(v_ff[1:] - batch[:-1])) < 1e-9 * np.ptp(batch)
    y = cosimulate_chain([inverse, fmu], y_d, m.dt)
    assert np.sqrt(np.mean((y[1:] - y_d[:-1]) ** 2)) < 0.05 * np.ptp(y_d)
