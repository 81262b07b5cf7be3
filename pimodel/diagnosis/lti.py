"""The linear part of the ``dynamics`` candidate: a Hammerstein model (hysteresis, then a linear
time-invariant system) whose order is chosen by the Bayesian information criterion on train.

Form (continuous time, every element discretised with a zero-order hold, as a DAC drives the
stage, and started at rest around the first sample):

    G(s) = M_1(s) + sum_j g_j (E_j(s) - M_1(s)),

with ``M_1 = w^2 / (s^2 + 2 zeta w s + w^2)`` the base mode (unit static gain) and the extra
elements ``E_j``, each of unit static gain:

- ``("mode", fn, zeta)``: a further mode [Hz, -];
- ``("lowpass", tau)``: a first-order low-pass ``1 / (tau s + 1)`` [s] (sensor or amplifier
  filter);
- ``("direct",)``: a direct feedthrough ``1`` (with the modes: a pair of zeros).

The gains ``g_j`` are free, so the elements in parallel give ``G`` zeros; its static gain is 1
(a gain of the linear part cannot be told from the hysteresis weights). The diagnosis applies
``M_1`` to the play outputs (fitted jointly with the weights) and the terms
``(E_j - M_1)[h0]`` to the reference hysteresis ``h0`` (the nominal model's output, as the creep
candidate does), so every fit stays linear in its coefficients: ``y[k] = (M_1[Z] w)[k] +
sum_j g_j c_j[k] + ...``, ``c_j = (E_j - M_1)[h0]``; ``c_j[k]`` depends on ``h0[0..k]`` (on
``h0[0..k-1]`` for a mode or a low-pass).

The order is chosen by forward selection: starting from ``M_1`` alone, the further mode (the
best on a grid, refined) that lowers the train BIC ``N ln(RSS / N) + k ln N`` is added while one
does (``k``: 3 per mode: frequency, damping, gain; 2 per low-pass: time constant, gain), up to
``MAX_MODES`` modes and ``MAX_ELEMENTS`` extra elements. The kinds tried are ``SELECTED``: modes
and a low-pass (a real pole, from ``LOWPASS_MIN_HZ``: a mode in series with a real pole, as an
amplifier or sensor filter adds, is no single mode; over a band below both it is one mode plus a
low-pass in parallel to well under a percent of the effect), not a direct term; the form,
:func:`lti_columns` and :func:`approximate_inverse` take every kind. A fitted linear part that
acts as a pure delay still gives way to ``delay`` (:mod:`.delaylike`). After each step every
frequency and damping is polished jointly (Nelder-Mead on the train RSS), and the step is kept
when the polished fit still lowers the BIC against the previous structure polished at the same
point.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.optimize import minimize
from scipy.signal import (
    bilinear_zpk,
    sosfilt,
    sosfilt_zi,
    zpk2sos,
)

from .._native import biquad_rows
from .filters import mode_coefficients
from .threads import helped_map

__all__ = [
    "MAX_MODES",
    "approximate_inverse",
    "continuous_zpk",
    "describe_lti",
    "element_coefficients",
    "inverse_sos",
    "lti_columns",
    "lti_k",
    "nelder_mead",
    "polish_elements",
    "select_order",
]

MAX_MODES = 3  # modes of the linear part, the base mode included
MAX_ELEMENTS = 2  # extra elements at most (each step costs a joint polish)
BASE_MIN_HZ = 50.0  # the polish keeps the base mode above this (a pole at 1 would be singular)
EXTRA_MODE_HZ = (300.0, 14)  # lowest frequency [Hz] and size of the extra modes' grid
EXTRA_DAMPING = (0.02, 0.05, 0.1, 0.2)
EXTRA_DAMPING_MAX = 0.25  # a heavily damped fast mode imitates a delay
MODE_SEPARATION = 1.25  # the modes' frequencies differ by this factor at least
LOWPASS_MIN_HZ = BASE_MIN_HZ  # slowest low-pass [Hz] (a real pole behind a 120-300 Hz mode)
LOWPASS_GRID = 10
# parameters each element adds; "lowpass_direct" (the low-pass sampled at the end of the hold,
# its output at sample k moved by v[k]) is a form of the Wiener filter (module wiener), not
# selected here
ELEMENT_K = {"mode": 3, "lowpass": 2, "lowpass_direct": 2, "direct": 1}
# the kinds the selection tries (the forward form and the inverse accept every kind): a direct
# term beside the modes imitates a fractional delay; a low-pass is the real pole that a mode
# alone cannot follow (on density_stage's mode + pole, the one-mode candidate lost to `delay`
# or took a spurious second effect beside it in 7 of 10 seeds)
SELECTED = ("mode", "lowpass")
INVERSE_FILTER = 2.0  # the inverse's low-pass sits at this factor above the fastest pole



def nelder_mead(cost: Callable, x0: np.ndarray, **options):
    """``scipy.optimize.minimize(cost, x0, method="Nelder-Mead", options=options)`` with NumPy's
    invalid-value warnings off: the costs here are ``inf`` at inadmissible points, and SciPy's
    convergence test then computes ``inf - inf``.

    Parameters
    ----------
    cost : callable
        ``cost(x) -> float`` (``inf`` where ``x`` is not admissible; a point where it
        raises ``numpy.linalg.LinAlgError`` or returns NaN counts as ``inf``).
    x0 : numpy.ndarray
        Start point.
    **options
        Nelder-Mead options (``initial_simplex``, ``maxfev``, ``xatol``, ``fatol``).

    Returns
    -------
    scipy.optimize.OptimizeResult
        SciPy's result (``x``, ``fun``).

    Examples
    --------
    >>> r = nelder_mead(lambda x: float((x[0] - 2.0) ** 2) if x[0] < 5 else np.inf,
    ...                 np.array([0.0]), xatol=1e-8, fatol=1e-12)
    >>> round(float(r.x[0]), 4)
    2.0
    """
    def guarded(x):  # a point whose fit breaks down (non-finite columns) is not admissible
        try:
            f = float(cost(x))
        except np.linalg.LinAlgError:
            return np.inf
        return f if np.isfinite(f) else np.inf

    with np.errstate(invalid="ignore"):
        return minimize(guarded, x0, method="Nelder-Mead", options=options)

def _kind(element) -> str:
    kind = element[0]
    if kind not in ELEMENT_K:
        raise ValueError(f"element: expected a kind in {sorted(ELEMENT_K)}, got {kind!r}")
    return kind


def element_coefficients(element: Sequence, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """ZOH discretisation ``(b, a)`` of one element of unit static gain.

    Parameters
    ----------
    element : sequence
        ``("mode", fn [Hz], zeta)``, ``("lowpass", tau [s])``, ``("lowpass_direct", tau [s])``
        or ``("direct",)``. ``"lowpass_direct"`` is the low-pass of ``"lowpass"`` with its
        output sampled at the end of each hold instead of its start, ``x[k] = a x[k-1] +
        (1 - a) v[k]``, ``a = exp(-dt / tau)``: the ZOH low-pass advanced one sample (an
        amplifier whose output the sensor samples just before the next update).
    dt : float
        Sample time [s].

    Returns
    -------
    b, a : numpy.ndarray
        Numerator and denominator in powers of ``z^-1`` (``a[0] = 1``) for
        :func:`scipy.signal.lfilter`.

    Raises
    ------
    ValueError
        An unknown element kind.

    Examples
    --------
    >>> b, a = element_coefficients(("lowpass", 1e-3), 1e-3)
    >>> np.round(b, 4).tolist(), np.round(a, 4).tolist()
    ([0.0, 0.6321], [1.0, -0.3679])
    >>> b, a = element_coefficients(("lowpass_direct", 1e-3), 1e-3)
    >>> np.round(b, 4).tolist(), np.round(a, 4).tolist()
    ([0.6321], [1.0, -0.3679])
    >>> b, a = element_coefficients(("mode", 100.0, 0.1), 1e-4)
    >>> round(float(b.sum() / a.sum()), 9)  # unit static gain
    1.0
    """
    kind = _kind(element)
    if kind == "direct":
        return np.array([1.0]), np.array([1.0])
    if kind == "lowpass":
        a1 = np.exp(-dt / float(element[1]))
        return np.array([0.0, 1.0 - a1]), np.array([1.0, -a1])
    if kind == "lowpass_direct":
        a1 = np.exp(-dt / float(element[1]))
        return np.array([1.0 - a1]), np.array([1.0, -a1])
    return mode_coefficients(float(element[1]), float(element[2]), dt)


def _at_rest(element, x: np.ndarray, dt: float) -> np.ndarray:
    """``x`` through the element, at rest around ``x[0]``."""
    b, a = element_coefficients(element, dt)
    if a.size == 1:
        return x * (b[0] / a[0])
    return biquad_rows(b, a, x)  # the C core (lfilter at rest around x[0])


def lti_columns(h0: np.ndarray, fn: float, zeta: float, elements: Sequence, dt: float, *,
                base: np.ndarray | None = None) -> np.ndarray:
    """The extra elements' columns ``c_j = (E_j - M_1)[h0]`` (module docstring).

    Parameters
    ----------
    h0 : numpy.ndarray
        Reference hysteresis output ``h0[k]`` [output units].
    fn, zeta : float
        Base mode ``M_1``: natural frequency [Hz] and damping ratio [-].
    elements : sequence
        The extra elements (module docstring).
    dt : float
        Sample time [s].
    base : numpy.ndarray, optional
        ``M_1[h0]`` when already computed.

    Returns
    -------
    numpy.ndarray
        Shape (N, len(elements)), output units; each column has zero static gain.

    Examples
    --------
    >>> h0 = np.r_[0.0, np.ones(2000)]  # a unit step
    >>> c = lti_columns(h0, 200.0, 0.3, [("mode", 600.0, 0.2), ("direct",)], 1e-4)
    >>> c.shape, bool(np.all(np.abs(c[-1]) < 1e-9))  # the columns settle at zero
    ((2001, 2), True)
    """
    h0 = np.asarray(h0, float)
    if base is None:
        base = _at_rest(("mode", fn, zeta), h0, dt)
    out = np.empty((h0.size, len(elements)))
    for j, el in enumerate(elements):
        out[:, j] = _at_rest(el, h0, dt) - base
    return out


def lti_k(elements: Sequence) -> int:
    """Parameters the extra elements add to the one-mode ``dynamics`` candidate.

    Parameters
    ----------
    elements : sequence
        The extra elements.

    Returns
    -------
    int
        3 per mode, 2 per low-pass, 1 for the direct term.

    Examples
    --------
    >>> lti_k([("mode", 900.0, 0.1), ("lowpass", 2e-4)])
    5
    """
    return sum(ELEMENT_K[_kind(e)] for e in elements)


def describe_lti(fn: float, zeta: float, elements: Sequence, gains: Sequence) -> dict:
    """The linear part as plain data for a report.

    Parameters
    ----------
    fn, zeta : float
        Base mode [Hz, -].
    elements : sequence
        The extra elements.
    gains : sequence of float
        Their gains ``g_j``.

    Returns
    -------
    dict
        ``dynamics_order`` (number of modes), ``lti_elements`` (JSON lists), ``lti_gains``,
        ``dynamics_modes`` (each mode's ``hz``, ``damping`` and ``share`` of the static gain:
        ``1 - sum g`` for the base mode), ``lowpass_hz`` and ``direct_share`` when present.

    Examples
    --------
    >>> d = describe_lti(500.0, 0.1, [("mode", 900.0, 0.15)], [0.25])
    >>> d["dynamics_order"], [m["share"] for m in d["dynamics_modes"]]
    (2, [0.75, 0.25])
    """
    gains = [float(g) for g in gains]
    modes = [{"hz": float(fn), "damping": float(zeta), "share": 1.0 - sum(gains)}]
    out: dict = {}
    for el, g in zip(elements, gains, strict=True):
        kind = _kind(el)
        if kind == "mode":
            modes.append({"hz": float(el[1]), "damping": float(el[2]), "share": g})
        elif kind == "lowpass":
            out["lowpass_hz"] = 1.0 / (2 * np.pi * float(el[1]))
            out["lowpass_share"] = g
        else:
            out["direct_share"] = g
    return {"dynamics_order": len(modes), "lti_elements": [list(e) for e in elements],
            "lti_gains": gains, "dynamics_modes": modes, **out}


def _normalised_tf(element, wr: float) -> tuple[np.ndarray, np.ndarray]:
    """Continuous transfer function of an element in ``s' = s / wr`` (numerator, denominator)."""
    kind = _kind(element)
    if kind == "direct":
        return np.array([1.0]), np.array([1.0])
    if kind == "lowpass":
        return np.array([1.0]), np.array([float(element[1]) * wr, 1.0])
    w = 2 * np.pi * float(element[1]) / wr
    return np.array([w * w]), np.array([1.0, 2 * float(element[2]) * w, w * w])


