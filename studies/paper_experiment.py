"""Study: the paper's experiment (Sec. V) on the piezo-like stage generated from its identified
values (p = 6.3460, 1.6735, 1.1552, 0.4477 um/V; r = 0, 0.1945, 0.4826, 0.5707 V): slopes and
weights from the 1 Hz triangle of 2 V peak to peak, radius estimation, major- and minor-loop
errors, and the conventional method for n = 4..10 (the paper's Figs. 8 and 9).
``--quick`` uses n = 4, 7, 10 only for the conventional method.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pimodel import identify  # noqa: E402
from pimodel.experiments.compensation import STAGE  # noqa: E402
from pimodel.experiments.studies import StudyResult, Table, study_main  # noqa: E402
from pimodel.plotting import new_figure, save_figure  # noqa: E402
from pimodel.signals import add_noise_snr, major_minor_loops, triangle  # noqa: E402

PAPER_SLOPES = (6.3460, 8.0195, 9.1747, 9.6224)


def run(out: Path, quick: bool = False) -> StudyResult:
    res = StudyResult("paper_experiment")
    t, v = triangle(1, 1, fs=1000, duration=3)
    y = add_noise_snr(STAGE.simulate(v), 40, np.random.default_rng(0))
    tm, vm = major_minor_loops(1, 1, fs=1000, minor_fractions=(0.6, 0.3, 0.15))
    ym = STAGE.simulate(vm)
    major = slice(0, int(2 * 1000))  # the two major loops at the start
    prop = identify(v, y, dt=1e-3, n_plays=4)
    s = prop.slopes
    res.tables.append(Table("Slopes of the loop (SNR 40 dB record) against the paper",
                            ["", "s1", "s2", "s3", "s4"],
                            [["paper", *PAPER_SLOPES], ["identified", *s.slopes[:4]]]))
    rows, numbers = [], {}

    def errs(idn):
        e = idn.predict(vm) - ym
        return float(np.max(np.abs(e[major]))), float(np.max(np.abs(e)))

    mj, mx = errs(prop)
    rows.append(["proposed (slopes + adaptive radii)", 4, mj, mx])
    numbers["proposed"] = {"major": mj, "max": mx, "radii": prop.radii.tolist(),
                           "weights": prop.weights.tolist()}
    ns = (4, 7, 10) if quick else tuple(range(4, 11))
    for n in ns:
        c = identify(v, y, dt=1e-3, method="conventional", n_plays=n)
        mj, mx = errs(c)
        rows.append(["conventional (preset radii, LS weights)", n, mj, mx])
        numbers[f"conventional_{n}"] = {"major": mj, "max": mx}
    res.tables.append(Table("Max error on major and on major + minor loops (range 17 um)",
                            ["model", "n", "major loops [um]", "major + minor [um]"], rows))
    fig, ax = new_figure(2, 1)
    labels = [f"{r[0].split(' ')[0]} n={r[1]}" for r in rows]
    ax[0, 0].bar(np.arange(len(rows)), [r[3] for r in rows], color="tab:blue",
                 label="major + minor loops")
    ax[0, 0].bar(np.arange(len(rows)), [r[2] for r in rows], color="tab:orange", width=0.5,
                 label="major loops")
    ax[0, 0].set_xticks(np.arange(len(rows)), labels, rotation=45, fontsize=7)
    ax[0, 0].set(xlabel="model (identified from the 1 Hz triangle)", ylabel="max error [um]",
                 title="Proposed n = 4 against conventional n")
    ax[0, 0].legend()
    ax[0, 1].plot(vm, ym, lw=1.0, color="0.3", label="stage (truth)")
    ax[0, 1].plot(vm, prop.predict(vm), "--", lw=0.8, label="proposed n = 4")
    ax[0, 1].set(xlabel="input v [V]", ylabel="displacement y [um]",
                 title="Major and minor loops")
    ax[0, 1].legend()
    res.figures.append(save_figure(fig, out / "paper_experiment.png"))
    res.numbers = numbers
    return res


if __name__ == "__main__":
    sys.exit(study_main("paper_experiment"))
