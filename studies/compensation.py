"""Study: inverse compensation of the piezo-like stage. Open loop (chord gain), exact inverse,
proposed n = 4 and conventional n = 4, 7, 10 inverses as feedforward, on the static plant, with
a 1 kHz second-order mode, and with a PID loop; tracking-error table and a tracking figure.
``--quick`` is the same size (the compiled loops take well under a second)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pimodel.experiments.compensation import (
    STAGE,
    chord_gain,
    compensation_table,
    identified_models,
    reference,
)
from pimodel.experiments.studies import StudyResult, Table, study_main  # noqa: E402
from pimodel.loops.actuators import stage_dynamics  # noqa: E402
from pimodel.loops.compiled import run_loop  # noqa: E402
from pimodel.plotting import new_figure, save_figure  # noqa: E402


def run(out: Path, quick: bool = False) -> StudyResult:
    res = StudyResult("compensation")
    models = identified_models()
    tab = compensation_table(models)
    rows = [[name, *(f"{row[s]['max_percent']:.3f} / {row[s]['rms_percent']:.3f}"
                     for s in ("static", "mode", "mode+PID"))] for name, row in tab.items()]
    res.tables.append(Table("Tracking error, max / RMS in % of range",
                            ["feedforward", "static plant", "with 1 kHz mode",
                             "with mode + PID"], rows))
    res.numbers = tab
    fs = 10_000.0
    t, yd = reference(fs)
    G = stage_dynamics(1 / fs, fn_hz=1000, damping=0.05)
    fig, ax = new_figure(2, 1)
    for name, ff in (("none (chord gain)", "none"), ("proposed n = 4", models["proposed n=4"]),
                     ("conventional n = 4", models["conventional n=4"])):
        r = run_loop(yd, STAGE, 1 / fs, dynamics=G, feedforward=ff, ff_gain=chord_gain())
        ax[0, 0].plot(t, r.error, lw=0.8, label=name)
        ax[0, 1].plot(yd, r.y, lw=0.8, label=name)
    ax[0, 0].set(xlabel="time t [s]", ylabel="tracking error y_d - y [um]",
                 title="Feedforward compensation with the 1 kHz mode")
    ax[0, 1].set(xlabel="desired displacement y_d [um]", ylabel="displacement y [um]",
                 title="Output against reference (a line is perfect)")
    for a in ax[0]:
        a.legend(fontsize=8)
        a.grid(alpha=0.3)
    res.figures.append(save_figure(fig, out / "compensation.png"))
    return res


if __name__ == "__main__":
    sys.exit(study_main("compensation"))
