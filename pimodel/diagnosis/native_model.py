"""A :class:`~pimodel.diagnosis.model.DiagnosedModel` streamed sample by sample on the C core
(``fmu/src/pim_diagnosed.c``): the python-control block (:meth:`DiagnosedModel.block`), a
runner (:func:`stream_simulate`) and the values of the DiagnosedModel FMU unit
(:func:`fmu_parameters`), so that the block, the runner and the FMU are one implementation.
:meth:`DiagnosedModel.simulate` stays the NumPy form of the diagnosis (its own prediction);
``tests/test_diagnosed_block_fmu.py`` holds the two equal to 1e-12 for every effect.

Discrete-time semantics (those of ``simulate``, written per sample): with the play states
``z_i[k-1]`` (at rest before the first sample: at 0, or at ``v[0]`` when the model's
``plays_start`` is ``"v0"``, set by the C step on the first sample) and the input ``v[k]``,
``y[k]`` depends on ``v[0..k]`` and ``t[k]`` only; the LTI part (the dynamics) and the delay act
on the hysteresis term ``sum_i w_i z_i[k]`` and start at rest around its first value; the creep
lags start at rest around ``h0[0]`` (or at the model's ``creep_start_levels`` when its
``creep_start`` is ``"common"``; with ``"record"`` the term less ``sum_j g_j h0[0]``, the start
kept in the state ``L0``: :mod:`.creep`); the rate effect (:mod:`.rate`) low-passes the
normalised input rate from rest at 0 (without a filter, a one-sample jump above ``STEP_SHARE *
input_range`` counts as a step, no rate); the radius family holds each play's term from its last
contact, the weight family scales the band's ``sum_i w0_i z_i[k]`` by the current rate.

Two things ``simulate`` takes from the whole record are parameters here:

* ``input_range`` (the rate effect's step rule, used without a filter only): ``simulate``
  defaults to ``ptp(v)``, the block and the FMU to ``2 r_n`` (the diagnosis' grid span, as
  :meth:`DiagnosedInverse.simulate`); pass the same value to compare.
* the drift clock: ``"record"`` counts from the first sample (``t[k] - t[0]``), ``"absolute"``
  (and a settling, ``drift_variant == "settle"``) uses ``t[k]`` as given; in a python-control
  block ``t[k]`` is python-control's time, in the FMU ``k Ts`` (its sample instants): to run a
  record that starts at ``t[0]`` on the shared clock, subtract ``t[0]`` from the FMU's
  ``drift_settling_start``.

The dynamics is an LTI part ``b(z^-1) / a(z^-1)`` (``a[0] = 1``): the model's
``params["lti_b"]``, ``params["lti_a"]`` when given, else the unit-gain mode
(:func:`~pimodel.diagnosis.filters.mode_coefficients` of ``mode_hz``, ``mode_damping``). Its
further elements (``params["lti_elements"]``, ``params["lti_gains"]``, :mod:`.lti`: a higher
order chosen by the diagnosis, zeros from the parallel gains) run as second-order sections on
``h0``: ``sum_j g_j (E_j - M_1)[h0]``, each started at rest around ``h0[0]``, added to the
hysteresis term before the delay, as :func:`~pimodel.diagnosis.lti.lti_columns` (at most
``MAX_ELEMENTS`` elements, :func:`element_sections`).

A Wiener model (``params["dynamics_position"] == "before"``, :mod:`.wiener`) has its filter
``F`` before the hysteresis instead: the elements of ``params["wiener_elements"]`` run as
sections in series on ``v`` (:func:`prefilter_sections`), each started at rest around its own
first input (``x_f[0] = v[0]``), and a second set of plays, at rest at 0 like the first
(or at ``x_f[0]``), follows ``x_f[k]``; the hysteresis term is ``sum_i w_i zf_i[k]`` of
these plays (then the delay, as above), while ``h0`` and the creep, asymmetry and rate terms
keep the plays of ``v`` itself, as :meth:`DiagnosedModel.simulate`. No LTI part after the
plays applies in this form.
"""

