"""Benchmark: a diagnosed model's feedforward on the C core (``NativeInverse``) against the Python
stream of ``DiagnosedInverse.block()`` (``reference_inverse._InverseStream``), the baseline, in the
same run, with the largest difference of their outputs.

Run: ``.venv/bin/python benchmarks/bench_inverse_native.py [--samples N]``. Models: 80 signed
plays (a diagnosis' grid) with creep and a delay, with the asymmetry (a cubic root per segment)
and with a radius-family rate (the nested rate-free solve), each with a mode's prefilter.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.native_inverse import NativeInverse
from pimodel.diagnosis.reference_inverse import _InverseStream

EFFECTS = {
    "creep+delay": ("dynamics", "creep", "delay"),
    "+asymmetry": ("dynamics", "creep", "delay", "asymmetry"),
    "+rate": ("dynamics", "creep", "delay", "rate"),
}


def stage(effects, n_plays: int = 80) -> DiagnosedModel:
    rng = np.random.default_rng(0)
    radii = np.linspace(0.0, 1.0, n_plays)
    w = np.abs(rng.normal(0, 0.1, n_plays)) / n_plays + 1.0 / n_plays
    return DiagnosedModel(radii, w, 0.1, dt=1e-4, effects=effects, reference_weights=w,
                          params={"mode_hz": 400.0, "mode_damping": 0.1,
                                  "creep_lag_gains": [0.03, 0.02],
                                  "creep_time_constants_s": [0.01, 0.3], "delay_samples": 2.5,
                                  "asymmetry_quadratic": 0.03, "asymmetry_cubic": 0.01,
                                  "center": 0.5, "half_range": 1.0, "rate_gains": [0.05, 0.02],
                                  "rate_family": "radius", "rate_time_constant_s": 0.0,
                                  "rate_scale": 50.0})


def timed(f) -> float:
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def python_stream(m: DiagnosedModel, y_d: np.ndarray) -> np.ndarray:
    """The baseline: the Python stream of ``DiagnosedInverse.block()``, sample by sample."""
    stream = _InverseStream(m, None, None)
    x = np.zeros(stream.size)
    return np.array([stream.step(x, float(y)) for y in y_d])


def compare(label: str, m: DiagnosedModel, v: np.ndarray) -> None:
    y_d = m.simulate(v, input_range=2.0)
    native = NativeInverse(m.inverse())
    out = {}
    s_py = timed(lambda: out.__setitem__("py", python_stream(m, y_d)))
    s_c = min(timed(lambda: out.__setitem__("c", native.run(y_d))) for _ in range(5))
    n = y_d.size
    diff = float(np.max(np.abs(out["py"] - out["c"])))
    print(f"{label:12s} Python stream {1e6 * s_py / n:8.0f} us/sample, C "
          f"{1e6 * s_c / n:6.2f} us/sample, ratio {s_py / s_c:6.0f}x, max |C - Python| "
          f"{diff:.1e}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=2000)
    args = ap.parse_args()
    t = np.arange(args.samples) * 1e-4
    v = 0.8 * np.sin(2 * np.pi * 5 * t) + 0.2 * np.sin(2 * np.pi * 61 * t)
    v[:20] = 0.0
    v[20:] -= v[20]
    for label, effects in EFFECTS.items():
        compare(label, stage(effects), v)


if __name__ == "__main__":
    main()
