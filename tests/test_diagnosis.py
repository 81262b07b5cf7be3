"""Sim-to-real gap diagnosis on records of ``pimodel.stages.pi_stage``: withheld effects
(generation and diagnosis kept apart: the effect name never reaches diagnose), a clean record, bad
input, the CLI, and the real record. The independent generator is tested in
``test_diagnosis_alt.py``.

The unit suite runs one seed per effect and per pair; the full sweep (10 seeds per case) is
``studies/sim_to_real.py``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pimodel import Record, save_record
from pimodel.cli import main
from pimodel.diagnosis import diagnose
from pimodel.diagnosis.effects import EFFECTS as CANDIDATES
from pimodel.stages.pi_stage import EFFECTS, excitation, random_truth


def records(effects, seed, drift_clock="record"):
    """Train and validate records; the validate clock continues 1 s after train ends."""
    tt, vt = excitation("train", seed=2 * seed + 1)
    tv, vv = excitation("validate", seed=2 * seed + 2)
    truth = random_truth(list(effects), seed, drift_clock=drift_clock)
    tv = tv + tt[-1] + 1.0
    return [truth.record(tt, vt, seed, "train")], [truth.record(tv, vv, 100 + seed, "val")]


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("effect", EFFECTS)
def test_withheld_single_effect(effect):
    train, validate = records([effect], 0)
    v = diagnose(train, validate).verdict
    assert v["effects"] == [effect]
    assert v["shrink"] >= (0.7 if effect in ("asymmetry", "rate") else 0.5)


@pytest.mark.parametrize("pair,seed,clock", [
    (("creep", "asymmetry"), 3, "record"),
    (("rate", "creep"), 0, "record"),
    (("dynamics", "drift"), 1, "record"),  # a light 2 kHz mode (damping 0.02)
    (("delay", "drift"), 0, "record"),  # drift restarting with each record
    (("asymmetry", "drift"), 0, "absolute"),  # drift on the clock the records share
])
@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_withheld_pair(pair, seed, clock):
    train, validate = records(list(pair), seed, clock)
    v = diagnose(train, validate).verdict
    assert sorted(v["effects"]) == sorted(pair)
    assert v["shrink"] >= 0.5
    if "drift" in pair:
        assert v["model"]["drift_clock"] == clock


def test_clean_pi_says_none():
    train, validate = records([], 4)
    rep = diagnose(train, validate)
    assert rep.verdict["effects"] == ["none"]
    data = rep.to_json()
    assert {"nominal", "where", "candidates", "verdict"} <= set(data)
    assert len(data["candidates"]) == len(CANDIDATES)
    assert rep.verdict["noise_floor_method"] == "repeated periods"
    assert rep.verdict["gap_before"] < 2 * rep.verdict["noise_floor"]
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


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_cli_diagnose(tmp_path):
    train, validate = records(["drift"], 5)
    save_record(train[0], tmp_path / "a.csv")
    save_record(validate[0], tmp_path / "b.csv")
    out = tmp_path / "d.json"
    assert main(["diagnose", "--train", str(tmp_path / "a.csv"), "--validate",
                 str(tmp_path / "b.csv"), "--json", str(out), "--plots",
                 str(tmp_path / "plots"), "--initial-state", "unknown"]) == 0
    data = json.loads(out.read_text())
    assert data["verdict"]["effects"] == ["drift"]
    assert 0.5 <= data["verdict"]["shrink"] <= 1
    assert (tmp_path / "plots" / "residuals.png").exists()
    assert data["nominal"]["initial_state"] == "unknown"


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_real_record_diagnosis(real_record_path):
    from pimodel import load_record

    rec = load_record(real_record_path)
    k0 = int(np.argmax(np.abs(rec.v) > 1))
    mid = k0 + (len(rec) - k0) // 2
    rep = diagnose([rec.slice(k0, mid)], [rec.slice(mid, None)], initial_state="rest")
    v = rep.verdict
    # the real stage is not a clean PI operator: its loop is wider than a static PI's, as a lag
    # of about 11 ms, rate-dependent hysteresis or a damped linear lag after it makes it; one
    # 1 Hz sine cannot tell them apart, and the verdict says so (one named, the others as
    # alternatives; since the linear part may hold a low-pass, issue 28, the damped lag fits
    # 1 % better on validate than the delay and is named)
    assert v["effects"] in (["delay"], ["rate"], ["dynamics"])
    assert {"delay", "rate"} <= set(v["effects"] + v["alternatives"])
    delay = next(c for c in rep.candidates if c["effect"] == "delay")
    assert 0.008 < delay["params"]["delay_s"] < 0.016
    # the sine cycles repeat exactly: the noise floor comes from the difference of periods
    assert v["noise_floor_method"] == "repeated periods"
    assert v["gap_after"] < 1.5 * v["noise_floor"] < v["gap_before"]
    # most of the gap lies in the start-up region (the stage's memory before the record is
    # unknown); without it the validate gap is within the noise
    rep = diagnose([rec.slice(k0, mid)], [rec.slice(mid, None)], initial_state="unknown")
    assert rep.verdict["effects"] == ["none"]
    assert rep.verdict["gap_before"] < 1.5 * rep.verdict["noise_floor"]
    # validate starts mid-sine: the default ("auto") finds the start-up contradicts a start at
    # rest (the nominal fitted with it mispredicts the rest of validate) and leaves it out
    auto = diagnose([rec.slice(k0, mid)], [rec.slice(mid, None)])
    choice = auto.nominal["initial_state_choice"]
    assert choice["chosen"] == "unknown"
    assert choice["post_startup_ratio"] > choice["limits"]["post_startup_ratio"]
    assert auto.verdict["effects"] == rep.verdict["effects"]
    assert auto.verdict["gap_before"] == pytest.approx(rep.verdict["gap_before"], rel=1e-9)
