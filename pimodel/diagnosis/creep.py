"""The creep candidate's lag grid and the creep law it is reported as.

The diagnosis fits creep as lags of the reference hysteresis output ``h0`` (:mod:`.effects`)::

    y[k] = ... + sum_i g_i (L_i[k] - h0[k]),   L_i[k] = a_i L_i[k-1] + (1 - a_i) h0[k],
    a_i = exp(-dt / tau_i)

so a step of ``h0`` by ``D`` at ``t = 0`` gives ``D (1 - sum_i g_i exp(-t / tau_i))``: at once
``(1 - sum g) D``, then creeping to ``D``. The lags' time constants follow the records: one
per decade, on the decades ``3 10^j`` s, from the first at least ``MIN_LAG_SAMPLES`` sample
times to the last at most ``LONGEST_LAG`` times the longest train record (and at least one).

Why the last lag is bounded by the record: a lag much longer than the record settles little
within it, so over the record its column ``L_i - h0`` is ``h0[0] - h0[k]`` plus a near-linear
ramp in time. The first part lies in the span of the play weights and the offset on every
record, and the lag's state at rest at ``h0[0]`` then carries ``g_i h0[0]`` into each record: a
level that follows the record's first output. Its gain is pinned only by the ramp (what a
drift's trend fits), and the extrapolation to a validate record that starts elsewhere is a
level error a drift with a level per record takes up (issue 28: on 1 s multisine records of a
stage with a 50 ms creep behind a delay, lags up to 3 s left the creep candidate alone worse
than the nominal on validate in 5 of 10 seeds, and the verdict named `drift` in 8 and `rate` in
4; with lags up to 0.3 s the creep alone leaves 6-40 % of the gap, comes first in 10 of 10, and
`drift` is named in 3, `rate` in none: docs/diagnosis.md). A lag of at most twice the record
shows at least ``1 - exp(-1/2)`` (39 %) of its settling within it. Before, the last lag was the
first at least half the record (0.5 to 5 times it: 3 s on those 1 s records); the first at
least the record itself, 300 s on a 40 s record, had taken the place of a drift and left no
creep law. On the existing generators' records (10 kHz over 3 s; 5 kHz over 1.7 s; 2 kHz over 5
s) the grid is the one before this rule (3 ms to 3 s; 30 ms to 3 s); on a 200 Hz record of 100
s it is 0.3 s to 30 s, on 5 kHz records of 1 s 3 ms to 0.3 s.

Where the lags start (``creep_start``, a variant of the creep scored on validate by BIC where
the creep enters a combination, then held for the fits built on it: :func:`creep_starts`).
``"rest"``: each lag at rest at the record's first reference output, ``L_i[-1] = h0[0]`` (the
stage sat at the record's first input before it).
``"common"``: each lag at rest at one level ``s_i`` shared by every record, ``L_i[-1] = s_i``
(a piezo stage parked at one voltage between records: its lags rest where it rested, then
settle from the step to the record's first input through the record). Since
``L_i[s_i] = L_i[0] + s_i a_i^(k+1)`` (the lag from 0 plus its free response), the common start
is linear in ``g_i`` and ``g_i s_i``: the columns ``L_i[0] - h0`` (the lag at rest at 0) and
``a_i^(k+1) = exp(-(k + 1) dt / tau_i)`` (:func:`start_columns`, restarting with each record),
one coefficient each shared by the records, ``2 n_lags`` parameters in the BIC; validate gets
the same starts, so nothing is fitted on it. The report gives ``creep_start_levels``, the
``s_i`` (output unit), and the exported model starts its lags there (issue 28: on the blind
generator parked as its docstring says, drift50 measured 11 of 15 creep cases right against 5
of 15, a spurious `drift` in 2 against 5; docs/notes/creep60.md).
``"record"``: the creep counted from each record's start (a stage whose creep restarts with
each record, as a generator that writes creep as lags of ``h - h[0]`` makes it: each record's
first output is un-crept). The lags start as at rest (``L_i[-1] = h0[0]``) and the term is
``g_i (L_i[k] - h0[k] - L_i[-1])``, the rest start less ``sum_i g_i h0[0]``: the level the
resolved lags predict. The creep faster than the first lag (and any error of ``sum g``) leaves
a further level per record that no lag carries, so the start has **a level per record**, as a
drift's ``"levels"`` (:mod:`.drift`): one column per train record after the first, and on a
validate record its level measured out of fold (one parameter each in the validate BIC;
:func:`creep_levels`), **bounded** by ``RECORD_LEVEL_SHARE`` (10 %) of the change of the first
reference output from the first train record's, ``|h0[0] - h0_train[0]|``: the level of a creep
counted from the record's start follows where the record starts, so a record that starts where
train started gets none (a drift's level, on the shared clock, moves regardless: on the blind
generator's thermal drifts behind a mode, an unbounded level let the creep take the drift's place
in 2 of 2 such cases; the 10 % is creep faster than the first lag, a few per cent per
decade). Beside a drift that has its own levels they are the same columns and the creep adds
none. Measured (issue 28): on the blind generator at half length (creep alone,
1 kHz, offset sines and multisines, 8 seeds drawn) `creep` alone in 7 of 8, against 0 of 8
(`drift` beside it) with the rest and common starts; with the predicted level alone (no
level per record) in 1 of 5: ``sum g`` from one train record's dynamics is not precise enough
for a record that starts tens of volts away (the level is ``sum g`` times the difference of the
first outputs).
"""

