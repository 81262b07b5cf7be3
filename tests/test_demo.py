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
