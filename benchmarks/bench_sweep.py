"""Benchmark: a sweep study serially (``--workers 0``) against a 2-worker local Dask cluster.

Run: ``.venv/bin/python benchmarks/bench_sweep.py [--study sim_to_real] [--quick] [--workers 2]
[--repeat 1]``.
Goal (issue 17): the full ``sim_to_real`` (250 cases) at least 1.7x faster on 2 workers than
serially, on a 2-core machine. Both runs start from an empty case folder (``fresh``) and include
everything ``pimodel study`` does: cluster start-up and shut-down, the cases, the aggregate step
(the real-record diagnosis) and the figures. The runs alternate (serial, cluster, serial, ...)
so that a changing machine load hits both; the load average is printed, since other processes
on the machine take cores from both runs. The results.json of both runs must be equal.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from pimodel.experiments.studies import run_study


def timed_run(study: str, quick: bool, workers: int, out: Path) -> tuple[float, dict]:
    t0 = time.perf_counter()
    res = run_study(study, out, quick=quick, workers=workers, fresh=True)
    return time.perf_counter() - t0, res.to_json()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--study", default="sim_to_real")
    ap.add_argument("--quick", action="store_true", help="the study's reduced size")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=1, help="alternating pairs of runs")
    args = ap.parse_args()
    serial, cluster = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.repeat):
            for workers, times in ((0, serial), (args.workers, cluster)):
                load = os.getloadavg()[0]
                dt, result = timed_run(args.study, args.quick, workers,
                                       Path(tmp) / f"w{workers}-{k}")
                times.append(dt)
                print(f"run {k}, workers {workers}: {dt:8.1f} s  (load average before: "
                      f"{load:.1f} on {os.cpu_count()} cores)", flush=True)
                if workers == 0:
                    reference = result
                elif result != reference:
                    raise SystemExit("results.json differs between serial and cluster runs")
        n_cases = len(list((Path(tmp) / "w0-0" / "cases").glob("*.json")))
    t0, t1 = min(serial), min(cluster)
    speedup = t0 / t1
    size = "quick" if args.quick else "full"
    print(f"\n{args.study} ({size}, {n_cases} cases), best of {args.repeat}")
    print(f"{'run':<34}{'time [s]':>10}{'s/case':>10}{'cases/hour':>12}")
    print(f"{'serial (--workers 0)':<34}{t0:>10.1f}{t0 / n_cases:>10.2f}"
          f"{3600 * n_cases / t0:>12.0f}")
    print(f"{f'local cluster (--workers {args.workers})':<34}{t1:>10.1f}"
          f"{t1 / n_cases:>10.2f}{3600 * n_cases / t1:>12.0f}")
    print(f"speed-up: {speedup:.2f}x   goal (full sim_to_real, 2 workers): >= 1.7x -> "
          f"{'met' if speedup >= 1.7 else 'NOT met'}; results.json equal: yes")
    print(json.dumps({"study": args.study, "quick": args.quick, "cases": n_cases,
                      "serial_s": serial, "cluster_s": cluster, "speedup": speedup}))


if __name__ == "__main__":
    main()
