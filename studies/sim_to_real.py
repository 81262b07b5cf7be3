"""Study: sim-to-real gap diagnosis with withheld effects (confusion table) and on the shared
real piezo record.

For each effect (and two pairs, and a clean PI stage) the truth simulator generates train and
validate records with seeded random magnitudes; the diagnosis never sees the effect's name.
Full size: 10 seeds per case; ``--quick``: 1 seed, no pairs.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pimodel.diagnosis import diagnose  # noqa: E402
from pimodel.study_runner import StudyResult, Table, study_main  # noqa: E402
from pimodel.truth import EFFECTS, excitation, random_truth  # noqa: E402

REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real" / \
    "smarthysteresis-piezo-1hz" / "piezo_1hz.csv"


def withheld_cases(quick: bool):
    cases = [(e,) for e in EFFECTS] + [()]
    if not quick:
        cases += [("creep", "asymmetry"), ("dynamics", "drift")]
    return cases


def cases(quick: bool) -> list[dict]:
    """One case per withheld effect set and seed (the sweep's plain parameter dicts)."""
    seeds = range(1 if quick else 10)
    return [{"effects": list(effects), "seed": s} for effects in withheld_cases(quick)
            for s in seeds]


def run_case(params: dict) -> dict:
    """The diagnosis' verdict on train/validate records of a random truth (seeded)."""
    effects, seed = params["effects"], params["seed"]
    tt, vt = excitation("train", seed=2 * seed + 1)
    tv, vv = excitation("validate", seed=2 * seed + 2)
    truth = random_truth(list(effects), seed)
    rep = diagnose([truth.record(tt, vt, seed, "train")], [truth.record(tv, vv, 100 + seed,
                                                                        "validate")])
    return rep.verdict


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
    """Confusion table over the cases (grouped by withheld effects) and the real record."""
    res = StudyResult("sim_to_real")
    rows, numbers = [], {}
    groups: dict[tuple, list[dict]] = {}
    for params, verdict in zip(cases, results, strict=True):
        groups.setdefault(tuple(params["effects"]), []).append(verdict)
    for effects, verdicts in groups.items():
        expected = sorted(effects) or ["none"]
        hits = sum(sorted(v["effects"]) == expected for v in verdicts)
        shrinks = [v["shrink"] for v in verdicts]
        found: dict[str, int] = {}
        for v in verdicts:
            key = "+".join(sorted(v["effects"]))
            found[key] = found.get(key, 0) + 1
        name = "+".join(effects) or "none (clean PI)"
        rows.append([name, f"{hits}/{len(verdicts)}", float(np.min(shrinks)),
                     float(np.median(shrinks)), ", ".join(f"{k}: {n}" for k, n in found.items())])
        numbers[name] = {"hits": hits, "n": len(verdicts), "min_shrink": float(np.min(shrinks))}
    res.tables.append(Table("Withheld effects: verdicts (correct / cases) and validate-gap shrink",
                            ["truth", "correct", "min shrink", "median shrink", "verdicts"],
                            rows))
    if REAL.exists():
        rep, figs = real_record(out)
        v = rep.verdict
        res.figures += figs
        res.tables.append(Table("Shared real record (train: first half of the sine cycles, "
                                "validate: second half)",
                                ["verdict", "gap before [um]", "gap after [um]", "shrink",
                                 "noise floor [um]"],
                                [["+".join(v["effects"]), v["gap_before"], v["gap_after"],
                                  v["shrink"], v["noise_floor"]]]))
        numbers["real"] = {k: v[k] for k in ("effects", "gap_before", "gap_after", "shrink")}
        rep.save_json(out / "real_diagnosis.json")
    else:
        res.notes.append(f"shared real record not found at {REAL}: real-data part skipped")
    res.numbers = numbers
    return res


if __name__ == "__main__":
    sys.exit(study_main("sim_to_real"))
