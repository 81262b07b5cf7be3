"""Study: the adaptive compensation loop as an FMU co-simulation. Builds the three FMUs, runs
plant FMU + 1 kHz stage mode + RadiusEstimator FMU + adaptive InversePI FMU in a fixed-step
master, and compares with the native compiled loop (same result expected to 1e-12).
Full: 2 s at 10 kHz; ``--quick``: 0.3 s."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pimodel.experiments.compensation import STAGE  # noqa: E402
from pimodel.experiments.fmu_comparison import compare_with_native, plot_comparison  # noqa: E402
from pimodel.experiments.studies import StudyResult, Table, study_main  # noqa: E402
from pimodel.fmu import build_fmus  # noqa: E402
from pimodel.fmu.cosim import LOOP_UNITS  # noqa: E402

R0 = [0.0, 0.3, 0.4, 0.8]


def run(out: Path, quick: bool = False) -> StudyResult:
    res = StudyResult("cosimulation")
    with tempfile.TemporaryDirectory() as tmp:
        build_fmus(tmp, LOOP_UNITS)
        cmp = compare_with_native(tmp, duration=0.3 if quick else 2.0, weights=STAGE.weights,
                                  initial_radii=R0, gain=20.0)
    co, steps = cmp.cosim, cmp.cosim.t.size
    last = int(0.8 * steps)
    res.tables.append(Table("FMU co-simulation against the native compiled loop", [
        "quantity", "value"], [
        ["samples", steps], ["max |y_cosim - y_native| [um]", cmp.max_difference],
        ["final radii (co-simulation)", np.array2string(co.radii[-1], precision=4)],
        ["true radii", np.array2string(STAGE.radii, precision=4)],
        ["tracking error, last 20 %, max [% of range]", co.tracking(last)["max_percent"]],
        ["co-simulation steps/s (Python master, 3 FMUs)", cmp.cosim_steps_per_s],
        ["native compiled loop steps/s", cmp.native_steps_per_s]]))
    res.numbers = {"max_difference": cmp.max_difference, "tracking_last": co.tracking(last),
                   "final_radii": co.radii[-1].tolist()}
    res.figures.append(plot_comparison(cmp, out / "cosimulation.png"))
    return res


if __name__ == "__main__":
    sys.exit(study_main("cosimulation"))
