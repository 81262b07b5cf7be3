"""The checks of the signals and the sample time the diagnosed model, its inverse and their
blocks and C runners take."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["block_dt", "checked_signal"]


def checked_signal(x, name: str) -> np.ndarray:
    """``x`` as a float array, or a ValueError naming ``name``.

    Parameters
    ----------
    x : array_like
        The samples.
    name : str
        The argument's name, for the message.

    Returns
    -------
    numpy.ndarray
        ``x`` as a 1-D float64 array.

    Raises
    ------
    ValueError
        ``x`` not 1-D, shorter than 2 samples, or not finite.

    Examples
    --------
    >>> checked_signal([0, 1], "v").tolist()
    [0.0, 1.0]
    >>> checked_signal([0.0], "v")
    Traceback (most recent call last):
    ...
    ValueError: v: expected a finite 1-D signal of at least 2 samples
    """
    a = np.asarray(x, float)
    if a.ndim != 1 or a.size < 2 or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected a finite 1-D signal of at least 2 samples")
    return a


def block_dt(model, dt: float | None, why: str) -> float:
    """The sample time of a block of ``model``: its ``dt`` (default), or a ValueError.

    Parameters
    ----------
    model : DiagnosedModel
        The model (its ``dt`` [s]).
    dt : float or None
        The block's sample time [s] asked for; None gives the model's.
    why : str
        What of the model is per sample, for the message (``"its filter and delay"``).

    Returns
    -------
    float
        ``model.dt``.

    Raises
    ------
    ValueError
        ``dt`` other than the model's (relative tolerance 1e-12).

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> block_dt(DiagnosedModel([0.0], [1.0], 0.0, dt=1e-3), None, "its delay")
    0.001
    """
    dt = model.dt if dt is None else float(dt)
    if not math.isclose(dt, model.dt, rel_tol=1e-12, abs_tol=0.0):
        raise ValueError(f"dt: {dt!r} differs from the model's dt = {model.dt!r} ({why} are per "
                         "sample of that dt)")
    return model.dt
