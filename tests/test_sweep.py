"""The sweep runner: case order, serial without Dask, errors naming the case, resuming after a
failure or a killed run, the same numbers serially and on a Dask cluster, grids, random samples,
tidy tables and the ``pimodel sweep`` verb."""

from __future__ import annotations

import csv
import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from pimodel.cli import main
from pimodel.experiments.sweeps import (
    WORKER_ENV,
    CaseFailed,
    case_key,
    grid,
    random_cases,
    run_cases,
    tidy_rows,
    write_table,
)


def _square_logged(params: dict) -> dict:
    """A case function that logs each computed case to ``params['log']`` (one line each)."""
    with open(params["log"], "a") as fh:
        fh.write(f"{params['x']}\n")
    if params["x"] in params.get("fail_at", []):
        raise ArithmeticError(f"x = {params['x']} is not allowed")
    return {"y": params["x"] ** 2}


def _computed(log: Path) -> list[int]:
    return [int(s) for s in log.read_text().split()] if log.exists() else []


def test_serial_results_in_case_order_and_json_plain(tmp_path):
    import numpy as np

    cases = [{"x": x, "seed": x} for x in (3, 1, 2)]
    got = run_cases(lambda p: {"y": np.float64(p["x"]) / 2, "v": np.arange(p["x"])}, cases,
                    workers=0, progress=False)
    assert got == [{"y": 1.5, "v": [0, 1, 2]}, {"y": 0.5, "v": [0]}, {"y": 1.0, "v": [0, 1]}]
    assert type(got[0]["y"]) is float  # JSON values, the same whether computed or loaded


