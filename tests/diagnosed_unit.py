"""Run the DiagnosedModel FMU unit sample by sample (shared by the tests of the unit)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pimodel.fmu.unit import FMUUnit


def unit_file(folder: Path, fmi: str) -> Path:
    """The DiagnosedModel unit of FMI version ``fmi`` among the built FMUs in ``folder``."""
    return folder / f"DiagnosedModel{'_fmi3' if fmi == '3.0' else ''}.fmu"


def step_through(unit: FMUUnit, xs, h: float, inp: str = "v", out: str = "y") -> list:
    """Output ``out`` of an open unit after each communication step ``h`` [s] with input
    ``inp`` held at ``xs[k]`` (the DiagnosedModel unit: ``v`` in, ``y`` out; the
    DiagnosedInverse unit: ``y_d`` in, ``v`` out)."""
    res = []
    for x in xs:
        unit.set({inp: x})
        unit.step(h)
        res.append(unit.get([out])[0])
    return res


def run_unit(path: Path, params: dict, v: np.ndarray, h: float) -> np.ndarray:
    """``y[k]`` of the unit at ``path`` for ``v[k]``, one communication step ``h`` [s] each."""
    unit = FMUUnit(path, params)
    try:
        return np.array(step_through(unit, v, h))
    finally:
        unit.close()