from __future__ import annotations

import math

import numpy as np

from .drift import has_levels, out_of_fold_level

__all__ = ["CREEP_STARTS", "RECORD_LEVEL_SHARE", "START_SEEN", "creep_law", "creep_levels",
           "creep_start_levels", "creep_starts", "creep_time_constants", "first_scored",
           "record_level", "start_columns", "start_hint"]

CREEP_STARTS = ("rest", "common", "record")  # where the lags start (module docstring)
MIN_LAG_SAMPLES = 10  # the shortest lag spans at least this many samples
DECADE_ANCHOR = 3.0  # lags at DECADE_ANCHOR 10^j s
RECORD_LEVEL_SHARE = 0.1  # "record": a validate level at most this share of h0[0]'s change
LONGEST_LAG = 2.0  # the last lag is the last at most this many times the longest train record
START_SEEN = 1e-8  # a common start's column smaller at the first scored sample is zero


def creep_time_constants(dt: float, duration: float) -> tuple[float, ...]:
    """The creep lags' time constants for records of sample time ``dt`` and length
    ``duration`` (module docstring).

    Parameters
    ----------
    dt : float
        Sample time [s], ``> 0``.
    duration : float
        The longest train record [s], ``>= 0``.

    Returns
    -------
    tuple of float
        ``3 10^j`` [s], ascending, from the first ``>= MIN_LAG_SAMPLES dt`` to the last
        ``<= LONGEST_LAG duration`` (at least one).

    Raises
    ------
    ValueError
        ``dt`` not finite and positive, or ``duration`` not finite and non-negative.

    Examples
    --------
    >>> creep_time_constants(1e-4, 3.0)
    (0.003, 0.03, 0.3, 3.0)
    >>> creep_time_constants(5e-3, 100.0)
    (0.3, 3.0, 30.0)
    >>> creep_time_constants(2e-4, 1.0)  # 5 kHz, 1 s: a lag of 3 s would settle 28 % in it
    (0.003, 0.03, 0.3)
    """
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt: expected a finite sample time > 0, got {dt!r}")
    if not (math.isfinite(duration) and duration >= 0):
        raise ValueError(f"duration: expected a finite length >= 0 s, got {duration!r}")
    j0 = math.ceil(math.log10(MIN_LAG_SAMPLES * dt / DECADE_ANCHOR) - 1e-9)
    j1 = max(math.floor(math.log10(max(LONGEST_LAG * duration, 1e-300) / DECADE_ANCHOR)
                        + 1e-9), j0)
    return tuple(float(f"{DECADE_ANCHOR * 10.0 ** j:.12g}") for j in range(j0, j1 + 1))


