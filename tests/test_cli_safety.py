"""The command line never writes over an input file (same name, relative path, symlink, plots
folder), new output columns that collide with input columns get a suffix, and t,v-only records
simulate. Also the record reader's clear errors: corrupt .npz, a CSV named .npz, other
separators, a UTF-8 BOM, a sampling interval that changes mid-record."""

from __future__ import annotations

import hashlib
import os

import numpy as np
import pytest

from pimodel import PIOperator, Record, load_record, save_record
from pimodel.cli import main
from pimodel.records import DataError

SIM = ["--weights", "1,0.5", "--radii", "0,0.2"]


def digest(path) -> str:
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


@pytest.fixture
def record(tmp_path):
    t = np.arange(400) * 1e-3
    v = 2 * np.sin(2 * np.pi * 5 * t)
    path = tmp_path / "d.csv"
    save_record(Record(t, v, PIOperator([1, 0.5], [0, 0.2]).simulate(v)), path)
    return path


def refused(argv, path, capsys, option):
    before = digest(path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert option in err and "never writes over an input file" in err
    assert digest(path) == before


@pytest.mark.parametrize("spelling", ["same", "relative", "dotdot", "symlink", "hardlink"])
def test_no_command_writes_over_its_input(record, tmp_path, capsys, monkeypatch, spelling):
    monkeypatch.chdir(tmp_path)
    out = {"same": str(record), "relative": "d.csv", "dotdot": f"../{tmp_path.name}/d.csv",
           "symlink": str(tmp_path / "link.csv"), "hardlink": str(tmp_path / "hard.csv")}[spelling]
    if spelling == "symlink":
        os.symlink(record, out)
    if spelling == "hardlink":
        os.link(record, out)
    refused(["simulate", str(record), *SIM, "--out", out], record, capsys, "--out")
    refused(["identify", str(record), "--json", out], record, capsys, "--json")
    refused(["diagnose", "--train", str(record), "--validate", str(record), "--json", out],
            record, capsys, "--json")


def test_plots_folder_that_is_the_input(record, capsys):
    refused(["identify", str(record), "--json", str(record.with_suffix(".json")), "--plots",
             str(record)], record, capsys, "--plots")


def test_simulate_suffixes_colliding_columns(tmp_path, capsys):
    t = np.arange(100) * 1e-3
    v = np.sin(2 * np.pi * 10 * t)
    src = tmp_path / "in.csv"
    save_record(Record(t, v, 2 * v, {"y_measured": 3 * v, "y_measured_1": 4 * v}), src)
    out = tmp_path / "out.csv"
    assert main(["simulate", str(src), *SIM, "--out", str(out)]) == 0
    assert "warning: UserWarning: column 'y_measured' exists in the input; the new column is " \
        "written as 'y_measured_2'" in capsys.readouterr().err
    rec = load_record(out)
    np.testing.assert_array_equal(rec.extra["y_measured"], 3 * v)   # the input's, kept
    np.testing.assert_array_equal(rec.extra["y_measured_1"], 4 * v)
    np.testing.assert_array_equal(rec.extra["y_measured_2"], 2 * v)  # the measured y, moved


def test_simulate_t_v_only_record(tmp_path):
    src = tmp_path / "tv.csv"
    src.write_text("t,v\n" + "".join(f"{k * 1e-3},{np.sin(k / 10)}\n" for k in range(50)))
    out = tmp_path / "y.csv"
    assert main(["simulate", str(src), *SIM, "--out", str(out)]) == 0
    rec = load_record(out)
    assert "y_measured" not in rec.extra
    np.testing.assert_allclose(rec.y, PIOperator([1, 0.5], [0, 0.2]).simulate(rec.v))
    with pytest.raises(DataError, match="'y'.*not found"):
        load_record(src)  # the output column stays required elsewhere


def test_corrupt_npz_and_csv_named_npz(record, tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"PK\x03\x04" + b"\x00" * 40)
    with pytest.raises(DataError, match="bad.npz: corrupt .npz"):
        load_record(bad)
    renamed = tmp_path / "csv.npz"
    renamed.write_bytes(record.read_bytes())
    with pytest.raises(DataError, match="csv.npz: not a valid .npz.*rename it to .csv"):
        load_record(renamed)


@pytest.mark.parametrize(("sep", "name"), [(";", "semicolon"), ("\t", "tab")])
def test_other_separators_are_read_with_a_warning(tmp_path, sep, name):
    path = tmp_path / "s.csv"
    path.write_text(f"t{sep}v{sep}y\n" + "".join(f"{k * 0.1}{sep}{k % 3}{sep}{k % 5}\n"
                                                  for k in range(10)))
    with pytest.warns(UserWarning, match=f"read as {name}-separated"):
        rec = load_record(path)
    assert np.array_equal(rec.v, np.arange(10) % 3)


def test_decimal_comma_hint(tmp_path):
    path = tmp_path / "eu.csv"
    path.write_text("t;v;y\n0;0,5;1\n0,1;1;2\n")
    with pytest.warns(UserWarning), pytest.raises(DataError, match="row 1.*decimal comma"):
        load_record(path)


def test_utf8_bom_accepted(tmp_path):
    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbft,v,y\n0,1,2\n0.1,2,3\n")
    assert np.array_equal(load_record(path).v, [1.0, 2.0])


def test_sampling_interval_change_names_the_row():
    t = np.concatenate([np.arange(100) * 1e-3, 0.1 + np.arange(1, 100) * 2e-3])
    with pytest.raises(DataError, match=r"row 101, column 't': the sample interval changes"):
        Record(t, np.sin(t), np.cos(t))
    jitter = np.arange(200) * 1e-3 + np.random.default_rng(0).uniform(-2e-6, 2e-6, 200)
    assert len(Record(jitter, np.sin(jitter), np.cos(jitter))) == 200  # 0.4 % jitter is fine
