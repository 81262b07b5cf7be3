"""A :class:`~pimodel.diagnosis.model.DiagnosedInverse`'s causal feedforward on the C core
(``fmu/src/pim_diag_inverse.c``): the python-control block (:func:`inverse_block`, what
:meth:`DiagnosedInverse.block` returns), the runner :class:`NativeInverse` and the values of the
DiagnosedInverse FMU unit (:func:`inverse_fmu_parameters`), so that the block, the runner and
the FMU are one implementation.

It runs what the NumPy reference :func:`~pimodel.diagnosis.reference_inverse.inverse_block`
runs (the ``_InverseStream`` sample), so ``tests/test_inverse_native.py`` holds the two equal
to 1e-9, output and whole state: fed ``y_d[0..k]``, it outputs ``v[k] =
DiagnosedInverse.simulate(y_d)[k - A]`` for ``k >= A`` (``A`` =
:func:`~pimodel.diagnosis.reference_inverse.inverse_latency`: the dynamics' one-sample advance
and the delay's whole samples, one more for a fractional delay) and ``v_rest``, the inverse of
``y_d[0]`` from the initial state, before. Per sample: the prefilter's second-order sections
(:func:`~pimodel.diagnosis.lti.inverse_sos`, at rest around ``y_d[0]``), the delay's fractional
interpolation, and the exact root of the static part (creep, asymmetry, rate with the fresh
rate of a nested rate-free solve), on the model's nearest monotone weights (:mod:`.monotone`);
the semantics in ``fmu/src/pim_diag_inverse.h``.

Parameters computed here and passed to C: the projected weights, the sections, the latency,
the delay's fraction and the root rule's scale ``reference_range``. A model with the filter
before the hysteresis (``dynamics_position = "before"``, a Wiener model) has no prefilter; its
filter's approximate inverse (:func:`~pimodel.diagnosis.wiener.inverse_sections`) runs as
post sections on the solver's output, at rest around the first solve, with one more sample of
latency (the batch's one-sample advance).
"""

from __future__ import annotations

import math

import control
import numpy as np

from .. import _native
from ..blocks.framework import labelled_values, signal_labels
from .checks import checked_signal
from .limits import MAX_LATENCY, MAX_SECTIONS, NMAX
from .native_model import _band_gains, _static_effect_values
from .rate import FAMILY_CODES
from .reference_inverse import StaticInverse, _delay, _filter, feedforward_block, inverse_latency
from .wiener import inverse_sections

__all__ = ["NativeInverse", "inverse_block", "inverse_fmu_parameters"]


