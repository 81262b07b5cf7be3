"""Model files: one format (operator, offset, sample time, units, provenance) written by
identify, diagnose --export and save_model, and one schema checked by load_model and
pimodel fmu build --model (issue 30's first point; issue 32 cases 5, 6, 12, 13, 14, 17)."""

from __future__ import annotations

import copy
import json
import math
import shutil

import control
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pimodel import PIOperator
from pimodel.blocks import initial_state, inverse_pi_block, pi_block
from pimodel.cli import main
from pimodel.diagnosis.limits import NMAX
from pimodel.diagnosis.model import DiagnosedModel
from pimodel.model_files import Model, check_model_dict, load_model, model_to_dict, save_model
from pimodel.operators.cascade import Cascade
from pimodel.operators.creep import CreepOperator
from pimodel.operators.envelopes import Envelope
from pimodel.operators.generalized import GeneralizedPI
from pimodel.operators.rate_dependent import RateDependentPI
from pimodel.records import Record, save_record


def diagnosed(effects=("creep", "delay")) -> dict:
    """A valid DiagnosedModel JSON with creep and delay."""
    return DiagnosedModel([0.0, 0.3], [1.0, 0.5], 0.1, dt=1e-3, effects=effects,
                          params={"creep_lag_gains": [0.05, 0.02],
                                  "creep_time_constants_s": [0.1, 1.0],
                                  "delay_samples": 2}).to_dict()


def bases() -> list[dict]:
    """One valid model file of each family (with metadata at the top)."""
    pi = Model(PIOperator([1.0, 0.5, 0.2], [0.0, 0.2, 0.5]), offset=0.3, dt=1e-3,
               units={"time": "s", "input": "V", "output": "um"},
               provenance={"record": "lab.csv", "method": "adaptive"}).as_file_dict()
    return [pi, model_to_dict(CreepOperator([0.05, 0.02], [0.1, 1.0], dt=1e-3)),
            model_to_dict(RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)),
            model_to_dict(GeneralizedPI([1.0, 0.5], [0.0, 0.2],
                                        output_envelope=Envelope.affine(1.0, 0.1))),
            model_to_dict(Cascade(PIOperator([1.0, 0.5], [0.0, 0.2]),
                                  CreepOperator([0.05], [0.1], dt=1e-3))),
            diagnosed()]


def write(tmp_path, d, name="m.json"):
    path = tmp_path / name
    path.write_text(json.dumps(d))
    return path


def refused_everywhere(tmp_path, capsys, d, pattern):
    """load_model and fmu build --model refuse ``d`` with the same message (file, key)."""
    path = write(tmp_path, d)
    with pytest.raises(ValueError, match=pattern) as err:
        load_model(path)
    assert str(path) in str(err.value)
    assert main(["fmu", "build", "--model", str(path), "--out", str(tmp_path / "fmus")]) == 2
    message = capsys.readouterr().err
    assert str(path) in message and len(message) < 400, message
    assert pattern.split(":")[0].replace("\\", "") in message
    assert not (tmp_path / "fmus").exists() or not any((tmp_path / "fmus").iterdir())


# --- issue 32 case 5: types and keys -------------------------------------------------------------

@pytest.mark.parametrize("key,value,pattern", [
    ("inverted", "false", r"model\.inverted: expected true or false, got 'false'"),
    ("rate_time_constnt", 0.1, r"model\.rate_time_constnt: unknown key; did you mean "
                               r"'rate_time_constant'"),
    ("initial_sate", 0.0, r"model\.initial_sate: unknown key; did you mean 'initial_state'"),
])
def test_case5_types_and_unknown_keys_are_refused(tmp_path, capsys, key, value, pattern):
    d = (model_to_dict(RateDependentPI([1.0], [0.0], rate_gain=0.01, dt=1e-3))
         if key.startswith("rate") else model_to_dict(CreepOperator([0.05], [0.1], dt=1e-3)))
    d[key] = value
    refused_everywhere(tmp_path, capsys, d, pattern)


def test_case5_string_signed_weights_cannot_let_a_negative_weight_through():
    d = model_to_dict(GeneralizedPI([1.0, 0.5], [0.0, 0.2]))
    d["signed_weights"], d["weights"] = "false", [1.0, -0.5]
    with pytest.raises(ValueError, match=r"model\.signed_weights: expected true or false"):
        check_model_dict(d)


