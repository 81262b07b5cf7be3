"""Benchmark: PIHysteresis FMU cost per sample from a small C host (dlopen, setReal, doStep,
getReal per sample) and steps per second through fmpy (FMU2Slave loop in Python), n = 10 plays.

Run: ``.venv/bin/python benchmarks/bench_fmu.py``. Goal (issue 29): under 20 ns CPU per
sample (setReal + doStep + getReal) in the C host (issue 5: 50 ns). The C host runs REPEATS
times, interleaved run by run with the same loop calling only the C core's ``pim_pi_step``
(the floor that no FMU glue can go below); the medians of both loops' wall-clock and CPU ns
per sample are printed with the machine's load average (a loaded machine inflates the wall
clock most, so the verdict is on CPU time) and the ratio of the two. With valgrind installed
it also prints both loops' instructions per sample (callgrind: the count of 2N samples minus
that of N, so the set-up cancels), which a loaded machine does not change. The Python loop
shows what a Python master costs on top.
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

from pimodel.fmu import build_fmus
from pimodel.fmu.build import find_compiler, fmi_headers, guid
from pimodel.fmu.spec import config_h
from pimodel.fmu.unit import FMUUnit

HERE = Path(__file__).resolve().parent
REPEATS = 7

# The host's loop and input without the FMU: the C core's play step alone.
FLOOR_C = r"""
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "pim_core.h"
static double now(clockid_t id)
{
    struct timespec t;
    clock_gettime(id, &t);
    return t.tv_sec * 1e9 + t.tv_nsec;
}
int main(int argc, char **argv)
{
    const long N = atol(argv[1]);
    const int n = atoi(argv[2]);
    double p[64], r[64], z[64] = {0}, acc = 0.0;
    for (int i = 0; i < n; ++i) { p[i] = 1.0 / (i + 1); r[i] = 0.2 * i; }
    const double w0 = now(CLOCK_MONOTONIC), c0 = now(CLOCK_PROCESS_CPUTIME_ID);
    for (long k = 0; k < N; ++k) {
        double v = 3.0 * ((k % 2000) < 1000 ? (k % 1000) / 1000.0 : 1.0 - (k % 1000) / 1000.0);
        acc += pim_pi_step((size_t)n, p, r, z, v);
    }
    const double w1 = now(CLOCK_MONOTONIC), c1 = now(CLOCK_PROCESS_CPUTIME_ID);
    printf("%.2f %.2f %g\n", (w1 - w0) / N, (c1 - c0) / N, acc);
    return 0;
}
"""


def _medians(*cmds: list[str]) -> list[tuple[float, float]]:
    """Median wall and CPU ns per sample of each program (printing both) over REPEATS runs,
    the programs interleaved run by run, so that a change in the machine's speed during the
    runs moves them alike."""
    runs: list[list[list[str]]] = [[] for _ in cmds]
    for _ in range(REPEATS):
        for out, cmd in zip(runs, cmds, strict=True):
            out.append(subprocess.run(cmd, capture_output=True, text=True,
                                      check=True).stdout.split())
    return [(statistics.median(float(r[0]) for r in out),
             statistics.median(float(r[1]) for r in out)) for out in runs]


def _instructions(cmd: list[str], n_samples: int = 100_000) -> float | None:
    """Instructions per sample of a program whose second-last argument is N (callgrind), or None
    without valgrind."""
    if shutil.which("valgrind") is None:
        return None

    def total(N: int) -> int:
        run = [*cmd]
        run[-2] = str(N)
        out = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                              *run], capture_output=True, text=True, check=True).stderr
        return int(next(line for line in out.splitlines() if "Collected" in line)
                   .split()[-1])

    return (total(2 * n_samples) - total(n_samples)) / n_samples


def main() -> None:
    n = 10
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (fmu,) = build_fmus(tmp, ["PIHysteresis"])
        with zipfile.ZipFile(fmu) as z:
            z.extract("binaries/linux64/PIHysteresis.so", tmp)
        host = tmp / "fmu_host"
        (tmp / "config.h").write_text(config_h("PIHysteresis"))  # the value references
        subprocess.run([find_compiler(), "-O2", "-std=c99", "-D_POSIX_C_SOURCE=200809L",
                        "-I", str(fmi_headers()), "-I", str(tmp), str(HERE / "fmu_host.c"),
                        "-o", str(host),
                        "-ldl"], check=True)
        core = HERE.parent / "fmu" / "src" / "core"
        (tmp / "floor.c").write_text(FLOOR_C)
        floor = tmp / "floor"
        subprocess.run([find_compiler(), "-O3", "-std=c99", "-D_POSIX_C_SOURCE=200809L", "-I",
                        str(core), str(tmp / "floor.c"), str(core / "pim_pi.c"), "-o",
                        str(floor), "-lm"], check=True)
        N = 5_000_000
        load = os.getloadavg()[0]
        (ns_c, cpu_c), (ns_f, cpu_f) = _medians(
            [str(host), str(tmp / "binaries/linux64/PIHysteresis.so"), guid("PIHysteresis"),
             str(N), str(n)],
            [str(floor), str(N), str(n)])
        ir_c = _instructions([str(host), str(tmp / "binaries/linux64/PIHysteresis.so"),
                              guid("PIHysteresis"), str(N), str(n)])
        ir_f = _instructions([str(floor), str(N), str(n)])
        start = {"Ts": 1e-4, "n": n, **{f"p[{i + 1}]": 1.0 / (i + 1) for i in range(n)},
                 **{f"r[{i + 1}]": 0.2 * i for i in range(n)}}
        unit = FMUUnit(fmu, start)
        M = 20_000
        v = 3 * np.sin(np.linspace(0, 20, M))
        t0 = time.perf_counter()
        for x in v:
            unit.set({"v": x})
            unit.step(1e-4)
            unit.get(["y"])
        t_py = time.perf_counter() - t0
        unit.close()
    print(f"PIHysteresis FMU, n = {n} plays")
    print(f"load average {load:.1f} on {os.cpu_count()} CPUs; medians of {REPEATS} runs")
    print(f"C host (dlopen; setReal + doStep + getReal per sample): {ns_c:.1f} ns/sample wall, "
          f"{cpu_c:.1f} ns CPU ({1e3 / cpu_c:.1f} M steps/s); goal < 20 ns CPU -> "
          f"{'met' if cpu_c < 20 else 'NOT met'}")
    print(f"the core's pim_pi_step alone in the same loop: {ns_f:.1f} ns wall, {cpu_f:.1f} ns "
          f"CPU (the FMU glue adds {cpu_c - cpu_f:.1f} ns CPU; FMU / core {cpu_c / cpu_f:.2f})")
    if ir_c is not None and ir_f is not None:
        print(f"instructions per sample (callgrind, with the host's loop): FMU {ir_c:.0f}, "
              f"the core alone {ir_f:.0f}")
    print(f"fmpy FMU2Slave loop in Python: {M / t_py:,.0f} steps/s "
          f"({t_py / M * 1e6:.1f} us/step), {t_py / M * 1e9 / ns_c:.0f}x the C host")


if __name__ == "__main__":
    main()
