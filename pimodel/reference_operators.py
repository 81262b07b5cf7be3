"""Plain NumPy/SciPy references for the generalized, rate-dependent and creep operators: the
readable specification the C core (:mod:`pimodel.generalized`, :mod:`pimodel.rate_dependent`,
:mod:`pimodel.creep`) is held equal to (1e-12) by ``tests/test_operators_native_reference.py``.

The inverses are computed by other means than the C core: the rate-dependent inverse by
root bracketing (``scipy.optimize.brentq``) of the step equation, the creep inverse by
a triangular solve with the Toeplitz matrix of G's impulse response.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_triangular, toeplitz
from scipy.optimize import brentq

from .envelopes import Envelope
from .reference import pi_reference, tdpi_reference


def gpi_reference(v, weights, radii, input_envelope: Envelope, output_envelope: Envelope,
                  state=0.0) -> np.ndarray:
    """``y[k] = g(sum_i p_i z_i[k])``, ``z_i[k] = clamp(z_i[k-1], h(v[k]) -+ r_i)``."""
    u = input_envelope.reference(np.asarray(v, float))
    return output_envelope.reference(pi_reference(u, weights, radii, state))


def _rates(v_prev: float, rate: float, lam: float, dt: float, v: np.ndarray) -> np.ndarray:
    """``rate[k]`` for every k (``rate[k+1] = lam rate[k] + (1 - lam) |v[k] - v[k-1]| / dt``)."""
    out = np.empty(len(v))
    for k, vk in enumerate(v):
        out[k] = rate
        rate = lam * rate + (1 - lam) * abs(vk - v_prev) / dt
        v_prev = vk
    return out


def rdpi_reference(v, weights, base_radii, rate_gain: float, dt: float, *, lam: float = 0.0,
                   state=0.0, v_prev: float = 0.0, rate: float = 0.0) -> np.ndarray:
    """Rate-dependent PI: radii ``alpha (1 + beta rate[k])``, then the time-dependent PI."""
    p, a = np.asarray(weights, float), np.asarray(base_radii, float)
    v = np.asarray(v, float)
    R = a[None, :] * (1 + rate_gain * _rates(v_prev, rate, lam, dt, v))[:, None]
    return tdpi_reference(v, p, R, state)


def rdpi_inverse_reference(y_d, weights, base_radii, rate_gain: float, dt: float, *,
                           lam: float = 0.0, state=0.0, v_prev: float = 0.0,
                           rate: float = 0.0) -> np.ndarray:
    """``v[k]`` solving the forward step equation by bracketing (``brentq``), sample by sample."""
    p, a = np.asarray(weights, float), np.asarray(base_radii, float)
    z = np.broadcast_to(np.asarray(state, float), p.shape).copy()
    v = np.empty(len(y_d))
    for k, yk in enumerate(np.asarray(y_d, float)):
        r = a * (1 + rate_gain * rate)

        def f(x, r=r, z=z, yk=yk):
            return p @ np.maximum(x - r, np.minimum(x + r, z)) - yk

        lo = min(z.min() - r.max(), 0.0) - abs(yk) / p.sum() - 1.0
        hi = max(z.max() + r.max(), 0.0) + abs(yk) / p.sum() + 1.0
        vk = brentq(f, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=500)
        z = np.maximum(vk - r, np.minimum(vk + r, z))
        rate = lam * rate + (1 - lam) * abs(vk - v_prev) / dt
        v_prev = vk
        v[k] = vk
    return v


def creep_reference(u, gains, time_constants, dt: float, state=0.0) -> np.ndarray:
    """``y[k] = u[k] + sum_i c_i x_i[k]``, ``x_i[k+1] = a_i x_i[k] + (1 - a_i) u[k]``."""
    c, tau = np.asarray(gains, float), np.asarray(time_constants, float)
    a = np.exp(-dt / tau)
    x = np.broadcast_to(np.asarray(state, float), c.shape).copy()
    y = np.empty(len(u))
    for k, uk in enumerate(np.asarray(u, float)):
        y[k] = uk + c @ x
        x = a * x + (1 - a) * uk
    return y


def creep_inverse_reference(y, gains, time_constants, dt: float) -> np.ndarray:
    """``u = G^-1[y]`` from zero state by solving the lower-triangular Toeplitz system of G's
    impulse response ``g[0] = 1``, ``g[j] = sum_i c_i (1 - a_i) a_i^(j-1)`` (O(N^2) memory:
    short records only)."""
    c, tau = np.asarray(gains, float), np.asarray(time_constants, float)
    a = np.exp(-dt / tau)
    y = np.asarray(y, float)
    j = np.arange(1, len(y))
    g = np.concatenate(([1.0], (c * (1 - a)) @ (a[:, None] ** (j[None, :] - 1))))
    T = toeplitz(g, np.zeros(len(y)))
    return solve_triangular(T, y, lower=True)


def asym_reference(v, direct_weight: float, weights, radii, ascending, descending,
                   shape: Envelope, state=0.0) -> np.ndarray:
    """``y[k] = p0 s + sum p_i z_i``, ``z_i = max(a_l s + d_l - r_i, min(a_r s + d_r + r_i,
    z_i))``, ``s = phi(v[k])``."""
    p, r = np.asarray(weights, float), np.asarray(radii, float)
    (al, dl), (ar, dr) = ascending, descending
    z = np.broadcast_to(np.asarray(state, float), p.shape).copy()
    s = shape.reference(np.asarray(v, float))
    y = np.empty(len(s))
    for k, sk in enumerate(s):
        z = np.maximum(al * sk + dl - r, np.minimum(ar * sk + dr + r, z))
        y[k] = direct_weight * sk + p @ z
    return y


def asym_inverse_reference(y_d, direct_weight: float, weights, radii, ascending, descending,
                           shape: Envelope, state=0.0) -> np.ndarray:
    """Inverse by bracketing (``brentq``) the step equation in ``s``, then ``phi^-1``."""
    p, r = np.asarray(weights, float), np.asarray(radii, float)
    (al, dl), (ar, dr) = ascending, descending
    z = np.broadcast_to(np.asarray(state, float), p.shape).copy()
    v = np.empty(len(y_d))
    for k, yk in enumerate(np.asarray(y_d, float)):

        def f(s, z=z, yk=yk):
            return direct_weight * s + p @ np.maximum(al * s + dl - r,
                                                      np.minimum(ar * s + dr + r, z)) - yk

        lo, hi = -1.0, 1.0
        while f(lo) > 0:
            lo *= 2
        while f(hi) < 0:
            hi *= 2
        sk = brentq(f, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=500)
        z = np.maximum(al * sk + dl - r, np.minimum(ar * sk + dr + r, z))
        v[k] = shape.inverse().reference(np.array([sk]))[0]
    return v
