"""Candidate augmentations of the nominal PI model, each a physical model with few parameters.

The hysteresis is represented by the play outputs ``Z`` of a fixed radius grid (the conventional
parametrisation, linear in the weights), so every candidate is fitted *jointly* with the
hysteresis weights by linear least squares on the train records (a nonlinear parameter such as
a mode frequency or a delay is chosen on a grid by the train residual). A candidate adds ``k``
parameters to the nominal model (for the information criterion on the validate records).
"""

from __future__ import annotations

import copy
import threading
import weakref
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import minimize_scalar

from .._native import pi_run_rows
from .chunked import NormalEquations, chunks, transposed
from .chunked import combine as _combine
from .chunked import stack_rows as _stack_rows
from .creep import creep_levels, creep_time_constants, first_scored, record_level, start_columns
from .drift import (
    DRIFT_VARIANTS,
    SETTLE_POINTS,
    drift_columns,
    drift_k,
    has_levels,
    level_rows,
    out_of_fold_level,
    settle_grid,
    settle_start,
)
from .filters import lag, mode, mode_coefficients, mode_rows, shift
from .lti import describe_lti, lti_columns, lti_k, nelder_mead, select_order
from .rate import (
    RATE_BANDS,
    RATE_FAMILIES,
    RATE_GROWTH_REFINE,
    RATE_GROWTHS,
    RATE_KEYS,
    RATE_POLISH_ROUNDS,
    RATE_SATURATION_REFINE,
    RATE_SATURATIONS,
    RATE_SCALED_EVALS,
    RATE_TAU_MAX,
    RATE_TAU_REFINE,
    RATE_TAU_START,
    RATE_TAUS,
    SCALED,
)
from .streamed import combo_chunks, is_streamed, n_plays, play_row_chunks, stacked_times
from .threads import helped_map, read_ahead
from .wiener import LOWPASS_KINDS, describe_wiener, polish_filter, search_filter, wiener_k

__all__ = [
    "base_features",
    "delay_grid",
    "fit_effect",
    "fitted_in",
    "fit_nominal",
    "head_segment",
    "lag",
    "make_segment",
    "mode",
    "mode_coefficients",
    "mode_rows",
    "Model",
    "nominal_params",
    "play_chunks",
    "Segment",
    "segment_of_rows",
    "shift",
]

MODE_HZ = tuple(np.geomspace(300.0, 5000.0, 15))
MODE_DAMPING = (0.02, 0.05, 0.1, 0.2)
# heavily damped points from lower frequencies: a mode in series with a real pole looks like one
# damped mode near a Butterworth damping over a band well below both (density_stage below
# 50 Hz: the best single mode sits at 130-250 Hz, damping 0.5-0.8, off the light grid, and the
# low-pass element of the linear part, module lti, then started from a poor base mode)
MODE_HEAVY = (tuple(np.geomspace(100.0, 5000.0, 9)), 0.7)
MODE_DAMPING_RANGE = (0.005, 0.9)  # bounds of the refined damping
MAX_MODE_NYQUIST = 0.8  # the mode frequency stays below this fraction of the Nyquist frequency
SEARCH_COLUMNS = 12  # play columns (leading first) in the grid searches; the final fit uses all
# (and the search of a filter before the hysteresis: module wiener)
SCREEN_SAMPLES = 1 << 16  # a longer train record: searches on its first samples (_screen)
LTI_MEMO = 16  # columns of the linear part's elements memoised per record (the last base mode)
_ORDER_LOCK = threading.Lock()  # guards the memos of _order_memo (module threads)
GRAM_STORE_BYTES = 32 << 20  # per segment: the play rows' terms kept by what they are
# (_stored_grams; 80 plays on 4 chunks of a screen: 0.2 MB a key)
DELAYED_GRAM_MAX = 1024  # samples: a longer whole delay's Gram formed anew (_delayed_grams)
SCREEN_CONFIRM = 3  # grid points of the screen confirmed on the whole records
MAX_DELAY_S = 20e-3  # s: real measurement chains (amplifier, sensor filter) lag by ms
EFFECTS = ("creep", "dynamics", "delay", "asymmetry", "drift", "rate")
DRIFT_CLOCKS = DRIFT_VARIANTS  # t - t[0] of each record, t as given, or a level per record
REFINED_CREEP_LAG = 10.0  # the refined creep's further lag, this factor beyond the longest
ASYMMETRY_ITERATIONS = 2  # refits of the asymmetry on the hysteresis part of the previous fit


@dataclass
class Segment:
    """One record prepared for the fits: samples ``k = 0..N-1`` at a constant sample time.

    Parameters
    ----------
    t : numpy.ndarray
        Time ``t[k]`` [s] as given (a record's own clock or one shared by the records).
    v : numpy.ndarray
        Input ``v[k]``.
    y : numpy.ndarray
        Measured output ``y[k]``.
    Z : numpy.ndarray
        Play outputs ``z_i[k]`` of the radius grid, shape (N, n).
    mask : numpy.ndarray or None
        Boolean, the samples that are fitted and scored (False in a start-up region whose
        initial memory is unknown); None: all.
    rate_basis : pimodel.diagnosis.rate.RateBasis or None
        The rate candidate's columns (:class:`~pimodel.diagnosis.rate.RateBasis`), set by the
        diagnosis.
    wiener_basis : pimodel.diagnosis.wiener.WienerBasis or None
        The play columns of a filtered input, for ``dynamics`` before the hysteresis
        (:mod:`.wiener`), set by the diagnosis; None: that variant is not tried.

    Examples
    --------
    >>> t = np.arange(4) * 1e-3
    >>> seg = Segment(t, np.zeros(4), np.zeros(4), np.zeros((4, 1)))
    >>> seg.dt, seg.used
    (0.001, slice(None, None, None))
    """

    t: np.ndarray
    v: np.ndarray
    y: np.ndarray
    Z: np.ndarray
    mask: np.ndarray | None = None
    rate_basis: object = None  # a rate.RateBasis, set by the diagnosis
    wiener_basis: object = None  # a wiener.WienerBasis, set by the diagnosis

    @property
    def used(self) -> np.ndarray:
        """Indices or slice of the fitted and scored samples."""
        return slice(None) if self.mask is None else self.mask

    @property
    def dt(self) -> float:
        """Sample time ``t[1] - t[0]`` [s]."""
        return float(self.t[1] - self.t[0])

    def play_rows(self, ncols: int | None = None, *, offset: bool = False) -> np.ndarray:
        """The play outputs as rows, the layout the fits stack their regressors in.

        Built once per segment and kept (C-contiguous), so a search does not transpose ``Z``
        at each point.

        Parameters
        ----------
        ncols : int or None
            The leading play outputs wanted; None: all ``n``.
        offset : bool
            Return all play rows followed by a row of ones (the nominal's regressors; ``ncols``
            is then ignored).

        Returns
        -------
        numpy.ndarray
            ``Z[:, :ncols].T``, shape (ncols, N) (a view of the kept array); with ``offset``
            shape (n + 1, N).

        Examples
        --------
        >>> seg = make_segment(np.arange(3) * 1e-3, np.array([0.0, 1.0, 0.5]), np.zeros(3),
        ...                    [0.0, 0.5])
        >>> seg.play_rows(1).tolist(), seg.play_rows(offset=True).shape
        ([[0.0, 1.0, 0.5]], (3, 3))
        """
        rows = self.__dict__.get("_rows")
        if rows is None or rows.shape[1] != self.Z.shape[0]:
            rows = self.__dict__["_rows"] = _stack_rows((self.Z.T, np.ones((1, self.Z.shape[0]))))
        n = self.Z.shape[1]
        if offset:
            return rows
        return rows[:n if ncols is None else min(ncols, n)]

    def forget_grams(self) -> None:
        """Drop the play rows' Gram the fits keep on the segment (and the rows it holds).

        Examples
        --------
        >>> seg = make_segment(np.arange(3) * 1e-3, np.array([0.0, 1.0, 0.5]), np.zeros(3),
        ...                    [0.0])
        >>> seg.forget_grams()  # nothing kept yet: nothing to drop
        """
        self.__dict__.pop("_first_grams", None)  # every thread's
        self.__dict__.pop("_base_grams", None)


def make_segment(t, v, y, radii, mask=None, *, at_rest: bool = True) -> Segment:
    """Segment of one record with the play outputs of ``radii``, the plays at rest at ``v[0]``.

    The play states before the first sample are ``z_i[-1] = v[0]`` (the diagnosis' ``"rest"``
    convention): a record that starts away from 0 starts with every play in its interior, not
    with the large plays held at 0 until the input has travelled past their radius. With
    ``at_rest=False`` they are 0 (the memory of a record cut from periodic motion near an
    extreme, where the plays sit near ``v[0] -+ r``).

    Parameters
    ----------
    t : numpy.ndarray
        Time ``t[k]`` [s].
    v : numpy.ndarray
        Input ``v[k]``.
    y : numpy.ndarray
        Measured output ``y[k]``.
    radii : array_like
        Play radii of the grid [input units], ``n`` of them.
    mask : numpy.ndarray or None
        Samples fitted and scored (see :class:`Segment`); None: all.
    at_rest : bool
        Plays at rest at ``v[0]`` (default); False: at 0.

    Returns
    -------
    Segment
        With ``Z[k, i]`` the output of play ``i`` at sample ``k``, shape (N, n).

    Examples
    --------
    >>> seg = make_segment(np.arange(4) * 1e-3, np.array([0.0, 1.0, 0.5, 0.0]), np.zeros(4),
    ...                    [0.0, 0.5])
    >>> seg.Z.tolist()
    [[0.0, 0.0], [1.0, 0.5], [0.5, 0.5], [0.0, 0.5]]
    """
    radii = np.asarray(radii, float)
    v = np.asarray(v, float)
    rows = np.empty((radii.size + 1, np.size(v)))
    for c, rc in play_chunks(v, radii, at_rest=at_rest):
        rows[:-1, c] = rc[:-1]
    return segment_of_rows(t, v, y, rows, mask)


