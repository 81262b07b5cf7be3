"""The blind generator's ``bandwidth`` cases (bw49; docs/diagnosis.md, "An amplifier's
bandwidth of 20-120 Hz"): one JSON line per case and variant appended to ``OUT``.

Variants: ``as-recorded`` (the records of ``stage48``); ``exact`` and ``zoh`` (the input
replaced by the truth's filter, ``u[k] = a u[k-1] + (1 - a) v[k]``, or by the ZOH low-pass at
the same corner: the nominal's validate RMS is then the Wiener oracle's); ``rest`` (the truth's
plays at rest at the first filtered input instead of stepped from the park level).

Usage: python tests/blind/bw49.py OUT SEEDS [VARIANTS]
"""

from __future__ import annotations

import json
import os
import sys
import time

import numpy as np
from scipy import signal

sys.path.insert(0, os.path.dirname(__file__))

import run48 as R  # noqa: E402
import stage48 as S  # noqa: E402

from pimodel import Record, diagnose  # noqa: E402
from pimodel.diagnosis.wiener import prefilter  # noqa: E402

_PLAYS = S.Stage._plays


def _rest_plays(self, u, fs):
    vb, self.v_bias = self.v_bias, u[0]
    try:
        return _PLAYS(self, u, fs)
    finally:
        self.v_bias = vb


def _exact(v, fc, fs):
    a = np.exp(-2 * np.pi * fc / fs)
    return signal.lfilter([1 - a], [1, -a], v, zi=[a * v[0]])[0]


def _records(case, variant):
    S.Stage._plays = _rest_plays if variant == "rest" else _PLAYS
    try:
        rt, rv, st, info = S.make_records(case)
    finally:
        S.Stage._plays = _PLAYS
    fc = st.effects["bandwidth"]
    if variant == "exact":
        rt, rv = (Record(r.t, _exact(r.v, fc, case.fs), r.y) for r in (rt, rv))
    elif variant == "zoh":
        els = [("lowpass", 1 / (2 * np.pi * fc))]
        rt, rv = (Record(r.t, prefilter(r.v, els, 1 / case.fs), r.y) for r in (rt, rv))
    return rt, rv, st, info


def main():
    out, seeds = sys.argv[1], [int(s) for s in sys.argv[2].split(",")]
    variants = sys.argv[3].split(",") if len(sys.argv) > 3 else ["as-recorded"]
    for case in R.cases(seeds):
        if case.name != "bandwidth":
            continue
        for var in variants:
            rt, rv, st, info = _records(case, var)
            t0 = time.process_time()
            j = diagnose([rt], [rv], workers=1).to_json()
            v, floor = j["verdict"], j["verdict"]["noise_floor"]
            dyn = next(c["params"] for c in j["candidates"] if c["effect"] == "dynamics")
            start = [r for r in j["where"]["regions"] if r["region"].startswith("start-up")]
            row = dict(seed=case.seed, kind=case.kind, fs=case.fs, bandwidth_hz=st.effects[
                "bandwidth"], variant=var, effects=v["effects"],
                nominal_floors=v["gap_before"] / floor,
                after_floors=(v.get("gap_after") or np.nan) / floor,
                candidates_floors={c["effect"]: c["validate"]["rms"] / floor
                                   for c in j["candidates"]},
                dynamics_position=dyn.get("dynamics_position"),
                lowpass_hz=dyn.get("lowpass_hz"), wiener_elements=dyn.get("wiener_elements"),
                dynamics_modes=dyn.get("dynamics_modes"),
                positions_tried=dyn.get("dynamics_positions_tried"),
                startup_energy_share=start[0]["energy_share"] if start else None,
                park_v=st.v_bias, v0=float(rt.v[0]), effect_sigma=info["effect_rms_sigma"],
                cpu=time.process_time() - t0)
            with open(out, "a") as f:
                f.write(json.dumps(row, default=str) + "\n")
            print(case.seed, case.kind, case.fs, round(row["bandwidth_hz"]), var, v["effects"],
                  round(row["nominal_floors"], 1), round(row["after_floors"], 1), flush=True)


if __name__ == "__main__":
    main()
