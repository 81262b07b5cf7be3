"""Study: the radius estimator on the inputs users apply (issue 27). Random stages (3-7
plays, weights known, ``2 r_n`` at most two thirds of the input range), drawn per seed;
:func:`pimodel.estimate_radii` with its defaults (online law, then the batch refinement) from
starts below (0.3 x truth), at zero and far above (3 x the largest radius), over

- inputs: centred sine, offset sine, triangle, multisine, band-limited random, stair steps,
  decaying loops (:mod:`pimodel.experiments.estimator_map`);
- output noise: clean, SNR 30, 20, 10 dB;
- seeds 0 and 1 (``--quick``: seed 0, start zero only).

Each cell: the largest radius error relative to the largest radius, of the online estimate and
of the refined one, and (noisy) the largest ratio of the refined error to the Cramer-Rao
standard deviation. Records: 20 s at 1 kHz, so the whole map runs in a few minutes.
"""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import numpy as np

from pimodel.experiments.estimator_map import INPUT_KINDS, STARTS, run_cell
from pimodel.experiments.studies import StudyResult, Table, study_main
from pimodel.plotting import new_figure, save_figure

NOISE = [None, 30.0, 20.0, 10.0]  # SNR [dB], None: clean
DURATION = 20.0  # s at 1 kHz


def cases(quick: bool = False) -> list[dict]:
    """The grid as plain parameter dicts (one per cell)."""
    seeds, starts = ([0], ["zero"]) if quick else ([0, 1], list(STARTS))
    return [{"kind": k, "snr_db": s, "start": st, "seed": sd}
            for k, s, st, sd in itertools.product(INPUT_KINDS, NOISE, starts, seeds)]


def run_case(case: dict) -> dict:
    """One cell (:func:`pimodel.experiments.estimator_map.run_cell`)."""
    return run_cell(case["kind"], case["snr_db"], case["start"], case["seed"],
                    duration=DURATION)


def _label(snr) -> str:
    return "clean" if snr is None else f"{snr:g} dB"


def aggregate(out: Path, quick: bool, cases: list[dict], results: list[dict]) -> StudyResult:
    """Worst and median error per input kind and noise level, the ratio to the bound, and the
    map figure."""
    res = StudyResult("estimator_inputs")
    rows = []
    worst = np.zeros((len(INPUT_KINDS), len(NOISE)))
    for i, kind in enumerate(INPUT_KINDS):
        for j, snr in enumerate(NOISE):
            cell = [r for r in results if r["kind"] == kind and r["snr_db"] == snr]
            pol = [100 * r["polished"] for r in cell]
            onl = [100 * r["online"] for r in cell]
            ratio = [r["ratio"] for r in cell if r["ratio"] is not None]
            worst[i, j] = max(pol)
            rows.append([kind, _label(snr), max(onl), float(np.median(pol)), max(pol),
                         max(ratio) if ratio else float("nan")])
    res.tables.append(Table("Largest radius error [% of the largest radius] over starts and "
                            "seeds: online law, refined (median, worst); worst ratio of the "
                            "refined error to the Cramer-Rao sd",
                            ["input", "noise", "online worst", "refined median",
                             "refined worst", "error / bound"], rows))
    fig, axes = new_figure(1, 1, size=(6.0, 4.0))
    ax = axes[0][0]
    ax.imshow(np.log10(np.maximum(worst, 1e-6)), vmin=-4, vmax=2, cmap="RdYlGn_r",
              aspect="auto")
    ax.set_xticks(range(len(NOISE)), [_label(s) for s in NOISE])
    ax.set_yticks(range(len(INPUT_KINDS)), list(INPUT_KINDS))
    for i in range(len(INPUT_KINDS)):
        for j in range(len(NOISE)):
            ax.text(j, i, f"{worst[i, j]:.2g}", ha="center", va="center", fontsize=7)
    ax.set(xlabel="output noise", ylabel="input",
           title="worst refined radius error [% of largest radius]")
    res.figures.append(save_figure(fig, out / "estimator_inputs.png"))
    res.numbers = {"worst_by_noise": {_label(s): float(worst[:, j].max())
                                      for j, s in enumerate(NOISE)}, "cases": len(results)}
    res.notes.append(f"Random stages per seed, {DURATION:g} s at 1 kHz, default settings; "
                     + ("quick: seed 0, start zero." if quick else
                        "seeds 0-1, starts below / zero / far above."))
    return res


if __name__ == "__main__":
    sys.exit(study_main("estimator_inputs"))