def creep_law(gains, time_constants) -> dict:
    """The fitted lags as a creep law a piezo engineer reads.

    With the step response ``s(t) = 1 - sum_i g_i exp(-t / tau_i)`` (module docstring; ``s(0+)
    = 1 - sum g`` the part that follows at once): the creep per decade of time is the
    least-squares slope of ``s(t) / s(t_1)`` against ``log10(t / t_1)`` over the lags' span
    ``t_1 = tau_1 .. tau_n`` (the law ``y(t) = y(t_1) (1 + gamma log10(t / t_1))``), and each
    lag's share is ``g_i / (1 - sum g)`` of the immediate response.

    Parameters
    ----------
    gains : array_like
        ``g_i`` of the lags.
    time_constants : array_like
        ``tau_i`` [s], as many, ascending.

    Returns
    -------
    dict
        ``percent_per_decade`` (gamma [%]), ``total_percent`` (the creep after the step,
        ``100 sum g / (1 - sum g)`` [% of the immediate response]), ``time_constants_s`` and
        ``lag_percent`` (per lag, ``100 g_i / (1 - sum g)``), ``span_s`` (the time range the
        law describes).

    Raises
    ------
    ValueError
        Gains and time constants of different lengths, or ``sum g >= 1`` (no immediate
        response: not a creep).

    Examples
    --------
    >>> law = creep_law([0.01, 0.01, 0.01], [0.01, 0.1, 1.0])
    >>> round(law["percent_per_decade"], 2), round(law["total_percent"], 2)
    (0.97, 3.09)
    """
    g = np.asarray(gains, float)
    tau = np.asarray(time_constants, float)
    if g.shape != tau.shape or g.ndim != 1 or g.size == 0:
        raise ValueError(f"gains: expected one gain per time constant ({tau.size}), got "
                         f"{g.shape}")
    total = float(np.sum(g))
    if not total < 1.0:
        raise ValueError(f"gains: their sum {total:.4g} is >= 1: no immediate response")
    t = np.geomspace(tau[0], tau[-1], 50) if tau[-1] > tau[0] else tau[:1] * np.array([1, 10])
    s = 1.0 - np.exp(-t[:, None] / tau[None, :]) @ g
    x = np.log10(t / t[0])
    slope = float(np.polyfit(x, s / s[0], 1)[0])
    return {"percent_per_decade": 100.0 * slope,
            "total_percent": 100.0 * total / (1.0 - total),
            "time_constants_s": tau.tolist(),
            "lag_percent": (100.0 * g / (1.0 - total)).tolist(),
            "span_s": [float(t[0]), float(t[-1])]}


def creep_starts(effects, held: str | None = None, n_validate: int = 1) -> list[dict]:
    """The creep's starts a diagnosis scores on validate (by BIC) when ``effects`` hold a
    creep: each lag at rest at the record's first output, at a level shared by the records, or
    at rest with the creep counted from the record's start (module docstring). All are scored
    where the creep enters a combination (the candidate alone, a pair, the creep added beside
    chosen effects) and where the lag beside it is searched again; another fit built on a
    model that holds a creep keeps that creep's start (``held``, :func:`start_hint`), so the
    start is not chosen anew for every combination.

    Parameters
    ----------
    effects : tuple of str
        The effects of the model being fitted.
    held : str or None
        The start held (one of ``CREEP_STARTS``: that of the creep already chosen); None:
        all.
    n_validate : int
        Validate records: the levels of the start ``"record"`` (``creep_levels``).

    Returns
    -------
    list of dict
        ``[{}]`` without a creep, else ``{"creep_start": s}`` for ``s`` of ``CREEP_STARTS``
        (only ``held`` when given), with ``creep_levels`` for ``"record"``.

    Examples
    --------
    >>> creep_starts(("drift",))
    [{}]
    >>> creep_starts(("creep", "delay"), n_validate=2)  # doctest: +NORMALIZE_WHITESPACE
    [{'creep_start': 'rest'}, {'creep_start': 'common'},
     {'creep_start': 'record', 'creep_levels': 2}]
    >>> creep_starts(("creep", "delay"), held="common")
    [{'creep_start': 'common'}]
    """
    if "creep" not in effects:
        return [{}]
    if held is not None and held not in CREEP_STARTS:
        raise ValueError(f"held: expected one of {CREEP_STARTS} or None, got {held!r}")
    return [{"creep_start": s, **({"creep_levels": n_validate} if s == "record" else {})}
            for s in ((held,) if held is not None else CREEP_STARTS)]