def _conjugate_pairs(r: np.ndarray) -> np.ndarray:
    """Roots of a real polynomial as exact conjugate pairs (real roots made real)."""
    r = np.asarray(r, complex)
    tol = 1e-9 * np.maximum(np.abs(r), 1e-300)
    upper = r[r.imag > tol]
    return np.concatenate((r[np.abs(r.imag) <= tol].real, upper, upper.conj()))


def continuous_zpk(fn: float, zeta: float, elements: Sequence,
                   gains: Sequence) -> tuple[np.ndarray, np.ndarray, float]:
    """Zeros, poles and gain of ``G(s)`` (module docstring), ``s`` in rad/s.

    Parameters
    ----------
    fn, zeta : float
        Base mode [Hz, -].
    elements : sequence
        The extra elements.
    gains : sequence of float
        Their gains.

    Returns
    -------
    zeros, poles : numpy.ndarray
        [rad/s].
    gain : float
        Such that ``G(s) = gain prod(s - zeros) / prod(s - poles)``; ``G(0) = 1``.

    Examples
    --------
    >>> z, p, k = continuous_zpk(100.0, 0.5, [], [])
    >>> z.size, np.round(np.abs(p) / (2 * np.pi), 6).tolist()
    (0, [100.0, 100.0])
    """
    wr = 2 * np.pi * float(fn)
    parts = [(1.0 - float(np.sum(gains)), _normalised_tf(("mode", fn, zeta), wr))]
    parts += [(float(g), _normalised_tf(el, wr)) for el, g in zip(elements, gains, strict=True)]
    den = np.array([1.0])
    for _, (_, d) in parts:
        den = np.polymul(den, d)
    num = np.array([0.0])
    for i, (g, (n, _)) in enumerate(parts):
        term = g * n
        for j, (_, (_, d)) in enumerate(parts):
            if j != i:
                term = np.polymul(term, d)
        num = np.polyadd(num, term)
    num = np.trim_zeros(num, "f")
    if num.size and abs(num[0]) < 1e-12 * np.max(np.abs(num)):
        num = np.trim_zeros(np.where(np.abs(num) < 1e-12 * np.max(np.abs(num)), 0.0, num), "f")
    zeros, poles = _conjugate_pairs(np.roots(num) * wr), _conjugate_pairs(np.roots(den) * wr)
    gain = float(num[0] / den[0]) * wr ** (poles.size - zeros.size)
    return zeros, poles, gain


