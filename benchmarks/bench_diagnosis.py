"""Benchmark: the sim-to-real gap diagnosis on two 100k-sample records.

Run: ``.venv/bin/python benchmarks/bench_diagnosis.py [--samples N]``. Goal (issues 6, 16): a
diagnosis of a 100k-sample train and a 100k-sample validate record in under 30 s. Baseline in
the same run: one plain least-squares fit of a PI model (``np.linalg.lstsq`` on the 20-play
design matrix of the train record), so the ratio says how many such fits a whole diagnosis
(grid refinement, noise floor, breakdown, six candidates, combinations) costs.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from pimodel.diagnosis import diagnose
from pimodel.operators.pi import PIOperator
from pimodel.records import Record
from pimodel.stages.pi_stage import excitation, random_truth


def long_record(kind: str, n: int, truth, seed: int) -> Record:
    """Excitations of ``kind`` (new random steps each) joined to ``n`` samples at 10 kHz."""
    parts, total, s = [], 0, seed
    while total < n:
        parts.append(excitation(kind, seed=s)[1])
        total += parts[-1].size
        s += 1
    v = np.concatenate(parts)[:n]
    t = np.arange(n) * 1e-4
    return truth.record(t, v, seed, kind)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=100_000)
    args = ap.parse_args()
    truth = random_truth(["creep", "dynamics"], 0)
    tr = long_record("train", args.samples, truth, 1)
    va = long_record("validate", args.samples, truth, 100)
    t0, c0 = time.perf_counter(), time.process_time()
    rep = diagnose([tr], [va])
    t_diag, c_diag = time.perf_counter() - t0, time.process_time() - c0

    radii = np.linspace(0, np.ptp(tr.v) / 2, 20)
    t0 = time.perf_counter()
    A = np.column_stack((PIOperator(np.ones(20), radii).play_outputs(tr.v), np.ones(tr.v.size)))
    np.linalg.lstsq(A, tr.y, rcond=None)
    t_base = time.perf_counter() - t0
    print(f"diagnosis of a {args.samples:,}-sample train and a {args.samples:,}-sample validate "
          "record (truth: creep + dynamics)")
    print(f"{'step':<44}{'time [s]':>10}")
    print(f"{'baseline: one nominal PI least-squares fit':<44}{t_base:>10.3f}")
    print(f"{'whole diagnosis':<44}{t_diag:>10.3f}")
    print(f"{'whole diagnosis, process CPU time':<44}{c_diag:>10.3f}  (less sensitive to the "
          "load of a shared machine)")
    print(f"nominal grid {len(rep.nominal['model']['radii'])} plays; noise floor "
          f"{rep.verdict['noise_floor']:.4f} um ({rep.verdict['noise_floor_method']})")
    print(f"ratio {t_diag / t_base:.0f} plain fits; verdict {rep.verdict['effects']}, "
          f"shrink {rep.verdict['shrink']:.2f}; goal < 30 s -> "
          f"{'met' if t_diag < 30 else 'NOT met'}")


if __name__ == "__main__":
    main()
