"""The ``drift`` candidate's levels per record (:mod:`pimodel.diagnosis.drift`): the out-of-fold
level of a validate record, and records whose output levels differ (a sensor zeroed anew) found
as ``drift`` on ``pimodel.stages.pi_stage`` records, with one and with two train records. The drift
pairs and the clock variants on both generators are in ``test_diagnosis.py`` and
``test_diagnosis_alt.py``."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel import Record
from pimodel.diagnosis import diagnose
from pimodel.diagnosis.drift import describe_levels, drift_term, out_of_fold_level
from pimodel.stages.pi_stage import excitation, random_truth


def test_out_of_fold_level_never_uses_its_own_block():
    rng = np.random.default_rng(0)
    r = 0.3 + rng.normal(0.0, 0.01, 400)
    spiked = r.copy()
    spiked[:100] += 5.0  # a gap confined to the first block
    lv, lv_spiked = out_of_fold_level(r, folds=4), out_of_fold_level(spiked, folds=4)
    assert np.array_equal(lv[:100], lv_spiked[:100])  # block 0 does not see its own samples
    assert np.all(lv_spiked[100:] > lv[100:] + 1.0)  # the other blocks do
    assert np.max(np.abs(lv - 0.3)) < 0.005


def test_out_of_fold_level_masked_samples_and_bad_folds():
    r = np.r_[np.full(50, 9.0), np.full(100, 1.0), np.full(100, 3.0)]
    used = np.arange(250) >= 50  # the first 50 samples are not scored
    lv = out_of_fold_level(r, used, folds=2)
    assert np.all(lv[:150] == 3.0) and np.all(lv[150:] == 1.0)
    with pytest.raises(ValueError, match="folds"):
        out_of_fold_level(r, folds=1)
    with pytest.raises(ValueError, match="folds"):
        out_of_fold_level(r[:3], folds=4)


def test_describe_levels_reads_the_clock():
    # a trend of -0.1 um/s: a record starting 4 s after train sits 0.4 um lower on the shared
    # clock, at the train level when the trend restarts, elsewhere when it has its own level
    assert describe_levels(-0.1, [-0.41], [4.0], 0.0)["drift_clock"] == "absolute"
    assert describe_levels(-0.1, [0.01], [4.0], 0.0)["drift_clock"] == "record"
    d = describe_levels(0.0, [0.2], [4.0], 0.0)
    assert d["drift_record_offsets"] == pytest.approx([0.2])


def _records(seed, levels_train=(0.0,), level_validate=0.0):
    truth = random_truth([], seed)
    train = []
    for j, lv in enumerate(levels_train):
        tt, vt = excitation("train", seed=2 * seed + 1 + 10 * j)
        rec = truth.record(tt + j * (tt[-1] + 1.0), vt, seed + j, f"train{j}")
        train.append(Record(rec.t, rec.v, rec.y + lv, source=rec.source))
    tv, vv = excitation("validate", seed=2 * seed + 2)
    rec = truth.record(tv + train[-1].t[-1] + 1.0, vv, 100 + seed, "val")
    return train, [Record(rec.t, rec.v, rec.y + level_validate, source="val")], truth


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
@pytest.mark.parametrize("levels_train,level_validate", [((0.0,), 0.12), ((0.0, -0.08), 0.1)])
def test_record_offsets_are_found_as_drift(levels_train, level_validate):
    train, validate, truth = _records(2, levels_train, level_validate)
    rep = diagnose(train, validate)
    v = rep.verdict
    assert v["effects"] == ["drift"]
    assert v["model"]["drift_variant"] == "levels"
    assert v["shrink"] >= 0.5
    assert v["gap_after"] < 2 * truth.noise_um
    # the validate record's own level, relative to the first train record's
    assert v["model"]["drift_record_offsets"][0] == pytest.approx(
        level_validate - levels_train[0], abs=0.02)
    # the model reproduces the diagnosis' prediction given the record's measured output
    aug = rep.model()
    rec = validate[0]
    y = aug.simulate(rec.v, rec.t, measured=rec.y)
    assert np.max(np.abs(y - rep.after[0])) < 1e-9 * np.ptp(rec.y)


def test_drift_term_without_the_measured_output_follows_the_clock():
    p = {"drift_per_s": 0.2, "drift_clock": "absolute", "drift_variant": "levels",
         "drift_t0_train": 1.0}
    t = np.array([5.0, 5.5])
    assert drift_term(p, t).tolist() == pytest.approx([0.8, 0.9])
    assert drift_term({**p, "drift_clock": "record"}, t).tolist() == pytest.approx([0.0, 0.1])