def approximate_inverse(x: np.ndarray, fn: float, zeta: float, elements: Sequence,
                        gains: Sequence, dt: float) -> np.ndarray:
    """``x`` through a stable approximate inverse of ``G`` (the feedforward prefilter).

    ``G(s)^-1`` with its zeros in the right half plane (or on the axis) mirrored into the left
    one, times the low-pass ``(s / wf + 1)^-r`` that makes it proper (``r`` the relative degree
    of ``G``, ``wf`` ``INVERSE_FILTER`` times its fastest pole), static gain 1, discretised with
    Tustin; advanced one sample for the zero-order hold when ``G`` has no direct term. For the
    base mode alone this is ``M(s)^-1 / (s / (2 w) + 1)^2``.

    Parameters
    ----------
    x : numpy.ndarray
        Desired output of the linear part, every ``dt``.
    fn, zeta : float
        Base mode [Hz, -].
    elements : sequence
        The extra elements.
    gains : sequence of float
        Their gains.
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        The input ``u[k]`` of the linear part (started at rest around ``x[0]``); ``u[k]``
        depends on ``x[0..k+1]`` (``x[0..k]`` with a direct term), the last sample held.

    Examples
    --------
    >>> t = np.arange(4000) * 1e-4
    >>> u = np.sin(2 * np.pi * 5 * t)
    >>> b, a = element_coefficients(("mode", 800.0, 0.05), 1e-4)
    >>> from scipy.signal import lfilter
    >>> y = lfilter(b, a, u)  # the mode's response to a slow sine
    >>> bool(np.max(np.abs(approximate_inverse(y, 800.0, 0.05, [], [], 1e-4) - u)[:-1]) < 0.01)
    True
    """
    sos, advance = inverse_sos(fn, zeta, elements, gains, dt)
    out = sosfilt(sos, x, zi=sosfilt_zi(sos) * x[0])[0]
    if not advance:
        return out
    return np.r_[out[1:], out[-1]]


