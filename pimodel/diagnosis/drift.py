"""The ``drift`` candidate: a linear trend on the records' clock, levels that differ from
record to record, or a settling on the clock the records share.

Discrete-time form, with ``t[k]`` the time of sample ``k`` of a record [s] as given (the
records may share one clock) and ``t[0]`` its first sample; the term is added to the model
output ``y[k]`` [output units]:

``"record"``
    ``s (t[k] - t[0])``: a trend that restarts with each record; one offset for all records
    (the nominal's).
``"absolute"``
    ``s t[k]``: a trend on the clock the records share; one offset for all records.
``"levels"``
    ``s (t[k] - t[0]) + c_j``: the trend plus a level ``c_j`` of each record ``j`` (a sensor
    zeroed anew, a thermal offset, or a drift on a clock the records do not show). With a level
    per record, a trend on the shared clock and one that restarts with each record differ only
    by these levels, so one variant covers both and the levels say which clock they follow.
``"settle"``
    ``D (1 - exp(-(t[k] - t_s) / T))``: a slow settling (thermal, after switch-on) on the clock
    the records share; one offset for all records. ``t_s`` is the first time of the train
    records, so ``D`` is how far the output still moves from there on. Linear in ``D`` given
    ``T``; ``T`` is searched on a geometric grid that follows the train records' span on the
    shared clock (:func:`settle_grid`), then continuously. It depends on ``t`` only, not on the
    input history, which tells it from creep (that follows the input; docs/diagnosis.md gives
    the measured limits).
    It is scored twice: with one offset for all records (``drift_variant == "settle"``: the
    validate records' level extrapolated from train), and with a level per record as
    ``"levels"`` (``"settle_levels"``: a settling seen only in part on train leaves ``D`` and
    ``T`` uncertain, and the level they extrapolate to a later record with it).

The levels of the train records are fitted jointly with everything else (one indicator column
per train record after the first). A validate record's level cannot come from train; it is a
nuisance measured on the record itself **out of fold**: the record's scored samples are cut
into ``LEVEL_FOLDS`` contiguous blocks and every sample of block ``b`` gets the mean residual
(measured output minus the model without the level) of the *other* blocks. No validate sample
is predicted with a level computed from its own block, so the level cannot follow the noise or
a local gap, only a constant that holds over the record; every other parameter still comes
from train. The validate BIC counts one parameter per validate record for the levels.
"""

from __future__ import annotations

import numpy as np

DRIFT_VARIANTS = ("record", "absolute", "levels", "settle")
DRIFT_KEYS = ("clock", "levels", "settle_tau", "settle_t0")  # a drift variant's grid parameters
LEVEL_FOLDS = 4  # contiguous blocks of a validate record for its out-of-fold level
SETTLE_SPAN = (1 / 20, 4.0)  # settle grid: T from span/20 to 4 span (span: train, shared clock)
SETTLE_POINTS = 12  # geometric grid points of T

__all__ = [
    "DRIFT_KEYS",
    "DRIFT_VARIANTS",
    "LEVEL_FOLDS",
    "describe_levels",
    "drift_columns",
    "drift_k",
    "drift_term",
    "drift_variants",
    "has_levels",
    "level_report",
    "level_rows",
    "out_of_fold_level",
    "record_levels",
    "settle_bow",
    "settle_grid",
    "settle_start",
]


def drift_variants(effects, n_validate: int) -> list[dict]:
    """The drift variants to score on validate whenever ``effects`` hold a drift. A level per
    validate record cannot be chosen on train, and the variant that fits best changes as other
    effects join (a trend fitted beside an unmodelled asymmetry takes part of it), so the
    variant is chosen anew for every combination, never carried over from an earlier round.

    Parameters
    ----------
    effects : tuple of str
        The effects of the model being fitted.
    n_validate : int
        Number of validate records (one level each for ``"levels"``).

    Returns
    -------
    list of dict
        ``[{}]`` without a drift, else one dict per variant (``clock``, and ``levels`` for
        ``"levels"``).

    Examples
    --------
    >>> drift_variants(("creep",), 1)
    [{}]
    >>> [v["clock"] for v in drift_variants(("creep", "drift"), 1)]
    ['record', 'absolute', 'levels', 'settle', 'settle']
    """
    if "drift" not in effects:
        return [{}]
    return [{"clock": c, **({"levels": n_validate} if c == "levels" else {})}
            for c in DRIFT_VARIANTS] + [{"clock": "settle", "levels": n_validate}]


