"""The NumPy reference of a :class:`~pimodel.diagnosis.model.DiagnosedInverse`'s causal
feedforward: the per-sample solver of the static part (:class:`StaticInverse`, which
:meth:`DiagnosedInverse.simulate` steps over the record, :func:`solve_static`) and the causal
python-control block around it (:func:`inverse_block`). :meth:`DiagnosedInverse.block` returns
the same block stepped on the C core (:func:`pimodel.diagnosis.native_inverse.inverse_block`);
``tests/test_inverse_native.py`` holds the two equal to 1e-9, output and whole state.

``DiagnosedInverse.simulate`` is not causal when the model has dynamics or a delay: its
prefilter reads the reference ahead, by one sample for the zero-order hold of the dynamics'
approximate inverse (none when the linear part has a direct term) and by the delay ``d``
samples. The block runs the causal part and delays its output instead, by the latency

    A = advance + floor(d) + (1 if the delay has a fractional part else 0)
          + (1 for a filter before the hysteresis)                           samples,

so that, fed ``y_d[0..k]``, it outputs ``v[k] = v_batch[k - A]`` for ``k >= A`` (``v_batch =
DiagnosedInverse.simulate(y_d)``, exact to rounding, the last ``A`` batch samples aside, which
``simulate`` computes with the reference held) and, for ``k < A``, ``v_rest``, the inverse of
``y_d[0]`` at rest (``v_batch[0]`` when the reference rests at ``y_d[0]`` for its first
``A + 1`` samples). A model driven by the block then follows the reference delayed by ``A``:
with a reference at rest at its start, ``y[k] = y_batch[k - A]`` (``y_batch`` the model's
response to ``v_batch``), except a drift term (a function of time, not inverted). To track
``y_d`` itself, feed the block the reference ``A`` samples ahead (a known trajectory).

Per sample ``k``: the reference goes through the prefilter's filter (second-order sections,
:func:`~pimodel.diagnosis.lti.inverse_sos`, started at rest around ``y_d[0]``, as
:func:`~pimodel.diagnosis.lti.approximate_inverse`), the advanced sample ``j = k - A`` is
interpolated from its last two outputs (the delay's fraction), and the static part is inverted
sample by sample (:class:`StaticInverse`, the per-sample form of the model module's solver).
A filter before the hysteresis (a Wiener model, ``dynamics_position == "before"``) has no
prefilter; the solver gives the filter's output ``x`` and the sections of the filter's stable
approximate inverse (:func:`~pimodel.diagnosis.wiener.inverse_sections`, started at rest around
the first solver output, as :func:`~pimodel.diagnosis.wiener.inverse_prefilter`) give ``v``.
The batch advances that inverse by one sample (the zero-order hold); the block cannot, which
is its one more sample of latency.
"""

from __future__ import annotations

import math
from dataclasses import replace

import control
import numpy as np
from scipy.signal import sosfilt_zi

from .._native import LIMITS
from ..blocks.framework import BlockSettings, signal_labels, stepped_block
from .checks import block_dt
from .creep import creep_start_levels
from .lti import inverse_sos
from .monotone import monotone_model
from .rate import (
    SCALED,
    STEP_SHARE,
    play_bands,
    rate_growth,
    rate_params,
    rate_saturation,
    saturated_rate,
)
from .wiener import inverse_sections

__all__ = ["StaticInverse", "feedforward_block", "inverse_block", "inverse_latency",
           "solve_static"]

# the solved input's rate fed back: at most this times the fresh rate (the C core's constant)
RATE_FEEDBACK_CAP = LIMITS["PIM_DINV_RATE_FEEDBACK_CAP"]


def inverse_latency(model) -> int:
    """Samples by which :func:`inverse_block` delays the feedforward (module docstring).

    Parameters
    ----------
    model : DiagnosedModel
        The model whose inverse the block runs.

    Returns
    -------
    int
        ``A = advance + floor(d) + (1 if d has a fractional part above 1e-12)``, plus 1 for a
        filter before the hysteresis (its inverse's one-sample advance); 0 for a model
        without dynamics and delay.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0], [1.0], 0.0, dt=1e-3, effects=("dynamics", "delay"),
    ...                    params={"mode_hz": 50.0, "mode_damping": 0.5, "delay_samples": 2.5})
    >>> inverse_latency(m), inverse_latency(m.static_part())
    (4, 0)
    """
    d0, f = _delay(model)
    return _advance_of(model) + d0 + (1 if f > 0 else 0) + (1 if model.dynamics_before else 0)


