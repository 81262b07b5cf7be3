"""The model a diagnosis chose, as one object: forward simulation and a causal feedforward
inverse (:meth:`pimodel.diagnosis.DiagnosisReport.model`).

The diagnosis fits every candidate *jointly* with the hysteresis weights, in a parallel form
(:mod:`.effects`): with ``Z`` the play outputs of the radius grid (plays at rest at
``z_i[-1] = z_s``, then ``z_i[k] = Gamma_{r_i}[v][k]``; ``z_s = v[0]`` when
``plays_start == "v0"``, as the diagnosis' nominal since issue 33, else 0) and
``h0 = Z w0 + c0`` the reference hysteresis output the effect columns are built from::

    y[k] = (D Z)[k] w + c                                    hysteresis (weights w, offset c)
         + sum_i g_i (L_i[h0][k] - h0[k])                     creep: lags L_i, tau_i (s)
         + q u[k]^2 + c3 u[k]^3,  u = (h0 - center) / half    asymmetry (static output terms)
         + sum_b g_b R_b[k]                                   rate (radii or weights, .rate)
         + s t_clock[k] (+ c_j)                               drift (record or shared clock;
                                                              or a level c_j per record;
         (or + D (1 - exp(-(t[k] - t_s) / T)))                or a settling, shared clock)
         + sum_j g_j (D' (E_j - M_1)[h0])[k]                  dynamics: further elements

where ``D`` is the identity, the unit-gain base mode ``M_1`` (ZOH, ``(D Z)[k]`` depends on
``Z[0..k-1]``) and/or a delay of ``d`` samples (fractional: linear interpolation); ``D'`` the
delay alone. A delay acts on the input of everything the plays drive: with it, ``h0`` in the
creep and asymmetry terms is ``h0`` delayed by ``d`` samples too (held at ``h0[0]`` before the
start). ``E_j`` are the further modes, low-pass and direct term of the linear part
(:mod:`.lti`). ``L_i`` is the exact
first-order lag at rest around ``h0[0]``: ``L[k] = a L[k-1] + (1 - a) h0[k]``,
``a = exp(-dt / tau)``; with ``creep_start == "common"`` (a stage parked between records,
:mod:`.creep`) each lag rests instead at its level ``s_i`` of ``creep_start_levels``,
``L_i[-1] = s_i``, shared by every record; with ``creep_start == "record"`` the lags start as
at rest and the creep is counted from the record's start, ``g_i (L_i[k] - h0[k] - L_i[-1])``
(the record's first output un-crept). This class evaluates exactly that form, so
:meth:`simulate` equals the diagnosis' own prediction. The same form, streamed sample by sample on
the C core (:mod:`.native_model`), is the python-control block (:meth:`DiagnosedModel.block`) and
the DiagnosedModel FMU unit (``pimodel fmu build --model MODEL.json``); a test holds them equal to
:meth:`simulate` to 1e-12.

The inverse solves, sample by sample, ``F_k(v[k]) = y_d[k]``: with the play states, the lags
and the rate memory of sample k - 1 fixed, ``F_k`` is a polynomial of degree at most 3 in
``v[k]`` between the play breakpoints ``z_i[k-1] -+ r_i`` (and ``v[k-1]``), so the root is
exact to rounding. Exact (round trip to 1e-9) for the nominal model and
for creep and asymmetry, alone or together, while ``F_k`` is monotone near the input. The
plays start at rest at 0 (``plays_start == "v0"``: at rest at the ``v[0]`` that puts the
first sample on ``y_d[0]``, :meth:`DiagnosedInverse.first_input`), or, when the diagnosis
took the stage's initial memory as unknown (``initial_state="unknown"``), from the memory of
one reversal that puts ``y_d[0]`` on the model's output at the input 0
(:meth:`DiagnosedInverse.initial_memory`).
A model without creep, asymmetry or a first-order rate (the rate's ``"scaled"`` family may be
there) whose hysteresis weights fold (a partial sum
``w_1 + ... + w_m <= 0``, as signed
fine-grid least squares can give: its branches turn back, and the root the inverse follows
vanishes there, so it jumped to a far one) is inverted through its nearest monotone model
(:func:`.monotone.monotone_model`: branch slopes at least a floor, the branch curve closest in
the maximum norm): the inverse is then exact for that model, misses the folding model by at
most the documented branch distance, and its one-sample step is at most the reference's step
over the floor slope. A monotone model is inverted as it is.
Approximations, by choice:

* **rate**: the rate of sample k is not taken from the solution's own ``v[k]``. The model's
  filtered rate is ``rho_f[k] = a rho_f[k-1] + (1 - a) rho[k]`` with the instantaneous
  ``rho[k] = |v[k] - v[k-1]| / (dt rate_scale)`` (``a = 0`` without a filter). The inverse
  keeps the model's own ``rho_f[k-1]`` (of its solution) and takes the fresh ``rho[k]`` from a
  source that does not feed back: the rate of ``v0``, the inverse of the model without its rate
  term (the same step rule); ``v0[k]`` depends on ``y_d[0..k]``, so the feedforward stays
  causal. With that ``rho_f[k]``, ``F_k`` is again piecewise linear and solved exactly; the
  plays' held terms take the solution's own rate at their last contact, as the model does. The
  model's term then differs from the assumed one by ``(1 - a) (rho[k] - rho_v0[k])``: the
  round trip is close, not exact. Why not exact: with the rate of ``v[k]`` itself the model is,
  linearised on a branch, ``y[k] = A v[k] + B' (v[k] - v[k-1])`` with ``B' = -sum g_b r_i /
  (dt rate_scale)``, a zero at ``z = B' / (A + B')``; on ``pimodel.stages.pi_stage`` (``tau = 0``)
  ``z`` is 1.8 to 2.1 (the fitted models and the truth alike), so the exact inverse is unstable
  (an error grows about 2x per sample). A rate held from sample k - 1 (the earlier choice,
  ``A z^2 + B' z - B' = 0``: complex roots of modulus 1.4) makes the feedforward oscillate
  from sample to sample (it tracked worse than the nominal inverse, 0.71x to 0.94x), and
  repeated passes, each on the previous pass' rate, diverge after the first. Measured
  open-loop cuts against the nominal inverse: ``pimodel.stages.pi_stage`` rate 8.9x to 9.3x,
  ``pimodel.stages.preisach_stage`` rate 28x to 47x (``docs/notes/ff-rate.md``).
* **delay**: not inverted; the feedforward is advanced by the delay (``y_d[k + d]``, linear
  interpolation): it needs the reference ``d`` samples ahead (a known trajectory).
* **dynamics**: the linear part ``G`` is replaced by a stable approximate inverse
  (:func:`.lti.approximate_inverse`): ``G(s)^-1`` with right-half-plane zeros mirrored, times
  a low-pass ``(s / wf + 1)^-r`` (``r`` the relative degree, ``wf`` twice the fastest pole;
  for one mode ``M(s)^-1 / (s / (2 w) + 1)^2``), discretised with Tustin, and a one-sample
  advance for the zero-order hold; the reference is filtered by it, then the static part is
  inverted.
* **dynamics before the hysteresis** (``dynamics_position == "before"``, a Wiener model,
  :mod:`.wiener`): the play outputs are those of the filtered input ``F[v]``; the inverse solves
  the static part for the filter's output ``x``, then passes ``x`` through a stable
  approximate inverse of ``F`` (:func:`.wiener.inverse_prefilter`: ``F(s)^-1`` times a low-pass
  of its order at twice its fastest pole, Tustin, one-sample advance), approximate like the
  dynamics after it.
* **drift**: not inverted (an additive term in time; compensating it would extrapolate a
  fitted trend), the offset is.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import brentq

from .._native import LIMITS
from ..operators.base import check_finite
from ..operators.pi import PIOperator
from .checks import checked_signal
from .creep import creep_start_levels, record_level
from .drift import drift_term
from .filters import lag, mode, shift
from .lti import approximate_inverse, lti_columns
from .monotone import monotone_model
from .native_inverse import NativeInverse, inverse_block
from .native_model import diagnosed_block
from .rate import (
    SCALED,
    play_bands,
    rate_columns,
    rate_growth,
    rate_params,
    rate_saturation,
    scaled_plays,
)
from .reference_inverse import solve_static
from .wiener import inverse_prefilter, prefilter

if TYPE_CHECKING:
    import control

__all__ = ["DiagnosedInverse", "DiagnosedModel", "load_diagnosed_model"]

KIND = "DiagnosedModel"
INITIAL_STATES = ("rest", "unknown")  # as diagnose(initial_state=...)
PLAYS_STARTS = ("zero", "v0")  # plays at rest at 0, or at the first input v[0]


@dataclass(frozen=True)
class DiagnosedModel:
    """Nominal or augmented model of a diagnosis (module docstring for the form).

    Parameters
    ----------
    radii : array_like
        Play radii ``r_i`` [input units], the diagnosis' grid (``r_1 = 0``).
    weights, offset
        Hysteresis weights ``w`` and offset ``c`` [output units].
    dt : float
        Sample time [s].
    effects : tuple of str
        The effects of the model (``()``: nominal).
    reference_weights, reference_offset
        ``w0``, ``c0`` of ``h0`` (the diagnosis' nominal fit the effect columns use).
    params : dict
        Effect parameters: ``creep_lag_gains``, ``creep_time_constants_s`` (and
        ``creep_start = "common"`` with ``creep_start_levels``, the lags' rest levels [output
        unit], when they start at a common rest; or ``creep_start = "record"``, the creep
        counted from each record's start, less ``sum_i g_i L_i[-1]``, :mod:`.creep`);
        ``asymmetry_quadratic``, ``asymmetry_cubic``, ``center``, ``half_range``;
        ``rate_gains``, ``rate_family``, ``rate_time_constant_s``, ``rate_scale``
        (:mod:`.rate`); ``drift_per_s``, ``drift_clock`` (and ``drift_variant``,
        ``drift_t0_train`` for a level per record; ``drift_settling``,
        ``drift_settling_time_s``, ``drift_settling_start_s`` for a settling, :mod:`.drift`);
        ``mode_hz``, ``mode_damping``, ``lti_elements``, ``lti_gains`` (:mod:`.lti`), or
        ``dynamics_position = "before"`` and ``wiener_elements`` (:mod:`.wiener`);
        ``delay_samples``.
    initial_state : {"rest", "unknown"}
        The diagnosis' assumption on the stage's memory at the start of a record
        (:func:`~pimodel.diagnosis.diagnose`); the default of :meth:`DiagnosedInverse.simulate`
        (``"unknown"``: the inverse starts from the memory that puts ``y_d[0]`` on the model's
        output at rest, :meth:`DiagnosedInverse.initial_memory`). :meth:`simulate` starts at
        rest either way (it has no output to match).
    plays_start : {"zero", "v0"}
        Where the plays rest before the first sample: at 0 (``z_i[-1] = 0``, the default and
        the form of models saved before issue 33) or at the record's first input
        (``z_i[-1] = v[0]``; a Wiener model's plays of the filtered input at its first sample),
        as the diagnosis' nominal fitted them (``report.nominal["model"]["plays_start"]``).
        :meth:`simulate`, the C stream, the block and the DiagnosedModel FMU
        (``plays_start = 1``) all follow it.

    Examples
    --------
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> v = np.sin(np.linspace(0, 6, 300))
    >>> bool(np.max(np.abs(m.inverse().simulate(m.simulate(v)) - v)) < 1e-9)
    True
    """

    radii: np.ndarray
    weights: np.ndarray
    offset: float
    dt: float
    effects: tuple = ()
    reference_weights: np.ndarray | None = None
    reference_offset: float = 0.0
    params: dict = field(default_factory=dict)
    initial_state: str = "rest"
    plays_start: str = "zero"

    def __post_init__(self):
        r = np.asarray(self.radii, float)
        w = np.asarray(self.weights, float)
        if r.ndim != 1 or r.size == 0 or w.shape != r.shape:
            raise ValueError(f"weights: expected {r.size} values like radii, got {w.shape}")
        if np.any(r < 0) or np.any(np.diff(r) < 0):
            raise ValueError("radii: expected non-negative, ascending values")
        _check_limits(r.size, self.params)
        if not self.dt > 0:
            raise ValueError(f"dt: expected > 0, got {self.dt!r}")
        bad = set(self.effects) - {"creep", "asymmetry", "rate", "drift", "dynamics", "delay"}
        if bad:
            raise ValueError(f"effects: unknown {sorted(bad)}")
        if "creep" in self.effects:
            creep_start_levels(self.params)  # a common rest's levels checked
        w0 = w if self.reference_weights is None else np.asarray(self.reference_weights, float)
        if w0.shape != r.shape:
            raise ValueError(f"reference_weights: expected {r.size} values, got {w0.shape}")
        object.__setattr__(self, "radii", r)
        object.__setattr__(self, "weights", w)
        object.__setattr__(self, "reference_weights", w0)
        object.__setattr__(self, "offset", float(self.offset))
        object.__setattr__(self, "reference_offset", float(
            self.offset if self.reference_weights is None else self.reference_offset))
        object.__setattr__(self, "effects", tuple(self.effects))
        if self.initial_state not in INITIAL_STATES:
            raise ValueError(f"initial_state: expected one of {INITIAL_STATES}, got "
                             f"{self.initial_state!r}")
        if self.plays_start not in PLAYS_STARTS:
            raise ValueError(f"plays_start: expected one of {PLAYS_STARTS}, got "
                             f"{self.plays_start!r}")

    # -- construction -------------------------------------------------------------------
    @classmethod
    def from_fit(cls, fitted: dict, *, augmented: bool = True) -> DiagnosedModel:
        """The model from a diagnosis' internals (``DiagnosisReport.fitted``)."""
        radii, V = fitted["radii"], fitted["projection"]
        n = radii.size

        def play_weights(coef, q):
            return V @ coef[:q] if V is not None else coef[:n]

        if not augmented:
            nom = fitted["nominal"]
            return cls(radii, nom.coef[:n], float(nom.coef[n]), fitted["dt"], (),
                       params={"rate_scale": nom.params["rate_scale"]},
                       initial_state=fitted.get("initial_state", "rest"),
                       plays_start=fitted.get("plays_start", "zero"))
        model, ref = fitted["model"], fitted["reference"]
        q = n if V is None else V.shape[1]
        params = dict(model.params)
        params.update({k: ref.params[k] for k in ("center", "half_range", "rate_scale")})
        if "fn" in model.grid:
            params["mode_hz"], params["mode_damping"] = model.grid["fn"], model.grid["zeta"]
        return cls(radii, play_weights(model.coef, q), float(model.coef[q]), fitted["dt"],
                   tuple(fitted["chosen"]), play_weights(ref.coef, q), float(ref.coef[q]),
                   params, fitted.get("initial_state", "rest"),
                   fitted.get("plays_start", "zero"))

    # -- forward ------------------------------------------------------------------------
    def _clock(self, v: np.ndarray, t) -> np.ndarray:
        if t is None:
            return np.arange(v.size) * self.dt
        t = np.asarray(t, float)
        if t.shape != v.shape:
            raise ValueError(f"t: expected {v.size} samples like v, got {t.shape}")
        return t

    def simulate(self, v, t=None, *, input_range: float | None = None,
                 measured=None) -> np.ndarray:
        """Output ``y[k]`` for the input ``v[k]`` (plays at rest before ``v[0]``: at 0, or at
        ``v[0]`` itself when :attr:`plays_start` is ``"v0"``).

        Parameters
        ----------
        v : array_like
            Input samples, every ``dt``.
        t : array_like, optional
            Times [s] (for a drift on the shared clock); default ``k dt``.
        input_range : float, optional
            Rate effect without a filter: a one-sample jump above ``STEP_SHARE`` of this range
            counts as a step (no rate); default ``ptp(v)``, as the diagnosis.
        measured : array_like, optional
            The record's measured output, used as the diagnosis uses it on a validate record:
            a drift with a level per record (``drift_variant`` ``"levels"`` or
            ``"settle_levels"``) takes the record's level from it out of fold
            (:func:`.drift.drift_term`; without it, the level the drift's clock predicts);
            with :attr:`initial_state` ``"unknown"``, the creep's lags start at its first
            sample ``measured[0]`` (the creep of the stage's unknown memory; without it, at
            ``h0[0]``); a creep counted from each record's start (``creep_start``
            ``"record"``) takes the record's level from it out of fold, bounded
            (:func:`.creep.record_level`; without it, none). Ignored by other models.

        Returns
        -------
        numpy.ndarray

        Raises
        ------
        ValueError
            ``v`` not a finite 1-D signal, ``t`` of another length, or an output float64
            cannot hold (the sample is named; docs/reliability.md).

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> m.simulate([0.0, 1.0, 0.0]).round(3).tolist()
        [0.1, 1.35, 0.35]
        """
        v = checked_signal(v, "v")
        tk = self._clock(v, t)
        p, e = self.params, self.effects
        Z = self._plays(v)
        Zp = Z
        if self.dynamics_before:  # the plays of the filtered input (module wiener)
            Zp = self._plays(prefilter(v, p["wiener_elements"], self.dt))
        elif "dynamics" in e:
            Zp = mode(Zp, p["mode_hz"], p["mode_damping"], self.dt)
        if "delay" in e:
            Zp = shift(Zp, p["delay_samples"])
        y = Zp @ self.weights + self.offset
        h0 = Z @ self.reference_weights + self.reference_offset
        if "dynamics" in e and not self.dynamics_before and p.get("lti_elements"):
            # the linear part's further elements
            cols = lti_columns(h0, p["mode_hz"], p["mode_damping"], p["lti_elements"], self.dt)
            if "delay" in e:
                cols = shift(cols, p["delay_samples"])
            y = y + cols @ np.asarray(p["lti_gains"], float)
        if "delay" in e:  # the delay acts on the input: the effect terms' h0 delayed too
            h0 = shift(h0, p["delay_samples"])
        y_meas = None if measured is None else checked_signal(measured, "measured")
        if y_meas is not None and y_meas.shape != v.shape:
            raise ValueError(f"measured: expected {v.size} samples like v, got {y_meas.shape}")
        if "creep" in e:
            # memory unknown at the start: the lags start at the measured first output
            y0 = float(y_meas[0]) if y_meas is not None and self.initial_state == "unknown" \
                else None
            starts = creep_start_levels(p)  # a common rest: where each lag starts
            # counted from the record's start (module creep): less each lag's start
            record = p.get("creep_start") == "record"
            for i, (g, tau) in enumerate(zip(p["creep_lag_gains"], p["creep_time_constants_s"],
                                             strict=True)):
                start = y0 if starts is None else float(starts[i])
                less = (float(h0[0]) if start is None else start) if record else 0.0
                y = y + g * (lag(h0, tau, self.dt, start) - h0 - less)
        if "asymmetry" in e:
            u = (h0 - p["center"]) / p["half_range"]
            y = y + p["asymmetry_quadratic"] * u**2 + p["asymmetry_cubic"] * u**3
        if "rate" in e and p.get("rate_family") == SCALED:  # sum_i g_b w_i (zs_i - z_i)
            gains, _, tau = rate_params(p)
            Zs = scaled_plays(v, self.radii, self.dt, p["rate_scale"], tau, rate_saturation(p),
                              rate_growth(p), float(v[0]) if self.plays_start == "v0" else 0.0)
            per_play = np.repeat(gains, [b.size for b in play_bands(self.radii.size,
                                                                     gains.size)])
            y = y + (Zs - Z) @ (self.weights * per_play)
        elif "rate" in e:
            gains, family, tau = rate_params(p)
            R = rate_columns(Z, self.radii, v, self.dt, p["rate_scale"], self.reference_weights,
                             tau, family, gains.size, input_range=input_range,
                             saturation=rate_saturation(p))
            y = y + R @ gains
        if "drift" in e:
            y = y + drift_term(p, tk, y, y_meas)
        if "creep_record_reference" in p and y_meas is not None:
            y = y + record_level(p, h0[0], y_meas - y)
        return check_finite(y, v, "v")

    def _plays(self, x: np.ndarray) -> np.ndarray:
        """Play outputs of ``x`` on the grid, at rest at ``x[0]`` or 0 (:attr:`plays_start`)."""
        z0 = float(x[0]) if self.plays_start == "v0" else 0.0
        return PIOperator(np.ones(self.radii.size), self.radii,
                          initial_state=z0).play_outputs(x)

    def inverse(self) -> DiagnosedInverse:
        """The causal feedforward inverse (module docstring: exact or approximate per effect).

        Returns
        -------
        DiagnosedInverse
            Its ``simulate(y_d)`` gives the input that makes this model follow ``y_d``.

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> m.inverse().simulate([0.1, 1.35, 0.35]).round(6).tolist()
        [0.0, 1.0, 0.0]
        """
        return DiagnosedInverse(self)

    def block(self, dt: float | None = None, *, name: str = "diagnosed", input: str = "v",
              output: str = "y", input_range: float | None = None
              ) -> control.NonlinearIOSystem:
        """The model as a discrete python-control block (C core step, :mod:`.native_model`).

        Every forward form streams, a Wiener model (``dynamics_position == "before"``) too:
        its filter runs as sections in series on ``v`` before a second set of plays, as
        ``simulate``.

        Parameters
        ----------
        dt : float, optional
            Sample time [s]: the model's ``dt`` (default; another value raises).
        name, input, output : str
            Block name (prefix of its params) and signal names.
        input_range : float, optional
            Range of the rate effect's step rule; default ``2 r_n`` (``simulate``'s default is
            ``ptp(v)``: pass the same value to compare).

        Returns
        -------
        control.NonlinearIOSystem
            ``y[k]`` from ``v[k]`` (direct feedthrough), states
            :func:`~pimodel.diagnosis.native_model.state_labels`, all zero at the start; a drift
            term reads python-control's time ``t``.

        Raises
        ------
        ValueError
            ``dt`` other than the model's, or a parameter the C core refuses.

        Examples
        --------
        >>> import control
        >>> from pimodel.blocks import initial_state
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> blk = m.block()
        >>> t = np.arange(3) * 1e-3
        >>> res = control.input_output_response(blk, t, [0.0, 1.0, 0.0],
        ...                                     initial_state=initial_state(blk))
        >>> bool(np.allclose(res.outputs, m.simulate([0.0, 1.0, 0.0]), rtol=0, atol=1e-12))
        True
        """
        return diagnosed_block(self, dt, name=name, input=input, output=output,
                               input_range=input_range)

    @property
    def dynamics_before(self) -> bool:
        """True when the model's dynamics is a filter before the hysteresis (:mod:`.wiener`).

        Examples
        --------
        >>> DiagnosedModel([0.0], [1.0], 0.0, dt=1e-3).dynamics_before
        False
        """
        return "dynamics" in self.effects and self.params.get("dynamics_position") == "before"

    @property
    def is_exactly_invertible(self) -> bool:
        """True when no effect of the model is inverted approximately (drift aside)."""
        return not {"dynamics", "delay", "rate"} & set(self.effects)

    # -- JSON ---------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON form ``{"type": "DiagnosedModel", ...}`` (:func:`load_diagnosed_model`).

        Returns
        -------
        dict
            ``type``, ``radii``, ``weights``, ``offset``, ``dt``, ``effects``,
            ``reference_weights``, ``reference_offset``, ``initial_state``,
            ``plays_start``, ``params`` (plain JSON values).

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> d = m.to_dict()
        >>> d["type"], d["weights"]
        ('DiagnosedModel', [1.0, 0.5])
        >>> DiagnosedModel.from_dict(d).to_dict() == d
        True
        """
        return {"type": KIND, "radii": self.radii.tolist(), "weights": self.weights.tolist(),
                "offset": self.offset, "dt": self.dt, "effects": list(self.effects),
                "reference_weights": self.reference_weights.tolist(),
                "reference_offset": self.reference_offset, "initial_state": self.initial_state,
                "plays_start": self.plays_start,
                "params": {k: (list(v) if isinstance(v, tuple) else v)
                           for k, v in self.params.items()}}

    @classmethod
    def from_dict(cls, d: dict) -> DiagnosedModel:
        """Rebuild from :meth:`to_dict` (ValueError naming a missing key; a model saved without
        ``plays_start``, before issue 33, starts its plays at 0 as it was fitted)."""
        if not isinstance(d, dict) or d.get("type") != KIND:
            raise ValueError(f"model: expected a JSON object with type {KIND!r}")
        try:
            return cls(d["radii"], d["weights"], d["offset"], d["dt"], tuple(d["effects"]),
                       d["reference_weights"], d["reference_offset"], dict(d["params"]),
                       d.get("initial_state", "rest"), d.get("plays_start", "zero"))
        except KeyError as err:
            raise ValueError(f"model: missing key {err.args[0]!r}") from None

    def save(self, path) -> Path:
        """Write :meth:`to_dict` as JSON to ``path``.

        Parameters
        ----------
        path : str or pathlib.Path
            The file to write (its folder must exist).

        Returns
        -------
        pathlib.Path
            ``path``.

        Examples
        --------
        >>> import tempfile
        >>> from pathlib import Path
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> with tempfile.TemporaryDirectory() as d:
        ...     load_diagnosed_model(m.save(Path(d) / "m.json")).to_dict() == m.to_dict()
        True
        """
        path = Path(path)
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
        return path

    def operator_form(self):
        """The model as an operator that ``pimodel fmu build --model`` accepts.

        Only the nominal model (no effects) has one: a
        :class:`~pimodel.operators.generalized.GeneralizedPI` with the weights (signed, positive
        partial sums) and the offset as an affine output envelope, equal to :meth:`simulate`. The
        diagnosis fits the effects in parallel to the hysteresis (module docstring), which no chain
        of the operator FMUs reproduces; the DiagnosedModel FMU unit runs any model
        (:func:`pimodel.diagnosis.native_model.fmu_parameters`).

        Returns
        -------
        pimodel.operators.generalized.GeneralizedPI

        Raises
        ------
        ValueError
            A model with effects (named), plays that start at ``v[0]``
            (:attr:`DiagnosedModel.plays_start`), or weights the PI operator refuses.

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> op = m.operator_form()
        >>> v = np.array([0.0, 1.0, 0.0])
        >>> bool(np.allclose(op.simulate(v), m.simulate(v)))
        True
        """
        from ..operators.envelopes import Envelope
        from ..operators.generalized import GeneralizedPI

        if self.plays_start == "v0":
            raise ValueError("model: its plays start at rest at each record's first input "
                             "v[0] (plays_start 'v0'), which an operator's fixed initial state "
                             "cannot express; the DiagnosedModel FMU unit runs it (plays_start "
                             "= 1)")
        if self.effects:
            raise ValueError(f"model: the effects {list(self.effects)} are fitted in parallel "
                             "to the hysteresis; no operator chain reproduces them (the "
                             "DiagnosedModel FMU unit does: save the model and run 'pimodel fmu "
                             "build --model'); only the nominal model has an operator form")
        return GeneralizedPI(self.weights, self.radii,
                             signed_weights=bool(np.any(self.weights <= 0)),
                             output_envelope=Envelope.affine(1.0, self.offset))

    def static_part(self) -> DiagnosedModel:
        """The model without its dynamics and delay (what the inverse solves exactly).

        Returns
        -------
        DiagnosedModel
            The same model with ``"dynamics"`` and ``"delay"`` removed from ``effects``.

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3, effects=("delay",),
        ...                    params={"delay_samples": 2})
        >>> m.static_part().effects
        ()
        """
        return replace(self, effects=tuple(e for e in self.effects
                                           if e not in ("dynamics", "delay")))


def load_diagnosed_model(path) -> DiagnosedModel:
    """Read a model written by :meth:`DiagnosedModel.save` (ValueError naming the file).

    Parameters
    ----------
    path : str or pathlib.Path
        A JSON file written by :meth:`DiagnosedModel.save`.

    Returns
    -------
    DiagnosedModel

    Raises
    ------
    ValueError
        The file is not valid JSON or not a DiagnosedModel (a missing key is named).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> with tempfile.TemporaryDirectory() as d:
    ...     load_diagnosed_model(m.save(Path(d) / "m.json")).weights.tolist()
    [1.0, 0.5]
    """
    p = Path(path)
    try:
        return DiagnosedModel.from_dict(json.loads(p.read_text()))
    except (ValueError, json.JSONDecodeError) as err:
        raise ValueError(f"{p}: {err}") from None


class DiagnosedInverse:
    """Causal feedforward inverse of a :class:`DiagnosedModel` (module docstring).

    Parameters
    ----------
    model : DiagnosedModel
        The model to invert.

    Examples
    --------
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3, effects=("creep",),
    ...                    params={"creep_lag_gains": [0.05], "creep_time_constants_s": [0.1]})
    >>> v = np.sin(np.linspace(0, 6, 300))
    >>> bool(np.max(np.abs(m.inverse().simulate(m.simulate(v)) - v)) < 1e-9)
    True
    """

    def __init__(self, model: DiagnosedModel):
        self.model = model

    def prefilter(self, y_d: np.ndarray) -> np.ndarray:
        """The reference after the approximate inverses of the dynamics and the delay.

        Parameters
        ----------
        y_d : numpy.ndarray
            Desired output, every ``dt``.

        Returns
        -------
        numpy.ndarray
            ``y_d`` advanced by the delay and filtered by the mode's approximate inverse (a
            filter before the hysteresis is inverted after the solve, not here);
            ``y_d`` itself for a model with neither.

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3, effects=("delay",),
        ...                    params={"delay_samples": 1})
        >>> m.inverse().prefilter(np.array([0.0, 1.0, 2.0, 3.0])).round(3).tolist()
        [1.0, 2.0, 3.0, 3.0]
        """
        m, p = self.model, self.model.params
        x = y_d
        if "dynamics" in m.effects and not m.dynamics_before:  # (before: after the solve)
            x = approximate_inverse(x, p["mode_hz"], p["mode_damping"],
                                    p.get("lti_elements", ()), p.get("lti_gains", ()), m.dt)
        if "delay" in m.effects:
            x = _advance(x, float(p["delay_samples"]))
        return x

    def initial_memory(self, y_0: float) -> np.ndarray:
        """Play states before the first sample when the stage's memory is unknown: those of one
        reversal at ``u`` (from rest, the input went to ``u`` and back to 0), with ``u`` chosen
        so that the model's output at the input 0 is ``y_0`` (a ``y_0`` out of reach gives the
        memory closest to it).

        Play ``i`` then holds ``z_i = max(min(u + r_i, 0), -r_i)`` for ``u <= 0`` (an ascending
        branch from a minimum, as after negative saturation) and ``min(max(u - r_i, 0), r_i)``
        for ``u >= 0``; ``u = 0`` is the memory at rest. Only the static part counts (creep,
        rate and dynamics act from the next sample; the output is that of :meth:`simulate`'s
        model at its first sample with the input 0).

        ``u`` lies on the side where the output moves towards ``y_0`` (below the output at
        rest: ``u < 0`` for a model whose output rises with the input, the sign of
        ``sum w_i``), and of the ``u`` there that reach ``y_0`` the one nearest 0 is taken: it
        moves the fewest plays. Plays the record never moves keep their memory for good, and
        at rest their constant share is already in the fitted offset; the weights of the
        plays with large radii are also the least determined (the output along the family
        can wiggle about ``y_0``). Measured on ``pimodel.stages.preisach_stage`` (records from
        negative saturation), the deepest ``u`` that reaches ``y_0`` left, e.g., a rate model's
        open-loop error 2.5 times that of the nearest (``docs/notes/ff-creep.md``).

        Parameters
        ----------
        y_0 : float
            The first sample of the (prefiltered) reference [output units].

        Returns
        -------
        numpy.ndarray
            ``z_i`` [input units], one per play, ``|z_i| <= r_i``.

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3)
        >>> m.inverse().initial_memory(-0.1).round(12).tolist()  # ascending branch, u = -0.7
        [0.0, -0.2]
        >>> m.inverse().initial_memory(0.0).tolist()  # the output at rest: at rest
        [0.0, 0.0]
        """
        m = monotone_model(self.model.static_part())  # the model the solver inverts
        r = m.radii

        def memory(u: float) -> np.ndarray:
            return np.clip(np.clip(0.0, u - r, u + r), -r, r)

        def output(u: float) -> float:
            return _first_output(m, memory(u)) - float(y_0)

        f0 = output(0.0)
        if f0 == 0.0:
            return memory(0.0)
        rising = 1.0 if float(np.sum(m.weights)) >= 0 else -1.0
        side = -1.0 if rising * f0 > 0 else 1.0  # the output at rest is above y_0: u < 0
        # the output is piecewise linear (cubic with the asymmetry) in u between these
        u = side * np.unique(np.concatenate(([0.0], r, 2 * r)))
        f = np.array([f0] + [output(x) for x in u[1:]])
        cross = np.flatnonzero(f[:-1] * f[1:] <= 0)
        if cross.size == 0:  # out of reach: the memory closest to it
            return memory(float(u[np.argmin(np.abs(f))]))
        i = int(cross[0])  # the crossing nearest 0
        if f[i + 1] == 0.0:
            return memory(float(u[i + 1]))
        return memory(brentq(output, min(u[i], u[i + 1]), max(u[i], u[i + 1]),
                             xtol=1e-15 * (1.0 + float(r[-1]))))

    def first_input(self, y_0: float) -> float:
        """The first input ``v[0]`` of a model whose plays start at rest at ``v[0]``
        (:attr:`DiagnosedModel.plays_start` ``"v0"``): every play then outputs ``v[0]`` on the
        first sample, so the static part's output there, ``(sum w) v[0] + c`` plus the
        asymmetry of ``h0`` (and a creep whose lags start at a common rest), is solved for
        ``y_0`` (rate, and a creep at rest at ``h0[0]``, act from the next sample).

        Parameters
        ----------
        y_0 : float
            Output to reach on the first sample (the reference after :meth:`prefilter`).

        Returns
        -------
        float
            ``v[0]`` [input units]; the input nearest the linear guess ``(y_0 - c) / sum w``
            that reaches ``y_0`` (the guess itself when none does within 1e6 of it).

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3, plays_start="v0")
        >>> round(m.inverse().first_input(1.6), 12)
        1.0
        """
        m = monotone_model(self.model.static_part())
        ones = np.ones(m.radii.size)

        def f(u: float) -> float:
            return _first_output(m, u * ones) - float(y_0)

        total = float(np.sum(m.weights))
        u0 = (float(y_0) - m.offset) / total if total != 0 else 0.0
        if f(u0) == 0.0 or ("asymmetry" not in m.effects and (
                "creep" not in m.effects or (creep_start_levels(m.params) is None
                                             and m.params.get("creep_start") != "record"))):
            return u0
        step = 1e-3 * (1.0 + abs(u0) + float(m.radii[-1]))
        while step < 1e6:
            for lo, hi in ((u0 - step, u0), (u0, u0 + step)):
                if f(lo) * f(hi) <= 0:
                    return brentq(f, lo, hi, xtol=1e-15 * (1.0 + abs(u0)))
            step *= 2.0
        return u0

    def simulate(self, y_d, t=None, *, input_range: float | None = None,
                 initial_state: str | None = None) -> np.ndarray:
        """Input ``v[k]`` that makes the model's output follow ``y_d[k]``.

        Parameters
        ----------
        y_d : array_like
            Desired output, every ``dt``.
        t : array_like, optional
            Times [s] (unused: drift is not inverted; checked for length).
        input_range : float, optional
            Range for the rate effect's step rule; default the diagnosis' train input span
            (``2 r_n``).
        initial_state : {"rest", "unknown"}, optional
            The stage's memory before the first sample; default the model's
            :attr:`~DiagnosedModel.initial_state` (the diagnosis' assumption). ``"rest"``: the
            plays at rest as the model's (:attr:`~DiagnosedModel.plays_start`: at 0, or at the
            ``v[0]`` of :meth:`first_input`), the exact inverse of
            :meth:`DiagnosedModel.simulate`.
            ``"unknown"``: the plays start from :meth:`initial_memory` of the first
            (prefiltered) reference sample, so the stage is taken to sit at ``y_d[0]`` with
            the input 0 instead of being driven there from rest. On a stage whose memory
            differs from rest (e.g. after saturation), the rest assumption makes the inverse's
            first inputs wrong, and a creep (log law) carries that start-up error through the
            whole record; measured in ``docs/notes/ff-creep.md``.

        Returns
        -------
        numpy.ndarray
            ``v[k]`` depends on ``y_d[0..k]`` (plus ``y_d`` up to the delay ahead, or the
            filter's one-sample advance, when the model has a delay or dynamics).

        Raises
        ------
        ValueError
            ``y_d`` not a finite 1-D signal, an unknown ``initial_state``, or an input float64
            cannot hold (the sample is named).

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> v = m.inverse().simulate([0.1, 0.6, 1.1])
        >>> bool(np.allclose(m.simulate(v), [0.1, 0.6, 1.1]))
        True
        >>> # y_d[0] = 0 is below the output at rest (0.1): taken as an ascending branch
        >>> m.inverse().simulate([0.0, 0.6], initial_state="unknown").round(6).tolist()
        [0.0, 0.5]
        """
        yd = checked_signal(y_d, "y_d")
        self.model._clock(yd, t)
        state = self.model.initial_state if initial_state is None else initial_state
        if state not in INITIAL_STATES:
            raise ValueError(f"initial_state: expected one of {INITIAL_STATES}, got {state!r}")
        rng = 2 * self.model.radii[-1] if input_range is None else float(input_range)
        x = self.prefilter(yd)
        _check_headroom(x, self.model)
        z0 = self.initial_memory(x[0]) if state == "unknown" else None
        if state == "rest" and self.model.plays_start == "v0":
            z0 = np.full(self.model.radii.size, self.first_input(x[0]))
        x = _solve_static(self.model.static_part(), x, rng, z0)
        if self.model.dynamics_before:  # the filter's output -> its input (approximate)
            x = inverse_prefilter(x, self.model.params["wiener_elements"], self.model.dt)
        return check_finite(x, yd, "y_d")

    def block(self, dt: float | None = None, *, name: str = "inverse", input: str = "y_d",
              output: str = "v", input_range: float | None = None,
              reference_range: float | None = None) -> control.NonlinearIOSystem:
        """The feedforward as a causal discrete python-control block, ``y_d -> v``.

        :meth:`simulate` reads the reference ahead (one sample for the dynamics' approximate
        inverse, after the hysteresis or before it, ``d`` for a delay); the block cannot, so it
        delays ``v`` instead by ``A = block.latency`` samples
        (:func:`~pimodel.diagnosis.reference_inverse.inverse_latency`, 0 without dynamics and
        delay): fed ``y_d[0..k]`` it outputs ``v[k] = simulate(y_d)[k -
        A]`` for ``k >= A`` and the inverse of ``y_d[0]`` at rest before. A model driven by it
        follows ``y_d[k - A]`` (for a reference at rest over its first ``A + 1`` samples,
        exactly as the batch: ``y[k] = model.simulate(simulate(y_d))[k - A]``, drift aside).
        To follow ``y_d[k]`` itself, feed the block ``y_d[k + A]`` (a known trajectory).

        Parameters
        ----------
        dt : float, optional
            Sample time [s]: the model's ``dt`` (default; another value raises).
        name, input, output : str
            Block name (prefix of its params) and signal names.
        input_range : float, optional
            Range of the rate effect's step rule; default ``2 r_n`` (as :meth:`simulate`).
        reference_range : float, optional
            The scale of the root rule, which :meth:`simulate` takes from the whole reference
            (``ptp(self.prefilter(y_d))``); default 0 (scale ``max(2 r_n, 1)``). It matters
            only where the static part has several roots.

        Returns
        -------
        control.NonlinearIOSystem
            Input ``y_d``, output ``v``; initial state all zeros
            (``pimodel.blocks.initial_state``); attribute ``latency`` (samples).

        Raises
        ------
        ValueError
            ``dt`` other than the model's, or a bad model parameter.

        Examples
        --------
        >>> import control
        >>> from pimodel.blocks import initial_state
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3, effects=("delay",),
        ...                    params={"delay_samples": 1})
        >>> blk = m.inverse().block()
        >>> y_d = np.array([0.1, 0.1, 1.35, 0.35, 0.35])
        >>> res = control.input_output_response(blk, np.arange(5) * 1e-3, y_d,
        ...                                     initial_state=initial_state(blk))
        >>> blk.latency, res.outputs.round(9).tolist()
        (1, [0.0, 0.0, 1.0, 0.0, 0.0])
        >>> m.inverse().simulate(y_d).round(9).tolist()
        [0.0, 1.0, 0.0, 0.0, 0.0]
        """
        return inverse_block(self, dt, name=name, input=input, output=output,
                             input_range=input_range, reference_range=reference_range)


def _first_output(m: DiagnosedModel, z: np.ndarray) -> float:
    """The static part's output on a first sample whose play outputs are ``z`` (hysteresis,
    offset and the asymmetry of ``h0``; rate is 0 there, and creep too unless its lags start
    at a common rest ``s_j``: then ``sum_j g_j a_j (s_j - h0)``; or is counted from the
    record's start, ``creep_start`` ``"record"``: then ``-sum_j g_j h0``)."""
    p = m.params
    y = float(z @ m.weights) + m.offset
    h0 = float(z @ m.reference_weights) + m.reference_offset
    if "asymmetry" in m.effects:
        x = (h0 - p["center"]) / p["half_range"]
        y += p["asymmetry_quadratic"] * x**2 + p["asymmetry_cubic"] * x**3
    starts = creep_start_levels(p) if "creep" in m.effects else None
    if starts is not None:
        ga = np.asarray(p["creep_lag_gains"], float) * np.exp(
            -m.dt / np.asarray(p["creep_time_constants_s"], float))
        y += float(ga @ (starts - h0))
    if "creep" in m.effects and p.get("creep_start") == "record":  # less sum_j g_j h0[0]
        y -= float(np.sum(p["creep_lag_gains"])) * h0
    return y


