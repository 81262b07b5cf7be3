"""The ``rate`` candidate: hysteresis whose play radii or weights depend on a low-passed input
rate, to first order as columns that are linear in their gains, or exactly as plays whose
radii scale with the rate (the ``"scaled"`` shape, below).

A rate-dependent PI model (as :class:`pimodel.operators.rate_dependent.RateDependentPI`,
generalised) has radii ``r_i (1 + a_b rho_f[k])`` or weights ``w_i (1 + c_b rho_f[k])`` for the
plays ``i`` of band ``b``, where ``rho_f`` is the input rate, normalised by ``rate_scale`` and
passed through a first-order low-pass with time constant ``tau`` (``tau = 0``: the rate of the last
sample interval). Two families, one loop that widens with the rate and one that grows as a whole; to
first order in the gains the output changes by

* ``"radius"`` columns ``R_b[k] = sum_{i in b} (-s_i) r_i rho_f[j_i]``: play ``i`` lags further
  behind the input on the branch it last touched; ``j_i <= k`` is the last sample at which the
  nominal play was in contact (``|v[j] - z_i[j]| = r_i``, pushed or about to be) and ``s_i`` the
  sign of ``v - z_i`` there: while in contact the column follows the current rate (a play whose
  radius shrinks as the input slows down stays in contact), after it the play's output is held;
* ``"weight"`` columns ``W_b[k] = rho_f[k] sum_{i in b} w0_i z_i[k]``: the band's contribution
  scales with the current filtered rate (``w0`` the reference weights, so a uniform ``c_b``
  scales the band's part of the loop as a whole).

Fitted jointly, the two families share too much on a record of a few constant rates (while a
play is in contact, ``R`` is ``rho_f (z_i - v)``, a weight column minus a linear one) and the fit
then follows neither out of contact (measured: a validate RMS 2.2 times that of the radius
family alone on ``pimodel.stages.pi_stage``). So the candidate fits one family's ``RATE_BANDS``
gains jointly with the hysteresis weights and chooses the family and ``tau`` by the train residual:
``tau`` on the grid ``RATE_TAUS``, then by geometric steps (``RATE_TAU_REFINE``) around the best
positive one. Without a filter (``tau = 0``) a sampled step, a one-sample jump above
``STEP_SHARE`` of the input range, is no rate a play follows (its rate counts as 0); a low-pass
spreads a step's rate over ``tau``, so with a filter it counts as moved.

The filtered rate enters the columns through a saturating map, ``rho_s = rho_f / (1 + rho_f /
S)`` (:func:`saturated_rate`; ``S`` None: ``rho_s = rho_f``): a loop that widens with the rate
up to a bound, as a stage's does. Without it, gains fitted on slow train records (the train's
rates are at most a few ``rate_scale``) extrapolate linearly to fast validate records (measured
on ``pimodel.stages.density_stage``, train up to about 600 V/s, validate up to 8000 V/s: a
validate RMS 6.7 times the nominal's on seed 0; with the map 0.14-0.49 times it over 10
seeds). ``S`` is chosen on train after the filter, on the grid ``RATE_SATURATIONS`` (None
among them); then ``S`` by the steps ``RATE_SATURATION_REFINE`` and
``tau`` by the finest of ``RATE_TAU_REFINE``, both tried in each of up to ``RATE_POLISH_ROUNDS``
rounds while the train residual falls (the two trade against each other: a longer filter
lowers the peaks the saturation bounds).

The first-order form follows each nominal play's contact; when the radii grow by tens of
percent a play whose radius grew meets its boundary later than the nominal play does, and the
columns cannot follow (measured on ``pimodel.stages.density_stage``, radii growing by 30-60 %:
seed 0 leaves 8.3 noise floors with the stage's own filter and ``S``). The exact shape,
family ``SCALED`` (``"scaled"``), runs the plays themselves with radii scaled per sample,

    ``rho_i[k] = r_i (1 + g(s[k]))``, ``g(s) = G s / (1 + s / S)`` (``S`` None: ``G s``),
    ``s[k] = a s[k-1] + (1 - a) |v[k-1] - v[k-2]| / dt / rate_scale``, ``a = exp(-dt / tau)``,

strictly causal (``s[k]`` from ``v[..k-1]``: the radii of sample ``k`` are fixed before
``v[k]``, as in :mod:`pimodel.operators.rate_dependent`, whose C core runs them,
:func:`scaled_plays`). The weights are fitted by least squares on these plays in place of the
nominal ones (the hysteresis is ``sum_i w_i zs_i``; as an effect term beside the plays, the
model's ``sum_i g_b w_i (zs_i - z_i)`` with one gain ``g = 1``). ``G``, ``S`` and
``tau > 0`` are nonlinear: a grid (``RATE_GROWTHS`` times half, once and twice the
first-order form's ``S``, at its filter), then the three together by a Nelder-Mead polish in
their logarithms (at most ``RATE_SCALED_EVALS`` fits; ``G`` and ``S`` trade along a valley;
the filter at most ``RATE_TAU_MAX``, what the first-order search reaches).
The shape is offered beside the first-order one and chosen by validate BIC
(:func:`rate_shapes`), not with dynamics or a delay (their columns filter or shift the
nominal plays).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from .. import _native
from ..operators.pi import PIOperator
from .chunked import chunks, transposed
from .threads import drop_threads, per_thread

RATE_TAUS = (0.0, 1e-3, 3e-3, 10e-3, 30e-3)  # s: low-pass of the input rate, half decades
RATE_TAU_START = 0.0  # the filter held while other grids (mode, delay, ...) are searched
RATE_TAU_REFINE = (10**0.25, 10**0.125)  # then steps around the optimum: 1/4, 1/8 decade
RATE_BANDS = 8  # play bands: the candidate has RATE_BANDS gains
RATE_FAMILIES = ("radius", "weight")  # radii or weights growing with the rate
STEP_SHARE = 0.05  # without a filter, a one-sample jump above this share of the range is a step
RATE_SATURATIONS = (None, 4.0, 2.0, 1.0, 0.5)  # S [-]: rho_f / (1 + rho_f / S), None: linear
RATE_SATURATION_REFINE = 2**0.25  # then steps of S (1/4 octave) and of the filter (1/8 decade)
RATE_POLISH_ROUNDS = 4  # ... in turn, while the train residual falls
SCALED = "scaled"  # the exact shape: plays whose radii scale with the rate (module docstring)
# a rate candidate's grid parameters, held or searched together (rate_growth: SCALED only)
RATE_KEYS = ("rate_family", "rate_tau", "rate_saturation", "rate_growth")
FAMILY_CODES = (*RATE_FAMILIES, SCALED)  # rate_family of the C core (pim_diagnosed.h): 0, 1, 2
RATE_GROWTHS = (0.1, 0.2, 0.4, 0.8, 1.6)  # G [-] of the scaled shape's grid
RATE_GROWTH_REFINE = 2**0.25  # then G, S and the filter polished (first steps: 1/4 octave)
RATE_SCALED_EVALS = 60  # ... by at most this many fits (Nelder-Mead in log G, log S, log tau)
# the exact shape's filter stays within what the first-order search reaches (its grid, one
# step of each RATE_TAU_REFINE, RATE_POLISH_ROUNDS of the finest: 30 ms * 10^0.875 = 0.22 s);
# the polish refines the optimum and does not leave the candidate's range (issue 28: on
# density_stage drift seed 4 it ran to 1.9 s, 38 % of the record, where the filtered rate is a
# slow envelope of the input speed, a loop width changing in time beside a drift)
RATE_TAU_MAX = RATE_TAUS[-1] * RATE_TAU_REFINE[0] * RATE_TAU_REFINE[-1] ** (RATE_POLISH_ROUNDS + 1)
CONTACT_BYTES = 96 << 20  # a basis keeps its plays' last contacts up to this size (12 B each)

__all__ = [
    "FAMILY_CODES",
    "RATE_BANDS",
    "RATE_FAMILIES",
    "RATE_KEYS",
    "RATE_GROWTHS",
    "RATE_GROWTH_REFINE",
    "RATE_POLISH_ROUNDS",
    "RATE_SATURATIONS",
    "RATE_SCALED_EVALS",
    "RATE_SATURATION_REFINE",
    "RATE_TAUS",
    "RATE_TAU_MAX",
    "RATE_TAU_REFINE",
    "RateBasis",
    "SCALED",
    "filtered_rate",
    "input_rate",
    "play_bands",
    "rate_columns",
    "rate_growth",
    "rate_params",
    "rate_saturation",
    "rate_shapes",
    "saturated_rate",
    "scaled_plays",
]


def input_rate(v: np.ndarray, dt: float, rate_scale: float, tau: float,
               input_range: float | None = None) -> np.ndarray:
    """Normalised input rate ``rho_f[k]``, low-passed with time constant ``tau``.

    ``rho[k] = |v[k] - v[k-1]| / dt / rate_scale`` (``rho[0] = 0``), then
    ``rho_f[k] = a rho_f[k-1] + (1 - a) rho[k]``, ``a = exp(-dt / tau)``, from ``rho_f[-1] = 0``;
    ``tau = 0``: ``rho_f = rho``, with a one-sample jump above ``STEP_SHARE`` of the input range
    counted as 0 (a sampled step, no rate a play follows).

    Parameters
    ----------
    v : numpy.ndarray
        Input ``v[k]``.
    dt : float
        Sample time [s].
    rate_scale : float
        Input rate [input units / s] that makes ``rho = 1``.
    tau : float
        Time constant of the low-pass [s], ``>= 0``.
    input_range : float, optional
        The range of the step rule (default ``ptp(v)``).

    Returns
    -------
    numpy.ndarray
        ``rho_f[k]`` [-], shape of ``v``; ``rho_f[k]`` depends on ``v[0..k]``.

    Raises
    ------
    ValueError
        A negative or non-finite ``tau``, a non-positive ``rate_scale``.

    Examples
    --------
    >>> v = np.r_[np.linspace(0.0, 0.1, 5), 1.0, 1.0]  # a ramp, then a jump and a hold
    >>> input_rate(v, 1.0, 0.025, 0.0).round(3).tolist()  # the jump is a step: no rate
    [0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0]
    >>> input_rate(v, 1.0, 0.025, 1.0).round(3).tolist()  # a low-pass spreads the jump
    [0.0, 0.632, 0.865, 0.95, 0.982, 23.117, 8.504]
    """
    if not np.isfinite(tau) or tau < 0:
        raise ValueError(f"tau: expected a finite time constant >= 0 [s], got {tau!r}")
    if not rate_scale > 0:
        raise ValueError(f"rate_scale: expected > 0, got {rate_scale!r}")
    dv = np.abs(np.diff(v, prepend=v[0]))
    rho = dv / dt / rate_scale
    if tau == 0:
        span = float(np.ptp(v)) if input_range is None else float(input_range)
        return np.where(dv <= STEP_SHARE * span, rho, 0.0)
    return filtered_rate(rho, tau, dt)


def filtered_rate(rho: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """``rho`` through the first-order low-pass of time constant ``tau > 0`` from rest at 0.

    Parameters
    ----------
    rho : numpy.ndarray
        Rate ``rho[k]``.
    tau : float
        Time constant [s].
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        ``rho_f[k] = a rho_f[k-1] + (1 - a) rho[k]``, ``a = exp(-dt / tau)``.

    Examples
    --------
    >>> filtered_rate(np.array([0.0, 1.0, 1.0]), 1.0, 1.0).round(4).tolist()
    [0.0, 0.6321, 0.8647]
    """
    a = np.exp(-dt / tau)
    return lfilter([1 - a], [1, -a], rho)


def saturated_rate(rho: np.ndarray, saturation: float | None) -> np.ndarray:
    """The filtered rate through the saturating map ``rho / (1 + rho / S)``.

    Parameters
    ----------
    rho : numpy.ndarray
        Filtered rate ``rho_f[k] >= 0`` [-].
    saturation : float or None
        ``S > 0`` [-], the bound the map approaches; None: no saturation (``rho`` returned).

    Returns
    -------
    numpy.ndarray
        ``rho_s[k]`` [-], below ``min(rho_f[k], S)``; sample by sample (no memory).

    Raises
    ------
    ValueError
        A non-positive or non-finite ``saturation``.

    Examples
    --------
    >>> saturated_rate(np.array([0.0, 1.0, 3.0, 100.0]), 1.0).round(3).tolist()
    [0.0, 0.5, 0.75, 0.99]
    """
    if saturation is None:
        return rho
    if not (np.isfinite(saturation) and saturation > 0):
        raise ValueError(f"saturation: expected a finite S > 0 or None, got {saturation!r}")
    return rho / (1.0 + rho / saturation)


def play_bands(n: int, bands: int) -> list[np.ndarray]:
    """Contiguous groups of the ``n`` plays (radii ascending), ``min(bands, n)`` of them.

    Parameters
    ----------
    n : int
        Number of plays.
    bands : int
        Groups wanted.

    Returns
    -------
    list of numpy.ndarray
        Play indices of each group (none when ``bands`` is 0).

    Examples
    --------
    >>> [b.tolist() for b in play_bands(5, 2)]
    [[0, 1, 2], [3, 4]]
    """
    return np.array_split(np.arange(n), min(bands, n)) if bands > 0 else []


class RateBasis:
    """The parts of one record's rate columns that do not depend on the filter (each play's
    contact sign and last contact sample, the band sums of the weighted play outputs);
    :meth:`columns` builds (and keeps) the columns of one family and filter time constant.

    Parameters
    ----------
    Z : numpy.ndarray or None
        Play outputs ``z_i[k]``, shape (N, n); None: computed from ``v`` chunk by chunk
        whenever the columns need them (plays at rest before ``v[0]``: see ``at_rest``), so
        the basis holds no N x n array.
    radii : array_like
        Play radii ``r_i`` [input units], ascending.
    v : numpy.ndarray
        Input ``v[k]``.
    dt : float
        Sample time [s].
    rate_scale : float
        Input rate [input units / s] that makes ``rho = 1``.
    weights : array_like
        Reference play weights ``w0_i`` of the weight columns.
    bands : int
        Bands of plays (one column each).
    input_range : float, optional
        The range of the step rule (default ``ptp(v)``).
    at_rest : bool
        With ``Z`` None: the plays at rest at ``v[0]`` before the first sample (the
        nominal's start, :func:`~pimodel.diagnosis.effects.make_segment`); False (default):
        at 0.
    projection : numpy.ndarray or None
        ``V`` (n, q) when the fits' play columns are ``Z V`` (the diagnosis' compression):
        :meth:`scaled_rows` are then projected the same way; None: the plays as they are.

    Examples
    --------
    >>> v = np.r_[np.linspace(0.0, 1.0, 41), 1.0]  # a ramp at 0.025 per sample, then a hold
    >>> Z = np.maximum(v - 0.5, 0.0)[:, None]  # one play of radius 0.5, pushed from v = 0.5
    >>> basis = RateBasis(Z, [0.5], v, 1.0, 0.025, [1.0], 1)
    >>> (basis.columns(0.0, "radius")[[0, 20, 21, 41], 0].round(6) + 0.0).tolist()  # hold: 0
    [0.0, -0.5, -0.5, 0.0]
    >>> basis.columns(0.0, "weight")[[0, 20, 21, 41], 0].round(6).tolist()
    [0.0, 0.0, 0.025, 0.0]
    """

    _cache = per_thread("cache", dict)
    _weighted = per_thread("weighted", lambda: None)

    def __getstate__(self) -> dict:
        return {k: x for k, x in drop_threads(self.__dict__).items() if k != "_kept"}

    @property
    def _shared(self) -> dict:
        """What a screen's basis keeps for every thread and every fit (:meth:`_keeps`): the
        band sums and the last contacts, each stored whole once built (never half-built),
        dropped by :meth:`forget` only."""
        return self.__dict__.setdefault("_kept", {})

    def _keeps(self) -> bool:
        """Whether the last contacts (12 B per sample and play) fit ``CONTACT_BYTES``: a
        record's screen, not a long record."""
        return self.v.size * self.radii.size * 12 <= CONTACT_BYTES

    def __init__(self, Z: np.ndarray, radii, v: np.ndarray, dt: float, rate_scale: float,
                 weights, bands: int = RATE_BANDS, *, input_range: float | None = None,
                 at_rest: bool = False, projection: np.ndarray | None = None):
        self.Z, self.radii, self.at_rest = Z, np.asarray(radii, float), at_rest
        self.projection = projection
        self.v, self.dt, self.rate_scale, self.input_range = v, dt, rate_scale, input_range
        self.bands = play_bands(self.radii.size, bands)
        self.weights = np.asarray(weights, float)
        self._starts = [int(g[0]) for g in self.bands]
        # memos (per thread, module threads): the band sums of w0_i z_i, built on first use
        # (_weighted); the latest columns (_cache); per chunk, each play's last contact and
        # its sign (_contacts, below)

    def rate(self, tau: float) -> np.ndarray:
        """The filtered rate ``rho_f`` of the record (:func:`input_rate`).

        Parameters
        ----------
        tau : float
            Time constant of the low-pass [s].

        Returns
        -------
        numpy.ndarray
            ``rho_f[k]`` [-].

        Examples
        --------
        >>> v = np.array([0.0, 0.01, 0.02, 0.02])
        >>> basis = RateBasis(v[:, None], [0.0], v, 1.0, 0.01, [1.0])
        >>> basis.rate(0.0).tolist(), basis.rate(1.0).round(3).tolist()  # jumps; low-passed
        ([0.0, 0.0, 0.0, 0.0], [0.0, 0.632, 0.865, 0.318])
        """
        return input_rate(self.v, self.dt, self.rate_scale, tau, self.input_range)

    def columns(self, tau: float, family: str, saturation: float | None = None) -> np.ndarray:
        """The columns of ``family`` for the filter ``tau`` and the saturation ``S`` (memoised).

        Parameters
        ----------
        tau : float
            Time constant of the low-pass [s].
        family : {"radius", "weight"}
            Radii or weights growing with the rate (module docstring).
        saturation : float or None
            ``S`` of :func:`saturated_rate` (None: none).

        Returns
        -------
        numpy.ndarray
            Shape (N, bands), output units per unit gain; row ``k`` depends on ``v[0..k]``.

        Raises
        ------
        ValueError
            An unknown ``family``.

        Examples
        --------
        >>> v = np.array([0.0, 0.01, 0.02, 0.02])
        >>> basis = RateBasis(v[:, None], [0.0], v, 1.0, 0.01, [2.0], 1)
        >>> basis.columns(1.0, "weight").round(4).tolist()  # 2 v rho_f
        [[0.0], [0.0126], [0.0346], [0.0127]]
        """
        if family not in RATE_FAMILIES:
            raise ValueError(f"family: expected one of {RATE_FAMILIES}, got {family!r}")
        key = (float(tau), family, saturation)
        if key not in self._cache:
            rho = saturated_rate(self.rate(key[0]), saturation)
            if family == "weight":
                cols = rho[:, None] * self._band_sums()
            else:
                cols = self._radius_columns(rho)
            self._cache.clear()  # the latest only: a search asks for each filter once
            self._cache[key] = cols
        return self._cache[key]

    def release(self) -> None:
        """Drop this thread's memoised columns (rebuilt on the next use); a screen's band sums
        and last contacts, which no filter changes, stay for the next fit (:meth:`forget`).

        Examples
        --------
        >>> v = np.array([0.0, 0.01, 0.02, 0.02])
        >>> basis = RateBasis(v[:, None], [0.0], v, 1.0, 0.01, [2.0], 1)
        >>> a = basis.columns(1.0, "weight"); basis.release()
        >>> bool(np.array_equal(a, basis.columns(1.0, "weight")))
        True
        """
        self._cache.clear()
        self._weighted = None

    def forget(self) -> None:
        """:meth:`release`, and drop what the basis keeps for every fit and every thread (the
        band sums and last contacts of a screen; the diagnosis, before the whole-record refit).

        Examples
        --------
        >>> v = np.array([0.0, 0.01, 0.02, 0.02])
        >>> basis = RateBasis(v[:, None], [0.0], v, 1.0, 0.01, [2.0], 1)
        >>> a = basis.columns(1.0, "radius"); basis.release(); sorted(basis._shared)
        ['contacts']
        >>> basis.forget(); basis._shared
        {}
        """
        self.release()
        self.__dict__.pop("_kept", None)
        self.__dict__.pop("_threads", None)  # every thread's memos (module threads)

    def _band_sums(self) -> np.ndarray:
        """Band sums ``sum_{i in b} w0_i z_i[k]`` of the nominal plays (built on first use;
        a screen's kept for every fit, :meth:`_keeps`)."""
        kept = self._shared.get("weighted")
        if kept is not None:
            return kept
        if self._weighted is None:
            member = np.zeros((self.radii.size, len(self.bands)))
            for b, g in enumerate(self.bands):
                member[g, b] = self.weights[g]
            weighted = np.empty((self.v.size, member.shape[1]))
            for c, Zc in self._play_chunks():
                weighted[c] = Zc @ member
            if self._keeps():
                self._shared["weighted"] = weighted
                return weighted
            self._weighted = weighted
        return self._weighted

    def scaled_rows(self, tau: float, saturation: float | None, growth: float) -> np.ndarray:
        """The plays of the exact shape as rows (:func:`scaled_plays`, at rest as the nominal's
        plays; memoised, the latest only).

        Parameters
        ----------
        tau, saturation, growth : float
            The filter [s] (> 0), ``S`` (or None) and ``G``.

        Returns
        -------
        numpy.ndarray
            Shape (n, N), or (q, N) with a ``projection``; C-contiguous.

        Examples
        --------
        >>> v = np.r_[np.linspace(0.0, 1.0, 11), np.full(3, 1.0)]
        >>> basis = RateBasis(None, [0.0, 0.2], v, 1.0, 0.1, [1.0, 1.0], at_rest=True)
        >>> basis.scaled_rows(1e-9, None, 0.5)[:, 10].round(6).tolist()  # radius 0.2 -> 0.3
        [1.0, 0.7]
        """
        key = ("scaled", float(tau), saturation, float(growth))
        if key not in self._cache:
            z0 = float(self.v[0]) if self.at_rest else 0.0
            # the plays written as rows when they are the rows (no transpose of N x n)
            Zs = scaled_plays(self.v, self.radii, self.dt, self.rate_scale, tau, saturation,
                              growth, z0, rows=self.projection is None)
            rows = Zs if self.projection is None else transposed(Zs @ self.projection)
            self._cache.clear()
            self._cache[key] = rows
        return self._cache[key]

    def _play_chunks(self):
        """``(slice, Z[slice])`` over the record, the plays computed chunk by chunk (their
        states carried over) when the basis was built without ``Z``."""
        z0 = float(self.v[0]) if self.at_rest else 0.0
        op = None if self.Z is not None else PIOperator(np.ones(self.radii.size), self.radii,
                                                        initial_state=z0)
        state = None
        for c in chunks(self.v.size):
            if op is None:
                yield c, self.Z[c]
            else:
                Zc = op.play_outputs(self.v[c], state=state)
                state = Zc[-1]
                yield c, Zc

    def _radius_columns(self, rho: np.ndarray) -> np.ndarray:
        """Band sums of ``rho_f[last contact of play i] * (-s_i r_i)``, chunk by chunk. The
        last contacts and their signs do not depend on the filter: they are found once per
        basis (:meth:`_contact_chunks`) and kept while they take at most ``CONTACT_BYTES``
        (a record's screen), for every thread and every fit until :meth:`forget`, so a search
        over filters costs a gather and a band sum per point; longer records find them again
        at each call (nothing of size N x n kept)."""
        out = np.empty((self.v.size, len(self.bands)))
        contacts = self._shared.get("contacts")
        if contacts is None:
            contacts = self._contact_chunks()
            if self._keeps():
                contacts = list(contacts)
                self._shared["contacts"] = contacts
        for c, last, signed in contacts:
            per_play = np.take(rho, last)
            per_play *= signed
            out[c] = np.add.reduceat(per_play, self._starts, axis=1)
        return out

    def _contact_chunks(self):
        """``(slice, last, signed)`` per chunk: each play's last contact sample up to each
        sample (0 before its first; ``int32``) and ``-gap`` there (``-(-s_i r_i)``, 0 before
        the first contact), the last contact and its sign carried from chunk to chunk."""
        r, v = self.radii, self.v
        last_prev = np.full(r.size, -1, dtype=np.int64)
        signed_prev = np.zeros(r.size)
        for c, Zc in self._play_chunks():
            gap = v[c, None] - Zc  # +-r_i while play i is in contact
            contact = np.abs(gap) >= r * (1 - 1e-9)
            contact &= r > 0
            k = np.arange(gap.shape[0], dtype=np.int64)[:, None]
            local = np.maximum.accumulate(np.where(contact, k, -1), axis=0)
            inside = local >= 0
            signed = np.where(inside, -np.take_along_axis(gap, np.maximum(local, 0), axis=0),
                              signed_prev)  # -(-s_i r_i) at the last contact
            last = np.where(inside, local + c.start, last_prev)
            yield c, np.maximum(last, 0).astype(np.int32), signed
            last_prev, signed_prev = last[-1], signed[-1]


