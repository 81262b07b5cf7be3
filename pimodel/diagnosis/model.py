"""The model a diagnosis chose, as one object: forward simulation and a causal feedforward
inverse (:meth:`pimodel.diagnosis.DiagnosisReport.model`).

The diagnosis fits every candidate *jointly* with the hysteresis weights, in a parallel form
(:mod:`.effects`): with ``Z`` the play outputs of the radius grid (plays at rest at 0, then
``z_i[k] = Gamma_{r_i}[v][k]``) and ``h0 = Z w0 + c0`` the reference hysteresis output the
effect columns are built from,

    y[k] = (D Z)[k] w + c                                    hysteresis (weights w, offset c)
         + sum_i g_i (L_i[h0][k] - h0[k])                     creep: lags L_i, tau_i (s)
         + q u[k]^2 + c3 u[k]^3,  u = (h0 - center) / half    asymmetry (static output terms)
         + sum_b g_b R_b[k]                                   rate (radii or weights, .rate)
         + s t_clock[k] (+ c_j)                               drift (record or shared clock;
                                                              or a level c_j per record)
         + sum_j g_j (D' (E_j - M_1)[h0])[k]                  dynamics: further elements

where ``D`` is the identity, the unit-gain base mode ``M_1`` (ZOH, ``(D Z)[k]`` depends on
``Z[0..k-1]``) and/or a delay of ``d`` samples (fractional: linear interpolation); ``D'`` the
delay alone. ``E_j`` are the further modes, low-pass and direct term of the linear part
(:mod:`.lti`). ``L_i`` is the exact
first-order lag at rest around ``h0[0]``: ``L[k] = a L[k-1] + (1 - a) h0[k]``,
``a = exp(-dt / tau)``. This class evaluates exactly that form, so :meth:`simulate` equals the
diagnosis' own prediction. The same form, streamed sample by sample on the C core
(:mod:`.stream`), is the python-control block (:meth:`DiagnosedModel.block`) and the
DiagnosedModel FMU unit (``pimodel fmu build --model MODEL.json``); a test holds them equal to
:meth:`simulate` to 1e-12.

The inverse solves, sample by sample, ``F_k(v[k]) = y_d[k]``: with the play states, the lags
and the rate memory of sample k - 1 fixed, ``F_k`` is a polynomial of degree at most 3 in
``v[k]`` between the play breakpoints ``z_i[k-1] -+ r_i`` (and ``v[k-1]``), so the root is
exact to rounding. Exact (round trip to 1e-9) for the nominal model and
for creep and asymmetry, alone or together, while ``F_k`` is monotone near the input.
Approximations, by choice:

* **rate**: the filtered rate of sample k is taken from sample k - 1 (radius family: the terms
  as held at each play's last contact up to k - 1; weight family: ``rho_f[k-1]`` times the play
  outputs of sample k). Solved exactly, a term in ``|v[k] - v[k-1]| / (dt rate_scale)`` makes
  ``F_k`` steep and non-monotone, and the feedforward follows wrong roots (measured with the
  radius family: open-loop errors 6 to 9 times the nominal's).
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

from ..operator import PIOperator
from .drift import drift_term
from .effects import lag, mode, shift
from .lti import approximate_inverse, lti_columns
from .rate import RATE_FAMILIES, STEP_SHARE, play_bands, rate_columns
from .wiener import inverse_prefilter, prefilter

if TYPE_CHECKING:
    import control

__all__ = ["DiagnosedModel", "DiagnosedInverse", "load_diagnosed_model"]

KIND = "DiagnosedModel"


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
        Effect parameters: ``creep_lag_gains``, ``creep_time_constants_s``;
        ``asymmetry_quadratic``, ``asymmetry_cubic``, ``center``, ``half_range``;
        ``rate_gains``, ``rate_family``, ``rate_time_constant_s``, ``rate_scale``
        (:mod:`.rate`); ``drift_per_s``, ``drift_clock`` (and ``drift_variant``,
        ``drift_t0_train`` for a level per record, :mod:`.drift`);
        ``mode_hz``, ``mode_damping``, ``lti_elements``, ``lti_gains`` (:mod:`.lti`), or
        ``dynamics_position = "before"`` and ``wiener_elements`` (:mod:`.wiener`);
        ``delay_samples``.

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

    def __post_init__(self):
        r = np.asarray(self.radii, float)
        w = np.asarray(self.weights, float)
        if r.ndim != 1 or r.size == 0 or w.shape != r.shape:
            raise ValueError(f"weights: expected {r.size} values like radii, got {w.shape}")
        if np.any(r < 0) or np.any(np.diff(r) < 0):
            raise ValueError("radii: expected non-negative, ascending values")
        if not self.dt > 0:
            raise ValueError(f"dt: expected > 0, got {self.dt!r}")
        bad = set(self.effects) - {"creep", "asymmetry", "rate", "drift", "dynamics", "delay"}
        if bad:
            raise ValueError(f"effects: unknown {sorted(bad)}")
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
                       params={"rate_scale": nom.params["rate_scale"]})
        model, ref = fitted["model"], fitted["reference"]
        q = n if V is None else V.shape[1]
        params = dict(model.params)
        params.update({k: ref.params[k] for k in ("center", "half_range", "rate_scale")})
        if "fn" in model.grid:
            params["mode_hz"], params["mode_damping"] = model.grid["fn"], model.grid["zeta"]
        return cls(radii, play_weights(model.coef, q), float(model.coef[q]), fitted["dt"],
                   tuple(fitted["chosen"]), play_weights(ref.coef, q), float(ref.coef[q]),
                   params)

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
        """Output ``y[k]`` for the input ``v[k]`` (plays at rest at 0 before ``v[0]``).

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
            The record's measured output: a drift with a level per record
            (``drift_variant == "levels"``) takes the record's level from it out of fold, as
            the diagnosis does on a validate record (:func:`.drift.drift_term`); without it,
            the level the drift's clock predicts. Ignored by other models.

        Returns
        -------
        numpy.ndarray

        Raises
        ------
        ValueError
            ``v`` not a finite 1-D signal, ``t`` of another length.

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> m.simulate([0.0, 1.0, 0.0]).round(3).tolist()
        [0.1, 1.35, 0.35]
        """
        v = _signal(v, "v")
        tk = self._clock(v, t)
        p, e = self.params, self.effects
        Z = PIOperator(np.ones(self.radii.size), self.radii).play_outputs(v)
        Zp = Z
        if self.dynamics_before:  # the plays of the filtered input (module wiener)
            Zp = PIOperator(np.ones(self.radii.size), self.radii).play_outputs(
                prefilter(v, p["wiener_elements"], self.dt))
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
        if "creep" in e:
            for g, tau in zip(p["creep_lag_gains"], p["creep_time_constants_s"], strict=True):
                y = y + g * (lag(h0, tau, self.dt) - h0)
        if "asymmetry" in e:
            u = (h0 - p["center"]) / p["half_range"]
            y = y + p["asymmetry_quadratic"] * u**2 + p["asymmetry_cubic"] * u**3
        if "rate" in e:
            gains, family, tau = _rate_params(p)
            R = rate_columns(Z, self.radii, v, self.dt, p["rate_scale"], self.reference_weights,
                             tau, family, gains.size, input_range=input_range)
            y = y + R @ gains
        if "drift" in e:
            y_meas = None if measured is None else _signal(measured, "measured")
            if y_meas is not None and y_meas.shape != v.shape:
                raise ValueError(f"measured: expected {v.size} samples like v, got "
                                 f"{y_meas.shape}")
            y = y + drift_term(p, tk, y, y_meas)
        return y

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
        """The model as a discrete python-control block (C core step, :mod:`.stream`).

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
            :func:`~pimodel.diagnosis.stream.state_labels`, all zero at the start; a drift term
            reads python-control's time ``t``.

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
        from .stream import diagnosed_block

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
            ``reference_weights``, ``reference_offset``, ``params`` (plain JSON values).

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
                "reference_offset": self.reference_offset,
                "params": {k: (list(v) if isinstance(v, tuple) else v)
                           for k, v in self.params.items()}}

    @classmethod
    def from_dict(cls, d: dict) -> DiagnosedModel:
        """Rebuild from :meth:`to_dict` (ValueError naming a missing key)."""
        if not isinstance(d, dict) or d.get("type") != KIND:
            raise ValueError(f"model: expected a JSON object with type {KIND!r}")
        try:
            return cls(d["radii"], d["weights"], d["offset"], d["dt"], tuple(d["effects"]),
                       d["reference_weights"], d["reference_offset"], dict(d["params"]))
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
        :class:`~pimodel.generalized.GeneralizedPI` with the weights (signed, positive partial
        sums) and the offset as an affine output envelope, equal to :meth:`simulate`. The
        diagnosis fits the effects in parallel to the hysteresis (module docstring), which no
        chain of the operator FMUs reproduces; the DiagnosedModel FMU unit runs any model
        (:func:`pimodel.diagnosis.stream.fmu_parameters`).

        Returns
        -------
        pimodel.generalized.GeneralizedPI

        Raises
        ------
        ValueError
            A model with effects (named), or weights the PI operator refuses.

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> op = m.operator_form()
        >>> v = np.array([0.0, 1.0, 0.0])
        >>> bool(np.allclose(op.simulate(v), m.simulate(v)))
        True
        """
        from ..envelopes import Envelope
        from ..generalized import GeneralizedPI

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


def _signal(x, name: str) -> np.ndarray:
    a = np.asarray(x, float)
    if a.ndim != 1 or a.size < 2 or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected a finite 1-D signal of at least 2 samples")
    return a


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

    def simulate(self, y_d, t=None, *, input_range: float | None = None) -> np.ndarray:
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

        Returns
        -------
        numpy.ndarray
            ``v[k]`` depends on ``y_d[0..k]`` (plus ``y_d`` up to the delay ahead, or the
            filter's one-sample advance, when the model has a delay or dynamics).

        Raises
        ------
        ValueError
            ``y_d`` not a finite 1-D signal.

        Examples
        --------
        >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
        >>> v = m.inverse().simulate([0.1, 0.6, 1.1])
        >>> bool(np.allclose(m.simulate(v), [0.1, 0.6, 1.1]))
        True
        """
        yd = _signal(y_d, "y_d")
        self.model._clock(yd, t)
        rng = 2 * self.model.radii[-1] if input_range is None else float(input_range)
        x = _solve(self.model.static_part(), self.prefilter(yd), rng)
        if self.model.dynamics_before:  # the filter's output -> its input (approximate)
            return inverse_prefilter(x, self.model.params["wiener_elements"], self.model.dt)
        return x