def play_chunks(v, radii, *, at_rest: bool = True) -> Iterator[tuple[slice, np.ndarray]]:
    """The play outputs of ``radii`` chunk by chunk (:func:`~.chunked.chunks`), their states
    carried over from one chunk to the next, so a pass over a record holds one chunk of them.
    Within :func:`.threads.lend`, the next chunk is made on an idle thread of the lent pool
    while the caller works on this one (:func:`.threads.read_ahead`; the same chunks).

    Parameters
    ----------
    v : numpy.ndarray
        Input ``v[k]``.
    radii : array_like
        Play radii [input units], ``n`` of them.
    at_rest : bool
        Plays at rest at ``v[0]`` before the first sample (default); False: at 0.

    Returns
    -------
    iterator of (slice, numpy.ndarray)
        The chunk's samples ``c`` and its rows ``[z_1[c]; ...; z_n[c]; 1]``, shape
        (n + 1, len(c)): the play outputs after each sample and a row of ones (the offset).

    Examples
    --------
    >>> [rows.tolist() for _, rows in play_chunks(np.array([0.0, 1.0, 0.5]), [0.5])]
    [[[0.0, 0.5, 0.5], [1.0, 1.0, 1.0]]]
    """
    radii = np.ascontiguousarray(radii, float)
    v = np.ascontiguousarray(v, float)
    ones = np.ones(radii.size)
    z = np.full(radii.size, float(v[0]) if at_rest else 0.0)  # the plays' states, carried

    def each():
        for c in chunks(v.size):
            rows = np.empty((radii.size + 1, c.stop - c.start))
            pi_run_rows(ones, radii, z, v[c], rows[:-1])  # written as rows by the C core
            rows[-1] = 1.0
            yield c, rows

    return read_ahead(each())  # the next chunk on an idle thread of a lent pool (module threads)


def segment_of_rows(t, v, y, rows: np.ndarray, mask=None) -> Segment:
    """Segment whose play columns are the leading rows of ``rows``, shape (n + 1, N), C-contiguous
    (the last row is set to ones: the offset): ``Z`` is a view of them, so the segment holds the
    play outputs once, in the layout the fits use.

    Parameters
    ----------
    t, v, y : numpy.ndarray
        Time [s], input and output, shape (N,).
    rows : numpy.ndarray
        Play outputs as rows with one spare last row, shape (n + 1, N); taken over, not copied.
    mask : numpy.ndarray or None
        Samples fitted and scored (see :class:`Segment`); None: all.

    Returns
    -------
    Segment
        With ``Z = rows[:n].T`` and ``play_rows(offset=True) is rows``.

    Examples
    --------
    >>> rows = np.array([[0.0, 1.0, 0.5], [0.0, 0.0, 0.0]])
    >>> seg = segment_of_rows(np.arange(3) * 1e-3, rows[0].copy(), np.zeros(3), rows)
    >>> seg.Z.tolist(), seg.play_rows(offset=True)[1].tolist()
    ([[0.0], [1.0], [0.5]], [1.0, 1.0, 1.0])
    """
    rows = np.ascontiguousarray(rows, float)
    rows[-1] = 1.0
    seg = Segment(t, v, y, rows[:-1].T, mask)
    seg.__dict__["_rows"] = rows
    return seg


@dataclass
class Model:
    """A fitted (nominal or augmented) model: ``features(seg) @ coef``.

    Parameters
    ----------
    name : str
        ``"nominal"`` or the effects joined by ``+`` (``"creep+delay"``).
    k : int
        Parameters added to the nominal model.
    features : callable
        ``features(seg)``: the regressor matrix of a :class:`Segment`, shape (N, p).
    coef : numpy.ndarray
        Fitted coefficients, shape (p,).
    params : dict
        Fitted physical parameters (``mode_hz``, ``delay_samples``, ...).
    grid : dict
        The grid parameters the model was built with.
    adjust : callable or None
        ``adjust(seg, out)``: the prediction ``out`` of a record corrected by a nuisance
        measured on the record itself (a drift's out-of-fold level, :mod:`.drift`); None: none.
    reference : Model or None
        The reference hysteresis ``h0`` the effect columns were built from, when it is not the
        nominal model (an asymmetry's, see :func:`fit_effect`); None: the nominal.

    Examples
    --------
    >>> seg = make_segment(np.arange(3) * 1e-3, np.array([0.0, 1.0, 0.0]), np.zeros(3), [0.0])
    >>> Model("nominal", 0, base_features, np.array([2.0, 0.5])).predict(seg).tolist()
    [0.5, 2.5, 0.5]
    """

    name: str
    k: int
    features: object = field(repr=False)
    coef: np.ndarray = field(repr=False, default=None)
    params: dict = field(default_factory=dict)
    grid: dict = field(default_factory=dict)
    adjust: object = field(repr=False, default=None)
    reference: object = field(repr=False, default=None)

    def release(self) -> None:
        """Drop the columns the model's features memoised per record (filtered plays, lags,
        rate columns); a later :meth:`predict` rebuilds them. A diagnosis keeps every fitted
        candidate: without this, each kept a few copies of its records' columns.

        Examples
        --------
        >>> seg = make_segment(np.arange(2) * 1e-3, np.array([0.0, 1.0]), np.zeros(2), [0.0])
        >>> m = Model("nominal", 0, base_features, np.array([3.0, 0.0]))
        >>> m.release(); m.predict(seg).tolist()
        [0.0, 3.0]
        """
        release = getattr(self.features, "release", None)
        if release is not None:
            release()

    def predict(self, seg: Segment) -> np.ndarray:
        """Model output of a record.

        Parameters
        ----------
        seg : Segment
            The record.

        Returns
        -------
        numpy.ndarray
            ``features(seg) @ coef`` (then ``adjust``, if set): the model output at each
            sample, output units.

        Examples
        --------
        >>> seg = make_segment(np.arange(2) * 1e-3, np.array([0.0, 1.0]), np.zeros(2), [0.0])
        >>> Model("nominal", 0, base_features, np.array([3.0, 0.0])).predict(seg).tolist()
        [0.0, 3.0]
        """
        if is_streamed(seg):  # a long record's rows a chunk at a time (module streamed)
            out = np.empty(seg.y.size)
            for c, P in read_ahead(self.features.parts_chunks(seg)):  # (module threads)
                out[c] = _combine(P, self.coef)
        else:
            out = _combine(_row_parts(self.features, seg), self.coef)
        return out if self.adjust is None else self.adjust(seg, out)


def _fit(name, k, features, train, params=None) -> tuple[Model, float]:
    """Least squares over all train records through normal equations accumulated chunk by
    chunk (:class:`~pimodel.diagnosis.chunked.NormalEquations`: columns scaled to unit norm, the
    Gram matrix is small), so a grid search costs one pass over the data per point and no
    temporary larger than a chunk; the residual sum of squares is taken from the same sums
    when that is safe from cancellation (:meth:`~pimodel.diagnosis.chunked.NormalEquations.rss`,
    within ``RSS_RTOL``), else computed from the residuals themselves, chunk by chunk (a second
    pass). The regressors are taken as blocks of rows when the builder has
    them (:func:`_row_parts`): no copy of the play columns at each point of a search. A
    streamed segment (a long record in the whole-record refit, module streamed) gives its
    blocks chunk by chunk (``features.parts_chunks``), built once per pass: the same values
    as the slices of its whole blocks, so the same sums. With a pool lent to the caller
    (module threads), idle threads make some chunks' terms of whole blocks; every sum is
    still taken in the chunks' order (:func:`_per_chunk`)."""
    memo = _fit_memo(features, train)
    if memo is not None and memo[1] is not None:  # this fit made before: its coefficients
        coef, rss = memo[1]
        return Model(name, k, features, coef.copy(), params or {}), rss
    blocks = [None if is_streamed(s) else _row_parts(features, s) for s in train]
    ne = None
    for P, s in zip(blocks, train, strict=True):
        first = None if P is None else _first_grams(P[0], s, getattr(P, "delayed", None),
                                                    getattr(P, "first_key", None))
        for terms in _per_chunk(features, P, s, lambda j, c, Pc, s=s, first=first:
                                _normal_terms(Pc, s, c, None if first is None else first[j])):
            if ne is None:
                ne = NormalEquations(terms[0].shape[0])
            ne.add_gram(*terms)
    coef = ne.solve()
    rss = ne.rss(coef)  # from the sums when that is safe from cancellation (RSS_RTOL)
    if rss is None:  # else a second pass, over the residuals
        rss = 0.0
        for P, s in zip(blocks, train, strict=True):
            for r in _per_chunk(features, P, s, lambda j, c, Pc, s=s: _chunk_rss(Pc, s, c, coef)):
                rss += r  # summed in the chunks' order, whichever thread made each
    if memo is not None:
        memo[0][memo[2]] = (memo[3], (coef.copy(), rss))
    return Model(name, k, features, coef, params or {}), rss


_FIT_MEMO_LOCK = threading.Lock()  # guards the memos of _fit_memo (module threads)


