"""The blind check of issue 28 (``tests/blind/stage48.py``, a generator written without reading
pimodel's generators): a few of its cases that the diagnosis gets right, on short records.

Each draws its seeds in the test and asserts the verdict and margins against the noise floor,
not one machine's numbers. The measured table (failures included) is in docs/diagnosis.md,
"A blind check (issue 28)".
"""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent / "blind"))

import stage48 as S  # noqa: E402

from pimodel import diagnose  # noqa: E402

SEEDS = [int(s) for s in np.random.default_rng(4828).integers(100, 10_000, 2)]


def _diagnose(case, scale):
    rt, rv, st, info = S.make_records(case, scale=scale)
    return diagnose([rt], [rv], workers=1), info


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("kind", ["logchirp", "staircase"])
def test_clean_stage_started_at_its_park_level_is_none(kind, seed):
    """A clean stage driven from its park level (a log chirp, a staircase scan at 1 kHz) is
    ``none``, its nominal within 2 noise floors on validate."""
    rep, _ = _diagnose(S.Case(f"clean-{kind}", (), kind, 1000.0, seed), 0.5)
    v = rep.verdict
    assert v["effects"] == ["none"]
    assert v["gap_before"] < 2.0 * v["noise_floor"]


@pytest.mark.parametrize("seed", SEEDS[:1])
def test_thermal_or_polynomial_drift_is_drift(seed):
    """A drift on the shared clock (a thermal settling or a polynomial in time, of 1-3 % of the
    stroke) under a linear chirp at 1 kHz is ``drift``, and the validate gap shrinks by more
    than half."""
    rep, info = _diagnose(S.Case("drift", ("drift",), "linchirp", 1000.0, seed), 0.5)
    v = rep.verdict
    assert info["effect_rms_sigma"] > 5.0  # the effect is visible above the noise
    assert v["effects"] == ["drift"]
    assert v["shrink"] > 0.5


def _rep(start_share, start_conc):
    """A report whose start-up region ranks third, below two regions inside it."""
    from types import SimpleNamespace
    regions = [{"region": "fast input (top quarter of |dv/dt|)", "concentration": 8.3,
                "energy_share": 0.93, "sample_share": 0.11},
               {"region": "ascending branches", "concentration": 4.4, "energy_share": 0.93,
                "sample_share": 0.21},
               {"region": "start-up (until the input first spans 90 % of its range)",
                "concentration": start_conc, "energy_share": start_share,
                "sample_share": start_share / start_conc}]
    return SimpleNamespace(
        verdict={"effects": ["unexplained"], "gap_after": 0.06, "noise_floor": 0.01,
                 "alternatives": [], "unexplained": {"share": 1.0},
                 "noise_floor_method": "local model", "model": {}},
        where={"regions": regions}, nominal={"initial_state": "rest"})


def test_startup_holding_most_of_the_residual_gets_the_hint_below_the_top_two():
    """The blind clean stage on triangles with holds (seed 0) left 97 % of its nominal residual
    in the start-up (concentration 3.65), ranked third below two regions inside it: the hint to
    try ``--initial-state unknown`` is given (it was not before issue 28's blind check). A
    start-up with a minority of the residual there still gets none."""
    from pimodel.diagnosis.summary import hints
    assert any("--initial-state unknown" in h for h in hints(_rep(0.97, 3.65)))
    assert not any("--initial-state unknown" in h for h in hints(_rep(0.3, 1.6)))


@pytest.mark.slow
def test_blind_clean_triangles_from_a_parked_stage_point_to_the_unknown_start():
    """A clean stage parked at the bottom of its range and driven by ramps to held levels from
    mid-range (1 kHz, the blind case clean-triangle_hold, seed 0) was not ``none`` at rest when
    measured; then the report's hints say to try ``--initial-state unknown`` (a later fix of the
    start may make it ``none`` at rest: not asserted), and with it the verdict is ``none``
    within 2 noise floors."""
    from pimodel.diagnosis.summary import hints
    rt, rv, _, _ = S.make_records(S.Case("clean-triangle_hold", (), "triangle_hold", 1000.0, 0))
    rep = diagnose([rt], [rv], workers=1, initial_state="rest")
    if rep.verdict["effects"] != ["none"]:  # as measured (docs): the start-up misfit, hinted
        assert any("--initial-state unknown" in h for h in hints(rep))
    rep = diagnose([rt], [rv], workers=1, initial_state="unknown")
    assert rep.verdict["effects"] == ["none"]
    assert rep.verdict["gap_before"] < 2.0 * rep.verdict["noise_floor"]


@pytest.mark.slow
@pytest.mark.parametrize("name, seed", [("clean-triangle_hold", 0), ("clean-triangle_hold", 1),
                                        ("clean-multisine", 1)])
