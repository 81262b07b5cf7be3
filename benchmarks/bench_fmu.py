"""Benchmark: PIHysteresis FMU cost per sample from a small C host (dlopen, setReal, doStep,
getReal per sample) and steps per second through fmpy (FMU2Slave loop in Python), n = 10 plays.

Run: ``.venv/bin/python benchmarks/bench_fmu.py``. Goal (issue 29): under 20 ns per doStep in
the C host (issue 5: 50 ns). The Python loop shows what a Python master costs on top.
"""

from __future__ import annotations

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
        N = 5_000_000
        out = subprocess.run([str(host), str(tmp / "binaries/linux64/PIHysteresis.so"),
                              guid("PIHysteresis"), str(N), str(n)], capture_output=True,
                             text=True, check=True)
        ns_c = float(out.stdout.split()[0])
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
    print(f"C host (dlopen; setReal + doStep + getReal per sample): {ns_c:.1f} ns/sample "
          f"({1e3 / ns_c:.1f} M steps/s); goal < 20 ns -> {'met' if ns_c < 20 else 'NOT met'}")
    print(f"fmpy FMU2Slave loop in Python: {M / t_py:,.0f} steps/s "
          f"({t_py / M * 1e6:.1f} us/step), {t_py / M * 1e9 / ns_c:.0f}x the C host")


if __name__ == "__main__":
    main()
