"""Benchmark: a DiagnosedModel with a three-mode linear part on the C stream, and the inverse's
block, each against a plain baseline in the same run.

Run: ``.venv/bin/python benchmarks/bench_lti_stream.py [--samples N]``. Baselines: the same
model without its further elements on the C stream (what the further elements cost per sample)
and ``DiagnosedModel.simulate`` (NumPy); for the inverse, ``DiagnosedInverse.simulate`` (the
batch solver) against the block through ``control.input_output_response``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import control
import numpy as np

from pimodel.blocks import initial_state
from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.native_model import stream_simulate


def stage(n_plays: int = 80) -> DiagnosedModel:
    """80 signed plays, creep, a delay and a three-mode linear part (dt = 0.1 ms)."""
    rng = np.random.default_rng(0)
    radii = np.linspace(0.0, 1.0, n_plays)
    return DiagnosedModel(radii, rng.normal(0, 0.1, n_plays) + 1.0 / n_plays, 0.1, dt=1e-4,
                          effects=("dynamics", "creep", "delay"),
                          reference_weights=rng.normal(0, 0.1, n_plays) + 1.0 / n_plays,
                          params={"mode_hz": 400.0, "mode_damping": 0.1,
                                  "lti_elements": [["mode", 900.0, 0.05],
                                                   ["mode", 2000.0, 0.2]],
                                  "lti_gains": [0.25, -0.05],
                                  "creep_lag_gains": [0.03, 0.02],
                                  "creep_time_constants_s": [0.01, 0.3],
                                  "delay_samples": 2.5})


def timed(f, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=100_000)
    args = ap.parse_args()
    m = stage()
    plain = replace(m, params={k: v for k, v in m.params.items()
                               if k not in ("lti_elements", "lti_gains")})
    t = np.arange(args.samples) * m.dt
    v = 0.8 * np.sin(2 * np.pi * 5 * t) + 0.2 * np.sin(2 * np.pi * 61 * t)
    rng = 2 * m.radii[-1]
    n = args.samples
    s_el = timed(lambda: stream_simulate(m, v, input_range=rng))
    s_plain = timed(lambda: stream_simulate(plain, v, input_range=rng))
    s_np = timed(lambda: m.simulate(v, input_range=rng), repeat=1)
    diff = np.max(np.abs(stream_simulate(m, v, input_range=rng) - m.simulate(v)))
    print(f"C stream, 3 modes: {1e6 * s_el / n:.3f} us/sample; without the further elements "
          f"{1e6 * s_plain / n:.3f} us/sample (ratio {s_el / s_plain:.2f}); NumPy simulate "
          f"{1e6 * s_np / n:.2f} us/sample; max |stream - simulate| {diff:.1e}")
    k = min(n, 3000)
    y_d = m.simulate(np.where(t[:k] < 0.002, 0.0, v[:k] - v[20]))
    inv = m.inverse()
    blk = inv.block(reference_range=float(np.ptp(inv.prefilter(y_d))))
    s_batch = timed(lambda: inv.simulate(y_d), repeat=1)
    s_blk = timed(lambda: control.input_output_response(blk, t[:k], y_d,
                                                        initial_state=initial_state(blk)),
                  repeat=1)
    print(f"inverse, {k} samples: batch simulate {1e6 * s_batch / k:.0f} us/sample, block "
          f"(input_output_response) {1e6 * s_blk / k:.0f} us/sample (ratio "
          f"{s_blk / s_batch:.2f}), latency {blk.latency} samples")


if __name__ == "__main__":
    main()