def inverse_sos(fn: float, zeta: float, elements: Sequence, gains: Sequence,
                dt: float) -> tuple[np.ndarray, int]:
    """The filter of :func:`approximate_inverse` as second-order sections, and its advance.

    Parameters
    ----------
    fn, zeta : float
        Base mode [Hz, -].
    elements : sequence
        The extra elements.
    gains : sequence of float
        Their gains.
    dt : float
        Sample time [s].

    Returns
    -------
    sos : numpy.ndarray
        Shape (sections, 6), for :func:`scipy.signal.sosfilt` (Tustin, static gain 1).
    advance : int
        1: the filter's output is advanced one sample (the zero-order hold; ``G`` has no direct
        term), else 0.

    Examples
    --------
    >>> sos, advance = inverse_sos(800.0, 0.05, [], [], 1e-4)
    >>> sos.shape, advance
    ((1, 6), 1)
    """
    zeros, poles, _ = continuous_zpk(fn, zeta, elements, gains)
    mirrored = np.where(zeros.real > -1e-3 * np.abs(zeros), -np.abs(zeros.real) - 1e-3 *
                        np.abs(zeros) + 1j * zeros.imag, zeros)
    r = poles.size - zeros.size
    wf = INVERSE_FILTER * float(np.max(np.abs(poles))) if poles.size else 1.0
    z_inv, p_inv = poles, np.concatenate((mirrored, np.full(r, -wf)))
    # static gain 1: prod(-z_inv) / prod(-p_inv) * k = 1
    k = float(np.real(np.prod(-p_inv) / np.prod(-z_inv))) if z_inv.size else \
        float(np.real(np.prod(-p_inv)))
    zd, pd, kd = bilinear_zpk(z_inv, p_inv, k, fs=1.0 / dt)
    return zpk2sos(zd, pd, kd), int(not any(_kind(e) == "direct" for e in elements))