def _advance(x, d):
    """``x[k + d]`` (linear interpolation, the last sample held)."""
    k = np.arange(x.size) + d
    return np.interp(k, np.arange(x.size), x)


def _solve(m: DiagnosedModel, yd: np.ndarray, input_range: float) -> np.ndarray:
    """Per-sample root of ``F_k(v) = yd[k]`` (module docstring)."""
    p, e, r = m.params, m.effects, m.radii
    n = r.size
    w, w0 = m.weights, m.reference_weights
    creep = "creep" in e
    if creep:
        ga = np.asarray(p["creep_lag_gains"]) * np.exp(-m.dt / np.asarray(
            p["creep_time_constants_s"]))
        a_lag = np.exp(-m.dt / np.asarray(p["creep_time_constants_s"]))
        lags = np.zeros(ga.size)
    asym = "asymmetry" in e
    rate = "rate" in e
    if rate:
        gains, family, tau = _rate_params(p)
        rg, rw = np.zeros(n), np.zeros(n)  # per play: g_b r_i (radius) or g_b w0_i (weight)
        for g, idx in zip(gains, play_bands(n, gains.size), strict=True):
            if family == "radius":
                rg[idx] = g * r[idx]
            else:
                rw[idx] = g * w0[idx]
        memory = np.zeros(n)  # -s_i rho_f at the last contact of play i
        step = STEP_SHARE * input_range
        a_rate = np.exp(-m.dt / tau) if tau > 0 else 0.0
        rho_f = 0.0  # filtered rate of sample k - 1
    z = np.zeros(n)
    v_prev = 0.0
    out = np.empty(yd.size)
    span = max(2 * float(r[-1]), float(np.ptp(yd)) / max(abs(w.sum()), 1e-12), 1.0)

    guess = 0.0
    for k in range(yd.size):
        first = k == 0

        def F(vs, z=z, v_prev=v_prev, first=first, lags=lags if creep else None,
              memory=memory if rate else None, rho_f=rho_f if rate else None):
            Zc = np.clip(z[None, :], vs[:, None] - r, vs[:, None] + r)
            y = Zc @ w + m.offset
            h0 = Zc @ w0 + m.reference_offset
            if creep and not first:
                y = y + (ga * lags).sum() - ga.sum() * h0
            if asym:
                u = (h0 - p["center"]) / p["half_range"]
                y = y + p["asymmetry_quadratic"] * u**2 + p["asymmetry_cubic"] * u**3
            if rate and not first:  # the rate held from sample k - 1 (module docstring)
                y = y + memory @ rg + rho_f * (Zc @ rw)
            return y

        b = np.concatenate((z - r, z + r, [v_prev]))
        b = np.unique(np.concatenate((b, [b.min() - 10 * span, b.max() + 10 * span])))
        roots = _roots(F, b, yd[k], cubic=asym)
        gb = np.abs(F(b) - yd[k])
        roots = np.concatenate((roots, b[gb <= 1e-10 * (1.0 + abs(yd[k]))]))
        if roots.size:
            vk = float(roots[np.argmin(np.abs(roots - guess))])
        else:  # out of reach: the breakpoint closest to the target
            vk = float(b[np.argmin(gb)])
        out[k] = vk
        z_new = np.clip(z, vk - r, vk + r)
        h = float(z_new @ w0 + m.reference_offset)
        if creep:
            lags = h + 0 * lags if first else a_lag * lags + (1 - a_lag) * h
        if rate and not first:
            dv = abs(vk - v_prev)
            rho = dv / m.dt / p["rate_scale"] if dv <= step or tau > 0 else 0.0
            rho_f = a_rate * rho_f + (1 - a_rate) * rho
            gap = vk - z_new
            contact = (r > 0) & (np.abs(gap) >= r * (1 - 1e-9))
            memory = np.where(contact, -np.sign(gap) * rho_f, memory)
        # the next sample takes the root nearest the extrapolated input (a smooth input's
        # branch), or nearest this one after a jump (a step)
        guess = vk if first or abs(vk - v_prev) > 0.01 * span else 2 * vk - v_prev
        z, v_prev = z_new, vk
    return out


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


def _rate_params(p: dict) -> tuple[np.ndarray, str, float]:
    """Gains, family and filter time constant [s] of a rate effect."""
    if "rate_band_gains" in p:
        raise ValueError("params: 'rate_band_gains' is the rate effect of an earlier version "
                         "(radii growing with the unfiltered rate, pushed plays); diagnose the "
                         "records again for 'rate_gains', 'rate_family' and "
                         "'rate_time_constant_s'")
    missing = [k for k in ("rate_gains", "rate_family", "rate_time_constant_s") if k not in p]
    if missing:
        raise ValueError(f"params: the rate effect needs {missing}")
    if p["rate_family"] not in RATE_FAMILIES:
        raise ValueError(f"params: rate_family expected one of {RATE_FAMILIES}, got "
                         f"{p['rate_family']!r}")
    return (np.asarray(p["rate_gains"], float), str(p["rate_family"]),
            float(p["rate_time_constant_s"]))
