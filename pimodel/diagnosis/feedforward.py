"""Open-loop feedforward with a diagnosed model's inverse, tried on a simulated true stage.

The reference is the true stage's own noise-free response to the validate input (reachable by
construction); the feedforward ``v_ff = model.inverse().simulate(y_d)`` drives the noise-free
true stage, and the tracking error ``y - y_d`` is scored after the start-up region (until the
input first spans 90 % of its range: the true stage's initial memory may differ from the
model's plays at rest).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .where import startup_length

__all__ = ["open_loop_rms"]


def open_loop_rms(truth, t: np.ndarray, v: np.ndarray, models: dict) -> dict:
    """RMS open-loop tracking error of each model's inverse feedforward on ``truth``.

    Parameters
    ----------
    truth : pimodel.truth.Truth or pimodel.truth_alt.AltTruth
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
    >>> from pimodel.truth import Truth
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