class _Projection:
    """Least squares on fixed regressors, and the train RSS when one column is added (rank-one
    update: ``RSS - (r . c_perp)^2 / |c_perp|^2``, ``c_perp`` the part of ``c`` the fixed
    regressors do not span)."""

    def __init__(self, blocks, ys):
        self.blocks = blocks
        G = sum(A.T @ A for A in blocks)
        d = np.sqrt(np.diag(G))
        d[d == 0] = 1.0
        self.d = d
        self.P = np.linalg.pinv(G / d[:, None] / d[None, :], rcond=1e-13)
        g = sum(A.T @ y for A, y in zip(blocks, ys, strict=True))
        coef = self.P @ (g / d) / d
        self.res = [y - A @ coef for A, y in zip(blocks, ys, strict=True)]
        self.rss = float(sum(r @ r for r in self.res))

    def rss_with(self, cols) -> float:
        a = sum(A.T @ c for A, c in zip(self.blocks, cols, strict=True)) / self.d
        cc = float(sum(c @ c for c in cols))
        s = cc - float(a @ (self.P @ a))
        if not s > 1e-12 * cc:
            return self.rss
        rc = float(sum(r @ c for r, c in zip(self.res, cols, strict=True)))
        return self.rss - rc * rc / s

    def rss_with_each(self, candidates) -> np.ndarray:
        """:meth:`rss_with` of several candidate columns (each a list with one column per
        block), one matrix product per block instead of one pass over the regressors each."""
        C = [np.vstack([c[j] for c in candidates]) for j in range(len(self.blocks))]  # (m, n)
        a = sum(A.T @ Cj.T for A, Cj in zip(self.blocks, C, strict=True)) / self.d[:, None]
        cc = sum(np.einsum("ij,ij->i", Cj, Cj) for Cj in C)
        s = cc - np.einsum("im,im->m", a, self.P @ a)
        rc = sum(Cj @ r for Cj, r in zip(C, self.res, strict=True))
        ok = s > 1e-12 * cc
        return np.where(ok, self.rss - rc * rc / np.where(ok, s, 1.0), self.rss)


def _separated(freqs) -> bool:
    """Modes at least ``MODE_SEPARATION`` apart in frequency (two close modes with opposite
    gains act as a derivative that fits any systematic misfit)."""
    f = np.sort(np.asarray(freqs, float))
    return bool(np.all(f[1:] >= MODE_SEPARATION * f[:-1]))