from __future__ import annotations

import math
from dataclasses import replace

import control
import numpy as np

from .. import _native
from ..blocks.framework import BlockSettings, labelled_values, signal_labels, stepped_block
from .checks import block_dt, checked_signal
from .creep import creep_start_levels
from .filters import mode_coefficients
from .limits import MAX_DELAY, MAX_ELEMENTS, MAX_ORDER, NMAX, SECTION
from .lti import ELEMENT_K, element_coefficients
from .rate import FAMILY_CODES, play_bands, rate_growth, rate_params, rate_saturation
from .wiener import ELEMENT_K as WIENER_K

__all__ = ["NativeModel", "diagnosed_block", "element_sections", "fmu_parameters",
           "prefilter_sections", "state_labels", "stream_simulate"]

CLOCKS = {"record": 1, "absolute": 2}


def lti_coefficients(model) -> tuple[np.ndarray, np.ndarray] | None:
    """The LTI part ``(b, a)`` of a model with ``"dynamics"`` (powers of ``z^-1``, ``a[0] = 1``),
    or None.

    Parameters
    ----------
    model : DiagnosedModel
        The model.

    Returns
    -------
    tuple of numpy.ndarray or None
        ``params["lti_b"], params["lti_a"]`` (normalised by ``a[0]``) when given, else the
        ZOH mode of ``mode_hz``, ``mode_damping`` at the model's ``dt``.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0], [1.0], 0.0, dt=1e-3, effects=("dynamics",),
    ...                    params={"mode_hz": 50.0, "mode_damping": 0.7})
    >>> b, a = lti_coefficients(m)
    >>> round(float(b.sum() / a.sum()), 12), float(a[0])
    (1.0, 1.0)
    """
    if "dynamics" not in model.effects:
        return None
    p = model.params
    if "lti_b" in p and "lti_a" in p:
        b, a = np.asarray(p["lti_b"], float), np.asarray(p["lti_a"], float)
        if a.ndim != 1 or b.ndim != 1 or a.size == 0 or a[0] == 0:
            raise ValueError("params: lti_b, lti_a: expected 1-D coefficients with a[0] != 0")
        return b / a[0], a / a[0]
    return mode_coefficients(p["mode_hz"], p["mode_damping"], model.dt)


_FORMS = {"mode": "('mode', fn > 0 [Hz], zeta > 0)", "lowpass": "('lowpass', tau > 0 [s])",
          "lowpass_direct": "('lowpass_direct', tau > 0 [s])", "direct": "('direct',)"}


def _section(element, dt: float, name: str, kinds=ELEMENT_K) -> tuple[np.ndarray, np.ndarray]:
    """ZOH ``(b, a)`` of one element (a kind of ``kinds``) padded to ``SECTION`` coefficients
    (ValueError naming ``name`` for a malformed element)."""
    forms = [_FORMS[k] for k in kinds]
    expected = "expected " + ", ".join(forms[:-1]) + " or " + forms[-1]
    try:
        kind = str(element[0])
        values = [float(x) for x in element[1:]]
    except (TypeError, ValueError, IndexError):
        raise ValueError(f"params: {name} = {element!r}: {expected}") from None
    # the values an element holds: the parameters it adds in the linear part, its gain aside
    if (kind not in kinds or len(values) != ELEMENT_K[kind] - 1
            or not all(math.isfinite(x) and x > 0 for x in values)):
        raise ValueError(f"params: {name} = {element!r}: {expected}")
    b, a = element_coefficients((kind, *values), dt)
    return np.pad(b, (0, SECTION - b.size)), np.pad(a, (0, SECTION - a.size))


