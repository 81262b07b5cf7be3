"""The linear part's further elements on the C core (issue 19): a DiagnosedModel whose dynamics
has more than one mode (or a low-pass, a direct term; ``lti_elements``, ``lti_gains`` of
:mod:`pimodel.diagnosis.lti`) streams sample by sample as the runner, the python-control block
and the DiagnosedModel FMU (FMI 2 and 3), each equal to ``DiagnosedModel.simulate`` to 1e-12;
malformed elements are refused with the element named (ValueError in Python, a logged
fmi2Error/fmi3Error in the FMU). The end-to-end test on a diagnosed
``pimodel.stages.preisach_stage``
two-mode stage is in ``tests/test_diagnosis_lti.py``."""

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

from pimodel._native import LIMITS
from pimodel.blocks import initial_state
from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.native_model import (
    MAX_ELEMENTS,
    NativeModel,
    element_sections,
    fmu_parameters,
    state_labels,
    stream_simulate,
)
from pimodel.fmu.model_fmu import cosimulate_chain
from pimodel.fmu.unit import FMUUnit

sys.path.insert(0, str(Path(__file__).parent))
from diagnosed_unit import run_unit, unit_file  # noqa: E402

DT = 1e-3
RADII = [0.0, 0.15, 0.4, 0.7, 1.0]
ELEMENTS = {
    "two_modes": ([["mode", 130.0, 0.05]], [0.3]),
    "three_modes": ([["mode", 130.0, 0.05], ["mode", 260.0, 0.2]], [0.3, -0.1]),
    "modes_lowpass_direct": ([["mode", 130.0, 0.05], ["lowpass", 2e-3], ["direct"]],
                             [0.3, 0.2, 0.05]),
}
OTHER_EFFECTS = {  # every other effect beside the dynamics (the delay delays the elements too)
    "creep_lag_gains": [0.04, -0.01], "creep_time_constants_s": [0.003, 0.03],
    "asymmetry_quadratic": 0.05, "asymmetry_cubic": -0.02, "center": 0.4, "half_range": 1.1,
    "rate_gains": [0.3, -0.2], "rate_family": "weight", "rate_time_constant_s": 3e-3,
    "drift_per_s": 0.02, "drift_clock": "record", "delay_samples": 2.5,
}
ALL = ("dynamics", "creep", "asymmetry", "rate", "drift", "delay")


def model(case: str = "two_modes", effects: tuple = ("dynamics",)) -> DiagnosedModel:
    """Signed weights, a reference fit unlike them, the base mode at 40 Hz and the case's
    further elements."""
    elements, gains = ELEMENTS[case]
    params = {"mode_hz": 40.0, "mode_damping": 0.1, "lti_elements": elements,
              "lti_gains": gains, "rate_scale": 5.0, **OTHER_EFFECTS}
    return DiagnosedModel(RADII, [1.2, -0.4, 0.8, -0.3, 0.25], 0.3, dt=DT, effects=effects,
                          reference_weights=[1.0, -0.2, 0.7, -0.2, 0.2], reference_offset=0.1,
                          params=params)