def scaled_plays(v: np.ndarray, radii, dt: float, rate_scale: float, tau: float,
                 saturation: float | None, growth: float, z0: float = 0.0, *,
                 rows: bool = False) -> np.ndarray:
    """Outputs ``zs_i[k]`` of plays whose radii scale with the rate (the exact shape).

    ``zs_i[k] = min(max(zs_i[k-1], v[k] - rho_i[k]), v[k] + rho_i[k])``, ``zs_i[-1] = z0``,
    ``rho_i[k] = r_i (1 + G s[k] / (1 + s[k] / S))``, ``s[k]`` the strictly causal filtered
    rate of the module docstring (``s[0] = s[1] = 0``); run by the C core
    (``pim_rdpi_sat_plays``: the plays of ``pim_rdpi_sat_run``, as
    :mod:`pimodel.operators.rate_dependent`, all on the one rate in one pass).

    Parameters
    ----------
    v : numpy.ndarray
        Input ``v[k]``.
    radii : array_like
        Play radii ``r_i`` [input units].
    dt : float
        Sample time [s].
    rate_scale : float
        Input rate [input units / s] that makes ``s = 1``.
    tau : float
        Time constant of the rate's low-pass [s], ``> 0``.
    saturation : float or None
        ``S`` [-] (None: ``g = G s``).
    growth : float
        ``G`` [-].
    z0 : float
        Play states before ``v[0]``.
    rows : bool
        Return the plays as rows, shape (n, N), written so by the C core (the same values as
        the transpose of the default, without the copy).

    Returns
    -------
    numpy.ndarray
        Shape (N, n) (``rows``: (n, N)); sample ``k`` depends on ``v[0..k]``.

    Raises
    ------
    ValueError
        ``tau`` not finite and > 0, ``rate_scale`` not > 0, ``saturation`` not None or > 0,
        ``growth`` not finite.

    Examples
    --------
    >>> v = np.r_[np.linspace(0.0, 1.0, 11), np.full(3, 1.0)]  # a ramp at 0.1/s, then a hold
    >>> zs = scaled_plays(v, [0.2], 1.0, 0.1, 1e-9, None, 0.5)
    >>> round(float(v[10] - zs[10, 0]), 6)  # the radius grew by G s = 0.5 at the rate 1
    0.3
    """
    if not (np.isfinite(tau) and tau > 0):
        raise ValueError(f"tau: the {SCALED!r} family needs a finite time constant > 0 [s], "
                         f"got {tau!r}")
    if not rate_scale > 0:
        raise ValueError(f"rate_scale: expected > 0, got {rate_scale!r}")
    if not np.isfinite(growth):
        raise ValueError(f"growth: expected a finite G, got {growth!r}")
    saturated_rate(np.zeros(1), saturation)  # checks S
    v = np.ascontiguousarray(v, float)
    r = np.asarray(radii, float)
    lam = float(np.exp(-dt / tau))
    sat = 0.0 if saturation is None else saturation * rate_scale
    return _native.rdpi_sat_plays(np.ascontiguousarray(r), growth / rate_scale, sat, lam, dt,
                                  np.full(r.size, z0), np.array([v[0], 0.0]), v, rows=rows)