def _check_limits(n_plays: int, params: dict) -> None:
    """ValueError above the C core's limits, the FMUs' too (``LIMITS``): at most
    ``PIM_DIAG_MAX_PLAYS`` plays and ``PIM_DIAG_MAX_LAGS`` creep lags, so a model that loads
    also exports and each sample costs a bounded time (issue 32, docs/reliability.md)."""
    most = LIMITS["PIM_DIAG_MAX_PLAYS"]
    if n_plays > most:
        raise ValueError(f"radii: {n_plays} plays; a diagnosed model (and its FMU) takes at "
                         f"most {most}")
    lags = params.get("creep_lag_gains", ()) if isinstance(params, dict) else ()
    most = LIMITS["PIM_DIAG_MAX_LAGS"]
    if hasattr(lags, "__len__") and len(lags) > most:
        raise ValueError(f"params: creep_lag_gains: {len(lags)} creep lags; a diagnosed model "
                         f"(and its FMU) takes at most {most}")


def _check_headroom(x: np.ndarray, model: DiagnosedModel) -> None:
    """ValueError naming the ``y_d`` sample when the static inverse's root bracket, the
    breakpoints plus 10 input spans (``pim_diag_inverse.c``), would overflow float64: the
    input scale ``(max |x| + ptp x) / |sum w| + 2 r_n`` must stay below ``float max / 32``.
    Beyond it the C solve returned a finite, wrong input (issue 32)."""
    wsum = max(abs(float(model.weights.sum())), 1e-12)
    with np.errstate(over="ignore"):
        scale = (np.max(np.abs(x)) + np.ptp(x)) / wsum + 2 * float(model.radii[-1])
    bound = np.finfo(float).max / 32
    if not scale < bound:
        k = int(np.argmax(np.abs(x)))
        raise ValueError(
            f"y_d: sample {k} ({float(x[k]):.6g}) is out of the inverse's range: the input it "
            f"asks for, about {scale:.3g}, leaves no float64 headroom for the root bracket "
            f"(expected below {bound:.3g}); scale the reference down")


def _solve_static(static: DiagnosedModel, x: np.ndarray, input_range: float, z0) -> np.ndarray:
    """:func:`.reference_inverse.solve_static` on the C core (equal to 1e-9,
    ``tests/test_inverse_native.py``); the NumPy reference for a model the C core does not
    take (more than 128 plays or 64 creep lags)."""
    try:
        native = NativeInverse(DiagnosedInverse(static), input_range, float(np.ptp(x)))
    except ValueError:  # the reference raises its own errors, or runs what C does not take
        return solve_static(static, x, input_range, z0)
    return native.run(x, z0)


def _advance(x, d):
    """``x[k + d]`` (linear interpolation, the last sample held)."""
    k = np.arange(x.size) + d
    return np.interp(k, np.arange(x.size), x)