def _fit_memo(features, train) -> tuple | None:
    """The memo of :func:`_fit` for a candidate's regressors (:func:`_combo_features`: the
    effects, the grid point and the play columns name them) on the train segments ``train``:
    ``(memo, (coef, rss) or None, key, weak references to train)``; None for other builders,
    grid points it cannot name exactly, or streamed segments. A search revisits points (a
    polish's optimum fitted again as the search's result, the confirmation of the screen's
    best, the same combination asked for by the rounds, the revision and the lag's re-search):
    the same regressors on the same segments give the same sums in the same order, so the
    coefficients and RSS kept are those a second pass makes, to the bit. Kept on the
    ``nominal`` the regressors are built from (one per diagnosis, a new one for each refined
    or asymmetry reference), by the segments' identity (weak references checked, so a segment
    freed and another at its address is not taken for it)."""
    recipe = getattr(features, "recipe", None)
    if recipe is None or any(is_streamed(s) for s in train):
        return None
    nominal, exact = recipe
    if exact is None:
        return None
    key = (exact, tuple(id(s) for s in train))
    with _FIT_MEMO_LOCK:
        memo = nominal.__dict__.setdefault("_fit_memo", {})
        kept = memo.get(key)
    if kept is not None and all(r() is s for r, s in zip(kept[0], train, strict=True)):
        return memo, kept[1], key, kept[0]
    return memo, None, key, [weakref.ref(s) for s in train]


def _exact(x):
    """``x`` (a grid point's value) as a hashable key that tells apart every value and type
    (floats by ``repr``, which round-trips their bits; arrays by their bytes); None when ``x``
    holds anything else."""
    if isinstance(x, dict):
        items = tuple((k, _exact(v)) for k, v in sorted(x.items()))
        return None if any(v is None for _, v in items) else ("dict", items)
    if isinstance(x, (tuple, list)):
        items = tuple(_exact(v) for v in x)
        return None if any(v is None for v in items) else (type(x).__name__, items)
    if x is None or isinstance(x, (bool, int, float, str, np.generic)):
        return (type(x).__name__, repr(x))
    if isinstance(x, np.ndarray):
        return ("ndarray", x.dtype.str, x.shape, x.tobytes())
    return None


def _per_chunk(features, P: tuple | None, s: Segment, fn: Callable) -> Iterable:
    """``fn(j, c, Pc)`` for each chunk ``c`` (the ``j``-th) of ``s`` with the blocks ``Pc`` on
    it, in the chunks' order: for whole blocks ``P`` the chunks are independent and idle
    threads of a lent pool may make some (:func:`.threads.helped_map`: each chunk's value the
    same on any thread); a streamed segment's (``P`` None) are made in turn as its blocks
    are built, the next chunk's blocks built on an idle thread meanwhile
    (:func:`.threads.read_ahead`)."""
    if P is None:
        return (fn(j, c, Pc) for j, (c, Pc) in enumerate(read_ahead(features.parts_chunks(s))))
    return helped_map(lambda jc: fn(*jc, tuple(X[:, jc[1]] for X in P)),
                      list(enumerate(chunks(s.y.size))))


def _normal_terms(Pc: tuple, s: Segment, c: slice, first: np.ndarray | None):
    """The Gram matrix, ``X y``, the sample count and ``y^T y`` of the fitted samples of
    chunk ``c``."""
    Pc, y = _used_chunk(Pc, s, c)
    if first is None:
        return _gram(Pc), np.concatenate([X @ y for X in Pc]), y.size, float(y @ y)
    gram, zy = first  # the first block's, kept (_first_grams)
    return (_gram(Pc, gram), np.concatenate([zy] + [X @ y for X in Pc[1:]]), y.size,
            float(y @ y))


def _chunk_rss(Pc: tuple, s: Segment, c: slice, coef: np.ndarray) -> float:
    """The residual sum of squares of the fitted samples of chunk ``c``."""
    Pc, y = _used_chunk(Pc, s, c)
    return float(np.sum((_combine(Pc, coef) - y) ** 2))


def _used_chunk(Pc: tuple, s: Segment, c: slice) -> tuple[tuple, np.ndarray]:
    """The blocks of rows ``Pc`` on the chunk ``c`` of segment ``s`` and its output there,
    the fitted samples only."""
    if s.mask is None:
        return Pc, s.y[c]
    m = fitted_in(s.mask, c)
    return tuple(X[:, m] for X in Pc), s.y[c][m]


def fitted_in(mask: np.ndarray, c: slice) -> slice | np.ndarray:
    """The fitted samples of chunk ``c`` under ``mask`` (:class:`Segment`), as an index into
    the chunk.

    Parameters
    ----------
    mask : numpy.ndarray
        Boolean, the fitted samples of the whole record.
    c : slice
        The chunk's samples ``a:b`` (:func:`~.chunked.chunks`).

    Returns
    -------
    slice or numpy.ndarray
        A slice when the chunk's fitted samples are one run (a start-up region left out: the
        blocks of rows are then sliced as views, not copied at each fit; ``slice(0, 0)`` when
        none is fitted), else the chunk's boolean mask.

    Examples
    --------
    >>> fitted_in(np.arange(10) >= 3, slice(0, 5)), fitted_in(np.arange(10) >= 3, slice(5, 10))
    (slice(3, 5, None), slice(0, 5, None))
    """
    m = mask[c]
    first = int(np.argmax(m))
    if not m[first]:
        return slice(0, 0)
    stop = m.size - int(np.argmax(m[::-1]))
    return slice(first, stop) if stop - first == int(np.count_nonzero(m)) else m


def _row_parts(features, s: Segment) -> tuple:
    """The regressors of ``s`` as blocks of rows (shape (p_i, N) each, stacked in order they
    are the transposed ``features(s)``): ``features.parts`` or ``features.rows`` when the builder
    has them (no copy: the fits and predictions work on the blocks), else the transpose."""
    if hasattr(features, "parts"):
        return features.parts(s)
    if hasattr(features, "rows"):
        return (features.rows(s),)
    return (features(s).T,)


def _first_grams(Z: np.ndarray, s: Segment, delayed: tuple | None = None,
                 key: tuple | None = None) -> list | None:
    """``(Z_c Z_c^T, Z_c y_c)`` of the first block of rows ``Z`` (the play rows) on each chunk
    ``c`` of ``s`` (its fitted samples), kept on the segment for the latest ``Z`` while ``Z`` is a
    screen's (at most ``SCREEN_SAMPLES`` samples): the fits of a search that holds the play
    rows (creep, asymmetry, drift, the rate's filters, the linear part's elements around one
    mode) then form only the blocks that change. None for a whole long record.

    ``delayed = (Z0, d)``: ``Z`` is ``Z0`` delayed by ``d`` samples (held at ``Z0[:, 0]``
    before the start). For a whole ``d`` and no mask, the Gram on a chunk ``[a, b)`` is that
    of ``Z0`` on ``[a - d, b - d)``: ``Z0``'s on ``[a, b)`` (kept for the latest ``Z0``,
    :func:`_delayed_grams`) less its ``d`` last samples' outer products plus those of the ``d``
    samples before ``a``, so a delay search forms one Gram of the play rows per ``Z0``, not
    one per delay (the same sums in another order: equal to rounding).

    ``key``: what ``Z`` is (:func:`_combo_features`: the play rows and the transforms made of
    them, such as a mode's filter at ``(fn, zeta)``), or None. With a key the terms are kept on
    the segment by it (:func:`_stored_grams`), not only for the latest ``Z``: a search builds
    the same rows anew for each combination and drift variant around one mode, and gets the
    terms it made before, to the bit."""
    if Z.shape[1] > SCREEN_SAMPLES:
        return None
    cuts = list(chunks(s.y.size))

    def make() -> list:
        grams = None
        if delayed is not None and s.mask is None and Z.shape == delayed[0].shape:
            grams = _delayed_grams(Z, s, cuts, *delayed)
        if grams is None:
            grams = helped_map(lambda c: _first_terms(*_used_chunk((Z[:, c],), s, c)), cuts)
        return grams

    if key is not None:
        return _stored_grams(s, (key, len(cuts)), make)
    return _rows_memo(s, "_first_grams", Z, cuts, make)


_GRAM_LOCK = threading.Lock()  # guards the stores of _stored_grams (module threads)


def _stored_grams(s: Segment, key: tuple, make: Callable) -> list:
    """``make()`` (a list of ``(G, zy)`` arrays) kept on the segment ``s`` by ``key``, the least
    recently used dropped beyond ``GRAM_STORE_BYTES`` per segment. Two threads that miss one
    key both make it (the same values) and the later one is kept."""
    with _GRAM_LOCK:
        store = s.__dict__.setdefault("_gram_store", {})  # insertion order: least recent first
        kept = store.pop(key, None)
        if kept is not None:
            store[key] = kept
            return kept[1]
    grams = make()
    size = sum(g.nbytes + zy.nbytes for g, zy in grams)
    with _GRAM_LOCK:
        old = store.pop(key, None)
        store[key] = (size, grams)
        total = s.__dict__.get("_gram_bytes", 0) + size - (0 if old is None else old[0])
        while total > GRAM_STORE_BYTES and len(store) > 1:
            total -= store.pop(next(iter(store)))[0]
        s.__dict__["_gram_bytes"] = total
    return grams