def test_blind_clean_stages_not_started_at_rest_are_none_by_default(name, seed):
    """Three of the four clean blind cases that were not ``none`` from rest (the stage parked at the
    bottom of its range before each record; ramps to held levels and random-phase multisines
    at 1-20 kHz: a validate start-up misfit of 5-30 noise floors, or weights that fitted slow
    noise by the large plays' one move in train's start-up) are ``none`` with the default
    ``initial_state="auto"``, which chose ``"unknown"`` (the records contradict a start at
    rest, and without the start-ups the nominal is at the noise) and says so in a hint;
    validate within 1.5 noise floors."""
    import run48

    from pimodel.diagnosis.summary import hints
    case = next(c for c in run48.cases([seed]) if c.name == name)
    rt, rv, _, _ = S.make_records(case)
    rep = diagnose([rt], [rv], workers=1)
    choice = rep.nominal["initial_state_choice"]
    assert choice["chosen"] == rep.nominal["initial_state"] == "unknown"
    assert choice["post_startup_ratio"] > choice["limits"]["post_startup_ratio"] or \
        choice["startup_ratio"] > choice["limits"]["startup_ratio"]
    assert choice["free_over_noise"] <= choice["limits"]["free_over_noise"]
    assert any("do not all start at rest" in h for h in hints(rep))
    assert rep.verdict["effects"] == ["none"]
    assert rep.verdict["gap_before"] < 1.5 * rep.verdict["noise_floor"]


@pytest.mark.parametrize("seed", [2])
def test_clean_band_noise_stage_is_none_with_non_negative_play_weights(seed):
    """A clean stage under band-limited noise at 5 kHz (the blind case clean-bandnoise, seed 2)
    was ``rate`` before the nominal's play weights of radius > 0 were held non-negative (least
    squares on its 80-play grid validated at 9.6 noise floors, its weights swinging in sign);
    with them (kept when validate agrees) it is ``none``, the nominal within 2 noise floors on
    validate and its weights of radius > 0 all >= 0."""
    rt, rv, _, _ = S.make_records(S.Case("clean-bandnoise", (), "bandnoise", 5000.0, seed))
    rep = diagnose([rt], [rv], workers=1)
    v = rep.verdict
    assert v["effects"] == ["none"]
    assert v["gap_before"] < 2.0 * v["noise_floor"]
    model = rep.nominal["model"]
    w = np.asarray(model["weights"])[np.asarray(model["radii"]) > 0]
    assert np.all(w >= 0.0)


@pytest.mark.parametrize("seed", SEEDS)
def test_creep_restarted_with_each_record_is_creep_alone(seed):
    """The generator's creep restarts with each record (lags of ``h - h[0]`` from 0): under an
    offset sine at 1 kHz the verdict is ``creep`` alone (counted from each record's start
    where that passes, module creep) and the gap shrinks by more than half; before that start,
    `drift` beside it (8 of 8 seeds drawn, offset sines and multisines)."""
    rep, info = _diagnose(S.Case("creep", ("creep",), "offset_sine", 1000.0, seed), 0.5)
    v = rep.verdict
    assert info["effect_rms_sigma"] > 5.0
    assert v["effects"] == ["creep"], v["effects"]
    assert v["shrink"] > 0.5


@pytest.mark.slow
@pytest.mark.parametrize("seed", SEEDS)
def test_asymmetry_under_a_staircase_scan_is_named_not_left_out_with_the_start_ups(seed):
    """A quadratic output map under a staircase scan (up and down once, 5 kHz, half length):
    the start-up region is nearly half of each record and one branch follows it, which a PI
    without the start-ups fits whatever the stage (such records read ``none`` at 58-79 noise
    floors of effect before). ``auto`` neither puts the start in question nor makes the
    diagnosis without the start-ups, and names the asymmetry (measured on 12 seeds: named in
    12, alone in 8)."""
    rep, info = _diagnose(S.Case("asymmetry", ("asymmetry",), "staircase", 5000.0, seed), 0.5)
    choice = rep.nominal["initial_state_choice"]
    assert info["effect_rms_sigma"] > 5.0  # the effect is visible above the noise
    assert choice["one_branch"] and "second_look" not in choice
    assert rep.nominal["initial_state"] == "rest"
    assert "asymmetry" in rep.verdict["effects"]


@pytest.mark.parametrize("seed", [int(s) for s in
                                  np.random.default_rng(71).integers(100, 10_000, 3)])
def test_creep_beside_a_delay_fits_a_stage_with_creep_behind_its_amplifier_delay(seed):
    """The blind stage delays its input (the amplifier) before the plays and the creep: a creep
    fitted beside the delay, held at the stage's own, leaves the train record's residual within
    the noise the record holds (a staircase at 5 kHz, half length). Before, the creep's columns
    took ``h0`` undelayed beside the delayed plays: 0.98-1.17 times that noise, above 1.01 in 7
    of 11 seeds drawn (0.96-0.99 now), and the whole diagnosis missed the creep (seed 1 of
    the blind table: ``delay`` alone)."""
    from pimodel.diagnosis.effects import fit_effect, fit_nominal, make_segment
    rt, _, st, _ = S.make_records(S.Case("creep+delay", ("creep", "delay"), "staircase", 5000.0,
                                         seed), scale=0.5)
    seg = make_segment(rt.t, rt.v, rt.y, np.linspace(0.0, 0.5 * np.ptp(rt.v), 41)[:-1])
    nominal, held = fit_nominal([seg]), {"d": st.effects["delay"]}
    noise = np.sqrt(np.mean((rt.y - st.clean(rt.t, rt.v, 0.0)) ** 2))

    def rms(combo, name):
        m = fit_effect(name, [seg], combo, dict(held), nominal)
        return np.sqrt(np.mean((seg.y - m.predict(seg)) ** 2))

    assert rms((), "delay") > 1.3 * noise  # the creep is there to be fitted
    assert rms(("delay",), "creep") < 1.01 * noise
