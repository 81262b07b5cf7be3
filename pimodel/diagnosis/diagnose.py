"""The sim-to-real gap diagnosis: nominal PI model, where the residual lies, which unmodelled
effect explains it, how far the gap shrinks on held-out records, and what stays unexplained.

Train records fit every model; validate records only score. The nominal model is the PI operator
in the conventional parametrisation (plays on a uniform radius grid over half the input range,
weights and an output offset by least squares, linear in its parameters). The grid is refined
(20, 40, 80 plays) and the size with the lowest train BIC is kept, so the nominal fits clean
hysteresis whose radii lie off a coarse grid down to the noise. The plays start at rest at
``v[0]``, or at 0 when that has the lower BIC over train and validate together (validate's
after a gain and an offset per record, :func:`_affine_validate_bic`); records that travel
further than half the range from ``v[0]`` also try the grid extended to that travel, kept when
validate agrees (issue 33, :func:`_nominal`); train records of few samples also try grids
topped below half the range, likewise kept when validate agrees (issue 28,
:func:`_topped_grids`), and one play above half the range at a radius searched on train
(:func:`_one_above`). A plain least-squares PI fit is reported beside it as a check
(``nominal["baseline"]``), with a warning when the nominal is worse. Each candidate effect is
refitted *jointly* with the hysteresis weights (:mod:`.effects`). Effects are added greedily:
each round fits every remaining candidate on train (on top of those already chosen) and scores
it on validate with ``BIC = N ln(RSS/N) + k ln N``; the best is kept if it lowers the BIC by
more than 10, cuts the validate RMS by at least 20 %, and the current RMS is above 1.5 times the
noise floor (:mod:`.noise`: repeated input periods, else a flexible local model). When no single
effect passes in the first round, every pair is fitted jointly and the best pair kept on the
same terms (two effects can mask each other). A further effect beside those chosen must also
pass, on the same terms, against each chosen effect's own model refined one step (a further
creep lag, a further element of the linear part of ``dynamics``: a low-pass or a mode), so the
misfit of one effect is not named as another (issue 28). Beside a chosen ``rate``, a ``drift``
that lowers the BIC but cuts the RMS by less also passes when it passes with the rate's own
misfit on validate set aside (:mod:`.misfit`: the rate's extrapolation to faster validate input
can leave an error no other effect cuts; a yardstick, never the model kept). After each
accepted effect, a lag chosen earlier (``dynamics`` or ``delay``, one of them) is searched
again beside it and the other lag tried in its place, the lowest validate BIC kept
(:func:`_research_lag`). Then the choice is
revised on the same terms: a chosen effect is swapped for an unchosen one while that passes, and
an effect that no longer passes against the combination without it is dropped (an effect chosen
early can stand in for one that only passes beside a later one). Last, a chosen ``dynamics``
that acts as a pure delay on the records (gain within 10 % of 1 over the lower quarter of the
band, :mod:`.delaylike`) gives way to ``delay`` when the delay fits validate within 10 % in its
place, and a chosen ``creep`` gives way to ``drift`` when the drift fits validate within 10 % in
its place and the creep explains less than half a noise floor beyond it. When the path so
chosen leaves a gap ``unexplained``, the rounds are run again forced to
start from each of the next ``ALT_STARTS`` candidates (alone or in a pair with each
other effect), and the path with the lowest validate BIC is kept: a first effect can stand
in for two others that pass only together (a broad lag for creep and rate-dependent
hysteresis). When the path leaves more than ``PAIR_LOOK`` noise floors without a gap
unexplained, the rounds are run again with every pair of the effects it did not name tried in
the first round, and that path is kept when it passes against the first (and against its
effects refined one step) and does not merely add effects to it: a delay stood in for a creep
and an asymmetry that pass only together.
The ``dynamics`` candidate is a linear system after the hysteresis (:mod:`.lti`) or, where the
train BIC says so, a filter before it (:mod:`.wiener`). The drift's variant (its clock, or a
level per record, :mod:`.drift`) is chosen on validate for every combination; the creep's start
(its lags at rest at each record's first output, or at levels shared by the records: a stage
parked between records, :mod:`.creep`) is chosen on validate where the creep enters a
combination and held for the fits built on the model that holds it.

Verdict: ``["none"]`` when no effect is accepted and the validate gap is within 2 times the
noise floor; the accepted effects; and ``"unexplained"`` (alone or after the effects) when the
gap after the best combination stays above 2 times the noise floor and its excess over the noise
is more than 10 % of the gap's energy before. ``unexplained`` gives that share and where the
remaining residual lies. ``alternatives`` lists effects that alone explain the gap within 10 %
of the validate RMS of the first chosen one: the records cannot tell them apart (for example a
delay and rate-dependent hysteresis under a single-frequency sine). ``interchangeable`` lists
each named effect whose usual stand-in (``delay`` and ``dynamics``, ``creep`` and ``drift``) in
its place, the other effects held, fits validate within 10 % as well (:func:`_interchangeable`).
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from ..identification.branches import find_reversals
from ..records import Record
from .chunked import ChunkedQR, NormalEquations
from .coverage import coverage, informed_radii, span_and_reach
from .creep import creep_law, creep_levels, creep_starts, start_hint
from .delaylike import is_delay_like
from .drift import DRIFT_KEYS, drift_variants, level_report, settle_bow
from .effects import (
    EFFECTS,
    SCREEN_SAMPLES,
    Model,
    Segment,
    base_features,
    fit_effect,
    fitted_in,
    make_segment,
    nominal_params,
    play_chunks,
    segment_of_rows,
)
from .gain import gain_note, record_gains
from .misfit import rate_correction
from .noise import measure_noise_floor
from .rate import RATE_KEYS, RateBasis, rate_shapes
from .streamed import attach_plays, streamable
from .threads import OnceCache, Pool, default_workers, lend
from .where import residual_breakdown, startup_length
from .wiener import WienerBasis, position_hint

__all__ = [
    "diagnose",
    "DiagnosisReport",
]

GRID_SIZES = (20, 40, 80)  # nominal radius grids tried; the lowest train BIC is kept
GRID_TOPS = (0.9, 0.8)  # with few train samples (_topped_grids), grids topped at these
# fractions of half the train range are tried too, kept when validate agrees
FEW_SAMPLES_PER_PLAY = 50  # few: fewer train samples than this per play of the finest grid
ABOVE_POINTS = 40  # with few train samples, radii tried for one play above half the range
ABOVE_MARGIN = 10.0  # ... kept when it lowers the train BIC by this much (and validate agrees)
BASELINE_PLAYS = 60  # plays of the plain least-squares baseline (0 to max |v| of train)
NONNEG_PLAYS = True  # the nominal's play weights of radius > 0 held >= 0 when validate agrees
PROJECTED = 32  # principal directions of the play outputs kept beside the nominal's weights
SPANNED = 1e-12  # a principal direction of less variance (this share of the largest) is not kept
BASELINE_WARN = 1.1  # warn when the nominal's validate RMS exceeds this factor of the baseline's
MIN_BIC_DROP = 10.0  # an effect must lower the validate BIC by more than this
MIN_RMS_CUT = 0.20  # ... and cut the validate RMS by at least this fraction
NOISE_STOP = 1.5  # no further effect once the validate RMS is within this factor of the noise
SLOW_DEGREE = 3  # the compression's check beside a slow drift: a cubic in time (_slow_rss)
SETTLE_BOW_FLOORS = 2.0  # a settling is named only when its bow exceeds this many noise floors
UNEXPLAINED_FACTOR = 2.0  # a gap above this factor of the noise floor is not "none"
UNEXPLAINED_SHARE = 0.10  # ... and is "unexplained" when its excess is this share of the gap
DYNAMICS_KEYS = ("fn", "zeta", "lti")  # grid keys of dynamics after the hysteresis
LAG_EFFECTS = ("dynamics", "delay")  # two names for one lag: re-decided beside later effects
LAG_KEYS = (*DYNAMICS_KEYS, "wiener", "d")  # their grid keys
ALT_STARTS = 2  # greedy paths from the next candidates tried when a gap is left unexplained
PAIR_LOOK = 5.0  # a choice leaving more than this many noise floors: every pair tried first
ALTERNATIVE_RMS = 1.1  # an effect alone within 10 % of the first chosen one's validate RMS
STAND_INS = {"delay": ("dynamics", LAG_KEYS), "dynamics": ("delay", LAG_KEYS),
             "creep": ("drift", ("creep_start", "creep_levels")),
             "drift": ("creep", DRIFT_KEYS)}  # effect: the one in its place, the keys it frees
DRIFT_LIKE_CREEP = 0.5  # a chosen creep gives way to a drift in its place fitting within
# ALTERNATIVE_RMS when what it explains beyond that drift is under this many noise floors (RMS)
INITIAL_STATES = ("auto", "rest", "unknown")
START_POST_GAIN = 3.0  # "auto": unknown when the start-up fitted as at rest makes the nominal
# mispredict validate after its start-up this many times worse (mean square) than without it,
START_EXCESS = 10.0  # ... or leaves validate's start-up with this many times the mean squared
# misfit of the rest of the record (_auto_start)
BRANCH_TRAVEL = 0.05  # "auto": a reversal after the start-up counts when the input moves back
# this share of the record's input range; with at most one in every train record, what follows
# the start-up is one branch, which a PI fits whatever the stage: no test of the start
START_SLOW = ("creep", "drift")  # "auto": effects that a wrong start's misfit in the start-ups
# can be taken for: named from rest, the diagnosis without the start-ups may be made too and
# compared (_second_look, _final_start)
START_SLOW_EXCESS = 2.0  # ... by a full search when the rest nominal misfits validate's start-ups
# at least this many times as densely (mean square) as the rest of validate (a ratio near 1,
# as residuals spread evenly give, is no evidence either way; blind gain change s1 at 1.006: the
# full search without the start-ups took 182 s CPU, capped 9 s, the same verdict as from rest)
START_SWAP = 1.25  # ... kept too when it names other effects, no more of them (unexplained
# counted), and the rest one's mean squared misfit after the start-ups exceeds this many times
# its own (_final_start: preisach_stage drift on each record's clock read as creep from rest)
EFFECT_SIGNATURES = {
    "creep": ("hold after a step (after 50 ms)", "< 1 Hz"),
    "drift": ("late in the record (last third)", "< 1 Hz"),
    "dynamics": ("near a reversal (travel < 10 % of range)", "> 1 kHz"),
    "delay": ("fast input (top quarter of |dv/dt|)", "10-100 Hz"),
    "asymmetry": ("input extremes (outer 20 % of range)", "1-10 Hz"),
    "rate": ("fast input (top quarter of |dv/dt|)", "1-10 Hz"),
}


@dataclass
class DiagnosisReport:
    """Result of :func:`diagnose`; ``to_json()`` gives nominal, where, candidates, verdict.

    Parameters
    ----------
    nominal : dict
        The nominal PI model: its grid, parameters and train/validate errors, and
        ``baseline``: the plain least-squares PI fit it is checked against (``BASELINE_PLAYS``
        radii uniform from 0 to the train input's largest magnitude, plays at rest at ``v[0]``,
        one offset; ``kind``, ``plays``, ``max_radius``, ``train`` and ``validate`` errors).
        :func:`diagnose` warns when the nominal's validate RMS exceeds ``BASELINE_WARN`` times
        the baseline's. ``coverage``: which plays each validate record drives on loops that
        train moved only in its start-up or never (:func:`.coverage.coverage`).
    where : dict
        Where the nominal's validate residual lies (:mod:`.where`).
    candidates : list of dict
        Every effect tried, with its fit and scores.
    verdict : dict
        ``effects``, ``gap_before``/``gap_after``, ``shrink``, ``noise_floor``,
        ``unexplained`` (see :func:`diagnose`).
    validate : list of Record
        The validate records.
    before, after : list of numpy.ndarray
        Validate predictions of the nominal and of the chosen model, one per record.
    fitted : dict, optional
        Internals for :meth:`model` (radii, projection, models, dt, initial_state); None in a report
        rebuilt from JSON.

    Examples
    --------
    >>> rep = DiagnosisReport({"bic": 1.0}, {}, [], {"effects": ["none"]}, [], [], [])
    >>> rep.to_json()["verdict"]
    {'effects': ['none']}
    """

    nominal: dict
    where: dict
    candidates: list
    verdict: dict
    validate: list
    before: list
    after: list
    fitted: dict | None = None  # internals for :meth:`model` (radii, projection, models, dt)

    def model(self, augmented: bool = True):
        """The nominal or the augmented model the verdict chose, as one object.

        Parameters
        ----------
        augmented : bool
            True: the model with the effects of ``verdict["effects"]`` (as fitted, jointly with
            the hysteresis weights); False: the nominal PI (+ offset).

        Returns
        -------
        pimodel.diagnosis.model.DiagnosedModel
            With ``simulate(v, t=None)``, ``inverse()``, ``to_dict()``.

        Raises
        ------
        ValueError
            A report without the fitted internals (e.g. rebuilt from JSON).

        Examples
        --------
        >>> from pimodel.stages.pi_stage import excitation, random_truth
        >>> truth = random_truth(["creep"], 0)
        >>> tt, vt = excitation("train", seed=1)
        >>> tv, vv = excitation("validate", seed=2)
        >>> rep = diagnose([truth.record(tt, vt, 1)], [truth.record(tv, vv, 2)])
        >>> rep.model().effects
        ('creep',)
        """
        from .model import DiagnosedModel

        if self.fitted is None:
            raise ValueError("report: no fitted model kept (only reports from diagnose() have "
                             "one)")
        return DiagnosedModel.from_fit(self.fitted, augmented=augmented)

    def to_json(self) -> dict:
        """The report as plain data: nominal, where, candidates and verdict.

        Returns
        -------
        dict
            Keys ``nominal``, ``where``, ``candidates``, ``verdict`` (the validate records and
            predictions are left out).

        Examples
        --------
        >>> rep = DiagnosisReport({"bic": 1.0}, {}, [], {"effects": ["none"]}, [], [], [])
        >>> sorted(rep.to_json())
        ['candidates', 'nominal', 'verdict', 'where']
        """
        return {"nominal": self.nominal, "where": self.where, "candidates": self.candidates,
                "verdict": self.verdict}

    def save_json(self, path) -> Path:
        """Write :meth:`to_json` as JSON to ``path`` (parent folders are created).

        Parameters
        ----------
        path : str or pathlib.Path
            The file to write.

        Returns
        -------
        pathlib.Path
            ``path``.

        Examples
        --------
        >>> import json, tempfile
        >>> from pathlib import Path
        >>> rep = DiagnosisReport({"bic": 1.0}, {}, [], {"effects": ["none"]}, [], [], [])
        >>> with tempfile.TemporaryDirectory() as d:
        ...     json.loads(rep.save_json(Path(d) / "r.json").read_text())["verdict"]
        {'effects': ['none']}
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_json(), indent=2, default=_plain))
        return path


