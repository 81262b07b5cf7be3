"""Run the blind cases of ``stage48`` through ``pimodel.diagnose`` (one worker), one JSON line
per case appended to ``OUT``; cases already in ``OUT`` are skipped (resumable).

Usage: python tests/blind/run48.py OUT SEEDS [FILTER]
"""

from __future__ import annotations

import ctypes
import json
import os
import signal as _signal
import sys
import time

sys.path.insert(0, os.path.dirname(__file__))

import stage48 as S  # noqa: E402

from pimodel import diagnose  # noqa: E402

RATES = (1000.0, 5000.0, 20000.0)


def cases(seeds):
    out = []
    for seed in seeds:
        for i, kind in enumerate(S.KINDS):
            fs = RATES[(i + seed) % 3]
            out.append(S.Case(f"clean-{kind}", (), kind, fs, seed))
        for j, e in enumerate(S.EFFECTS):
            kind = S.KINDS[(j + 2 * seed) % len(S.KINDS)]
            fs = RATES[(j + seed) % 3]
            if e in ("resonance", "delay", "bandwidth") and fs == 1000.0:
                fs = 5000.0
            out.append(S.Case(e, (e,), kind, fs, seed))
        for j, pair in enumerate((("creep", "delay"), ("resonance", "drift"),
                                  ("asymmetry", "creep"))):
            kind = S.KINDS[(j + 3 * seed + 1) % len(S.KINDS)]
            out.append(S.Case("+".join(pair), pair, kind, 5000.0, seed))
        for j, e in enumerate(S.OUTSIDE):
            kind = S.KINDS[(j + seed + 3) % len(S.KINDS)]
            out.append(S.Case(e, (e,), kind, RATES[(j + seed) % 3], seed))
    return out


def truth_set(effects):
    return sorted({S.VOCAB.get(e, e) for e in effects})


def judge(effects, verdict):
    if any(e in S.OUTSIDE for e in effects):
        return "unexplained" in verdict
    want = truth_set(effects) or ["none"]
    return sorted(verdict) == want


class _Late(Exception):
    pass


def _alarm(*_):
    raise _Late


def main():
    out, seeds = sys.argv[1], [int(s) for s in sys.argv[2].split(",")]
    filt = sys.argv[3] if len(sys.argv) > 3 else ""
    done = set()
    if os.path.exists(out):
        for line in open(out):
            d = json.loads(line)
            done.add((d["name"], d["seed"]))
    _signal.signal(_signal.SIGALRM, _alarm)
    for c in cases(seeds):
        if (c.name, c.seed) in done or filt not in c.name:
            continue
        rt, rv, st, info = S.make_records(c)
        t0 = time.process_time()
        _signal.alarm(150)
        try:
            rep = diagnose([rt], [rv], workers=1)
            v = rep.verdict
            row = {"effects": v["effects"], "shrink": v.get("shrink"),
                   "gap_before": v.get("gap_before"), "gap_after": v.get("gap_after"),
                   "noise_floor": v.get("noise_floor"),
                   "confidence": v.get("confidence")}
        except (_Late, ctypes.ArgumentError) as exc:  # the alarm inside a ctypes call
            if isinstance(exc, ctypes.ArgumentError) and "_Late" not in repr(exc):
                raise
            row = {"effects": ["TIMEOUT"]}
        finally:
            _signal.alarm(0)
        row.update(name=c.name, seed=c.seed, kind=c.kind, truth=list(c.effects),
                   cpu=time.process_time() - t0, **info)
        row["right"] = judge(c.effects, row["effects"])
        with open(out, "a") as f:
            f.write(json.dumps(row, default=str) + "\n")
        print(c.name, c.seed, c.kind, c.fs, row["effects"], row["right"],
              round(row["cpu"], 1), flush=True)


if __name__ == "__main__":
    main()