def rate_columns(Z: np.ndarray, radii, v: np.ndarray, dt: float, rate_scale: float, weights,
                 tau: float, family: str, bands: int = RATE_BANDS, *,
                 input_range: float | None = None,
                 saturation: float | None = None) -> np.ndarray:
    """The rate candidate's columns of one record (module docstring), for one family and filter.

    Parameters
    ----------
    Z : numpy.ndarray
        Play outputs ``z_i[k]``, shape (N, n).
    radii : array_like
        Play radii ``r_i`` [input units], ascending.
    v : numpy.ndarray
        Input ``v[k]``.
    dt : float
        Sample time [s].
    rate_scale : float
        Input rate [input units / s] that makes ``rho = 1``.
    weights : array_like
        Reference play weights ``w0_i`` (the weight family).
    tau : float
        Time constant of the rate's low-pass [s] (0: none).
    family : {"radius", "weight"}
        Radii or weights growing with the rate.
    bands : int
        Bands of plays (one column each).
    input_range : float, optional
        The range of the step rule (default ``ptp(v)``).
    saturation : float or None
        ``S`` of :func:`saturated_rate` (None: none).

    Returns
    -------
    numpy.ndarray
        Shape (N, min(bands, n)); row ``k`` depends on ``v[0..k]``.

    Examples
    --------
    >>> v = np.r_[np.linspace(0.0, 1.0, 41), np.linspace(0.975, 0.0, 40)]  # up and down
    >>> Z = np.minimum(np.maximum(v - 0.5, 0.0), 0.5)[:, None]  # a play of radius 0.5
    >>> R = rate_columns(Z, [0.5], v, 1.0, 0.025, [1.0], 0.0, "radius", 1)
    >>> R[[10, 20, 40, 41, 80], 0].round(6).tolist()  # no contact yet, contact, then held
    [0.0, -0.5, -0.5, -0.5, -0.5]
    """
    return RateBasis(Z, radii, v, dt, rate_scale, weights, bands,
                     input_range=input_range).columns(tau, family, saturation)


