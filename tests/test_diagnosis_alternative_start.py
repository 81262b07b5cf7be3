"""The alternative starts of the diagnosis' rounds (:mod:`pimodel.diagnosis.diagnose`,
``ALT_STARTS``): when the greedy path leaves a gap unexplained, paths forced to start from the
next candidates are tried. On a PI stage with creep and rate-dependent hysteresis a broad lag
(``dynamics``) can win the first round alone (it did on seed 6 before the low-pass sampled at the
end of the hold; now `rate` does); the verdict must still be creep and rate. (With
the exact rate shape, measured on seeds 6 and 7, the greedy path itself now reaches creep and
rate, so the other starts are a safeguard there.) An effect outside the vocabulary stays
``unexplained``."""

from __future__ import annotations

import pytest

from pimodel.diagnosis import diagnose
from pimodel.stages.density_stage import density_records
from pimodel.stages.pi_stage import excitation, random_truth


def _pi_stage_records(effects: list[str], seed: int):
    tt, vt = excitation("train", seed=2 * seed + 1)
    tv, vv = excitation("validate", seed=2 * seed + 2)
    truth = random_truth(effects, seed, drift_clock="record")
    return ([truth.record(tt, vt, seed, "train")],
            [truth.record(tv + tt[-1] + 1.0, vv, 100 + seed, "validate")])


@pytest.mark.slow
def test_rate_and_creep_found_beside_a_lag_that_rivals_them():
    train, validate = _pi_stage_records(["rate", "creep"], 6)
    rep = diagnose(train, validate)
    alone = {c["effect"]: c["delta_bic"] for c in rep.candidates}
    # a lag rivals the truth alone: since the low-pass before the plays may also be sampled
    # at the end of the hold (issue 28, bw49: a lag of a few samples before the plays widens
    # the loops with the rate), `rate` wins the first round here and the greedy path reaches
    # creep and rate itself (the broad lag used to win: the alternative starts recovered)
    assert alone["dynamics"] < 0 and alone["rate"] < 0 and alone["creep"] < 0
    assert sorted(rep.verdict["effects"]) == ["creep", "rate"]
    assert rep.verdict["gap_after"] < 0.3 * rep.verdict["gap_before"]


@pytest.mark.slow
def test_outside_the_vocabulary_stays_unexplained():
    train, validate = density_records(["sensor_gain"], 0, "mixed")
    rep = diagnose([train], [validate])
    assert "unexplained" in rep.verdict["effects"]