class NativeInverse:
    """A diagnosed model's feedforward in the C core's form (``pim_dinv``), arrays kept alive.

    Parameters
    ----------
    inverse : DiagnosedInverse
        The inverse (``model.inverse()``).
    input_range : float, optional
        Range of the rate effect's step rule; default ``2 r_n`` (as ``simulate``).
    reference_range : float, optional
        The root rule's scale (:class:`~pimodel.diagnosis.reference_inverse.StaticInverse`);
        ``simulate`` uses ``ptp(inverse.prefilter(y_d))``; default 0.

    Raises
    ------
    ValueError
        A Wiener model (``dynamics_position = "before"``), more than 128 plays or 64 creep
        lags, a parameter the C core refuses (named), or one the Python solver refuses.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> ni = NativeInverse(m.inverse())
    >>> ni.run([0.1, 1.35, 0.35]).round(9).tolist(), ni.latency
    ([0.0, 1.0, 0.0], 0)
    """

    def __init__(self, inverse, input_range: float | None = None,
                 reference_range: float | None = None):
        model = inverse.model
        solver = StaticInverse(model, input_range, reference_range)  # checks, projects
        m, p = solver.model, solver.model.params
        n = solver.n
        if n > 2 * NMAX:
            raise ValueError(f"model: {n} plays; the C feedforward takes at most {2 * NMAX}")
        self.model, self.input_range = model, solver.input_range
        self.reference_range = 0.0 if reference_range is None else float(reference_range)
        keep = {"w": solver.w, "r": solver.r, "w0": solver.w0}
        d = _native.InverseParams()
        d.n, d.c, d.c0, d.dt = n, m.offset, m.reference_offset, m.dt
        d.input_range, d.reference_range = self.input_range, self.reference_range
        if solver.creep:
            keep["lag_a"] = solver.a_lag
            keep["lag_g"] = np.asarray(p["creep_lag_gains"], float)
            if keep["lag_g"].shape != solver.a_lag.shape or solver.m > NMAX:
                raise ValueError("params: creep_lag_gains and creep_time_constants_s: expected "
                                 f"as many gains as time constants, at most {NMAX}")
            d.m = solver.m
            if solver.starts is not None:  # the lags at a common rest (module creep)
                keep["lag_start"] = solver.starts
            d.lag_record = solver.record  # counted from each record's start: L0 in the state
        if solver.asym:
            d.asym, d.q, d.c3 = 1, p["asymmetry_quadratic"], p["asymmetry_cubic"]
            d.center, d.half = p["center"], p["half_range"]
        if solver.rate:
            keep["rate_w"] = _band_gains(np.asarray(p["rate_gains"], float), n)
            d.rate_family = FAMILY_CODES.index(p["rate_family"])
            d.rate_growth = solver.growth or 0.0
            d.rate_tau, d.rate_scale = solver.tau, p["rate_scale"]
            d.rate_saturation = solver.saturation or 0.0
        sos, _ = _filter(model)
        if sos is not None:
            if sos.shape[0] > MAX_SECTIONS:
                raise ValueError(f"params: the prefilter has {sos.shape[0]} sections; the C "
                                 f"feedforward takes at most {MAX_SECTIONS}")
            keep["sos"] = sos
            d.ns = sos.shape[0]
        if model.dynamics_before:  # the filter's approximate inverse after the solve
            post = inverse_sections(model.params["wiener_elements"], model.dt)
            if post is not None and post.shape[0] > MAX_SECTIONS:
                raise ValueError(f"params: wiener_elements: the filter's inverse has "
                                 f"{post.shape[0]} sections; the C feedforward takes at most "
                                 f"{MAX_SECTIONS}")
            if post is not None:
                keep["post"] = post
                d.npost = post.shape[0]
        self.latency = inverse_latency(model)
        if self.latency > MAX_LATENCY:
            raise ValueError(f"params: the latency {self.latency} is above {MAX_LATENCY} samples")
        d.latency, d.frac = self.latency, _delay(model)[1]
        self._keep = {k: np.ascontiguousarray(v, dtype=float) for k, v in keep.items()}
        for k, v in self._keep.items():
            setattr(d, k, _native.diag_pointer(v))
        msg = _native.inverse_check(d)
        if msg:
            raise ValueError(f"model: {msg}")
        self.params, self.n = d, n
        self.nstates = _native.inverse_state_size(d)
        self._solver_labels = solver.labels()

    def labels(self) -> list[str]:
        """Names of the state values (the layout of the reference stream's state).

        Returns
        -------
        list of str
            ``started``, ``seen`` (samples seen while the latency fills), ``v_rest``,
            ``F_prev`` (the last prefiltered sample), ``f[1..2 ns]`` (prefilter sections),
            ``g[1..2 np]`` (a Wiener model's post sections) and ``solver.*``
            (:meth:`~pimodel.diagnosis.reference_inverse.StaticInverse.labels`).

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> ni = NativeInverse(DiagnosedModel([0.0], [1.0], 0.0, dt=1e-3).inverse())
        >>> ni.labels()[4:], len(ni.labels()) == ni.nstates
        (['solver.started', 'solver.v_prev', 'solver.guess', 'solver.z[1]'], True)
        """
        d = self.params
        return (["started", "seen", "v_rest", "F_prev"] + signal_labels("f", 2 * d.ns)
                + signal_labels("g", 2 * d.npost) + [f"solver.{s}" for s in self._solver_labels])

    def initial_state(self, z0=None) -> np.ndarray:
        """The state before the first sample: not started, the plays at rest at 0 or at ``z0``.

        Parameters
        ----------
        z0 : array_like, optional
            The plays' outputs before the first sample (``inverse.initial_memory(y_d[0])`` for
            a stage whose memory is unknown, as ``simulate(initial_state="unknown")``).

        Returns
        -------
        numpy.ndarray
            ``nstates`` values, the layout of the Python stream's state.

        Raises
        ------
        ValueError
            ``z0`` not ``n`` finite values.

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> ni = NativeInverse(DiagnosedModel([0.0], [1.0], 0.0, dt=1e-3).inverse())
        >>> ni.initial_state([0.0]).tolist()
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        """
        if z0 is None:
            return _native.inverse_initial_state(self.params)
        z = np.ascontiguousarray(z0, dtype=float)
        if z.shape != (self.n,) or not np.all(np.isfinite(z)):
            raise ValueError(f"z0: expected {self.n} finite play outputs, got shape {z.shape}")
        return _native.inverse_initial_state(self.params, z)

    def step(self, x: np.ndarray, y_d: float) -> float:
        """``v[k]`` for the reference sample ``y_d[k]``; ``x`` (float64) advances in place.

        Parameters
        ----------
        x : numpy.ndarray
            The state after sample k - 1 (``nstates`` values, C-contiguous).
        y_d : float
            The reference sample [output units].

        Returns
        -------
        float
            ``v[k]`` [input units].

        Raises
        ------
        ValueError
            ``x`` of another length, ``y_d`` not finite.

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> ni = NativeInverse(DiagnosedModel([0.0], [2.0], 0.0, dt=1e-3).inverse())
        >>> ni.step(ni.initial_state(), 1.0)
        0.5
        """
        if x.shape != (self.nstates,) or x.dtype != np.float64:
            raise ValueError(f"state: expected {self.nstates} float64 values, got {x.shape} "
                             f"{x.dtype}")
        if not math.isfinite(y_d):
            raise ValueError(f"y_d: sample {y_d!r} is not finite")
        return _native.inverse_step(self.params, x, y_d)

    def run(self, y_d, z0=None) -> np.ndarray:
        """``v[k]`` for a whole reference from the initial state (:meth:`initial_state`).

        Parameters
        ----------
        y_d : array_like
            Reference samples, every ``dt``.
        z0 : array_like, optional
            The plays' start (:meth:`initial_state`).

        Returns
        -------
        numpy.ndarray

        Raises
        ------
        ValueError
            ``y_d`` not a finite 1-D signal.

        Examples
        --------
        >>> from pimodel.diagnosis.model import DiagnosedModel
        >>> m = DiagnosedModel([0.0], [2.0], 0.0, dt=1e-3, effects=("delay",),
        ...                    params={"delay_samples": 1})
        >>> NativeInverse(m.inverse()).run([2.0, 4.0, 6.0]).tolist()  # latency 1
        [1.0, 2.0, 3.0]
        """
        yd = np.ascontiguousarray(checked_signal(y_d, "y_d"), dtype=float)
        return _native.inverse_run(self.params, self.initial_state(z0), yd)