def rate_params(p: dict) -> tuple[np.ndarray, str, float]:
    """Gains, family and filter time constant [s] of a model's rate effect.

    Parameters
    ----------
    p : dict
        The model's ``params`` (``rate_gains``, ``rate_family``, ``rate_time_constant_s``).

    Returns
    -------
    (numpy.ndarray, str, float)

    Raises
    ------
    ValueError
        A missing key (named), an unknown family, or the rate parameters of an earlier version
        (``rate_band_gains``).

    Examples
    --------
    >>> rate_params({"rate_gains": [0.1], "rate_family": "weight", "rate_time_constant_s": 0.0})
    (array([0.1]), 'weight', 0.0)
    """
    if "rate_band_gains" in p:
        raise ValueError("params: 'rate_band_gains' is the rate effect of an earlier version "
                         "(radii growing with the unfiltered rate, pushed plays); diagnose the "
                         "records again for 'rate_gains', 'rate_family' and "
                         "'rate_time_constant_s'")
    missing = [k for k in ("rate_gains", "rate_family", "rate_time_constant_s") if k not in p]
    if missing:
        raise ValueError(f"params: the rate effect needs {missing}")
    if p["rate_family"] not in (*RATE_FAMILIES, SCALED):
        raise ValueError(f"params: rate_family expected one of {(*RATE_FAMILIES, SCALED)}, "
                         f"got {p['rate_family']!r}")
    return (np.asarray(p["rate_gains"], float), str(p["rate_family"]),
            float(p["rate_time_constant_s"]))