def element_sections(model) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The linear part's further elements in the C core's form, or None (none, or no
    ``"dynamics"``).

    Parameters
    ----------
    model : DiagnosedModel
        The model (``params["lti_elements"]``, ``params["lti_gains"]``, ``mode_hz``,
        ``mode_damping``).

    Returns
    -------
    tuple of numpy.ndarray or None
        ``b``, ``a`` of shape ``(ne + 1, 3)`` (powers of ``z^-1``, ``a[:, 0] = 1``): row 0 the
        base mode ``M_1``, row ``j`` the element ``E_j``, ZOH at the model's ``dt``
        (:func:`~pimodel.diagnosis.lti.element_coefficients`); and the gains ``g_j`` (``ne``).

    Raises
    ------
    ValueError
        More than ``MAX_ELEMENTS`` (8) elements, a malformed element (named
        ``lti_elements[j]``), or not one gain per element.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0], [1.0], 0.0, dt=1e-4, effects=("dynamics",),
    ...                    params={"mode_hz": 500.0, "mode_damping": 0.1,
    ...                            "lti_elements": [["mode", 1500.0, 0.05], ["direct"]],
    ...                            "lti_gains": [0.2, 0.01]})
    >>> b, a, g = element_sections(m)
    >>> b.shape, b[2].tolist(), g.tolist()
    ((3, 3), [1.0, 0.0, 0.0], [0.2, 0.01])
    """
    p = model.params
    if "dynamics" not in model.effects or not p.get("lti_elements"):
        return None
    elements = list(p["lti_elements"])
    if len(elements) > MAX_ELEMENTS:
        raise ValueError(f"params: lti_elements: {len(elements)} elements; the C stream and the "
                         f"FMU take at most {MAX_ELEMENTS}")
    try:
        gains = np.asarray(p.get("lti_gains", ()), float)
    except (TypeError, ValueError):
        gains = np.empty(0)
    if gains.shape != (len(elements),):
        raise ValueError(f"params: lti_gains: expected {len(elements)} gains, one per element of "
                         f"lti_elements, got {p.get('lti_gains')!r}")
    rows = [_section(("mode", p["mode_hz"], p["mode_damping"]), model.dt,
                     "mode_hz, mode_damping")]
    rows += [_section(el, model.dt, f"lti_elements[{j}]") for j, el in enumerate(elements)]
    return np.array([b for b, _ in rows]), np.array([a for _, a in rows]), gains


def prefilter_sections(model) -> tuple[np.ndarray, np.ndarray] | None:
    """A Wiener model's filter before the hysteresis in the C core's form, or None (no filter
    before the plays).

    Parameters
    ----------
    model : DiagnosedModel
        The model (``params["wiener_elements"]`` when ``model.dynamics_before``).

    Returns
    -------
    tuple of numpy.ndarray or None
        ``b``, ``a`` of shape ``(nw, 3)`` (powers of ``z^-1``, ``a[:, 0] = 1``): row ``j`` the
        ZOH of element ``j`` (:func:`~pimodel.diagnosis.lti.element_coefficients`, a first-order
        low-pass padded with zeros), run in series from ``v``.

    Raises
    ------
    ValueError
        No element or more than ``MAX_ELEMENTS`` (8), or a malformed element (named
        ``wiener_elements[j]``; kinds ``"lowpass"`` and ``"mode"``).

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0], [1.0], 0.0, dt=1e-3, effects=("dynamics",),
    ...                    params={"dynamics_position": "before",
    ...                            "wiener_elements": [["lowpass", 1e-3]]})
    >>> b, a = prefilter_sections(m)
    >>> b.round(4).tolist(), a.round(4).tolist()
    ([[0.0, 0.6321, 0.0]], [[1.0, -0.3679, 0.0]])
    """
    if not model.dynamics_before:
        return None
    elements = model.params.get("wiener_elements")
    if not isinstance(elements, (list, tuple)) or not 1 <= len(elements) <= MAX_ELEMENTS:
        raise ValueError(f"params: wiener_elements = {elements!r}: expected 1 to {MAX_ELEMENTS} "
                         "elements of the filter before the hysteresis")
    rows = [_section(el, model.dt, f"wiener_elements[{j}]", WIENER_K)
            for j, el in enumerate(elements)]
    return np.array([b for b, _ in rows]), np.array([a for _, a in rows])


def _band_gains(gains: np.ndarray, n: int) -> np.ndarray:
    """Per play, the gain of its rate band (:func:`.rate.play_bands`, as ``simulate``)."""
    if gains.ndim != 1 or not 1 <= gains.size <= n:
        raise ValueError(f"params: rate_gains: expected 1 to {n} gains (one per band of the "
                         f"{n} plays), got shape {gains.shape}")
    out = np.empty(n)
    for g, idx in zip(gains, play_bands(n, gains.size), strict=True):
        out[idx] = g
    return out


class NativeModel:
    """A model in the C core's form (``pim_diag``), with its arrays kept alive.

    Parameters
    ----------
    model : DiagnosedModel
        The model.
    input_range : float, optional
        Range of the rate effect's step rule; default ``2 r_n``.

    Raises
    ------
    ValueError
        A parameter the C core refuses (named), rate parameters of an earlier version
        (``rate_band_gains``) or more rate gains than plays, an LTI order above 63, a malformed
        further element of the linear part or more than 8 (:func:`element_sections`), a
        malformed filter before the hysteresis (:func:`prefilter_sections`, a Wiener model), or
        a delay above 4094 samples.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> nm = NativeModel(DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3))
    >>> x = nm.initial_state()
    >>> round(nm.step(x, 1.0, 0.0), 12), x[:2].tolist()  # y[0], (started, v_prev)
    (1.35, [1.0, 1.0])
    """

    def __init__(self, model, input_range: float | None = None):
        e, p, r = model.effects, model.params, model.radii
        n = r.size
        self.model = model
        self.input_range = float(2 * r[-1] if input_range is None else input_range)
        keep = {"w": model.weights, "r": r, "w0": model.reference_weights}
        d = _native.DiagParams()
        d.n, d.c, d.c0, d.dt = n, model.offset, model.reference_offset, model.dt
        d.plays_start = int(model.plays_start == "v0")  # 1: the C step sets z = v[0]
        if "creep" in e:
            taus = np.asarray(p["creep_time_constants_s"], float)
            keep["lag_a"] = np.exp(-model.dt / taus)  # as effects.lag
            keep["lag_g"] = np.asarray(p["creep_lag_gains"], float)
            if keep["lag_g"].shape != taus.shape:
                raise ValueError("params: creep_lag_gains and creep_time_constants_s: expected "
                                 "as many gains as time constants")
            d.m = taus.size
            starts = creep_start_levels(p)  # the lags at a common rest (module creep)
            if starts is not None:
                keep["lag_start"] = starts
            # counted from each record's start (module creep): less sum_j g_j L_j[-1]
            d.lag_record = int(p.get("creep_start") == "record")
        if "asymmetry" in e:
            d.asym, d.q, d.c3 = 1, p["asymmetry_quadratic"], p["asymmetry_cubic"]
            d.center, d.half = p["center"], p["half_range"]
        if "rate" in e:
            gains, family, tau = rate_params(p)
            keep["rate_w"] = _band_gains(gains, n)
            d.rate_family, d.rate_tau = FAMILY_CODES.index(family), tau
            d.rate_saturation = rate_saturation(p) or 0.0
            d.rate_growth = rate_growth(p) or 0.0
            d.rate_scale, d.input_range = p["rate_scale"], self.input_range
        lti = None if model.dynamics_before else lti_coefficients(model)
        if lti is not None:
            order = max(lti[0].size, lti[1].size) - 1
            if order > MAX_ORDER:
                raise ValueError(f"params: the LTI order {order} is above {MAX_ORDER}")
            keep["b"] = np.pad(lti[0], (0, order + 1 - lti[0].size))
            keep["a"] = np.pad(lti[1], (0, order + 1 - lti[1].size))
            d.order = order
        sections = None if model.dynamics_before else element_sections(model)
        if sections is not None:
            keep["el_b"], keep["el_a"], keep["el_g"] = sections
            d.ne = sections[2].size
        prefilter = prefilter_sections(model)
        if prefilter is not None:
            keep["wf_b"], keep["wf_a"] = prefilter
            d.nw = prefilter[0].shape[0]
        if "delay" in e:
            d.delay = float(p["delay_samples"])
            if not 0 <= d.delay <= MAX_DELAY:
                raise ValueError(f"params: delay_samples = {d.delay!r}: expected 0 to "
                                 f"{MAX_DELAY} samples")
        if "drift" in e:
            if p["drift_clock"] not in CLOCKS:
                raise ValueError(f"params: drift_clock = {p['drift_clock']!r}: expected one of "
                                 f"{sorted(CLOCKS)}")
            d.drift_clock, d.drift = CLOCKS[p["drift_clock"]], p["drift_per_s"]
            if "drift_settling_time_s" in p:  # a settling on the clock t (drift.drift_term)
                d.settle, d.settle_tau = p["drift_settling"], p["drift_settling_time_s"]
                d.settle_t0 = p["drift_settling_start_s"]
            if p.get("drift_variant") == "levels" and p["drift_clock"] == "absolute":
                # a level per record, predicted by the clock: the trend since the train
                # record's start, s (t - t0_train) (drift.drift_term without `measured`)
                d.c = model.offset - p["drift_per_s"] * float(p["drift_t0_train"])
        self._keep = {k: np.ascontiguousarray(v, dtype=float) for k, v in keep.items()}
        for k, v in self._keep.items():
            setattr(d, k, _native.diag_pointer(v))
        msg = _native.diag_check(d)
        if msg:
            raise ValueError(f"model: {msg}")
        self.params = d
        self.nstates = _native.diag_state_size(d)

    def initial_state(self) -> np.ndarray:
        """The state before the first sample: not started, plays (and a Wiener model's plays of
        the filtered input) at rest at 0 (``pim_diag_initial_state``); a model whose plays
        start at ``v[0]`` has them set on the first sample.

        Returns
        -------
        numpy.ndarray
            Zeros, ``nstates`` values (labels: :func:`state_labels`).

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> NativeModel(DiagnosedModel([0.0], [1.0], 0.0, dt=1e-3)).initial_state().tolist()
        [0.0, 0.0, 0.0, 0.0, 0.0]
        """
        return _native.diag_initial_state(self.params, 0.0)

    def step(self, x: np.ndarray, v: float, t: float) -> float:
        """``y[k]`` for ``v[k]`` at time ``t[k]`` [s]; ``x`` (float64) advances in place.

        Parameters
        ----------
        x : numpy.ndarray
            The state after sample k - 1 (``nstates`` float64 values, C-contiguous).
        v, t : float
            Input sample and its time [s].

        Returns
        -------
        float

        Raises
        ------
        ValueError
            ``x`` of another length, ``v`` or ``t`` not finite.

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> nm = NativeModel(DiagnosedModel([0.0], [2.0], 0.0, dt=1e-3))
        >>> nm.step(nm.initial_state(), 0.5, 0.0)
        1.0
        """
        if x.shape != (self.nstates,):
            raise ValueError(f"state: expected {self.nstates} values, got {x.shape}")
        if not (math.isfinite(v) and math.isfinite(t)):
            raise ValueError(f"v, t: sample ({v!r}, {t!r}) is not finite")
        return _native.diag_step(self.params, x, v, t)

    def run(self, v: np.ndarray, t: np.ndarray | None = None) -> np.ndarray:
        """``y[k]`` for a whole signal from the initial state (``t``: None gives ``k dt``).

        Parameters
        ----------
        v : numpy.ndarray
            Input samples.
        t : numpy.ndarray, optional
            Their times [s].

        Returns
        -------
        numpy.ndarray

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> NativeModel(DiagnosedModel([0.0], [2.0], 0.0, dt=1e-3)).run(np.ones(2)).tolist()
        [2.0, 2.0]
        """
        v = np.ascontiguousarray(v, dtype=float)
        t = None if t is None else np.ascontiguousarray(t, dtype=float)
        return _native.diag_run(self.params, self.initial_state(), v, t)


def stream_simulate(model, v, t=None, *, input_range: float | None = None) -> np.ndarray:
    """``model.simulate(v, t)`` on the C core, sample by sample (what the block and the FMU run).

    Parameters
    ----------
    model : DiagnosedModel
        The model.
    v : array_like
        Input samples, every ``dt``.
    t : array_like, optional
        Times [s] (drift); default ``k dt``.
    input_range : float, optional
        Range of the rate effect's step rule; default ``2 r_n`` (``simulate``: ``ptp(v)``).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ValueError
        ``v`` not a finite 1-D signal, ``t`` of another length, a bad model parameter.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> stream_simulate(m, [0.0, 1.0, 0.0]).round(3).tolist()
    [0.1, 1.35, 0.35]
    """
    v = checked_signal(v, "v")
    tk = model._clock(v, t)
    return NativeModel(model, input_range).run(v, tk)


def state_labels(model) -> list[str]:
    """Names of the block's states, in the C core's layout (``fmu/src/pim_diagnosed.h``).

    Parameters
    ----------
    model : DiagnosedModel
        The model.

    Returns
    -------
    list of str
        ``started``, ``v_prev``, ``t_start``, ``head`` (delay line position), ``z[1..n]`` (play
        states), ``rho_f`` (filtered rate of the last sample, with a rate effect) and
        ``m[1..n]`` (the radius family's terms held from each play's last contact),
        ``L[1..m]`` (creep lags),
        ``s[1..q]`` (LTI states), ``e[1..2 (ne + 1)]`` (the sections of the linear part's
        further elements and of its base mode on ``h0``), ``x_delay[1..nbuf]`` and
        ``h0_delay[1..nbuf]`` (delay lines of the hysteresis term and of ``h0``),
        and for a Wiener model ``zf[1..n]`` (plays of the filtered input) and ``f[1..2 nw]``
        (two states per section of the filter before the hysteresis), and ``L0`` (the lags'
        start ``h0[0]``, kept for a creep counted from each record's start, ``creep_start``
        ``"record"``).

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> state_labels(DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3))
    ['started', 'v_prev', 't_start', 'head', 'z[1]', 'z[2]']
    """
    d = NativeModel(model).params
    n = model.radii.size
    nbuf = int(math.floor(d.delay)) + 2 if d.delay > 0 else 0
    rate = []
    if d.rate_w:
        rate = (["rho_f"] + signal_labels("m", n) if d.rate_family == 0 else
                ["rate"] + signal_labels("zs", n) if d.rate_family == 2 else ["rho_f"])
    return (["started", "v_prev", "t_start", "head"] + signal_labels("z", n)
            + rate + signal_labels("L", d.m)
            + signal_labels("s", d.order) + signal_labels("e", 2 * (d.ne + 1) if d.ne else 0)
            + signal_labels("x_delay", nbuf) + signal_labels("h0_delay", nbuf)
            + (signal_labels("zf", n) + signal_labels("f", 2 * d.nw) if d.nw else [])
            + (["L0"] if d.lag_record and d.m else []))


def _block_setting(value):
    """A model parameter as a block setting: numeric lists stay lists (arrays in params); other
    lists (``lti_elements``: kinds and numbers; a report's ``dynamics_modes``: dicts) become
    tuples, which the block's settings keep as they are."""
    if not isinstance(value, list):
        return value
    try:
        np.asarray(value, dtype=float)
        return value
    except (TypeError, ValueError):
        return tuple(tuple(x) if isinstance(x, list) else x for x in value)


def diagnosed_block(model, dt: float | None = None, *, name: str = "diagnosed",
                    input: str = "v", output: str = "y",
                    input_range: float | None = None) -> control.NonlinearIOSystem:
    """The model as a discrete python-control block (C step, :mod:`pimodel.blocks` contract).

    ``outfcn(t, x[k], v[k])`` gives ``y[k]`` and ``updfcn`` the state after sample k (direct
    feedthrough); ``t`` is python-control's time, used by a drift term (module docstring).

    Parameters
    ----------
    model : DiagnosedModel
        The model.
    dt : float, optional
        Sample time [s]; must be the model's ``dt`` (default), at which its lags, LTI part and
        delay were fitted.
    name, input, output : str
        Block name (params prefix) and signal names.
    input_range : float, optional
        Range of the rate effect's step rule; default ``2 r_n``.

    Returns
    -------
    control.NonlinearIOSystem
        States :func:`state_labels`; initial state all zeros (``pimodel.blocks.initial_state``).

    Raises
    ------
    ValueError
        ``dt`` other than the model's, a bad model parameter.

    Notes
    -----
    Params (defaults from the model): ``"<name>.weights"``, ``"<name>.offset"``,
    ``"<name>.reference_weights"``, ``"<name>.reference_offset"``, ``"<name>.input_range"``
    and every effect parameter of ``model.params`` (``"<name>.creep_lag_gains"``, ...). A
    change that alters the state layout (number of lags, LTI order, delay line, number of
    elements of a Wiener model's filter) is refused.

    Examples
    --------
    >>> import control
    >>> from pimodel.blocks import initial_state
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> blk = diagnosed_block(m)
    >>> t = np.arange(3) * 1e-3
    >>> res = control.input_output_response(blk, t, [0.0, 1.0, 0.0],
    ...                                     initial_state=initial_state(blk))
    >>> res.outputs.round(3).tolist()
    [0.1, 1.35, 0.35]
    """
    block_dt(model, dt, "its lags, LTI part and delay")
    native = NativeModel(model, input_range)
    labels = state_labels(model)

    def build(s: dict) -> NativeModel:
        params = {k: s[k] for k in model.params}
        new = replace(model, weights=s["weights"], offset=s["offset"],
                      reference_weights=s["reference_weights"],
                      reference_offset=s["reference_offset"], params=params)
        nm = NativeModel(new, s["input_range"])
        if nm.nstates != len(labels):
            raise ValueError(f"the state layout changed ({nm.nstates} states, the block has "
                             f"{len(labels)}): build a new block for this model")
        return nm

    params = {k: _block_setting(x) for k, x in model.params.items()}
    defaults = {"weights": model.weights.copy(), "offset": model.offset,
                "reference_weights": model.reference_weights.copy(),
                "reference_offset": model.reference_offset,
                "input_range": native.input_range, **params}
    settings = BlockSettings(name, defaults, build)

    def step(nm, x, v, t):
        return nm.step(x, v, t), x

    return stepped_block(settings, step, own_state=lambda params: settings.get(params)
                          .initial_state(), states=labels, dt=model.dt, name=name, input=input,
                          output=output)


def _static_effect_values(d, k: dict, params: dict) -> dict:
    """The creep, asymmetry and rate variables shared by the DiagnosedModel and
    DiagnosedInverse FMU units: ``d`` and ``k`` are a checked parameter set and its kept
    arrays (:class:`NativeModel` or :class:`~.native_inverse.NativeInverse`), ``params`` the
    model's parameters (the creep's time constants)."""
    def arr(name, values):
        return labelled_values(name, values, split=NMAX)

    out = {}
    if d.m:
        out.update({"n_lags": int(d.m), **arr("creep_gain", k["lag_g"]),
                    **arr("creep_tau", params["creep_time_constants_s"])})
        if "lag_start" in k:  # the lags' common rest (module creep)
            out.update({"creep_start": 1, **arr("creep_start_level", k["lag_start"])})
        if d.lag_record:  # counted from each record's start (both units)
            out["creep_start"] = 2
    if d.asym:
        out.update({"asymmetry_quadratic": d.q, "asymmetry_cubic": d.c3, "center": d.center,
                    "half_range": d.half})
    if "rate_w" in k:
        out.update({**arr("rate_band_gain", k["rate_w"]), "rate_scale": d.rate_scale,
                    "rate_family": int(d.rate_family), "rate_tau": d.rate_tau,
                    "rate_saturation": d.rate_saturation,
                    **({"rate_growth": d.rate_growth} if d.rate_family == 2 else {})})
    return out


def fmu_parameters(model, *, input_range: float | None = None) -> tuple[str, dict]:
    """The DiagnosedModel FMU unit and its variable values for ``model`` (``Ts = dt``).

    Parameters
    ----------
    model : DiagnosedModel
        The model (at most 128 plays, ``p[1..64]`` and ``p_hi[1..64]``, and 64 creep lags; a
        Wiener model's filter in ``n_wiener_elements``, ``wiener_element_b``,
        ``wiener_element_a``, :func:`prefilter_sections`).
    input_range : float, optional
        Range of the rate effect's step rule; default ``2 r_n``.

    Returns
    -------
    (str, dict)
        ``"DiagnosedModel"`` and ``{variable name: value}`` (FMI 2 names, ``"p[2]"``).

    Raises
    ------
    ValueError
        More than 128 plays or 64 lags, or a parameter the C core refuses.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> name, values = fmu_parameters(DiagnosedModel([0.0, 0.5], [1.0, -0.2], 0.1, dt=1e-3))
    >>> name, values["n"], values["p[2]"], values["offset"]
    ('DiagnosedModel', 2, -0.2, 0.1)
    """
    nm = NativeModel(model, input_range)  # checks the parameters
    d, k = nm.params, nm._keep
    n = model.radii.size
    if n > 2 * NMAX or d.m > NMAX:
        raise ValueError(f"model: {n} plays and {d.m} creep lags; the FMU takes at most "
                         f"{2 * NMAX} plays and {NMAX} lags")

    def arr(name, values):
        """Plays 1..64 in NAME[i], 65..128 in NAME_hi[i] (other arrays: up to 64)."""
        return labelled_values(name, values, split=NMAX)

    out = {"Ts": model.dt, "n": n, "z0": 0.0, "plays_start": int(d.plays_start),
           **arr("p", model.weights), **arr("r", model.radii),
           **arr("w0", model.reference_weights), "offset": d.c,
           "reference_offset": model.reference_offset, "input_range": nm.input_range}
    out.update(_static_effect_values(d, k, model.params))
    if d.order:
        out.update({"lti_order": int(d.order), **arr("lti_b", k["b"]), **arr("lti_a", k["a"])})
    if d.ne:
        out.update({"n_lti_elements": int(d.ne), **arr("lti_gain", k["el_g"]),
                    **arr("lti_element_b", k["el_b"].ravel()),
                    **arr("lti_element_a", k["el_a"].ravel())})
    if d.nw:
        out.update({"n_wiener_elements": int(d.nw), **arr("wiener_element_b", k["wf_b"].ravel()),
                    **arr("wiener_element_a", k["wf_a"].ravel())})
    if d.delay:
        out["delay_samples"] = d.delay
    if d.drift_clock:
        out.update({"drift_per_s": d.drift, "drift_clock": int(d.drift_clock)})
    if d.settle_tau:
        out.update({"drift_settling": d.settle, "drift_settling_tau": d.settle_tau,
                    "drift_settling_start": d.settle_t0})
    return "DiagnosedModel", out

