"""Benchmark: start-up time of the ``pimodel`` command (goal: ``pimodel --help`` under 0.5 s).

Run: ``.venv/bin/python benchmarks/bench_cli.py [--repeat N]``. Each command runs as a fresh
process (the console script beside this Python); the median and the best of N runs are printed,
with ``python -c pass`` (the interpreter alone) and ``python -c "import numpy"`` as baselines.
``--help`` and ``--version`` load no NumPy (the package's names are imported on first use and
only the chosen subcommand registers its options), so they cost about the interpreter's start.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

GOAL_S = 0.5


def wall(argv: list[str], repeat: int) -> tuple[float, float]:
    """Median and best wall time [s] of ``repeat`` runs of ``argv``."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    exe = str(Path(sys.executable).with_name("pimodel"))
    rows = [("python -c pass", [sys.executable, "-c", "pass"]),
            ("python -c 'import numpy'", [sys.executable, "-c", "import numpy"]),
            ("pimodel --help", [exe, "--help"]),
            ("pimodel --version", [exe, "--version"]),
            ("pimodel identify --help", [exe, "identify", "--help"]),
            ("pimodel sweep --help", [exe, "sweep", "--help"])]
    print(f"{'command':28s} {'median s':>9s} {'best s':>9s}")
    for name, argv in rows:
        med, best = wall(argv, args.repeat)
        flag = "" if not name.endswith("--help") or name != "pimodel --help" else \
            ("  (goal < 0.5 s: met)" if med < GOAL_S else "  (goal < 0.5 s: NOT met)")
        print(f"{name:28s} {med:9.3f} {best:9.3f}{flag}")


if __name__ == "__main__":
    main()
