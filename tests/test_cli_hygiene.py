"""Command-line hygiene: --version, a --help that loads no NumPy, output paths checked before
any work (naming the option), each warning printed once, --columns per file, pimodel split, the
exact output path (issue 32 case 9) and an export that never mixes two runs (case 10)."""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from pimodel import Record, load_record, save_record
from pimodel.cli import main

sys.path.insert(0, str(Path(__file__).parent))
from test_cli_safety import SIM, record  # noqa: E402, F401 (the record fixture)


def test_version(capsys):
    from pimodel import __version__

    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0 and capsys.readouterr().out.strip() == f"pimodel {__version__}"


def test_help_lists_every_command_without_loading_numpy():
    code = ("import sys\nfrom pimodel.cli import COMMANDS, main\ntry:\n    main(['--help'])\n"
            "except SystemExit:\n    pass\nprint('numpy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    from pimodel.cli import COMMANDS

    assert out.strip().endswith("False")
    assert all(f"    {name} " in out for name in COMMANDS)


def test_sweep_help_lists_the_sweep_names_without_loading_the_simulator():
    from pimodel.cli.sweep import HELP_NAMES
    from pimodel.experiments.stage_sweeps import DIAGNOSE_SETTINGS, IDENTIFY_SETTINGS, TRUTH_PARAMS

    assert HELP_NAMES == {"Truth parameters": (*TRUTH_PARAMS, "fs"),
                          "Diagnose settings": DIAGNOSE_SETTINGS,
                          "Identify settings": IDENTIFY_SETTINGS}
    code = ("import sys\nfrom pimodel.cli import main\ntry:\n    main(['sweep', '--help'])\n"
            "except SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'scipy' or "
            "m.startswith('pimodel.stages')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip().endswith("[]")
    text = " ".join(out.split())  # argparse wraps the description
    for what, names in HELP_NAMES.items():
        assert f"{what}: {', '.join(names)}." in text


def test_json_folder_refused_before_any_work(record, tmp_path, capsys, monkeypatch):  # noqa: F811
    import pimodel.identification.chain as chain

    monkeypatch.setattr(chain, "identify", lambda *a, **k: pytest.fail("the fit ran"))
    folder = tmp_path / "adir"
    folder.mkdir()
    assert main(["identify", str(record), "--json", str(folder)]) == 2
    assert f"--json {folder}: a folder; expected a file name" in capsys.readouterr().err
    (tmp_path / "afile").write_text("x")
    assert main(["identify", str(record), "--json", str(tmp_path / "afile" / "m.json")]) == 2
    assert "--json" in capsys.readouterr().err
    assert main(["identify", str(record), "--json", str(tmp_path / "m.json"), "--plots",
                 str(tmp_path / "afile")]) == 2
    assert f"--plots {tmp_path / 'afile'}: a file; expected a folder" in capsys.readouterr().err



@pytest.mark.parametrize("other", ["--report", "--export"])
def test_diagnose_outputs_that_name_one_file_are_refused_before_any_work(
        record, tmp_path, capsys, monkeypatch, other):  # noqa: F811
    import pimodel.diagnosis as diagnosis

    monkeypatch.setattr(diagnosis, "diagnose", lambda *a, **k: pytest.fail("the diagnosis ran"))
    name = {"--report": "report.md", "--export": "augmented.json"}[other]
    out = tmp_path / "out"
    code = main(["diagnose", "--train", str(record), "--validate", str(record), "--json",
                 str(out / name), other, str(out)])
    err = capsys.readouterr().err
    assert code == 2 and f"{other} {name}" in err and f"the output --json ({out / name})" in err
    assert not out.exists()


def test_each_warning_printed_once(tmp_path, capsys, monkeypatch):
    import pimodel.identification.chain as chain

    def warns_twice(*args, **kwargs):
        for _ in range(2):
            warnings.warn("radius estimate health: radii still moving", UserWarning,
                          stacklevel=2)
        warnings.warn("radius estimate health: radii still moving", UserWarning, stacklevel=1)
        raise ValueError("stop here")

    monkeypatch.setattr(chain, "identify", warns_twice)
    path = tmp_path / "semi.csv"
    path.write_text("t;v;y\n0;0;0\n0.1;1;1\n0.2;0;0\n")
    assert main(["identify", str(path), "--json", str(tmp_path / "m.json")]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err.count("pimodel identify: warning: UserWarning: radius estimate health: radii "
                     "still moving") == 1
    assert sum("semicolon" in line for line in err) == 1
    assert len(err) == 3 and err[-1] == "pimodel identify: error: stop here"


def test_columns_per_file(tmp_path, capsys, monkeypatch):
    import pimodel.diagnosis as diagnosis

    t = np.arange(50) * 1e-3
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text("time_s,voltage_V,disp_um\n" + "".join(f"{float(x)!r},{k},{2 * k}\n"
                                                         for k, x in enumerate(t)))
    b.write_text("t,u,x,y\n" + "".join(f"{float(x)!r},{-k},{3 * k},9\n"
                                           for k, x in enumerate(t)))
    seen = {}

    def fake(train, validate, **kwargs):
        seen.update(train=train, validate=validate)
        raise ValueError("stop here")

    monkeypatch.setattr(diagnosis, "diagnose", fake)
    argv = ["diagnose", "--train", str(a), "--validate", str(b), "--json",
            str(tmp_path / "r.json"), "--columns", f"{a}:time_s,voltage_V,disp_um",
            "--columns", f"{b}:t,u,x"]
    assert main(argv) == 2
    assert np.array_equal(seen["train"][0].y, 2 * np.arange(50))
    assert np.array_equal(seen["validate"][0].v, -np.arange(50))
    assert np.array_equal(seen["validate"][0].y, 3 * np.arange(50))  # x, not the column y
    assert main(argv[:-2] + ["--columns", f"{tmp_path / 'c.csv'}:t,u,x"]) == 2
    assert "c.csv is not an input file" in capsys.readouterr().err


def test_split_command(record, tmp_path, capsys):  # noqa: F811
    train, validate = tmp_path / "train.csv", tmp_path / "val.npz"
    assert main(["split", str(record), "--fraction", "0.75", "--train", str(train),
                 "--validate", str(validate)]) == 0
    out = capsys.readouterr().out
    assert "train part: samples 0..299 of 400" in out and "validate part: samples 300..399" in out
    whole, a, b = load_record(record), load_record(train), load_record(validate)
    assert np.array_equal(np.concatenate([a.t, b.t]), whole.t)
    assert np.array_equal(np.concatenate([a.y, b.y]), whole.y)
    assert main(["split", str(record), "--fraction", "1", "--train", str(tmp_path / "x.csv"),
                 "--validate", str(tmp_path / "y.csv")]) == 2
    assert "--fraction 1.0" in capsys.readouterr().err


def test_simulate_writes_exactly_the_out_path(tmp_path, capsys):
    src = tmp_path / "keep.NPZ.npz"
    t = np.arange(100) * 1e-3
    save_record(Record(t, np.sin(50 * t), np.cos(50 * t)), src)
    before = src.read_bytes()
    out = tmp_path / "keep.NPZ"
    assert main(["simulate", str(src), *SIM, "--out", str(out)]) == 0
    assert src.read_bytes() == before
    assert f"to {out}" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.NPZ", "keep.NPZ.npz"]
    assert np.array_equal(load_record(out).t, t)


def test_interrupted_export_leaves_the_earlier_run(tmp_path, monkeypatch):
    from pimodel.cli import diagnose as cli_diagnose

    out = tmp_path / "model"
    out.mkdir()
    old = {"augmented.json": "old", "augmented_1_DiagnosedModel.fmu": "old fmu"}
    for name, text in old.items():
        (out / name).write_text(text)

    def interrupted(rep, folder, fmu):
        (folder / "augmented.json").write_text("new")
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_diagnose, "_write_exports", interrupted)
    with pytest.raises(KeyboardInterrupt):
        cli_diagnose.export_models(None, out, fmu=False)
    assert {p.name: p.read_text() for p in out.iterdir()} == old
    assert [p.name for p in tmp_path.iterdir()] == ["model"]  # no temporary folder left

    def json_only(rep, folder, fmu):
        for name in ("augmented.json", "nominal.json"):
            (folder / name).write_text("new")
        return [folder / "augmented.json", folder / "nominal.json"]

    monkeypatch.setattr(cli_diagnose, "_write_exports", json_only)
    paths = cli_diagnose.export_models(None, out, fmu=False)
    assert paths == [out / "augmented.json", out / "nominal.json"]
    assert {p.name: p.read_text() for p in out.iterdir()} == {"augmented.json": "new",
                                                              "nominal.json": "new"}


def test_sweep_reports_reused_and_computed_and_one_line_when_interrupted(tmp_path, capsys,
                                                                         monkeypatch):
    import pimodel.experiments.stage_sweeps as stage_sweeps
    from pimodel.experiments.sweeps import Interrupted

    def finished(cases, counts, **kwargs):
        counts.update(reused=3, computed=1)
        return [{}] * 4

    def interrupted(cases, counts, **kwargs):
        raise Interrupted(2, 4, tmp_path / "cases")

    argv = ["sweep", "identify", "--grid", "noise_um=0.005,0.05", "--seeds", "2",
            "--workers", "0", "--out", str(tmp_path)]
    monkeypatch.setattr(stage_sweeps, "truth_sweep", finished)
    assert main(argv) == 0
    assert f"4 cases (3 reused from {tmp_path / 'cases'}, 1 computed)" in capsys.readouterr().out
    monkeypatch.setattr(stage_sweeps, "truth_sweep", interrupted)
    assert main(argv) == 130
    out = capsys.readouterr()
    assert out.err == (f"pimodel sweep: interrupted: 2 of 4 cases kept in {tmp_path / 'cases'}; "
                       "rerun the same command to resume\n") and out.out == ""