def _plain(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(type(x))


def _residuals(segs: list[Segment], outputs) -> np.ndarray:
    """The residuals ``y[k] - output[k]`` of the fitted samples (``s.used``: a slice or a
    mask) of every segment, in one array (the records' in order): written in place, no other
    column of the records' length."""
    def size(s) -> int:
        u = s.used
        return s.y[u].size if isinstance(u, slice) else int(np.count_nonzero(u))

    sizes = [size(s) for s in segs]
    r = np.empty(sum(sizes))
    pos = 0
    for s, o, m in zip(segs, outputs, sizes, strict=True):
        u = s.used
        if isinstance(u, slice):
            np.subtract(s.y[u], np.asarray(o)[u], out=r[pos:pos + m])
        else:
            r[pos:pos + m] = (s.y - o)[u]
        pos += m
    return r


def _errors(segs: list[Segment], outputs) -> dict:
    """RMS and largest residual of the fitted samples (and as percent of the fitted outputs'
    range), the same numbers as from the concatenated residuals, with one column of residuals
    held (:func:`_residuals`, squared in place) and the range and the largest magnitude taken
    per record (a maximum does not depend on the grouping)."""
    r = _residuals(segs, outputs)
    ys = [s.y[s.used] for s in segs]
    rng = float(np.max([np.max(y) for y in ys]) - np.min([np.min(y) for y in ys])) or 1.0
    mx = max(float(np.max(r)), -float(np.min(r)))  # max |r| without a column of |r|
    rms = float(np.sqrt(np.mean(np.square(r, out=r))))
    return {"rms": rms, "max": mx, "rms_percent": 100 * rms / rng,
            "max_percent": 100 * mx / rng, "range": rng}


def _bic(segs, outputs, k, n: int | None = None) -> float:
    """``N ln(RSS/N) + k ln N`` of the fitted samples; with ``n``: the BIC of ``n`` samples
    whose mean squared residual is that of ``segs`` (a screen standing for whole records)."""
    r = _residuals(segs, outputs)
    n = r.size if n is None else n
    return float(n * np.log(max(np.mean(np.square(r, out=r)), 1e-300)) + k * np.log(n))


def _fitted_samples(records: list[Record], initial_state: str) -> int:
    """The fitted samples of ``records`` (all, or those after the start-up)."""
    return sum(len(r) if (m := _mask(r, initial_state)) is None else int(np.sum(m))
               for r in records)


def _check(records: list[Record], role: str) -> None:
    if not records:
        raise ValueError(f"{role}: at least one record is needed")
    for rec in records:
        if len(rec) < 200:
            raise ValueError(f"{rec.source}: too short ({len(rec)} samples, need >= 200)")
        if np.ptp(rec.v) == 0:
            raise ValueError(f"{rec.source}: the input is constant (no reversal)")
        if np.ptp(rec.y) == 0:
            raise ValueError(f"{rec.source}: the output is constant")
        from ..identification.branches import find_reversals

        if not find_reversals(rec.v, 0.01 * float(np.ptp(rec.v))):
            raise ValueError(f"{rec.source}: the input has no reversal (no hysteresis loop)")


def diagnose(train: list[Record], validate: list[Record], *, max_effects: int = 3,
             initial_state: str = "auto",
             progress: Callable[[str], None] | None = None,
             workers: int | None = None) -> DiagnosisReport:
    """Diagnose the gap between a PI model fitted on ``train`` and the ``validate`` records.

    Parameters
    ----------
    train, validate : list of Record
        Records sharing one sample time; ``t`` is used as given (a drift may run on each
        record's own clock or on the clock the records share).
    max_effects : int
        Most effects combined.
    initial_state : {"auto", "rest", "unknown"}
        ``"rest"``: every model starts with its plays at rest (at ``v[0]`` or at 0) and every
        sample is fitted and scored. ``"unknown"``: the stage's memory at the start of a record
        is unknown; the start-up region (until the input first spans 90 % of the record's
        range) is left out of fitting and scoring. ``"auto"`` (default): ``"unknown"`` when the
        data contradict a start at rest (:func:`_auto_start`: the nominal fitted with the
        start-up mispredicts the rest of validate, or validate's own start-up, by far, and
        without the start-ups it is at the noise), else ``"rest"``; where a start at rest
        stays in doubt (the start in question, a gap left unexplained, or creep or drift
        named with the start-ups misfitted most), both diagnoses are made and the one
        without the start-ups kept when it predicts validate after them far better, or as well
        with fewer effects (:func:`_final_start`). The choice and its figures are in
        ``report.nominal["initial_state"]`` and ``["initial_state_choice"]``.
    progress : callable or None
        Called with a short message (``"candidate creep (1/6)"``) as each stage of the
        diagnosis starts (for a progress line on long records); None: silent.
    workers : int or None
        Threads for the independent fits (the candidates, the effects of a greedy round, the
        pairs, the revision's swaps and drops, the refined and re-searched lags) and the
        baseline beside the nominal; their results are taken in the serial order, so the
        report is the same to the bit for any ``workers`` (module threads). 1: one thread,
        the serial path. None: the CPUs this process may use, at most 2
        (:func:`.threads.default_workers`).

    Returns
    -------
    DiagnosisReport
        ``verdict`` holds ``effects`` (``["none"]``, effect names, possibly followed by
        ``"unexplained"``, or ``["unexplained"]``), ``gap_before``/``gap_after`` (validate
        RMS), ``shrink``, ``noise_floor`` (and how it was measured), ``unexplained``, and
        with creep among the effects ``creep_law`` (:func:`.creep.creep_law`: percent per
        decade, total creep, time constants; None when the lags have no immediate response).

    Raises
    ------
    ValueError
        Empty lists, records shorter than 200 samples or without a reversal, differing sample
        times, an unknown ``initial_state``, ``workers`` below 1.

    Warns
    -----
    UserWarning
        When a validate record is also a train record: nothing is held out.

    Examples
    --------
    >>> from pimodel.stages.pi_stage import excitation, random_truth
    >>> truth = random_truth(["creep"], 0)
    >>> tt, vt = excitation("train", seed=1)
    >>> tv, vv = excitation("validate", seed=2)
    >>> rep = diagnose([truth.record(tt, vt, 1)], [truth.record(tv, vv, 2)])
    >>> rep.verdict["effects"]
    ['creep']
    """
    if initial_state not in INITIAL_STATES:
        raise ValueError(f"initial_state: expected one of {INITIAL_STATES}, got "
                         f"{initial_state!r}")
    workers = default_workers() if workers is None else workers
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise ValueError(f"workers: expected an integer >= 1 or None, got {workers!r}")
    shared = [r.source for r in validate if any(
        r.t.size == t.t.size and np.array_equal(r.v, t.v) and np.array_equal(r.y, t.y)
        for t in train)]
    if shared:
        warnings.warn(f"validate: {shared} also in train; nothing is held out, so the validate "
                      "gap is a training fit, not a test", UserWarning, stacklevel=2)
    # the pool lent to this thread too: its passes over long records read their next chunk of
    # play outputs on an idle thread (module threads)
    progress = progress or (lambda message: None)
    with threadpool_limits(1, user_api="blas"), Pool(int(workers)) as pool, lend(pool):
        rep = _diagnose(train, validate, max_effects, initial_state, progress, pool)
        choice = rep.nominal.get("initial_state_choice")
        look = None if choice is None or choice["chosen"] != "rest" else \
            _second_look(choice, rep.verdict, max_effects)
        if look is None:
            return rep
        progress("a start at rest in doubt: the diagnosis without the start-ups")
        return _final_start(rep, _diagnose(train, validate, look, "unknown", progress, pool),
                            validate)


def _mask(r: Record, initial_state: str) -> np.ndarray | None:
    return np.arange(len(r)) >= startup_length(r.v) if initial_state == "unknown" else None


def _segments(records: list[Record], radii, initial_state: str,
              at_rest: bool = True) -> list[Segment]:
    return [make_segment(r.t, r.v, r.y, radii, _mask(r, initial_state), at_rest=at_rest)
            for r in records]


def _bare(records: list[Record], initial_state: str, samples: int | None = None) -> list[Segment]:
    """The records as segments without play outputs (``Z`` is None), cut to their first
    ``samples`` samples (None: whole; the start-up mask is that of the whole record)."""
    cut = slice(samples)
    return [Segment(r.t[cut], r.v[cut], r.y[cut], None,
                    None if (m := _mask(r, initial_state)) is None else m[cut]) for r in records]


def _plain_fit(records: list[Record], radii, initial_state: str,
               at_rest: bool = True, samples: int | None = None,
               factor: ChunkedQR | None = None) -> tuple[list[Segment], NormalEquations]:
    """The PI fit (play weights and an offset) that :func:`.effects.fit_nominal` makes, in one
    pass over the records with one chunk of play outputs at a time (:func:`.effects.play_chunks`
    into :class:`.chunked.NormalEquations`): nothing of size (samples x plays) is kept. Returns
    the records as segments without play outputs (:func:`_bare`, their first ``samples``
    samples; None: whole) and the normal equations (``solve()`` gives the coefficients, ``G``
    the Gram matrix of the plays and the offset on the fitted samples). A ``factor`` given
    (:class:`.chunked.ChunkedQR`, for the bounded weights of :func:`_bounded`) takes the same
    rows in the same pass."""
    segs = _bare(records, initial_state, samples)
    ne = NormalEquations(np.size(radii) + 1)
    sinks = (ne,) if factor is None else (ne, factor)
    for s in segs:
        for c, rows in play_chunks(s.v, radii, at_rest=at_rest):
            m = slice(None) if s.mask is None else fitted_in(s.mask, c)
            X, y = rows[:, m], s.y[c][m]
            for sink in sinks:
                sink.add(X, y)
    return segs, ne


def _plain_outputs(segs: list[Segment], radii, coef: np.ndarray,
                   at_rest: bool = True) -> list[np.ndarray]:
    """The output ``coef @ [z; 1]`` of the PI fit :func:`_plain_fit` at every sample of each
    segment, a second pass with one chunk of play outputs at a time."""
    out = []
    for s in segs:
        o = np.empty(s.v.size)
        for c, rows in play_chunks(s.v, radii, at_rest=at_rest):
            o[c] = coef @ rows
        out.append(o)
    return out


def _grids(train) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The nominal's radius grids: for each size in ``GRID_SIZES`` the uniform grid over half
    the train input range and, when a train record's input travels further than that from its
    first sample, the same grid extended to that travel at the coarsest grid's spacing.

    With the plays at rest at ``v[0]``, play ``r`` first moves once ``|v[k] - v[0]| > r``; a
    record that starts at one end of its range (a closed-loop record, a multisine with random
    phases, a record started at its top) moves plays up to its full range, beyond the half-range
    grid. A play beyond half the range moves only until the input has spanned its range (it can
    never cross to the other envelope), so the extension is informed by the records' start-up
    alone, where the stage's memory is an assumption (rest). Returns (half-range grids,
    extended grids; empty when no record travels that far)."""
    span, reach = span_and_reach(train)
    step = span / 2 / (GRID_SIZES[0] - 1)  # the extension's spacing: the coarsest grid's
    extra = step * np.arange(1, int(np.ceil((reach - span / 2) / step)) + 1) + span / 2
    half = [np.linspace(0.0, span / 2, n) for n in GRID_SIZES]
    return half, [np.concatenate((h, extra)) for h in half] if extra.size else []


def _few_samples(train: list[Record]) -> bool:
    """Whether the train records hold fewer than ``FEW_SAMPLES_PER_PLAY`` samples per play of
    the finest grid (counted over the whole records, start-up included)."""
    return sum(len(r) for r in train) < FEW_SAMPLES_PER_PLAY * max(GRID_SIZES)


def _topped_grids(train) -> list[np.ndarray]:
    """The nominal's grids topped below half the train input range ``S / 2`` (issue 28): for
    each top in ``GRID_TOPS`` (a fraction of ``S / 2``) and each size in ``GRID_SIZES`` the
    uniform grid from 0 to that top, when the train records hold fewer than
    ``FEW_SAMPLES_PER_PLAY`` samples per play of the finest grid (counted over the whole
    records, start-up included); else none.

    A play of radius ``r`` near ``S / 2`` moves only while the input is within ``S - 2 r`` of
    an extreme it has reached (and in the start-up from rest). On band-limited random input the
    extremes are visited a few times, so with few samples (a 4 s record at 500 Hz: 2000 samples
    for 81 coefficients) the top plays' weights are fitted to the noise and to the finer plays'
    off-grid error, and they mispredict a record that visits its extremes otherwise (on clean
    stages, validate 2-3.5 times the noise in 3 of 10 seeds). Whether a play that moves so
    little is part of the stage, train alone cannot tell (on ramps to held levels a stage's
    largest radius at 0.84-0.99 of ``S / 2`` misfits train little), so :func:`_nominal` keeps a
    topped grid only when validate agrees, as the extension. With more samples (every record
    of the ``sim_to_real`` study and the shared real record: at least 8275) none, as before."""
    if not _few_samples(train):
        return []
    span, _ = span_and_reach(train)
    return [np.linspace(0.0, top * span / 2, n) for top in GRID_TOPS for n in GRID_SIZES]


def _nominal(train, validate, initial_state):
    """The radius grid with the lowest train BIC (its nominal: :func:`_nominal_segments`).

    The half-range grids and the extended grids (:func:`_grids`) each give the one with the
    lowest train BIC; the extended one is kept only when it also has the lower validate BIC
    (its extra plays are informed by the start-up alone: on a record whose memory at the
    start is not at rest they fit that start and mispredict every other record's). The plays
    start at rest at ``v[0]``, or at 0 when that has the lower train BIC (a record cut from
    periodic motion near an extreme: the plays sit near ``v[0] -+ r``, as from 0) and the lower
    sum of the train BIC and the validate BIC after a gain and an offset per validate record
    (:func:`_affine_validate_bic`; issue 28: on staircases at 200 Hz behind a delay the plays
    from 0 won train by a hair and missed validate by 20-50 noise floors; on a blind stage
    with creep they won train by far and lost validate by a little, and were right; the gain
    and offset keep a sensor gain that differs between records from reading as a start).
    Returns the radii, whether the grid is extended and whether the plays start at rest at
    ``v[0]``.
    With ``initial_state="unknown"`` (the start-up is not fitted) the plays start at 0 on the
    half-range grids, as before issue 33
    (from ``v[0]`` the shared real record's validate gap was 0.154 um against 0.048 um noise).
    With few train samples, the topped grids (:func:`_topped_grids`, plays started as chosen)
    give the one with the lowest train BIC, kept in place of a half-range choice only when it
    has the lower validate BIC (issue 28), and the half-range pick with one play above half the
    range (:func:`_one_above`) takes the place of the half-range and extended picks when the
    train BIC and validate agree; the choice stays the grid with which every model
    then runs, in discrete time as before (plays updated at each sample ``k`` from ``v[k]``)."""
    half, extended = _grids(train)
    if initial_state == "unknown":  # the start-up is not fitted: the plays at 0, as before
        half, extended = [], []
    picks = []  # the grids are compared by fits streamed over the records (_plain_fit), on
    # the records' first SCREEN_SAMPLES samples (the grids span the whole train input), by
    # the BIC of the whole records' sample count (the screen's mean squared residual)
    n_train = _fitted_samples(train, initial_state)
    for at_rest, grids in ((True, half), (True, extended), (False, _grids(train)[0])):
        picks.append(_train_pick(train, grids, initial_state, at_rest, n_train))
    if picks[0] is None:
        return _topped(train, validate, initial_state, picks[2], n_train)[1], False, False
    if picks[1] is not None:  # the extension: kept only when validate agrees
        vbic = [_validate_bic(validate, initial_state, pick) for pick in picks[:2]]
        if vbic[1] >= vbic[0]:
            picks[1] = None
    above = _one_above(train, validate, initial_state, picks[0], picks[1], n_train)
    if above is not None:  # in place of the half-range grid and of the extension
        picks[1] = above
    ext = picks[1] is not None
    rest = picks[1] if ext else picks[0]
    chosen = rest
    if picks[2][0] < rest[0] and (
            picks[2][0] + _affine_validate_bic(validate, initial_state, picks[2])
            < rest[0] + _affine_validate_bic(validate, initial_state, rest)):
        chosen = picks[2]  # the plays from 0: the lower BIC over train and validate
    if not (ext and chosen[3]):
        chosen = _topped(train, validate, initial_state, chosen, n_train)
    _, radii, _, at_rest = chosen
    return radii, ext and at_rest, at_rest


def _auto_start(train, validate, rest_pick) -> tuple[str, dict, tuple]:
    """``initial_state="auto"``: whether the records start at rest. Returns the state
    (``"rest"`` or ``"unknown"``), its figures and the nominal's pick (:func:`_nominal`) for it.

    The nominal of each state (its grid, start and bounded weights, as :func:`_diagnose` fits
    them) is fitted on the train records' first ``SCREEN_SAMPLES`` samples and predicts the
    validate records' first ``SCREEN_SAMPLES`` from rest; ``post`` is the mean squared misfit
    after each validate record's start-up region (:func:`.where.startup_length`), where the
    stage's memory no longer depends on its start, ``startup`` within it. The start is in
    question when ``post`` of the rest nominal exceeds ``START_POST_GAIN`` times that of the
    nominal fitted without the start-ups (fitting them as at rest spoils the weights: a record
    started from a park level, or slow noise fitted by the large plays' one move in the
    start-up), or when the rest nominal's ``startup`` exceeds ``START_EXCESS`` times its
    ``post`` (validate's own start is not at rest). ``"unknown"`` is chosen when it is in
    question and the nominal without the start-ups predicts validate after them within
    ``NOISE_STOP`` times its noise floor (:func:`.noise.measure_noise_floor`): the start
    explains the gap. The start is not put in question when every train record's input
    reverses at most once after its start-up (:func:`_one_branch`): one branch, fitted by a PI
    whatever the stage, tests no start (issue 28: blind staircases, the start-up 43-47 % of each
    record, read ``none`` without the start-ups although an effect of 79-93 noise floors was
    there). Else ``"rest"``: a stage started at rest gives both nominals alike, and an
    effect strongest early in the records (a settling drift, creep after the first step) can
    spoil the weights as a wrong start does, but the nominal without the start-ups does not
    reach the noise then, and the effect is searched from rest as before (issue 28: the four
    clean blind cases that were wrong from rest, stages parked before each record)."""
    screens = [_bare(records, "rest", SCREEN_SAMPLES) for records in (train, validate)]
    one_branch = _one_branch(train)
    stats, outputs = {}, {}
    picks = {"rest": rest_pick}
    if not one_branch:
        picks["unknown"] = _nominal(train, validate, "unknown")
    for state, (radii, _, at_rest) in picks.items():
        nonneg = _bounded(train, validate, radii, state, at_rest)
        qr = None if nonneg is None else ChunkedQR(radii.size + 1)
        ne = _plain_fit(train, radii, state, at_rest, SCREEN_SAMPLES, factor=qr)[1]
        coef = ne.solve() if qr is None else qr.solve_nonneg(nonneg)
        outputs[state] = [_plain_outputs(sc, radii, coef, at_rest) for sc in screens]
        stats[state] = _startup_split(validate, [s.y - o for s, o in zip(
            screens[1], outputs[state][1], strict=True)])
    su_rest, post_rest = stats["rest"]
    post_free = stats["unknown"][1] if "unknown" in stats else None
    choice = {"asked": "auto", "one_branch": one_branch,
              "post_startup_ratio": post_rest / post_free if post_free else None,
              "startup_ratio": su_rest / post_rest if post_rest > 0 else None,
              "limits": {"post_startup_ratio": START_POST_GAIN, "startup_ratio": START_EXCESS,
                         "branch_travel": BRANCH_TRAVEL,
                         "free_over_noise": NOISE_STOP}}
    state = "rest"
    choice["in_question"] = bool(not one_branch and (
        post_rest > START_POST_GAIN * post_free or su_rest > START_EXCESS * post_rest))
    if choice["in_question"]:
        noise = measure_noise_floor([(s.v, s.y) for sc in screens for s in sc],
                                    [o for out in outputs["unknown"] for o in out])["value"]
        choice["free_over_noise"] = float(np.sqrt(post_free)) / noise if noise > 0 else None
        if noise > 0 and np.sqrt(post_free) <= NOISE_STOP * noise:
            state = "unknown"
    choice["chosen"] = state
    return state, choice, picks[state]


def _one_branch(train: list[Record]) -> bool:
    """Whether the input of every ``train`` record reverses at most once after its start-up
    region (:func:`.where.startup_length`), a reversal counted when the input moves back
    ``BRANCH_TRAVEL`` of the record's range (:func:`.identification.branches.find_reversals`)."""
    for r in train:
        v = np.asarray(r.v, float)
        k = startup_length(v)
        if len(find_reversals(v[k:], BRANCH_TRAVEL * float(np.ptp(v)))) > 1:
            return False
    return True


def _startup_split(validate: list[Record], residuals: list[np.ndarray]) -> list[float]:
    """The mean squared ``residuals`` of the ``validate`` records (each possibly cut short)
    within their start-up regions (:func:`.where.startup_length`) and after them (0.0 where
    there are no samples)."""
    k = [min(startup_length(r.v), e.size) for r, e in zip(validate, residuals, strict=True)]
    parts = [np.concatenate([e[:j] for e, j in zip(residuals, k, strict=True)]),
             np.concatenate([e[j:] for e, j in zip(residuals, k, strict=True)])]
    return [float(np.mean(np.square(p))) if p.size else 0.0 for p in parts]


def _second_look(choice: dict, verdict: dict, max_effects: int) -> int | None:
    """Whether ``"auto"``, having kept ``"rest"``, makes the diagnosis without the start-ups
    too (:func:`_final_start`), and with how many effects at most (None: not made).

    - ``max_effects`` when the start is in question (:func:`_auto_start`) or an effect of
      ``START_SLOW`` is named while the rest nominal misfits validate's start-ups at least
      ``START_SLOW_EXCESS`` times as densely (mean square) as the rest of validate;
    - as many effects as the rest verdict named when it left a gap ``unexplained`` (can they
      do without the start-ups?);
    - one fewer when it names one of ``START_SLOW`` beside others (on stages that are not at
      rest, the Preisach generator's, a wrong start's misfit in the start-ups is taken for
      creep beside the true effect);
    - else None. The caps keep the second diagnosis to what could replace the first.

    None too when every train record is one branch after its start-up (``one_branch``,
    :func:`_one_branch`): without the start-ups a PI fits that branch whatever the stage."""
    if choice.get("one_branch"):
        return None
    named = [e for e in verdict["effects"] if e not in ("none", "unexplained")]
    slow = set(named).intersection(START_SLOW)
    if choice["in_question"] or (slow and (choice["startup_ratio"] or 0.0) > START_SLOW_EXCESS):
        return max_effects
    if "unexplained" in verdict["effects"]:
        return len(named)
    return len(named) - 1 if slow and len(named) > 1 else None


def _final_start(rest: DiagnosisReport, unknown: DiagnosisReport,
                 validate: list[Record]) -> DiagnosisReport:
    """``initial_state="auto"``, the second look (:func:`_second_look`): with the start in
    question but not explained by the nominal alone (:func:`_auto_start`: an effect keeps the
    nominal without the start-ups above the noise), or with a verdict from rest that a misfit
    of a wrong start in the start-ups can give (creep or drift, or a gap left unexplained), the
    diagnosis without the start-ups (``"unknown"``, with at most the effects
    :func:`_second_look` allows) has been made too. Both chosen models
    predict validate after its start-up regions (the samples both score; mean squared misfits
    ``post``). The diagnosis without the start-ups is kept when

    - the rest one's ``post`` exceeds ``START_POST_GAIN`` times its ``post`` (the start spoiled
      the fit from rest beyond what the effects mend) and it names no more effects (else the
      gain may be its extra effects', not the start's), or
    - it names fewer effects (its effects, ``"unexplained"`` included, a strict subset of the
      rest verdict's) and the rest one's extra effects do not cut the RMS after the start-ups
      by ``MIN_RMS_CUT`` (``post`` ratio above ``(1 - MIN_RMS_CUT)**2``): they fitted the
      start-ups alone, or
    - it names other effects, no more of them (``"unexplained"`` counted), and the rest one's
      ``post`` exceeds ``START_SWAP`` times its ``post``: two explanations as large, the one
      that needs the start-ups predicting the rest of validate worse (a drift on each record's
      clock, of a stage not at rest, read as creep from rest).

    Else the rest diagnosis is kept: a stage started at rest gives both chosen models alike
    after the start-ups, and effects that show there are kept from rest. The figures are in
    ``nominal["initial_state_choice"]["second_look"]``."""
    post = [_startup_split(validate, [s.y - o for s, o in zip(rep.validate, rep.after,
                                                               strict=True)])[1]
            for rep in (rest, unknown)]
    named = [set(rep.verdict["effects"]) - {"none"} for rep in (rest, unknown)]
    ratio = post[0] / post[1] if post[1] > 0 else None
    fewer = named[1] < named[0]
    more = len(named[1] - {"unexplained"}) > len(named[0] - {"unexplained"})
    other = named[1] != named[0] and not fewer and len(named[1]) <= len(named[0])
    choice = rest.nominal["initial_state_choice"]
    choice["second_look"] = {"unknown_effects": list(unknown.verdict["effects"]),
                             "post_startup_ratio": ratio, "fewer_effects": fewer,
                             "more_effects": more, "other_effects": other,
                             "limits": {"post_startup_ratio": START_POST_GAIN,
                                        "fewer_effects_ratio": (1 - MIN_RMS_CUT) ** 2,
                                        "other_effects_ratio": START_SWAP}}
    if ratio is None or not ((ratio > START_POST_GAIN and not more) or
                             (fewer and ratio > (1 - MIN_RMS_CUT) ** 2) or
                             (other and ratio > START_SWAP)):
        return rest
    choice["chosen"] = "unknown"
    choice["second_look"]["rest_effects"] = list(rest.verdict["effects"])
    unknown.nominal["initial_state_choice"] = choice
    return unknown


def _one_above(train, validate, initial_state: str, half, extended, n_train: int):
    """The half-range pick ``half`` (of :func:`_train_pick`, plays at rest) with one more play
    above half the train input range ``h``, at the radius of ``ABOVE_POINTS`` uniform in
    ``(h, reach]`` (``reach``: the train input's largest travel from its first sample) with the
    lowest train BIC (issue 28); None unless the train records are few samples (as
    :func:`_few_samples`), the train BIC is lower than ``half``'s by ``ABOVE_MARGIN`` and the
    validate BIC lower than that of ``half`` and of ``extended`` (the extension's pick, None
    when not kept).

    A play above ``h`` moves in train only in the start-up (once, from rest): a grid of such
    plays (the extension) fits that one move with several weights, which then mispredict the
    loops of a validate record that spans more than ``2 h``. One play at a searched radius is
    fitted from it with one weight: on ramps to held levels at 500 Hz (4 s and 2 s records) a
    stage with a play at 1.05 ``h`` then validates to 0.0053 / 0.0094 um (0.108 / 0.092 um on
    every grid), and on the other 18 of 20 records (no play above ``h``, or one beyond ``reach``)
    the train BIC rises with it (docs/diagnosis.md). Plays beyond ``reach`` never move in
    train: nothing fits them."""
    if half is None or not half[3] or not _few_samples(train):
        return None
    h = half[1][-1]
    _, reach = span_and_reach(train)
    if reach <= h:
        return None
    grids = [np.append(half[1], r) for r in np.linspace(h, reach, ABOVE_POINTS + 1)[1:]]
    pick = _train_pick(train, grids, initial_state, True, n_train)
    if pick[0] > half[0] - ABOVE_MARGIN:
        return None
    vbic = _validate_bic(validate, initial_state, pick)
    if any(vbic >= _validate_bic(validate, initial_state, p) for p in (half, extended)
           if p is not None):
        return None
    return pick


def _train_pick(train, grids, initial_state: str, at_rest: bool, n_train: int):
    """``(train BIC, radii, coefficients, at_rest)`` of the grid in ``grids`` with the lowest
    train BIC (None when ``grids`` is empty), each grid that ends at or below half the train
    span without its top plays that move in train by a sliver (:func:`.coverage.informed_radii`:
    less than one grid spacing; records taken under feedback, issue 28), fitted by
    :func:`_plain_fit` on the records' first ``SCREEN_SAMPLES`` samples and scored with the BIC
    of ``n_train`` samples."""
    best = None
    half_top = span_and_reach(train)[0] / 2 * (1 + 1e-12)
    for radii in grids:
        if radii[-1] <= half_top:  # no play that moves by a sliver, on grids up to S / 2
            radii = informed_radii(train, radii, at_rest)
        segs, ne = _plain_fit(train, radii, initial_state, at_rest, SCREEN_SAMPLES)
        coef = ne.solve()
        bic = _bic(segs, _plain_outputs(segs, radii, coef, at_rest), radii.size + 1, n_train)
        if best is None or bic < best[0]:
            best = (bic, radii, coef, at_rest)
    return best


def _validate_bic(validate, initial_state: str, pick) -> float:
    """The validate BIC of a pick of :func:`_train_pick` (its train fit, on the validate
    records' first ``SCREEN_SAMPLES`` samples, with the BIC of their fitted samples)."""
    _, radii, coef, at_rest = pick
    va = _bare(validate, initial_state, SCREEN_SAMPLES)
    return _bic(va, _plain_outputs(va, radii, coef, at_rest), radii.size + 1,
                _fitted_samples(validate, initial_state))


def _affine_validate_bic(validate, initial_state: str, pick) -> float:
    """:func:`_validate_bic` after a gain and an offset per validate record fitted on its
    outputs (a sensor gain that differs between records is no start)."""
    _, radii, coef, at_rest = pick
    va = _bare(validate, initial_state, SCREEN_SAMPLES)
    outs = []
    for s, o in zip(va, _plain_outputs(va, radii, coef, at_rest), strict=True):
        x = o[s.used]
        ab, *_ = np.linalg.lstsq(np.column_stack((x, np.ones(x.size))), s.y[s.used], rcond=None)
        outs.append(ab[0] * o + ab[1])
    return _bic(va, outs, radii.size + 1 + 2 * len(va), _fitted_samples(validate, initial_state))


def _topped(train, validate, initial_state: str, chosen, n_train: int):
    """``chosen`` (a pick of :func:`_train_pick`), or the topped grid (:func:`_topped_grids`,
    the plays started as in ``chosen``) with the lowest train BIC when its validate BIC is
    lower than ``chosen``'s."""
    pick = _train_pick(train, _topped_grids(train), initial_state, chosen[3], n_train)
    if pick is None:
        return chosen
    return pick if _validate_bic(validate, initial_state, pick) < \
        _validate_bic(validate, initial_state, chosen) else chosen


def _baseline(train, validate, initial_state) -> dict:
    """The plain least-squares PI fit the nominal is checked against: ``BASELINE_PLAYS`` radii
    uniform from 0 to the train input's largest magnitude, plays at rest at ``v[0]``, one
    offset, fitted on the same (masked) train samples; its train and validate errors."""
    vmax = max(float(np.max(np.abs(r.v))) for r in train)
    radii = np.linspace(0.0, vmax, BASELINE_PLAYS)
    tr, ne = _plain_fit(train, radii, initial_state)  # streamed: no 60 play columns kept
    coef = ne.solve()
    va = _bare(validate, initial_state)
    return {"kind": "PI, plain least squares", "plays": BASELINE_PLAYS, "max_radius": vmax,
            "train": _errors(tr, _plain_outputs(tr, radii, coef)),
            "validate": _errors(va, _plain_outputs(va, radii, coef))}


def _bounded(train, validate, radii, initial_state: str, at_rest: bool) -> np.ndarray | None:
    """The plays held at or above 0 in the nominal's weights: radius above 0 (the radius-0 play
    and the offset free), when the fit so bounded (bounded-variable least squares on the
    triangular factor of the plays, :meth:`.chunked.ChunkedQR.solve_nonneg`) has a validate
    BIC not above the least-squares fit's (both on the records' first ``SCREEN_SAMPLES``
    samples, as :func:`_validate_bic`); else None (least squares, as before), and None when
    ``NONNEG_PLAYS`` is off.

    A PI stage's plays of radius above 0 have non-negative weights (a loop traversed
    anticlockwise); least squares on a fine grid is ill-conditioned (cond ``Z`` about 1e18 on 80
    plays), so on records whose inputs excite few directions (multisines, band-limited noise,
    ramps to held levels; issue 28) its weights swing in sign and mispredict validate by several
    noise floors. The bound is kept only where validate agrees, so a stage whose weights are
    truly signed keeps least squares."""
    if not NONNEG_PLAYS or radii.size < 2:
        return None
    mask = radii > 0
    qr = ChunkedQR(radii.size + 1)
    ne = _plain_fit(train, radii, initial_state, at_rest, SCREEN_SAMPLES, factor=qr)[1]
    vbic = [_validate_bic(validate, initial_state, (None, radii, coef, at_rest))
            for coef in (ne.solve(), qr.solve_nonneg(mask))]
    return mask if vbic[1] <= vbic[0] else None


def _nominal_segments(train, validate, radii, initial_state: str, at_rest: bool,
                      samples: int | None = None, pool: Pool | None = None,
                      nonneg: np.ndarray | None = None):
    """The nominal on the chosen grid and the segments the candidates are fitted on, the play
    outputs streamed (:func:`_plain_fit`): the nominal's train and validate outputs, then its
    play columns replaced by a few combinations (the least-squares weights, then the 32 leading
    principal directions of the train play outputs, from the Gram matrix of the same pass, and
    last the weights held non-negative where ``nonneg`` says, :func:`_bounded`) when they keep
    the nominal train RSS within 1 %; the candidates' grid searches filter the leading columns of
    these only, and refit every weight of them without bound. The projected nominal is fitted by
    normal equations streamed over the records (:func:`_projected_fit`), and the segments' rows
    are built chunk by chunk for the records' first ``samples`` samples only (None: whole; the
    screen of a long record), so neither the full (samples x plays) outputs nor the whole
    records' projected rows are held; without a projection (20 plays, or a worse RSS) the
    segments hold the full play outputs of those samples. Returns the train and validate
    segments, the nominal fitted on them (with the full model's ``params``), the full nominal,
    the projection ``V`` (play columns = ``Z @ V``; None: not compressed), the full nominal's
    train and validate outputs (every sample) and the whole records as segments without play rows
    (:func:`_bare`, for :func:`_with_rows`). With a ``pool`` of several threads, the validate
    outputs and the slow-drift check are made on it beside the train passes (the same values)."""
    n = radii.size
    threads = pool is not None and pool.workers > 1
    qr = None if nonneg is None else ChunkedQR(n + 1)  # the bounded weights: same pass
    segs, ne = _plain_fit(train, radii, initial_state, at_rest, factor=qr)
    coef_ls = ne.solve()
    coef = coef_ls if qr is None else qr.solve_nonneg(nonneg)
    vsegs = _bare(validate, initial_state)
    out_va = pool.submit(_plain_outputs, vsegs, radii, coef, at_rest) if threads else None
    out_tr = _plain_outputs(segs, radii, coef, at_rest)
    full = Model("nominal", 0, base_features, coef, nominal_params(coef, out_tr, segs))
    out_va = out_va.result() if threads else _plain_outputs(vsegs, radii, coef, at_rest)
    heads = (_bare(train, initial_state, samples), _bare(validate, initial_state, samples))
    if n > PROJECTED:
        rss_full = sum(float(np.sum(np.square(r, out=r))) for r in (
            (o - s.y)[s.used] for s, o in zip(segs, out_tr, strict=True)))
        lam, vecs = np.linalg.eigh(ne.G[:n, :n])
        # the least-squares weights first, then the principal directions (the grid searches
        # take the leading columns); a bounded nominal's own weights last, so that its fit is
        # in the span and the searches see the columns least squares gives them. Only the
        # directions the train outputs span: one of no variance (plays the train input never
        # moves apart) is rounding on train, and a fit scaling its column to unit norm gives it
        # a coefficient that blows up on validate, where the input moves those plays
        spanned = vecs[:, ::-1][:, lam[::-1] > SPANNED * lam[-1]]
        ws = [coef_ls[:n]] + ([] if nonneg is None else [coef[:n]])
        ws = [w / (np.linalg.norm(w) or 1.0) for w in ws]
        V = np.column_stack((ws[0], spanned[:, :PROJECTED], *ws[1:]))
        screen = _bare(train, initial_state, SCREEN_SAMPLES)
        slow = pool.submit(_slow_rss, screen, radii, at_rest, V) if threads else None
        m, rss = _projected_fit(segs, radii, V, at_rest)
        # beside a slow drift too, within 1 % plus what the dropped directions fit of the noise
        # (a drift the nominal leaves in its residual inflates its RSS, so that 1 % of it can
        # hide directions a drift model needs)
        # (on the records' first SCREEN_SAMPLES samples, where the effects are chosen)
        n_fit = sum(s.y.size if s.mask is None else int(np.sum(s.mask)) for s in screen)
        keep = rss <= 1.01 * rss_full
        if keep:
            slow_full, slow_projected = slow.result() if threads else \
                _slow_rss(screen, radii, at_rest, V)
            keep = slow_projected <= (1.01 + (n - V.shape[1]) / n_fit) * slow_full
        if keep:
            m.params = dict(full.params)
            return (*([_with_rows(s, radii, V, at_rest) for s in h] for h in heads), m, full, V,
                    out_tr, out_va, segs, vsegs)
    return (*([_with_rows(s, radii, None, at_rest) for s in h] for h in heads), full, full, None,
            out_tr, out_va, segs, vsegs)


def _projected_fit(segs: list[Segment], radii, V: np.ndarray, at_rest: bool
                   ) -> tuple[Model, float]:
    """The nominal on the play columns ``Z V`` and an offset (the least squares of
    :func:`.effects.fit_nominal`, the same sums chunk by chunk), with its train RSS, the
    projected rows built from the input one chunk at a time (two passes: the normal equations,
    then the residuals)."""
    def projected_chunks(s):
        for c, rows in _play_row_chunks(s, radii, V, at_rest):
            m = slice(None) if s.mask is None else fitted_in(s.mask, c)
            yield rows[:, m], s.y[c][m]

    ne = NormalEquations(V.shape[1] + 1)
    for s in segs:
        for X, y in projected_chunks(s):
            ne.add_gram(X @ X.T, X @ y, y.size)
    coef = ne.solve()
    rss = sum(float(np.sum((coef @ X - y) ** 2)) for s in segs for X, y in projected_chunks(s))
    return Model("nominal", 0, base_features, coef, {}), rss


def _with_rows(s: Segment, radii, V: np.ndarray | None, at_rest: bool) -> Segment:
    """The bare segment ``s`` (:func:`_bare`) with play columns: ``Z V`` built chunk by chunk
    (:func:`_projected`), or the full play outputs when ``V`` is None; its rate and Wiener
    bases kept."""
    out = make_segment(s.t, s.v, s.y, radii, s.mask, at_rest=at_rest) if V is None else \
        _projected(s, radii, V, at_rest)
    out.rate_basis, out.wiener_basis = s.rate_basis, s.wiener_basis
    return out


def _flat_settling(m: Model, tr, va, noise: float) -> bool:
    """Whether ``m`` holds a settling drift whose bow over the records (:func:`.drift.settle_bow`
    times ``|D|``) stays within ``SETTLE_BOW_FLOORS`` noise floors (the verdict's own threshold
    for a gap): on these records it is then a straight trend, which the drift's linear variants
    give with fewer parameters, and its time constant would be read into the noise or into
    another effect's leftover (a creep lag between the grid's lags)."""
    g = m.grid or {}
    if "drift" not in m.name.split("+") or g.get("clock") != "settle":
        return False
    bow = settle_bow([s.t for s in (*tr, *va)], g["settle_tau"], g["settle_t0"])
    return abs(float(m.params["drift_settling"])) * bow < SETTLE_BOW_FLOORS * noise


def _slow_rss(segs: list[Segment], radii, at_rest: bool, V: np.ndarray) -> tuple[float, float]:
    """RSS of the least-squares fits of the fitted samples of ``y`` on the play columns (``Z``,
    then ``Z V``; the play outputs streamed from the input, :func:`~.effects.play_chunks`), an
    offset per record and Legendre polynomials of degree 1 to ``SLOW_DEGREE`` of the time on
    the clock the records share (a slow drift), in one pass: a QR of the stacked chunks of
    ``[Z, offsets, polynomials, y]``, then of ``R T`` with ``T = diag(V, I)`` (``X T = Q (R T)``,
    so that factor is the projected fit's). Each RSS is its factor's last diagonal entry
    squared (0 with fewer fitted samples than columns)."""
    t0 = min(float(s.t[0]) for s in segs)
    span = max(float(s.t[-1]) for s in segs) - t0 or 1.0
    R = None
    for j, s in enumerate(segs):
        for c, P in play_chunks(s.v, radii, at_rest=at_rest):
            x = 2.0 * (s.t[c] - t0) / span - 1.0
            rows = [P[:-1], np.eye(len(segs))[j][:, None] * np.ones(x.size),
                    np.polynomial.legendre.legvander(x, SLOW_DEGREE)[:, 1:].T, s.y[c][None]]
            M = np.vstack(rows).T
            M = M if s.mask is None else M[fitted_in(s.mask, c)]
            R = np.linalg.qr(M if R is None else np.vstack((R, M)), mode="r")
    n, rest = V.shape[0], R.shape[1] - V.shape[0]
    T = np.zeros((R.shape[1], V.shape[1] + rest))
    T[:n, :V.shape[1]], T[n:, V.shape[1]:] = V, np.eye(rest)
    Rp = np.linalg.qr(R @ T, mode="r")
    return tuple(float(F[-1, -1] ** 2) if F.shape[0] == F.shape[1] else 0.0 for F in (R, Rp))


def _play_row_chunks(s: Segment, radii, V: np.ndarray | None, at_rest: bool):
    """``(c, rows)`` for each chunk ``c`` of ``s``: its play rows from the input (the plays'
    states carried, :func:`.effects.play_chunks`), ``V^T z`` when ``V`` is given, then the row
    of ones, shape (n + 1, len(c))."""
    for c, P in play_chunks(s.v, radii, at_rest=at_rest):
        if V is None:
            yield c, P
            continue
        rows = np.empty((V.shape[1] + 1, P.shape[1]))
        np.matmul(V.T, P[:-1], out=rows[:-1])
        rows[-1] = 1.0
        yield c, rows


def _streamed(s: Segment, radii, V: np.ndarray | None, at_rest: bool) -> Segment:
    """The bare segment ``s`` as a streamed one (:func:`.streamed.attach_plays`): its play
    rows (``Z V`` when ``V`` is given, as :func:`_projected` builds them; else ``Z``, as
    :func:`.effects.make_segment`) and the row of ones, chunk by chunk from the input
    (:func:`_play_row_chunks`); its rate and Wiener bases kept."""
    out = Segment(s.t, s.v, s.y, None, s.mask, s.rate_basis, s.wiener_basis)
    return attach_plays(out, lambda: _play_row_chunks(s, radii, V, at_rest),
                        np.size(radii) if V is None else V.shape[1])


def _projected(s: Segment, radii, V: np.ndarray, at_rest: bool) -> Segment:
    """The segment with play columns ``Z V``, built chunk by chunk as rows from the input."""
    rows = np.empty((V.shape[1] + 1, s.y.size))
    for c, chunk in _play_row_chunks(s, radii, V, at_rest):
        rows[:, c] = chunk
    return segment_of_rows(s.t, s.v, s.y, rows, s.mask)


def _diagnose(train: list[Record], validate: list[Record], max_effects: int,
              initial_state: str, progress: Callable[[str], None],
              pool: Pool) -> DiagnosisReport:
    _check(train, "train")
    _check(validate, "validate")
    dts = [(r.source, r.dt) for r in train + validate]
    for src, dt in dts[1:]:
        if abs(dt - dts[0][1]) > 1e-6 * dts[0][1]:
            raise ValueError(f"{src}: sample time {dt:g} s differs from {dts[0][0]} "
                             f"({dts[0][1]:g} s); resample the records to one sample time")
    dt = dts[0][1]
    progress("nominal model (radius grids)")
    asked = initial_state
    pick = _nominal(train, validate, "rest" if asked == "auto" else asked)
    if asked == "auto":
        initial_state, choice, pick = _auto_start(train, validate, pick)
    radii, extended, at_rest = pick
    n_plays = radii.size
    progress(f"nominal model ({radii.size} plays, fitted on the whole records)")
    # records longer than SCREEN_SAMPLES: every search and comparison below runs on their
    # first SCREEN_SAMPLES samples (the segments tr, va); the chosen model is refitted on the
    # whole records (_whole_fit), whose play rows are built only then
    screened = any(len(r) > SCREEN_SAMPLES for r in train + validate)
    # the baseline does not depend on the nominal: on a second thread, beside it
    baseline = pool.submit(_baseline, train, validate, initial_state) if pool.workers > 1 \
        else None
    nonneg = _bounded(train, validate, radii, initial_state, at_rest)
    tr, va, nominal, full_nominal, proj, out_tr, out_va, *whole = _nominal_segments(
        train, validate, radii, initial_state, at_rest, SCREEN_SAMPLES if screened else None,
        pool, nonneg)
    before = _errors(whole[1], out_va)
    progress("plain least-squares baseline")
    nominal_json = {"model": {"kind": "PI, conventional parametrisation", "radii": radii,
                              "weights": full_nominal.coef[:n_plays],
                              "offset": full_nominal.coef[n_plays],
                              "grid_sizes_tried": list(GRID_SIZES),
                              "grid_extended": extended,
                              "plays_start": "at rest at v[0]" if at_rest else "at 0"},
                    "train": _errors(whole[0], out_tr), "validate": before,
                    "initial_state": initial_state,
                    **({"initial_state_choice": choice} if asked == "auto" else {}),
                    "baseline": baseline.result() if baseline is not None else
                    _baseline(train, validate, initial_state),
                    "coverage": coverage(train, validate)}
    base_rms = nominal_json["baseline"]["validate"]["rms"]
    if before["rms"] > BASELINE_WARN * base_rms:
        warnings.warn(f"nominal: validate RMS {before['rms']:.4g} is {before['rms'] / base_rms:.2f}"
                      f" times that of a plain least-squares PI fit ({base_rms:.4g}; "
                      "report.nominal['baseline']): the effects are measured against a weak "
                      "nominal", UserWarning, stacklevel=3)
    progress("noise floor")
    noise_info = measure_noise_floor([(s.v, s.y) for s in whole[0] + whole[1]],
                                     out_tr + out_va)
    noise = noise_info["value"]
    del out_tr  # the nominal's train outputs: read by nothing after the noise floor (so not
    # held beside where's temporaries, nor through the choice)
    where = residual_breakdown(whole[1], [s.y - o for s, o in zip(whole[1], out_va,
                                                                   strict=True)])
    whole.append(out_va)
    if screened:
        out_va = [o[:SCREEN_SAMPLES] for o in out_va]
    segs = tr + va
    # the rate columns from the full play outputs (computed chunk by chunk from the input
    # when needed), weighted as the model will hold them; the step rule on the whole input
    w_ref = nominal.coef[:n_plays] if proj is None else proj @ nominal.coef[:proj.shape[1]]
    pairs = list(zip(segs, whole[0] + whole[1], strict=True))  # (segment, its whole record)
    if screened:
        pairs += [(w, w) for w in whole[0] + whole[1]]
    for s, w in pairs:
        s.rate_basis = RateBasis(None, radii, s.v, s.dt, nominal.params["rate_scale"], w_ref,
                                 input_range=float(np.ptp(w.v)), at_rest=at_rest,
                                 projection=proj)
        s.wiener_basis = WienerBasis(s.v, radii, proj, s.dt,  # dynamics before the plays
                                     at_rest=at_rest)

    cache: dict = {}
    once = OnceCache() if pool.workers > 1 else None  # several threads: each key fitted once

    def variants(name, combo=(), fixed_=None) -> list[tuple]:
        """The single fits ``fit(name, combo, fixed_)`` scores, in its order: ``(key, fx)``
        (a drift's clocks, a rate's shapes, the dynamics' two positions; one for most
        effects)."""
        bases = [fixed_ or {}]
        if combo and "dynamics" in (*combo, name) and not {"fn", "wiener"} & set(bases[0]):
            # the filter before the hysteresis, where the dynamics alone chose it, held; and
            # the linear part after the hysteresis searched beside the other effects (alone,
            # the filter may take a misfit that belongs to them: density_stage dynamics +
            # asymmetry s1, validate 0.82 um held against 0.39 um after)
            hint = position_hint(fit("dynamics")[0].grid)
            bases = [{**hint, **bases[0]}, bases[0]] if hint else bases
        out = []
        for base in bases:
            # a creep's start: each scored where the creep enters (alone, a pair, the creep
            # added or swapped in); held where ``base`` carries the chosen creep's (_hold)
            shapes = [{**r, **c} for r in rate_shapes((*combo, name), base)
                      for c in creep_starts((*combo, name), base.get("creep_start"), len(va))]
            for var, shape in ((d, r) for d in drift_variants((*combo, name), len(va))
                               for r in shapes):
                fx = {**{k: x for k, x in base.items() if not (var and k in DRIFT_KEYS)},
                      **var, **shape}
                out.append(((combo, name, tuple(sorted(fx.items()))), fx))
        return out

    def single(key, fx):
        """The single fit ``key`` (made once: kept in the cache)."""
        combo, name = key[:2]
        if once is not None:
            return once.get(key, lambda: fit_one(name, combo, fx))
        if key not in cache:
            cache[key] = fit_one(name, combo, fx)
        return cache[key]

    def fit(name, combo=(), fixed_=None):
        """Best variant of ``name`` on top of ``combo``: (model, validate outputs). A creep
        with a level per record (its start ``"record"``, module creep) is kept only when it
        passes against the best other variant as an effect would (:func:`_passes`): a level
        measured on each validate record takes up any constant misfit, so by BIC alone it
        would replace a creep at rest that fits (3 of 4 such stages measured)."""
        best = levels = None
        for key, fx in variants(name, combo, fixed_):
            m, o = single(key, fx)
            score = _bic(va, o, m.k)
            if _flat_settling(m, tr, va, noise):  # a settling no bow tells from a trend
                continue
            if creep_levels((*combo, name), fx):
                if levels is None or score < levels[0]:
                    levels = (score, m, o)
            elif best is None or score < best[0]:
                best = (score, m, o)
        if levels is not None and (best is None or _passes(va, levels[1:], best[1:])):
            best = levels
        return best[1], best[2]

    def fit_one(name, combo, fx):
        with lend(pool):  # a search's points may go to the pool's idle threads
            m = fit_effect(name, tr, combo, fx, nominal)
        out = (m, [m.predict(s) for s in va])
        m.params.update(level_report(m, va, tr))
        _release(m, segs)  # (the bases' memos of this thread: module threads)
        return out

    def prefetch(calls) -> None:
        """With several threads: make the single fits of ``calls`` (``fit``'s arguments; each
        variant a fit of its own) on the pool, the longest first; the loops after them take
        them from the cache in their own order, so every comparison and tie is decided as on
        one thread."""
        if pool.workers > 1:
            fits = {key: fx for c in calls for key, fx in variants(*c)}
            pool.map(lambda kf: single(*kf),
                     sorted(fits.items(), key=lambda kf: -_cost(kf[0][1], kf[0][0], kf[1])))

    prefetch([(name,) for name in EFFECTS])
    candidates = []
    for i, name in enumerate(EFFECTS):
        progress(f"candidate {name} ({i + 1}/{len(EFFECTS)})")
        m, o = fit(name)
        params = dict(m.params)
        if "delay_samples" in params:
            params["delay_s"] = params["delay_samples"] * dt
        candidates.append({"effect": name, "params": params, "k": m.k,
                           "validate": _errors(va, o),
                           "delta_bic": _bic(va, o, m.k) - _bic(va, out_va, 0)})
    candidates.sort(key=lambda c: c["delta_bic"])
    corrections: dict = {}

    def aside(new, old, old_effects, fixed_, added) -> bool:
        """When the effect ``added`` is the drift: whether ``new`` passes against ``old`` (the
        effects ``old_effects``) once the chosen rate's own misfit on validate is set aside
        (module misfit, memoised per rate). Only the drift: the rate's refinement ignores each
        record's level and trend, which is what the drift models, so it cannot take the
        drift's part; an effect of the input history (asymmetry, creep, lags) can take part of
        what the refinement leaves of the rate's misfit (preisach_stage rate + creep seed 3:
        with the rate's filter refined, an asymmetry cut the RMS by 23 %, plainly by 14 %)."""
        def correction():
            key = (old_effects, tuple(fixed_.get(k) for k in RATE_KEYS))
            if key not in corrections:
                progress("the rate's own misfit set aside")
                corrections[key] = rate_correction(old_effects, fixed_, fit, va)
            return corrections[key]
        return added == "drift" and _passes_rate_aside(va, new, old, correction,
                                                       NOISE_STOP * noise)

    def beside(new, old, old_effects, fixed_, added) -> bool:
        """``new`` passes against ``old`` plainly (:func:`_passes`) or with a chosen rate's
        misfit set aside (``aside``): the revision's drop test."""
        return _passes(va, new, old) or aside(new, old, old_effects, fixed_, added)

    def choose(start=None, pairs=None):
        """The greedy rounds, the revision, the delay and drift preferences; ``start`` forces
        the first round's effect; ``pairs`` (a tuple of effects): every pair of the other effects
        tried in the first round beside the single effects, not only when none of them passes.
        Returns ``(chosen, fixed, model, validate outputs)``."""
        chosen: tuple[str, ...] = ()
        fixed: dict = {}
        current: Model = nominal
        cur_out = out_va
        for round_ in range(max_effects):
            progress(f"combinations, round {round_ + 1}")
            rms_now = _errors(va, cur_out)["rms"]
            if rms_now <= NOISE_STOP * noise:
                break
            best = None
            prefetch([(name, chosen, dict(fixed) if chosen else None)
                      for name in (EFFECTS if chosen or start is None else (start,))
                      if name not in chosen])
            for name in EFFECTS if chosen or start is None else (start,):
                if name in chosen:
                    continue
                m, o = fit(name, chosen, dict(fixed) if chosen else None)
                dbic = _bic(va, o, m.k) - _bic(va, cur_out, current.k)
                if best is None or dbic < best[0]:
                    best = (dbic, name, m, o)
            if best is None:
                break

            def accepted(b_, rms_now=rms_now):
                return b_[0] <= -MIN_BIC_DROP and \
                    _errors(va, b_[3])["rms"] <= (1 - MIN_RMS_CUT) * rms_now

            if not chosen and max_effects >= 2 and (pairs is not None or start is not None or
                                                    not accepted(best)):
                # two effects can mask each other (a drift confounds an asymmetry fitted alone):
                # when no single effect passes in the first round, try every pair jointly (a
                # forced start: every pair with it; ``pairs``: every pair without those)
                rest = [e for e in EFFECTS if e not in chosen and e not in (pairs or ())]
                prefetch([(name, (*chosen, first), dict(fixed) if chosen else None)
                          for i, first in enumerate(rest) for name in rest[i + 1:]
                          if start is None or start in (first, name)])
                for i, first in enumerate(rest):
                    for name in rest[i + 1:]:
                        if start is not None and start not in (first, name):
                            continue
                        m, o = fit(name, (*chosen, first), dict(fixed) if chosen else None)
                        dbic = _bic(va, o, m.k) - _bic(va, cur_out, current.k)
                        if dbic < best[0]:
                            best = (dbic, (first, name), m, o)
            if accepted(best) and pool.workers > 1:  # the fits the acceptance may need next
                then = chosen + (best[1] if isinstance(best[1], tuple) else (best[1],))
                prefetch((_refined_calls(chosen, fixed) if chosen else []) +
                         _lag_calls(then, _hold(dict(fixed), then, best[2].grid)))
            # accepted(best) is _passes against the current choice (its BIC difference known)
            if not accepted(best) and not (chosen and aside(best[2:], (current, cur_out),
                                                            chosen, fixed, best[1])):
                break
            if chosen and not _beyond_refinement((best[2], best[3]), chosen, fixed, fit, va):
                break  # the misfit of the effects chosen, not a further effect
            dbic, name, m, o = best
            chosen += name if isinstance(name, tuple) else (name,)
            _hold(fixed, chosen, m.grid)
            current, cur_out = m, o
            chosen, current, cur_out = _research_lag(chosen, (current, cur_out), fixed,
                                                     fit, va)
        progress("revising the choice")
        chosen, current, cur_out = _revise(chosen, current, cur_out, fixed, fit, va,
                                           (nominal, out_va), noise, beside,
                                           prefetch)
        chosen, current, cur_out = _prefer_delay(chosen, current, cur_out, fixed, fit, va, dt)
        chosen, current, cur_out = _prefer_drift(chosen, current, cur_out, fixed, fit, va,
                                                 noise)
        return chosen, fixed, current, cur_out

    chosen, fixed, current, cur_out = choose()
    if chosen and _unexplained(va, cur_out, _errors(va, out_va)["rms"],
                               _errors(va, cur_out)["rms"], noise, out_va)["present"]:
        # a gap left unexplained after the greedy path: the first effect may stand in for
        # two others that only pass together (a broad lag for creep and rate); paths that
        # start from the next candidates alone are tried, the lowest validate BIC kept
        best = (_bic(va, cur_out, current.k), (chosen, fixed, current, cur_out))
        for c in [c["effect"] for c in candidates if c["effect"] != chosen[0]][:ALT_STARTS]:
            path = choose(c)
            score = _bic(va, path[3], path[2].k)
            if path[0] and score < best[0] - MIN_BIC_DROP:
                best = (score, path)
        chosen, fixed, current, cur_out = best[1]
    elif max_effects >= 2:
        chosen, fixed, current, cur_out = _pairs_first((chosen, fixed, current, cur_out),
                                                       choose, fit, va, noise, progress)
    progress("the stand-ins of the effects chosen")
    interchangeable = _interchangeable(chosen, cur_out, fixed, fit, va)
    _forget_rates(segs)  # the choice is made: the band sums and contacts kept for its fits
    screen = None
    if screened:  # the choice, refitted on the whole records; the verdict's figures whole
        progress("the chosen model on the whole records")
        for s in segs:  # the screen's kept play-row Grams (and rows) are done with
            s.forget_grams()
        # the pool's threads end, with what they held per thread; fresh ones read the refit's
        # next chunks and make some of its chunk terms (module threads)
        pool.renew()
        tr, va, out_va = whole
        if chosen:
            current, cur_out = _whole_fit(chosen, current, tr, va, nominal,
                                          lambda s: _with_rows(s, radii, proj, at_rest),
                                          lambda s: _streamed(s, radii, proj, at_rest))
            _forget_rates(tr + va)  # what a rate refit kept of a whole record (its contacts)
        else:
            current, cur_out = nominal, out_va
        screen = {"samples": SCREEN_SAMPLES,
                  "confirmed": bool(not chosen or _passes(va, (current, cur_out),
                                                          (nominal, out_va)))}
    after = _errors(va, cur_out)
    regions = {r["region"]: r for r in where["regions"]}
    bands = {b["band"]: b["energy_share"] for b in where["spectrum"]}
    evidence = []
    for name in chosen:
        reg, band = EFFECT_SIGNATURES[name]
        evidence.append({"effect": name, "region": reg,
                         "concentration": regions.get(reg, {}).get("concentration"),
                         "band": band, "band_energy_share": bands.get(band)})
    unexplained = _unexplained(va, cur_out, before["rms"], after["rms"], noise, out_va)
    alternatives: list[str] = []
    if chosen:  # effects that alone explain the gap about as well as the first one chosen
        alone = {c["effect"]: c["validate"]["rms"] for c in candidates}
        alternatives = [e for e, r in alone.items()
                        if e != chosen[0] and r <= ALTERNATIVE_RMS * alone[chosen[0]]]
    effects = list(chosen) + (["unexplained"] if unexplained["present"] else [])
    verdict = {"effects": effects or ["none"], "gap_before": before["rms"],
               "gap_after": after["rms"], "shrink": 1 - after["rms"] / before["rms"],
               "max_before": before["max"], "max_after": after["max"],
               "gap_before_percent": before["rms_percent"],
               "gap_after_percent": after["rms_percent"], "noise_floor": noise,
               "noise_floor_method": noise_info["method"],
               "noise_floor_detail": noise_info["detail"],
               # records whose input follows the measured noise (noise.py): taken in closed loop
               "closed_loop_records": [(train + validate)[i].source
                                       for i in noise_info.get("closed_loop", ())],
               "gap_after_over_noise": after["rms"] / noise if noise > 0 else float("inf"),
               "unexplained": unexplained, "alternatives": alternatives,
               "interchangeable": interchangeable,
               "model": current.params, "evidence": evidence}
    if screen is not None:
        verdict["screen"] = screen
    if "creep" in chosen:
        verdict["creep_law"] = _creep_law(current.params)
    fitted = {"radii": radii, "projection": proj, "nominal": full_nominal,
              "reference": current.reference or nominal,
              "chosen": chosen,
              "model": current, "dt": dt, "initial_state": initial_state,
              # the exported model's plays (DiagnosedModel.plays_start): at v[0] as fitted;
              # at 0 when every record starts at 0 (the same columns; the nominal then keeps
              # its operator form, DiagnosedModel.operator_form)
              "plays_start": "v0" if at_rest and any(r.v[0] != 0.0 for r in train + validate)
              else "zero"}
    return DiagnosisReport(nominal_json, where, candidates, verdict, va, out_va, cur_out,
                           fitted)


def _whole_fit(chosen: tuple, screened: Model, tr, va, nominal: Model,
               rows: Callable[[Segment], Segment],
               streams: Callable[[Segment], Segment] | None = None) -> tuple:
    """The model ``screened`` (chosen on the records' first samples) refitted on the whole
    train records, every grid parameter held (``"held"``: no search, the linear part's order
    too), and its outputs on the whole validate records. ``tr`` and ``va`` are the records
    without play rows; ``rows`` gives a record its play rows: the train records' are built
    for the fit and dropped after it, then each validate record's in turn for its prediction
    (all at once for a drift, whose validate levels are read from every record). Keeps the
    screen's reports its refit does not make (the structures tried, the validate levels).

    ``streams`` gives a record streamed play rows instead (module streamed): used for every
    record longer than ``SCREEN_SAMPLES`` when the model can be streamed
    (:func:`.streamed.streamable`: not the rate, nor a filter before the hysteresis), so the
    refit and the predictions hold a chunk of the model's columns at a time, not a record's;
    the same coefficients, RSS and outputs to the bit (``streams=None``: the full rows)."""
    if streams is not None and streamable(chosen, screened.grid):
        rows = _long_streamed(rows, streams)
    trw = [rows(s) for s in tr]
    m = fit_effect(chosen[-1], trw, chosen[:-1], {**screened.grid, "held": True}, nominal)
    _release(m, trw)
    del trw
    vas = [rows(s) for s in va] if "drift" in chosen else None
    m.params = {**screened.params, **m.params, **level_report(m, vas or [], tr)}
    out = []
    for i, s in enumerate(va):
        w = vas[i] if vas else rows(s)
        out.append(m.predict(w))
        _release(m, [w])
    return m, out


def _long_streamed(rows: Callable, streams: Callable) -> Callable:
    """``streams`` for a record longer than ``SCREEN_SAMPLES``, ``rows`` for the others."""
    return lambda s: streams(s) if s.y.size > SCREEN_SAMPLES else rows(s)


def _creep_law(params: dict) -> dict | None:
    try:
        return creep_law(params["creep_lag_gains"], params["creep_time_constants_s"])
    except ValueError:
        return None


def _forget_rates(segs: list[Segment]) -> None:
    """Drop what the segments' rate bases keep for every fit and thread (``RateBasis.forget``)."""
    for s in segs:
        if s.rate_basis is not None:
            s.rate_basis.forget()


def _release(model: Model, segs: list[Segment]) -> None:
    """Drop what a fit memoised over the records (the model's columns, the rate and filter
    bases' columns): the diagnosis keeps every fitted candidate and its validate outputs, so
    its memory stays that of the records' play columns, not one copy per candidate."""
    model.release()
    for s in segs:
        for basis in (s.rate_basis, s.wiener_basis):
            if basis is not None:
                basis.release()


def _revise(chosen, current, cur_out, fixed, fit, va, nominal, noise, beside=None,
            prefetch=None):
    """Revise the greedy choice on the terms it was made on (each effect must lower the
    validate BIC by ``MIN_BIC_DROP`` and cut the validate RMS by ``MIN_RMS_CUT`` given the
    others). Greedy rounds judge a candidate beside the effects chosen so far only, so an
    effect chosen early can be a stand-in for one that would only pass beside a later one (a
    mode for a fractional delay while an unmodelled drift dominates the validate gap). So:
    first swap one chosen effect for an unchosen one while that passes the test against the
    current combination, then drop every effect that no longer passes it against the
    combination without it (or whose removal leaves the gap within ``NOISE_STOP`` times the
    noise floor); ``beside(new, old, old_effects, fixed, dropped)`` is that drop test (None:
    :func:`_passes`; the diagnosis sets a chosen rate's own misfit aside, module misfit, as
    when the effect was added). Other effects keep their grid parameters; returns ``(chosen,
    model, validate outputs)``. ``prefetch(calls)`` (None: none) makes a step's refits
    (``fit``'s arguments) beforehand, on several threads (``fit`` keeps them; the step then
    takes them in its own order)."""
    def keys_of(e):  # grid parameters of an effect, as its single fit reports them (a drift's
        # and a rate's all of their kind: a single fit of another family or variant lacks some,
        # e.g. rate_growth, which a held SCALED rate needs)
        return set(fit(e)[0].grid) | set({"drift": DRIFT_KEYS, "rate": RATE_KEYS,
                                          "creep": ("creep_start", "creep_levels")}.get(e, ()))

    def call(effects):  # fit's arguments for the combination ``effects`` (not empty)
        kept = {k: x for k, x in fixed.items() if any(k in keys_of(e) for e in effects)}
        return effects[-1], effects[:-1], kept or None

    def refit(effects):
        return fit(*call(effects)) if effects else nominal

    def passes(new, old):
        return _passes(va, new, old)

    cur = (current, cur_out)
    for _ in range(len(EFFECTS)):  # swaps, the best first
        best = None
        if prefetch is not None:
            prefetch([call((*(c for c in chosen if c != e), x)) for e in chosen
                      for x in EFFECTS if x not in chosen])
        for e in chosen:
            rest = tuple(c for c in chosen if c != e)
            for x in (x for x in EFFECTS if x not in chosen):
                new = refit((*rest, x))
                score = _bic(va, new[1], new[0].k)
                if passes(new, cur) and (best is None or score < best[0]):
                    best = (score, (*rest, x), new)
        if best is None:
            break
        chosen, cur = best[1], best[2]
        _hold(fixed, chosen, cur[0].grid)
    while chosen:  # drops, the least needed first
        worst = None
        if prefetch is not None:
            prefetch([call(rest) for rest in (tuple(c for c in chosen if c != e)
                                              for e in chosen) if rest])
        for e in chosen:
            rest = tuple(c for c in chosen if c != e)
            without = refit(rest)
            needed = passes(cur, without) if beside is None else \
                beside(cur, without, rest, fixed, e)
            if needed and _errors(va, without[1])["rms"] > NOISE_STOP * noise:
                continue  # still needed
            score = _bic(va, without[1], without[0].k)
            if worst is None or score < worst[0]:
                worst = (score, rest, without)
        if worst is None:
            break
        chosen, cur = worst[1], worst[2]
    return chosen, cur[0], cur[1]


def _pairs_first(path: tuple, choose: Callable, fit, va, noise: float,
                 progress: Callable[[str], None]) -> tuple:
    """The choice ``path`` (``(chosen, fixed, model, validate outputs)``, its gap not
    unexplained), or the path of ``choose(pairs=chosen)``: the rounds again with every pair of
    the effects not chosen tried in the first round beside the single effects (a pair with a
    chosen effect only adds one to it: the greedy rounds judged that). Tried only when ``path``
    names an effect and leaves the validate RMS above ``PAIR_LOOK`` noise floors: one effect
    can stand in for a pair that passes only together (blind asymmetry + creep s0: a delay of
    3.7 ms cut the gap from 43 to 12.6 noise floors; the asymmetry and the creep together, to
    2.1). The new path is kept when it passes against ``path`` (:func:`_passes`) and against
    each of its effects refined one step (:func:`_beyond_refinement`), and does not merely add
    effects to it (the greedy rounds judged those)."""
    chosen, fixed, current, cur_out = path
    if not chosen or _errors(va, cur_out)["rms"] <= PAIR_LOOK * noise:
        return path
    progress("a gap well above the noise: every pair tried first")
    new = choose(pairs=chosen)
    if new[0] and not set(chosen) <= set(new[0]) and \
            _passes(va, new[2:], (current, cur_out)) and \
            _beyond_refinement(new[2:], chosen, fixed, fit, va):
        return new
    return path


def _hold(fixed: dict, effects: tuple, grid: dict) -> dict:
    """``fixed`` (changed in place and returned) updated with the grid parameters of the model
    chosen for ``effects``, and the start of its creep (:func:`.creep.start_hint`: the rest
    start is no grid key) held as ``fixed["creep_start"]`` (none without a creep): every fit
    built on that model keeps it (:func:`.creep.creep_starts`), while a creep entering a
    combination, or beside a lag searched again (:func:`_lag_calls`), has every start scored
    (creep61: not anew for every combination)."""
    fixed.pop("creep_start", None)
    fixed.update(grid)
    if "creep" in effects:
        fixed["creep_start"] = start_hint(grid)
    return fixed


def _passes(va, new, old) -> bool:
    """Whether the model and validate outputs ``new`` pass against ``old``: the validate BIC
    lower by ``MIN_BIC_DROP`` and the validate RMS cut by ``MIN_RMS_CUT``."""
    (m, o), (mb, ob) = new, old
    return (_bic(va, o, m.k) - _bic(va, ob, mb.k) <= -MIN_BIC_DROP
            and _errors(va, o)["rms"] <= (1 - MIN_RMS_CUT) * _errors(va, ob)["rms"])


def _passes_rate_aside(va, new, old, correction: Callable, stop: float = 0.0) -> bool:
    """Whether ``new`` passes against ``old`` once the chosen rate's own misfit on validate
    is set aside: ``new`` lowers the validate BIC by ``MIN_BIC_DROP`` as it is, and passes
    :func:`_passes` with ``correction()`` (:func:`.misfit.rate_correction`, computed only
    then; None: no refinement to set aside) added to both models' validate outputs, while
    ``old`` so corrected stays above ``stop`` (the diagnosis: ``NOISE_STOP`` noise floors,
    where the rounds stop). A rate fitted on slow train records and extrapolated to fast
    validate ones leaves an error no other effect can cut; a real drift beside it then cut
    the validate RMS by 3-6 % only."""
    (m, o), (mb, ob) = new, old
    if _bic(va, o, m.k) - _bic(va, ob, mb.k) > -MIN_BIC_DROP:
        return False
    c = correction()
    if c is None:
        return False
    old_c = [x + d for x, d in zip(ob, c, strict=True)]
    return _errors(va, old_c)["rms"] > stop and _passes(
        va, (m, [x + d for x, d in zip(o, c, strict=True)]), (mb, old_c))


def _beyond_refinement(new, chosen, fixed, fit, va) -> bool:
    """The second-effect rule: an effect added to ``chosen`` (``new``: its model and validate
    outputs) must also pass against each chosen effect's own model refined one step, the
    others held at ``fixed``: ``creep`` with a further lag; ``dynamics`` after the hysteresis
    searched again beside the others (its base mode was chosen before they were modelled) with
    one further element of its linear part. So a misfit of one effect is not named as
    another."""
    for call in _refined_calls(chosen, fixed):
        if not _passes(va, new, fit(*call)):
            return False
    return True


def _refined_calls(chosen, fixed) -> list[tuple]:
    """The fits (``fit``'s arguments) of :func:`_beyond_refinement`, in its order: the
    combination ``chosen`` with each chosen effect's own model refined one step."""
    calls = []
    for e in chosen:
        if e == "creep":
            refined = {**fixed, "refine": "creep"}
        elif e == "dynamics" and "wiener" not in fixed:
            refined = {**{k: x for k, x in fixed.items() if k not in DYNAMICS_KEYS},
                       "lti_min": len(fixed.get("lti", ())) + 1}
        else:
            continue
        calls.append((chosen[-1], chosen[:-1], refined))
    return calls


def _lag_calls(chosen, fixed) -> list[tuple]:
    """The fits (``fit``'s arguments) of :func:`_research_lag`, in its order: the lag chosen
    searched again beside the other effects, then the other lag in its place (none when
    ``chosen`` is not one lag beside other effects)."""
    lags = [e for e in chosen if e in LAG_EFFECTS]
    if len(chosen) < 2 or len(lags) != 1:
        return []
    # the creep's start scored again with the lag (chosen beside the lag searched before)
    kept = {k: x for k, x in fixed.items() if k not in (*LAG_KEYS, "creep_start")} | \
        {"search_all": True}
    other = next(e for e in LAG_EFFECTS if e != lags[0])
    return [(option[-1], option[:-1], dict(kept))
            for option in (chosen, tuple(other if e == lags[0] else e for e in chosen))]


def _cost(name: str, combo: tuple, fx: dict) -> int:
    """A rough rank of a single fit's cost (the pool starts the longest first): a mode search,
    a rate's exact-shape search or a lag searched again with every play column costs tens to
    hundreds of passes, a creep or asymmetry a few."""
    return sum({"dynamics": 4, "rate": 4, "drift": 2, "delay": 2}.get(e, 1)
               for e in (*combo, name)) + 4 * bool(fx.get("rate_shape")) \
        + 4 * bool(fx.get("search_all"))


def _research_lag(chosen, cur, fixed, fit, va):
    """After an effect is accepted beside others: the lag effect chosen (``dynamics`` or
    ``delay``, exactly one) searched again with the other effects present, and the other lag
    effect tried in its place (its own parameters searched with the others held). A lag chosen
    in an earlier round was chosen with a confounding effect unmodelled (a base mode picked
    while an asymmetry dominated the gap); the two names are alternatives for one part of the
    model, so the lowest validate BIC of the three decides (``cur``: the current model and
    validate outputs). The mode is searched with every play column (``"search_all"``): with
    the leading columns only, a base mode searched beside an asymmetry ran to the grid's
    lower end (density_stage seed 1: train RMS 0.148 um against 0.053 um at the stage's own
    mode). ``fixed`` is updated; returns ``(chosen, model, validate outputs)``."""
    calls = _lag_calls(chosen, fixed)
    if not calls:
        return chosen, cur[0], cur[1]
    best = (_bic(va, cur[1], cur[0].k), chosen, cur)
    for call in calls:
        option = (*call[1], call[0])
        new = fit(*call)
        score = _bic(va, new[1], new[0].k)
        if score < best[0]:
            best = (score, option, new)
    if best[1] is not chosen or best[2] is not cur:
        for k in LAG_KEYS:
            fixed.pop(k, None)
        _hold(fixed, best[1], best[2][0].grid)
    return best[1], best[2][0], best[2][1]


def _interchangeable(chosen, cur_out, fixed, fit, va) -> list[dict]:
    """The effects chosen that the records do not tell from their usual stand-in
    (``STAND_INS``: ``delay`` and ``dynamics``, ``creep`` and ``drift``): the stand-in in the
    effect's place, the other effects held at ``fixed``, fits the validate records within
    ``ALTERNATIVE_RMS`` of the choice (``cur_out``: its validate outputs). A mode and a real
    pole above the input's band act on it as a delay of a millisecond or two (density_stage
    creep + dynamics + delay: the three fitted together validate within 4-6 % of any two).
    Returns one dict per such effect: ``effect``, ``instead`` (the stand-in), its validate
    ``rms`` and its ``ratio`` to the choice's."""
    out: list[dict] = []
    rms = _errors(va, cur_out)["rms"]
    for e in chosen:
        if e not in STAND_INS or STAND_INS[e][0] in chosen:
            continue
        other = STAND_INS[e][0]
        r = _errors(va, _stand_in_fit(e, chosen, fixed, fit)[1])["rms"]
        if r <= ALTERNATIVE_RMS * rms:
            out.append({"effect": e, "instead": other, "rms": float(r),
                        "ratio": float(r / rms) if rms > 0 else 1.0})
    return out


def _stand_in_fit(effect, chosen, fixed, fit):
    """``fit`` of ``effect``'s stand-in (``STAND_INS``) in its place among ``chosen``: the
    other effects held at ``fixed``, the keys of ``effect``'s grid freed (``fixed`` holds a
    creep's start only with a creep chosen, :func:`_hold`). Returns (model, validate
    outputs)."""
    other, keys = STAND_INS[effect]
    rest = tuple(c for c in chosen if c != effect)
    kept = {k: x for k, x in fixed.items() if k not in keys}
    return fit(other, rest, kept or None)


def _prefer_delay(chosen, current, cur_out, fixed, fit, va, dt):
    """A chosen ``dynamics`` that acts as a pure delay on the records (gain within 10 % of 1
    over the lower quarter of the band, :mod:`.delaylike`) gives way to ``delay`` when the
    delay in its place fits the validate records within ``ALTERNATIVE_RMS`` (a fast, damped
    mode or two imitate a delay of a sample; the delay is the simpler name). Returns
    ``(chosen, model, validate outputs)``."""
    if "dynamics" not in chosen or "delay" in chosen or not is_delay_like(current.params, dt):
        return chosen, current, cur_out
    m, o = _stand_in_fit("dynamics", chosen, fixed, fit)
    if _errors(va, o)["rms"] <= ALTERNATIVE_RMS * _errors(va, cur_out)["rms"]:
        return tuple("delay" if c == "dynamics" else c for c in chosen), m, o
    return chosen, current, cur_out


def _prefer_drift(chosen, current, cur_out, fixed, fit, va, noise: float):
    """A chosen ``creep`` (without a drift) gives way to ``drift`` when the drift in its place,
    the other effects held, fits the validate records within ``ALTERNATIVE_RMS`` and what the
    creep explains beyond it, ``sqrt(rms_drift**2 - rms_creep**2)``, is under
    ``DRIFT_LIKE_CREEP`` noise floors (``fixed`` is updated): a creep whose lags restart with
    each record (or start at common levels) is a slow trend on each record's clock, and with a
    few more parameters it can take a drift's place by taking a little of another effect's
    misfit (pi_stage delay + drift on the record clock, seed 1: 0.25 floors beyond the drift,
    RMS ratio 1.024; the creeps of the three generators' creep cases explain 0.76-24 floors
    beyond it). The drift, independent of the input history, is the simpler name. Returns
    ``(chosen, model, validate outputs)``."""
    if "creep" not in chosen or "drift" in chosen:
        return chosen, current, cur_out
    m, o = _stand_in_fit("creep", chosen, fixed, fit)
    r_drift, r_creep = _errors(va, o)["rms"], _errors(va, cur_out)["rms"]
    beyond = np.sqrt(max(r_drift ** 2 - r_creep ** 2, 0.0))
    if r_drift <= ALTERNATIVE_RMS * r_creep and beyond < DRIFT_LIKE_CREEP * noise:
        chosen = tuple("drift" if c == "creep" else c for c in chosen)
        fixed.pop("creep_levels", None)
        _hold(fixed, chosen, m.grid)
        return chosen, m, o
    return chosen, current, cur_out


def _unexplained(va, outputs, gap_before: float, gap_after: float, noise: float,
                 nominal_outputs) -> dict:
    """The part of the validate gap no accepted effect explains: its share of the gap energy
    before (``(gap_after^2 - noise^2) / gap_before^2``) and where the remaining residual lies.
    A gap that a gain per validate record explains (:func:`.gain.record_gains`, on the chosen
    model's or the nominal's residual: a drift's out-of-fold levels vary within a record) is
    unexplained whatever its share, with the gains named in ``gain`` and ``note``."""
    share = max(gap_after**2 - noise**2, 0.0) / max(gap_before**2, 1e-300)
    above = gap_after > UNEXPLAINED_FACTOR * noise
    gain = (record_gains(va, outputs, noise) or record_gains(va, nominal_outputs, noise)) \
        if above else None
    present = above and (share > UNEXPLAINED_SHARE or gain is not None)
    out: dict = {"present": bool(present), "share": share}
    if gain is not None:
        out["gain"] = gain
        out["note"] = gain_note(gain)
    if present:
        wb = residual_breakdown(va, [s.y - o for s, o in zip(va, outputs, strict=True)])
        out["where"] = [r["region"] for r in wb["regions"][:3]]
        out["band"] = max(wb["spectrum"], key=lambda b: b["energy_share"])["band"]
    return out
