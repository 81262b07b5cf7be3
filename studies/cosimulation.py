"""Study: the adaptive compensation loop as an FMU co-simulation. Builds the three FMUs, runs
plant FMU + 1 kHz stage mode + RadiusEstimator FMU + adaptive InversePI FMU in a fixed-step
master, and compares with the native compiled loop (same result expected to 1e-12).
Full: 2 s at 10 kHz; ``--quick``: 0.3 s."""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pimodel import RadiusEstimator  # noqa: E402
from pimodel.actuators import stage_dynamics  # noqa: E402
from pimodel.compensation import STAGE  # noqa: E402
from pimodel.fmu import build_fmus  # noqa: E402
from pimodel.fmu.cosim import cosimulate_adaptive_loop  # noqa: E402
from pimodel.loops import run_loop  # noqa: E402
from pimodel.plotting import new_figure, save_figure  # noqa: E402
from pimodel.signals import triangle  # noqa: E402
from pimodel.study_runner import StudyResult, Table, study_main  # noqa: E402

R0 = [0.0, 0.3, 0.4, 0.8]


def run(out: Path, quick: bool = False) -> StudyResult:
    res = StudyResult("cosimulation")
    dt = 1e-4
    t, v = triangle(1.0, 5, fs=1 / dt, duration=0.3 if quick else 2.0)
    yd = STAGE.simulate(v)
    G = stage_dynamics(dt, fn_hz=1000, damping=0.05)
    with tempfile.TemporaryDirectory() as tmp:
        build_fmus(tmp)
        t0 = time.perf_counter()
        co = cosimulate_adaptive_loop(tmp, yd, dt, STAGE, weights=STAGE.weights, gain=20.0,
                                      initial_radii=R0, dynamics=G)
        t_co = time.perf_counter() - t0
    est = RadiusEstimator(STAGE.weights, dt=dt, gains=20.0, initial_radii=R0,
                          known_linear_play=True)
    t0 = time.perf_counter()
    native = run_loop(yd, STAGE, dt, dynamics=G, feedforward="adaptive", estimator=est)
    t_native = time.perf_counter() - t0
    diff = float(np.max(np.abs(co.y - native.y)))
    last = int(0.8 * t.size)
    res.tables.append(Table("FMU co-simulation against the native compiled loop", [
        "quantity", "value"], [
        ["samples", t.size], ["max |y_cosim - y_native| [um]", diff],
        ["final radii (co-simulation)", np.array2string(co.radii[-1], precision=4)],
        ["true radii", np.array2string(STAGE.radii, precision=4)],
        ["tracking error, last 20 %, max [% of range]", co.tracking(last)["max_percent"]],
        ["co-simulation steps/s (Python master, 3 FMUs)", t.size / t_co],
        ["native compiled loop steps/s", t.size / max(t_native, 1e-9)]]))
    res.numbers = {"max_difference": diff, "tracking_last": co.tracking(last),
                   "final_radii": co.radii[-1].tolist()}
    fig, ax = new_figure(2, 1)
    for i in range(1, 4):
        ax[0, 0].plot(t, co.radii[:, i], label=f"r_hat[{i + 1}] (FMU)")
        ax[0, 0].axhline(STAGE.radii[i], color="0.6", ls="--", lw=0.6)
    ax[0, 0].set(xlabel="time t [s]", ylabel="radius estimate [V]",
                 title="RadiusEstimator FMU inside the co-simulation")
    ax[0, 0].legend(fontsize=8)
    ax[0, 1].plot(t, co.error, lw=0.7, label="co-simulation")
    ax[0, 1].plot(t, native.error, "--", lw=0.7, label="native compiled loop")
    ax[0, 1].set(xlabel="time t [s]", ylabel="tracking error [um]",
                 title="Adaptive inverse compensation (1 kHz mode)")
    ax[0, 1].legend(fontsize=8)
    res.figures.append(save_figure(fig, out / "cosimulation.png"))
    return res


if __name__ == "__main__":
    sys.exit(study_main("cosimulation"))