def rate_saturation(p: dict) -> float | None:
    """The saturation ``S`` of a model's rate effect (:func:`saturated_rate`); None when the
    params have none (``rate_saturation`` absent or None: the linear map of earlier versions).

    Parameters
    ----------
    p : dict
        The model's ``params``.

    Returns
    -------
    float or None

    Raises
    ------
    ValueError
        ``rate_saturation`` neither None nor a finite number > 0.

    Examples
    --------
    >>> rate_saturation({"rate_saturation": 2.0}), rate_saturation({})
    (2.0, None)
    """
    s = p.get("rate_saturation")
    if s is None:
        return None
    if not (isinstance(s, (int, float)) and np.isfinite(s) and s > 0):
        raise ValueError(f"params: rate_saturation expected None or a finite number > 0, got "
                         f"{s!r}")
    return float(s)


def rate_growth(p: dict) -> float | None:
    """The growth ``G`` of a model's ``"scaled"`` rate shape; None for the first-order families.

    Parameters
    ----------
    p : dict
        The model's ``params``.

    Returns
    -------
    float or None

    Raises
    ------
    ValueError
        The ``"scaled"`` family without a finite ``rate_growth``.

    Examples
    --------
    >>> rate_growth({"rate_family": "scaled", "rate_growth": 0.4})
    0.4
    """
    if p.get("rate_family") != SCALED:
        return None
    g = p.get("rate_growth")
    if not (isinstance(g, (int, float)) and np.isfinite(g)):
        raise ValueError(f"params: rate_family 'scaled' needs a finite rate_growth, got {g!r}")
    return float(g)


def rate_shapes(effects, fixed: dict) -> list[dict]:
    """The rate shapes a diagnosis scores on validate (by BIC) whenever ``effects`` hold a rate
    not yet fitted: the first-order form and the exact one (``{"rate_shape": "scaled"}``);
    ``[{}]`` without a rate, with its parameters held in ``fixed`` (from earlier rounds) or
    beside dynamics or a delay.

    Parameters
    ----------
    effects : tuple of str
        The effects of the model being fitted.
    fixed : dict
        Grid parameters held from earlier rounds.

    Returns
    -------
    list of dict

    Examples
    --------
    >>> rate_shapes(("rate",), {})
    [{}, {'rate_shape': 'scaled'}]
    >>> rate_shapes(("creep", "rate"), {"rate_tau": 0.01}), rate_shapes(("creep",), {})
    ([{}], [{}])
    """
    if "rate" not in effects or "rate_tau" in fixed or {"dynamics", "delay"} & set(effects):
        return [{}]
    return [{}, {"rate_shape": SCALED}]
