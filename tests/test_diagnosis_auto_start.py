"""``initial_state="auto"`` (the default of :func:`pimodel.diagnose`): records that start at
rest are diagnosed as with ``"rest"``, to the bit; the choice and its figures are in the
report, the CLI takes it, and a bad value names the argument. Records that do not start at
rest (``"unknown"`` chosen) are tested on the blind generator (tests/test_blind48.py) and the
shared real record (tests/test_diagnosis.py)."""

import json

import numpy as np
import pytest

from pimodel import diagnose, save_record
from pimodel.stages.pi_stage import excitation, random_truth

SEEDS = [int(s) for s in np.random.default_rng(2811).integers(0, 1000, 2)]


@pytest.mark.slow
@pytest.mark.parametrize("effects, seed", [((), SEEDS[0]), (("creep",), SEEDS[1])])
def test_records_started_at_rest_are_diagnosed_as_from_rest(effects, seed):
    """A stage started at rest (pimodel's own generator, a stage drawn in the test, clean or
    with creep): ``auto`` keeps ``"rest"`` with both ratios below their limits, and the verdict
    and figures equal those of ``initial_state="rest"``."""
    truth = random_truth(list(effects), seed)
    tt, vt = excitation("train", seed=seed + 1)
    tv, vv = excitation("validate", seed=seed + 2)
    train, validate = [truth.record(tt, vt, seed + 3)], [truth.record(tv, vv, seed + 4)]
    auto = diagnose(train, validate, workers=1)
    choice = auto.nominal["initial_state_choice"]
    assert choice["asked"] == "auto" and choice["chosen"] == auto.nominal["initial_state"] == \
        "rest"
    assert choice["post_startup_ratio"] < choice["limits"]["post_startup_ratio"]
    assert choice["startup_ratio"] < choice["limits"]["startup_ratio"]
    rest = diagnose(train, validate, workers=1, initial_state="rest")
    assert "initial_state_choice" not in rest.nominal
    assert auto.verdict == rest.verdict


def test_bad_initial_state_names_the_argument_and_the_choices():
    truth = random_truth([], 0)
    t, v = excitation("train", seed=1)
    rec = truth.record(t, v, 2)
    with pytest.raises(ValueError, match=r"initial_state: expected one of \('auto', 'rest', "
                                         r"'unknown'\), got 'resting'"):
        diagnose([rec], [rec], initial_state="resting")


def test_cli_default_is_auto_and_the_choice_is_in_the_json(tmp_path):
    from pimodel.cli import main

    truth = random_truth([], 5)
    paths = []
    for role, seed in (("train", 6), ("validate", 7)):
        t, v = excitation(role, seed=seed)
        path = tmp_path / f"{role}.csv"
        save_record(truth.record(t, v, seed + 10), path)
        paths.append(str(path))
    out = tmp_path / "report.json"
    assert main(["diagnose", "--train", paths[0], "--validate", paths[1], "--json",
                 str(out)]) == 0
    nominal = json.loads(out.read_text())["nominal"]
    assert nominal["initial_state_choice"]["asked"] == "auto"
    assert nominal["initial_state"] == nominal["initial_state_choice"]["chosen"]
