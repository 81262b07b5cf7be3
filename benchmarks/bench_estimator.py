"""Benchmark: batch radius estimator (C core) against the NumPy per-sample reference.

Run: ``.venv/bin/python benchmarks/bench_estimator.py [--samples N]``. Goal (issues 3, 15): the
batch estimator at >= 10 million samples per second for n = 5 plays (the paper's simulation
case), for the default law (``law="data"``, regime from the measured branch profile); the
paper's law is timed in the same run for comparison.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from pimodel import PIOperator, RadiusEstimator
from pimodel.reference.radius_estimator import estimate_radii_reference
from pimodel.signals import add_noise_snr, sinusoid

P = np.array([0.3, 0.5, 0.8, 0.3, 0.2])
R = np.array([0.4, 1.0, 1.5, 2.0, 3.6])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=2_000_000)
    ap.add_argument("--reference-samples", type=int, default=20_000)
    args = ap.parse_args()
    t, v = sinusoid(30, 1, fs=1000, duration=args.samples / 1000)
    y = add_noise_snr(PIOperator(P, R).simulate(v), 20, np.random.default_rng(0))
    kw = dict(dt=1e-3, gains=10.0, initial_radii=[1, 2, 3, 4, 5], guard=0.2, threshold=0.0,
              slope_window=8)
    rates = {}
    for law in ("data", "paper"):
        best = np.inf
        for _ in range(3):
            est = RadiusEstimator(P, law=law, **kw)
            t0 = time.perf_counter()
            est.run(v, y)  # the C batch loop (estimate_radii adds the health report)
            best = min(best, time.perf_counter() - t0)
        rates[law] = (best, v.size / best)
    m = args.reference_samples
    t0 = time.perf_counter()
    estimate_radii_reference(v[:m], y[:m], P, **kw)
    t_ref = (time.perf_counter() - t0) * v.size / m
    rate_ref = v.size / t_ref
    print(f"radius estimator, n = 5 plays, N = {v.size:,} samples (history kept)")
    print(f"{'implementation':<36}{'time [s]':>10}{'Msamples/s':>14}")
    for law, (best, rate) in rates.items():
        name = f"C core run, law={law!r}"
        print(f"{name:<36}{best:>10.3f}{rate / 1e6:>14.2f}")
    print(f"{'NumPy per-sample reference (data)':<36}{t_ref:>10.1f}{rate_ref / 1e6:>14.4f}")
    rate_c = rates["data"][1]
    print(f"speed-up {rate_c / rate_ref:.0f}x; goal >= 10 Msamples/s (law='data') -> "
          f"{'met' if rate_c >= 10e6 else 'NOT met'}")


if __name__ == "__main__":
    main()
