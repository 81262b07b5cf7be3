"""Study: convergence map of the radius estimator (issue 15). The paper's five plays,
p = (0.3, 0.5, 0.8, 0.3, 0.2), r = (0.4, 1, 1.5, 2, 3.6), estimated with the default law
(``law="data"``) and the default settings chosen from the record
(:meth:`pimodel.RadiusEstimator.for_record`), over a grid of

- starts: below, zero, all equal 2, mixed, far above, 0.8 x truth, (1..5);
- output noise: clean, SNR 30, 20, 10 dB;
- inputs (all between about -30 and 30, 1 Hz): sine, triangle, stair-step (steps 0.5 held
  5 ms on a triangle), decaying minor loops (30 e^{-t'} sin(4 pi t'), t' = t mod 4 s: one full
  loop then shrinking minor loops, every 4 s).

Each cell: the largest relative radius error of the final estimate (clean) or of the mean over
the last half of the record (noisy). Full size: clean 1 kHz for 150 s; 30 dB 10 kHz for 300 s;
20 and 10 dB 10 kHz for 2000 s (the 10 dB length the tests use, 6000 s, would take 30 min
here); ``--quick``: 1 kHz for 60 s everywhere. The cases are plain dicts (:func:`cases`) and
:func:`run_case` runs one, so the grid can go onto a sweep runner as it is.
"""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import numpy as np

from pimodel import PIOperator, RadiusEstimator, estimate_radii
from pimodel.experiments.studies import StudyResult, Table, study_main
from pimodel.identification.adaptive.radius_estimator import stream_tail_average
from pimodel.plotting import new_figure, save_figure
from pimodel.stages.long_records import noisy_output_chunks, record_length

P = np.array([0.3, 0.5, 0.8, 0.3, 0.2])
R = np.array([0.4, 1.0, 1.5, 2.0, 3.6])
STARTS = {
    "below": [0.1, 0.2, 0.3, 0.4, 0.5],
    "zero": [0.0] * 5,
    "all equal 2": [2.0] * 5,
    "mixed": [0.2, 1.5, 1.6, 3.0, 3.2],
    "far above": [5.0, 10.0, 15.0, 20.0, 25.0],
    "0.8 x truth": list(0.8 * R),
    "(1..5)": [1.0, 2.0, 3.0, 4.0, 5.0],
}
NOISE = [None, 30.0, 20.0, 10.0]  # SNR [dB], None: clean
INPUTS = ["sine", "triangle", "stair-step", "decaying minor loops"]


def _triangle(t):
    return 2 / np.pi * np.arcsin(np.sin(2 * np.pi * t))  # 1 Hz, between -1 and 1


def input_at(name: str, t: np.ndarray) -> np.ndarray:
    """The input ``v(t)`` of the named case at times ``t`` [s]."""
    if name == "sine":
        return 30 * np.sin(2 * np.pi * t)
    if name == "triangle":
        return 30 * _triangle(t)
    if name == "stair-step":
        held = np.floor(t / 0.005) * 0.005  # held 5 ms
        return 5 + 0.5 * np.round(20 * _triangle(held) / 0.5)  # -15..25 in steps of 0.5
    if name == "decaying minor loops":
        tm = np.mod(t, 4.0)
        return 30 * np.exp(-tm) * np.sin(4 * np.pi * tm)
    raise ValueError(f"input: unknown name {name!r}; expected one of {INPUTS}")


def cases(quick: bool = False) -> list[dict]:
    """The grid as plain parameter dicts (one per cell)."""
    out = []
    for inp, snr, start in itertools.product(INPUTS, NOISE, STARTS):
        if quick:
            fs, dur = 1000.0, 60.0
        elif snr is None:
            fs, dur = 1000.0, 150.0
        elif snr >= 30:
            fs, dur = 10_000.0, 300.0
        else:
            fs, dur = 10_000.0, 2000.0
        out.append({"input": inp, "snr_db": snr, "start": start, "fs": fs, "duration": dur,
                    "seed": 0})
    return out


