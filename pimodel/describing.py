"""Describing function and linearised views of a PI operator, in python-control's terms.

A play of radius ``r`` is a friction-dominated backlash of width ``2 r``
(``control.friction_backlash_nonlinearity(2 r)``). In the periodic steady state of the input
``v(t) = v0 + A sin(w t)`` its first harmonic is ``N_r(A) A sin(w t + arg N_r(A))`` with
(Gelb & Vander Velde, backlash no. 48; ``x = 1 - 2 r / A``)::

    N_r(A) = (1 + f(x)) / 2 - j (4 r / A - 4 r^2 / A^2) / pi      for A > r
    N_r(A) = 0                                                   for A <= r
    f(x)   = 2 / pi (asin x + x sqrt(1 - x^2))

independent of ``w`` and of the bias ``v0`` (the play is rate independent and shift
invariant). The PI operator ``y = sum_i p_i Gamma_{r_i}[v]`` is a sum of plays, so its
describing function is exactly ``N(A) = sum_i p_i N_{r_i}(A)``, signed weights (the exact
inverse) included. For sampled inputs the same holds when a sample falls on each peak of the
sine (the discrete play equals the continuous one at the samples).

Linearised views (paper Lemma 1): along any input the output's increments are
``y[k] - y[k-1] = kappa[k] (v[k] - v[k-1])`` with ``kappa[k]`` in the **sector**
``[min slope, max slope]`` of the loop-branch slopes (``0`` included when ``r_1 > 0``); for
signed weights the slopes are the partial sums ``p_1 + ... + p_i``. (Exact when the play states
satisfy ``|z_i - z_j| <= |r_i - r_j|``, which holds for a scalar initial state and is kept by
the dynamics.) The **static gain** at amplitude ``A`` is the ratio of the output and input
half ranges of the symmetric loop, ``phi(A) / A`` with the initial loading curve
``phi(A) = sum_i p_i max(A - r_i, 0)``. :func:`circle_criterion` applies the sector to the
differenced loop, :func:`harmonic_balance` solves ``1 + N(A) L(jw) = 0``.

Units: ``A`` in input units (those of the radii), ``N`` and gains in output per input unit,
frequencies in rad/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np
import scipy.optimize

from .checks import as_vector
from .operator import PIOperator

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


def _amplitudes(A, name: str = "A") -> np.ndarray:
    a = np.asarray(A, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"{name}: expected finite amplitudes >= 0, got {A!r}")
    return a


def play_describing_function(radius: float, A) -> np.ndarray | complex:
    """Exact describing function of one play (a backlash of width ``2 radius``).

    Parameters
    ----------
    radius : float
        Play radius ``r >= 0`` (input units).
    A : float or array_like
        Amplitudes ``A >= 0`` of the sinusoidal input.

    Returns
    -------
    complex or ndarray of complex
        ``N_r(A)``: 0 for ``A <= r``, 1 for ``r = 0``; phase in (-90, 0] degrees.

    Raises
    ------
    ValueError
        If ``radius`` or an amplitude is negative or not finite.

    Examples
    --------
    >>> import control, numpy as np
    >>> complex(np.round(play_describing_function(0.5, 2.0), 4))
    (0.8045-0.2387j)
    >>> complex(np.round(control.friction_backlash_nonlinearity(1.0).describing_function(2.0), 4))
    (0.8045-0.2387j)
    """
    r = float(radius)
    if not math.isfinite(r) or r < 0:
        raise ValueError(f"radius: expected a finite number >= 0, got {radius!r}")
    a = _amplitudes(A)
    out = np.zeros(a.shape, dtype=complex)
    on = a > r
    if r == 0.0:
        out[on] = 1.0
    else:
        q = 2.0 * r / a[on]  # backlash width over amplitude, in (0, 2)
        x = 1.0 - q
        f = (np.arcsin(x) + x * np.sqrt(1.0 - x * x)) * 2.0 / np.pi
        out[on] = (1.0 + f) / 2.0 - 1j * (2.0 * q - q * q) / np.pi
    return complex(out) if out.ndim == 0 else out


def sector(op: PIOperator) -> tuple[float, float]:
    """Sector of incremental gains of a PI operator (paper Lemma 1).

    Parameters
    ----------
    op : PIOperator
        Any PI operator, signed weights included.

    Returns
    -------
    (float, float)
        ``(k_min, k_max)``: the smallest and largest loop-branch slope, ``0`` included when
        ``r_1 > 0``. Every increment obeys ``k_min <= (y[k] - y[k-1]) / (v[k] - v[k-1]) <=
        k_max`` (output per input unit).

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> sector(PIOperator([1.0, 0.5], [0.0, 0.2]))
    (1.0, 1.5)
    >>> sector(PIOperator([1.0, 0.5], [0.1, 0.2]))
    (0.0, 1.5)
    """
    s = _operator(op).slopes()
    return float(s.min()), float(s.max())


def static_gain(op: PIOperator, A) -> np.ndarray | float:
    """Static (chord) gain ``phi(A) / A`` of the symmetric loop of amplitude ``A``.

    In the periodic steady state of an input oscillating between ``v0 - A`` and ``v0 + A``
    the output oscillates with half range ``phi(A) = sum_i p_i max(A - r_i, 0)``; the ratio is
    the gain a linear model fitted to that loop's end points would use. It lies in
    :func:`sector` and tends to ``sum p_i`` for large ``A``.

    Parameters
    ----------
    op : PIOperator
        The operator.
    A : float or array_like
        Amplitudes ``A > 0`` (input units).

    Returns
    -------
    float or ndarray
        The gain (output per input unit).

    Raises
    ------
    ValueError
        If an amplitude is not finite and > 0.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> float(static_gain(PIOperator([1.0, 0.5], [0.0, 0.2]), 1.0))
    1.4
    """
    op = _operator(op)
    a = _amplitudes(A)
    if np.any(a <= 0):
        raise ValueError(f"A: expected amplitudes > 0, got {A!r}")
    phi = np.maximum(a[..., None] - op.radii, 0.0) @ op.weights
    g = phi / a
    return float(g) if g.ndim == 0 else g


def _operator(op) -> PIOperator:
    if not isinstance(op, PIOperator):
        raise TypeError(f"op: expected a PIOperator, got {type(op).__name__}")
    return op


class PIDescribingFunction(control.DescribingFunctionNonlinearity):
    """A PI operator as a python-control describing-function nonlinearity.

    Usually made by :meth:`PIOperator.describing_function`. ``describing_function(A)`` is the
    exact ``sum_i p_i N_{r_i}(A)`` (module docstring); calling the object with a scalar input
    ``v[k]`` streams the operator (``y[k]`` of ``v[0..k]``, starting from the operator's
    initial state), like ``control.friction_backlash_nonlinearity``, so python-control's
    numerical ``describing_function(F, A, try_method=False)`` also works.

    Parameters
    ----------
    op : PIOperator
        The operator (copied; later changes to ``op``'s streaming state do not matter).

    Examples
    --------
    >>> import control, numpy as np
    >>> from pimodel import PIOperator
    >>> F = PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function()
    >>> complex(np.round(control.describing_function(F, 1.0), 4))
    (1.4288-0.1019j)
    """

    def __init__(self, op: PIOperator):
        super().__init__()
        op = _operator(op)
        self.operator = PIOperator(op.weights, op.radii, initial_state=op.initial_state,
                                   signed_weights=op.signed_weights)

    def __call__(self, x) -> float:
        """One streaming step: ``y[k]`` for the input sample ``x = v[k]``."""
        return self.operator.step(float(np.squeeze(x)))

    def reset(self) -> None:
        """Return the streaming state to the operator's initial state.

        Returns
        -------
        None

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> F = PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function()
        >>> F(1.0), F.reset(), F(1.0)
        (1.4, None, 1.4)
        """
        self.operator.reset()

    def _isstatic(self) -> bool:
        return False

    def describing_function(self, A):
        """Exact describing function ``N(A) = sum_i p_i N_{r_i}(A)``.

        Parameters
        ----------
        A : float or array_like
            Amplitudes ``A >= 0`` (input units).

        Returns
        -------
        complex or ndarray of complex
            ``N(A)`` (output per input unit); ``N(0)`` is the smallest-radius slope when
            ``r_1 = 0``, else 0.

        Raises
        ------
        ValueError
            If an amplitude is negative or not finite.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> F = PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function()
        >>> F.describing_function([0.1, 1.0]).round(4)
        array([1.    +0.j    , 1.4288-0.1019j])
        """
        a = _amplitudes(A)
        op = self.operator
        n = sum(p * play_describing_function(r, a) for p, r in zip(op.weights, op.radii,
                                                                       strict=True))
        n = np.asarray(n, dtype=complex)
        return complex(n) if n.ndim == 0 else n

    def sector(self) -> tuple[float, float]:
        """Incremental-gain sector, see :func:`sector`.

        Returns
        -------
        (float, float)
            ``(k_min, k_max)``, the smallest and largest loop-branch slope.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function().sector()
        (1.0, 1.5)
        """
        return sector(self.operator)

    def static_gain(self, A):
        """Static (chord) gain at amplitude ``A``, see :func:`static_gain`.

        Parameters
        ----------
        A : float or array_like
            Amplitudes ``A > 0`` (input units).

        Returns
        -------
        float or ndarray
            ``phi(A) / A`` (output per input unit).

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> float(PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function().static_gain(1.0))
        1.4
        """
        return static_gain(self.operator, A)

    def __repr__(self) -> str:
        return f"PIDescribingFunction({self.operator!r})"


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
