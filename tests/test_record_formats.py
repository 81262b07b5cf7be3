"""Records from the formats labs use, and the reliability cases of their reading: MATLAB
.mat (v5; v7.3 needs h5py), documented .npz keys, Record.from_arrays for (N,), (N,1), (1,N),
the split into train and validate, chosen columns never shadowed by others (issue 32 case 1,
with a property test over random layouts), a CSV cut mid-row (8), the exact output path (9),
epoch time stamps (15), a quoted decimal comma and a trailing header comma (16), editor line
numbers, and a file read without a Python list of rows."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pimodel import Record, load_record, save_record
from pimodel.records import DataError


def _signals(n=200, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 5e-3
    v = np.cumsum(rng.normal(size=n))
    return t, v, 0.5 * v + rng.normal(scale=0.1, size=n)


@pytest.mark.parametrize("shape", ["row", "column", "flat"])
def test_from_arrays_takes_every_vector_layout(shape):
    t, v, y = _signals()
    lay = {"row": lambda a: a[None, :], "column": lambda a: a[:, None], "flat": lambda a: a}
    rec = Record.from_arrays(lay[shape](t), lay[shape](v), lay[shape](y),
                             {"T": lay[shape](2 * t)})
    assert rec.t.shape == rec.v.shape == rec.y.shape == rec.extra["T"].shape == (t.size,)
    assert np.array_equal(rec.v, v) and np.array_equal(rec.extra["T"], 2 * t)
    with pytest.raises(DataError, match=r"column 'v' must be a vector .* got shape \(2, 100\)"):
        Record.from_arrays(t, v.reshape(2, -1), y)


def test_mat_v5_file_with_matlab_shapes(tmp_path):
    scipy_io = pytest.importorskip("scipy.io")
    t, v, y = _signals()
    path = tmp_path / "lab.mat"  # as MATLAB saves column vectors, plus a scalar and text
    scipy_io.savemat(path, {"time_s": t[:, None], "voltage_V": v[None, :], "disp_um": y,
                            "fs": 200.0, "note": "run 3"})
    rec = load_record(path, columns=("time_s", "voltage_V", "disp_um"))
    assert np.array_equal(rec.t, t) and np.array_equal(rec.v, v) and np.array_equal(rec.y, y)
    assert rec.extra == {}  # the scalar and the text are not columns
    back = save_record(rec, tmp_path / "copy.mat", columns=("t", "v", "y"))
    assert np.array_equal(load_record(back).y, y)


def test_mat_v73_without_h5py_names_the_package(tmp_path, monkeypatch):
    path = tmp_path / "big.mat"  # a MATLAB v7.3 header: version 0x0200, then an HDF5 body
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5"
    path.write_bytes(header.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02IM" + b"\x00" * 512)
    monkeypatch.setitem(__import__("sys").modules, "h5py", None)  # as if not installed
    with pytest.raises(DataError, match=r"big.mat: a MATLAB v7.3 \(HDF5\) file; .* h5py"):
        load_record(path)


def test_npz_keys_are_the_column_names_in_any_vector_shape(tmp_path):
    t, v, y = _signals()
    path = tmp_path / "r.npz"
    np.savez(path, t=t[None, :], U=v[:, None], x=y, meta=np.zeros((3, 3)))
    rec = load_record(path, columns=("t", "U", "x"))
    assert np.array_equal(rec.v, v) and rec.extra == {}


def test_split_first_part_is_train_rest_is_validate():
    t, v, y = _signals(101)
    rec = Record(t, v, y, {"T": t + 1})
    train, validate = rec.split(0.3)
    k = round(0.3 * 101)
    assert len(train) == k and len(validate) == 101 - k
    assert np.array_equal(np.concatenate([train.v, validate.v]), v)
    assert validate.t[0] == t[k] and np.array_equal(validate.extra["T"], t[k:] + 1)
    for bad in (0, 1, 1.5, -0.2, True):
        with pytest.raises(ValueError, match="fraction"):
            rec.split(bad)
    with pytest.raises(ValueError, match="at least 2"):
        rec.split(0.995)


# --- issue 32, case 1: the chosen columns are the record's signals -------------------------

@given(st.lists(st.sampled_from(["t", "v", "y", "y_measured", "time", "U", "x", "T"]),
                min_size=3, max_size=8, unique=True),
       st.randoms(use_true_random=False))
def test_chosen_columns_are_picked_in_any_layout(tmp_path_factory, names, rnd):
    chosen = rnd.sample(names, 3)
    n = 12
    cols = {name: (np.arange(n) + 0.5) * (i + 1) for i, name in enumerate(names)}
    cols[chosen[0]] = np.arange(n) * 1e-3  # time must increase evenly
    path = tmp_path_factory.mktemp("lay") / "r.csv"
    path.write_text(",".join(names) + "\n" + "".join(
        ",".join(repr(float(cols[c][k])) for c in names) + "\n" for k in range(n)))
    rec = load_record(path, columns=tuple(chosen))
    assert np.array_equal(rec.t, cols[chosen[0]])
    assert np.array_equal(rec.v, cols[chosen[1]])
    assert np.array_equal(rec.y, cols[chosen[2]])
    assert set(rec.extra) == set(names) - set(chosen)
    for name in rec.extra:
        assert np.array_equal(rec.extra[name], cols[name])


def test_leftover_y_column_never_shadows_the_chosen_output(tmp_path):
    path = tmp_path / "sim.csv"  # as written by pimodel simulate: model y, measured y_measured
    path.write_text("t,v,y,y_measured\n0,0,9,1\n0.1,1,9,2\n0.2,2,9,3\n")
    rec = load_record(path, columns=("t", "v", "y_measured"))
    assert np.array_equal(rec.y, [1, 2, 3]) and np.array_equal(rec.extra["y"], [9, 9, 9])
    rec2 = Record(rec.t, rec.v, rec.y, {"y": np.zeros(3), "t": np.ones(3)})
    assert np.array_equal(rec2.y, [1, 2, 3]) and np.array_equal(rec2.t, rec.t)
    with pytest.raises(ValueError, match=r"\['y'\] would appear twice"):
        save_record(rec, tmp_path / "o.csv")


# --- case 8: a CSV cut mid-row ---------------------------------------------------------------

@pytest.mark.parametrize("cut", range(1, 9))
def test_csv_cut_mid_row_never_reads_a_cut_number(tmp_path, cut):
    full = "t,v,y\n0,1.25,-7.8125\n0.001,1.5,-7.8125\n0.002,1.75,-7.8125\n"
    last = "0.002,1.75,-7.8125\n"
    path = tmp_path / "live.csv"
    path.write_text(full[: len(full) - len(last) + cut])  # the last row cut after `cut` chars
    with pytest.warns(UserWarning, match=r"line 4 has no line end.* data row 3 is left out"):
        rec = load_record(path)
    assert len(rec) == 2 and np.array_equal(rec.y, [-7.8125, -7.8125])


def test_complete_csv_without_final_newline_after_blank_line_is_kept(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("t,v,y\n0,1,2\n0.1,2,3\n\n   ")
    assert len(load_record(path)) == 2


# --- case 9: the path written is the path checked and reported ------------------------------

@pytest.mark.parametrize("name", ["keep.NPZ", "out.Npz", "x.npz"])
def test_npz_written_under_exactly_its_name(tmp_path, name):
    t, v, y = _signals(20)
    path = save_record(Record(t, v, y), tmp_path / name)
    assert path == tmp_path / name and sorted(p.name for p in tmp_path.iterdir()) == [name]
    assert np.array_equal(load_record(path).v, v)


# --- case 15: epoch time stamps -------------------------------------------------------------

def test_epoch_time_stamps_name_float64_resolution():
    t = 1.7e9 + np.arange(200) * 1e-5  # 100 kHz at epoch time: rounding to 2.4e-7 s
    with pytest.raises(DataError, match=r"float64 resolution: .* resolved only to 2.4e-07 s.*"
                       r"t - t\[0\]"):
        Record(t, np.zeros(200), np.zeros(200))
    slow = 1.7e9 + np.arange(200) * 1e-3  # 1 kHz: the rounding is 0.024 % of the interval
    assert len(Record(slow, np.zeros(200), np.zeros(200))) == 200


# --- case 16 and line numbers ----------------------------------------------------------------

def test_quoted_decimal_comma_gets_the_hint(tmp_path):
    path = tmp_path / "eu.csv"
    path.write_text('t,v,y\n0,"0,001",1\n0.1,1,2\n')
    with pytest.raises(DataError, match=r"line 2 \(data row 1\), column 'v': '0,001' is not a "
                       r"number \(a decimal comma\? write decimal points\)"):
        load_record(path)


def test_trailing_comma_in_header_and_rows(tmp_path):
    path = tmp_path / "excel.csv"
    path.write_text("t,v,y,\n0,1,2,\n0.1,2,3\n0.2,3,4,\n")
    rec = load_record(path)
    assert np.array_equal(rec.v, [1, 2, 3]) and rec.extra == {}
    path.write_text("t,,y\n0,1,2\n0.1,2,3\n")
    with pytest.raises(DataError, match="line 1: column 2 has no name"):
        load_record(path)


def test_error_lines_match_an_editor_across_blank_lines(tmp_path):
    path = tmp_path / "gaps.csv"
    path.write_text("t,v,y\n0,1,2\n\n\n0.1,1,2\n0.2,x,2\n")
    with pytest.raises(DataError, match=r"line 6 \(data row 3\), column 'v': 'x'"):
        load_record(path)
    path.write_text("t,v,y\n0,1,2\n\n0.1,1,2\n0.1,1,2\n")
    with pytest.raises(DataError, match=r"line 5 \(data row 3\), column 't': time 0.1 does "):
        load_record(path)


def test_long_csv_crosses_parse_blocks(tmp_path, monkeypatch):
    import pimodel.records as records

    monkeypatch.setattr(records, "CHUNK_ROWS", 7)
    t, v, y = _signals(100)
    path = save_record(Record(t, v, y), tmp_path / "r.csv")
    rec = load_record(path)
    assert np.array_equal(rec.t, t) and np.array_equal(rec.y, y)
    text = path.read_text().splitlines()
    text[60] = text[60].replace(",", ",oops", 1)
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(DataError, match=r"line 61 \(data row 60\), column 'v'"):
        load_record(path)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_block_reader_equals_line_reader(tmp_path, monkeypatch, seed):
    # a regular CSV is read by numpy.loadtxt in blocks of bytes (cut mid-line here), an
    # irregular one (a blank line, a CRLF file, a stray field) by the line reader: the same
    # record, to the bit, either way
    import pimodel.records as records

    rng = np.random.default_rng(seed)
    monkeypatch.setattr(records, "FAST_BLOCK_BYTES", int(rng.integers(40, 400)))
    n = int(rng.integers(50, 300))
    t = np.arange(n) * float(rng.uniform(1e-4, 1e-2))
    cols = [t, rng.normal(size=n) * 10.0 ** rng.integers(-8, 8, n), rng.normal(size=n)]
    lines = [",".join(repr(float(c[k])) for c in cols) for k in range(n)]
    path = tmp_path / "r.csv"
    path.write_text("t,v,y\n" + "\n".join(lines) + "\n")
    assert records._fast_csv(path) is not None
    fast = load_record(path)
    monkeypatch.setattr(records, "_fast_csv", lambda p: None)
    slow = load_record(path)
    for a, b, c in zip((fast.t, fast.v, fast.y), (slow.t, slow.v, slow.y), cols, strict=True):
        assert np.array_equal(a, b) and np.array_equal(a, c)
    monkeypatch.undo()
    k = int(rng.integers(1, n - 1))
    for text in ("t,v,y\n" + "\n".join(lines[:k] + [""] + lines[k:]) + "\n",
                 "t,v,y\r\n" + "\r\n".join(lines) + "\r\n"):
        path.write_text(text, newline="")
        assert np.array_equal(load_record(path).v, cols[1])
    path.write_text("t,v,y\n" + "\n".join(lines[:k] + ["1,2"] + lines[k:]) + "\n")
    with pytest.raises(DataError, match=rf"line {k + 2} \(data row {k + 1}\) has 2 fields"):
        load_record(path)


def test_npz_reads_only_the_columns_and_vectors_of_their_length(tmp_path, monkeypatch):
    t, v, y = _signals(120)
    path = tmp_path / "r.npz"
    np.savez(path, t=t, v=v, y=y, temp=v[:, None], other=np.zeros(7),
             image=np.zeros((120, 50)))
    read = []
    getitem = np.lib.npyio.NpzFile.__getitem__
    monkeypatch.setattr(np.lib.npyio.NpzFile, "__getitem__",
                        lambda self, k: read.append(k) or getitem(self, k))
    rec = load_record(path)
    assert sorted(read) == ["t", "temp", "v", "y"] and list(rec.extra) == ["temp"]
    assert np.array_equal(rec.y, y)