def _rows_memo(s: Segment, name: str, Z: np.ndarray, cuts: list, make: Callable) -> list:
    """``make()`` kept on the segment ``s`` (attribute ``name``, one entry per thread: module
    threads) for the latest rows ``Z``, keyed by their address, shape and strides and the
    chunk count; the entry keeps ``Z`` alive, so its address stays its own."""
    key = (Z.__array_interface__["data"][0], Z.shape, Z.strides, len(cuts))
    kept = s.__dict__.setdefault(name, {})
    memo = kept.get(threading.get_ident())
    if memo is None or memo[0] != key:
        memo = kept[threading.get_ident()] = (key, Z, make())
    return memo[2]


def _delayed_grams(Z: np.ndarray, s: Segment, cuts: list, Z0: np.ndarray, d) -> list | None:
    """:func:`_first_grams` of ``Z``, ``Z0`` delayed by a whole ``d`` samples, from those of
    ``Z0`` (kept on the segment for the latest ``Z0``, per thread); None for a fractional or
    zero ``d`` or one beyond ``DELAYED_GRAM_MAX`` samples (``Z`` then fitted as it is)."""
    n = int(d) if float(d).is_integer() else 0
    if not 0 < n <= DELAYED_GRAM_MAX:
        return None
    base = _rows_memo(s, "_base_grams", Z0, cuts,
                      lambda: helped_map(lambda c: _square(Z0[:, c]), cuts))
    z0 = Z0[:, :1]

    def window(x: int, y: int) -> np.ndarray:  # sum of z_max(j,0) z_max(j,0)^T, j in [x, y)
        G = _square(Z0[:, max(x, 0):y]) if y > 0 else 0.0
        return G + (min(y, 0) - x) * _square(z0) if x < 0 else G

    return [((G0 - window(c.stop - n, c.stop)) + window(c.start - n, c.start), Z[:, c] @ s.y[c])
            for c, G0 in zip(cuts, base, strict=True)]