def _admissible(element, fmax: float, damping_range, modes=()) -> bool:
    """Within the bounds; a mode also at least ``MODE_SEPARATION`` from the ``modes`` [Hz]."""
    kind = _kind(element)
    if kind == "mode":
        # an extra mode is a resonance: not lighter than the grid's lightest (a light mode at a
        # harmonic of a periodic train input would fit the periodic misfit of the hysteresis),
        # not heavier than EXTRA_DAMPING_MAX (heavy damping is the low-pass's part)
        return (EXTRA_MODE_HZ[0] <= element[1] <= fmax and
                max(damping_range[0], EXTRA_DAMPING[0]) <= element[2] <= EXTRA_DAMPING_MAX and
                _separated([element[1], *modes]))
    if kind == "lowpass":
        return LOWPASS_MIN_HZ <= 1.0 / (2 * np.pi * element[1]) <= fmax
    return True


def _refine(rss_of, element, fmax: float, damping_range, modes=(), maxfev: int = 30):
    """Local Nelder-Mead refinement of one element's parameters (log scale) on ``rss_of``."""
    kind = _kind(element)
    if kind == "direct":
        return element, rss_of(element)
    x0 = np.log(np.asarray(element[1:], float))
    steps = [0.05, 0.3] if kind == "mode" else [0.2]

    def make(x):
        return (kind, *(float(v) for v in np.exp(x)))

    def cost(x):
        el = make(x)
        return rss_of(el) if _admissible(el, fmax, damping_range, modes) else np.inf

    simplex = [x0] + [x0 + np.eye(x0.size)[i] * s for i, s in enumerate(steps)]
    r = nelder_mead(cost, x0, initial_simplex=simplex, maxfev=maxfev, xatol=1e-3)
    return make(r.x), float(r.fun)


def _best_addition(blocks: list, ys: list, column: Callable, chosen: tuple, fmax: float,
                   damping_range, base_hz: float) -> tuple | None:
    """The element that lowers the train BIC most when added to ``chosen`` with the base mode
    held (``blocks`` hold the regressors with the chosen elements' columns): of each kind the
    best on its grid, refined; ``(element, rss)`` or None when no kind is left."""
    n = sum(y.size for y in ys)
    proj = _Projection(blocks, ys)
    modes = [base_hz] + [e[1] for e in chosen if _kind(e) == "mode"]

    def rss_of(el):
        return proj.rss_with(column(el))

    options = []
    if len(chosen) >= MAX_ELEMENTS:
        return None
    if 1 + sum(_kind(e) == "mode" for e in chosen) < MAX_MODES and EXTRA_MODE_HZ[0] < fmax:
        grid = [("mode", float(f), z) for f in np.geomspace(EXTRA_MODE_HZ[0], fmax,
                                                             EXTRA_MODE_HZ[1])
                for z in EXTRA_DAMPING if _admissible(("mode", f, z), fmax, damping_range,
                                                      modes)]
        if grid:  # the columns on idle threads too (module threads; the same columns)
            rss = proj.rss_with_each(helped_map(column, grid))
            options.append((grid[int(np.argmin(rss))], float(np.min(rss))))
    if ("lowpass" in SELECTED and not any(_kind(e) == "lowpass" for e in chosen) and
            LOWPASS_MIN_HZ < fmax):
        grid = [("lowpass", float(1 / (2 * np.pi * f)))
                for f in np.geomspace(LOWPASS_MIN_HZ, fmax, LOWPASS_GRID)]
        options.append(min(zip(grid, helped_map(rss_of, grid), strict=True),
                           key=lambda o: o[1]))
    if "direct" in SELECTED and not any(_kind(e) == "direct" for e in chosen):
        options.append((("direct",), rss_of(("direct",))))
    if not options:
        return None
    # each kind's refinement is its own (the projection is only read): one per thread
    options = helped_map(lambda o: _refine(rss_of, o[0], fmax, damping_range, modes), options)
    return min(options, key=lambda o: n * np.log(max(o[1], 1e-300)) + lti_k([o[0]]) * np.log(n))


