"""Loop analysis of a PI operator in python-control's terms: circle criterion, harmonic balance
(limit cycles) and the model error as a residual hysteresis.

The describing function ``N(A)`` itself, the sector and the static gain live with the operator
(:mod:`pimodel.operators.describing_function`, re-exported here). :func:`circle_criterion`
applies the sector ``[k_min, k_max]`` of the loop-branch slopes to the differenced loop,
:func:`harmonic_balance` solves ``1 + N(A) L(jw) = 0``. Units: ``A`` in input units (those of
the radii), ``N`` and gains in output per input unit, frequencies in rad/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np
import scipy.optimize

from ..checks import as_vector
from ..operators.describing_function import (
    PIDescribingFunction,
    _operator,
    play_describing_function,
    sector,
    static_gain,
)
from ..operators.pi import PIOperator

__all__ = [
    "CircleCriterion",
    "LimitCycle",
    "PIDescribingFunction",
    "circle_criterion",
    "harmonic_balance",
    "play_describing_function",
    "residual_hysteresis",
    "sector",
    "static_gain",
]


# -- loop analysis ------------------------------------------------------------------------------


def _freq_response(L, omega) -> np.ndarray:
    """``L`` at ``s = j omega`` (continuous) or ``z = exp(j omega dt)`` (discrete)."""
    w = np.asarray(omega, dtype=float)
    if control.isdtime(L, strict=True):
        return np.asarray(L(np.exp(1j * w * L.dt)), dtype=complex).reshape(w.shape)
    return np.asarray(L(1j * w), dtype=complex).reshape(w.shape)


def _check_siso(L) -> control.LTI:
    if not isinstance(L, control.LTI):
        raise TypeError(f"L: expected a python-control LTI system, got {type(L).__name__}")
    if L.ninputs != 1 or L.noutputs != 1:
        raise ValueError("L: expected a single-input single-output system")
    return L


def _default_omega(L, omega) -> np.ndarray:
    if omega is not None:
        w = as_vector(omega, "omega")
        if np.any(w <= 0):
            raise ValueError("omega: expected frequencies > 0 (rad/s)")
        return np.sort(w)
    poles = np.asarray(control.poles(L))
    if control.isdtime(L, strict=True):
        hi = np.pi / L.dt
        lo = hi * 1e-5
    else:
        mags = np.abs(poles[np.abs(poles) > 0])
        hi = 100 * max(mags.max() if mags.size else 1.0, 1.0)
        lo = 1e-3 * min(mags.min() if mags.size else 1.0, 1.0)
    return np.geomspace(lo, hi * (1 - 1e-9), 20_000)


def _closed_loop_stable(L, gain: float) -> bool:
    cl = control.feedback(control.ss(L), gain)
    p = np.asarray(control.poles(cl))
    if control.isdtime(L, strict=True):
        return bool(np.all(np.abs(p) < 1 - 1e-12))
    return bool(np.all(p.real < -1e-12))


@dataclass(frozen=True)
class CircleCriterion:
    """Result of :func:`circle_criterion`.

    Parameters
    ----------
    holds : bool
        True when the criterion proves the loop free of limit cycles.
    sector : (float, float)
        The sector ``(a, b)`` used.
    margin : float
        ``min_w Re[(1 + b L) / (1 + a L)]`` (> 0 needed); ``-inf`` when the loop with the
        gain ``a`` is already unstable.
    omega_worst : float
        Frequency [rad/s] of that minimum.
    stable_at_a : bool
        Whether the linear loop closed with the gain ``a`` is stable.

    Examples
    --------
    >>> import control
    >>> res = circle_criterion(control.tf([1.0], [1.0, 1.0, 0.0]), (0.5, 1.5))
    >>> res.holds, res.sector, res.stable_at_a
    (True, (0.5, 1.5), True)
    """

    holds: bool
    sector: tuple[float, float]
    margin: float
    omega_worst: float
    stable_at_a: bool


def circle_criterion(L, sector_bounds: tuple[float, float], *, omega=None) -> CircleCriterion:
    """Circle criterion for the loop ``v = -L h``, ``h = PI[v]`` with a sector of increments.

    The differenced loop ``dv = -L dh``, ``dh[k] = kappa[k] dv[k]`` with ``kappa[k]`` in
    ``[a, b]`` (:func:`sector`) is a Lur'e loop with a time-varying gain, so the circle
    criterion applies to it: if ``1 + a L`` closes stably and ``Re[(1 + b L)/(1 + a L)] > 0``
    at every frequency, ``dv`` decays exponentially for every constant reference: the loop
    settles and no limit cycle (no periodic orbit) exists. The converse does not hold.

    Parameters
    ----------
    L : control.LTI
        Loop transfer function from the nonlinearity's output ``h`` to ``-v`` (controller
        times plant dynamics), continuous or discrete; strictly proper in discrete time.
    sector_bounds : (float, float)
        ``(a, b)`` with ``0 <= a < b``.
    omega : array_like, optional
        Frequencies [rad/s] to check; default a dense log grid up to the Nyquist frequency
        (discrete) or 100 times the fastest pole (continuous).

    Returns
    -------
    CircleCriterion

    Raises
    ------
    ValueError
        If the sector is not ``0 <= a < b`` or ``L`` is not SISO.

    Examples
    --------
    >>> import control
    >>> L = control.tf([1.0], [1.0, 1.0, 0.0])  # integrator and a lag
    >>> circle_criterion(L, (0.5, 1.5)).holds
    True
    """
    L = _check_siso(L)
    a, b = (float(x) for x in sector_bounds)
    if not (np.isfinite(a) and np.isfinite(b) and 0 <= a < b):
        raise ValueError(f"sector_bounds: expected 0 <= a < b, got {sector_bounds!r}")
    w = _default_omega(L, omega)
    stable = _closed_loop_stable(L, a) if a > 0 else _closed_loop_stable(L, 0.0)
    if not stable:
        return CircleCriterion(False, (a, b), -math.inf, math.nan, False)
    H = _freq_response(L, w)
    val = ((1 + b * H) / (1 + a * H)).real
    i = int(np.argmin(val))
    return CircleCriterion(bool(val[i] > 0), (a, b), float(val[i]), float(w[i]), True)


@dataclass(frozen=True)
class LimitCycle:
    """A solution of the harmonic balance ``1 + N(A) L(j omega) = 0``.

    Parameters
    ----------
    amplitude : float
        Amplitude ``A`` of the nonlinearity's input (input units).
    omega : float
        Frequency [rad/s].
    stable : bool
        Loeb's criterion: a small increase of ``A`` makes the oscillation decay (a stable,
        observable limit cycle) when True; an unstable one is a threshold between decay and
        growth.
    residual : float
        ``|1 + N(A) L(j omega)|`` at the solution.

    Examples
    --------
    >>> cycle = LimitCycle(amplitude=0.5, omega=2 * np.pi * 1000, stable=True, residual=0.0)
    >>> round(cycle.frequency_hz, 6)
    1000.0
    """

    amplitude: float
    omega: float
    stable: bool
    residual: float

    @property
    def frequency_hz(self) -> float:
        """Frequency in Hz."""
        return self.omega / (2 * np.pi)


def harmonic_balance(L, F, amplitudes, *, omega=None) -> list[LimitCycle]:
    """Predicted limit cycles of the loop ``v = -L h``, ``h = F[v]`` (describing function).

    Finds every crossing of the Nyquist curve ``L(j w)`` with the locus ``-1 / N(A)`` over
    the given amplitude range, refines it (``scipy.optimize.fsolve`` on ``1 + N(A) L = 0``)
    and classifies it by Loeb's criterion. Unlike ``control.describing_function_response``
    (whose refinement evaluates ``L(j w)`` also for discrete systems), a discrete ``L`` is
    evaluated at ``z = exp(j w dt)``.

    Parameters
    ----------
    L : control.LTI
        Loop transfer function from ``h`` to ``-v``, continuous or discrete.
    F : control.DescribingFunctionNonlinearity
        The nonlinearity, e.g. :meth:`PIOperator.describing_function`.
    amplitudes : array_like
        Increasing amplitudes ``A > 0`` spanning the search range (input units).
    omega : array_like, optional
        Frequencies [rad/s] for the Nyquist curve (default as :func:`circle_criterion`).

    Returns
    -------
    list of LimitCycle
        Sorted by amplitude; empty when none exists in the range.

    Examples
    --------
    >>> import control, numpy as np
    >>> L = control.tf([8.0], [1.0, 2.0, 2.0, 1.0])
    >>> F = control.saturation_nonlinearity(1)
    >>> [round(c.amplitude, 2) for c in harmonic_balance(L, F, np.linspace(1, 4, 40))]
    [3.34]
    """
    L = _check_siso(L)
    A = as_vector(amplitudes, "amplitudes")
    if np.any(A <= 0) or np.any(np.diff(A) <= 0):
        raise ValueError("amplitudes: expected increasing values > 0")
    w = _default_omega(L, omega)
    H = _freq_response(L, w)

    def N(a):
        return complex(np.squeeze(control.describing_function(F, a)))

    Nv = np.array([N(a) for a in A])
    ok = np.abs(Nv) > 0
    loc = np.full(A.shape, np.nan + 0j)
    loc[ok] = -1.0 / Nv[ok]
    found: list[LimitCycle] = []
    for i in range(A.size - 1):
        if not (ok[i] and ok[i + 1]):
            continue
        for s_a, s_w, k in _crossings(loc[i], loc[i + 1], H):
            a0 = A[i] + s_a * (A[i + 1] - A[i])
            w0 = w[k] + s_w * (w[k + 1] - w[k])
            cyc = _refine(L, N, a0, w0, (A[i], A[i + 1]))
            if cyc is not None and not any(
                    abs(cyc.amplitude - c.amplitude) < 1e-6 * c.amplitude
                    and abs(cyc.omega - c.omega) < 1e-6 * c.omega for c in found):
                found.append(cyc)
    return sorted(found, key=lambda c: c.amplitude)


def _crossings(p0: complex, p1: complex, H: np.ndarray):
    """Crossings of segment p0-p1 with the polyline H: (s along p, s along H, index)."""
    d1 = p1 - p0
    d2 = H[1:] - H[:-1]
    b = H[:-1] - p0
    det = d1.imag * d2.real - d1.real * d2.imag
    with np.errstate(divide="ignore", invalid="ignore"):
        s1 = (d2.real * b.imag - d2.imag * b.real) / -det
        s2 = (d1.real * b.imag - d1.imag * b.real) / -det
    hit = (np.abs(det) > 0) & (s1 >= 0) & (s1 <= 1) & (s2 >= 0) & (s2 <= 1)
    for k in np.flatnonzero(hit):
        yield float(s1[k]), float(s2[k]), int(k)


def _refine(L, N, a0: float, w0: float, bracket) -> LimitCycle | None:
    def res(x):
        c = 1 + N(abs(x[0])) * complex(_freq_response(L, abs(x[1])))
        return [c.real, c.imag]

    sol, info, ier, _ = scipy.optimize.fsolve(res, [a0, w0], full_output=True, xtol=1e-12)
    a, w = abs(float(sol[0])), abs(float(sol[1]))
    r = float(np.hypot(*res([a, w])))
    lo, hi = bracket
    if ier != 1 or r > 1e-6 or not (0.5 * lo <= a <= 2 * hi):
        a, w, r = a0, w0, float(np.hypot(*res([a0, w0])))
    # Loeb: stable when U_A V_w - U_w V_A > 0, Phi = 1 + N(A) L(jw) = U + jV.
    ha, hw = 1e-6 * a, 1e-6 * w

    def phi(x, y):
        return 1 + N(x) * complex(_freq_response(L, y))

    dA = (phi(a + ha, w) - phi(a - ha, w)) / (2 * ha)
    dW = (phi(a, w + hw) - phi(a, w - hw)) / (2 * hw)
    stable = dA.real * dW.imag - dW.real * dA.imag > 0
    return LimitCycle(a, w, bool(stable), r)


# -- model error as a residual hysteresis ------------------------------------------------------


def _loading_curve(op: PIOperator, s: np.ndarray) -> np.ndarray:
    return np.maximum(s[..., None] - op.radii, 0.0) @ op.weights


def _loading_slope(op: PIOperator, s: np.ndarray) -> np.ndarray:
    return (s[..., None] > op.radii) @ op.weights


def residual_hysteresis(truth: PIOperator, model: PIOperator) -> PIOperator:
    """The hysteresis left when ``model``'s exact inverse drives ``truth``: ``truth o model^-1``.

    A PI operator with initial loading curve ``phi_t`` composed with one with ``phi_m^-1``
    is the PI operator with loading curve ``phi_t o phi_m^-1`` (the composition rule behind
    the exact inverse), so the cascade is again a PI operator, with signed weights in general;
    it is the identity when ``model`` equals ``truth``. Radii are in the cascade's input units
    (those of the model's output, e.g. um), weights dimensionless for a stage model.

    Parameters
    ----------
    truth : PIOperator
        The real hysteresis (any PI operator whose loading curve increases).
    model : PIOperator
        The model whose inverse is used; must be invertible (``r_1 = 0``).

    Returns
    -------
    PIOperator
        ``R`` with ``R.simulate(u) == truth.simulate(model.inverse().simulate(u))`` (both
        from the virgin state).

    Raises
    ------
    ValueError
        If ``model`` is not invertible, or either operator has a non-zero initial state.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> truth = PIOperator([1.0, 0.5], [0.0, 0.2])
    >>> residual_hysteresis(truth, truth)  # doctest: +NORMALIZE_WHITESPACE
    PIOperator(weights=[1.], radii=[0.])
    """
    truth, model = _operator(truth), _operator(model)
    if not model.is_invertible:
        raise ValueError("model: not invertible; the exact inverse needs r_1 = 0 and positive "
                         "partial sums of weights")
    for name, op in (("truth", truth), ("model", model)):
        if np.any(op.initial_state != 0):
            raise ValueError(f"{name}: residual_hysteresis needs the virgin (zero) initial "
                             "state")
    # breakpoints in the cascade's input (= model output) coordinate
    s_break = np.unique(np.concatenate([model.radii, truth.radii]))
    u = _loading_curve(model, s_break)
    u, idx = np.unique(u, return_index=True)
    s_break = s_break[idx]
    # slope of phi_t o phi_m^-1 on each interval [u_k, u_k+1) and beyond the last breakpoint
    s_mid = np.append((s_break[:-1] + s_break[1:]) / 2, s_break[-1] + 1.0)
    slope = _loading_slope(truth, s_mid) / _loading_slope(model, s_mid)
    w = np.diff(slope, prepend=0.0)
    tol = 1e-12 * np.abs(slope).max()
    keep = np.abs(w) > tol
    w, r = w[keep], u[keep]
    return PIOperator(w, r, signed_weights=bool(np.any(w < 0)))