def _first_terms(Pc: tuple, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return _square(Pc[0]), Pc[0] @ y  # the products _normal_terms would make


def _square(X: np.ndarray) -> np.ndarray:
    return X @ X.T


def _gram(P: tuple, first: np.ndarray | None = None) -> np.ndarray:
    """``B B^T`` of the rows ``B`` the blocks ``P`` stack, block by block (``first``: that of
    the first block, when known)."""
    edges = np.cumsum([0] + [X.shape[0] for X in P])
    G = np.empty((edges[-1], edges[-1]))
    for i, X in enumerate(P):
        for j in range(i, len(P)):
            blk = (X @ X.T if first is None or i else first) if j == i else X @ P[j].T
            G[edges[i]:edges[i + 1], edges[j]:edges[j + 1]] = blk
            G[edges[j]:edges[j + 1], edges[i]:edges[i + 1]] = blk.T
    return G


def _ones(s: Segment) -> np.ndarray:
    return np.ones((s.t.size, 1))


def base_features(s: Segment) -> np.ndarray:
    """Regressors of the nominal model: the play outputs and a constant offset.

    Parameters
    ----------
    s : Segment
        The record.

    Returns
    -------
    numpy.ndarray
        ``[Z, 1]``, shape (N, n + 1).

    Examples
    --------
    >>> seg = make_segment(np.arange(2) * 1e-3, np.array([0.0, 1.0]), np.zeros(2), [0.0, 0.5])
    >>> base_features(seg).tolist()
    [[0.0, 0.0, 1.0], [1.0, 0.5, 1.0]]
    """
    return _base_rows(s).T


def _base_rows(s: Segment) -> np.ndarray:
    return s.play_rows(offset=True)


base_features.rows = _base_rows
base_features.parts_chunks = lambda s: ((c, (rows,)) for c, rows in play_row_chunks(s))


def fit_nominal(train) -> Model:
    """The nominal PI model: play weights and an offset by least squares on the train records.

    Parameters
    ----------
    train : list of Segment
        The train records (their masked samples are fitted).

    Returns
    -------
    Model
        Named ``"nominal"``, ``k = 0``; ``params`` holds the ``center`` and ``half_range`` of
        its output, ``slope_sum`` (sum of the play weights), ``rate_scale`` (95th
        percentile of the moving input rate [input units / s]) and ``creep_taus`` (the creep
        candidate's lags for these records, :func:`.creep.creep_time_constants`).

    Examples
    --------
    >>> v = np.sin(np.linspace(0.0, 6 * np.pi, 300))
    >>> y = 2.0 * v + 0.1  # a linear stage with an offset
    >>> seg = make_segment(np.arange(300) * 1e-3, v, y, [0.0, 0.3])
    >>> m = fit_nominal([seg])
    >>> round(float(m.coef[0]), 6), round(float(m.coef[-1]), 6)  # slope, offset
    (2.0, 0.1)
    >>> round(float(np.max(np.abs(m.predict(seg) - y))), 6)
    0.0
    """
    model = _fit("nominal", 0, base_features, train)[0]
    model.params = nominal_params(model.coef, [model.predict(s) for s in train], train)
    return model


def nominal_params(coef: np.ndarray, outputs: list, train) -> dict:
    """The ``params`` of a nominal model (:func:`fit_nominal`) from its fit.

    Parameters
    ----------
    coef : numpy.ndarray
        Play weights, then the offset.
    outputs : list of numpy.ndarray
        The model output on each train record, every sample.
    train : list of Segment
        The train records (their ``t`` and ``v`` are read).

    Returns
    -------
    dict
        ``center``, ``half_range``, ``slope_sum``, ``rate_scale``, ``creep_taus`` as
        :func:`fit_nominal` describes them.

    Examples
    --------
    >>> seg = make_segment(np.arange(3) * 1e-3, np.array([0.0, 1.0, 0.0]), np.zeros(3), [0.0])
    >>> p = nominal_params(np.array([2.0, 0.0]), [np.array([0.0, 2.0, 0.0])], [seg])
    >>> p["center"], p["half_range"], p["slope_sum"], p["rate_scale"]
    (0.6666666666666666, 1.0, 2.0, 1000.0)
    """
    # (the same numbers as from the concatenated outputs and rates; a record's own array is
    # used as it is, its rate built in place, the percentile's selection made in place)
    h = outputs[0] if len(outputs) == 1 else np.concatenate(outputs)
    center, half_range = float(np.mean(h)), max(float(np.ptp(h)) / 2, 1e-12)
    del h
    rates = []
    for s in train:
        r = np.diff(s.v)
        np.abs(r, out=r)
        r /= s.dt
        rates.append(r)
    rate = rates[0] if len(rates) == 1 else np.concatenate(rates)
    del rates
    moving = rate[rate > 1e-9 * (float(np.ptp(rate)) or 1.0)]
    del rate
    return {"center": center, "half_range": half_range,
            "slope_sum": float(np.sum(coef[:-1])),
            "rate_scale": float(np.percentile(moving, 95, overwrite_input=True))
            if moving.size else 1.0,
            "creep_taus": creep_time_constants(
                train[0].dt, max(float(s.t[-1] - s.t[0]) for s in train))}


class TrainRecords:
    """The train records of a fit, by identity: which record a segment is (a drift's level
    per train record; validate records get an out-of-fold level).

    Weak: a train segment freed after the fit (the whole-record refit drops its rows) is no
    longer one, and a new segment that Python puts at its address is not taken for it (keyed
    by ``id`` alone, a validate record built after the train rows were dropped could get a
    train record's level column and lose its own level).

    Parameters
    ----------
    train : list of Segment
        The train records, in order.

    Examples
    --------
    >>> a = make_segment(np.arange(2) * 1e-3, np.zeros(2), np.zeros(2), [0.0])
    >>> train = TrainRecords([a])
    >>> train.index(a), len(train), a in train
    (0, 1, True)
    >>> b = make_segment(np.arange(2) * 1e-3, np.zeros(2), np.zeros(2), [0.0])
    >>> train.index(b), b in train
    (None, False)
    """

    def __init__(self, train) -> None:
        self._refs = {id(s): (j, weakref.ref(s)) for j, s in enumerate(train)}

    def index(self, seg) -> int | None:
        """Which train record ``seg`` is.

        Parameters
        ----------
        seg : Segment
            A record.

        Returns
        -------
        int or None
            Its place among the train records (0, 1, ...); None when it is not one of them.

        Examples
        --------
        >>> seg = make_segment(np.arange(2) * 1e-3, np.zeros(2), np.zeros(2), [0.0])
        >>> TrainRecords([seg]).index(seg)
        0
        """
        hit = self._refs.get(id(seg))
        return hit[0] if hit is not None and hit[1]() is seg else None

    def __contains__(self, seg) -> bool:
        return self.index(seg) is not None

    def __len__(self) -> int:
        return len(self._refs)


def fit_effect(name: str, train, combo: tuple[str, ...] = (), fixed: dict | None = None,
               nominal: Model | None = None) -> Model:
    """Fit the nominal model augmented with the effects ``combo + (name,)`` jointly; the grid
    parameters of the effects in ``combo`` are held at ``fixed`` (from earlier rounds).

    Parameters
    ----------
    name : str
        The effect added, one of ``EFFECTS``.
    train : list of Segment
        The train records (``rate_basis`` set when ``"rate"`` is among the effects).
    combo : tuple of str
        Effects chosen in earlier rounds.
    fixed : dict or None
        Their grid parameters (``fn``, ``zeta``, ``d``, ``clock``, ``rate_family``,
        ``rate_tau``, ``rate_saturation``). Two keys make an effect's model richer:
        ``"refine": "creep"``, a further lag ``REFINED_CREEP_LAG`` times the longest;
        ``"lti_min": n``, at least ``n`` further elements of the linear part
        (:func:`.lti.select_order`). ``"held": True`` with every effect's grid parameters
        given (a fitted model's ``grid``): no search at all, the linear part's elements
        ``lti`` kept as given (a refit on other records). ``"search_all": True``: the mode
        search with every play column, not the leading ``SEARCH_COLUMNS`` (slower; the
        diagnosis' re-search of a lag beside a later effect,
        :func:`pimodel.diagnosis.diagnose._research_lag`).
    nominal : Model or None
        The nominal model (:func:`fit_nominal` of ``train`` when None).

    Returns
    -------
    Model
        Named by the effects joined by ``+``, with ``k`` added parameters, the grid optimum in
        ``grid`` and the fitted physical parameters in ``params``. With an asymmetry, the
        effect columns are built from the hysteresis part of the joint fit, refitted
        ``ASYMMETRY_ITERATIONS`` times, and ``reference`` holds it. With a delay, the columns
        built from that reference ``h0`` (creep, asymmetry, the linear part's elements) are
        delayed with the play rows: the delay acts on the input of everything the plays
        drive (:mod:`.model`).

    Examples
    --------
    >>> v = np.sin(np.linspace(0.0, 6 * np.pi, 300))
    >>> seg = make_segment(np.arange(300) * 1e-3, v, 2.0 * v, [0.0, 0.3])
    >>> m = fit_effect("creep", [seg])
    >>> m.name, m.k, m.params["creep_time_constants_s"]  # lags for 0.3 s at 1 kHz
    ('creep', 2, [0.03, 0.3])
    """
    return _order_memo((*combo, name), train, dict(fixed or {}), nominal or fit_nominal(train))


def _order_memo(effects: tuple[str, ...], train, fixed: dict, nominal: Model) -> Model:
    """:func:`_fit_combo`, memoised on ``nominal`` for a searched linear part: a fit asking for
    at least ``lti_min`` further elements (``fixed["lti_min"]``, the second-effect rule's
    refined dynamics) is the fit already made with ``m0 <= lti_min`` that chose at least
    ``lti_min`` elements on its own or found none left to add (:func:`.lti.select_order` then
    takes the same steps: the forced ones passed its test anyway), to the bit, and is not made
    again (each such fit is a whole mode search, grid, polish, order selection and Wiener
    search: 360-380 passes over the screen). Otherwise the fit reuses the earlier fits' grid
    searches (``memo["searched"]``) and goes on from where their order selection stopped
    (``memo["order"]``). A copy of the model is returned (its ``params`` and ``grid`` its own)."""
    if "dynamics" not in effects or {"fn", "wiener", "held"} & set(fixed):
        return _fit_combo(effects, train, fixed, nominal)
    lti_min = fixed.get("lti_min", 0)
    key = (effects, tuple(id(s) for s in train),
           repr(sorted((k_, v) for k_, v in fixed.items() if k_ != "lti_min")))
    with _ORDER_LOCK:  # one memo per key, filled by one thread at a time (module threads)
        memo = nominal.__dict__.setdefault("_order_memo", {})
        known = memo.setdefault(key, {"runs": [], "lock": threading.Lock()})
        if not all(r() is s for r, s in zip(known.setdefault("train", [weakref.ref(s) for s in
                                                                        train]),
                                             train, strict=True)):
            known = memo[key] = {"runs": [], "train": [weakref.ref(s) for s in train],
                                 "lock": threading.Lock()}
    with known["lock"]:
        for m0, chose, model in known["runs"]:
            if m0 <= lti_min <= chose:
                return _copy_model(model)
        known.pop("elements", None)
        model = _fit_combo(effects, train, dict(fixed), nominal, known)
        known["runs"].append((lti_min, known.pop("elements", -1), _copy_model(model)))
    return model


def _copy_model(model: Model) -> Model:
    """``model`` with ``params`` and ``grid`` copied (the diagnosis adds to a fit's params)."""
    return replace(model, params=copy.deepcopy(model.params), grid=copy.deepcopy(model.grid))


def delay_grid(dt: float) -> np.ndarray:
    """Coarse delay grid [samples]: every sample up to 12, then geometric up to MAX_DELAY_S.

    Parameters
    ----------
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        Sorted whole delays [samples], from 0 to ``round(MAX_DELAY_S / dt)`` (at least 1).

    Examples
    --------
    >>> delay_grid(5e-3).tolist()
    [0, 1, 2, 3, 4]
    >>> int(delay_grid(1e-4)[-1])
    200
    """
    dmax = max(int(round(MAX_DELAY_S / dt)), 1)
    coarse = np.concatenate((np.arange(min(dmax, 12) + 1), np.geomspace(12, dmax, 24)))
    return np.unique(np.round(coarse).astype(int)[coarse <= dmax])


def _fit_combo(effects: tuple[str, ...], train, fixed: dict, nominal: Model,
               memo: dict | None = None) -> Model:
    """Joint fit; the nonlinear parameters (mode, delay, drift clock) by grid search on the
    train RSS (a mode search with the leading ``SEARCH_COLUMNS`` play columns), refined around
    the grid optimum, then refitted with every play column. ``memo`` (:func:`_order_memo`):
    the grid searches' result is kept in ``memo["searched"]`` (and taken from it when there),
    the number of further elements the order selection chose in ``memo["elements"]``."""
    name = "+".join(effects)
    # an effect's own model one step richer, the yardstick a second effect must beat
    # (pimodel.diagnosis.diagnose): fixed["refine"] = "creep", a further lag;
    # fixed["lti_min"], at least that many further elements of the linear part
    lti_min = fixed.pop("lti_min", 0)
    held = fixed.pop("held", False)  # every grid parameter as given: no search at all
    search_all = fixed.pop("search_all", False)
    if fixed.pop("refine", None) == "creep" and "creep" in effects:
        taus = tuple(nominal.params["creep_taus"])
        nominal = replace(nominal, params={**nominal.params,
                                           "creep_taus": (*taus, REFINED_CREEP_LAG * taus[-1])})
    scaled = fixed.pop("rate_shape", None) == SCALED  # the rate's exact shape (module rate)
    k = _combo_k(effects, nominal) + (drift_k(fixed) - 1 if "drift" in effects else 0)
    # the creep's lags at rest at a level shared by the records (module creep): one further
    # coefficient per lag, g_i s_i
    start = fixed.get("creep_start") if "creep" in effects else None
    k += len(nominal.params["creep_taus"]) if start == "common" else 0
    # a creep counted from each record's start: a level per validate record (module creep),
    # unless a drift's levels are there already
    k += creep_levels(effects, fixed)
    if scaled or fixed.get("rate_family") == SCALED:  # tau, S and G, no gains (module rate)
        k -= RATE_BANDS - 1
    # held: one point, no search; its play rows' Gram formed as a streamed refit forms it
    # (no delayed Gram from the undelayed rows', _first_grams), so the two equal to the bit
    static: dict = {"train": TrainRecords(train), "held": held}
    # a mode search filters every column at every point: there, the leading columns only (not
    # for the rate filter: with 12 columns it chose 17 ms for a 20 ms truth_alt rate, which
    # then left a spurious second effect)
    lti_trace: list = []
    positions: list = []  # train BIC of the dynamics after and before the hysteresis
    # the dynamics held (a base mode, or a filter before the hysteresis: module wiener)
    dyn_fixed = "fn" in fixed or "wiener" in fixed
    ncols = SEARCH_COLUMNS if "dynamics" in effects and not dyn_fixed and not search_all \
        else None

    full, train = train, _screen(train, effects, fixed)  # the searches on the screen
    tried: list = []  # (train RSS, grid point) of the first search, for the confirmation

    def search(points, best=None):
        # the points are independent fits: idle threads of the diagnosis' pool may take some
        # (module threads); the best is then taken in the points' order, as on one thread
        fits = helped_map(lambda p: _fit(name, k, _combo_features(effects, p, nominal, static,
                                                                  ncols), train, p), points)
        for p, (model, rss) in zip(points, fits, strict=True):
            tried.append((rss, p))
            if best is None or rss < best[1]:
                best = (model, rss)
        return best

    fmax = MAX_MODE_NYQUIST * 0.5 / train[0].dt  # a sampled mode must stay below Nyquist
    # the base mode's polish: at least one period within the shortest train record (slower is
    # a trend, and near-singular: a pair fit ran to 1e-6 Hz and its least squares failed)
    fmin = 1.0 / min(s.t[-1] - s.t[0] for s in train)
    dgrid = delay_grid(train[0].dt)
    grids: list[list[dict]] = []
    for e in effects:
        if e == "dynamics":
            fgrid = [f for f in MODE_HZ if f <= fmax] or [fmax]
            grids.append([{"wiener": fixed["wiener"]}] if "wiener" in fixed else
                         [{"fn": fixed["fn"], "zeta": fixed["zeta"],
                           "lti": fixed.get("lti", ())}] if "fn" in fixed else
                         [{"fn": f, "zeta": z} for f in fgrid for z in MODE_DAMPING] +
                         [{"fn": f, "zeta": MODE_HEAVY[1]} for f in MODE_HEAVY[0] if f <= fmax])
        elif e == "creep":  # the start: a variant chosen on validate (module creep)
            grids.append([{"creep_start": start}] if start == "common" else
                         [{"creep_start": start, "creep_levels": fixed["creep_levels"]}]
                         if start == "record" else [{}])
        elif e == "delay":
            grids.append([{"d": fixed["d"]}] if "d" in fixed else
                         [{"d": int(d)} for d in dgrid])
        elif e == "drift" and fixed.get("clock") == "settle":  # T searched below
            tgrid = settle_grid(train)
            grids.append([{"clock": "settle", "settle_t0": settle_start(train),
                           "settle_tau": fixed.get("settle_tau",
                                                   float(tgrid[SETTLE_POINTS // 2])),
                           **({"levels": fixed["levels"]} if "levels" in fixed else {})}])
        elif e == "drift":  # the records' levels only on validate: variants chosen there
            grids.append([{k_: fixed[k_] for k_ in ("clock", "levels") if k_ in fixed}]
                         if "clock" in fixed else
                         [{"clock": c} for c in DRIFT_CLOCKS if c not in ("levels", "settle")])
        elif e == "rate":  # the filter is searched after the other grids (below)
            grids.append([{k_: fixed.get(k_) for k_ in RATE_KEYS}] if "rate_tau" in fixed else
                         [{"rate_family": f, "rate_tau": RATE_TAU_START, "rate_saturation": None}
                          for f in RATE_FAMILIES])
    points = [{}]
    for g in grids:  # Cartesian product of the nonlinear grids (at most dynamics x delay)
        points = [{**a, **b} for a in points for b in g]
    searched = None if memo is None else memo.get("searched")
    if searched is not None:  # the same search made before (_order_memo)
        best, grid_tried = searched
    elif held and len(points) == 1:  # one point, fitted below with every play column
        best, grid_tried = (Model(name, k, None, None, points[0]), None), []
    else:
        best = search(points)
        grid_tried = sorted(tried, key=lambda rp: rp[0])[:SCREEN_CONFIRM]
        if "rate" in effects and "rate_tau" not in fixed:
            # the rate family and filter (the other grid parameters held): the filter's grid,
            # then geometric steps around the best positive time constant
            best = search([{**best[0].params, "rate_family": f, "rate_tau": tau}
                           for f in RATE_FAMILIES for tau in RATE_TAUS if tau != RATE_TAU_START],
                          best)
            for step in RATE_TAU_REFINE:
                tau = best[0].params["rate_tau"]
                if tau > 0:
                    best = search([{**best[0].params, "rate_tau": tau * f}
                                   for f in (1 / step, step)], best)
            # the saturation of the filtered rate at that filter (module rate), then steps
            best = search([{**best[0].params, "rate_saturation": s_} for s_ in RATE_SATURATIONS
                           if s_ is not None], best)
            for _ in range(RATE_POLISH_ROUNDS):  # then the filter and the saturation in turn
                before, p_ = best[0], best[0].params
                if p_["rate_saturation"] is None:
                    break
                best = search([{**p_, "rate_saturation": p_["rate_saturation"] * f}
                               for f in (1 / RATE_SATURATION_REFINE, RATE_SATURATION_REFINE)]
                              + [{**p_, "rate_tau": p_["rate_tau"] * f}
                                 for f in (1 / RATE_TAU_REFINE[-1], RATE_TAU_REFINE[-1])
                                 if p_["rate_tau"] > 0], best)
                if best[0] is before:
                    break
            if scaled:
                best = _search_scaled(search, best[0].params)
        if best[0].params.get("clock") == "settle" and "settle_tau" not in fixed:
            # the settling time constant (the other grid parameters held): its grid, then
            # continuously in log T between the grid neighbours of the best point
            tgrid, tau0 = settle_grid(train), best[0].params["settle_tau"]
            best = search([{**best[0].params, "settle_tau": float(x)} for x in tgrid if x != tau0],
                          best)
            base, step = dict(best[0].params), np.log(tgrid[1] / tgrid[0])
            r = minimize_scalar(lambda x: _fit(name, k, _combo_features(
                effects, {**base, "settle_tau": float(np.exp(x))}, nominal, static, ncols),
                train)[1], bounds=(np.log(base["settle_tau"]) - step,
                                   np.log(base["settle_tau"]) + step),
                method="bounded", options={"xatol": 0.01})
            if r.fun < best[1]:
                best = search([{**base, "settle_tau": float(np.exp(r.x))}], best)
        if "delay" in effects and "d" not in fixed:  # every sample between the grid neighbours
            i = int(np.searchsorted(dgrid, best[0].params["d"]))
            lo, hi = dgrid[max(i - 1, 0)], dgrid[min(i + 1, dgrid.size - 1)]
            best = search([{**best[0].params, "d": int(d)} for d in range(lo, hi + 1)
                           if d not in dgrid], best)
            d0 = best[0].params["d"]  # then a fraction of a sample on either side
            best = search([{**best[0].params, "d": d0 + f} for f in (-0.75, -0.5, -0.25, 0.25,
                                                                      0.5, 0.75) if d0 + f >= 0],
                          best)
            # and continuously between the quarter-sample neighbours: an eighth of a sample off
            # leaves several noise floors on fast input
            base, d1 = dict(best[0].params), float(best[0].params["d"])
            r = minimize_scalar(lambda d: _fit(name, k, _combo_features(
                effects, {**base, "d": float(d)}, nominal, static, ncols), train)[1],
                bounds=(max(d1 - 0.25, 0.0), d1 + 0.25), method="bounded",
                options={"xatol": 0.01})
            if r.fun < best[1]:
                best = search([{**base, "d": float(r.x)}], best)
        if "dynamics" in effects and not dyn_fixed:
            # refine the mode around the grid optimum, then polish it continuously (a light
            # mode's resonance is narrower than the grid)
            f0, z0 = best[0].params["fn"], best[0].params["zeta"]
            best = search([{**best[0].params, "fn": float(f), "zeta": float(z)}
                           for f in f0 * np.linspace(0.88, 1.12, 9)
                           for z in z0 * np.array([0.5, 0.75, 1.0, 1.35, 2.0])
                           if f <= fmax and MODE_DAMPING_RANGE[0] <= z <= MODE_DAMPING_RANGE[1]],
                          best)
            base = dict(best[0].params)

            def cost(x):
                p = {**base, "fn": float(np.exp(x[0])), "zeta": float(np.exp(x[1]))}
                # a mode far below the sample rate is a near-singular pole (its columns overflow
                # the least squares: density seed 0, creep + dynamics, wandered to 1e-6 Hz)
                if not fmin <= p["fn"] <= fmax or \
                        not MODE_DAMPING_RANGE[0] <= p["zeta"] <= MODE_DAMPING_RANGE[1]:
                    return np.inf
                return _fit(name, k, _combo_features(effects, p, nominal, static, ncols),
                            train, p)[1]

            x0 = np.log([base["fn"], base["zeta"]])
            r = nelder_mead(cost, x0, initial_simplex=[x0, x0 + [0.03, 0], x0 + [0, 0.2]],
                            xatol=1e-4, fatol=1e-9 * best[1], maxfev=60)
            if r.fun < best[1]:
                best = search([{**base, "fn": float(np.exp(r.x[0])),
                                "zeta": float(np.exp(r.x[1]))}], best)
        if memo is not None:
            memo["searched"] = (best, grid_tried)
    if "dynamics" in effects and "wiener" not in fixed and not held:
        # the order of the linear part: further modes, a low-pass, a direct term (module lti);
        # chosen again beside effects added later (the base mode held, no polish)
        p0 = {**best[0].params, "lti": ()}

        def lti_point(fn, zeta, els):
            return {**p0, "fn": float(fn), "zeta": float(zeta), "lti": tuple(els)}

        def lti_regressors(fn, zeta, els):
            feats = _combo_features(effects, lti_point(fn, zeta, els), nominal, static, ncols)
            return ([_stack_rows(feats.parts(s))[:, s.used].T for s in train],
                    [s.y[s.used] for s in train])

        fn, zeta, elements, lti_trace = select_order(
            lambda fn, zeta, els: search([lti_point(fn, zeta, els)])[1], lti_regressors,
            lambda fn, zeta, el: [_lti_block(s, lti_point(fn, zeta, (el,)), nominal,
                                             static)[s.used, 0] for s in train],
            p0["fn"], p0["zeta"], fmax, MODE_DAMPING_RANGE, polish="fn" not in fixed,
            min_elements=lti_min, memo=None if memo is None else memo.setdefault("order", {}))
        if memo is not None:  # any larger lti_min gives this fit when none was left to add
            memo["elements"] = np.inf if memo["order"].get("exhausted") else len(elements)
        best = search([lti_point(fn, zeta, elements)])
    if train is not full:  # screened: the searched point against the grid's best, whole
        train = full
        best = _confirm(search, k, [best[0].params, *(q for _, q in grid_tried)], train)
    p = best[0].params  # the grid optimum, refitted with every play column
    k_all = k + lti_k(p.get("lti", ()))  # the linear part's further elements count too
    if p.get("wiener"):  # a filter's parameters instead of the base mode's two
        k_all += wiener_k(p["wiener"]) - _combo_k(("dynamics",), nominal)
    model, rss = _fit(name, k_all, _combo_features(effects, p, nominal, static), train, p)
    if effects == ("dynamics",) and not dyn_fixed and all(s.wiener_basis is not None
                                                          for s in train):
        # the linear part before the hysteresis (module wiener), kept on a lower train BIC
        n = sum(s.y[s.used].size for s in train)
        def rss_of(e):  # with every play column
            return _fit(name, k, _combo_features(effects, {"wiener": e}, nominal, static),
                        train, {"wiener": e})[1]
        # the low-pass (an amplifier's bandwidth) with every play column: the leading ones
        # (principal directions of the unfiltered plays) misfit a filtered input's hysteresis
        # ~200x the noise; the mode with the leading columns, as the modes after the
        # hysteresis (with every column a light mode before the plays took the misfit of a
        # quadratic output map on a staircase scan: blind seed 9639), then scored with every
        # column; the lower train BIC of the two kinds kept
        lows = search_filter(rss_of, fmax, n, rss_to_beat=rss, kinds=LOWPASS_KINDS)
        mode = search_filter(lambda e: search([{"wiener": e}])[1], fmax, n,
                             rss_to_beat=best[1], kinds=("mode",))
        mode = (mode[0], rss_of(mode[0]), mode[2])
        els, wrss, kw = min((lows, mode), key=lambda o: n * np.log(max(o[1], 1e-300))
                            + o[2] * np.log(n))
        delta = n * np.log(max(wrss, 1e-300) / max(rss, 1e-300)) + (kw - k_all) * np.log(n)
        positions = [{"position": "after", "train_bic": 0.0},
                     {"position": "before", "structure": [els[0][0]], "train_bic": float(delta)}]
        if delta < 0:  # kept: polished with every play column
            els, _ = polish_filter(rss_of, els, wrss, fmax)  # the RSS does not depend on k
            p, k_all, lti_trace = {"wiener": els}, kw, []
            model = _fit(name, kw, _combo_features(effects, p, nominal, static), train, p)[0]
    if "asymmetry" in effects:
        # the static map acts on the hysteresis output, not on the nominal (which took part
        # of the asymmetry into its weights): rebuild the reference h0 from the hysteresis
        # part of the joint fit and refit (a fixed-point iteration; measured on an
        # exponential map, the validate RMS drops 3 to 10 times in two steps)
        for _ in range(ASYMMETRY_ITERATIONS):
            ref = _hysteresis_reference(model, train, nominal)
            model = _fit(name, k_all, _combo_features(
                effects, p, ref, {"train": static["train"], "held": held}), train, p)[0]
            model.reference = ref
    model.grid = dict(model.params)
    model.params = _describe(effects, model, nominal, len(static["train"]))
    if lti_trace:
        model.params["dynamics_structures_tried"] = lti_trace
    if positions:
        model.params["dynamics_positions_tried"] = positions
    in_train = static["train"]
    if "drift" in effects and has_levels(p):  # a level per record
        model.params["drift_t0_train"] = float(train[0].t[0])

        def with_level(seg, out):  # a record's own level, out of fold (not for train records)
            return out if seg in in_train else out + out_of_fold_level(seg.y - out, seg.mask)
        model.adjust = with_level
    elif creep_levels(effects, p):  # the creep's level, bounded by its first output's change
        first = {id(full[0]): float(nominal.predict(full[0])[0])}
        model.params["creep_record_reference"] = first[id(full[0])]  # the bound's origin

        def with_creep_level(seg, out):
            if seg in in_train:
                return out
            if id(seg) not in first:
                first[id(seg)] = float(nominal.predict(seg)[0])
            return out + record_level(model.params, first[id(seg)], seg.y - out, seg.mask)
        model.adjust = with_creep_level
    return model


def _screen(train, effects: tuple[str, ...], fixed: dict) -> list:
    """The train records the searches of :func:`_fit_combo` run on: the first ``SCREEN_SAMPLES``
    samples of each (:func:`head_segment`) when a record is longer and a mode or a delay is
    searched (not with the rate's or the drift's per-record columns, nor a filter before the
    hysteresis held); else ``train`` itself. A search costs a pass over the screen per point;
    its result is confirmed on the whole records (:func:`_confirm`)."""
    searched = ("dynamics" in effects and not {"fn", "wiener"} & set(fixed)) or \
        ("delay" in effects and "d" not in fixed)
    if not searched or {"rate", "drift"} & set(effects) or "wiener" in fixed or \
            all(s.y.size <= SCREEN_SAMPLES for s in train):
        return train
    return [head_segment(s, SCREEN_SAMPLES) for s in train]


def head_segment(s: Segment, m: int) -> Segment:
    """The first ``m`` samples of ``s`` (its play rows copied; no rate or Wiener basis).

    Parameters
    ----------
    s : Segment
        The record.
    m : int
        Samples kept.

    Returns
    -------
    Segment
        Samples ``0..m-1`` of ``t``, ``v``, ``y``, the play rows and the mask; every filter of
        the candidates starts from the same state on it as on ``s``, so its columns are the
        first ``m`` samples of ``s``'s.

    Examples
    --------
    >>> seg = make_segment(np.arange(4) * 1e-3, np.array([0.0, 1.0, 0.5, 0.0]), np.zeros(4),
    ...                    [0.5])
    >>> head_segment(seg, 2).Z.tolist()
    [[0.0], [0.5]]
    """
    rows = np.array(s.play_rows(offset=True)[:, :m], order="C")
    return segment_of_rows(s.t[:m], s.v[:m], s.y[:m], rows,
                           None if s.mask is None else s.mask[:m])


def _confirm(search, k: int, points: list[dict], train) -> tuple:
    """The point of ``points`` (the screen's searched optimum, then its best grid points)
    with the lowest BIC on the whole ``train`` records (the linear part's elements counted,
    ``lti_k``), as ``search`` returns it: (model, train RSS). One fit per point."""
    n = sum(s.y[s.used].size for s in train)
    best = None
    for p in points:
        model, rss = search([p])
        bic = n * np.log(max(rss, 1e-300)) + (k + lti_k(p.get("lti", ()))) * np.log(n)
        if best is None or bic < best[0]:
            best = (bic, model, rss)
    return best[1], best[2]


def _hysteresis_reference(model: Model, train, nominal: Model) -> Model:
    """The hysteresis part ``Z w + c`` of a joint fit as a reference model (``center`` and
    ``half_range`` of its train output, the nominal's other ``params``)."""
    q = n_plays(train[0])
    ref = Model("reference", 0, base_features, model.coef[:q + 1].copy())
    h = np.concatenate([ref.predict(s) for s in train])
    ref.params = {**nominal.params, "center": float(np.mean(h)),
                  "half_range": max(float(np.ptp(h)) / 2, 1e-12)}
    return ref


def _search_scaled(search, start: dict):
    """The rate's exact shape (family ``SCALED``, module rate) from the first-order optimum
    ``start``: its filter (at least ``RATE_TAUS[1]``), ``G`` on ``RATE_GROWTHS`` times ``S``
    at half, once and twice the first-order ``S`` (1 when linear), then ``G``, ``S`` and the
    filter together by a Nelder-Mead polish in their logarithms (``G`` and ``S`` trade
    against each other along a valley that steps of one at a time do not follow), the filter
    at most ``RATE_TAU_MAX`` (what the first-order search reaches, module rate)."""
    s0 = start["rate_saturation"] or 1.0
    p0 = {**start, "rate_family": SCALED, "rate_tau": max(start["rate_tau"], RATE_TAUS[1])}
    best = search([{**p0, "rate_growth": g, "rate_saturation": s0 * f}
                   for g in RATE_GROWTHS for f in (0.5, 1.0, 2.0)])

    def point(x):
        return {**p0, "rate_growth": float(np.exp(x[0])), "rate_saturation": float(np.exp(x[1])),
                "rate_tau": min(float(np.exp(x[2])), RATE_TAU_MAX)}

    q = best[0].params
    x0 = np.log([q["rate_growth"], q["rate_saturation"], q["rate_tau"]])
    step = np.log(RATE_GROWTH_REFINE)
    r = nelder_mead(lambda x: search([point(x)])[1], x0,
                    initial_simplex=[x0, x0 + [step, 0, 0], x0 + [0, step, 0],
                                     x0 + [0, 0, step]],
                    xatol=1e-3, fatol=1e-9 * best[1], maxfev=RATE_SCALED_EVALS)
    return search([point(r.x)], best) if r.fun < best[1] else best


def _combo_k(effects, nominal: Model) -> int:
    return sum({"creep": len(nominal.params["creep_taus"]), "dynamics": 2, "delay": 1,
                "asymmetry": 2, "drift": 1, "rate": RATE_BANDS + 2}[e] for e in effects)


class _Parts(tuple):
    """Blocks of rows (:func:`_row_parts`); ``delayed``: ``(Z0, d)`` when the first block is
    ``Z0`` delayed by ``d`` samples (:func:`_first_grams`), else None; ``first_key``: what the
    first block is (the key of its terms in :func:`_first_grams`), or None."""

    delayed = None
    first_key = None


def _combo_features(effects, p, nominal: Model, static: dict, ncols: int | None = None):
    """Feature builder for the effects with grid parameters ``p``; the columns that do not
    depend on ``p`` (offset, creep, asymmetry) are memoised per segment in ``static`` (the rate
    columns per filter in the segment's ``rate_basis``). The regressors are built as two blocks
    of rows (``feats.parts(s)``: the play rows, then the others; :func:`_row_parts`);
    ``feats(s)`` is the transpose of their stack."""

    start = p.get("creep_start") if "creep" in effects else None
    common = start == "common"

    def static_rows(s: Segment) -> np.ndarray:
        key = (start, creep_levels(effects, p), id(s)) if start in ("common", "record") \
            else id(s)
        # a delay delays the input of everything the hysteresis drives: h0 too (the rows of
        # the latest delay kept per segment: a delay search tries many)
        d = p["d"] if "delay" in effects else 0
        kept = static.get(key)
        if kept is None or kept[2] != d:
            out = [np.ones(s.t.size)]
            h0 = shift(_reference(s, nominal, static), d) if d else nominal.predict(s)
            taus = nominal.params["creep_taus"] if "creep" in effects else ()
            if common:  # lags at rest at levels shared by the records (module creep)
                out += [lag(h0, tau, s.dt, 0.0) - h0 for tau in taus]
                out += list(start_columns(np.arange(h0.size), s.dt, taus,
                                          first_scored(s.mask)))
            elif taus:
                # the stage's memory at the start unknown (a start-up mask): the creep's
                # too; its lags start at the measured first output, not at h0[0]
                y0 = None if s.mask is None else float(s.y[0])
                # "record": counted from the record's start, less the lags' start
                less = (float(h0[0]) if y0 is None else y0) if start == "record" else 0.0
                out += [lag(h0, tau, s.dt, y0) - h0 - less for tau in taus]
                if creep_levels(effects, p):  # a level per train record after the first
                    out += list(level_rows(static["train"].index(s), len(static["train"]),
                                           s.t.size))
            if "asymmetry" in effects:
                u = (h0 - nominal.params["center"]) / nominal.params["half_range"]
                out += [u**2, u**3]
            kept = static[key] = (s, np.vstack(out), d)  # s alive: its id stays unique
        return kept[1]

    def rows(s: Segment) -> tuple[np.ndarray, np.ndarray]:  # the play rows, then the others
        Z = s.play_rows(ncols)
        what: tuple = ("plays", ncols)  # what Z is: the key of its Gram (_first_grams)
        scaled = "rate" in effects and p["rate_family"] == SCALED
        if scaled:  # the exact shape's plays in place of the nominal ones (module rate)
            Z = s.rate_basis.scaled_rows(p["rate_tau"], p["rate_saturation"], p["rate_growth"])
            what = ("scaled", p["rate_tau"], p["rate_saturation"], p["rate_growth"])
        if p.get("wiener"):  # the linear part before the hysteresis (module wiener)
            Z = s.wiener_basis.columns(p["wiener"], ncols).T  # rows, kept C-contiguous
            what = ("wiener", p["wiener"], ncols)
        elif "dynamics" in effects:  # filter the play rows
            last = static.get(("mode", id(s), ncols))  # the last mode filtered, for a delay
            if last is None or last[0] != (p["fn"], p["zeta"]):  # search at a fixed mode
                last = ((p["fn"], p["zeta"]), mode_rows(Z, p["fn"], p["zeta"], s.dt), s)
                static[("mode", id(s), ncols)] = last
            Z = last[1]
            what = (*what, "mode", p["fn"], p["zeta"])
        delayed = None
        if "delay" in effects:
            delayed, Z = (None if static.get("held") else (Z, p["d"])), shift(Z, p["d"], axis=-1)
            what = (*what, "held" if delayed is None else "delayed", p["d"])
        parts = [Z, static_rows(s)]
        if p.get("lti"):  # the extra elements of the linear part
            parts.append(_lti_block(s, p, nominal, static).T)
        if "rate" in effects and not scaled:
            which = (p["rate_tau"], p["rate_family"], p.get("rate_saturation"))
            key = ("rate", id(s))
            kept = static.get(key)  # the latest filter only, per segment; read once: two
            if kept is None or kept[0] != which:  # points of a search may run on two threads
                kept = static[key] = (which, transposed(s.rate_basis.columns(*which)), s)
            parts.append(kept[1])
        if "drift" in effects:  # the trend column last
            parts.append(drift_columns(s.t, p, static["train"].index(s),
                                       len(static["train"])).T)
        # the other rows as they are when there is one block (the static rows, C-contiguous:
        # a mode or delay search then copies nothing of them per point)
        out = _Parts((Z, parts[1] if len(parts) == 2 else _stack_rows(parts[1:])))
        out.delayed = delayed  # the play rows before the delay (their Gram: _first_grams)
        out.first_key = _exact(what)
        return out

    def feats(s: Segment) -> np.ndarray:
        return _stack_rows(rows(s)).T

    def release() -> None:  # drop the memoised columns (rebuilt on the next use)
        for key in [key for key in static if key not in ("train", "held")]:
            del static[key]

    def parts_chunks(s: Segment):  # a streamed segment's blocks, chunk by chunk (held p)
        return combo_chunks(effects, p, nominal, s, static["train"].index(s),
                            len(static["train"]))

    feats.parts = rows
    feats.recipe = (nominal, _exact((tuple(effects), p, ncols)))  # names the regressors (_fit_memo)
    feats.parts_chunks = parts_chunks
    feats.stacked_times = lambda s, coef: stacked_times(parts_chunks, feats, s, coef)
    feats.release = release
    return feats


_LTI_LOCK = threading.Lock()  # the element columns' memo of _lti_block


def _reference(s: Segment, nominal: Model, static: dict) -> np.ndarray:
    """``h0``, the reference hysteresis output ``nominal.predict(s)``, memoised per segment in
    ``static``."""
    key = ("h0", id(s))
    if key not in static:
        static[key] = (s, nominal.predict(s))
    return static[key][1]


def _lti_block(s: Segment, p: dict, nominal: Model, static: dict) -> np.ndarray:
    """The columns ``(E_j - M_1)[h0]`` of the elements ``p["lti"]`` (delayed by ``p["d"]`` when
    the delay is fitted too); ``h0`` is memoised per segment in ``static``."""
    h0 = _reference(s, nominal, static)
    base = static.get(("M1[h0]", id(s)))  # the base mode's response, for the last mode only
    if base is None or base[0] != (p["fn"], p["zeta"]):
        base = ((p["fn"], p["zeta"]), mode(h0, p["fn"], p["zeta"], s.dt))
        static[("M1[h0]", id(s))] = base
    # each element's column memoised for the last base mode (the order selection tries many
    # sets of elements around one mode; a column does not depend on the others)
    known = static.get(("lti", id(s)))
    if known is None or known[0] != base[0]:
        known = static[("lti", id(s))] = (base[0], {})
    cols = np.empty((h0.size, len(p["lti"])))
    for j, el in enumerate(p["lti"]):
        key = tuple(el)
        with _LTI_LOCK:  # the points of one search may run on two threads (module threads)
            col = known[1].pop(key, None)  # reinserted last: the least recently used goes first
        if col is None:
            col = lti_columns(h0, p["fn"], p["zeta"], (el,), s.dt, base=base[1])[:, 0]
        cols[:, j] = col
        with _LTI_LOCK:
            known[1][key] = col
            while len(known[1]) > LTI_MEMO:
                del known[1][next(iter(known[1]))]
    return shift(cols, p["d"]) if "d" in p else cols


def _start_levels(gains: np.ndarray, terms: np.ndarray) -> list:
    """The common start's levels ``s_i`` from the fitted ``g_i`` and ``g_i s_i`` (module
    creep); a lag of gain 0 has no start (its level 0: the term is then lost, never met on a
    least-squares fit)."""
    return [float(b / g) if g != 0 else 0.0 for g, b in zip(gains, terms, strict=True)]


def _describe(effects, model: Model, nominal: Model, n_train: int = 1) -> dict:
    out: dict = {}
    n = nominal.coef.size - 1
    extra = model.coef[n + 1:]
    i = 0
    for e in (e for e in ("creep", "asymmetry", "rate") if e in effects):  # column order
        if e == "creep":
            taus = nominal.params["creep_taus"]
            gains = extra[i:i + len(taus)]
            out["creep_lag_gains"] = gains.tolist()
            out["creep_time_constants_s"] = list(taus)
            i += len(taus)
            if model.params.get("creep_start") == "record":  # counted from each start
                out["creep_start"] = "record"
                # its levels of the train records after the first (their own columns)
                i += max(n_train - 1, 0) if creep_levels(effects, model.params) else 0
            elif model.params.get("creep_start") == "common":  # g_i s_i, then the levels s_i
                out["creep_start"] = "common"
                out["creep_start_levels"] = _start_levels(gains, extra[i:i + len(taus)])
                i += len(taus)
        elif e == "asymmetry":
            out["asymmetry_quadratic"], out["asymmetry_cubic"] = extra[i:i + 2].tolist()
            i += 2
        elif e == "rate":
            scaled = model.params["rate_family"] == SCALED  # one gain of 1 (module rate)
            out["rate_gains"] = [1.0] if scaled else extra[i:i + RATE_BANDS].tolist()
            out["rate_family"] = model.params["rate_family"]
            out["rate_time_constant_s"] = model.params["rate_tau"]
            out["rate_saturation"] = model.params.get("rate_saturation")
            if scaled:
                out["rate_growth"] = model.params["rate_growth"]
            i += 0 if scaled else RATE_BANDS
    if "drift" in effects and model.params["clock"] == "settle":  # on the shared clock
        out.update({"drift_per_s": 0.0, "drift_clock": "absolute",
                    "drift_variant": "settle_levels" if "levels" in model.params else "settle",
                    "drift_settling": float(model.coef[-1]),
                    "drift_settling_time_s": float(model.params["settle_tau"]),
                    "drift_settling_start_s": float(model.params["settle_t0"])})
    elif "drift" in effects:
        out["drift_per_s"] = float(model.coef[-1])
        clock = model.params["clock"]  # "levels": the clock is read from the levels later
        out["drift_clock"] = "record" if clock == "levels" else clock
        out["drift_variant"] = "levels" if clock == "levels" else "trend"
    if "wiener" in model.params:
        out.update(describe_wiener(model.params["wiener"]))
    if "fn" in model.params:
        out["dynamics_position"] = "after"
        out["mode_hz"], out["mode_damping"] = model.params["fn"], model.params["zeta"]
        lti = model.params.get("lti", ())
        out.update(describe_lti(model.params["fn"], model.params["zeta"], lti,
                                extra[i:i + len(lti)]))
    if "d" in model.params:
        out["delay_samples"] = model.params["d"]
    return out
