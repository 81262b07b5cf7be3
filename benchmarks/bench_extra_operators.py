"""Benchmark and round-trip measurement: generalized, rate-dependent and creep operators.

Run: ``.venv/bin/python benchmarks/bench_extra_operators.py [--samples N] [--cases K]``.
Goals (issue 19): each forward operator within 5x the plain PI operator's time per sample
(baseline: ``PIOperator.simulate`` in the same run, n = 8 plays), and the round trips
``inverse().simulate(op.simulate(v))`` within 1e-9 of ``v`` over K random operators and inputs
(rate-dependent: with rate_sensitivity < 1, the documented condition). Timings on a shared
machine are inflated; the ratios are what counts.
"""

from __future__ import annotations

import argparse

import numpy as np
from bench_operator import best_time  # the benchmarks folder is on sys.path when run

from pimodel import PIOperator
from pimodel.operators.asymmetric import AsymmetricPI
from pimodel.operators.creep import CreepOperator
from pimodel.operators.envelopes import Envelope
from pimodel.operators.generalized import GeneralizedPI
from pimodel.operators.rate_dependent import RateDependentPI


def random_operators(rng, n: int = 8):
    p = rng.uniform(0.05, 1, n)
    r = np.concatenate(([0.0], np.sort(rng.uniform(0, 2, n - 1))))
    gpi = GeneralizedPI(p, r, input_envelope=Envelope.tanh(rng.uniform(3, 6), rng.uniform(0.1, 0.3),
                                                           rng.uniform(-0.5, 0.5)),
                        output_envelope=Envelope.poly2(0.0, 1.0, rng.uniform(-0.02, 0.02)))
    probe = RateDependentPI(p, r, rate_gain=1.0, dt=1e-4)
    rdpi = RateDependentPI(p, r, rate_gain=rng.uniform(0.1, 0.9) / probe.rate_sensitivity,
                           dt=1e-4)
    creep = CreepOperator(rng.uniform(0.005, 0.03, 4), 10.0 ** np.arange(-2, 2), dt=1e-4)
    asym = AsymmetricPI(rng.uniform(0.1, 1), p, r, ascending=(1.0, 0.0),
                        descending=(rng.uniform(0.7, 1.5), rng.uniform(-0.3, 0.3)),
                        shape=Envelope.tanh(rng.uniform(3, 6), rng.uniform(0.1, 0.3)))
    return gpi, rdpi, creep, asym


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--cases", type=int, default=20)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    N = args.samples
    tt = np.arange(N) * 1e-4
    v = 3 * np.sin(2 * np.pi * 5 * tt) * np.sin(2 * np.pi * 0.3 * tt) + rng.normal(0, 0.02, N)
    gpi, rdpi, creep, asym = random_operators(rng)
    pi = PIOperator(gpi.weights, gpi.radii)
    t_pi = best_time(lambda: pi.simulate(v), repeat=3)
    rows = [("PIOperator (baseline)", t_pi)]
    for name, op in (("GeneralizedPI", gpi), ("RateDependentPI", rdpi), ("CreepOperator", creep),
                     ("AsymmetricPI", asym)):
        y = op.simulate(v)
        inv = op.inverse()
        rows.append((name, best_time(lambda op=op: op.simulate(v), repeat=3)))
        rows.append(("  inverse", best_time(lambda inv=inv, y=y: inv.simulate(y), repeat=3)))
    print(f"forward and inverse runs, n = 8 plays / 4 lags, N = {N:,} samples (best of 3)")
    print(f"{'operator':<26}{'time [s]':>10}{'ns/sample':>12}{'x PI':>8}")
    for name, t in rows:
        print(f"{name:<26}{t:>10.4f}{t / N * 1e9:>12.1f}{t / t_pi:>8.2f}")
    speed_ok = all(t / t_pi <= 5 for name, t in rows[1:] if not name.startswith("  "))

    worst = {"GeneralizedPI": 0.0, "RateDependentPI": 0.0, "CreepOperator": 0.0,
             "AsymmetricPI": 0.0}
    for _ in range(args.cases):
        ops = random_operators(rng)
        w = np.cumsum(rng.normal(0, 0.05, 20_000))
        w = 4 * w / max(1.0, np.max(np.abs(w)))
        for op in ops:
            err = float(np.max(np.abs(op.inverse().simulate(op.simulate(w)) - w)))
            worst[type(op).__name__] = max(worst[type(op).__name__], err)
    print(f"round trips over {args.cases} random operators, 20,000-sample random walks:")
    for name, err in worst.items():
        print(f"  {name:<18} max |v - inverse(op(v))| = {err:.2e}")
    trip_ok = max(worst.values()) <= 1e-9
    print(f"goal: forward <= 5x PI and round trips <= 1e-9 -> "
          f"{'met' if speed_ok and trip_ok else 'NOT met'}")


if __name__ == "__main__":
    main()
