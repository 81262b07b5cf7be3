"""Sim-to-real gap diagnosis: withheld effects (generation and diagnosis kept apart: the effect
name never reaches diagnose), a clean record, bad input, the CLI, and the real record.

The unit suite runs one seed per effect and one pair; the full sweep (10 seeds per effect and
pairs) is ``studies/sim_to_real.py`` (figures in the README)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pimodel import Record, save_record
from pimodel.cli import main
from pimodel.diagnosis import diagnose
from pimodel.truth import EFFECTS, excitation, random_truth


def records(effects, seed):
    tt, vt = excitation("train", seed=2 * seed + 1)
    tv, vv = excitation("validate", seed=2 * seed + 2)
    truth = random_truth(list(effects), seed)
    return [truth.record(tt, vt, seed, "train")], [truth.record(tv, vv, 100 + seed, "val")]


@pytest.mark.parametrize("effect", EFFECTS)
def test_withheld_single_effect(effect):
    train, validate = records([effect], 0)
    v = diagnose(train, validate).verdict
    assert v["effects"] == [effect]
    assert v["shrink"] >= 0.5


@pytest.mark.parametrize("pair,seed", [(("creep", "asymmetry"), 3), (("dynamics", "drift"), 1)])
def test_withheld_pair(pair, seed):
    # seed 1 of dynamics+drift: a light 2 kHz mode (damping 0.02), narrower than the mode grid
    train, validate = records(list(pair), seed)
    v = diagnose(train, validate).verdict
    assert sorted(v["effects"]) == sorted(pair)
    assert v["shrink"] >= 0.5


def test_clean_pi_says_none():
    train, validate = records([], 4)
    rep = diagnose(train, validate)
    assert rep.verdict["effects"] == ["none"]
    data = rep.to_json()
    assert {"nominal", "where", "candidates", "verdict"} <= set(data)
    assert len(data["candidates"]) == len(EFFECTS)
    assert data["where"]["regions"][0]["concentration"] >= data["where"]["regions"][-1][
        "concentration"]


def test_bad_input():
    train, validate = records([], 0)
    r = train[0]
    slow = Record(r.t * 2, r.v, r.y, source="slow.csv")
    with pytest.raises(ValueError, match="slow.csv: sample time 0.0002 s differs"):
        diagnose(train, [slow])
    with pytest.raises(ValueError, match="too short"):
        diagnose([r.slice(0, 100)], validate)
    mono = Record(r.t, np.linspace(0, 1, len(r)), r.y, source="ramp.csv")
    with pytest.raises(ValueError, match="ramp.csv: the input has no reversal"):
        diagnose([mono], validate)
    flat = Record(r.t, r.v, np.zeros(len(r)), source="flat.csv")
    with pytest.raises(ValueError, match="flat.csv: the output is constant"):
        diagnose(train, [flat])
    with pytest.raises(ValueError, match="train: at least one record"):
        diagnose([], validate)


def test_cli_diagnose(tmp_path):
    train, validate = records(["drift"], 5)
    save_record(train[0], tmp_path / "a.csv")
    save_record(validate[0], tmp_path / "b.csv")
    out = tmp_path / "d.json"
    assert main(["diagnose", "--train", str(tmp_path / "a.csv"), "--validate",
                 str(tmp_path / "b.csv"), "--json", str(out), "--plots",
                 str(tmp_path / "plots")]) == 0
    data = json.loads(out.read_text())
    assert data["verdict"]["effects"] == ["drift"]
    assert 0.5 <= data["verdict"]["shrink"] <= 1
    assert (tmp_path / "plots" / "residuals.png").exists()


def test_real_record_diagnosis(real_record_path):
    from pimodel import load_record

    rec = load_record(real_record_path)
    k0 = int(np.argmax(np.abs(rec.v) > 1))
    mid = k0 + (len(rec) - k0) // 2
    rep = diagnose([rec.slice(k0, mid)], [rec.slice(mid, None)])
    v = rep.verdict
    # the real stage is not a clean PI operator: its output lags the voltage by about 12 ms
    assert v["effects"] == ["delay"]
    assert 0.008 < v["model"]["delay_samples"] * rec.dt < 0.016
    assert v["shrink"] >= 0.5
