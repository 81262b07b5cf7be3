"""Run the DiagnosedModel FMU unit sample by sample (shared by the tests of the unit)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pimodel.fmu.unit import FMUUnit


def unit_file(folder: Path, fmi: str) -> Path:
    """The DiagnosedModel unit of FMI version ``fmi`` among the built FMUs in ``folder``."""
    return folder / f"DiagnosedModel{'_fmi3' if fmi == '3.0' else ''}.fmu"


def run_unit(path: Path, params: dict, v: np.ndarray, h: float) -> np.ndarray:
    """``y[k]`` of the unit at ``path`` for ``v[k]``, one communication step ``h`` [s] each."""
    unit = FMUUnit(path, params)
    out = []
    try:
        for x in v:
            unit.set({"v": x})
            unit.step(h)
            out.append(unit.get(["y"])[0])
    finally:
        unit.close()
    return np.array(out)