def _delay(model) -> tuple[int, float]:
    """Whole and fractional parts of the model's delay (a fraction up to 1e-12 counts as 0)."""
    d = float(model.params["delay_samples"]) if "delay" in model.effects else 0.0
    if not (math.isfinite(d) and d >= 0):
        raise ValueError(f"params: delay_samples = {d!r}: expected a finite delay >= 0")
    d0 = math.floor(d)
    f = d - d0
    return d0, (f if f > 1e-12 else 0.0)


def _filter(model) -> tuple[np.ndarray | None, int]:
    """The prefilter's sections (None without dynamics after the hysteresis) and its advance
    (0 or 1)."""
    if "dynamics" not in model.effects or model.dynamics_before:
        return None, 0
    p = model.params
    return inverse_sos(p["mode_hz"], p["mode_damping"], p.get("lti_elements", ()),
                       p.get("lti_gains", ()), model.dt)


def _advance_of(model) -> int:
    return _filter(model)[1]


def solve_static(m, yd: np.ndarray, input_range: float, z0=None) -> np.ndarray:
    """Per-sample root of ``F_k(v) = yd[k]`` (module docstring of :mod:`.model`), the plays
    starting from ``z0`` (None: at rest at 0): :class:`StaticInverse` over the record, its root
    rule scaled by the reference's range (``DiagnosedInverse.simulate``'s solver).

    Parameters
    ----------
    m : DiagnosedModel
        The model (its dynamics and delay ignored).
    yd : numpy.ndarray
        The (prefiltered) reference.
    input_range : float
        Range of the rate effect's step rule.
    z0 : array_like, optional
        Start memory of the plays.

    Returns
    -------
    numpy.ndarray
        ``v[k]`` for ``yd[0..k]``.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> solve_static(m, np.array([0.1, 1.35, 0.35]), 1.0).round(9).tolist()
    [0.0, 1.0, 0.0]
    """
    inv = StaticInverse(m, input_range, float(np.ptp(yd)))
    x = inv.initial_state(z0)
    return np.array([inv.step(x, float(y)) for y in yd])


_NODES = {False: np.array([0.25, 0.75]), True: np.array([0.125, 0.375, 0.625, 0.875])}


