"""Diagnosis on records of the independent generator ``pimodel.stages.preisach_stage`` (Preisach
hysteresis, log-law creep, two modes, fractional delay, exponential static map, drift on the shared
clock, coloured noise): withheld effects, a clean record, and effects outside the vocabulary (a dead
zone, a second input the model does not see, Bouc-Wen hysteresis) that must be "unexplained".

The records start from negative saturation, a memory the nominal model cannot know, so the
diagnosis runs with ``initial_state="unknown"``. One seed per case here; ten in
``studies/sim_to_real.py``."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel import Record
from pimodel.diagnosis import diagnose
from pimodel.stages.preisach_stage import excitations, random_alt_truth


def alt_records(effects, seed, drift_clock="absolute"):
    (tt, vt), (tv, vv) = excitations(seed + 1)
    truth = random_alt_truth(list(effects), seed, drift_clock)
    rng = np.random.default_rng(3 + seed)
    return ([Record(tt, vt, truth.simulate(tt, vt, rng), source="alt-train")],
            [Record(tv, vv, truth.simulate(tv, vv, rng), source="alt-validate")])


def test_alt_clean_says_none():
    v = diagnose(*alt_records([], 0), initial_state="unknown").verdict
    assert v["effects"] == ["none"]


@pytest.mark.parametrize("effect", ["creep", "asymmetry", "drift", "dynamics", "rate"])
def test_alt_withheld_single_effect(effect):
    v = diagnose(*alt_records([effect], 0), initial_state="unknown").verdict
    assert v["effects"] == [effect]
    assert v["shrink"] >= (0.7 if effect in ("asymmetry", "rate") else 0.5)


def test_alt_rate_is_a_loop_that_grows_with_a_filtered_rate():
    """The generator's rate effect scales its Preisach loop with a low-passed rate: the
    candidate's weight family with a filter of the order of tens of ms explains it (the radius
    family with the unfiltered rate, the earlier candidate, left ``creep`` + ``unexplained``)."""
    rep = diagnose(*alt_records(["rate"], 1), initial_state="unknown")
    model = rep.verdict["model"]
    assert rep.verdict["effects"] == ["rate"] and rep.verdict["shrink"] >= 0.7
    assert model["rate_family"] == "weight"
    assert 5e-3 <= model["rate_time_constant_s"] <= 80e-3


def test_alt_rate_with_creep():
    v = diagnose(*alt_records(["rate", "creep"], 0), initial_state="unknown").verdict
    assert sorted(v["effects"]) == ["creep", "rate"]
    assert v["shrink"] >= 0.5


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("seed", [6, 8])
def test_alt_creep_of_the_unknown_start_is_creep_not_a_drift(seed):
    """The records start from negative saturation, and the generator's log-law creep carries
    the first cycles' rise away from it through the whole record: a slow rise the start-up
    mask does not remove. With the creep's lags started at the model's own first output, a
    straight-trend drift was named beside creep on these seeds (validate RMS 0.0110 um, with
    the trend 0.0086, seed 6). With the stage's memory unknown the creep's is too: the lags
    start at the measured first output. Creep alone then; the report's validate output is the
    exported model's ``simulate(measured=y)``, and without ``measured`` the lags start at
    ``h0[0]`` (a new experiment from rest), which differs; with the lags at common levels
    (``creep_start="common"``) both are the same."""
    train, validate = alt_records(["creep"], seed)
    rep = diagnose(train, validate, initial_state="unknown")
    v = rep.verdict
    assert v["effects"] == ["creep"]
    assert v["gap_after"] < 1.5 * v["noise_floor"]
    m = rep.model()
    assert m.initial_state == "unknown"
    va = validate[0]
    scored = ~np.isnan(rep.after[0]) if np.isnan(rep.after[0]).any() else slice(None)
    got = m.simulate(va.v, va.t, measured=va.y)
    assert np.max(np.abs(got[scored] - rep.after[0][scored])) < 1e-9
    from_rest = m.simulate(va.v, va.t)
    if v["model"].get("creep_start") == "common":
        # the lags at levels shared by the records (chosen on these seeds since a start the
        # start-up mask hides is no longer fitted, session 74): no measured start to take
        assert np.max(np.abs(from_rest[scored] - got[scored])) < 1e-9
    else:
        assert np.max(np.abs(from_rest[scored] - got[scored])) > 1e-3


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("effect", ["dead_zone", "second_input", "bouc_wen"])
def test_alt_outside_library_is_unexplained(effect):
    v = diagnose(*alt_records([effect], 0), initial_state="unknown").verdict
    assert "unexplained" in v["effects"]
    assert v["unexplained"]["share"] > 0.1
    assert v["gap_after"] > 2 * v["noise_floor"]
    assert v["unexplained"]["where"]


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_alt_revision_keeps_a_scaled_rate_whole():
    """Seed 5's second input: the combination's rate takes the exact (scaled) shape, the rate
    fitted alone another family; the revision's refit kept the combination's rate filter but
    not its growth (absent from the single fit's grid) and raised a TypeError. It keeps the
    rate's parameters together now, and the outside effect is named."""
    v = diagnose(*alt_records(["second_input"], 5, "record"), initial_state="unknown").verdict
    assert "unexplained" in v["effects"]
    assert v["gap_after"] > 2 * v["noise_floor"]


@pytest.mark.parametrize("pair,clock", [
    (("delay", "drift"), "record"),  # a fractional delay; drift restarting with each record
    (("asymmetry", "drift"), "absolute"),  # drift on the clock the records share
])
def test_alt_withheld_pair(pair, clock):
    v = diagnose(*alt_records(pair, 0, clock), initial_state="unknown").verdict
    assert sorted(v["effects"]) == sorted(pair)
    assert v["shrink"] >= (0.7 if "asymmetry" in pair else 0.5)
    assert v["model"]["drift_clock"] == clock


def test_alt_record_offset_is_drift_with_a_level_of_its_own():
    train, validate = alt_records([], 0)
    level = -0.09  # the sensor zeroed anew before the validate record
    validate = [Record(r.t, r.v, r.y + level, source=r.source) for r in validate]
    v = diagnose(train, validate, initial_state="unknown").verdict
    assert v["effects"] == ["drift"]
    assert v["shrink"] >= 0.5
    assert v["model"]["drift_variant"] == "levels"
    assert abs(v["model"]["drift_record_offsets"][0] - level) < 0.2 * abs(level)