def signal(n: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """Times from 0 and an input with minor loops and a step (it rings the modes)."""
    t = np.arange(n) * DT
    v = 1.5 * np.sin(2 * np.pi * 1.3 * t) + 0.3 * np.sin(2 * np.pi * 11 * t)
    v[n // 2:] += 0.5
    return t, v


def without_elements(m: DiagnosedModel) -> DiagnosedModel:
    return replace(m, params={k: x for k, x in m.params.items()
                              if k not in ("lti_elements", "lti_gains")})


@pytest.mark.parametrize("effects", [("dynamics",), ALL], ids=["dynamics", "all"])
@pytest.mark.parametrize("case", list(ELEMENTS))
def test_stream_equals_simulate(case, effects):
    m = model(case, effects)
    t, v = signal()
    want = m.simulate(v, t)
    got = stream_simulate(m, v, t, input_range=float(np.ptp(v)))
    assert np.max(np.abs(got - want)) < 1e-12
    # the further elements changed the output (they are not dropped)
    assert np.max(np.abs(want - without_elements(m).simulate(v, t))) > 1e-3


def test_block_equals_simulate_and_labels_its_states():
    m = model("modes_lowpass_direct", ALL)
    t, v = signal(1200)
    blk = m.block()
    labels = state_labels(m)
    assert blk.state_labels == labels
    assert [x for x in labels if x.startswith("e[")] == [f"e[{i}]" for i in range(1, 9)]
    res = control.input_output_response(blk, t, v, initial_state=initial_state(blk))
    assert np.max(np.abs(res.outputs - m.simulate(v, t, input_range=2 * RADII[-1]))) < 1e-12
    # a gain is a block parameter; another number of elements is another state layout
    res = control.input_output_response(blk, t, v, params={"diagnosed.lti_gains": [0.1, 0, 0]},
                                        initial_state=initial_state(blk))
    new = replace(m, params={**m.params, "lti_gains": [0.1, 0, 0]})
    assert np.max(np.abs(res.outputs - new.simulate(v, t, input_range=2 * RADII[-1]))) < 1e-12
    with pytest.raises(ValueError, match="state layout changed"):
        control.input_output_response(blk, t, v, params={
            "diagnosed.lti_elements": [["direct"]], "diagnosed.lti_gains": [0.1]},
            initial_state=initial_state(blk))


def test_sections_are_the_elements_zoh_and_the_bound_matches_the_c_core():
    m = model("modes_lowpass_direct")
    b, a, g = element_sections(m)
    assert b.shape == a.shape == (4, 3) and np.all(a[:, 0] == 1.0)
    assert np.allclose(b.sum(axis=1) / a.sum(axis=1), 1.0, rtol=0, atol=1e-12)  # unit gains
    assert g.tolist() == [0.3, 0.2, 0.05]
    assert element_sections(without_elements(m)) is None
    assert element_sections(replace(m, effects=())) is None  # no dynamics: not used
    assert MAX_ELEMENTS == LIMITS["PIM_DIAG_MAX_ELEMENTS"]


@pytest.mark.parametrize(("change", "message"), [
    ({"lti_elements": [["mode", 130.0, 0.05]] * 9, "lti_gains": [0.1] * 9},
     "9 elements; the C stream and the FMU take at most 8"),
    ({"lti_gains": [0.3, 0.1]}, "lti_gains: expected 1 gains, one per element"),
    ({"lti_gains": None}, "lti_gains: expected 1 gains"),
    ({"lti_elements": [["mode", -130.0, 0.05]]}, "lti_elements[0] = ['mode', -130.0, 0.05]"),
    ({"lti_elements": [["mode", 130.0]]}, "lti_elements[0] = ['mode', 130.0]: expected"),
    ({"lti_elements": [["lowpass", float("nan")]]}, "lti_elements[0] = ['lowpass', nan]"),
    ({"lti_elements": [["notch", 1.0]]}, "lti_elements[0] = ['notch', 1.0]"),
    ({"lti_elements": ["mode"]}, "lti_elements[0] = 'mode'"),
    ({"lti_elements": [["direct", 1.0]]}, "lti_elements[0] = ['direct', 1.0]"),
    ({"mode_damping": 0.0}, "mode_hz, mode_damping = ('mode', 40.0, 0.0)")])
def test_bad_elements_are_named(change, message):
    m = model()
    with pytest.raises(ValueError, match=re.escape(message)):
        NativeModel(replace(m, params={**m.params, **change}))


# ---- the FMU unit -------------------------------------------------------------------------

@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
@pytest.mark.parametrize(("case", "effects"), [("three_modes", ("dynamics",)),
                                               ("modes_lowpass_direct", ALL)])
def test_unit_equals_simulate(built_fmus, fmi, case, effects):
    m = model(case, effects)
    name, params = fmu_parameters(m)
    assert params["n_lti_elements"] == len(ELEMENTS[case][0])
    t, v = signal(1500)
    got = run_unit(unit_file(built_fmus, fmi), params, v, DT)
    assert np.max(np.abs(got - m.simulate(v, t, input_range=2 * RADII[-1]))) < 1e-12


@pytest.mark.parametrize(
    ("start", "message"),
    [({"n_lti_elements": 9}, "parameter n_lti_elements = 9 out of range: 0 <= n_lti_elements "
                             "<= 8"),
     ({"n_lti_elements": -1}, "parameter n_lti_elements = -1 out of range"),
     ({"n_lti_elements": 1, "lti_element_a[4]": 2.0},
      "parameter lti_element_a[4] = 2: each section's denominator must be normalised"),
     ({"n_lti_elements": 1, "lti_element_b[5]": float("nan")},
      "lti_element_b[5] = nan is not finite"),
     ({"n_lti_elements": 2, "lti_element_a[5]": float("inf")},
      "lti_element_a[5] = inf is not finite"),
     ({"n_lti_elements": 2, "lti_gain[2]": float("nan")}, "lti_gain[2] = nan is not finite"),
     ({"n_lti_elements": 1, "lti_element_a[5]": -1.0},
      "a further LTI element has a pole at z = 1")])
@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_bad_element_parameters_give_logged_errors(built_fmus, fmi, start, message):
    with pytest.raises(ValueError, match="initialisation failed") as err:
        FMUUnit(unit_file(built_fmus, fmi), start)
    assert message in str(err.value)


@pytest.mark.slow
@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_cli_builds_a_multi_mode_fmu_that_validates_and_runs_in_the_masters(tmp_path, fmi):
    """pimodel fmu build --model MODEL.json of a three-mode model with every effect: fmpy
    validate, fmutool -check, fmpy.simulate_fmu (the model's values as start values), the
    co-simulation master and the native block, each equal to simulate to 1e-12."""
    from pimodel.cli import main

    m = model("three_modes", ALL)
    path = m.save(tmp_path / "stage.json")
    out = tmp_path / "fmus"
    assert main(["fmu", "build", "--model", str(path), "--out", str(out),
                 "--fmi-version", fmi]) == 0
    fmu = out / f"stage_1_DiagnosedModel{'_fmi3' if fmi == '3.0' else ''}.fmu"
    assert validate_fmu(str(fmu)) == []
    t, v = signal(1000)
    want = m.simulate(v, t, input_range=2 * RADII[-1])
    inp = np.array(list(zip(t, v, strict=True)), dtype=[("time", float), ("v", float)])
    res = fmpy.simulate_fmu(str(fmu), input=inp, output=["y"], stop_time=t[-1] + DT,
                            output_interval=DT)
    assert np.max(np.abs(res["y"][1:] - want)) < 1e-12  # y recorded at t_{k+1} is y[k]
    assert np.max(np.abs(cosimulate_chain([fmu], v, DT) - want)) < 1e-12
    blk = m.block()
    r = control.input_output_response(blk, t, v, initial_state=initial_state(blk))
    assert np.max(np.abs(r.outputs - want)) < 1e-12
    exe = shutil.which("fmutool", path=str(Path(sys.executable).parent))
    if exe is None:
        pytest.skip("fmutool (fmu-manipulation-toolbox) is not installed; fmpy checks passed")
    chk = subprocess.run([exe, "-input", str(fmu), "-check"], capture_output=True, text=True,
                         timeout=120)
    assert chk.returncode == 0 and f"No semantic error against the FMI-{fmi[0]}" in \
        chk.stdout + chk.stderr, chk.stdout + chk.stderr


def test_block_of_a_model_with_report_parameters():
    """A diagnosed model's params also hold the report's plain data (``dynamics_modes``, a list
    of dicts; ``dynamics_order``): the block keeps them as settings and still equals simulate."""
    m = model("two_modes")
    m = replace(m, params={**m.params, "dynamics_order": 2,
                           "dynamics_modes": [{"hz": 40.0, "damping": 0.1, "share": 0.7},
                                              {"hz": 130.0, "damping": 0.05, "share": 0.3}]})
    t, v = signal(300)
    blk = m.block()
    res = control.input_output_response(blk, t, v, initial_state=initial_state(blk))
    assert np.max(np.abs(res.outputs - m.simulate(v, t))) < 1e-12


def test_diagnosis_limits_are_the_c_cores():
    """The C limits the diagnosis checks first (one place, pimodel.diagnosis.limits) are the C
    core's (pimodel._native.LIMITS, which tests/test_fmu_spec.py holds equal to the header) and
    the FMU builder's."""
    from pimodel.diagnosis import limits
    from pimodel.fmu.build import MAX_LTI_ELEMENTS, NMAX

    assert limits.NMAX == NMAX == LIMITS["PIM_MAX_PLAYS"]
    assert limits.MAX_ELEMENTS == MAX_LTI_ELEMENTS == LIMITS["PIM_DIAG_MAX_ELEMENTS"]
    assert limits.MAX_DELAY == LIMITS["PIM_DIAG_MAX_DELAY"] - 2
    assert limits.MAX_ORDER == LIMITS["PIM_DIAG_MAX_ORDER"]
    assert limits.SECTION == LIMITS["PIM_DIAG_SECTION"]
    assert limits.MAX_SECTIONS == LIMITS["PIM_DINV_MAX_SECTIONS"]
    assert limits.MAX_LATENCY == LIMITS["PIM_DINV_MAX_LATENCY"]


@pytest.mark.parametrize(("old", "new"), [
    ("pimodel.diagnosis.stream", "pimodel.diagnosis.native_model"),
    ("pimodel.diagnosis.inverse_native", "pimodel.diagnosis.native_inverse"),
    ("pimodel.diagnosis.inverse_stream", "pimodel.diagnosis.reference_inverse")])
def test_old_diagnosis_module_paths_warn_and_are_the_new_modules(old, new):
    import importlib

    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=f"import {new} instead"):
        module = importlib.import_module(old)
    assert module is importlib.import_module(new)
