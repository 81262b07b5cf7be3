"""The pimodel command line: help on every subcommand, simulate end to end, clear errors."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from pimodel import PIOperator, Record, load_record, save_record
from pimodel.cli import COMMANDS, main


@pytest.mark.parametrize("command", COMMANDS)
def test_help_on_every_subcommand(command, capsys):
    with pytest.raises(SystemExit) as info:
        main([command, "--help"])
    assert info.value.code == 0
    assert "usage: pimodel" in capsys.readouterr().out


def test_entry_point_runs():
    out = subprocess.run([sys.executable, "-m", "pimodel", "--help"], capture_output=True,
                         text=True, check=True)
    assert "simulate" in out.stdout


def test_simulate_and_inverse_round_trip(tmp_path):
    t = np.arange(500) * 1e-3
    v = 2 * np.sin(2 * np.pi * 3 * t)
    save_record(Record(t, v, np.zeros_like(v)), tmp_path / "in.csv")
    args = ["--weights", "1,0.5,0.3", "--radii", "0,0.2,0.6"]
    out = ["--out", str(tmp_path / "y.csv")]
    assert main(["simulate", str(tmp_path / "in.csv"), *args, *out]) == 0
    rec = load_record(tmp_path / "y.csv")
    np.testing.assert_allclose(rec.y, PIOperator([1, 0.5, 0.3], [0, 0.2, 0.6]).simulate(v),
                               atol=1e-12)
    # feed the output back as "v" to the inverse: recovers the original input
    save_record(Record(t, rec.y, np.zeros_like(v)), tmp_path / "yd.csv")
    assert main(["simulate", str(tmp_path / "yd.csv"), *args, "--inverse",
                 "--out", str(tmp_path / "v.npz")]) == 0
    np.testing.assert_allclose(load_record(tmp_path / "v.npz").y, v, atol=1e-10)


def test_simulate_errors_are_clear(tmp_path, capsys):
    (tmp_path / "bad.csv").write_text("t,v,y\n0,1,2\n0.1,x,3\n")
    code = main(["simulate", str(tmp_path / "bad.csv"), "--weights", "1", "--radii", "0",
                 "--out", str(tmp_path / "o.csv")])
    assert code == 2
    assert "line 3 (data row 2), column 'v'" in capsys.readouterr().err
    code = main(["simulate", str(tmp_path / "bad.csv"), "--weights", "1,2", "--radii", "0",
                 "--out", str(tmp_path / "o.csv")])
    assert code == 2
    with pytest.raises(SystemExit):
        main(["simulate", "x.csv", "--weights", "a,b", "--radii", "0", "--out", "o.csv"])
    assert "expected numbers separated by commas" in capsys.readouterr().err