# --- case 6: non-finite and out-of-range values of a DiagnosedModel ---------------------------

@pytest.mark.parametrize("path,value,key", [
    (("weights", 1), math.nan, r"model\.weights\[1\]"),
    (("offset",), math.nan, r"model\.offset"),
    (("params", "creep_lag_gains", 0), math.nan, r"model\.params\.creep_lag_gains\[0\]"),
    (("params", "creep_time_constants_s", 1), -1.0,
     r"model\.params\.creep_time_constants_s\[1\]: expected a finite number > 0"),
    (("dt",), math.inf, r"model\.dt: expected a finite number > 0"),
])
def test_case6_nonfinite_diagnosed_model_is_refused(tmp_path, capsys, path, value, key):
    d = diagnosed()
    target = d
    for part in path[:-1]:
        target = target[part]
    target[path[-1]] = value
    refused_everywhere(tmp_path, capsys, d, key)


# --- case 12: parameters an effect needs --------------------------------------------------------

@pytest.mark.parametrize("effects,drop,key", [
    (("creep",), "creep_lag_gains", r"model\.params\.creep_lag_gains: missing key"),
    (("delay",), "delay_samples", r"model\.params\.delay_samples: missing key"),
])
def test_case12_missing_effect_parameter_is_named(tmp_path, capsys, effects, drop, key):
    d = diagnosed(effects)
    del d["params"][drop]
    refused_everywhere(tmp_path, capsys, d, key)


# --- case 13: a number beyond float64 ------------------------------------------------------------

def test_case13_huge_integer_names_file_and_key(tmp_path, capsys):
    path = tmp_path / "m.json"
    path.write_text('{"type": "PIOperator", "weights": [1, ' + "1" + "0" * 400 +
                    '], "radii": [0, 0.1]}')
    with pytest.raises(ValueError, match=r"m\.json: model\.weights\[1\]: .*401 digits"):
        load_model(path)
    refused_everywhere(tmp_path, capsys, json.loads(path.read_text()), r"model\.weights\[1\]")


# --- case 14: more plays than the FMU takes ---

@pytest.mark.parametrize("n", [NMAX + 1, 10_000])
def test_case14_too_many_plays_says_at_most(tmp_path, capsys, n):
    rng = np.random.default_rng(14)
    radii = np.sort(rng.uniform(0, 1, n))
    radii[0] = 0.0
    save_model(PIOperator(rng.uniform(0.1, 1, n), radii), tmp_path / "m.json")
    assert main(["fmu", "build", "--model", str(tmp_path / "m.json"), "--out",
                 str(tmp_path / "fmus")]) == 2
    err = capsys.readouterr().err
    assert f"model.weights: {n} plays; the FMU takes at most {NMAX} plays" in err
    assert len(err) < 300


def test_case14_diagnosed_model_limit_is_twice_nmax(tmp_path, capsys):
    n = 2 * NMAX + 1
    d = diagnosed(())
    d["radii"], d["weights"] = np.linspace(0, 1, n).tolist(), [0.1] * n
    d["reference_weights"] = [0.1] * n
    write(tmp_path, d, "d.json")
    assert main(["fmu", "build", "--model", str(tmp_path / "d.json"), "--out",
                 str(tmp_path / "fmus")]) == 2
    err = capsys.readouterr().err  # the constructor's limit (Python = FMU) or the FMU check
    assert "d.json" in err and f"{n} plays" in err and f"at most {2 * NMAX}" in err
    assert len(err) < 300


# --- case 17: list lengths ------------------------------------------------------------------------

def test_case17_creep_gains_and_time_constants_of_different_lengths(tmp_path, capsys):
    d = model_to_dict(CreepOperator([0.05, 0.02], [0.1, 1.0], dt=1e-3))
    d["time_constants"] = [0.1]
    refused_everywhere(tmp_path, capsys, d, r"model\.time_constants: expected 2 values, one "
                                            r"per entry of gains, got 1")
    dd = diagnosed(("creep",))
    dd["params"]["creep_time_constants_s"] = [0.1, 1.0, 2.0]
    refused_everywhere(tmp_path, capsys, dd, r"model\.params\.creep_time_constants_s: expected 2")


# --- the format ---