def drift_k(p: dict) -> int:
    """Parameters the drift adds on validate: the slope, plus one level per validate record for
    the variants with levels (``p["levels"]``); ``D`` and ``T`` instead of the slope for
    ``"settle"``.

    Parameters
    ----------
    p : dict
        The variant: ``clock`` (one of ``DRIFT_VARIANTS``) and, for ``"levels"``, ``levels``
        (number of validate records).

    Returns
    -------
    int

    Examples
    --------
    >>> drift_k({"clock": "record"}), drift_k({"clock": "levels", "levels": 2})
    (1, 3)
    >>> drift_k({"clock": "settle"}), drift_k({"clock": "settle", "levels": 1})
    (2, 3)
    """
    return (2 if p.get("clock") == "settle" else 1) + int(p.get("levels", 0))


def has_levels(p: dict) -> bool:
    """Whether the variant ``p`` has a level per record (``"levels"``, or ``p["levels"]``).

    Parameters
    ----------
    p : dict
        A drift variant (``clock``, and ``levels`` when it has levels).

    Returns
    -------
    bool

    Examples
    --------
    >>> has_levels({"clock": "levels"}), has_levels({"clock": "settle", "levels": 2})
    (True, True)
    """
    return p.get("clock") == "levels" or "levels" in p


def settle_start(segments) -> float:
    """``t_s`` of a settling: the first time of the records (train) on the shared clock [s].

    Parameters
    ----------
    segments : list
        The records, each with its time ``t`` [s].

    Returns
    -------
    float

    Examples
    --------
    >>> from types import SimpleNamespace as S
    >>> settle_start([S(t=np.array([3.0, 4.0])), S(t=np.array([1.0, 2.0]))])
    1.0
    """
    return float(min(s.t[0] for s in segments))


def settle_grid(segments) -> np.ndarray:
    """The grid of the settling time constant ``T`` [s]: ``SETTLE_POINTS`` geometric points
    from ``SETTLE_SPAN[0]`` to ``SETTLE_SPAN[1]`` times the span of the records on the shared
    clock (last time minus :func:`settle_start`), so it follows the records, not a fixed scale.

    Parameters
    ----------
    segments : list
        The (train) records, each with its time ``t`` [s].

    Returns
    -------
    numpy.ndarray
        Increasing time constants [s].

    Raises
    ------
    ValueError
        The records span no time.

    Examples
    --------
    >>> from types import SimpleNamespace as S
    >>> g = settle_grid([S(t=np.linspace(0.0, 10.0, 5)), S(t=np.linspace(15.0, 20.0, 5))])
    >>> float(g[0]), float(g[-1])
    (1.0, 80.0)
    """
    span = float(max(s.t[-1] for s in segments)) - settle_start(segments)
    if not span > 0:
        raise ValueError(f"segments: expected records spanning some time, got span {span}")
    return np.geomspace(SETTLE_SPAN[0] * span, SETTLE_SPAN[1] * span, SETTLE_POINTS)


def settle_column(t: np.ndarray, tau: float, t0: float) -> np.ndarray:
    """The settling's regressor ``1 - exp(-(t[k] - t0) / tau)`` (as ``-expm1``, the C core's
    form).

    Parameters
    ----------
    t : numpy.ndarray
        Time ``t[k]`` [s].
    tau, t0 : float
        Time constant ``T`` (> 0) and start ``t_s`` [s].

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> settle_column(np.array([1.0, 2.0]), 1.0, 1.0).round(4).tolist()
    [0.0, 0.6321]
    """
    return -np.expm1(-(t - t0) / tau)


