"""The diagnosis in words (``pimodel.diagnosis.summary``): the summary names the verdict, how
sure it is, where the gap sits and a next step drawn from the report's own figures; the
Markdown report holds them and its figures."""

import re

import numpy as np
import pytest

from pimodel.cli import main
from pimodel.diagnosis.diagnose import DiagnosisReport
from pimodel.diagnosis.summary import (
    confidence,
    hints,
    markdown_table,
    next_step,
    summarize,
    write_report,
)

STARTUP = "start-up (until the input first spans 90 % of its range)"


def _report(effects=("creep",), *, ratio=1.2, alternatives=(), startup=1.0, share=0.0,
            initial_state="rest", seed=0, choice=None):
    rng = np.random.default_rng(seed)
    noise = rng.uniform(0.005, 0.02)
    before = noise * rng.uniform(5, 20)
    after = ratio * noise
    regions = sorted([{"region": "hold after a step (after 50 ms)", "concentration": 2.5,
                       "energy_share": 0.5, "sample_share": 0.2},
                      {"region": STARTUP, "concentration": startup,
                       "energy_share": 0.1 * startup, "sample_share": 0.1},
                      {"region": "ascending branches", "concentration": 0.8,
                       "energy_share": 0.4, "sample_share": 0.5}],
                     key=lambda r: -r["concentration"])
    un = {"present": "unexplained" in effects, "share": share}
    if un["present"]:
        un.update(where=["input extremes (outer 20 % of range)"], band="1-10 Hz")
    verdict = {"effects": list(effects), "gap_before": before, "gap_after": after,
               "shrink": 1 - after / before, "noise_floor": noise,
               "noise_floor_method": "repeated periods", "gap_after_over_noise": ratio,
               "alternatives": list(alternatives), "unexplained": un, "model": {}}
    where = {"regions": regions, "spectrum": [{"band": "< 1 Hz", "energy_share": 0.7},
                                              {"band": "1-10 Hz", "energy_share": 0.3}]}
    nominal = {"initial_state": initial_state}
    if choice is not None:
        nominal["initial_state_choice"] = choice
    return DiagnosisReport(nominal, where, [], verdict, [], [], [])


def test_summary_states_verdict_figures_and_region():
    rep = _report(seed=3)
    text = summarize(rep)
    lines = text.splitlines()
    assert len(lines) == 4 and [ln.split(":")[0] for ln in lines] == [
        "Verdict", "How sure", "Where the gap sits (nominal model)", "Next"]
    v = rep.verdict
    assert "creep" in lines[0]
    assert f"{v['gap_before']:.3g}" in lines[1] and f"{v['gap_after']:.3g}" in lines[1]
    assert f"{100 * v['shrink']:.0f} %" in lines[1]
    assert lines[1].startswith("How sure: sure")
    assert "hold after a step (after 50 ms)" in lines[2] and "70 % of it at < 1 Hz" in lines[2]
    assert "ascending" not in lines[2]  # a region below uniform concentration is not named
    assert "--export" in lines[3]


def test_startup_hint_only_when_started_at_rest():
    rep = _report(startup=3.0)
    assert "--initial-state unknown" in next_step(rep)
    assert "--initial-state unknown" in summarize(rep).splitlines()[-1]
    quiet = _report(startup=3.0, initial_state="unknown")
    assert not any("--initial-state" in h for h in hints(quiet))
    assert "start-up" in summarize(rep) and "start-up" not in summarize(quiet)
    assert not any("--initial-state" in h for h in hints(_report(startup=1.2)))


def test_an_auto_start_left_out_is_said_with_its_reason():
    """``initial_state="auto"`` that chose ``"unknown"``: a hint says the records do not start
    at rest, with the ratio that decided it (only that one); one that chose rest says nothing."""
    limits = {"post_startup_ratio": 3.0, "startup_ratio": 10.0}
    post = {"asked": "auto", "chosen": "unknown", "post_startup_ratio": 4.08,
            "startup_ratio": 4.8, "limits": limits}
    said = [h for h in hints(_report(("none",), initial_state="unknown", choice=post))
            if "do not all start at rest" in h]
    assert len(said) == 1 and "4.08 times" in said[0] and "4.8 times" not in said[0]
    start = dict(post, post_startup_ratio=1.05, startup_ratio=93.4)
    said = [h for h in hints(_report(("none",), initial_state="unknown", choice=start))
            if "do not all start at rest" in h]
    assert len(said) == 1 and "93.4 times as much misfit in validate's start-up" in said[0]
    rest = dict(post, chosen="rest", post_startup_ratio=0.9, startup_ratio=1.2)
    assert not any("do not all start at rest" in h for h in hints(_report(choice=rest)))


