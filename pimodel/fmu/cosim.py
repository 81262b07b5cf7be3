"""A fixed-step co-simulation master for the adaptive compensation loop built from FMUs.

Units: PIHysteresis (the plant's hysteresis), RadiusEstimator, InversePI (adaptive mode), and
the linear stage dynamics stepped by the master (discrete state space). Per step k (dt):
InversePI gets ``y_d[k]`` and the estimator's ``r_hat`` (the estimate after step k-1) and gives
``v[k]``; PIHysteresis gives ``h[k] = PI[v][k]``; the master computes ``y[k] = C xd + D h`` and
``xd <- A xd + B h``; the estimator takes ``(v[k], y[k])``. This is the loop of
:func:`pimodel.loops.run_loop` with ``feedforward="adaptive"``, so the two agree exactly.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import control
import numpy as np
from fmpy import read_model_description

from ..blocks.framework import labelled_values, signal_labels
from ..loops.compiled import LoopResult
from ..operators.pi import PIOperator
from .build import fmu_filename
from .unit import FMUUnit

__all__ = ["cosimulate_adaptive_loop"]

LOOP_UNITS = ("PIHysteresis", "RadiusEstimator", "InversePI")  # the FMUs this master runs




def _estimator_unit(path, start: dict) -> FMUUnit:
    """The RadiusEstimator FMU; ``linear_play`` goes to the FMU's variable of that name, or to
    ``known_linear`` in FMUs built before the rename."""
    names = {v.name for v in read_model_description(str(path)).modelVariables}
    if "linear_play" not in names and "known_linear" in names:
        start = dict(start)
        start["known_linear"] = start.pop("linear_play")
    return FMUUnit(path, start, instance_name="estimator")


def cosimulate_adaptive_loop(fmu_dir, ref, dt: float, plant: PIOperator, *, weights, gain: float,
                             initial_radii, dynamics=None, linear_play: bool = True,
                             guard: float = 0.0, slope_window: int = 8,
                             fmi_version: str = "2.0", estimator_start: dict | None = None,
                             known_linear: bool | None = None) -> LoopResult:
    """Run the adaptive compensation loop with the three FMUs in ``fmu_dir``.

    Parameters
    ----------
    fmu_dir : str or Path
        Folder with the FMUs as written by :func:`~pimodel.fmu.build_fmus` for ``fmi_version``.
    ref : array_like
        Reference ``y_d[k]`` (desired output).
    dt : float
        Sample and communication step [s] (every unit's ``Ts``).
    plant : PIOperator
        The plant's hysteresis (PIHysteresis FMU).
    weights, gain, initial_radii, linear_play, guard, slope_window
        RadiusEstimator FMU settings (``linear_play`` holds ``r_hat[1] = 0``); ``weights`` is
        also the adaptive inverse's model.
    dynamics : control.StateSpace or LTI, optional
        Discrete SISO stage dynamics after the hysteresis, stepped by the master.
    fmi_version : str
        "2.0" or "3.0".
    estimator_start : dict, optional
        Further RadiusEstimator FMU start values by variable name (new settings pass through).
    known_linear : bool, optional
        Deprecated name of ``linear_play``.

    Returns
    -------
    LoopResult
        ``radii[k]`` is the estimate ``r_hat[1..n]`` the compensator used at step k.

    Raises
    ------
    FileNotFoundError
        A unit's FMU is missing from ``fmu_dir``.
    ValueError
        An FMU rejected its parameters at initialisation or failed a step (its log is in the
        message).

    Examples
    --------
    The three FMUs must be built first (a compile of a few seconds), hence the co-simulation is
    skipped here; the native loop it equals runs in the C core:

    >>> import tempfile
    >>> from pimodel import PIOperator
    >>> from pimodel.blocks import radius_estimator
    >>> from pimodel.fmu import build_fmus
    >>> from pimodel.loops import run_loop
    >>> plant = PIOperator([1.0, 0.5], [0.0, 0.3])
    >>> ref = np.sin(np.linspace(0, 4 * np.pi, 200))
    >>> est = radius_estimator([1.0, 0.5], dt=1e-3, gains=10.0, initial_radii=[0.0, 0.1],
    ...                        linear_play=True)
    >>> native = run_loop(ref, plant, 1e-3, feedforward="adaptive", estimator=est)
    >>> fmu_dir = tempfile.mkdtemp()
    >>> _ = build_fmus(fmu_dir, LOOP_UNITS)  # doctest: +SKIP
    >>> res = cosimulate_adaptive_loop(fmu_dir, ref, 1e-3, plant, weights=[1.0, 0.5],
    ...                                gain=10.0, initial_radii=[0.0, 0.1])  # doctest: +SKIP
    >>> bool(np.allclose(res.y, native.y, atol=1e-12)), res.radii.shape  # doctest: +SKIP
    (True, (200, 2))
    """
    if known_linear is not None:
        warnings.warn("cosimulate_adaptive_loop: known_linear is deprecated; use linear_play",
                      DeprecationWarning, stacklevel=2)
        linear_play = known_linear
    fmu_dir = Path(fmu_dir)
    files = {name: fmu_dir / fmu_filename(name, fmi_version)
             for name in ("PIHysteresis", "RadiusEstimator", "InversePI")}
    ref = np.asarray(ref, float)
    w = np.asarray(weights, float)
    n = w.size
    plant_fmu = FMUUnit(files["PIHysteresis"], {
        "Ts": dt, "n": plant.n, **labelled_values("p", plant.weights),
        **labelled_values("r", plant.radii)},
        instance_name="plant")
    est = _estimator_unit(files["RadiusEstimator"], {
        "Ts": dt, "n": n, "gain": gain, "linear_play": linear_play, "guard": guard,
        "slope_window": slope_window, **labelled_values("p", w),
        **labelled_values("r", initial_radii),
        **(estimator_start or {})})
    inv = FMUUnit(files["InversePI"], {
        "Ts": dt, "n": n, "adaptive": True, **labelled_values("p", w)}, instance_name="inverse")
    if dynamics is not None:
        dyn = control.ss(dynamics)
        A, B, C, D = dyn.A, dyn.B[:, 0], dyn.C[0], float(dyn.D[0, 0])
        xd = np.zeros(dyn.nstates)
    rhat_names = signal_labels("r_hat", n)
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
