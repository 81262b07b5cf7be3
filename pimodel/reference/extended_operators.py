"""Plain NumPy/SciPy references for the generalized, rate-dependent and creep operators: the
readable specification the C core (:mod:`pimodel.operators.generalized`,
:mod:`pimodel.operators.rate_dependent`,
:mod:`pimodel.operators.creep`) is held equal to (1e-12) by
``tests/test_operators_native_reference.py``.

The inverses are computed by other means than the C core: the rate-dependent inverse by
root bracketing (``scipy.optimize.brentq``) of the step equation, the creep inverse by
a triangular solve with the Toeplitz matrix of G's impulse response.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_triangular, toeplitz
from scipy.optimize import brentq

from ..operators.envelopes import Envelope
from .operators import pi_reference, tdpi_reference

__all__ = [
    "asym_inverse_reference",
    "asym_reference",
    "creep_inverse_reference",
    "creep_reference",
    "gpi_reference",
    "rdpi_inverse_reference",
    "rdpi_reference",
]


def gpi_reference(v, weights, radii, input_envelope: Envelope, output_envelope: Envelope,
                  state=0.0) -> np.ndarray:
    """Generalized PI: ``y[k] = g(sum_i p_i z_i[k])``, ``z_i[k] = clamp(z_i[k-1], h(v[k]) -+ r_i)``.

    Parameters
    ----------
    v : array_like
        Input samples.
    weights : array_like
        Play weights ``p_i``.
    radii : array_like
        Play radii ``r_i``.
    input_envelope : Envelope
        Input envelope ``h``.
    output_envelope : Envelope
        Output envelope ``g``.
    state : float or array_like, optional
        Initial play states ``z_i``.

    Returns
    -------
    numpy.ndarray
        Output samples ``y``.

    Examples
    --------
    >>> from pimodel.operators.envelopes import Envelope
    >>> I = Envelope.identity()
    >>> np.round(gpi_reference([0.0, 1.0, 0.5, 0.0], [1.0, 0.5], [0.0, 0.3], I, I), 4)
    array([0.  , 1.35, 0.85, 0.15])
    """
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
    """Rate-dependent PI: radii ``alpha (1 + beta rate[k])``, then the time-dependent PI.

    Parameters
    ----------
    v : array_like
        Input samples.
    weights : array_like
        Play weights ``p_i``.
    base_radii : array_like
        Base radii ``alpha_i``.
    rate_gain : float
        ``beta``: radii grow as ``alpha (1 + beta rate)``.
    dt : float
        Sample period.
    lam : float, optional
        Rate filter pole (0: the last difference quotient).
    state : float or array_like, optional
        Initial play states.
    v_prev : float, optional
        Input before the first sample.
    rate : float, optional
        Initial filtered rate.

    Returns
    -------
    numpy.ndarray
        Output samples.

    Examples
    --------
    >>> np.round(rdpi_reference([0.0, 1.0, 0.5, 0.0], [1.0, 0.5], [0.0, 0.3], 0.1, 0.01), 4)
    array([0.  , 1.35, 0.85, 0.35])
    """
    p, a = np.asarray(weights, float), np.asarray(base_radii, float)
    v = np.asarray(v, float)
    R = a[None, :] * (1 + rate_gain * _rates(v_prev, rate, lam, dt, v))[:, None]
    return tdpi_reference(v, p, R, state)


def rdpi_inverse_reference(y_d, weights, base_radii, rate_gain: float, dt: float, *,
                           lam: float = 0.0, state=0.0, v_prev: float = 0.0,
                           rate: float = 0.0) -> np.ndarray:
    """Inverse rate-dependent PI: ``v[k]`` solving the forward step equation by bracketing
    (``brentq``), sample by sample.

    Parameters
    ----------
    y_d : array_like
        Desired output samples.
    weights : array_like
        Play weights ``p_i``.
    base_radii : array_like
        Base radii ``alpha_i``.
    rate_gain : float
        ``beta``: radii grow as ``alpha (1 + beta rate)``.
    dt : float
        Sample period.
    lam : float, optional
        Rate filter pole (0: the last difference quotient).
    state : float or array_like, optional
        Initial play states.
    v_prev : float, optional
        Input before the first sample.
    rate : float, optional
        Initial filtered rate.

    Returns
    -------
    numpy.ndarray
        Input samples ``v`` that produce ``y_d``.

    Examples
    --------
    >>> v = rdpi_inverse_reference([0.0, 1.2, 0.5, 0.0], [1.0, 0.5], [0.0, 0.3], 0.1, 0.01)
    >>> np.round(v, 4) + 0.0  # + 0.0 turns -0.0 into 0.0
    array([ 0. ,  0.9,  0.2, -0.3])
    """
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
    """Creep operator ``y = G[u]``.

    ``y[k] = u[k] + sum_i c_i x_i[k]``, ``x_i[k+1] = a_i x_i[k] + (1 - a_i) u[k]``.

    Parameters
    ----------
    u : array_like
        Input samples.
    gains : array_like
        Creep gains ``c_i``.
    time_constants : array_like
        Creep time constants ``tau_i`` (``a_i = exp(-dt / tau_i)``).
    dt : float
        Sample period.
    state : float or array_like, optional
        Initial creep states ``x_i``.

    Returns
    -------
    numpy.ndarray
        Output samples ``y``.

    Examples
    --------
    >>> np.round(creep_reference([1.0, 1.0, 1.0, 1.0], [0.1], [0.02], 0.01), 4)
    array([1.    , 1.0393, 1.0632, 1.0777])
    """
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
    short records only).

    Parameters
    ----------
    y : array_like
        Output samples.
    gains : array_like
        Creep gains ``c_i``.
    time_constants : array_like
        Creep time constants ``tau_i`` (``a_i = exp(-dt / tau_i)``).
    dt : float
        Sample period.

    Returns
    -------
    numpy.ndarray
        Input samples ``u`` with ``creep_reference(u, ...) == y``.

    Examples
    --------
    >>> np.round(creep_inverse_reference([1.0, 1.0, 1.0, 1.0], [0.1], [0.02], 0.01), 4)
    array([1.    , 0.9607, 0.9383, 0.9257])
    """
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
    z_i))``, ``s = phi(v[k])`` (asymmetric PI).

    Parameters
    ----------
    v : array_like
        Input samples.
    direct_weight : float
        ``p0``, the weight of the direct term.
    weights : array_like
        Play weights ``p_i``.
    radii : array_like
        Play radii ``r_i``.
    ascending : tuple of float
        ``(a_l, d_l)``, slope and offset of the ascending boundary.
    descending : tuple of float
        ``(a_r, d_r)``, slope and offset of the descending boundary.
    shape : Envelope
        Input shaping ``phi``.
    state : float or array_like, optional
        Initial play states.

    Returns
    -------
    numpy.ndarray
        Output samples ``y``.

    Examples
    --------
    >>> from pimodel.operators.envelopes import Envelope
    >>> I = Envelope.identity()
    >>> v = [0.0, 1.0, 0.5, 0.0]
    >>> np.round(asym_reference(v, 0.5, [1.0], [0.2], (1.0, 0.0), (1.0, 0.0), I), 4)
    array([0.  , 1.3 , 0.95, 0.2 ])
    """
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
    """Inverse asymmetric PI by bracketing (``brentq``) the step equation in ``s``, then ``phi^-1``.

    Parameters
    ----------
    y_d : array_like
        Desired output samples.
    direct_weight : float
        ``p0``, the weight of the direct term.
    weights : array_like
        Play weights ``p_i``.
    radii : array_like
        Play radii ``r_i``.
    ascending : tuple of float
        ``(a_l, d_l)``, slope and offset of the ascending boundary.
    descending : tuple of float
        ``(a_r, d_r)``, slope and offset of the descending boundary.
    shape : Envelope
        Input shaping ``phi``.
    state : float or array_like, optional
        Initial play states.

    Returns
    -------
    numpy.ndarray
        Input samples ``v`` that produce ``y_d``.

    Examples
    --------
    >>> from pimodel.operators.envelopes import Envelope
    >>> I = Envelope.identity()
    >>> y_d = [0.0, 1.3, 0.5, 0.0]
    >>> v = asym_inverse_reference(y_d, 0.5, [1.0], [0.2], (1.0, 0.0), (1.0, 0.0), I)
    >>> np.round(v, 4) + 0.0  # + 0.0 turns -0.0 into 0.0
    array([ 0.    ,  1.    ,  0.2   , -0.1333])
    """
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