def select_order(fit: Callable, regressors: Callable, column: Callable, fn: float, zeta: float,
                 fmax: float, damping_range: tuple[float, float], *,
                 polish: bool = True, min_elements: int = 0,
                 memo: dict | None = None) -> tuple[float, float, tuple, list]:
    """Forward selection of the extra elements by the train BIC (module docstring).

    Each step screens every kind of element with the base mode held (a rank-one update of the
    least squares), then polishes the base mode and all elements jointly
    (:func:`polish_elements`) and keeps the step when the polished fit lowers the train BIC.

    Parameters
    ----------
    fit : callable
        ``fit(fn, zeta, elements)``: the train RSS of the full fit.
    regressors : callable
        ``regressors(fn, zeta, elements)``: ``(blocks, ys)``, per train record the regressors
        of that fit and the measured output (fitted rows only).
    column : callable
        ``column(fn, zeta, element)``: per train record the column ``(E - M_1)[h0]`` on those
        rows.
    fn, zeta : float
        The one-mode fit's mode [Hz, -].
    fmax : float
        Highest frequency of a mode or a low-pass [Hz].
    damping_range : tuple of float
        Bounds of a mode's damping ratio.
    polish : bool
        Polish jointly after each step; False: the base mode is held and each element keeps
        its screened parameters (a cheaper reselection).
    min_elements : int
        Add elements (the best of each step) up to this many whether or not they lower the
        train BIC (at most ``MAX_ELEMENTS``): the linear part refined one step further, the
        yardstick a second effect beside ``dynamics`` must beat (:mod:`.diagnose`).
    memo : dict or None
        Kept between calls with the same ``fit``, ``regressors``, ``column`` and start: where
        a call stopped on the train BIC (its state and the addition it turned down) is kept
        in it, and a later call with a larger ``min_elements`` goes on from there, as it would
        have (its earlier steps passed the test anyway), without making them again;
        ``memo["exhausted"]`` is set when a call ended with no element left to add (a larger
        ``min_elements`` then gives the same result).

    Returns
    -------
    fn, zeta : float
        The base mode after the last accepted step.
    elements : tuple
        The chosen extra elements (``()``: one mode).
    trace : list of dict
        Per accepted step, the ``structure`` (element kinds) and its train BIC relative to one
        mode.

    Examples
    --------
    A linear stage (no hysteresis) with two modes; the one-mode fit is a little off:

    >>> from scipy.signal import lfilter
    >>> dt = 1e-4
    >>> rng = np.random.default_rng(0)
    >>> h = np.r_[0.0, np.cumsum(rng.normal(size=4000))] * 1e-2  # input of the linear part
    >>> def mode(f, z):
    ...     return lfilter(*element_coefficients(("mode", f, z), dt), h)
    >>> y = 0.7 * mode(400.0, 0.1) + 0.3 * mode(900.0, 0.1) + rng.normal(0.0, 1e-4, h.size)
    >>> def regressors(fn, zeta, els):
    ...     return [np.column_stack((mode(fn, zeta), lti_columns(h, fn, zeta, els, dt)))], [y]
    >>> def fit(fn, zeta, els):
    ...     A = regressors(fn, zeta, els)[0][0]
    ...     return float(np.sum((A @ np.linalg.lstsq(A, y, rcond=None)[0] - y) ** 2))
    >>> def column(fn, zeta, el):
    ...     return [lti_columns(h, fn, zeta, [el], dt)[:, 0]]
    >>> fn, zeta, els, trace = select_order(fit, regressors, column, 420.0, 0.12, 4000.0,
    ...                                     (0.005, 0.9))
    >>> [e[0] for e in els], round(fn / 400.0, 2), round(els[0][1] / 900.0, 2)
    (['mode'], 1.0, 1.0)
    """
    def bic(rss: float, k: int) -> float:
        return n * np.log(max(rss, 1e-300) / n) + k * np.log(n)

    stop = None if memo is None else memo.get("stop")
    if stop is not None and len(stop[4]) < min_elements:  # on from where that run stopped
        n, b0, fn, zeta, elements, current, trace, found, polished = stop
        trace = list(trace)
    else:
        blocks, ys = regressors(fn, zeta, ())
        n = sum(y.size for y in ys)
        b0 = current = bic(fit(fn, zeta, ()), 0)
        elements: tuple = ()
        trace = [{"structure": ["mode"], "train_bic": 0.0}]
        found = _best_addition(blocks, ys, lambda el, f=fn, z=zeta: column(f, z, el),
                               elements, fmax, damping_range, fn)
        polished = None

    def stopped(polished_) -> None:  # the state a larger min_elements goes on from
        if memo is not None:
            memo["stop"] = (n, b0, fn, zeta, elements, current, tuple(trace), found, polished_)

    while found is not None:
        trial = elements + (found[0],)
        k = lti_k(trial)
        forced = len(elements) < min_elements
        if polished is not None:  # taken up where an earlier call stopped
            (fn2, zeta2, trial, score), polished = polished, None
        else:
            if not forced and not bic(found[1], k) < current:
                stopped(None)
                break
            if not polish:
                fn2, zeta2, score = fn, zeta, bic(found[1], k)
            else:
                # to half a BIC unit: an RSS change of rss / n moves n ln(RSS / n) by one
                fn2, zeta2, trial = polish_elements(fit, fn, zeta, trial, fmax, damping_range,
                                                    fatol=0.5 * found[1] / n)
                score = bic(fit(fn2, zeta2, trial), k)
            # the polish may improve the elements already chosen as well: credit the new
            # element only with what it adds at the polished point
            previous = bic(fit(fn2, zeta2, trial[:-1]), lti_k(elements)) if polish else current
            if previous < current:
                fn, zeta, elements, current = fn2, zeta2, trial[:-1], previous
        if not forced and not score < current:
            stopped((fn2, zeta2, trial, score))
            break
        fn, zeta, elements, current = fn2, zeta2, trial, score
        trace.append({"structure": ["mode"] + [e[0] for e in elements],
                      "train_bic": float(current - b0)})
        blocks, ys = regressors(fn, zeta, elements)
        found = _best_addition(blocks, ys, lambda el, f=fn, z=zeta: column(f, z, el),
                               elements, fmax, damping_range, fn)
    if found is None and memo is not None:  # no element left to add: any min_elements alike
        memo["exhausted"] = True
    return fn, zeta, elements, trace


