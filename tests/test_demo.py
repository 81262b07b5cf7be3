"""The headline chain (`pimodel demo`): runs end to end through the CLI and its numbers hold."""

from __future__ import annotations

import json
import re

import pytest

from pimodel.cli import main


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_demo_chain(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    report = out / "report.md"
    assert str(report) in printed
    text = report.read_text()
    for fig in re.findall(r"\]\(([^)]+\.png)\)", text):
        assert (out / fig).stat().st_size > 10_000, fig
    assert len(re.findall(r"\.png\)", text)) >= 5
    for fmu in ("PIHysteresis", "RadiusEstimator", "InversePI"):
        assert (out / "fmus" / f"{fmu}.fmu").exists()

    res = json.loads((out / "results.json").read_text())
    ident = res["identify"]
    adaptive = ident["adaptive (slopes + radii)"]
    assert adaptive["n"] == 4
    assert adaptive["heldout_rms_percent"] < ident["conventional n=10"]["heldout_rms_percent"]
    assert adaptive["heldout_max_percent"] < 0.1
    comp = res["compensate"]
    assert comp["adaptive (slopes + radii)"]["open_loop"]["rms_percent"] < \
        0.1 * comp["none (static gain)"]["open_loop"]["rms_percent"]
    assert res["fmu"]["max_abs_difference_um"] < 1e-9
    assert res["diagnose"]["effects"] == ["creep"]
    assert res["diagnose"]["shrink"] >= 0.5
    _readme_table_matches(res)


def _readme_table_matches(res: dict) -> None:
    """The README's demo table shows this run's figures (to their printed rounding, plus a
    margin for floating-point differences between machines)."""
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    row = re.search(r"\| diagnose \(stage with unmodelled creep\) \| verdict `(\w+)`, validate "
                    r"RMS ([\d.]+) -> ([\d.]+) um \(shrink (\d+) %\) \|", readme)
    assert row is not None, "README: the demo table's diagnose row is missing"
    diag = res["diagnose"]
    assert [row[1]] == diag["effects"]
    assert abs(float(row[2]) - diag["gap_before"]) <= 0.0015
    assert abs(float(row[3]) - diag["gap_after"]) <= 0.0015
    assert abs(int(row[4]) - 100 * diag["shrink"]) <= 3  # percentage points
    ident = re.search(r"adaptive n = 4: held-out RMS ([\d.]+) % / max ([\d.]+) % of range; "
                      r"conventional n = 10: ([\d.]+) % / ([\d.]+) %", readme)
    assert ident is not None, "README: the demo table's identify row is missing"
    ada, conv = res["identify"]["adaptive (slopes + radii)"], res["identify"]["conventional n=10"]
    values = (ada["heldout_rms_percent"], ada["heldout_max_percent"],
              conv["heldout_rms_percent"], conv["heldout_max_percent"])
    for text, value in zip(ident.groups(), values, strict=True):
        assert abs(float(text) - value) <= 0.2 * value + 1e-4, (text, value)