def run_case(case: dict) -> dict:
    """Run one cell: returns the case with ``final_error``, ``mean_error`` (max relative
    radius error of the final estimate and of the mean over the last half) and ``error`` (the
    one the map shows: final when clean, mean when noisy)."""
    op = PIOperator(P, R)
    fs, dur, r0 = case["fs"], case["duration"], STARTS[case["start"]]
    if case["snr_db"] is None:
        t = np.arange(record_length(fs, dur)) / fs
        v = input_at(case["input"], t)
        res = estimate_radii(v, op.simulate(v), P, dt=1 / fs, initial_radii=r0)
        final, mean = res.radii, res.radii_mean
    else:
        chunks = noisy_output_chunks(op, lambda t: input_at(case["input"], t), fs=fs,
                                     duration=dur, snr_db=case["snr_db"],
                                     rng=np.random.default_rng(case["seed"]))
        first = next(chunks)
        est = RadiusEstimator.for_record(*first, P, dt=1 / fs, initial_radii=r0)
        final, mean = stream_tail_average(est, itertools.chain([first], chunks),
                                          total=record_length(fs, dur))
    fe = float(np.max(np.abs(final / R - 1)))
    me = float(np.max(np.abs(mean / R - 1)))
    return {**case, "final_error": fe, "mean_error": me,
            "error": fe if case["snr_db"] is None else me}


def _label(snr) -> str:
    return "clean" if snr is None else f"{snr:g} dB"


def aggregate(out: Path, quick: bool, cases: list[dict], results: list[dict]) -> StudyResult:
    """The map (table and figure) from the finished cells."""
    res = StudyResult("convergence_map")
    grid = {(r["input"], r["snr_db"], r["start"]): r for r in results}
    rows = [[inp, start, *[100 * grid[inp, snr, start]["error"] for snr in NOISE]]
            for inp in INPUTS for start in STARTS]
    res.tables.append(Table("Largest relative radius error [%] (final estimate when clean, "
                            "mean of the last half when noisy)",
                            ["input", "start", *[_label(s) for s in NOISE]], rows))
    fig, axes = new_figure(len(INPUTS), 1, size=(3.6, 4.2))
    for ax, inp in zip(axes[0], INPUTS, strict=True):
        z = np.array([[np.log10(max(grid[inp, snr, s]["error"], 1e-5)) for snr in NOISE]
                      for s in STARTS])
        ax.imshow(z, vmin=-4, vmax=0, cmap="RdYlGn_r", aspect="auto")
        ax.set_xticks(range(len(NOISE)), [_label(s) for s in NOISE], fontsize=7)
        ax.set_yticks(range(len(STARTS)), list(STARTS), fontsize=7)
        ax.set(xlabel="output noise", ylabel="initial radii", title=inp)
        for i, s in enumerate(STARTS):
            for j, snr in enumerate(NOISE):
                ax.text(j, i, f"{100 * grid[inp, snr, s]['error']:.2g}", ha="center",
                        va="center", fontsize=6)
    fig.suptitle("Largest relative radius error [%] (colour: log scale, green 0.01 %, "
                 "red >= 100 %)", fontsize=9)
    res.figures.append(save_figure(fig, out / "convergence_map.png"))
    clean = [r["error"] for r in results if r["snr_db"] is None]
    res.numbers = {"clean_worst": max(clean),
                   "worst_by_noise": {_label(s): max(r["error"] for r in results
                                                     if r["snr_db"] == s) for s in NOISE},
                   "cases": len(results)}
    res.notes.append("Default law and settings (chosen from the record) in every cell; cell "
                     "values in %. " + ("Quick size: 1 kHz for 60 s everywhere, too short for "
                                        "the noisy cells." if quick else
                                        "Clean: 1 kHz, 150 s; 30 dB: 10 kHz, 300 s; 20 and "
                                        "10 dB: 10 kHz, 2000 s; seed 0."))
    return res


if __name__ == "__main__":
    sys.exit(study_main("convergence_map"))