def _pack(fn, zeta, elements) -> np.ndarray:
    return np.log(np.array([fn, zeta] + [float(v) for e in elements for v in e[1:]]))


def _unpack(x, elements) -> tuple[float, float, tuple]:
    v = np.exp(x)
    out, i = [], 2
    for e in elements:
        m = len(e) - 1
        out.append((e[0], *(float(u) for u in v[i:i + m])))
        i += m
    return float(v[0]), float(v[1]), tuple(out)


def polish_elements(cost: Callable, fn: float, zeta: float, elements: tuple, fmax: float,
                    damping_range: tuple[float, float], maxfev: int = 150,
                    fatol: float | None = None) -> tuple[float, float, tuple]:
    """Joint Nelder-Mead refinement (log scale) of the base mode and the elements' parameters.

    Parameters
    ----------
    cost : callable
        ``cost(fn, zeta, elements)``: the train RSS of the full fit.
    fn, zeta : float
        Base mode [Hz, -], the start.
    elements : tuple
        Extra elements, the start.
    fmax : float
        Highest frequency [Hz].
    damping_range : tuple of float
        Bounds of a damping ratio.
    maxfev : int
        Most cost evaluations.
    fatol : float, optional
        Stop when the costs of the simplex differ by less (and the parameters by less than
        0.1 %); default ``1e-9`` times the starting cost.

    Returns
    -------
    tuple
        ``(fn, zeta, elements)`` with the lowest cost found (the start if nothing is lower).

    Examples
    --------
    >>> def cost(fn, zeta, els):  # a bowl around 500 Hz, damping 0.1 and a 2 kHz mode
    ...     return (np.log(fn / 500)) ** 2 + (np.log(zeta / 0.1)) ** 2 + \\
    ...         (np.log(els[0][1] / 2000)) ** 2
    >>> fn, zeta, els = polish_elements(cost, 450.0, 0.12, (("mode", 1800.0, 0.1),), 4000.0,
    ...                                 (0.005, 0.9), maxfev=400)
    >>> round(fn), round(els[0][1], -1)
    (500, 2000.0)
    """
    x0 = _pack(fn, zeta, elements)

    def f(x):
        fn_, z_, els = _unpack(x, elements)
        if not (BASE_MIN_HZ <= fn_ <= fmax and damping_range[0] <= z_ <= damping_range[1] and
                all(_admissible(e, fmax, damping_range) for e in els) and
                _separated([fn_] + [e[1] for e in els if _kind(e) == "mode"])):
            return np.inf
        return cost(fn_, z_, els)

    steps = np.where(np.arange(x0.size) == 0, 0.03, 0.2)
    for i, e in enumerate(elements):  # a mode's frequency moves by a few percent
        if _kind(e) == "mode":
            steps[2 + sum(len(q) - 1 for q in elements[:i])] = 0.03
    simplex = [x0] + [x0 + np.eye(x0.size)[i] * s for i, s in enumerate(steps)]
    f0 = f(x0)
    r = nelder_mead(f, x0, initial_simplex=simplex, maxfev=maxfev, xatol=1e-3,
                    fatol=(1e-9 * f0 if fatol is None else fatol) if np.isfinite(f0) else 0.0)
    return _unpack(r.x, elements) if r.fun < f0 else (float(fn), float(zeta), tuple(elements))
