"""The adaptive compensation loop of the piezo-like stage run as an FMU co-simulation and as the
native compiled loop, side by side (used by ``pimodel demo`` and ``studies/cosimulation.py``).

Loop: a 5 Hz triangle of the stage's own output as reference (10 kHz), the stage's hysteresis
(PIHysteresis FMU) followed by a 1 kHz mode (damping 0.05), the RadiusEstimator FMU and the
adaptive InversePI FMU; the native loop is :func:`pimodel.loops.run_loop` with the same
estimator settings.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..actuators import stage_dynamics
from ..blocks import radius_estimator
from ..compensation import STAGE
from ..loops import LoopResult, run_loop
from ..plotting import new_figure, save_figure
from ..signals import triangle
from .cosim import cosimulate_adaptive_loop

DT = 1e-4  # s


@dataclass
class CosimComparison:
    """Both runs, their largest output difference [um] and speeds [steps/s]."""

    cosim: LoopResult
    native: LoopResult
    max_difference: float
    cosim_steps_per_s: float
    native_steps_per_s: float


def compare_with_native(fmu_dir, *, duration: float, weights, initial_radii,
                        gain: float = 20.0, fmi_version: str = "2.0") -> CosimComparison:
    """Run the loop for ``duration`` seconds with the FMUs in ``fmu_dir`` and natively."""
    _, v = triangle(1.0, 5, fs=1 / DT, duration=duration)
    yd = STAGE.simulate(v)
    G = stage_dynamics(DT, fn_hz=1000, damping=0.05)
    t0 = time.perf_counter()
    co = cosimulate_adaptive_loop(fmu_dir, yd, DT, STAGE, weights=weights, gain=gain,
                                  initial_radii=initial_radii, dynamics=G,
                                  fmi_version=fmi_version)
    t_co = time.perf_counter() - t0
    est = radius_estimator(weights, dt=DT, gains=gain, initial_radii=initial_radii,
                           linear_play=True)
    t0 = time.perf_counter()
    native = run_loop(yd, STAGE, DT, dynamics=G, feedforward="adaptive", estimator=est)
    t_native = time.perf_counter() - t0
    return CosimComparison(co, native, float(np.max(np.abs(co.y - native.y))),
                           yd.size / t_co, yd.size / max(t_native, 1e-9))


def plot_comparison(cmp: CosimComparison, path) -> Path:
    """Radius estimates of the FMU run (dashed: the stage's radii) and both tracking errors."""
    co, t = cmp.cosim, cmp.cosim.t
    fig, ax = new_figure(2, 1)
    for i in range(1, co.radii.shape[1]):
        ax[0, 0].plot(t, co.radii[:, i], label=f"r_hat[{i + 1}] (FMU)")
    for r in STAGE.radii[1:]:
        ax[0, 0].axhline(r, color="0.6", ls="--", lw=0.6)
    ax[0, 0].set(xlabel="time t [s]", ylabel="radius estimate [V]",
                 title="RadiusEstimator FMU in the loop (dashed: truth)")
    ax[0, 0].legend(fontsize=8)
    ax[0, 1].plot(t, co.error, lw=0.8, label="FMU co-simulation")
    ax[0, 1].plot(t, cmp.native.error, "--", lw=0.8, label="native compiled loop")
    ax[0, 1].set(xlabel="time t [s]", ylabel="tracking error [um]",
                 title="Adaptive inverse compensation (1 kHz mode)")
    ax[0, 1].legend(fontsize=8)
    return save_figure(fig, path)
