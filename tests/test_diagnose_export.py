"""``pimodel diagnose --export DIR``: the model JSON files and both models' FMUs."""

import json

import numpy as np
import pytest

from pimodel.cli import main
from pimodel.diagnosis.model import load_diagnosed_model
from pimodel.model_files import load_model
from pimodel.records import save_record
from pimodel.stages.pi_stage import excitation, random_truth


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    d = tmp_path_factory.mktemp("rec")
    truth = random_truth(["creep"], 0)
    tt, vt = excitation("train", seed=1)
    tv, vv = excitation("validate", seed=2)
    return (save_record(truth.record(tt, vt, 1), d / "train.csv"),
            save_record(truth.record(tv, vv, 2), d / "validate.csv"), vv)


def test_export_writes_models(records, tmp_path):
    train, validate, vv = records
    out = tmp_path / "export"
    assert main(["diagnose", "--train", str(train), "--validate", str(validate), "--json",
                 str(tmp_path / "r.json"), "--export", str(out), "--no-fmu"]) == 0
    aug = load_diagnosed_model(out / "augmented.json")
    nom = load_diagnosed_model(out / "nominal.json")
    assert aug.effects == ("creep",) and nom.effects == ()
    op = load_model(out / "nominal.model.json")
    assert np.max(np.abs(op.simulate(vv) - nom.simulate(vv))) < 1e-9
    assert json.loads((out / "augmented.json").read_text())["type"] == "DiagnosedModel"


def test_export_refuses_to_overwrite_an_input(records, tmp_path):
    train, validate, _ = records
    clash = tmp_path / "nominal.json"
    clash.write_text(train.read_text())
    code = main(["diagnose", "--train", str(clash), "--validate", str(validate), "--json",
                 str(tmp_path / "r.json"), "--export", str(tmp_path), "--no-fmu"])
    assert code != 0
    assert clash.read_text() == train.read_text()


@pytest.mark.slow
def test_export_writes_fmus_equal_to_the_models(records, tmp_path):
    """--export writes both models' FMUs (unit DiagnosedModel, signed weights and the creep
    term in parallel): fmpy validate and fmutool -check pass, and in the co-simulation master
    each equals its model's simulate to 1e-12 on the validate input; and their feedforwards'
    FMUs (unit DiagnosedInverse) validate and equal the C stream of the inverse."""
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    from fmpy.validation import validate_fmu

    from pimodel.diagnosis.inverse_native import NativeInverse
    from pimodel.fmu.model_fmu import cosimulate_chain

    train, validate, vv = records
    out = tmp_path / "export"
    assert main(["diagnose", "--train", str(train), "--validate", str(validate), "--json",
                 str(tmp_path / "r.json"), "--export", str(out)]) == 0
    exe = shutil.which("fmutool", path=str(Path(sys.executable).parent))
    for stem in ("augmented", "nominal"):
        model = load_diagnosed_model(out / f"{stem}.json")
        fmu = out / f"{stem}_1_DiagnosedModel.fmu"
        assert validate_fmu(str(fmu)) == []
        if exe is not None:
            chk = subprocess.run([exe, "-input", str(fmu), "-check"], capture_output=True,
                                 text=True, timeout=120)
            assert chk.returncode == 0 and "No semantic error against the FMI-2" in \
                chk.stdout + chk.stderr, chk.stdout + chk.stderr
        v = vv[:4000]
        want = model.simulate(v, input_range=2 * model.radii[-1])
        assert np.max(np.abs(cosimulate_chain([fmu], v, model.dt) - want)) < 1e-12
        # the feedforward's FMU (unit DiagnosedInverse) equals the C stream of its inverse
        inverse_fmu = out / f"{stem}_1_DiagnosedInverse.fmu"
        assert validate_fmu(str(inverse_fmu)) == []
        y_d = want[:1500]
        v_ff = NativeInverse(model.inverse()).run(y_d)
        assert np.max(np.abs(cosimulate_chain([inverse_fmu], y_d, model.dt) - v_ff)) < 1e-9
    assert np.any(load_diagnosed_model(out / "nominal.json").weights < 0)  # signed weights
