"""Benchmark: compiled PI operator (C core) against a plain per-sample NumPy loop.

Run: ``.venv/bin/python benchmarks/bench_operator.py [--samples N] [--plays n]``.
Goal (issue 2): at most 3 ns per play-sample on one core and >= 100x the NumPy loop, for
n = 10 plays and N = 1e6 samples. The NumPy loop is timed on a slice and scaled (it is slow).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from pimodel import PIOperator
from pimodel.reference.operators import pi_reference


def best_time(fn, repeat: int = 5) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--plays", type=int, default=10)
    ap.add_argument("--numpy-samples", type=int, default=50_000,
                    help="samples timed for the NumPy loop (scaled to --samples)")
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    n, N = args.plays, args.samples
    op = PIOperator(rng.uniform(0.1, 1, n), np.linspace(0, 2, n))
    v = 3 * np.sin(np.linspace(0, 200 * np.pi, N)) + rng.normal(0, 0.05, N)

    t_c = best_time(lambda: op.simulate(v))
    vs = v[: args.numpy_samples]
    t_np = best_time(lambda: pi_reference(vs, op.weights, op.radii), repeat=2) * N / vs.size
    ns_c = t_c / (N * n) * 1e9
    ns_np = t_np / (N * n) * 1e9
    print(f"PI operator, n = {n} plays, N = {N:,} samples (best of runs)")
    print(f"{'implementation':<28}{'time [s]':>12}{'ns/play-sample':>18}{'Msamples/s':>14}")
    print(f"{'C core (PIOperator)':<28}{t_c:>12.4f}{ns_c:>18.3f}{N / t_c / 1e6:>14.1f}")
    print(f"{'NumPy per-sample loop':<28}{t_np:>12.4f}{ns_np:>18.3f}{N / t_np / 1e6:>14.3f}")
    print(f"speed-up: {t_np / t_c:.0f}x   goal: <= 3 ns/play-sample and >= 100x -> "
          f"{'met' if ns_c <= 3 and t_np / t_c >= 100 else 'NOT met'}")


if __name__ == "__main__":
    main()
