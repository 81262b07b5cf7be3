"""The check of the signals the diagnosed model, its inverse and their C runners take."""

from __future__ import annotations

import numpy as np

__all__ = ["checked_signal"]


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
