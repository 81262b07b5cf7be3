"""Plain NumPy reference implementations: the readable specification of the operators.

These per-sample loops define the discrete-time semantics; the compiled core
(:mod:`pimodel._native`) must agree with them to 1e-12 (``tests/test_native_equals_reference``).
They favour clarity over speed.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "pi_inverse_reference",
    "pi_reference",
    "play_reference",
    "tdpi_reference",
]


def play_reference(v: np.ndarray, r: float, x: float = 0.0) -> np.ndarray:
    """Play (backlash) operator of radius ``r``, one sample at a time.

    ``z[k] = max(v[k] - r, min(v[k] + r, z[k-1]))`` with ``z[-1] = x``.

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples (input unit, e.g. V).
    r : float
        Radius (input unit), ``>= 0``. Not checked: this is the specification, not the API.
    x : float, optional
        Initial state ``z[-1]`` (default 0).

    Returns
    -------
    numpy.ndarray of float, shape (N,)
        The play output ``z[k]`` (input unit).

    See Also
    --------
    pimodel.PIOperator : the compiled operator held equal to this reference.

    Examples
    --------
    >>> from pimodel.reference import play_reference
    >>> play_reference([0.0, 1.0, 0.5, -1.0], r=0.25)
    array([ 0.  ,  0.75,  0.75, -0.75])
    """
    z = np.empty(len(v))
    prev = x
    for k, vk in enumerate(v):
        prev = max(vk - r, min(vk + r, prev))
        z[k] = prev
    return z


def pi_reference(
    v: np.ndarray, weights: np.ndarray, radii: np.ndarray, state: np.ndarray | float = 0.0
) -> np.ndarray:
    """PI operator ``y[k] = sum_i p_i z_i[k]``, one NumPy step per sample over all plays.

    Each play ``z_i`` follows :func:`play_reference` with radius ``r_i``; ``y[k]`` depends on
    ``v[0..k]`` (direct feedthrough).

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples (input unit).
    weights : array_like of float, shape (n,)
        Play weights ``p_i`` (output unit per input unit).
    radii : array_like of float, shape (n,)
        Play radii ``r_i`` (input unit).
    state : float or array_like of float, shape (n,), optional
        Initial play states ``z_i[-1]`` (default 0).

    Returns
    -------
    numpy.ndarray of float, shape (N,)
        The output ``y[k]`` (output unit).

    Examples
    --------
    >>> from pimodel.reference import pi_reference
    >>> pi_reference([0.0, 1.0, 0.0], weights=[1.0, 0.5], radii=[0.0, 0.5])
    array([0.  , 1.25, 0.25])
    """
    p = np.asarray(weights, float)
    r = np.asarray(radii, float)
    z = np.broadcast_to(np.asarray(state, float), p.shape).copy()
    y = np.empty(len(v))
    for k, vk in enumerate(v):
        z = np.maximum(vk - r, np.minimum(vk + r, z))
        y[k] = p @ z
    return y


def tdpi_reference(
    v: np.ndarray, weights: np.ndarray, radii_per_sample: np.ndarray,
    state: np.ndarray | float = 0.0,
) -> np.ndarray:
    """Time-dependent PI operator (paper eq. 7): radius ``R[k, i]`` used at step k.

    ``z_i[k] = max(v[k] - R[k, i], min(v[k] + R[k, i], z_i[k-1]))`` and
    ``y[k] = sum_i p_i z_i[k]``: the adaptive estimator's model, whose radii change with time.

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples (input unit).
    weights : array_like of float, shape (n,)
        Play weights ``p_i``.
    radii_per_sample : array_like of float, shape (N, n)
        Radius ``R[k, i]`` of play ``i`` at sample ``k`` (input unit).
    state : float or array_like of float, shape (n,), optional
        Initial play states ``z_i[-1]`` (default 0).

    Returns
    -------
    numpy.ndarray of float, shape (N,)
        The output ``y[k]``.

    Examples
    --------
    >>> from pimodel.reference import tdpi_reference
    >>> tdpi_reference([1.0, 0.0], [1.0], [[0.0], [0.5]])   # radius 0, then 0.5
    array([1. , 0.5])
    """
    p = np.asarray(weights, float)
    R = np.asarray(radii_per_sample, float)
    z = np.broadcast_to(np.asarray(state, float), p.shape).copy()
    y = np.empty(len(v))
    for k, vk in enumerate(v):
        z = np.maximum(vk - R[k], np.minimum(vk + R[k], z))
        y[k] = p @ z
    return y


def pi_inverse_reference(
    weights: np.ndarray, radii: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Inverse weights and radii by the Krejci-Kuhnen formulas, written literally.

    With ``P_i = p_1 + ... + p_i``: ``p'_1 = 1 / p_1``, ``p'_i = -p_i / (P_i P_{i-1})`` and
    ``r'_i = sum_{j <= i} p_j (r_i - r_j)``. Needs sorted radii with ``r_1 = 0``.

    Parameters
    ----------
    weights : array_like of float, shape (n,)
        Forward weights ``p_i > 0`` (output unit per input unit).
    radii : array_like of float, shape (n,)
        Forward radii, ascending, ``r_1 = 0`` (input unit).

    Returns
    -------
    weights : numpy.ndarray of float, shape (n,)
        Inverse weights ``p'_i`` (signed; every partial sum is positive).
    radii : numpy.ndarray of float, shape (n,)
        Inverse radii ``r'_i`` (output unit).

    See Also
    --------
    pimodel.PIOperator.inverse : the operator's inverse, held equal to these formulas.

    Examples
    --------
    >>> from pimodel.reference import pi_inverse_reference
    >>> pi_inverse_reference([1.0, 1.0], [0.0, 0.5])
    (array([ 1. , -0.5]), array([0. , 0.5]))
    """
    p = np.asarray(weights, float)
    r = np.asarray(radii, float)
    P = np.cumsum(p)
    rinv = np.array([sum(p[j] * (r[i] - r[j]) for j in range(i + 1)) for i in range(len(p))])
    pinv = np.empty_like(p)
    pinv[0] = 1.0 / p[0]
    pinv[1:] = -p[1:] / (P[1:] * P[:-1])
    return pinv, rinv
