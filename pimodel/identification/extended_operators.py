"""Identification of the generalized, rate-dependent and creep operators from records.

- :func:`fit_generalized`: weights of a PI operator on a fixed radius grid between a ``tanh``
  (or affine) input envelope and a quadratic output envelope, all fitted together by bounded
  nonlinear least squares (``scipy.optimize.least_squares``) from a non-negative least-squares
  start. The loop shapes (branch curvature, saturation, asymmetry) fix the envelopes.
- :func:`fit_asymmetric`: distinct ascending/descending envelopes (``gamma_r = a_r phi + d_r``
  against ``gamma_l = phi``) and the shape ``phi`` by least squares, weights and the direct term
  by non-negative least squares inside (variable projection).
- :func:`fit_rate_dependent`: records at several rates; weights by non-negative least squares
  on a base-radius grid, the rate gain ``beta`` and the grid scale by a bounded search.
- :func:`fit_creep`: lag gains by non-negative least squares on a grid of time constants (two
  per decade),
  from the creep input ``u`` (the hysteresis output, e.g. a PI model's) and the measurement;
  steps with holds excite it best. :func:`fit_hysteresis_with_creep` alternates it with the
  hysteresis fit on the creep-compensated record, from the input ``v`` alone.

Every fit scores the samples after the input has reached both its maximum and its minimum
(from then on a rate-independent operator's state no longer depends on its initial state);
the models start with every play at the first input (a relaxed state). Errors are in the output
unit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares, minimize_scalar, nnls

from ..checks import as_signal, integer_in, positive_scalar
from ..operators.asymmetric import AsymmetricPI
from ..operators.cascade import Cascade
from ..operators.creep import CreepOperator
from ..operators.envelopes import Envelope
from ..operators.generalized import GeneralizedPI
from ..operators.pi import PIOperator, TimeDependentPI
from ..operators.rate_dependent import RateDependentPI

__all__ = ["OperatorFit", "fit_asymmetric", "fit_creep", "fit_generalized",
           "fit_hysteresis_with_creep", "fit_rate_dependent"]


@dataclass(frozen=True)
class OperatorFit:
    """Result of an identification.

    Parameters
    ----------
    model : GeneralizedPI, RateDependentPI or CreepOperator
        The identified operator.
    rms : float
        RMS residual on the scored samples (output unit).
    max_error : float
        Largest absolute residual on the scored samples (output unit).
    y_range : float
        Peak-to-peak of the measured output over the scored samples.
    settings : dict
        Fit settings and by-products (grid, rate sensitivity, ...).

    Examples
    --------
    >>> OperatorFit(model=None, rms=0.01, max_error=0.03, y_range=2.0).relative_rms
    0.005
    """

    model: object
    rms: float
    max_error: float
    y_range: float
    settings: dict = field(default_factory=dict)

    @property
    def relative_rms(self) -> float:
        """``rms / y_range``."""
        return self.rms / self.y_range if self.y_range > 0 else float("nan")


def _record(v, y, name: str = "", *, input: str = "v") -> tuple[np.ndarray, np.ndarray]:
    a, b = f"{input}{name}", f"y{name}"
    v = as_signal(v, a, min_length=10)
    y = as_signal(y, b, min_length=10)
    if v.size != y.size:
        raise ValueError(f"{a} and {b}: expected equal lengths, got {v.size} and {y.size}")
    if np.ptp(v) == 0:
        raise ValueError(f"{a}: the input is constant; identification needs a varying input")
    return v, y


def _scored(v: np.ndarray) -> int:
    """First sample after the input has reached both its extremes."""
    return int(max(np.argmax(v), np.argmin(v)))


def _stats(pred: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    e = pred - y
    return float(np.sqrt(np.mean(e**2))), float(np.max(np.abs(e))), float(np.ptp(y))


# -- generalized -----------------------------------------------------------------------------

def _input_envelope(kind: str, theta: np.ndarray, mid: float, half: float) -> Envelope:
    if kind == "identity":
        return Envelope.affine(1.0 / half, -mid / half)
    b1, b2 = np.exp(theta[0]), theta[1]
    return Envelope.tanh(1.0, b1 / half, b2 - b1 * mid / half, 0.0)


def fit_generalized(v, y, *, n_plays: int = 8, input_envelope: str = "tanh",
                    output_envelope: str = "poly2") -> OperatorFit:
    """Fit a :class:`~pimodel.operators.generalized.GeneralizedPI` to one record ``(v[k], y[k])``.

    The input is normalised to ``[-1, 1]`` (``vn = (v - mid) / half``); the input envelope is
    ``h(v) = tanh(b1 vn + b2)`` (or ``vn``), the radii are the grid
    ``r_i = (i - 1) / n * ptp(h(v)) / 2`` (``r_1 = 0``: invertible), the output envelope
    ``g(w) = c0 + w + c2 w^2`` (or ``c0 + w``). Weights ``p_i >= 0`` (``p_1 > 0``), ``b1``,
    ``b2``, ``c0``, ``c2`` minimise the squared output error on the scored samples.

    Parameters
    ----------
    v, y : array_like
        Input and measured output, same length (at least 10 samples).
    n_plays : int
        Plays on the radius grid (2..64).
    input_envelope : {"tanh", "identity"}
    output_envelope : {"poly2", "identity"}

    Returns
    -------
    OperatorFit
        ``model`` is a GeneralizedPI with ``r_1 = 0`` (so ``model.inverse()`` exists).

    Raises
    ------
    ValueError
        Bad record or settings, or an output envelope that is not increasing over the
        record's range.

    Examples
    --------
    >>> from pimodel.operators.envelopes import Envelope
    >>> v = 2 * np.sin(np.linspace(0, 30, 3000))
    >>> truth = GeneralizedPI([1.0, 0.4, 0.3], [0.0, 0.3, 0.8],
    ...                       output_envelope=Envelope.poly2(0.0, 1.0, 0.05))
    >>> fit = fit_generalized(v, truth.simulate(v), input_envelope="identity")
    >>> fit.relative_rms < 0.01
    True
    """
    v, y = _record(v, y)
    n = integer_in(n_plays, "n_plays", 2, 64)
    if input_envelope not in ("tanh", "identity"):
        raise ValueError(f"input_envelope: expected 'tanh' or 'identity', got {input_envelope!r}")
    if output_envelope not in ("poly2", "identity"):
        raise ValueError(f"output_envelope: expected 'poly2' or 'identity', got "
                         f"{output_envelope!r}")
    mid, half = 0.5 * (v.max() + v.min()), 0.5 * np.ptp(v)
    k0 = _scored(v)
    ys = y[k0:]
    yscale = max(float(np.ptp(ys)), 1e-300)
    n_h = 2 if input_envelope == "tanh" else 0
    use_c2 = output_envelope == "poly2"

    def plays(theta_h):
        h = _input_envelope(input_envelope, theta_h, mid, half)
        u = h.reference(v)
        r = np.arange(n) / n * 0.5 * np.ptp(u)
        F = PIOperator(np.ones(n), r, initial_state=u[0]).play_outputs(u)
        return h, r, F

    cache: dict = {}

    def play_block(theta_h):
        key = tuple(theta_h)
        if key not in cache:
            cache.clear()
            cache[key] = plays(theta_h)[2][k0:]
        return cache[key]

    def predict(x):
        F = play_block(x[:n_h])
        p = x[n_h:n_h + n]
        c2 = x[n_h + n + 1] / yscale if use_c2 else 0.0
        w = F @ p
        return x[n_h + n] + w + c2 * w * w

    def residual(x):
        return (predict(x) - ys) / yscale

    def jacobian(x):
        """Analytic in weights, c0, c2; central differences in the envelope parameters."""
        F = play_block(x[:n_h])
        p = x[n_h:n_h + n]
        c2 = x[n_h + n + 1] / yscale if use_c2 else 0.0
        w = F @ p
        J = np.empty((ys.size, x.size))
        for j in range(n_h):
            step = 1e-6 * max(1.0, abs(x[j]))
            xp, xm = x.copy(), x.copy()
            xp[j] += step
            xm[j] -= step
            J[:, j] = (predict(xp) - predict(xm)) / (2 * step)
        J[:, n_h:n_h + n] = F * (1.0 + 2.0 * c2 * w)[:, None]
        J[:, n_h + n] = 1.0
        if use_c2:
            J[:, n_h + n + 1] = w * w / yscale
        return J / yscale

    # start: nearly linear input envelope, output offset, non-negative weights
    theta0 = np.array([np.log(0.5), 0.0])[:n_h]
    _, _, F0 = plays(theta0)
    A = np.column_stack((F0[k0:], np.ones(ys.size), -np.ones(ys.size)))
    sol, _ = nnls(A, ys)
    p0 = np.maximum(sol[:n], 1e-9 * max(sol[:n].max(), 1e-300))
    x0 = np.concatenate((theta0, p0, [sol[n] - sol[n + 1]], [0.0] if use_c2 else []))
    lo = np.concatenate(([np.log(1e-3), -3.0][:n_h], np.full(n, 0.0), [-np.inf],
                         [-0.45] if use_c2 else []))
    hi = np.concatenate(([np.log(20.0), 3.0][:n_h], np.full(n, np.inf), [np.inf],
                         [0.45] if use_c2 else []))
    lo[n_h] = 1e-6 * p0.sum()  # p_1 > 0: the linear play keeps the model invertible
    x0 = np.clip(x0, lo, hi)
    res = least_squares(residual, x0, jac=jacobian, bounds=(lo, hi), x_scale="jac",
                        max_nfev=50 * (x0.size + 1))
    x = res.x
    h, r, F = plays(x[:n_h])
    p, c0 = x[n_h:n_h + n], float(x[n_h + n])
    c2 = float(x[n_h + n + 1]) / yscale if use_c2 else 0.0
    keep = p > 1e-9 * p.sum()
    keep[0] = True
    g = Envelope.poly2(c0, 1.0, c2)
    model = GeneralizedPI(p[keep], r[keep], input_envelope=h, output_envelope=g,
                          initial_state=float(h.reference(v[:1])[0]))
    try:
        pred = model.simulate(v)
    except ValueError as err:
        raise ValueError(f"fit_generalized: the fitted output envelope is not increasing over "
                         f"the record ({err})") from None
    rms, mx, rng = _stats(pred[k0:], ys)
    return OperatorFit(model, rms, mx, rng, {"n_plays": n, "input_envelope": input_envelope,
                                             "output_envelope": output_envelope,
                                             "scored_from": k0, "nfev": int(res.nfev)})


# -- asymmetric ------------------------------------------------------------------------------

def fit_asymmetric(v, y, *, n_plays: int = 8, shape: str = "tanh") -> OperatorFit:
    """Fit an :class:`~pimodel.operators.asymmetric.AsymmetricPI` to one record ``(v[k], y[k])``.

    ``phi(v) = tanh(b1 vn + b2)`` (or ``vn``) with ``vn = (v - mid) / half``; ascending envelope
    ``gamma_l = phi``, descending ``gamma_r = a_r phi + d_r``; radii on the grid
    ``r_i = (i - 1) / n * ptp(phi(v)) / 2``. For each ``(a_r, d_r, b1, b2)`` the direct weight,
    the play weights (all >= 0) and an output offset come from non-negative least squares on
    the scored samples; ``scipy.optimize.least_squares`` adjusts the envelope parameters. The
    offset is moved into both envelopes (``d += offset / sum p_i``).

    Parameters
    ----------
    v, y : array_like
        Input and measured output (at least 10 samples).
    n_plays : int
        Plays on the grid (2..64).
    shape : {"tanh", "identity"}

    Returns
    -------
    OperatorFit
        ``model`` has an exact inverse (``model.inverse()``).

    Raises
    ------
    ValueError
        Bad record or settings, or a fit in which every play weight is zero.

    Examples
    --------
    >>> truth = AsymmetricPI(0.3, [1.0, 0.5], [0.0, 0.4], ascending=(1.0, 0.0),
    ...                      descending=(1.3, 0.1))
    >>> v = 2 * np.sin(np.linspace(0, 30, 3000))
    >>> fit_asymmetric(v, truth.simulate(v), shape="identity").relative_rms < 0.01
    True
    """
    v, y = _record(v, y)
    n = integer_in(n_plays, "n_plays", 2, 64)
    if shape not in ("tanh", "identity"):
        raise ValueError(f"shape: expected 'tanh' or 'identity', got {shape!r}")
    mid, half = 0.5 * (v.max() + v.min()), 0.5 * np.ptp(v)
    k0 = _scored(v)
    ys = y[k0:]
    yscale = max(float(np.ptp(ys)), 1e-300)
    n_s = 2 if shape == "tanh" else 0

    def parts(theta):
        phi = _input_envelope(shape, theta[2:], mid, half)
        s = phi.reference(v)
        r = np.arange(n) / n * 0.5 * np.ptp(s)
        asc, desc = (1.0, 0.0), (float(np.exp(theta[0])), float(theta[1]))
        z0 = 0.5 * (s[0] + desc[0] * s[0] + desc[1])
        cols = [AsymmetricPI(1.0, [1.0], [ri], ascending=asc, descending=desc, shape=phi,
                             initial_state=z0).simulate(v) - s for ri in r]
        A = np.column_stack([s] + cols + [np.ones(v.size), -np.ones(v.size)])[k0:]
        x, _ = nnls(A, ys)
        return phi, r, asc, desc, z0, A, x

    def residual(theta):
        A, x = parts(theta)[5:]
        return (A @ x - ys) / yscale

    theta0 = np.concatenate(([0.0, 0.0], [np.log(0.5), 0.0][:n_s]))
    lo = np.concatenate(([np.log(0.2), -0.5], [np.log(1e-3), -3.0][:n_s]))
    hi = np.concatenate(([np.log(5.0), 0.5], [np.log(20.0), 3.0][:n_s]))
    res = least_squares(residual, theta0, bounds=(lo, hi), diff_step=1e-6,
                        max_nfev=40 * (theta0.size + 1))
    phi, r, asc, desc, z0, _, x = parts(res.x)
    p0, p, offset = float(x[0]), x[1:n + 1], float(x[n + 1] - x[n + 2])
    if p.sum() <= 0:
        raise ValueError("fit_asymmetric: every play weight is zero; the record shows no "
                         "hysteresis to fit")
    delta = offset / p.sum()
    keep = p > 1e-9 * p.sum()
    model = AsymmetricPI(max(p0, 1e-9 * p.sum()), p[keep], r[keep],
                         ascending=(asc[0], asc[1] + delta),
                         descending=(desc[0], desc[1] + delta), shape=phi,
                         initial_state=z0 + delta)
    rms, mx, rng = _stats(model.simulate(v)[k0:], ys)
    return OperatorFit(model, rms, mx, rng, {"n_plays": n, "shape": shape, "scored_from": k0,
                                             "nfev": int(res.nfev)})


# -- rate-dependent --------------------------------------------------------------------------

def _rates(v: np.ndarray, dt: float, lam: float) -> np.ndarray:
    """``rate[k]`` of :mod:`pimodel.operators.rate_dependent` (``v[-1] = v[0]``, ``rate[0] =
    0``)."""
    d = np.abs(np.diff(v, prepend=v[0])) / dt  # d[k] = |v[k] - v[k-1]|
    rate = np.empty(v.size)
    acc = 0.0
    for k in range(v.size):
        rate[k] = acc
        acc = lam * acc + (1 - lam) * d[k]
    return rate


def fit_rate_dependent(records: Sequence[tuple], *, dt: float, n_plays: int = 8,
                       rate_time_constant: float = 0.0,
                       max_rate_gain: float | None = None) -> OperatorFit:
    """Fit a :class:`~pimodel.operators.rate_dependent.RateDependentPI` to records at several rates.

    Base radii on the grid ``alpha_i = (i - 1) / n * s * ptp(v) / 2`` (``alpha_1 = 0``);
    for each ``(s, beta)`` the weights ``p_i >= 0`` come from one non-negative least-squares
    problem over all records (time-dependent plays with radii ``alpha_i (1 + beta rate[k])``);
    ``beta`` is found by a bounded scalar search on ``log beta`` (and ``beta = 0`` is tried),
    for a few grid scales ``s``.

    Parameters
    ----------
    records : sequence of (v, y)
        Records sampled every ``dt``, ideally periodic inputs at different rates.
    dt : float
        Sample time [s].
    n_plays : int
        Plays on the grid (2..64).
    rate_time_constant : float
        Rate filter of the model (:class:`~pimodel.operators.rate_dependent.RateDependentPI`).
    max_rate_gain : float, optional
        Upper bound of ``beta`` [s per input unit]; default ``100 / max rate``.

    Returns
    -------
    OperatorFit
        ``settings["rate_sensitivity"]`` is the model's rounding-error gain (below 1: the
        inverse is numerically exact).

    Raises
    ------
    ValueError
        No records, bad records or settings.

    Examples
    --------
    >>> t = np.arange(4000) * 1e-3
    >>> truth = RateDependentPI([1.0, 0.5, 0.3], [0.0, 0.2, 0.5], rate_gain=0.02, dt=1e-3)
    >>> recs = [(np.sin(2 * np.pi * f * t), None) for f in (1.0, 5.0)]
    >>> recs = [(v, truth.simulate(v)) for v, _ in recs]
    >>> fit_rate_dependent(recs, dt=1e-3, n_plays=6).relative_rms < 0.01
    True
    """
    if len(records) == 0:
        raise ValueError("records: expected at least one (v, y) record")
    recs = [_record(v, y, f"[{i}]") for i, (v, y) in enumerate(records)]
    dt = positive_scalar(dt, "dt")
    n = integer_in(n_plays, "n_plays", 2, 64)
    tau = float(rate_time_constant)
    if not np.isfinite(tau) or tau < 0:
        raise ValueError(f"rate_time_constant: expected a finite number >= 0, got {tau!r}")
    lam = float(np.exp(-dt / tau)) if tau > 0 else 0.0
    span = max(np.ptp(v) for v, _ in recs)
    rates = [_rates(v, dt, lam) for v, _ in recs]
    top_rate = max(float(r.max()) for r in rates) or 1.0
    beta_max = 100.0 / top_rate if max_rate_gain is None else positive_scalar(
        max_rate_gain, "max_rate_gain")
    starts = [_scored(v) for v, _ in recs]
    target = np.concatenate([y[k0:] for (_, y), k0 in zip(recs, starts, strict=True)])

    def solve(scale: float, beta: float):
        alpha = np.arange(n) / n * scale * span / 2
        F = np.vstack([
            TimeDependentPI(np.ones(n)).simulate(v, alpha[None, :] * (1 + beta * rt)[:, None],
                                                 initial_state=v[0], return_plays=True)[1][k0:]
            for (v, _), rt, k0 in zip(recs, rates, starts, strict=True)])
        p, _ = nnls(F, target)
        return float(np.sum((F @ p - target) ** 2)), alpha, p

    best = None
    for scale in (0.5, 0.8, 1.0):
        cost0 = solve(scale, 0.0)
        res = minimize_scalar(lambda lb, s=scale: solve(s, float(np.exp(lb)))[0],
                              bounds=(np.log(beta_max * 1e-6), np.log(beta_max)),
                              method="bounded", options={"xatol": 1e-3})
        for beta, cost in ((0.0, cost0[0]), (float(np.exp(res.x)), float(res.fun))):
            if best is None or cost < best[0]:
                best = (cost, scale, beta)
    _, scale, beta = best
    _, alpha, p = solve(scale, beta)
    p = np.maximum(p, 0.0)
    p[0] = max(p[0], 1e-9 * p.sum())  # keep the linear play: invertible
    keep = p > 1e-9 * p.sum()
    keep[0] = True
    model = RateDependentPI(p[keep], alpha[keep], rate_gain=beta, dt=dt,
                            rate_time_constant=tau)
    preds, ys = [], []
    for (v, y), k0 in zip(recs, starts, strict=True):
        state = np.concatenate((np.full(model.n, v[0]), [v[0], 0.0]))
        preds.append(model.simulate(v, state=state)[k0:])
        ys.append(y[k0:])
    rms, mx, rng = _stats(np.concatenate(preds), np.concatenate(ys))
    return OperatorFit(model, rms, mx, rng, {"n_plays": n, "grid_scale": scale,
                                             "rate_sensitivity": model.rate_sensitivity,
                                             "scored_from": starts})


# -- creep -----------------------------------------------------------------------------------

def fit_creep(u, y, *, dt: float, time_constants=None) -> OperatorFit:
    """Fit a :class:`~pimodel.operators.creep.CreepOperator` ``y = G[u]`` with non-negative lag
    gains.

    ``y - u = sum_i c_i x_i[u]`` is linear in ``c`` for fixed time constants (lags started at
    rest at ``u[0]``), solved by non-negative least squares. ``u`` is the creep's input: the
    hysteresis output (e.g. ``PIOperator.simulate(v)`` of an identified model); steps with long
    holds show the creep best.

    Parameters
    ----------
    u, y : array_like
        Creep input and measured output (same unit), sampled every ``dt``.
    dt : float
        Sample time [s].
    time_constants : array_like, optional
        Lag time constants [s]; default two per decade from ``10 dt`` to the record length.

    Returns
    -------
    OperatorFit
        Lags with zero gain are dropped (at least one kept).

    Raises
    ------
    ValueError
        Bad record or time constants.

    Examples
    --------
    >>> cr = CreepOperator([0.03, 0.02], [0.01, 0.1], dt=1e-3)
    >>> u = np.repeat([0.0, 1.0, -0.5, 0.8], 500)
    >>> fit = fit_creep(u, cr.simulate(u), dt=1e-3, time_constants=[0.01, 0.1, 1.0])
    >>> np.round(fit.model.gains, 6).tolist()
    [0.03, 0.02]
    """
    u, y = _record(u, y, input="u")
    dt = positive_scalar(dt, "dt")
    if time_constants is None:
        lo, hi = np.log10(10 * dt), np.log10(u.size * dt)  # hi >= lo: at least 10 samples
        tau = 10.0 ** np.arange(lo, hi + 1e-9, 0.5)
    else:
        tau = np.sort(as_signal(time_constants, "time_constants"))
    X = np.column_stack([CreepOperator([1.0], [ti], dt=dt, initial_state=u[0]).simulate(u) - u
                         for ti in tau])
    c, _ = nnls(X, y - u)
    keep = c > 1e-9 * max(float(c.max()), 1e-300)
    if not keep.any():
        keep[np.argmax(tau)] = True
    model = CreepOperator(c[keep], tau[keep], dt=dt, initial_state=u[0])
    rms, mx, rng = _stats(model.simulate(u), y)
    return OperatorFit(model, rms, mx, rng, {"time_constants": tau.tolist()})


def fit_hysteresis_with_creep(v, y, *, dt: float, n_plays: int = 16, iterations: int = 3,
                              output_envelope: str = "identity",
                              time_constants=None) -> OperatorFit:
    """Fit ``y = G[H[v]]``: a hysteresis operator ``H`` followed by creep ``G``.

    Alternates (``iterations`` times): ``G`` by :func:`fit_creep` from ``H[v]`` and ``y``; ``H``
    by :func:`fit_generalized` (identity input envelope) on the creep-compensated record
    ``G^-1[y]``. Starts from ``H`` fitted to ``y`` itself.

    Parameters
    ----------
    v, y : array_like
        Input and measured output, sampled every ``dt`` (holds show the creep best).
    dt : float
        Sample time [s].
    n_plays : int
        Plays of ``H``.
    iterations : int
        Alternations (1..10).
    output_envelope : {"identity", "poly2"}
        ``H``'s output envelope (``"poly2"`` for asymmetric loops).
    time_constants : array_like, optional
        Creep lags (default: :func:`fit_creep`'s grid).

    Returns
    -------
    OperatorFit
        ``model`` is a :class:`~pimodel.operators.cascade.Cascade` ``(H, G)`` with an exact inverse.

    Examples
    --------
    >>> from pimodel.operators.generalized import GeneralizedPI
    >>> truth = Cascade(GeneralizedPI([1.0, 0.5], [0.0, 0.3]),
    ...                 CreepOperator([0.03], [0.1], dt=1e-3))
    >>> v = np.concatenate((np.sin(np.linspace(0, 20, 2000)), np.repeat([0.5, -0.4], 1000)))
    >>> fit = fit_hysteresis_with_creep(v, truth.simulate(v), dt=1e-3, n_plays=8)
    >>> fit.relative_rms < 0.01
    True
    """
    v, y = _record(v, y)
    dt = positive_scalar(dt, "dt")
    its = integer_in(iterations, "iterations", 1, 10)
    hyst = fit_generalized(v, y, n_plays=n_plays, input_envelope="identity",
                           output_envelope=output_envelope).model
    for _ in range(its):
        creep = fit_creep(hyst.simulate(v), y, dt=dt, time_constants=time_constants).model
        compensated = creep.inverse().simulate(y)
        hyst = fit_generalized(v, compensated, n_plays=n_plays, input_envelope="identity",
                               output_envelope=output_envelope).model
    creep = fit_creep(hyst.simulate(v), y, dt=dt, time_constants=time_constants).model
    model = Cascade(hyst, creep)
    k0 = _scored(v)
    rms, mx, rng = _stats(model.simulate(v)[k0:], y[k0:])
    return OperatorFit(model, rms, mx, rng, {"n_plays": n_plays, "iterations": its,
                                             "scored_from": k0})
