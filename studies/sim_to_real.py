"""Study: sim-to-real gap diagnosis with withheld effects on three generators (confusion
tables) and on the shared real piezo record.

Generators: ``pimodel.stages.pi_stage`` (PI hysteresis, the same model family as the
candidates), the independently written ``pimodel.stages.preisach_stage`` (Preisach hysteresis,
log-law creep, two modes, exponential static map, coloured noise; also effects outside the
vocabulary that must come back "unexplained") and, at full size only, the third, independent
``pimodel.stages.density_stage`` (2 kHz; a smooth PI density of many plays; random-phase
multisines, log chirps, ramps to held levels, band-limited random input; creep with lags up to
100 s, thermal settling on the shared clock, a mode plus a real pole, radii growing with a
low-passed rate, a quadratic output map; outside the vocabulary: output clipping, an unmeasured
second input, a sensor gain differing between records). Its clean stage is run on every input
kind (``kind``: ``mixed`` or one of ``INPUT_KINDS``). The diagnosis never sees the effect's
name. Full size: 10 seeds per case; ``--quick``: 1 seed, single effects only, no
``density`` cases.

A case ``offset`` adds a level of its own to each record (a sensor zeroed anew between
records; train at 0, validate at +-0.05 to 0.2 um, seeded) to an otherwise clean stage: the
right verdict is ``drift`` (the candidate that holds per-record levels,
:mod:`pimodel.diagnosis.drift`).

Each case is a plain picklable dict (``generator``, ``effects``, ``drift_clock``, ``seed``) and
:func:`run_case` turns one into a verdict row, so the cases can be spread over workers.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pimodel.diagnosis import diagnose  # noqa: E402
from pimodel.experiments.studies import StudyResult, Table, study_main  # noqa: E402
from pimodel.records import Record  # noqa: E402

REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real" / \
    "smarthysteresis-piezo-1hz" / "piezo_1hz.csv"
SINGLE = ("creep", "dynamics", "delay", "asymmetry", "drift", "rate")
PAIRS = ((("rate", "creep"), "record"), (("delay", "drift"), "record"),
         (("asymmetry", "drift"), "absolute"))
OUTSIDE = ("dead_zone", "second_input", "bouc_wen")  # truth_alt only: expect "unexplained"
OFFSET = (("offset",), "record")  # a level per record (module docstring), found as "drift"
DENSITY_PAIRS = (("creep", "delay"), ("dynamics", "asymmetry"), ("rate", "drift"),
                 ("creep", "dynamics", "delay"))
DENSITY_OUTSIDE = ("clipping", "second_input", "sensor_gain")  # density only: "unexplained"
DENSITY_KINDS = ("mixed", "multisine", "chirp", "ramps", "random")  # clean stage on each


def cases(quick: bool) -> list[dict]:
    """All cases of the study as plain dicts."""
    seeds = range(1 if quick else 10)
    groups = [((), "record")] + [((e,), "record") for e in SINGLE]
    if not quick:
        groups += list(PAIRS) + [(("drift",), "absolute"), OFFSET]
    out = []
    for gen in ("truth", "truth_alt"):
        extra = [((e,), "record") for e in OUTSIDE] if gen == "truth_alt" else []
        for effects, clock in groups + extra:
            for seed in seeds:
                out.append({"generator": gen, "effects": list(effects), "drift_clock": clock,
                            "seed": seed})
    return out + ([] if quick else density_cases(quick))


def density_cases(quick: bool, seeds=None) -> list[dict]:
    """The cases of the ``density`` generator: a clean stage on every input kind, each single
    effect, ``DENSITY_PAIRS`` and ``DENSITY_OUTSIDE`` (``quick``: one seed, the clean stage on
    the mixed input and the single effects; :func:`cases` adds them at full size only).
    ``seeds`` overrides the seeds."""
    seeds = range(1 if quick else 10) if seeds is None else seeds
    groups = [((), k) for k in (DENSITY_KINDS[:1] if quick else DENSITY_KINDS)]
    groups += [((e,), "mixed") for e in SINGLE]
    if not quick:
        groups += [(p, "mixed") for p in DENSITY_PAIRS]
        groups += [((e,), "mixed") for e in DENSITY_OUTSIDE]
    return [{"generator": "density", "effects": list(effects), "drift_clock": "absolute",
             "kind": kind, "seed": seed} for effects, kind in groups for seed in seeds]


def _records(case: dict):
    train, validate, initial_state = _stage_records({**case, "effects": [
        e for e in case["effects"] if e != "offset"]})
    if "offset" in case["effects"]:
        rng = np.random.default_rng(7000 + case["seed"])
        level = rng.uniform(0.05, 0.2) * rng.choice([-1, 1])
        validate = [Record(r.t, r.v, r.y + level, source=r.source) for r in validate]
    return train, validate, initial_state


def _stage_records(case: dict):
    seed, effects, clock = case["seed"], case["effects"], case["drift_clock"]
    if case["generator"] == "density":
        from pimodel.stages.density_stage import density_records

        train, validate = density_records(effects, seed, case["kind"])
        return [train], [validate], "rest"
    if case["generator"] == "truth":
        from pimodel.stages.pi_stage import excitation, random_truth

        tt, vt = excitation("train", seed=2 * seed + 1)
        tv, vv = excitation("validate", seed=2 * seed + 2)
        tv = tv + tt[-1] + 1.0  # the validate clock continues after train
        truth = random_truth(effects, seed, drift_clock=clock)
        return [truth.record(tt, vt, seed, "train")], [truth.record(tv, vv, 100 + seed,
                                                                   "validate")], "rest"
    from pimodel.stages.preisach_stage import excitations, random_alt_truth

    (tt, vt), (tv, vv) = excitations(seed + 1)
    truth = random_alt_truth(effects, seed, "absolute" if clock == "absolute" else "record")
    rng = np.random.default_rng(3 + seed)
    return ([Record(tt, vt, truth.simulate(tt, vt, rng), source="alt-train")],
            [Record(tv, vv, truth.simulate(tv, vv, rng), source="alt-validate")], "unknown")


def expected(case: dict) -> list[str]:
    """The right verdict: the withheld effects, "unexplained" for effects outside the
    vocabulary, "none" for a clean stage, "drift" for levels that differ by record."""
    if set(case["effects"]) & (set(OUTSIDE) | set(DENSITY_OUTSIDE)):
        return ["unexplained"]
    return sorted({"drift" if e == "offset" else e for e in case["effects"]}) or ["none"]


def run_case(case: dict) -> dict:
    """Diagnose one case; returns the case, the verdict's effects and figures, and whether the
    verdict is right (for effects outside the vocabulary: "unexplained" among the effects)."""
    train, validate, initial_state = _records(case)
    v = diagnose(train, validate, initial_state=initial_state).verdict
    want = expected(case)
    right = ("unexplained" in v["effects"]) if want == ["unexplained"] else \
        sorted(v["effects"]) == want
    return {**case, "verdict": v["effects"], "right": bool(right), "shrink": v["shrink"],
            "gap_before": v["gap_before"], "gap_after": v["gap_after"],
            "noise_floor": v["noise_floor"], "noise_method": v["noise_floor_method"]}


def group_name(row: dict) -> str:
    """Name of a case group: the withheld effects (and the drift's clock)."""
    key = "+".join(row["effects"]).replace("offset", "record offsets") or "none (clean)"
    if "drift" in row["effects"] and row["generator"] != "density":
        key += f" [{row['drift_clock']} clock]"
    if row["generator"] == "density" and not row["effects"]:
        key += f" [{row['kind']} input]"
    return key


def confusion(rows: list[dict]) -> list[list]:
    """One table row per case group: right / cases, shrink, verdict counts."""
    groups: dict = {}
    for r in rows:
        groups.setdefault(group_name(r), []).append(r)
    table = []
    for key, rs in groups.items():
        found: dict[str, int] = {}
        for r in rs:
            k = "+".join(sorted(r["verdict"]))
            found[k] = found.get(k, 0) + 1
        sh = [r["shrink"] for r in rs]
        table.append([key, f"{sum(r['right'] for r in rs)}/{len(rs)}", float(np.min(sh)),
                      float(np.median(sh)), ", ".join(f"{k}: {n}" for k, n in found.items())])
    return table


def real_record(out: Path):
    from pimodel import load_record
    from pimodel.diagnosis.plots import plot_diagnosis

    rec = load_record(REAL)
    k0 = int(np.argmax(np.abs(rec.v) > 1))
    mid = k0 + (len(rec) - k0) // 2
    train, validate = rec.slice(k0, mid), rec.slice(mid, None)
    rep = diagnose([train], [validate])
    figs = plot_diagnosis(rep, out, prefix="real_")
    return rep, figs


def aggregate(out: Path, quick: bool, cases: list[dict], results: list[dict]) -> StudyResult:
    """Confusion tables per generator (from the finished cases) and the real record."""
    res = StudyResult("sim_to_real")
    rows = results
    numbers: dict = {}
    for r in rows:
        key = f"{r['generator']}: {group_name(r)}"
        kind = "clean" if not r["effects"] else "outside" if expected(r) == ["unexplained"] \
            else "effect"
        d = numbers.setdefault(key, {"hits": 0, "n": 0, "min_shrink": np.inf, "kind": kind})
        d["hits"] += int(r["right"])
        d["n"] += 1
        d["min_shrink"] = min(d["min_shrink"], float(r["shrink"]))
    out.mkdir(parents=True, exist_ok=True)
    (out / "cases.json").write_text(json.dumps(rows, indent=1, default=float))
    for gen, title in (("truth", "pimodel.stages.pi_stage (PI family)"),
                       ("truth_alt", "pimodel.stages.preisach_stage (independent: Preisach, "
                                     "log creep, two modes, coloured noise)"),
                       ("density", "pimodel.stages.density_stage (independent: 2 kHz, smooth PI "
                                   "density, multisine/chirp/ramps/random input, thermal "
                                   "settling, mode + pole)")):
        res.tables.append(Table(f"Withheld effects, {title}: right verdicts / cases, "
                                "validate-gap shrink, verdicts",
                                ["truth", "right", "min shrink", "median shrink", "verdicts"],
                                confusion([r for r in rows if r["generator"] == gen])))
    if REAL.exists():
        rep, figs = real_record(out)
        v = rep.verdict
        res.figures += figs
        res.tables.append(Table("Shared real record (train: first half of the sine cycles, "
                                "validate: second half)",
                                ["verdict", "gap before [um]", "gap after [um]", "shrink",
                                 "noise floor [um]", "noise floor method"],
                                [["+".join(v["effects"]), v["gap_before"], v["gap_after"],
                                  v["shrink"], v["noise_floor"], v["noise_floor_method"]]]))
        numbers["real"] = {k: v[k] for k in ("effects", "gap_before", "gap_after", "shrink",
                                             "noise_floor", "noise_floor_method")}
        rep.save_json(out / "real_diagnosis.json")
    else:
        res.notes.append(f"shared real record not found at {REAL}: real-data part skipped")
    res.numbers = numbers
    return res


if __name__ == "__main__":
    sys.exit(study_main("sim_to_real"))