def creep_levels(effects, p: dict) -> int:
    """The levels a creep counted from each record's start adds on validate (module docstring):
    one per validate record (``p["creep_levels"]``), none for the other starts, without a
    creep, or beside a drift that has its own levels (they are the same columns).

    Parameters
    ----------
    effects : tuple of str
        The effects of the model.
    p : dict
        Its grid parameters (``creep_start``, ``creep_levels``; a drift's ``clock`` and
        ``levels``).

    Returns
    -------
    int

    Examples
    --------
    >>> creep_levels(("creep",), {"creep_start": "record", "creep_levels": 2})
    2
    >>> creep_levels(("creep", "drift"), {"creep_start": "record", "creep_levels": 1,
    ...                                   "clock": "levels", "levels": 1})
    0
    """
    if "creep" not in effects or p.get("creep_start") != "record":
        return 0
    if "drift" in effects and has_levels(p):
        return 0
    return int(p.get("creep_levels", 0))


def record_level(params: dict, h0_first: float, residual: np.ndarray,
                 used=None) -> np.ndarray:
    """The level of a record under a creep counted from each record's start (module
    docstring): the residual's level out of fold (:func:`.drift.out_of_fold_level`),
    bounded by ``RECORD_LEVEL_SHARE`` of ``|h0_first - params["creep_record_reference"]|``.

    Parameters
    ----------
    params : dict
        The model's parameters, with ``creep_record_reference`` (the first train record's
        first reference output, output unit).
    h0_first : float
        The record's first reference output ``h0[0]`` (output unit).
    residual : numpy.ndarray
        Measured output minus the model without the level (output unit).
    used : numpy.ndarray or None
        Boolean mask of the scored samples (None: every sample, as a model's ``simulate``).

    Returns
    -------
    numpy.ndarray
        The level at each sample (output unit).

    Examples
    --------
    >>> p = {"creep_record_reference": 1.0}
    >>> record_level(p, 3.0, np.full(4, 0.5)).tolist()  # bounded by 0.1 * |3 - 1|
    [0.2, 0.2, 0.2, 0.2]
    >>> record_level(p, 1.0, np.full(4, 0.5)).tolist()  # a record that starts where train did
    [0.0, 0.0, 0.0, 0.0]
    """
    bound = RECORD_LEVEL_SHARE * abs(float(h0_first) - float(params["creep_record_reference"]))
    return np.clip(out_of_fold_level(np.asarray(residual, float), used), -bound, bound)


def start_hint(grid: dict) -> str:
    """The start of the creep of a fitted model, held for the fits built on it:
    ``"common"`` or ``"record"`` when its grid says so, else ``"rest"`` (a fit at rest leaves
    the grid without the key, as before the other starts).

    Parameters
    ----------
    grid : dict
        The grid parameters of a model that holds a creep (``Model.grid``).

    Returns
    -------
    str
        One of ``CREEP_STARTS``.

    Examples
    --------
    >>> start_hint({}), start_hint({"creep_start": "common"}), start_hint({"creep_start": "record"})
    ('rest', 'common', 'record')
    """
    return grid.get("creep_start", CREEP_STARTS[0])