def inverse_block(inverse, dt: float | None = None, *, name: str = "inverse",
                  input: str = "y_d", output: str = "v", input_range: float | None = None,
                  reference_range: float | None = None) -> control.NonlinearIOSystem:
    """The causal feedforward as a discrete python-control block, stepped on the C core.

    Equal to the NumPy reference :func:`~pimodel.diagnosis.reference_inverse.inverse_block`
    (to 1e-9, ``tests/test_inverse_native.py``): fed ``y_d[0..k]``, it outputs ``v[k] =
    v_batch[k - A]`` (module docstring).

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
        :class:`~pimodel.diagnosis.reference_inverse.StaticInverse`'s scale of the root rule;
        ``simulate`` uses ``ptp(inverse.prefilter(y_d))``.

    Returns
    -------
    control.NonlinearIOSystem
        ``v[k] = v_batch[k - A]`` (``A`` =
        :func:`~pimodel.diagnosis.reference_inverse.inverse_latency`; ``v_rest`` before),
        direct feedthrough when ``A = 0``; states :meth:`NativeInverse.labels`, initial state
        all zeros; params ``"<name>.input_range"``, ``"<name>.reference_range"``. The latency
        is also the block's attribute ``latency``.

    Raises
    ------
    ValueError
        ``dt`` other than the model's, a bad model parameter, a model the C core does not
        take (:class:`NativeInverse`).

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
    return feedforward_block(inverse, dt, lambda ir, rr: NativeInverse(inverse, ir, rr),
                             name=name, input=input, output=output, input_range=input_range,
                             reference_range=reference_range)


def inverse_fmu_parameters(inverse, *, input_range: float | None = None,
                           reference_range: float | None = None) -> tuple[str, dict]:
    """The DiagnosedInverse FMU unit and its variable values for ``inverse`` (``Ts = dt``).

    The static part's variables are those of the DiagnosedModel unit
    (:func:`~pimodel.diagnosis.native_model.fmu_parameters`) with the projected (monotone) weights;
    the feedforward adds ``n_sections``, ``section[1..6 ns]`` (the prefilter),
    ``n_post_sections``, ``post_section[1..6 np]`` (a Wiener model's filter inverse),
    ``latency``, ``delay_fraction`` and ``reference_range``.

    Parameters
    ----------
    inverse : DiagnosedInverse
        The inverse (at most 128 plays, 64 creep lags, 10 prefilter sections).
    input_range : float, optional
        Range of the rate effect's step rule; default ``2 r_n``.
    reference_range : float, optional
        The root rule's scale; default 0.

    Returns
    -------
    (str, dict)
        ``"DiagnosedInverse"`` and ``{variable name: value}`` (FMI 2 names, ``"p[2]"``).

    Raises
    ------
    ValueError
        As :class:`NativeInverse`, or more sections than the FMU holds.

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> name, values = inverse_fmu_parameters(m.inverse())
    >>> name, values["n"], values["latency"], values["offset"]
    ('DiagnosedInverse', 2, 0, 0.1)
    """
    ni = NativeInverse(inverse, input_range, reference_range)
    d, k = ni.params, ni._keep
    for what, count in (("the prefilter", d.ns), ("the Wiener filter's inverse", d.npost)):
        if 6 * count > NMAX:
            raise ValueError(f"params: {what} has {count} sections; the FMU takes at most "
                             f"{NMAX // 6}")

    def arr(name, values):
        """Plays 1..64 in NAME[i], 65..128 in NAME_hi[i] (other arrays: up to 64)."""
        return labelled_values(name, values, split=NMAX)

    out = {"Ts": d.dt, "n": int(d.n), **arr("p", k["w"]), **arr("r", k["r"]),
           **arr("w0", k["w0"]), "offset": d.c, "reference_offset": d.c0,
           "input_range": d.input_range, "reference_range": d.reference_range,
           "latency": int(d.latency), "delay_fraction": d.frac}
    out.update(_static_effect_values(d, k, inverse.model.params))
    if d.ns:
        out.update({"n_sections": int(d.ns), **arr("section", k["sos"].ravel())})
    if d.npost:
        out.update({"n_post_sections": int(d.npost), **arr("post_section", k["post"].ravel())})
    return "DiagnosedInverse", out