def test_start_hint_after_the_second_look_says_which_rule_chose():
    """``initial_state="auto"`` decided by the two diagnoses (diagnose._final_start): the hint
    names the rest verdict and whether its model mispredicted after the start-ups or named
    more effects for no gain there."""
    limits = {"post_startup_ratio": 3.0, "startup_ratio": 10.0}
    look = {"unknown_effects": ["delay"], "rest_effects": ["delay", "unexplained"],
            "post_startup_ratio": 4.08, "fewer_effects": True,
            "limits": {"post_startup_ratio": 3.0, "fewer_effects_ratio": 0.64}}
    choice = {"asked": "auto", "chosen": "unknown", "post_startup_ratio": 1.03,
              "startup_ratio": 3.4, "limits": limits, "second_look": look}
    said = [h for h in hints(_report(("delay",), initial_state="unknown", choice=choice))
            if "do not all start at rest" in h]
    assert len(said) == 1 and "(delay, unexplained)" in said[0] and "4.08 times worse" in said[0]
    assert "the nominal left" not in said[0]
    fewer = dict(choice, second_look=dict(look, post_startup_ratio=1.02))
    said = [h for h in hints(_report(("delay",), initial_state="unknown", choice=fewer))
            if "do not all start at rest" in h]
    assert len(said) == 1 and "no better than the one without the start-ups" in said[0]
    assert "times worse" not in said[0]


def test_alternatives_and_unexplained_lower_the_confidence():
    alt = _report(("delay",), alternatives=("rate",))
    level, why = confidence(alt)
    assert level == "fairly sure" and "rate explains" in why
    assert any("tell them apart" in h for h in hints(alt))
    un = _report(("unexplained",), ratio=6.0, share=0.4)
    level, why = confidence(un)
    assert level == "unsure" and "40 %" in why
    assert "clipping" in next_step(un) and "input extremes" in next_step(un)
    assert confidence(_report(ratio=3.0))[0] == "fairly sure"  # named, but not at the noise


def test_none_says_use_the_nominal_model():
    rep = _report(("none",), ratio=1.1)
    assert "nominal PI model explains" in summarize(rep).splitlines()[0]
    assert next_step(rep).startswith("use the nominal PI model")


def test_report_without_records_has_no_figures(tmp_path):
    rep = _report(("unexplained",), ratio=6.0, share=0.4, startup=3.0)
    text = write_report(rep, tmp_path / "r").read_text()
    assert "## Summary" in text and "## Hints" in text and "![" not in text
    assert text.count("\n- ") == len(hints(rep)) >= 2
    assert STARTUP in text  # the regions table