def first_scored(mask: np.ndarray | None) -> int | None:
    """The first sample a start-up ``mask`` scores (``True``: scored); ``None`` without a
    mask (every sample scored)."""
    return None if mask is None or not mask.any() else int(np.argmax(mask))


def start_columns(samples, dt: float, taus, scored_from: int | None = None) -> np.ndarray:
    """The common start's columns ``a_i^(k+1) = exp(-(k + 1) dt / tau_i)``: the free response
    of each lag from a unit state before the record's first sample (module docstring).

    A lag whose free response has fallen below ``START_SEEN`` (``1e-8``) by the sample
    ``scored_from`` (the first a start-up mask scores, :func:`first_scored`) gets a column of
    zeros: the scored samples inform no level for it, and a least-squares fit of its column
    (scaled to unit norm on the scored samples) gave it a coefficient that grew the masked
    start-up's output past ``1e150`` (issue 28, the blind generator's asymmetry + creep: a lag
    of 3 ms behind a start-up mask of 0.32 s, ``e^-106``). Its level is then ``0``
    (:func:`creep_start_levels`).

    Parameters
    ----------
    samples : array_like of int
        The sample indices ``k`` within the record (``0`` its first sample; a chunk of a
        streamed record gives its own indices, with the same values as the whole record's).
    dt : float
        Sample time [s].
    taus : sequence of float
        The lags' time constants ``tau_i`` [s].
    scored_from : int, optional
        The record's first scored sample (a start-up mask); ``None``: the first.

    Returns
    -------
    numpy.ndarray
        Shape ``(len(taus), len(samples))``, dimensionless.

    Examples
    --------
    >>> start_columns(np.arange(3), 1e-3, [1e-3]).round(4).tolist()
    [[0.3679, 0.1353, 0.0498]]
    """
    k = np.asarray(samples)
    out = np.array([np.exp(-(k + 1) * dt / tau) for tau in taus]).reshape(len(taus), k.size)
    if scored_from is not None:
        seen = np.exp(-(scored_from + 1) * dt / np.asarray(taus, float)) >= START_SEEN
        out[~seen] = 0.0
    return out


def creep_start_levels(params: dict) -> np.ndarray | None:
    """The creep lags' common rest levels of a model's ``params`` (module docstring), or None
    when the lags start at rest at each record's first output (``creep_start`` absent,
    ``"rest"`` or ``"record"``).

    Parameters
    ----------
    params : dict
        :attr:`pimodel.diagnosis.model.DiagnosedModel.params`.

    Returns
    -------
    numpy.ndarray or None
        ``s_i`` [output unit], one per lag.

    Raises
    ------
    ValueError
        ``creep_start`` not one of ``CREEP_STARTS``, or levels that are not one
        finite value per lag.

    Examples
    --------
    >>> creep_start_levels({"creep_lag_gains": [0.1], "creep_time_constants_s": [0.3]}) is None
    True
    >>> creep_start_levels({"creep_lag_gains": [0.1], "creep_time_constants_s": [0.3],
    ...                     "creep_start": "common", "creep_start_levels": [2.5]}).tolist()
    [2.5]
    """
    start = params.get("creep_start", "rest")
    if start not in CREEP_STARTS:
        raise ValueError(f"params: creep_start: expected one of {CREEP_STARTS}, got {start!r}")
    if start != "common":
        return None
    levels = np.asarray(params.get("creep_start_levels", ()), float)
    n = len(params.get("creep_lag_gains", ()))
    if levels.shape != (n,) or not np.all(np.isfinite(levels)):
        raise ValueError(f"params: creep_start_levels: expected {n} finite values (one per "
                         f"creep lag) for creep_start 'common', got {levels.tolist()}")
    return levels
