"""Argument validation: every error names the argument and what was expected."""

from __future__ import annotations

import numpy as np

__all__ = [
    "as_signal",
    "as_vector",
    "integer_in",
    "positive_scalar",
    "scalar_or_vector",
]


def as_signal(value, name: str, *, min_length: int = 1) -> np.ndarray:
    """Return ``value`` as a finite 1-D float64 array, or raise ValueError naming ``name``.

    Parameters
    ----------
    value : array_like
        The samples; a scalar becomes one sample.
    name : str
        The argument's name, used in the error message.
    min_length : int, optional
        Fewest samples accepted. Default 1.

    Returns
    -------
    numpy.ndarray of float64
        A C-contiguous 1-D array.

    Raises
    ------
    ValueError
        If ``value`` is not numeric, not 1-D, too short, or holds a NaN/inf (the first one is
        named by its index).

    Examples
    --------
    >>> as_signal([0, 1, 2], "v")
    array([0., 1., 2.])
    >>> as_signal([0.0, float("nan")], "v")
    Traceback (most recent call last):
    ...
    ValueError: v: sample 1 is nan; all samples must be finite (1 non-finite in total)
    """
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
    """Return a finite 1-D float64 parameter vector (at least one entry, optional length).

    Parameters
    ----------
    value : array_like
        The entries; a scalar becomes one entry.
    name : str
        The parameter's name, used in the error message.
    length : int, optional
        Required number of entries.

    Returns
    -------
    numpy.ndarray of float64
        A C-contiguous 1-D array.

    Raises
    ------
    ValueError
        As :func:`as_signal`, or if the length differs from ``length``.

    Examples
    --------
    >>> as_vector(0.5, "radii")
    array([0.5])
    >>> as_vector([1.0, 2.0], "weights", length=3)
    Traceback (most recent call last):
    ...
    ValueError: weights: expected 3 values, got 2
    """
    arr = as_signal(value, name)
    if length is not None and arr.shape[0] != length:
        raise ValueError(f"{name}: expected {length} values, got {arr.shape[0]}")
    return arr


def scalar_or_vector(value, name: str, n: int, *, one_per: str | None = None) -> np.ndarray:
    """Return ``value`` as ``n`` finite floats: a scalar repeated ``n`` times, or n values.

    The form of an operator's (initial) state and of per-play settings such as gains.

    Parameters
    ----------
    value : float or array_like
        One value for all entries, or ``n`` values.
    name : str
        The argument's name, used in the error message.
    n : int
        Number of entries (plays, lags).
    one_per : str, optional
        What one entry belongs to (e.g. ``"play"``); the message then says ``(one per play)``.

    Returns
    -------
    numpy.ndarray of float64, shape (n,)
        A new array (never a view of ``value``).

    Raises
    ------
    ValueError
        As :func:`as_vector`, or if ``value`` holds neither 1 nor ``n`` values.

    Examples
    --------
    >>> scalar_or_vector(0.5, "initial_state", 3)
    array([0.5, 0.5, 0.5])
    >>> scalar_or_vector([1.0, 2.0], "state", 3, one_per="play")
    Traceback (most recent call last):
    ...
    ValueError: state: expected a scalar or 3 values (one per play), got 2
    """
    arr = as_vector(value, name)
    if arr.size not in (1, n):
        per = f" (one per {one_per})" if one_per else ""
        raise ValueError(f"{name}: expected a scalar or {n} values{per}, got {arr.size}")
    return np.broadcast_to(arr, (n,)).copy()


def positive_scalar(value, name: str) -> float:
    """Return ``value`` as a finite float > 0, or raise ValueError naming ``name``.

    Parameters
    ----------
    value : float
        The number (anything ``float()`` accepts).
    name : str
        The argument's name, used in the error message.

    Returns
    -------
    float
        ``float(value)``.

    Raises
    ------
    ValueError
        If ``value`` is not a number, not finite or not > 0.

    Examples
    --------
    >>> positive_scalar("1e-3", "dt")
    0.001
    >>> positive_scalar(0, "dt")
    Traceback (most recent call last):
    ...
    ValueError: dt: expected a finite number > 0, got 0
    """
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

    Parameters
    ----------
    value : int
        The value to check.
    name : str
        The argument's name, used in the error message.
    lo : int
        Smallest value accepted.
    hi : int, optional
        Largest value accepted (default: no upper bound).

    Returns
    -------
    int
        ``value`` as a Python int.

    Raises
    ------
    ValueError
        If ``value`` is not an integer or lies outside ``[lo, hi]``.

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
