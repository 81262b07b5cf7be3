"""Record files: round trips and validation errors naming file, row and column."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel import Record, load_record, save_record
from pimodel.records import DataError


def make_record(n=50):
    t = np.arange(n) * 1e-3
    return Record(t, np.sin(t * 50), np.cos(t * 50), {"temp": np.full(n, 21.5)})


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_round_trip_keeps_extra_columns(tmp_path, suffix):
    rec = make_record()
    path = save_record(rec, tmp_path / f"r{suffix}")
    back = load_record(path)
    np.testing.assert_array_equal(back.t, rec.t)
    np.testing.assert_array_equal(back.v, rec.v)
    np.testing.assert_array_equal(back.y, rec.y)
    np.testing.assert_array_equal(back.extra["temp"], rec.extra["temp"])


def test_selectable_column_names(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("time,U,x,other\n0,1,2,3\n0.1,2,3,4\n0.2,3,4,5\n")
    rec = load_record(path, columns=("time", "U", "x"))
    np.testing.assert_array_equal(rec.v, [1, 2, 3])
    np.testing.assert_array_equal(rec.extra["other"], [3, 4, 5])
    with pytest.raises(DataError, match=r"r.csv: column\(s\) \['t', 'v', 'y'\] not found"):
        load_record(path)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("t,v,y\n0,1,2\n0.1,abc,3\n", r"line 3 \(data row 2\), column 'v': 'abc' is not a number"),
        ("t,v,y\n0,1,2\n0.1,2\n", r"line 3 \(data row 2\) has 2 fields, expected 3"),
        ("t,v,y\n0,1,2\n0.1,nan,3\n", r"line 3 \(data row 2\), column 'v': value nan is not"),
        ("t,v,y\n0,1,2\n0,2,3\n", r"line 3 \(data row 2\), column 't': time 0.0 does not increase"),
        ("t,v,y\n0,1,2\n", "at least two samples are needed, got 1"),
        ("t,v,y\n", "at least two samples are needed, got 0"),
        ("", "empty file, expected a header line"),
        ("t,t,y\n0,1,2\n1,2,3\n", "duplicate column names"),
    ],
)
def test_malformed_csv(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(DataError, match=match) as info:
        load_record(path)
    assert "bad.csv" in str(info.value)


def test_user_column_names_in_errors(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("time,U,x\n0,1,2\n0.1,inf,3\n")
    with pytest.raises(DataError, match=r"line 3 \(data row 2\), column 'U'"):
        load_record(path, columns=("time", "U", "x"))


def test_missing_file_and_array_errors(tmp_path):
    with pytest.raises(DataError, match="no such file"):
        load_record(tmp_path / "nope.csv")
    with pytest.raises(DataError, match="column 'y' has 2 samples, expected 3"):
        Record(np.arange(3.0), np.zeros(3), np.zeros(2))


def test_real_record_loads(real_record_path):
    rec = load_record(real_record_path)
    assert len(rec) == 50001
    assert abs(rec.dt - 2e-4) < 1e-6
    assert rec.v.max() > 140 and rec.v.min() < -140