def settle_bow(times: list[np.ndarray], tau: float, t0: float, points: int = 4096) -> float:
    """How far a unit settling departs from a straight line over the records' samples: the
    largest ``|settle_column(t) - (a + b t)|`` with ``a + b t`` its least-squares line on the
    shared clock (at most ``points`` samples per record, evenly spaced). A settling whose
    ``|D|`` times this is below the noise floor cannot be told from a trend on these records.

    Parameters
    ----------
    times : list of numpy.ndarray
        Each record's ``t[k]`` [s] on the clock the records share.
    tau, t0 : float
        Time constant ``T`` (> 0) and start ``t_s`` [s].
    points : int
        Samples per record used at most.

    Returns
    -------
    float
        The bow per unit ``D`` (>= 0; 0 for a straight line).

    Examples
    --------
    >>> t = [np.linspace(0.0, 10.0, 101)]
    >>> settle_bow(t, 2.0, 0.0) > 0.2 > 0.01 > settle_bow(t, 1e3, 0.0)
    True
    """
    t = np.concatenate([np.asarray(x, float)[::max(1, len(x) // points)] for x in times])
    y = settle_column(t, tau, t0)
    A = np.column_stack((np.ones_like(t), t - t.mean()))
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    return float(np.max(np.abs(y - A @ coef)))


def drift_columns(t: np.ndarray, p: dict, train_record: int | None = None,
                  n_train: int = 1, t0: float | None = None) -> np.ndarray:
    """Regressors of the drift for one record, the trend column last.

    Parameters
    ----------
    t : numpy.ndarray
        Time ``t[k]`` of the record [s].
    p : dict
        The variant (``clock``: one of ``DRIFT_VARIANTS``).
    train_record : int or None
        Index of the record among the train records (None: not a train record).
    n_train : int
        Number of train records.
    t0 : float or None
        The record's first time ``t[0]`` when ``t`` is a chunk of it (a record's clock starts
        there); None: ``t[0]``.

    Returns
    -------
    numpy.ndarray
        Shape (N, 1) (the trend ``t[k]`` or ``t[k] - t[0]`` [s]; for ``"settle"``
        ``1 - exp(-(t[k] - p["settle_t0"]) / p["settle_tau"])``); with levels (``"levels"``,
        or ``p["levels"]`` given) and several train records, first one indicator column per
        train record after the first (shape (N, n_train)).

    Examples
    --------
    >>> t = np.array([2.0, 2.5, 3.0])
    >>> drift_columns(t, {"clock": "record"})[:, 0].tolist()
    [0.0, 0.5, 1.0]
    >>> drift_columns(t, {"clock": "levels"}, train_record=1, n_train=2).tolist()
    [[1.0, 0.0], [1.0, 0.5], [1.0, 1.0]]
    """
    if p["clock"] == "settle":
        trend = settle_column(t, p["settle_tau"], p["settle_t0"])[:, None]
    else:
        trend = (t if p["clock"] == "absolute" else t - (t[0] if t0 is None else t0))[:, None]
    if not has_levels(p) or n_train < 2:
        return trend
    return np.hstack((level_rows(train_record, n_train, t.size).T, trend))


def level_rows(train_record: int | None, n_train: int, size: int) -> np.ndarray:
    """The rows of a level per train record after the first (the first record's level is
    the model's offset): one indicator row per such record, 1 on the samples of its own.

    Parameters
    ----------
    train_record : int or None
        Index of the record among the train records (None: not a train record, all 0).
    n_train : int
        Number of train records.
    size : int
        Samples of the record.

    Returns
    -------
    numpy.ndarray
        Shape ``(max(n_train - 1, 0), size)``.

    Examples
    --------
    >>> level_rows(2, 3, 2).tolist(), level_rows(None, 2, 2).tolist(), level_rows(0, 1, 2).shape
    ([[0.0, 0.0], [1.0, 1.0]], [[0.0, 0.0]], (0, 2))
    """
    ind = np.zeros((max(n_train - 1, 0), size))
    if train_record is not None and train_record >= 1:
        ind[train_record - 1] = 1.0
    return ind


def out_of_fold_level(r: np.ndarray, used=None, folds: int = LEVEL_FOLDS) -> np.ndarray:
    """The level of a residual, estimated out of fold (module docstring).

    Parameters
    ----------
    r : numpy.ndarray
        Residual ``r[k]`` of one record (measured output minus the model without the level).
    used : numpy.ndarray or slice or None
        Boolean mask of the scored samples (None or a slice: all).
    folds : int
        Contiguous blocks of the scored samples (at least 2).

    Returns
    -------
    numpy.ndarray
        ``level[k]``: the mean of ``r`` over the scored samples outside the block of ``k``
        (samples between blocks belong to the block after them; those after the last scored
        sample to the last block), output units.

    Raises
    ------
    ValueError
        ``folds`` below 2, or fewer scored samples than ``folds``.

    Examples
    --------
    >>> r = np.array([1.0, 1.0, 3.0, 3.0])
    >>> out_of_fold_level(r, folds=2).tolist()  # each half gets the other half's mean
    [3.0, 3.0, 1.0, 1.0]
    """
    idx = np.arange(r.size) if used is None or isinstance(used, slice) else np.flatnonzero(used)
    if folds < 2 or idx.size < folds:
        raise ValueError(f"folds: expected 2 <= folds <= {idx.size} scored samples, got {folds}")
    blocks = np.array_split(idx, folds)
    sums = np.array([np.sum(r[blk]) for blk in blocks])
    level = np.empty(r.size)
    for b, blk in enumerate(blocks):
        start = 0 if b == 0 else int(blk[0])
        end = r.size if b == folds - 1 else int(blocks[b + 1][0])
        others = np.arange(folds) != b  # summed without block b (not total minus block b)
        level[start:end] = np.sum(sums[others]) / (idx.size - blk.size)
    return level


def record_levels(model, segments) -> list[float]:
    """Level of each record under a ``"levels"`` drift model: the mean of the measured output
    minus the model without the level over the record's scored samples (the value the
    out-of-fold levels scatter around).

    Parameters
    ----------
    model : pimodel.diagnosis.effects.Model
        A fitted model (its ``features`` and ``coef``; the level adjustment is not applied).
    segments : list of Segment
        The records.

    Returns
    -------
    list of float
        One level per record [output units].

    Examples
    --------
    >>> from pimodel.diagnosis.effects import Model, make_segment, base_features
    >>> seg = make_segment(np.arange(3) * 1e-3, np.array([0.0, 1.0, 0.0]),
    ...                    np.array([0.5, 1.5, 0.5]), [0.0])
    >>> record_levels(Model("nominal", 0, base_features, np.array([1.0, 0.0])), [seg])
    [0.5]
    """
    # (a record streamed chunk by chunk: the same product, a chunk at a time; module streamed)
    times = getattr(model.features, "stacked_times", None)
    return [float(np.mean((s.y - (model.features(s) @ model.coef if times is None else
                                  times(s, model.coef)))[s.used])) for s in segments]


def describe_levels(slope: float, levels, t0s, t0_train: float) -> dict:
    """Which clock the validate levels follow, and the part no clock explains.

    A trend ``s`` on the shared clock moves the level of a record starting at ``t0`` by
    ``s (t0 - t0_train)`` from the train level; a trend that restarts with each record leaves
    it at the train level. The clock whose prediction is closer (in total over the records) is
    reported; what remains is the records' own offset.

    Parameters
    ----------
    slope : float
        Fitted trend ``s`` [output units / s].
    levels : list of float
        Level of each validate record relative to the train level [output units].
    t0s : list of float
        First time ``t[0]`` of each validate record [s].
    t0_train : float
        First time of the (first) train record [s].

    Returns
    -------
    dict
        ``drift_clock`` (``"record"`` or ``"absolute"``), ``drift_record_levels`` (the levels
        as given) and ``drift_record_offsets`` (each level minus the clock's prediction), both
        in output units.

    Examples
    --------
    >>> d = describe_levels(0.1, [0.5], [5.0], 0.0)  # 0.1 um/s over 5 s: the shared clock
    >>> d["drift_clock"], [round(x, 6) for x in d["drift_record_offsets"]]
    ('absolute', [0.0])
    >>> describe_levels(0.1, [0.02], [5.0], 0.0)["drift_clock"]  # a level of its own
    'record'
    """
    lv = np.asarray(levels, float)
    absolute = slope * (np.asarray(t0s, float) - t0_train)
    clock = "absolute" if np.sum(np.abs(lv - absolute)) < np.sum(np.abs(lv)) else "record"
    rest = lv - absolute if clock == "absolute" else lv
    return {"drift_clock": clock, "drift_record_levels": lv.tolist(),
            "drift_record_offsets": rest.tolist()}


def level_report(model, validate, train) -> dict:
    """The drift parameters read from the validate levels of a ``"levels"`` model
    (:func:`describe_levels`); ``{}`` for any other model.

    Parameters
    ----------
    model : pimodel.diagnosis.effects.Model
        A fitted model.
    validate, train : list of Segment
        The validate and train records.

    Returns
    -------
    dict
        ``drift_clock``, ``drift_record_levels``, ``drift_record_offsets`` (output units).

    Examples
    --------
    >>> from pimodel.diagnosis.effects import Model, base_features
    >>> level_report(Model("creep", 4, base_features, np.zeros(2)), [], [])
    {}
    """
    variant = model.params.get("drift_variant")
    if variant == "settle_levels":
        return {"drift_record_levels": record_levels(model, validate)}
    if variant != "levels":
        return {}
    return describe_levels(model.params["drift_per_s"], record_levels(model, validate),
                           [float(s.t[0]) for s in validate], float(train[0].t[0]))


def drift_term(params: dict, t: np.ndarray, y_rest: np.ndarray | None = None,
               measured: np.ndarray | None = None) -> np.ndarray:
    """The drift term ``params`` describe, on the time ``t`` of one record.

    Parameters
    ----------
    params : dict
        ``drift_per_s`` [output units / s], ``drift_clock`` and, for a model with a level per
        record, ``drift_variant`` ``"levels"`` (or ``"settle_levels"``) and
        ``drift_t0_train`` (first time of the train record whose level the model's offset is
        [s]); a settling adds
        ``D (1 - exp(-(t - t_s) / T))`` with ``drift_settling`` ``D`` [output units],
        ``drift_settling_time_s`` ``T`` and ``drift_settling_start_s`` ``t_s`` [s].
    t : numpy.ndarray
        Time ``t[k]`` [s].
    y_rest : numpy.ndarray, optional
        The model output without the drift (needed with ``measured``).
    measured : numpy.ndarray, optional
        The record's measured output: with levels, its level is estimated out of fold
        from it, as the diagnosis does on a validate record (every sample scored). Without it,
        the level the reported clock predicts: the train level (``"record"``) or the train
        level moved by the trend since ``drift_t0_train`` (``"absolute"``).

    Returns
    -------
    numpy.ndarray
        The term [output units], shape of ``t``.

    Examples
    --------
    >>> p = {"drift_per_s": 0.5, "drift_clock": "record"}
    >>> drift_term(p, np.array([1.0, 2.0])).tolist()
    [0.0, 0.5]
    >>> q = {**p, "drift_variant": "levels", "drift_t0_train": 0.0}
    >>> y = np.full(4, 2.0) + 0.5 * np.arange(4.0)  # a record at a level of 2
    >>> drift_term(q, np.arange(4.0), np.zeros(4), y).tolist()
    [2.0, 2.5, 3.0, 3.5]
    >>> r = {"drift_per_s": 0.0, "drift_clock": "absolute", "drift_settling": 1.0,
    ...      "drift_settling_time_s": 2.0, "drift_settling_start_s": 1.0}
    >>> drift_term(r, np.array([1.0, 3.0])).round(4).tolist()  # 1 - exp(-1) after T
    [0.0, 0.6321]
    """
    s, variant = float(params["drift_per_s"]), params.get("drift_variant")
    term = s * (t - t[0] if params["drift_clock"] == "record" or variant == "levels" else t)
    if "drift_settling_time_s" in params:
        term = term + float(params["drift_settling"]) * settle_column(
            t, float(params["drift_settling_time_s"]), float(params["drift_settling_start_s"]))
    if variant in ("levels", "settle_levels") and measured is not None:
        return term + out_of_fold_level(measured - y_rest - term)
    if variant == "levels" and params["drift_clock"] == "absolute":
        return term + s * (t[0] - float(params["drift_t0_train"]))
    return term
