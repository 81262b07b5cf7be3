"""Argument validation: every error names the argument and what was expected."""

from __future__ import annotations

import numpy as np


def as_signal(value, name: str, *, min_length: int = 1) -> np.ndarray:
    """Return ``value`` as a finite 1-D float64 array, or raise ValueError naming ``name``."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected a 1-D array of numbers ({exc})") from None
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ValueError(f"{name}: expected a 1-D array, got shape {arr.shape}")
    if arr.shape[0] < min_length:
        raise ValueError(
            f"{name}: expected at least {min_length} sample(s), got {arr.shape[0]}"
        )
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise ValueError(
            f"{name}: sample {bad[0]} is {float(arr[bad[0]])!r}; all samples must be finite "
            f"({bad.size} non-finite in total)"
        )
    return np.ascontiguousarray(arr)


def as_vector(value, name: str, *, length: int | None = None) -> np.ndarray:
    """Return a finite 1-D float64 parameter vector (at least one entry, optional length)."""
    arr = as_signal(value, name)
    if length is not None and arr.shape[0] != length:
        raise ValueError(f"{name}: expected {length} values, got {arr.shape[0]}")
    return arr


def positive_scalar(value, name: str) -> float:
    """Return ``value`` as a finite float > 0, or raise ValueError naming ``name``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a positive number, got {value!r}") from None
    if not np.isfinite(x) or x <= 0:
        raise ValueError(f"{name}: expected a finite number > 0, got {value!r}")
    return x


def integer_in(value, name: str, lo: int, hi: int | None = None) -> int:
    """``value`` as an int in ``[lo, hi]``, else a ValueError naming ``name``.

    Accepts Python and NumPy integers; rejects floats (also integral ones such as ``4.0``),
    booleans and anything else with a message saying what was given.

    Examples
    --------
    >>> integer_in(4, "n_plays", 1, 64)
    4
    """
    rng = f"from {lo} to {hi}" if hi is not None else f">= {lo}"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        kind = type(value).__name__
        hint = ""
        if isinstance(value, (float, np.floating)) and np.isfinite(value) and \
                float(value).is_integer():
            hint = f"; write {int(value)}"
        raise ValueError(f"{name}: expected an integer {rng}, got {value!r} (a {kind}{hint})")
    if value < lo or (hi is not None and value > hi):
        raise ValueError(f"{name}: expected an integer {rng}, got {value!r}")
    return int(value)