@pytest.mark.slow
def test_cli_prints_the_summary_and_writes_the_report(tmp_path, capsys):
    """``pimodel diagnose --report DIR`` on a simulated stage with creep: the printed summary
    names creep, report.md links figures that exist."""
    from pimodel import save_record
    from pimodel.stages.pi_stage import Truth, excitation

    truth = Truth(creep_percent_per_decade=1.5)
    for name, role, seed in (("a.csv", "train", 1), ("b.csv", "validate", 2)):
        t, v = excitation(role, fs=5000.0)
        save_record(truth.record(t, v, seed=seed), tmp_path / name)
    out = tmp_path / "rep"
    assert main(["diagnose", "--train", str(tmp_path / "a.csv"), "--validate",
                 str(tmp_path / "b.csv"), "--json", str(tmp_path / "r.json"),
                 "--report", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "Verdict: creep" in printed and f"wrote {out / 'report.md'}" in printed
    text = (out / "report.md").read_text()
    figs = [ln[ln.index("(") + 1:-1] for ln in text.splitlines() if ln.startswith("![")]
    assert len(figs) == 2 and all((out / f).exists() for f in figs)
    assert "| creep |" in text  # the table of each effect alone


def test_report_tables_escape_pipes_in_region_names(tmp_path):
    rep = _report()
    rep.where["regions"].insert(0, {"region": "fast input (top quarter of |dv/dt|)",
                                    "concentration": 3.0, "energy_share": 0.6,
                                    "sample_share": 0.2})
    text = write_report(rep, tmp_path).read_text()
    row = next(ln for ln in text.splitlines() if ln.startswith("| fast input"))
    assert row.replace("\\|", "").count("|") == 5  # four cells


def test_report_folder_that_is_an_input_is_refused(tmp_path, capsys):
    from pimodel import Record, save_record

    t = np.arange(200) * 1e-3
    rec = save_record(Record(t, np.sin(20 * t), np.sin(20 * t)), tmp_path / "d.csv")
    code = main(["diagnose", "--train", str(rec), "--validate", str(rec), "--json",
                 str(tmp_path / "r.json"), "--report", str(rec)])
    assert code == 2 and "--report" in capsys.readouterr().err
    assert not (tmp_path / "r.json").exists()  # refused before any work


@pytest.mark.parametrize("seed", range(5))
def test_markdown_table_cells_round_trip(seed):
    """The one table helper (report and demo): a header, a rule, one line per row with one
    cell per column; floats read back to 4 significant digits, text with ``|`` intact."""
    from pimodel.experiments import demo

    assert demo.markdown_table is markdown_table
    rng = np.random.default_rng(seed)
    ncols, nrows = int(rng.integers(1, 6)), int(rng.integers(0, 8))
    header = [f"c{j}|x" if rng.random() < 0.3 else f"c{j}" for j in range(ncols)]
    rows = [[float(rng.lognormal(0, 5)) * rng.choice([-1, 1]) if rng.random() < 0.5 else
             f"t{i}{'|' if rng.random() < 0.5 else ''}{j}" for j in range(ncols)]
            for i in range(nrows)]
    lines = markdown_table(header, rows).splitlines()
    assert len(lines) == nrows + 2 and lines[1] == "|" + "---|" * ncols

    def cells(line):  # split at the unescaped pipes, then unescape
        parts = re.split(r"(?<!\\)\|", line)
        assert parts[0] == parts[-1] == ""
        return [c.strip().replace("\\|", "|") for c in parts[1:-1]]

    assert cells(lines[0]) == header
    for line, row in zip(lines[2:], rows, strict=True):
        got = cells(line)
        assert len(got) == ncols
        for g, x in zip(got, row, strict=True):
            if isinstance(x, float):
                assert abs(float(g) - x) <= 5e-4 * abs(x)
            else:
                assert g == x


def test_validate_looping_plays_train_did_not_identify_is_named_unless_none():
    """The extrapolation rule (issue 28, :mod:`pimodel.diagnosis.coverage`): a validate record
    whose input spans more than the train input drives plays above half the train range on loops
    (train moved them only in its start-up, or never); with a verdict other than ``none`` the
    hint names the record, its share and the train range, it comes first (the next step), and the
    confidence is ``unsure``; with ``none``, or a validate record within the train range, nothing
    is said."""
    from pimodel.diagnosis.coverage import coverage
    from pimodel.records import Record

    t = np.arange(2000) * 1e-3
    tri = 2 / np.pi * np.arcsin(np.sin(2 * np.pi * 3 * t))  # +-1, 3 Hz, starts at 0
    train = [Record(t, 1.0 + tri, np.zeros(t.size), source="tr")]
    inside = Record(t, 1.0 + 0.9 * tri[::-1], np.zeros(t.size), source="inside")
    wider = Record(t, 1.0 + np.where(t < 1.0, 0.5, 1.2) * tri, np.zeros(t.size), source="wider")
    cov = coverage(train, [train[0], inside, wider])
    assert cov["train_range"] == pytest.approx([0.0, 2.0]) and cov["half_range"] == \
        pytest.approx(1.0)
    same, ins, wid = cov["records"]
    assert same["loops_above"] == ins["loops_above"] == 0.0 and same["first_loop_s"] is None
    # the 1.2 amplitude from t = 1 s: plays above 1 move on its loops once it has spanned 2
    assert 0.05 < wid["loops_above"] < 0.5 and 1.0 <= wid["first_loop_s"] < 1.5
    assert wid["beyond_reach"] >= wid["loops_above"] > 0 and wid["range"][1] == \
        pytest.approx(2.2)
    for effects, covered, said in ((("drift",), [same, wid], True),
                                   (("unexplained",), [wid], True),
                                   (("none",), [wid], False), (("drift",), [same, ins], False)):
        rep = _report(effects, ratio=1.5 if effects == ("drift",) else 6.0, share=0.5)
        rep.nominal["coverage"] = dict(cov, records=covered)
        named = [h for h in hints(rep) if "half the train input's range" in h]
        assert bool(named) == said, (effects, named)
        if said:
            assert "wider" in named[0] and f"{100 * wid['loops_above']:.1f} %" in named[0]
            assert "0 to 2" in named[0] and next_step(rep) == named[0]
            assert confidence(rep)[0] == "unsure"
        elif effects == ("drift",):
            assert confidence(rep)[0] == "sure"
    assert not any("half the train" in h for h in hints(_report(("drift",))))  # no coverage
