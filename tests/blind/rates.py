"""Run ``stage48``'s stages at a sample rate the blind cases do not use (200 Hz, 500 Hz, 2 kHz,
50 kHz) through ``pimodel.diagnose`` (one worker), one JSON line per case appended to ``OUT``.

For each seed and effect name, a third of the input kinds (``(kind + name + seed) % 3 == 0``);
the records are drawn as :func:`stage48.make_records` draws them, with this rate's duration.

Usage: python tests/blind/rates.py OUT FS NAMES SEEDS   (NAMES: clean,creep,delay,...)
"""

from __future__ import annotations

import json
import os
import sys
import time
import zlib

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

import stage48 as S  # noqa: E402
from run48 import judge  # noqa: E402

from pimodel import diagnose  # noqa: E402

DURATIONS = {200.0: (40, 60), 500.0: (20, 30), 2000.0: (5, 8), 50000.0: (1.0, 1.5)}  # s


def records(name: str, kind: str, fs: float, seed: int):
    """(train, validate, stage, effect RMS in noise sigmas) of one case."""
    effects = () if name == "clean" else tuple(name.split("+"))
    rng = np.random.default_rng([48, seed, zlib.crc32(f"{name}-{kind}".encode()), int(fs)])
    st = S.random_stage(rng, effects, fs)
    dur = rng.uniform(*DURATIONS[fs])
    lo, hi = (rng.uniform(0, 10), 100 - rng.uniform(0, 10)) if rng.uniform() < 0.5 \
        else (10.0, 90.0)
    st.v_bias = lo
    vt, vv = (S.excitation(kind, fs, dur, rng, lo, hi) for _ in range(2))
    tt = np.arange(vt.size) / fs
    tv = round((tt[-1] + rng.uniform(5, 60)) * fs) / fs + np.arange(vv.size) / fs
    rt, rv = st.record(tt, vt, rng), st.record(tv, vv, rng)
    bare = S.Stage(st.radii, st.weights, st.a0, st.gain, st.v_bias, st.noise)
    eff = np.sqrt(np.mean((st.clean(tv, vv, 0) - bare.clean(tv, vv, 0)) ** 2)) / st.noise
    return rt, rv, st, float(eff)


def main():
    out, fs = sys.argv[1], float(sys.argv[2])
    names, seeds = sys.argv[3].split(","), [int(s) for s in sys.argv[4].split(",")]
    for seed in seeds:
        for j, name in enumerate(names):
            for i, kind in enumerate(S.KINDS):
                if (i + j + seed) % 3:
                    continue
                rt, rv, st, eff = records(name, kind, fs, seed)
                t0 = time.process_time()
                v = diagnose([rt], [rv], workers=1).verdict
                row = {"effects": v["effects"], "floors": v["gap_after"] / v["noise_floor"],
                       "name": name, "kind": kind, "fs": fs, "seed": seed, "n": int(rt.t.size),
                       "effect_rms_sigma": eff, "cpu": time.process_time() - t0,
                       "sizes": repr(st.effects)}
                row["right"] = judge(() if name == "clean" else tuple(name.split("+")),
                                     row["effects"])
                with open(out, "a") as f:
                    f.write(json.dumps(row, default=str) + "\n")
                print(name, kind, fs, seed, row["effects"], row["right"],
                      round(row["floors"], 2), round(eff, 1), round(row["cpu"]), flush=True)


if __name__ == "__main__":
    main()
