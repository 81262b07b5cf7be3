"""Benchmark: joint weight-and-radius estimator against the radius-only estimator (C core) on
the same record, in one run.

Run: ``.venv/bin/python benchmarks/bench_joint.py [--seconds S]``. Record: the paper's five-play
sinusoid at 10 kHz, SNR 20 dB, in memory. The joint estimator's per-sample work is the C
reversal scanner and per-branch NumPy binning; its refits (every ``--refit-every`` branches)
are timed separately.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from pimodel import JointEstimator, PIOperator, RadiusEstimator
from pimodel.signals import add_noise_snr, sinusoid

P = np.array([0.3, 0.5, 0.8, 0.3, 0.2])
R = np.array([0.4, 1.0, 1.5, 2.0, 3.6])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=1000.0, help="record length [s] at 10 kHz")
    ap.add_argument("--refit-every", type=int, default=500)
    args = ap.parse_args()
    _, v = sinusoid(30, 1, fs=10_000, duration=args.seconds)
    y = add_noise_snr(PIOperator(P, R).simulate(v), 20, np.random.default_rng(0))

    t0 = time.perf_counter()
    RadiusEstimator(P, dt=1e-4, gains=1.0, initial_radii=[1, 2, 3, 4, 5], guard=0.2,
                    slope_window=0).run(v, y)
    t_radius = time.perf_counter() - t0

    est = JointEstimator(5, refit_every=args.refit_every)
    fit_time = 0.0
    update = est._update

    def timed_update(k):
        nonlocal fit_time
        t = time.perf_counter()
        update(k)
        fit_time += time.perf_counter() - t

    est._update = timed_update
    t0 = time.perf_counter()
    est.run(v, y)
    res = est.finish()
    t_joint = time.perf_counter() - t0

    n = v.size
    print(f"five plays, N = {n:,} samples, {res.update_index.size} joint updates")
    print(f"{'estimator':<40}{'time [s]':>10}{'Msamples/s':>12}")
    print(f"{'radius law, C core (baseline)':<40}{t_radius:>10.2f}{n / t_radius / 1e6:>12.1f}")
    print(f"{'joint, total':<40}{t_joint:>10.2f}{n / t_joint / 1e6:>12.1f}")
    print(f"{'joint, without the refits':<40}{t_joint - fit_time:>10.2f}"
          f"{n / (t_joint - fit_time) / 1e6:>12.1f}")
    print(f"joint / radius-law time: {t_joint / t_radius:.2f}; "
          f"per refit {1e3 * fit_time / max(res.update_index.size, 1):.0f} ms")


if __name__ == "__main__":
    main()
