"""A fixed-step co-simulation master for the adaptive compensation loop built from FMUs.

Units: PIHysteresis (the plant's hysteresis), RadiusEstimator, InversePI (adaptive mode), and
the linear stage dynamics stepped by the master (discrete state space). Per step k (dt):
InversePI gets ``y_d[k]`` and the estimator's ``r_hat`` (the estimate after step k-1) and gives
``v[k]``; PIHysteresis gives ``h[k] = PI[v][k]``; the master computes ``y[k] = C xd + D h`` and
``xd <- A xd + B h``; the estimator takes ``(v[k], y[k])``. This is the loop of
:func:`pimodel.loops.run_loop` with ``feedforward="adaptive"``, so the two agree exactly.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np

from ..loops import LoopResult
from ..operator import PIOperator
from .build import fmu_filename
from .unit import FMUUnit


def _arrays(prefix: str, values) -> dict:
    return {f"{prefix}[{i + 1}]": float(x) for i, x in enumerate(values)}


def cosimulate_adaptive_loop(fmu_dir, ref, dt: float, plant: PIOperator, *, weights, gain: float,
                             initial_radii, dynamics=None, known_linear: bool = True,
                             guard: float = 0.0, slope_window: int = 8,
                             fmi_version: str = "2.0") -> LoopResult:
    """Run the adaptive compensation loop with the three FMUs in ``fmu_dir`` (as written by
    :func:`~pimodel.fmu.build_fmus` for that ``fmi_version``)."""
    fmu_dir = Path(fmu_dir)
    files = {name: fmu_dir / fmu_filename(name, fmi_version)
             for name in ("PIHysteresis", "RadiusEstimator", "InversePI")}
    ref = np.asarray(ref, float)
    w = np.asarray(weights, float)
    n = w.size
    plant_fmu = FMUUnit(files["PIHysteresis"], {
        "Ts": dt, "n": plant.n, **_arrays("p", plant.weights), **_arrays("r", plant.radii)},
        instance_name="plant")
    est = FMUUnit(files["RadiusEstimator"], {
        "Ts": dt, "n": n, "gain": gain, "linear_play": known_linear, "guard": guard,
        "slope_window": slope_window, **_arrays("p", w), **_arrays("r", initial_radii)},
        instance_name="estimator")
    inv = FMUUnit(files["InversePI"], {
        "Ts": dt, "n": n, "adaptive": True, **_arrays("p", w)}, instance_name="inverse")
    if dynamics is not None:
        dyn = control.ss(dynamics)
        A, B, C, D = dyn.A, dyn.B[:, 0], dyn.C[0], float(dyn.D[0, 0])
        xd = np.zeros(dyn.nstates)
    rhat_names = [f"r_hat[{i + 1}]" for i in range(n)]
    N = ref.size
    y, v, R = np.empty(N), np.empty(N), np.empty((N, n))
    try:
        rhat = est.get(rhat_names)
        for k in range(N):
            R[k] = rhat
            inv.set({"y_d": ref[k], **dict(zip(rhat_names, rhat, strict=True))})
            inv.step(dt)
            v[k] = inv.get(["v"])[0]
            plant_fmu.set({"v": v[k]})
            plant_fmu.step(dt)
            h = plant_fmu.get(["y"])[0]
            if dynamics is not None:
                y[k] = C @ xd + D * h
                xd = A @ xd + B * h
            else:
                y[k] = h
            est.set({"v": v[k], "y": y[k]})
            est.step(dt)
            rhat = est.get(rhat_names)
    finally:
        for unit in (plant_fmu, est, inv):
            unit.close()
    return LoopResult(np.arange(N) * dt, ref, y, v, ref - y, R)