def _roots(F, b: np.ndarray, target: float, *, cubic: bool) -> np.ndarray:
    """Roots of ``F - target`` between the breakpoints ``b``. Inside each segment ``F`` is a
    polynomial (linear, or cubic with the asymmetry) whose values at the breakpoints may jump
    (a play starts to move), so it is interpolated from interior nodes."""
    lo, width = b[:-1], np.diff(b)
    s = _NODES[cubic]
    vals = (F((lo[:, None] + s[None, :] * width[:, None]).ravel()) - target).reshape(lo.size,
                                                                                       s.size)
    coef = np.linalg.solve(np.vander(s, s.size), vals.T).T  # highest power first
    out = []
    if not cubic:
        slope, c0 = coef[:, 0], coef[:, 1]
        ok = slope != 0
        x = np.where(ok, -c0 / np.where(ok, slope, 1.0), -1.0)
        keep = ok & (x >= 0) & (x <= 1)
        return lo[keep] + x[keep] * width[keep]
    # a segment holds a root when the polynomial changes sign between its ends and its
    # extrema inside (closed form of the derivative's roots)
    a3, a2, a1 = coef[:, 0], coef[:, 1], coef[:, 2]
    disc = np.sqrt(np.maximum(4 * a2**2 - 12 * a3 * a1, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        ext = np.column_stack(((-2 * a2 + disc) / (6 * a3), (-2 * a2 - disc) / (6 * a3),
                               -a1 / (2 * a2)))
    ext = np.where(np.isfinite(ext) & (ext > 0) & (ext < 1), ext, 0.0)
    pts = np.column_stack((np.zeros(lo.size), np.ones(lo.size), ext))
    vals = ((a3[:, None] * pts + a2[:, None]) * pts + a1[:, None]) * pts + coef[:, 3:4]
    for i in np.flatnonzero((vals.min(axis=1) <= 0) & (vals.max(axis=1) >= 0)):
        rts = np.roots(np.trim_zeros(coef[i], "f")) if np.any(coef[i]) else np.array([0.0])
        real = rts[np.abs(rts.imag) < 1e-9].real
        out.extend(lo[i] + x * width[i] for x in real[(real >= -1e-12) & (real <= 1 + 1e-12)])
    return np.asarray(out, float)


class StaticInverse:
    """The exact inverse of a model's static part, one sample at a time: the per-sample form of
    ``DiagnosedInverse.simulate``'s solver on an already prefiltered reference (the module
    docstring of :mod:`pimodel.diagnosis.model` for the root and the approximations of the
    rate effect).

    Parameters
    ----------
    model : DiagnosedModel
        The model; its dynamics and delay are ignored (:meth:`DiagnosedModel.static_part`).
    input_range : float, optional
        Range of the rate effect's step rule; default ``2 r_n``.
    reference_range : float, optional
        Range of the (prefiltered) reference the root rule scales with: the jump that restarts
        the branch guess (1 %) and the search bracket (10 times). ``simulate`` takes
        ``ptp`` of the whole prefiltered reference; default 0 (the scale is then
        ``max(2 r_n, 1)``). It matters only where ``F_k`` has several roots.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> inv = StaticInverse(m)
    >>> x = inv.initial_state()
    >>> [round(inv.step(x, y), 9) for y in (0.1, 1.35, 0.35)]
    [0.0, 1.0, 0.0]
    """

    def __init__(self, model, input_range: float | None = None,
                 reference_range: float | None = None):
        # a model that folds is inverted through its nearest monotone one (model module docs)
        m = monotone_model(model.static_part())
        p, e, r = m.params, m.effects, m.radii
        self.model, self.r, self.w, self.w0 = m, r, m.weights, m.reference_weights
        n = self.n = r.size
        self.input_range = float(2 * r[-1] if input_range is None else input_range)
        rr = 0.0 if reference_range is None else float(reference_range)
        if not (math.isfinite(rr) and rr >= 0):
            raise ValueError(f"reference_range: expected a finite value >= 0, got {rr!r}")
        self.span = max(2 * float(r[-1]), rr / max(abs(self.w.sum()), 1e-12), 1.0)
        self.creep = "creep" in e
        self.m = 0
        self.record = 0
        self.starts = None  # the lags' common rest levels (module creep), or at rest at h0[0]
        if self.creep:
            taus = np.asarray(p["creep_time_constants_s"], float)
            self.a_lag = np.exp(-m.dt / taus)
            self.ga = np.asarray(p["creep_lag_gains"], float) * self.a_lag
            self.m = taus.size
            self.starts = creep_start_levels(p)
            # counted from each record's start (module creep): less sum_j g_j L_j[-1], the
            # lags' start h0[0] kept in the state (L0)
            self.record = int(p.get("creep_start") == "record")
            self.g_sum = float(np.sum(p["creep_lag_gains"]))
        self.asym = "asymmetry" in e
        self.rate = "rate" in e
        self.scaled = False
        if self.rate:
            gains, family, tau = rate_params(p)
            self.scaled = family == SCALED  # the exact shape: no fresh rate, no source
            self.rg, self.rw = np.zeros(n), np.zeros(n)  # per play: g_b r_i or g_b w0_i
            for g, idx in zip(gains, play_bands(n, gains.size), strict=True):
                if family == "radius":
                    self.rg[idx] = g * r[idx]
                elif family == SCALED:  # the scaled plays carry the weights w
                    self.rw[idx] = g * self.w[idx]
                else:
                    self.rw[idx] = g * self.w0[idx]
            self.step_size = STEP_SHARE * self.input_range
            self.tau = tau
            self.saturation = rate_saturation(p)
            self.a_rate = np.exp(-m.dt / tau) if tau > 0 else 0.0
            self.growth = rate_growth(p)
        if self.rate and not self.scaled:
            # the fresh rate's source: the inverse of the model without its rate term, in
            # lockstep (a low-passed rate counts every jump: no step rule)
            self.source = StaticInverse(replace(m, effects=tuple(x for x in e if x != "rate")),
                                        input_range, reference_range)
            self.source_step = self.step_size if tau == 0 else math.inf
        # state: started, v_prev, guess, z[n], L[m], (record start) L0, (rate) rho_f,
        # memory[n], v0_prev and the source's state; the positions once, as slices and indices
        self._z = slice(3, 3 + n)
        self._lags = slice(3 + n, 3 + n + self.m)
        self._l0 = 3 + n + self.m
        self._rho_f = 3 + n + self.m + self.record
        self._memory = slice(self._rho_f + 1, self._rho_f + 1 + n)
        self._v0_prev = self._rho_f + 1 + n
        self._source = slice(self._v0_prev + 1, None)
        self.size = self._rho_f + (0 if not self.rate else 1 + n if self.scaled else
                                   2 + n + self.source.size)

    def labels(self) -> list[str]:
        """Names of the state values.

        Returns
        -------
        list of str
            ``started``, ``v_prev``, ``guess`` (the root rule's branch guess), ``z[1..n]``,
            ``L[1..m]`` (creep lags), ``L0`` (the lags' start ``h0[0]`` of a creep counted
            from each record's start, ``creep_start`` ``"record"``) and, with a rate
            effect, ``rho_f``, ``m[1..n]``,
            ``v0_prev`` and ``source.*`` (the rate-free inverse that gives the fresh rate);
            the scaled family ``rate`` (its strictly causal rate [input unit / s]) and
            ``zs[1..n]`` (its plays).

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> StaticInverse(DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3)).labels()
        ['started', 'v_prev', 'guess', 'z[1]', 'z[2]']
        """
        rate = [] if not self.rate else ["rate"] + signal_labels("zs", self.n) if self.scaled \
            else (["rho_f"] + signal_labels("m", self.n) + ["v0_prev"]
                  + [f"source.{s}" for s in self.source.labels()])
        return (["started", "v_prev", "guess"] + signal_labels("z", self.n)
                + signal_labels("L", self.m) + ["L0"] * self.record + rate)

    def initial_state(self, z0=None) -> np.ndarray:
        """The state before the first sample: not started, the plays at rest at 0 (as
        ``simulate``) or at ``z0``.

        Parameters
        ----------
        z0 : array_like, optional
            The plays' outputs before the first sample (``DiagnosedInverse.initial_memory``
            for a record that starts where the memory is unknown); default zeros.

        Returns
        -------
        numpy.ndarray
            ``size`` values (:meth:`labels`); the rate source starts from the same plays.

        Raises
        ------
        ValueError
            ``z0`` not ``n`` finite values.

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> StaticInverse(DiagnosedModel([0.0], [1.0], 0.0, dt=1e-3)).initial_state().tolist()
        [0.0, 0.0, 0.0, 0.0]
        """
        x = np.zeros(self.size)
        if z0 is not None:
            z = np.asarray(z0, float)
            if z.shape != (self.n,) or not np.all(np.isfinite(z)):
                raise ValueError(f"z0: expected {self.n} finite play outputs, got shape "
                                 f"{z.shape}")
            x[self._z] = z
            if self.rate and not self.scaled:
                x[self._source] = self.source.initial_state(z)
        if self.scaled:  # the scaled plays start with the plays
            x[self._memory] = x[self._z]
        return x

    def step(self, x: np.ndarray, yk: float) -> float:
        """``v[k]`` for the (prefiltered) reference sample ``yk``; ``x`` advances in place.

        Parameters
        ----------
        x : numpy.ndarray
            The state after sample k - 1 (float64, :meth:`initial_state` at the start).
        yk : float
            The desired output of the static part at sample k.

        Returns
        -------
        float
            The input ``v[k]``.

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> inv = StaticInverse(DiagnosedModel([0.0], [2.0], 0.0, dt=1e-3))
        >>> round(inv.step(inv.initial_state(), 1.0), 12)
        0.5
        """
        m, p, r, w, w0 = self.model, self.model.params, self.r, self.w, self.w0
        first = x[0] == 0.0
        v_prev, guess = float(x[1]), float(x[2])
        z = x[self._z].copy()
        lags = x[self._lags].copy()
        if first and self.starts is not None:  # at their common rest before the first sample
            lags = self.starts.copy()
        creep_now = self.creep and (not first or self.starts is not None)
        rho_f = float(x[self._rho_f]) if self.rate else 0.0
        memory = x[self._memory].copy() if self.rate else None
        span = self.span
        if self.scaled:  # radii fixed by the rate of the samples before k (module .rate)
            rs = r * (1.0 + self._growth_of(rho_f))
            if first:  # at rest with the plays (as the model's first sample)
                memory = z.copy()
        elif self.rate:  # the fresh rate of sample k from the rate-free inverse v0 (not fed back)
            v0 = self.source.step(x[self._source], yk)  # advances the source's state in place
            dv0 = 0.0 if first else abs(v0 - x[self._v0_prev])
            fresh = dv0 / m.dt / p["rate_scale"] if dv0 <= self.source_step else 0.0
            x[self._v0_prev] = v0
            rho_k = float(saturated_rate(self.a_rate * rho_f + (1 - self.a_rate) * fresh,
                                         self.saturation))

        def F(vs):
            Zc = np.clip(z[None, :], vs[:, None] - r, vs[:, None] + r)
            y = Zc @ w + m.offset
            h0 = Zc @ w0 + m.reference_offset
            if creep_now:
                y = y + (self.ga * lags).sum() - self.ga.sum() * h0
            if self.record:  # less sum_j g_j L_j[-1]: h0[0] itself on the first sample
                y = y - self.g_sum * (h0 if first else x[self._l0])
            if self.asym:
                u = (h0 - p["center"]) / p["half_range"]
                y = y + p["asymmetry_quadratic"] * u**2 + p["asymmetry_cubic"] * u**3
            if self.scaled:  # the scaled plays less the plays (model module docstring)
                y = y + (np.clip(memory[None, :], vs[:, None] - rs, vs[:, None] + rs)
                         - Zc) @ self.rw
            elif self.rate and not first:  # the fresh rate (model module docstring)
                gap = vs[:, None] - Zc
                touch = (r > 0) & (np.abs(gap) >= r * (1 - 1e-9))
                y = y + np.where(touch, -np.sign(gap) * rho_k, memory) @ self.rg \
                    + rho_k * (Zc @ self.rw)
            return y

        b = np.concatenate((z - r, z + r, [v_prev]) +
                           ((memory - rs, memory + rs) if self.scaled else ()))
        b = np.unique(np.concatenate((b, [b.min() - 10 * span, b.max() + 10 * span])))
        roots = _roots(F, b, yk, cubic=self.asym)
        gb = np.abs(F(b) - yk)
        roots = np.concatenate((roots, b[gb <= 1e-10 * (1.0 + abs(yk))]))
        if roots.size:
            vk = float(roots[np.argmin(np.abs(roots - guess))])
        else:  # out of reach: the breakpoint closest to the target
            vk = float(b[np.argmin(gb)])
        z_new = np.clip(z, vk - r, vk + r)
        h = float(z_new @ w0 + m.reference_offset)
        if self.creep:
            lags = h + 0 * lags if first and self.starts is None else \
                self.a_lag * lags + (1 - self.a_lag) * h
        if self.scaled:
            memory = np.clip(memory, vk - rs, vk + rs)
            rho_f = self.a_rate * rho_f + (1 - self.a_rate) * (0.0 if first else
                                                               abs(vk - v_prev) / m.dt)
        elif self.rate and not first:
            dv = abs(vk - v_prev)
            rho = dv / m.dt / p["rate_scale"] if dv <= self.step_size or self.tau > 0 else 0.0
            rho = min(rho, RATE_FEEDBACK_CAP * fresh)  # (module docstring of .model)
            rho_f = self.a_rate * rho_f + (1 - self.a_rate) * rho
            gap = vk - z_new
            contact = (r > 0) & (np.abs(gap) >= r * (1 - 1e-9))
            memory = np.where(contact, -np.sign(gap) * saturated_rate(rho_f, self.saturation),
                              memory)
        x[2] = vk if first or abs(vk - v_prev) > 0.01 * span else 2 * vk - v_prev
        x[0], x[1] = 1.0, vk
        x[self._z] = z_new
        x[self._lags] = lags
        if self.record and first:
            x[self._l0] = h
        if self.rate:
            x[self._rho_f] = rho_f
            x[self._memory] = memory
        return vk

    def _growth_of(self, rate: float) -> float:
        """``g`` of the scaled family at the rate ``rate`` [input unit / s] (as the C core's
        ``pim_rdpi_sat_run``: ``beta rate / (1 + rate / sat)``)."""
        beta, s = self.growth / self.model.params["rate_scale"], self.saturation
        sat = 0.0 if s is None else s * self.model.params["rate_scale"]
        return beta * rate / (1.0 + rate / sat) if sat > 0 else beta * rate


def _sections_step(sos: np.ndarray, s: np.ndarray, u: float) -> float:
    """One sample of ``sos`` in transposed direct form II (as :func:`scipy.signal.sosfilt`);
    the states ``s`` (shape ``(sections, 2)``) advance in place."""
    for i, (b0, b1, b2, _, a1, a2) in enumerate(sos):
        y = b0 * u + s[i, 0]
        s[i, 0] = b1 * u - a1 * y + s[i, 1]
        s[i, 1] = b2 * u - a2 * y
        u = y
    return u


class _InverseStream:
    """The block's sample: prefilter sections, the delay's interpolation, the solver and, for a
    filter before the hysteresis, the sections of its inverse after the solver, on one flat
    state ``[started, seen, v_rest, F_prev, sections (2 each), post sections (2 each), solver
    state]``."""

    HEAD = 4

    def __init__(self, model, input_range, reference_range):
        self.solver = StaticInverse(model, input_range, reference_range)
        self.input_range = self.solver.input_range
        self.reference_range = 0.0 if reference_range is None else float(reference_range)
        self.sos, _ = _filter(model)
        self.zi = None if self.sos is None else sosfilt_zi(self.sos)
        self.ns = 0 if self.sos is None else self.sos.shape[0]
        self.post = (inverse_sections(model.params["wiener_elements"], model.dt)
                     if model.dynamics_before else None)
        self.post_zi = None if self.post is None else sosfilt_zi(self.post)
        self.np = 0 if self.post is None else self.post.shape[0]
        self.latency = inverse_latency(model)
        self.solve_from = self.latency - (1 if model.dynamics_before else 0)  # the delay's part
        self.frac = _delay(model)[1]
        self._s = slice(self.HEAD, self.HEAD + 2 * self.ns)
        self._post = slice(self._s.stop, self._s.stop + 2 * self.np)
        self.size = self._post.stop + self.solver.size

    def labels(self) -> list[str]:
        return (["started", "seen", "v_rest", "F_prev"] + signal_labels("f", 2 * self.ns)
                + signal_labels("g", 2 * self.np) + [f"solver.{s}" for s in self.solver.labels()])

    def step(self, x: np.ndarray, yd: float) -> float:
        """``v`` output at this sample; ``x`` advances in place."""
        s = x[self._s].reshape(self.ns, 2)
        post = x[self._post].reshape(self.np, 2)
        solver_x = x[self._post.stop:]
        if x[0] == 0.0:
            x[0] = 1.0
            if self.ns:
                s[:] = self.zi * yd
            if self.latency:  # the inverse of y_d[0] at rest (output until the first solve)
                x[2] = self.solver.step(self.solver.initial_state(), yd)
        fk = _sections_step(self.sos, s, yd) if self.ns else yd
        seen = int(x[1])
        v = float(x[2])
        if seen >= self.solve_from:
            ref = fk if self.frac == 0.0 else x[3] + (fk - x[3]) * self.frac
            v = self.solver.step(solver_x, ref)
            if self.np:  # the filter's inverse, at rest around the first solver output
                if seen == self.solve_from:
                    post[:] = self.post_zi * v
                v = _sections_step(self.post, post, v)
        if seen < self.latency:
            v = float(x[2])
            x[1] = seen + 1
        x[3] = fk
        return v


def inverse_block(inverse, dt: float | None = None, *, name: str = "inverse",
                  input: str = "y_d", output: str = "v", input_range: float | None = None,
                  reference_range: float | None = None) -> control.NonlinearIOSystem:
    """The causal feedforward as a discrete python-control block, stepped in NumPy (the
    reference of :func:`pimodel.diagnosis.native_inverse.inverse_block`; module docstring).

    Parameters
    ----------
    inverse : DiagnosedInverse
        The inverse.
    dt : float, optional
        Sample time [s]; must be the model's ``dt`` (default).
    name, input, output : str
        Block name (params prefix) and signal names.
    input_range : float, optional
        Range of the rate effect's step rule; default ``2 r_n`` (as ``simulate``).
    reference_range : float, optional
        :class:`StaticInverse`'s scale of the root rule; ``simulate`` uses
        ``ptp(inverse.prefilter(y_d))``.

    Returns
    -------
    control.NonlinearIOSystem
        ``v[k] = v_batch[k - A]`` (``A`` = :func:`inverse_latency`; ``v_rest`` before), direct
        feedthrough when ``A = 0``; initial state all zeros; params ``"<name>.input_range"``,
        ``"<name>.reference_range"``. The latency is also the block's attribute ``latency``.

    Raises
    ------
    ValueError
        ``dt`` other than the model's, a bad model parameter.

    Examples
    --------
    >>> import control
    >>> from pimodel.blocks import initial_state
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> blk = inverse_block(m.inverse())
    >>> res = control.input_output_response(blk, np.arange(3) * 1e-3, [0.1, 1.35, 0.35],
    ...                                     initial_state=initial_state(blk))
    >>> res.outputs.round(9).tolist(), blk.latency
    ([0.0, 1.0, 0.0], 0)
    """
    return feedforward_block(inverse, dt, lambda ir, rr: _InverseStream(inverse.model, ir, rr),
                             name=name, input=input, output=output, input_range=input_range,
                             reference_range=reference_range)


def feedforward_block(inverse, dt: float | None, make, *, name: str, input: str, output: str,
                      input_range: float | None, reference_range: float | None
                      ) -> control.NonlinearIOSystem:
    """The python-control block around a feedforward runner, NumPy or C.

    Parameters
    ----------
    inverse : DiagnosedInverse
        The inverse.
    dt : float or None
        Sample time [s]; must be the model's ``dt`` (None: the model's).
    make : callable
        ``make(input_range, reference_range)`` builds the runner (this module's per-sample
        stream, or :class:`~pimodel.diagnosis.native_inverse.NativeInverse`): ``step(x,
        y_d)`` (``x`` advances in place), ``labels()``, ``latency``, ``input_range``,
        ``reference_range``.
    name, input, output : str
        Block name (params prefix) and signal names.
    input_range, reference_range : float or None
        The runner's defaults (the block's params ``"<name>.input_range"``,
        ``"<name>.reference_range"``).

    Returns
    -------
    control.NonlinearIOSystem
        States ``labels()``, initial state all zeros, attribute ``latency``.

    Raises
    ------
    ValueError
        ``dt`` other than the model's, or what ``make`` raises.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> inv = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3).inverse()
    >>> blk = feedforward_block(inv, None, lambda ir, rr: _InverseStream(inv.model, ir, rr),
    ...                         name="ff", input="y_d", output="v", input_range=None,
    ...                         reference_range=None)
    >>> blk.latency, blk.nstates
    (0, 9)
    """
    dt = block_dt(inverse.model, dt, "its filter and delay")
    runner = make(input_range, reference_range)
    defaults = {"input_range": runner.input_range, "reference_range": runner.reference_range}
    settings = BlockSettings(name, defaults, lambda s: make(s["input_range"],
                                                            s["reference_range"]))
    labels = runner.labels()

    def step(ff, x, yd, t):
        return ff.step(x, yd), x

    blk = stepped_block(settings, step, own_state=lambda params: np.zeros(len(labels)),
                        states=labels, dt=dt, name=name, input=input, output=output, memo=True)
    blk.latency = runner.latency
    return blk
