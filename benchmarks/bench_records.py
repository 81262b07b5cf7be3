"""Benchmark: loading a long record from CSV and from ``.npz``, its time and peak memory (RSS).

Run: ``.venv/bin/python benchmarks/bench_records.py [--rows N]`` (default 10 M rows of
``t,v,y``, about 0.5 GB of text, written once to a temporary folder, and the same columns as
an ``.npz``). Each load runs in a fresh process, whose peak resident memory (``ru_maxrss``) is
compared with the imports alone and with the size of the record's columns (N x 3 x 8 bytes):
the CSV reader parses blocks of 8 MiB of bytes with ``numpy.loadtxt`` into preallocated float
columns (a file with blank lines or stray fields falls back to the line reader), the ``.npz``
reader reads the columns one by one; neither holds a Python list of every row. Wall and
process CPU time are both shown (CPU time is less sensitive to the load of a shared machine).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

PROBE = """
import resource, sys, time
import numpy as np
from pimodel.records import load_record
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0, c0 = time.perf_counter(), time.process_time()
rec = load_record(sys.argv[1])
dt, cpu = time.perf_counter() - t0, time.process_time() - c0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(len(rec), dt, cpu, base * 1024, peak * 1024)
"""

TO_NPZ = """
import sys
from pimodel.records import load_record, save_record
save_record(load_record(sys.argv[1]), sys.argv[2])
"""


def write_csv(path: Path, rows: int, block: int = 1_000_000) -> None:
    rng = np.random.default_rng(0)
    with path.open("w") as fh:
        fh.write("t,v,y\n")
        for start in range(0, rows, block):
            k = np.arange(start, min(start + block, rows))
            v = np.sin(2 * np.pi * k / 20000) * 2.0
            y = 8.0 * v + rng.normal(0, 0.01, k.size)
            np.savetxt(fh, np.column_stack([k * 5e-3, v, y]), delimiter=",", fmt="%.10g")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10_000_000)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "long.csv"
        t0 = time.perf_counter()
        write_csv(path, args.rows)
        print(f"wrote {args.rows} rows ({path.stat().st_size / 2**20:.0f} MiB) in "
              f"{time.perf_counter() - t0:.1f} s")
        report(path)
        npz = Path(tmp) / "long.npz"  # written by a child: Linux keeps ru_maxrss across exec,
        subprocess.run([sys.executable, "-c", TO_NPZ, str(path), str(npz)], check=True)
        report(npz)  # so the parent never holds the columns


def report(path: Path) -> None:
    """Load ``path`` in a fresh process and print its time and memory."""
    out = subprocess.run([sys.executable, "-c", PROBE, str(path)], check=True,
                         capture_output=True, text=True).stdout.split()
    n, seconds, cpu, base, peak = int(out[0]), float(out[1]), float(out[2]), int(out[3]), \
        int(out[4])
    columns = n * 3 * 8
    print(f"load_record {path.suffix}: {n} rows in {seconds:.1f} s wall, {cpu:.1f} s CPU "
          f"({n / seconds / 1e6:.2f} M rows/s)")
    print(f"  peak RSS {peak / 2**20:.0f} MiB; after imports {base / 2**20:.0f} MiB; "
          f"added {(peak - base) / 2**20:.0f} MiB = {(peak - base) / columns:.2f} x the "
          f"record's three float64 columns ({columns / 2**20:.0f} MiB)")

if __name__ == "__main__":
    main()