def test_serial_run_does_not_import_dask():
    code = textwrap.dedent("""
        import sys
        from pimodel.experiments.sweeps import run_cases
        assert run_cases(lambda p: p["x"] + 1, [{"x": 1}], workers=0, progress=False) == [2]
        print(sorted(m for m in sys.modules if m.split(".")[0] in ("dask", "distributed")))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize("cases, match", [
    ({"x": 1}, "cases: expected a list"),
    ([{"x": 1}, [1]], r"cases\[1\]: expected a dict"),
    ([{"x": (1, 2)}], r"cases\[0\]: .*lists, not tuples"),
    ([{"x": object()}], r"cases\[0\]: parameters must be plain JSON"),
    ([{"x": 1, "seed": 0}, {"seed": 0, "x": 1}], r"cases\[1\] repeats cases\[0\]"),
])
def test_bad_cases_are_refused(cases, match):
    with pytest.raises(ValueError, match=match):
        run_cases(lambda p: p, cases, workers=0, progress=False)


def test_bad_workers_are_refused():
    with pytest.raises(ValueError, match="workers: expected an integer >= 0, got -1"):
        run_cases(lambda p: p, [{"x": 1}], workers=-1)
    with pytest.raises(ValueError, match="give one of them"):
        run_cases(lambda p: p, [{"x": 1}], workers=2, scheduler="tcp://127.0.0.1:1")
    with pytest.raises(ValueError, match="func: expected a callable"):
        run_cases("f", [{"x": 1}], workers=0)


def test_failure_names_the_case_and_a_rerun_computes_only_the_rest(tmp_path):
    log, cache = tmp_path / "log", tmp_path / "cases"
    cases = [{"x": x, "log": str(log), "fail_at": [4]} for x in range(7)]
    with pytest.raises(CaseFailed, match=r"case 4 of 7 failed with ArithmeticError: x = 4 is "
                       r"not allowed; params: \{\"x\": 4.*4 finished cases kept in") as err:
        run_cases(_square_logged, cases, workers=0, cache_dir=cache, progress=False)
    assert err.value.index == 4 and err.value.params == cases[4]
    assert isinstance(err.value.__cause__, ArithmeticError)
    assert len(list(cache.glob("*.json"))) == 4
    # the bug is "fixed": the same cases without the failing switch are new cases, so keep the
    # params and let the function stop failing instead
    log.unlink()
    for c in cases:
        c["fail_at"] = [4]
    got = run_cases(_square_logged_fixed, cases, workers=0, cache_dir=cache, progress=False)
    assert _computed(log) == [4, 5, 6]
    assert got == [{"y": x * x} for x in range(7)]
    log.unlink()
    assert run_cases(_square_logged_fixed, cases, workers=0, cache_dir=cache,
                     progress=False) == got
    assert _computed(log) == []  # everything loaded
    run_cases(_square_logged_fixed, cases, workers=0, cache_dir=cache, fresh=True,
              progress=False)
    assert _computed(log) == list(range(7))


def _square_logged_fixed(params: dict) -> dict:
    return _square_logged({**params, "fail_at": []})


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_killed_sweep_resumes_with_only_the_missing_cases(tmp_path):
    """A sweep process killed (SIGKILL, no clean-up) during case 5 of 9 leaves 5 finished
    cases; the rerun computes the other 4."""
    log, cache = tmp_path / "log", tmp_path / "cases"
    script = textwrap.dedent(f"""
        import os, signal
        from pimodel.experiments.sweeps import run_cases

        def case(p):
            with open({str(log)!r}, "a") as fh:
                fh.write(f"{{p['x']}}\\n")
            if p["x"] == 5 and os.environ.get("KILL_AT_5"):
                os.kill(os.getpid(), signal.SIGKILL)
            return {{"y": p["x"] ** 2}}

        if __name__ == "__main__":
            cases = [{{"x": x, "seed": 10 + x}} for x in range(9)]
            print(run_cases(case, cases, workers=0, cache_dir={str(cache)!r}, progress=False))
    """)
    path = tmp_path / "sweep_script.py"
    path.write_text(script)
    first = subprocess.run([sys.executable, str(path)], env={**os.environ, "KILL_AT_5": "1"},
                           capture_output=True, text=True)
    assert first.returncode == -9
    assert _computed(log) == [0, 1, 2, 3, 4, 5]
    assert len(list(cache.glob("*.json"))) == 5 and not list(cache.glob("*.tmp*"))
    log.unlink()
    second = subprocess.run([sys.executable, str(path)], capture_output=True, text=True,
                            check=True)
    assert _computed(log) == [5, 6, 7, 8]
    assert second.stdout.strip() == str([{"y": x * x} for x in range(9)])


def test_unreadable_or_foreign_cache_files_are_recomputed(tmp_path):
    log, cache = tmp_path / "log", tmp_path / "cases"
    cases = [{"x": x, "log": str(log)} for x in range(3)]
    run_cases(_square_logged, cases, workers=0, cache_dir=cache, progress=False)
    (cache / f"{case_key(cases[0])}.json").write_text("{not json")
    (cache / f"{case_key(cases[1])}.json").write_text(json.dumps({"params": {"x": 99},
                                                                  "result": 0}))
    log.unlink()
    got = run_cases(_square_logged, cases, workers=0, cache_dir=cache, progress=False)
    assert sorted(_computed(log)) == [0, 1] and got == [{"y": 0}, {"y": 1}, {"y": 4}]


def test_case_key_ignores_key_order_and_separates_values():
    assert case_key({"a": 1, "b": [1, 2]}) == case_key({"b": [1, 2], "a": 1})
    assert case_key({"a": 1}) != case_key({"a": 1.5}) != case_key({"a": "1"})


def test_grid_and_random_cases():
    g = grid(snr=[10, 20], seed=[0, 1, 2])
    assert len(g) == 6 and g[1] == {"snr": 10, "seed": 1} and g[-1] == {"snr": 20, "seed": 2}
    r = random_cases(50, seed=3, noise_um=(0.003, 0.01), mode_hz=(500, 3000))
    assert r == random_cases(50, seed=3, noise_um=(0.003, 0.01), mode_hz=(500, 3000))
    assert [c["seed"] for c in r] == list(range(3, 53))
    assert all(0.003 <= c["noise_um"] <= 0.01 and 500 <= c["mode_hz"] <= 3000 for c in r)
    assert len({c["noise_um"] for c in r}) == 50
    with pytest.raises(ValueError, match="snr: expected a non-empty list"):
        grid(snr=[])
    with pytest.raises(ValueError, match="noise_um: expected a range"):
        random_cases(2, noise_um=(0.01, 0.003))
    with pytest.raises(ValueError, match="n: expected an integer >= 1"):
        random_cases(0, noise_um=(0, 1))


def test_tidy_table_csv_reads_back(tmp_path):
    cases = [{"seed": 0, "effects": ["creep"]}, {"seed": 1, "effects": []}]
    results = [{"radii": [0.4, 1.0], "fit": {"rms": 0.1}}, {"radii": [0.5], "ok": True}]
    rows = tidy_rows(cases, results)
    assert rows[0] == {"seed": 0, "effects": "creep", "radii[1]": 0.4, "radii[2]": 1.0,
                       "fit.rms": 0.1}
    path = write_table(rows, tmp_path / "t.csv")
    with path.open() as fh:
        back = list(csv.DictReader(fh))
    assert list(back[0]) == ["seed", "effects", "radii[1]", "radii[2]", "fit.rms", "ok"]
    assert back[1]["radii[2]"] == "" and float(back[0]["radii[2]"]) == 1.0
    assert back[1]["effects"] == "" and back[1]["ok"] == "True"
    with pytest.raises(ValueError, match=r"t.txt: expected a .csv or .parquet"):
        write_table(rows, tmp_path / "t.txt")


def test_tidy_table_parquet_or_clear_error(tmp_path):
    rows = [{"seed": 0, "rms": 0.1}, {"seed": 1, "rms": 0.2}]
    try:
        import pyarrow.parquet as pq
    except ImportError:
        with pytest.raises(ValueError, match="Parquet needs pyarrow"):
            write_table(rows, tmp_path / "t.parquet")
        return
    table = pq.read_table(write_table(rows, tmp_path / "t.parquet"))
    assert table.column("rms").to_pylist() == [0.1, 0.2]


def test_cli_sweep_identify_table(tmp_path):
    out = tmp_path / "sw"
    assert main(["sweep", "identify", "--grid", "noise_um=0.005,0.05", "--set", "n_plays=4",
                 "--seeds", "2", "--workers", "0", "--out", str(out)]) == 0
    with (out / "table.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [(float(r["noise_um"]), int(r["seed"])) for r in rows] == [
        (0.005, 0), (0.005, 1), (0.05, 0), (0.05, 1)]
    for r in rows:  # a 4-play fit of the 4-play truth: the residual is the sensor noise
        assert r["n_plays"] == "4" and r["target"] == "identify"
        assert 0.7 < float(r["validate_rms"]) / float(r["noise_um"]) < 1.5
        assert {"weights[4]", "radii[4]"} <= set(r)
    assert len(list((out / "cases").glob("*.json"))) == 4


def test_cli_sweep_random_diagnose(tmp_path):
    out = tmp_path / "sw"
    assert main(["sweep", "diagnose", "--random", "mode_hz=800:2500", "--samples", "1",
                 "--seed", "4", "--workers", "0", "--out", str(out)]) == 0
    with (out / "table.csv").open() as fh:
        (row,) = list(csv.DictReader(fh))
    assert row["seed"] == "4" and 800 <= float(row["mode_hz"]) <= 2500
    assert row["correct"] == str(row["verdict"] == "dynamics")
    assert float(row["gap_after"]) <= float(row["gap_before"])


@pytest.mark.parametrize("argv, match", [
    (["--grid", "bogus=1,2"], r"cases\[0\]: unknown parameter\(s\) \['bogus'\]"),
    (["--grid", "max_effects=1"], r"unknown parameter\(s\) \['max_effects'\] for target "
                                  r"'identify'"),
    (["--grid", "noise_um=0.01", "--random", "mode_hz=1:2", "--samples", "2"],
     "--grid and --random"),
    (["--random", "mode_hz=1:2"], "--samples: expected an integer >= 1"),
    (["--grid", "noise_um=0.01", "--set", "noise_um=0.02"], "--set noise_um: already swept"),
    (["--table", "t.xlsx"], "table: expected a .csv or .parquet"),
])
def test_cli_sweep_errors(tmp_path, capsys, argv, match):
    assert main(["sweep", "identify", "--workers", "0", "--out", str(tmp_path), *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pimodel sweep: error: ") and re.search(match, err), err


# ----- on a Dask cluster (one 2-worker LocalCluster for these tests; start-up costs seconds)

@pytest.fixture(scope="module")
def scheduler():
    import logging

    import cloudpickle
    from dask.distributed import LocalCluster

    cloudpickle.register_pickle_by_value(sys.modules[__name__])  # tests/ is not importable there
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=logging.ERROR,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as cluster:
        yield cluster.scheduler_address


@pytest.mark.slow
def test_cluster_gives_the_serial_numbers_in_case_order(tmp_path, scheduler):
    from pimodel.experiments.stage_sweeps import truth_sweep

    cases = [{**c, "n_plays": 4} for c in grid(noise_um=[0.005, 0.02], seed=[0, 1, 2])]
    serial = truth_sweep(cases, target="identify", out=tmp_path / "s", workers=0,
                         progress=False)
    cluster = truth_sweep(cases, target="identify", out=tmp_path / "c", scheduler=scheduler,
                          progress=False)
    assert cluster == serial
    assert (tmp_path / "s" / "table.csv").read_text() == (tmp_path / "c" / "table.csv").read_text()


@pytest.mark.slow
def test_cluster_failure_names_the_case_and_keeps_the_finished(tmp_path, scheduler):
    log, cache = tmp_path / "log", tmp_path / "cases"
    cases = [{"x": x, "log": str(log), "fail_at": [0]} for x in range(5)]
    with pytest.raises(CaseFailed, match=r"case 0 of 5 failed with ArithmeticError: x = 0 is "
                       r"not allowed; params: \{\"x\": 0"):
        run_cases(_square_logged, cases, scheduler=scheduler, cache_dir=cache, progress=False)
    kept = {json.loads(p.read_text())["params"]["x"] for p in cache.glob("*.json")}
    assert 0 not in kept
    log.unlink()
    got = run_cases(_square_logged_fixed, cases, scheduler=scheduler, cache_dir=cache,
                    progress=False)
    assert got == [{"y": x * x} for x in range(5)]
    assert sorted(_computed(log)) == sorted(set(range(5)) - kept)


def _start_environment(params: dict) -> dict:
    """The environment the worker process was started with (Linux: /proc/self/environ), which
    is what glibc read its malloc settings from; ``os.environ`` may have changed since."""
    raw = Path("/proc/self/environ").read_bytes().split(b"\0")
    env = dict(item.decode().split("=", 1) for item in raw if b"=" in item)
    return {k: env.get(k) for k in WORKER_ENV}


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/environ").exists(), reason="needs Linux /proc")
@pytest.mark.parametrize("parent_trim", [None, "65536"])
def test_local_workers_start_with_the_malloc_settings(monkeypatch, parent_trim):
    """Dask's default MALLOC_TRIM_THRESHOLD_=65536 switches off glibc's dynamic mmap threshold
    (a case spent as much CPU in page faults as in its own code); the local cluster's workers
    must be *started* with WORKER_ENV, not get it after start, also when an earlier Dask
    cluster left Dask's default in the parent's environment (the nanny prefers it to the
    config); the parent's own value is put back."""
    import cloudpickle

    if parent_trim is None:
        monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    else:
        monkeypatch.setenv("MALLOC_TRIM_THRESHOLD_", parent_trim)
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    got = run_cases(_start_environment, [{"i": 0}, {"i": 1}], workers=2, progress=False)
    assert got == [WORKER_ENV, WORKER_ENV]
    assert os.environ.get("MALLOC_TRIM_THRESHOLD_") == parent_trim


def _thread_budget_seen(params: dict) -> dict:
    from pimodel.cores import available_cores
    from pimodel.diagnosis.threads import default_workers

    return {"cores": available_cores(), "diagnosis_threads": default_workers()}


@pytest.mark.slow
def test_cases_on_dask_workers_get_one_thread_and_serial_cases_the_cores(scheduler):
    """A Dask worker runs one case per core: a case's own thread pools (the diagnosis') must
    default to one thread there, or two workers of a 2-core machine run four threads; the
    serial path keeps the process' cores."""
    from pimodel.cores import available_cores

    cloudpickle = pytest.importorskip("cloudpickle")
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    cases = [{"i": 0}, {"i": 1}]
    on_workers = run_cases(_thread_budget_seen, cases, scheduler=scheduler, progress=False)
    assert on_workers == [{"cores": 1, "diagnosis_threads": 1}] * 2
    serial = run_cases(_thread_budget_seen, cases, workers=0, progress=False)
    n = available_cores()
    assert serial == [{"cores": n, "diagnosis_threads": min(2, n)}] * 2
