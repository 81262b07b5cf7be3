"""Plain NumPy reference implementations: the readable specification of the operators.

These per-sample loops define the discrete-time semantics; the compiled core
(:mod:`pimodel._native`) must agree with them to 1e-12 (``tests/test_native_equals_reference``).
They favour clarity over speed.
"""

from __future__ import annotations

import numpy as np


def play_reference(v: np.ndarray, r: float, x: float = 0.0) -> np.ndarray:
    """Play operator: ``z[k] = max(v[k] - r, min(v[k] + r, z[k-1]))`` with ``z[-1] = x``."""
    z = np.empty(len(v))
    prev = x
    for k, vk in enumerate(v):
        prev = max(vk - r, min(vk + r, prev))
        z[k] = prev
    return z


def pi_reference(
    v: np.ndarray, weights: np.ndarray, radii: np.ndarray, state: np.ndarray | float = 0.0
) -> np.ndarray:
    """PI operator ``y[k] = sum_i p_i z_i[k]``, one NumPy step per sample over all plays."""
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
    """Time-dependent PI operator (paper eq. 7): radius ``R[k, i]`` used at step k."""
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
    """Inverse weights and radii by the Krejci-Kuhnen formulas (NOTES.md), written literally."""
    p = np.asarray(weights, float)
    r = np.asarray(radii, float)
    P = np.cumsum(p)
    rinv = np.array([sum(p[j] * (r[i] - r[j]) for j in range(i + 1)) for i in range(len(p))])
    pinv = np.empty_like(p)
    pinv[0] = 1.0 / p[0]
    pinv[1:] = -p[1:] / (P[1:] * P[:-1])
    return pinv, rinv
