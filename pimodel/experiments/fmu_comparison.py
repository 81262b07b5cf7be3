"""The adaptive compensation loop of the piezo-like stage run as an FMU co-simulation and as the
native compiled loop, side by side (used by ``pimodel demo`` and ``studies/cosimulation.py``).

Loop: a 5 Hz triangle of the stage's own output as reference (10 kHz), the stage's hysteresis
(PIHysteresis FMU) followed by a 1 kHz mode (damping 0.05), the RadiusEstimator FMU and the
adaptive InversePI FMU; the native loop is :func:`pimodel.loops.compiled.run_loop` with the same
estimator settings.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..blocks.pi import radius_estimator
from ..fmu.cosim import cosimulate_adaptive_loop
from ..loops.actuators import stage_dynamics
from ..loops.compiled import LoopResult, run_loop
from ..plotting import new_figure, save_figure
from ..signals import triangle
from .compensation import STAGE

__all__ = [
    "compare_with_native",
    "CosimComparison",
    "plot_comparison",
]


DT = 1e-4  # s


@dataclass
class CosimComparison:
    """Both runs, their largest output difference [um] and speeds [steps/s].

    Parameters
    ----------
    cosim : LoopResult
        The FMU co-simulation (``radii`` from the RadiusEstimator FMU).
    native : LoopResult
        The native compiled loop (:func:`pimodel.loops.compiled.run_loop`).
    max_difference : float
        ``max_k |y_cosim[k] - y_native[k]|`` [um].
    cosim_steps_per_s : float
        Samples per second of wall time of the co-simulation (machine and load dependent).
    native_steps_per_s : float
        The same for the native loop.

    Examples
    --------
    A stand-in with the native loop twice (the real one comes from
    :func:`compare_with_native`):

    >>> from pimodel.blocks import radius_estimator
    >>> from pimodel.experiments.compensation import STAGE
    >>> from pimodel.loops.compiled import run_loop
    >>> yd = STAGE.simulate(np.sin(np.linspace(0, 2 * np.pi, 100)))
    >>> est = radius_estimator(STAGE.weights, dt=DT, gains=20.0,
    ...                        initial_radii=[0.0, 0.1, 0.3, 0.5], linear_play=True)
    >>> native = run_loop(yd, STAGE, DT, feedforward="adaptive", estimator=est)
    >>> cmp = CosimComparison(native, native, 0.0, 1e4, 1e6)
    >>> cmp.cosim.radii.shape
    (100, 4)
    """

    cosim: LoopResult
    native: LoopResult
    max_difference: float
    cosim_steps_per_s: float
    native_steps_per_s: float


def compare_with_native(fmu_dir, *, duration: float, weights, initial_radii,
                        gain: float = 20.0, fmi_version: str = "2.0") -> CosimComparison:
    """Run the loop for ``duration`` seconds with the FMUs in ``fmu_dir`` and natively.

    Parameters
    ----------
    fmu_dir : str or Path
        Folder with the PIHysteresis, RadiusEstimator and InversePI FMUs
        (:func:`pimodel.fmu.build_fmus`).
    duration : float
        Length of the 5 Hz triangle reference [s] (sampled every ``DT`` = 0.1 ms).
    weights : array_like of float
        The estimator's and the adaptive inverse's play weights.
    initial_radii : array_like of float
        Start of the radius estimate [V].
    gain : float, optional
        Adaptation gain. Default 20.
    fmi_version : {"2.0", "3.0"}, optional
        Which FMUs to run. Default ``"2.0"``.

    Returns
    -------
    CosimComparison
        Both runs, their largest output difference and speeds.

    Raises
    ------
    FileNotFoundError
        An FMU is missing from ``fmu_dir``.
    ValueError
        An FMU rejected its parameters or failed a step.

    Examples
    --------
    The FMUs must be built first (a compile of a few seconds), hence skipped here:

    >>> import tempfile
    >>> from pimodel.experiments.compensation import STAGE
    >>> from pimodel.fmu import build_fmus
    >>> fmu_dir = tempfile.mkdtemp()
    >>> _ = build_fmus(fmu_dir, ["PIHysteresis", "RadiusEstimator", "InversePI"])  # doctest: +SKIP
    >>> cmp = compare_with_native(fmu_dir, duration=0.01, weights=STAGE.weights,  # doctest: +SKIP
    ...                           initial_radii=[0.0, 0.1, 0.3, 0.5])
    >>> bool(cmp.max_difference < 1e-9), cmp.cosim.y.size  # doctest: +SKIP
    (True, 100)
    """
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
    """Radius estimates of the FMU run (dashed: the stage's radii) and both tracking errors.

    Parameters
    ----------
    cmp : CosimComparison
        From :func:`compare_with_native`.
    path : str or Path
        The PNG file to write.

    Returns
    -------
    pathlib.Path
        The figure file.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from pimodel.blocks import radius_estimator
    >>> from pimodel.experiments.compensation import STAGE
    >>> from pimodel.loops.compiled import run_loop
    >>> yd = STAGE.simulate(np.sin(np.linspace(0, 2 * np.pi, 100)))
    >>> est = radius_estimator(STAGE.weights, dt=DT, gains=20.0,
    ...                        initial_radii=[0.0, 0.1, 0.3, 0.5], linear_play=True)
    >>> native = run_loop(yd, STAGE, DT, feedforward="adaptive", estimator=est)
    >>> cmp = CosimComparison(native, native, 0.0, 1e4, 1e6)
    >>> plot_comparison(cmp, pathlib.Path(tempfile.mkdtemp()) / "loop.png").name
    'loop.png'
    """
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
