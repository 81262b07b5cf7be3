"""Feedforward with a diagnosed model's inverse, tried on a simulated true stage: open loop
(:func:`open_loop_rms`) and inside an integral feedback loop (:func:`integral_loop`).

The reference is the true stage's own noise-free response to the validate input (reachable by
construction); the feedforward ``v_ff = model.inverse().simulate(y_d)`` drives the noise-free
true stage, and the tracking error ``y - y_d`` is scored after the start-up region (until the
input first spans 90 % of its range: the true stage's initial memory may differ from the
model's plays at rest). The inverse starts from the memory the diagnosis assumed
(:attr:`~pimodel.diagnosis.model.DiagnosedModel.initial_state`): with ``"unknown"`` from the
memory that puts ``y_d[0]`` on the model's output at rest
(:meth:`~pimodel.diagnosis.model.DiagnosedInverse.initial_memory`); a creep carries a start-up
error far beyond the start-up region.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .where import startup_length

__all__ = ["integral_loop", "open_loop_rms"]


def open_loop_rms(truth, t: np.ndarray, v: np.ndarray, models: dict) -> dict:
    """RMS open-loop tracking error of each model's inverse feedforward on ``truth``.

    Parameters
    ----------
    truth : pimodel.stages.pi_stage.Truth or pimodel.stages.preisach_stage.AltTruth
        The simulated stage (its noise is switched off here).
    t, v : numpy.ndarray
        Times [s] and input [V] that make the reference ``y_d`` (the stage's response).
    models : dict
        Name -> model with ``inverse().simulate(y_d)``.

    Returns
    -------
    dict
        Name -> RMS of ``y - y_d`` [output units] after the start-up region.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> from pimodel.stages.pi_stage import Truth
    >>> t = np.arange(2000) * 1e-4
    >>> v = np.sin(2 * np.pi * 5 * t)
    >>> truth = Truth(weights=(1.0, 0.5), radii=(0.0, 0.3))
    >>> m = DiagnosedModel([0.0, 0.3], [1.0, 0.5], 0.0, dt=1e-4)
    >>> bool(open_loop_rms(truth, t, v, {"exact": m})["exact"] < 1e-9)
    True
    """
    quiet = replace(truth, noise_um=0.0) if hasattr(truth, "noise_um") else \
        replace(truth, noise=0.0)
    rng = np.random.default_rng(0)
    y_d = quiet.simulate(t, v, rng)
    start = startup_length(v)
    out = {}
    for name, model in models.items():
        v_ff = model.inverse().simulate(y_d)
        e = quiet.simulate(t, v_ff, rng) - y_d
        out[name] = float(np.sqrt(np.mean(e[start:] ** 2)))
    return out


def _loop_inputs(t, ff, y_d) -> tuple[np.ndarray, np.ndarray, float]:
    t, ff, y_d = (np.asarray(x, float) for x in (t, ff, y_d))
    if t.ndim != 1 or t.size < 2 or ff.shape != t.shape or y_d.shape != t.shape:
        raise ValueError(f"ff, y_d: expected {t.size} samples like t, got {ff.shape} and "
                         f"{y_d.shape}")
    if not (np.all(np.isfinite(ff)) and np.all(np.isfinite(y_d))):
        raise ValueError("ff, y_d: expected finite values")
    dt = float(t[1] - t[0])
    if not dt > 0:
        raise ValueError(f"t: expected increasing times, got a step of {dt!r} s")
    return ff, y_d, dt


def integral_loop(step, t, ff, y_d, ki: float) -> tuple[np.ndarray, np.ndarray]:
    """Feedforward plus integral feedback around a stage given sample by sample.

    Per sample k: ``v[k] = ff[k] + u[k]``, ``y[k] = step(t[k], v[k])``, and
    ``u[k + 1] = u[k] + ki dt (y_d[k] - y[k])`` from ``u[0] = 0``: the backward-Euler integral
    of the compensation study's loop (:func:`pimodel.experiments.compensation.compensation_table`),
    with one sample of computation delay, because the stage passes ``v[k]`` to ``y[k]`` directly.

    Parameters
    ----------
    step : callable
        ``step(t_k, v_k) -> y_k``, the stage advanced by one sample.
    t : array_like
        Sample times [s], constant step ``dt``.
    ff : array_like
        Feedforward input [input units], e.g. a model's ``inverse().simulate(y_d)``.
    y_d : array_like
        Reference [output units].
    ki : float
        Integral gain [input units per output unit and second].

    Returns
    -------
    v, y : numpy.ndarray
        The stage's input and output.

    Raises
    ------
    ValueError
        Lengths that differ from ``t``, values that are not finite, times not increasing.

    Examples
    --------
    >>> t = np.arange(4000) * 1e-4
    >>> y_d = np.full(t.size, 1.0)
    >>> v, y = integral_loop(lambda tk, vk: 2.0 * vk, t, np.zeros(t.size), y_d, ki=50.0)
    >>> round(float(y[-1]), 6)            # the integral removes the static error
    1.0
    """
    ff, y_d, dt = _loop_inputs(t, ff, y_d)
    t = np.asarray(t, float)
    v, y = np.empty(ff.size), np.empty(ff.size)
    u = 0.0
    for k in range(ff.size):
        v[k] = ff[k] + u
        y[k] = step(t[k], v[k])
        u += ki * dt * (y_d[k] - y[k])
    return v, y
