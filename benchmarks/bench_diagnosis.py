"""Benchmark: the sim-to-real gap diagnosis of a train and a validate record of N samples each.

Run: ``.venv/bin/python benchmarks/bench_diagnosis.py [--samples 100000 300000 1000000]
[--workers 1 2]``.
Goals (issue 31): two 1M-sample records diagnosed in under 30 s and under 2 GB peak memory
on two cores, time and memory growing at most linearly from 100k to 1M samples. Each size
runs in a fresh process (its peak resident memory is the process' own, ``ru_maxrss``, and its
peak address space, ``VmPeak``, reservations included), with
wall time and process CPU time (less sensitive to the load of a shared machine). Baseline in
the same run, also in its own process: one plain least-squares fit of a PI model
(``np.linalg.lstsq`` on the 20-play design matrix of the train record), so the ratio says how
many such fits a whole diagnosis costs. Each size runs the diagnosis once per ``--workers``
value (``diagnose(workers=W)``: its independent fits on W threads), one after the other, so the
wall ratio of the two is measured under the same load; the load average is printed before and
after each row (on a shared machine the CPU time and the wall ratio are what compare).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

from pimodel.records import Record
from pimodel.stages.pi_stage import excitation, random_truth


def long_record(kind: str, n: int, truth, seed: int, t0: float = 0.0) -> Record:
    """Excitations of ``kind`` (new random steps each) joined to ``n`` samples at 10 kHz, the
    clock starting at ``t0`` [s]."""
    parts, total, s = [], 0, seed
    while total < n:
        parts.append(excitation(kind, seed=s)[1])
        total += parts[-1].size
        s += 1
    v = np.concatenate(parts)[:n]
    t = t0 + np.arange(n) * 1e-4
    return truth.record(t, v, seed, kind)


def records(n: int) -> tuple[Record, Record]:
    """The train and validate records of ``n`` samples (truth: creep + dynamics)."""
    truth = random_truth(["creep", "dynamics"], 0)
    return long_record("train", n, truth, 1), long_record("validate", n, truth, 100)


def run_one(n: int, what: str, workers: int = 1) -> dict:
    """Time and peak memory of the diagnosis (``what="diagnosis"``, on ``workers`` threads)
    or of the plain fit."""
    tr, va = records(n)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0, c0 = time.perf_counter(), time.process_time()
    out: dict = {}
    if what == "diagnosis":
        from pimodel.diagnosis import diagnose

        rep = diagnose([tr], [va], workers=workers)
        out = {"effects": rep.verdict["effects"], "shrink": rep.verdict["shrink"],
               "plays": len(rep.nominal["model"]["radii"])}
    else:
        from pimodel.operators.pi import PIOperator

        radii = np.linspace(0, np.ptp(tr.v) / 2, 20)
        A = np.column_stack((PIOperator(np.ones(20), radii).play_outputs(tr.v),
                             np.ones(tr.v.size)))
        np.linalg.lstsq(A, tr.y, rcond=None)
    out.update(wall=time.perf_counter() - t0, cpu=time.process_time() - c0,
               peak_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
               records_mb=rss0 / 1024, address_mb=_peak_address_space_mb())
    return out


def _peak_address_space_mb() -> float | None:
    """The process' peak virtual memory (``VmPeak``: what ``RLIMIT_AS`` bounds; reservations
    count) [MB]; None where ``/proc`` does not give it."""
    try:
        with open("/proc/self/status") as fh:
            line = next(x for x in fh if x.startswith("VmPeak:"))
    except (OSError, StopIteration):
        return None
    return int(line.split()[1]) / 1024


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, nargs="+", default=[100_000, 300_000, 1_000_000])
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2],
                    help="threads of the diagnosis, each value a row (default: 1 2)")
    ap.add_argument("--one", nargs=3, metavar=("N", "WHAT", "W"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(run_one(int(args.one[0]), args.one[1], int(args.one[2]))))
        return
    print("diagnosis of a train and a validate record of N samples each (truth: creep + "
          "dynamics); each row a fresh process")
    print(f"{'N':>10} {'step':<34}{'wall [s]':>10}{'CPU [s]':>10}{'peak [MB]':>11}"
          f"{'VmPeak [MB]':>13}  load")
    rows = {}
    for n in args.samples:
        for what, w in [("baseline", 1)] + [("diagnosis", w) for w in args.workers]:
            load0 = os.getloadavg()[0]
            p = subprocess.run([sys.executable, __file__, "--one", str(n), what, str(w)],
                               capture_output=True, text=True)
            load = f"{load0:.1f}-{os.getloadavg()[0]:.1f}"
            if p.returncode != 0:
                print(f"{n:>10,} {what:<34} failed (exit {p.returncode}): "
                      f"{p.stderr.strip().splitlines()[-1:]}")
                continue
            r = rows[(n, what, w)] = json.loads(p.stdout.strip().splitlines()[-1])
            label = "plain PI least squares (baseline)" if what == "baseline" else \
                f"whole diagnosis, {w} thread{'s' * (w > 1)}"
            vm = r.get("address_mb")
            print(f"{n:>10,} {label:<34}{r['wall']:>10.2f}{r['cpu']:>10.2f}"
                  f"{r['peak_mb']:>11.0f}{'' if vm is None else f'{vm:>13.0f}'}  {load}")
            if what == "diagnosis":
                print(f"{'':>10} verdict {r['effects']}, shrink {r['shrink']!r}, "
                      f"{r['plays']} plays; {r['cpu'] / rows[(n, 'baseline', 1)]['cpu']:.0f} "
                      "baseline fits of CPU", flush=True)
        one, more = rows.get((n, "diagnosis", 1)), [rows.get((n, "diagnosis", w))
                                                    for w in dict.fromkeys(args.workers)
                                                    if w > 1]
        for r in (r for r in more if r is not None and one is not None):
            print(f"{'':>10} wall ratio (threads / one thread) {r['wall'] / one['wall']:.2f}, "
                  f"CPU ratio {r['cpu'] / one['cpu']:.2f}")
    diag = sorted((n, r) for (n, what, w), r in rows.items()
                  if what == "diagnosis" and w == args.workers[0])
    if len(diag) >= 2:
        (n0, a), (n1, b) = diag[0], diag[-1]
        print(f"growth {n0:,} -> {n1:,} samples ({n1 / n0:.0f}x): CPU x{b['cpu'] / a['cpu']:.1f}, "
              f"peak memory x{b['peak_mb'] / a['peak_mb']:.1f}")
    for w, r in ((k[2], rows[k]) for k in sorted(rows) if k[:2] == (1_000_000, "diagnosis")):
        print(f"goal 2 x 1M samples < 30 s and < 2 GB ({w} thread{'s' * (w > 1)}): wall "
              f"{r['wall']:.0f} s, CPU "
              f"{r['cpu']:.0f} s, peak {r['peak_mb'] / 1024:.2f} GB -> "
              f"{'met' if r['wall'] < 30 and r['peak_mb'] < 2048 else 'NOT met'}")


if __name__ == "__main__":
    main()