def test_model_file_keeps_offset_units_provenance_and_the_inverse_uses_the_offset(tmp_path):
    rng = np.random.default_rng(30)
    op = PIOperator(rng.uniform(0.2, 1, 4), np.r_[0.0, np.sort(rng.uniform(0.05, 1, 3))])
    offset = float(rng.uniform(-5, 5))
    path = save_model(Model(op, offset=offset, dt=2e-3, units={"input": "V", "output": "um"}),
                      tmp_path / "m.json", source={"record": "lab.csv", "method": "adaptive"})
    m = load_model(path)
    assert (m.offset, m.dt, m.units["output"]) == (offset, 2e-3, "um")
    assert set(m.provenance) >= {"record", "method", "date", "pimodel_version"}
    v = 2 * np.sin(np.linspace(0, 6 * np.pi, 300))
    y = m.simulate(v)
    np.testing.assert_allclose(y, op.simulate(v) + offset, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m.inverse().simulate(y), v, rtol=0, atol=1e-9)
    # the blocks take the offset (and dt) from the model: no second input
    t = np.arange(v.size) * 2e-3
    for block, u, want in ((pi_block(m), v, y), (inverse_pi_block(m), y, v)):
        res = control.input_output_response(block, t, u, initial_state=initial_state(block))
        np.testing.assert_allclose(res.outputs, want, rtol=0, atol=1e-9)
    assert model_to_dict(m) == json.loads(path.read_text())


def test_older_identify_json_is_converted_with_a_warning(tmp_path):
    old = {"method": "adaptive", "n_plays": 2, "weights": [1.0, 0.5], "radii": [0.0, 0.3],
           "offset": 0.25, "fit": {"rms_error": 0.0}, "excitation": {}, "slopes": None,
           "settings": {}, "health": None}
    path = write(tmp_path, old)
    with pytest.warns(UserWarning, match="older pimodel.*PIOperator with its offset"):
        m = load_model(path)
    assert m.offset == 0.25 and m.provenance["method"] == "adaptive"
    v = [0.0, 1.0, -0.5]
    np.testing.assert_allclose(m.simulate(v), PIOperator([1.0, 0.5], [0.0, 0.3]).simulate(v)
                               + 0.25, rtol=0, atol=1e-12)


def test_diagnose_export_writer_and_simulate_model_read_the_same_format(tmp_path):
    d = diagnosed()
    path = save_model(DiagnosedModel.from_dict(d), tmp_path / "aug.json",
                      source={"method": "diagnose"})
    written = json.loads(path.read_text())
    assert written["format_version"] == 2 and written["provenance"]["method"] == "diagnose"
    rng = np.random.default_rng(3)
    op = PIOperator([1.0, 0.4], [0.0, 0.25])
    save_model(Model(op, offset=1.5), tmp_path / "pi.json")
    t = np.arange(200) * 1e-3
    v = np.cumsum(rng.normal(0, 0.05, t.size))
    save_record(Record(t, v, np.zeros_like(v)), tmp_path / "in.csv")
    assert main(["simulate", str(tmp_path / "in.csv"), "--model", str(tmp_path / "pi.json"),
                 "--out", str(tmp_path / "out.csv")]) == 0
    out = np.genfromtxt(tmp_path / "out.csv", delimiter=",", names=True)
    np.testing.assert_allclose(out["y"], op.simulate(v) + 1.5, rtol=0, atol=1e-9)
    assert main(["simulate", str(tmp_path / "in.csv"), "--model", str(tmp_path / "pi.json"),
                 "--weights", "1", "--radii", "0", "--out", str(tmp_path / "o2.csv")]) == 2


# --- property test: random edits either load and simulate finite or name the key ------------------

_VALUES = st.sampled_from(["false", True, None, {}, [], math.nan, math.inf, -math.inf, 10**400,
                           -1.0, 0.0, 1e3, 0.5])


def _paths(d, prefix=()):
    """Every (path, value) inside ``d`` (keys and list positions)."""
    items = d.items() if isinstance(d, dict) else enumerate(d)
    for key, value in items:
        yield (*prefix, key)
        if isinstance(value, (dict, list)) and key != "report":
            yield from _paths(value, (*prefix, key))


