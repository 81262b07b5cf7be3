"""Benchmark: compiled closed loop (C core) against python-control's input_output_response on
the same interconnection (PI plant + second-order mode + exact-inverse feedforward + PID).

Run: ``.venv/bin/python benchmarks/bench_loops.py``. Goal (issue 4): >= 100x.
"""

from __future__ import annotations

import time

import numpy as np

from pimodel.experiments.compensation import STAGE
from pimodel.loops.actuators import stage_dynamics
from pimodel.loops.compiled import PID, loop_system, run_loop
from pimodel.loops.simulation import simulate
from pimodel.signals import sinusoid


def main() -> None:
    dt = 1e-4
    G = stage_dynamics(dt, fn_hz=1000, damping=0.05)
    pid = PID(0.0, 20.0)
    t, yd = sinusoid(8, 10, fs=1 / dt, duration=0.3)
    sys = loop_system(STAGE, dt, dynamics=G, feedforward=STAGE, pid=pid)
    t0 = time.perf_counter()
    ref = simulate(sys, t, {"y_d": yd})
    t_pc = time.perf_counter() - t0
    t_long, yd_long = sinusoid(8, 10, fs=1 / dt, duration=100.0)
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        run_loop(yd_long, STAGE, dt, dynamics=G, feedforward=STAGE, pid=pid)
        best = min(best, time.perf_counter() - t0)
    fast = run_loop(yd, STAGE, dt, dynamics=G, feedforward=STAGE, pid=pid)
    rate_pc, rate_c = t.size / t_pc, t_long.size / best
    print("loop: PI plant (n = 4) + 1 kHz mode (2 states) + exact-inverse feedforward + PID")
    print(f"{'path':<36}{'samples':>10}{'steps/s':>14}")
    print(f"{'python-control input_output_response':<36}{t.size:>10}{rate_pc:>14,.0f}")
    print(f"{'compiled run_loop (C core)':<36}{t_long.size:>10}{rate_c:>14,.0f}")
    print(f"ratio {rate_c / rate_pc:,.0f}x (goal >= 100x); max |difference| on the common record "
          f"{np.max(np.abs(fast.y - ref['y'])):.1e}")


if __name__ == "__main__":
    main()
