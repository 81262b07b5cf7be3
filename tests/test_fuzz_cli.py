"""Fuzzing the command line over generated bad files, in a subprocess with a timeout so that a
crash or a hang fails the test instead of killing pytest (bounded: about a minute).

Each batch: hypothesis writes hostile record files (mutated CSVs, other separators, BOMs, binary
junk, truncated or fake .npz), then one child process runs ``pimodel simulate`` and ``pimodel
identify`` on each, plus a command whose output names the input (same path, relative path or
symlink). Every command must exit 0 or 2 (2 with a message naming the file or the argument),
never raise anything else, and no input file may change (SHA-256 before and after).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pimodel import PIOperator, Record, save_record

DRIVER = r"""
import contextlib, io, json, sys, traceback, warnings
from pimodel.cli import main
out = []
for argv in json.load(open(sys.argv[1])):
    err = io.StringIO()
    with warnings.catch_warnings(), contextlib.redirect_stderr(err), \
            contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse usage errors
            code = exc.code
        except BaseException as exc:
            code = "crash: " + "".join(traceback.format_exception(exc))[-800:]
    out.append({"argv": argv, "code": code, "stderr": err.getvalue()[-400:]})
json.dump(out, open(sys.argv[2], "w"))
"""
BATCH_TIMEOUT = 240  # seconds for one child process (a hang fails the test)
TOTALS = {"files": 0, "commands": 0, "overwrite_attempts": 0, "crashes": 0, "hangs": 0,
          "modified_inputs": 0}


def valid_csv() -> str:
    t = np.arange(300) * 1e-3
    v = 2 * np.sin(2 * np.pi * 4 * t)
    y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
    return "t,v,y\n" + "".join(f"{float(a)!r},{float(b)!r},{float(c)!r}\n"
                                for a, b, c in zip(t, v, y, strict=True))


VALID = valid_csv()


@st.composite
def hostile_file(draw):
    kind = draw(st.sampled_from(["mutate", "separator", "bom", "truncate", "junk", "npz",
                                 "columns", "dt", "valid"]))
    text = VALID
    if kind == "mutate":
        lines = text.splitlines()
        for _ in range(draw(st.integers(1, 4))):
            i = draw(st.integers(0, len(lines) - 1))
            lines[i] = draw(st.sampled_from(["", "nan,1,2", "1,2", "x,y,z", "0,0,0,0", "inf,0,0",
                                             "1e999,0,0", "\x00\x00", ",,", "-1,0,0",
                                             "0.1,1e308,1e308"]))
        text = "\n".join(lines) + "\n"
    elif kind == "separator":
        text = text.replace(",", draw(st.sampled_from([";", "\t", " ", "|"])))
    elif kind == "bom":
        text = "\ufeff" + text
    elif kind == "truncate":
        text = text[:draw(st.integers(0, 200))]
    elif kind == "columns":
        text = text.replace("t,v,y", draw(st.sampled_from(["t,v", "t,v,y_measured",
                                                           "time,v,y", "t,t,y", "T,V,Y"])), 1)
    elif kind == "dt":
        lines = text.splitlines()
        lines[150:] = [f"{float(ln.split(',')[0]) * 2!r},{ln.split(',', 1)[1]}"
                       for ln in lines[150:]]
        text = "\n".join(lines) + "\n"
    data = text.encode()
    if kind == "junk":
        data = draw(st.binary(max_size=300))
    elif kind == "npz":
        data = draw(st.sampled_from([b"PK\x03\x04" + bytes(50), text.encode(), b"",
                                     b"PK\x05\x06" + bytes(18)]))
    suffix = ".npz" if kind == "npz" else draw(st.sampled_from([".csv", ".csv", ".txt"]))
    return data, suffix


def sha(path) -> str:
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def commands(path, outdir, k, spelling, cwd):
    sim = ["simulate", str(path), "--weights", "1,0.5", "--radii", "0,0.3"]
    ident = ["identify", str(path), "--plays", "2", "--method", "joint"]
    same = {"same": str(path), "relative": os.path.relpath(path, cwd),
            "symlink": str(outdir / f"link{k}{path.suffix}")}[spelling]
    if spelling == "symlink":
        os.symlink(path, same)
    return [[*sim, "--out", str(outdir / f"o{k}.csv")],
            [*ident, "--json", str(outdir / f"o{k}.json")],
            [*sim, "--out", same], [*ident, "--json", same]]


@pytest.mark.slow
@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(files=st.lists(hostile_file(), min_size=10, max_size=25),
       spellings=st.lists(st.sampled_from(["same", "relative", "symlink"]), min_size=25,
                          max_size=25))
def test_cli_on_hostile_files(tmp_path_factory, files, spellings):
    root = tmp_path_factory.mktemp("cli")
    indir, outdir = root / "in", root / "out"
    indir.mkdir()
    outdir.mkdir()
    argvs, inputs = [], []
    for k, (data, suffix) in enumerate(files):
        path = indir / f"rec{k}{suffix}"
        path.write_bytes(data)
        inputs.append(path)
        argvs += commands(path, outdir, k, spellings[k], root)
    before = {p: sha(p) for p in inputs}
    (root / "argv.json").write_text(json.dumps(argvs))
    try:
        proc = subprocess.run([sys.executable, "-c", DRIVER, str(root / "argv.json"),
                               str(root / "res.json")], capture_output=True, text=True,
                              timeout=BATCH_TIMEOUT, cwd=root)
    except subprocess.TimeoutExpired:
        TOTALS["hangs"] += 1
        raise AssertionError(f"CLI batch did not finish in {BATCH_TIMEOUT} s (a hang)") from None
    assert proc.returncode == 0, f"child died (code {proc.returncode}): {proc.stderr[-2000:]}"
    results = json.loads((root / "res.json").read_text())
    modified = [str(p) for p in inputs if sha(p) != before[p]]
    crashes = [r for r in results if r["code"] not in (0, 2)]
    TOTALS["files"] += len(inputs)
    TOTALS["commands"] += len(results)
    TOTALS["overwrite_attempts"] += 2 * len(inputs)
    TOTALS["crashes"] += len(crashes)
    TOTALS["modified_inputs"] += len(modified)
    print(f"\nfuzz_cli: {TOTALS}")
    assert not crashes, crashes[:3]
    assert not modified, modified
    for r in results:
        if r["code"] == 2:  # names the file, an option, or the argument (e.g. "v: ...")
            assert re.search(r"error: (\S*rec\d|--|\S+: )", r["stderr"]), r
    for k, r in enumerate(results):
        if k % 4 >= 2:  # the commands writing over their input
            assert r["code"] == 2 and "never writes over an input file" in r["stderr"], r


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_installed_command_exit_status_on_bad_files(tmp_path):
    """Through ``python -m pimodel`` itself: exit 2 and a one-line error naming the file."""
    cases = {"bad.npz": b"t,v,y\n0,1,2\n", "empty.csv": b"", "junk.csv": b"\xff\xfe\x00\x01"}
    for name, data in cases.items():
        path = tmp_path / name
        path.write_bytes(data)
        proc = subprocess.run([sys.executable, "-m", "pimodel", "simulate", str(path),
                               "--weights", "1", "--radii", "0", "--out",
                               str(tmp_path / "o.csv")], capture_output=True, text=True,
                              timeout=120)
        assert proc.returncode == 2, proc.stderr
        assert name in proc.stderr and "Traceback" not in proc.stderr


def test_simulate_output_never_clobbers_a_linked_input(tmp_path):
    t = np.arange(100) * 1e-3
    save_record(Record(t, np.sin(50 * t), np.cos(50 * t)), tmp_path / "d.csv")
    os.symlink(tmp_path / "d.csv", tmp_path / "alias.csv")
    before = sha(tmp_path / "d.csv")
    proc = subprocess.run([sys.executable, "-m", "pimodel", "simulate", str(tmp_path / "d.csv"),
                           "--weights", "1", "--radii", "0", "--out",
                           str(tmp_path / "alias.csv")], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2 and "--out" in proc.stderr
    assert sha(tmp_path / "d.csv") == before
