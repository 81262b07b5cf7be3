"""``pimodel diagnose --export DIR``: the model JSON files and the nominal model's FMU."""

import json

import numpy as np
import pytest

from pimodel.cli import main
from pimodel.data import save_record
from pimodel.diagnosis.model import load_diagnosed_model
from pimodel.models import load_model
from pimodel.truth import excitation, random_truth


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


def test_export_says_why_a_model_has_no_fmu(records, tmp_path, capsys):
    train, validate, _ = records
    assert main(["diagnose", "--train", str(train), "--validate", str(validate), "--json",
                 str(tmp_path / "r.json"), "--export", str(tmp_path / "x"), "--no-fmu"]) == 0
    assert "augmented model: no FMU" in capsys.readouterr().out