@st.composite
def edited(draw):
    base = draw(st.sampled_from(range(len(bases()))))
    d = copy.deepcopy(bases()[base])
    paths = list(_paths(d))
    path = draw(st.sampled_from(paths))
    parent = d
    for part in path[:-1]:
        parent = parent[part]
    last = path[-1]
    action = draw(st.sampled_from(["replace", "delete", "misspell", "grow", "shrink"]))
    key = next((p for p in reversed(path) if isinstance(p, str)), "type")
    if action == "replace":
        parent[last] = draw(_VALUES)
    elif action == "delete" and isinstance(parent, dict):
        del parent[last]
    elif action == "misspell" and isinstance(parent, dict) and isinstance(last, str):
        wrong = last[:-1] + "x"
        parent[wrong] = parent.pop(last)
        key = wrong
    elif action in ("grow", "shrink") and isinstance(parent[last], list) and parent[last]:
        if action == "grow":
            parent[last].append(parent[last][-1])
        else:
            parent[last].pop()
    return d, key


@settings(max_examples=150, derandomize=True, deadline=None)
@given(edited())
def test_property_random_model_edits_load_and_simulate_finite_or_name_the_key(case):
    d, key = case
    v = 0.8 * np.sin(np.linspace(0, 4 * np.pi, 80))
    try:
        m = Model.from_dict(json.loads(json.dumps(d)))
    except ValueError as err:
        assert key in str(err) or "type" in str(err), (key, str(err))
        return
    assert np.all(np.isfinite(m.simulate(v)))


# --- the chain: CSV with its own column names -> identify --json -> fmu build --model -> fmpy

@pytest.mark.slow
@pytest.mark.parametrize("fmt", ["csv", "mat"])
def test_lab_file_chain_identify_fmu_build_equals_the_python_model_with_offset(tmp_path, fmt):
    """CSV or MATLAB .mat with its own column names -> identify --json -> fmu build --model on
    that very file -> the FMU in fmpy equals the Python model with its offset."""
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler on PATH")
    from pimodel.fmu.model_fmu import build_model_fmus, cosimulate_chain

    rng = np.random.default_rng(32)
    stage = PIOperator(rng.uniform(0.3, 1.0, 3), [0.0, 0.15, 0.4])
    offset = float(rng.uniform(2, 5))
    dt = 1 / 200  # 200 Hz
    t = np.arange(0, 12, dt)
    v = 2 * np.abs((t % 2) - 1) - 1  # a 0.5 Hz triangle, 2 V peak to peak
    y = stage.simulate(v) + offset + rng.normal(0, 1e-3, t.size)
    lab = tmp_path / f"lab.{fmt}"
    if fmt == "csv":
        np.savetxt(lab, np.c_[t, v, y], delimiter=",", fmt="%.17g",
                   header="time_s,voltage_V,disp_um", comments="")
    else:
        scipy_io = pytest.importorskip("scipy.io")
        scipy_io.savemat(lab, {"time_s": t, "voltage_V": v, "disp_um": y})  # (1, N) arrays
    model_json = tmp_path / "m.json"
    assert main(["identify", str(lab), "--columns", "time_s,voltage_V,disp_um",
                 "--json", str(model_json), "--method", "conventional", "--plays", "3"]) == 0
    m = load_model(model_json)
    assert m.units == {"time": "s", "input": "V", "output": "um"} and m.dt == pytest.approx(dt)
    assert abs(m.offset - offset) < 0.2 and m.provenance["record"].endswith(lab.name)
    assert main(["fmu", "build", "--model", str(model_json), "--out", str(tmp_path / "fmus")]) == 0
    fwd = sorted((tmp_path / "fmus").glob("m_1_*.fmu"))
    fwd = [p for p in fwd if "Inverse" not in p.name]
    assert len(fwd) == 1, fwd
    vv = v[:400]
    yy = cosimulate_chain(fwd, vv, dt)
    np.testing.assert_allclose(yy, m.simulate(vv), rtol=0, atol=1e-9)
    # the feedforward with the offset: one FMU chain, y_d in, v out
    inv = build_model_fmus(m.inverse().as_operator(), tmp_path / "inv", stem="inv")
    np.testing.assert_allclose(cosimulate_chain(inv, yy, dt), m.inverse().simulate(yy), rtol=0,
                               atol=1e-9)
    np.testing.assert_allclose(cosimulate_chain(inv, yy, dt), vv, rtol=0, atol=1e-6)
