"""The identification chain: plays and weights from the loop slopes, then radii.

``method="adaptive"`` (the paper's): :func:`~pimodel.identification.slopes.identify_slopes` gives
the number of plays, the weights and first radius guesses; the adaptive estimator then runs
over the record, repeated ``passes`` times from its first reversal (rate independence makes the
repetition a longer periodic excitation), and the average of the estimate over the last half
of the run starts the batch refinement
(:func:`~pimodel.identification.adaptive.polish.refine_radii`: least squares on the output with
the slopes' weights) for records of up to ``REFINE_LIMIT`` samples x plays; longer records keep
the average. ``method="conventional"``: preset radii, least-squares weights
(:func:`~pimodel.identification.conventional.fit_conventional`). ``method="joint"`` (beyond the
paper): the number of plays and the linear-play choice from the slopes, then weights and radii
together by the joint estimator (:class:`~pimodel.identification.adaptive.joint.JointEstimator`,
one pass). All model ``y[k] = PI[v][k] + offset`` with zero initial play states.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from .._native import LIMITS
from ..checks import as_signal, integer_in, positive_scalar
from ..operators.pi import PIOperator
from .adaptive.health import EstimatorHealth, estimator_health, refined_health
from .adaptive.joint import JointEstimator
from .adaptive.polish import refine_radii
from .adaptive.radius_estimator import RadiusEstimator, stream_tail_average
from .adaptive.settings import _norm2
from .branches import find_reversals
from .conventional import fit_conventional
from .identifiability import ExcitationReport, check_excitation
from .play_reduction import PlayReduction, reduce_plays
from .slopes import SlopeIdentification, identify_slopes

__all__ = [
    "Identification",
    "identify",
    "max_passes",
]

METHODS = ("adaptive", "conventional", "joint")
HISTORY_LIMIT = 2_000_000  # samples (record x passes) up to which the estimate history is kept
REFINE_LIMIT = 10_000_000  # samples x plays up to which the radii are refined in batch
MAX_PLAYS = LIMITS["PIM_MAX_PLAYS"]  # the FMUs' limit too
MAX_REPEATED_SAMPLES = 20_000_000  # passes * record length: bounds the repeated record's memory
PROGRESS_CHUNK = 1_000_000  # samples per chunk of a long estimator pass, each announced
MIN_LOOP_R2 = 0.5               # below: "no hysteresis loop found" warning


def max_passes(n_samples: int) -> int:
    """Largest ``passes`` for a record of ``n_samples``: ``MAX_REPEATED_SAMPLES // n_samples``
    (the repeated record is held in memory, 16 bytes per sample).

    Parameters
    ----------
    n_samples : int
        Length of the record.

    Returns
    -------
    int
        The bound on :func:`identify`'s ``passes`` (0 when the record alone exceeds it).

    Examples
    --------
    >>> max_passes(600), max_passes(1_000_000)
    (33333, 20)
    """
    return MAX_REPEATED_SAMPLES // max(int(n_samples), 1)


def _warn_if_no_loop(slopes: SlopeIdentification) -> None:
    if slopes.r2 < MIN_LOOP_R2:
        warnings.warn(
            f"y: no hysteresis loop found: the loop-branch fit explains {100 * slopes.r2:.2g} % "
            f"of the output variance along the branches (R^2 = {slopes.r2:.3g}, expected > "
            f"{MIN_LOOP_R2}; branch fit RMS {slopes.rms:.3g}); is y noise, or unrelated to v? "
            "The model returned describes noise", RuntimeWarning, stacklevel=3)


@dataclass
class Identification:
    """An identified model ``y = PI[v] + offset`` with its fit errors on the record.

    Parameters
    ----------
    operator : PIOperator
        The identified operator (zero initial play states).
    offset : float
        Output offset (output unit), the mean of ``y - PI[v]``.
    method : {"adaptive", "conventional", "joint"}
        How it was identified.
    rms_error : float
        RMS of ``PI[v] + offset - y`` on the record (output unit).
    max_error : float
        Largest absolute error on the record (output unit).
    output_range : float
        Peak-to-peak of ``y`` (output unit).
    excitation : ExcitationReport
        Whether the record excites every play
        (:func:`pimodel.identification.identifiability.check_excitation`).
    slopes : SlopeIdentification, optional
        The loop-slope identification (None for the conventional method).
    settings : dict, optional
        Settings used (gains, passes, guard, ...).
    health : EstimatorHealth, optional
        Adaptive method: the radius estimate's health.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = 2 * np.sin(np.linspace(0, 6 * np.pi, 600))     # three periods
    >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
    >>> ident = identify(v, y, dt=1e-3, n_plays=2, passes=2)
    >>> ident.method, ident.weights.round(3), ident.radii.round(3)
    ('adaptive', array([1. , 0.5]), array([0. , 0.4]))
    """

    operator: PIOperator
    offset: float
    method: str
    rms_error: float
    max_error: float
    output_range: float
    excitation: ExcitationReport
    slopes: SlopeIdentification | None = None
    settings: dict = field(default_factory=dict)
    health: EstimatorHealth | None = None  # adaptive method: the radius estimate's health

    @property
    def weights(self) -> np.ndarray:
        """Weights ``p_i`` of the identified operator."""
        return self.operator.weights

    @property
    def radii(self) -> np.ndarray:
        """Radii ``r_i`` of the identified operator (input unit), non-decreasing."""
        return self.operator.radii

    def predict(self, v) -> np.ndarray:
        """Model output ``PI[v] + offset`` from zero initial state.

        Parameters
        ----------
        v : array_like of float, shape (N,)
            Input samples ``v[k]`` (input unit).

        Returns
        -------
        numpy.ndarray of float, shape (N,)
            ``y[k] = PI[v][k] + offset`` (output unit).

        Raises
        ------
        ValueError
            If ``v`` is not a finite 1-D signal.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> v = 2 * np.sin(np.linspace(0, 6 * np.pi, 600))     # three periods
        >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
        >>> ident = identify(v, y, dt=1e-3, n_plays=2, passes=2)
        >>> bool(np.allclose(ident.predict([0.0, 1.0]), [0.0, 1.3]))
        True
        """
        return self.operator.simulate(v) + self.offset

    def to_json(self) -> dict:
        """The model, its fit and the reports as a JSON-ready dict.

        Returns
        -------
        dict
            ``method``, ``n_plays``, ``weights``, ``radii``, ``offset``, ``fit`` (errors, also
            in % of the output range), ``excitation``, ``slopes``, ``settings``, ``health``.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> v = 2 * np.sin(np.linspace(0, 6 * np.pi, 600))     # three periods
        >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
        >>> ident = identify(v, y, dt=1e-3, n_plays=2, passes=2)
        >>> d = ident.to_json()
        >>> d["n_plays"], d["fit"]["rms_error_percent"] < 1e-3
        (2, True)
        """
        return {
            "method": self.method,
            "n_plays": self.operator.n,
            "weights": self.weights.tolist(),
            "radii": self.radii.tolist(),
            "offset": self.offset,
            "fit": {
                "rms_error": self.rms_error,
                "max_error": self.max_error,
                "output_range": self.output_range,
                "rms_error_percent": 100 * self.rms_error / self.output_range,
                "max_error_percent": 100 * self.max_error / self.output_range,
            },
            "excitation": self.excitation.to_json(),
            "slopes": self.slopes.to_json() if self.slopes else None,
            "settings": self.settings,
            "health": self.health.to_json() if self.health else None,
        }

    def save_json(self, path) -> Path:
        """Write :meth:`to_json` to ``path`` (parent directories created).

        Parameters
        ----------
        path : str or Path
            The JSON file (overwritten).

        Returns
        -------
        pathlib.Path
            ``path``.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from pimodel import PIOperator
        >>> v = 2 * np.sin(np.linspace(0, 6 * np.pi, 600))     # three periods
        >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
        >>> ident = identify(v, y, dt=1e-3, n_plays=2, passes=2)
        >>> ident.save_json(pathlib.Path(tempfile.mkdtemp()) / "model.json").name
        'model.json'
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_json(), indent=2))
        return path


def _repeated_chunks(v: np.ndarray, y: np.ndarray, offset: float, first: int, passes: int,
                     chunk: int, progress: Callable[[float], None]
                     ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """The record repeated for ``passes`` passes, in chunks, never joined whole.

    The repeated record is ``vv = [v, v[first:], ..., v[first:]]`` (``passes - 1`` repeats)
    and ``yy`` the same of ``y - offset``; chunk ``j`` is ``vv[j*chunk:(j+1)*chunk]`` and its
    ``yy``, the same samples as slicing the joined arrays, so an estimator run over the chunks
    equals its run over the joined record (to the bit). ``progress(share)`` is called before
    each chunk with the share of the samples done. Holds one chunk at a time.
    """
    pieces = [(0, v.size)] + [(first, v.size)] * (passes - 1)
    total = sum(b - a for a, b in pieces)
    done, i, at = 0, 0, 0  # samples yielded; the piece and the position in it
    while done < total:
        progress(done / total)
        parts, need = [], min(chunk, total - done)
        while need:
            a, b = pieces[i]
            lo = max(a, at)
            take = min(need, b - lo)
            parts.append(slice(lo, lo + take))
            need -= take
            at = lo + take
            if at == b:
                i, at = i + 1, 0
        cv = np.concatenate([v[s] for s in parts]) if len(parts) > 1 else v[parts[0]]
        cy = np.concatenate([y[s] for s in parts]) if len(parts) > 1 else y[parts[0]]
        yield cv, cy - offset
        done += cv.size


def _errors(op: PIOperator, v: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    base = op.simulate(v)
    offset = float(np.mean(y - base))
    r = base + offset - y
    return offset, float(np.sqrt(np.mean(r**2))), float(np.max(np.abs(r)))


def identify(v, y, *, dt: float, n_plays: int | None = None, method: str = "adaptive",
             gains=None, passes: int | None = None, linear_play: bool | None = None,
             guard: float | None = None, conventional_span: float | None = None,
             max_segments: int = 8,
             progress: Callable[[str], None] | None = None) -> Identification:
    """Identify a PI model from a record ``(v[k], y[k])`` sampled every ``dt`` seconds.

    The adaptive method refines the online estimate in batch (see the module docstring;
    ``settings["radii_from"]`` says which estimate the radii are), reports the health of its
    radius estimate (``health``, :mod:`pimodel.identification.adaptive.health`) and warns
    when it fails. The model is
    ``y[k] = PI[v][k] + offset`` with zero initial play states.

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples (input unit), N >= 10, not constant.
    y : array_like of float, shape (N,)
        Measured output (output unit).
    dt : float
        Sample time [s].
    n_plays : int, optional
        Fixed number of plays, from 1 to 64 (adaptive: else chosen by BIC on the slopes;
        conventional: default 10).
    method : {"adaptive", "conventional", "joint"}, optional
        See the module docstring. Default ``"adaptive"``.
    gains : float or array_like of float, optional
        Estimator gains (default ``20 / sum p_i^2``, a convergence rate of about 20/s whatever
        the units).
    passes : int, optional
        Repetitions of the record, from 1 to ``max_passes(len(v))`` (2e7 samples in all;
        default: enough for 200 s of adaptation, at least 3, within that bound).
    linear_play : bool, optional
        Force (True) or forbid (False) a linear play ``r_1 = 0``; default: chosen from the
        slopes.
    guard : float, optional
        Estimator breakpoint guard (input unit; default 0.2 % of the input range).
    conventional_span : float, optional
        Conventional method: the span of the preset radii (input unit; default from the
        record).
    max_segments : int, optional
        Most loop-branch segments tried by the slope fit (1 to 65). Default 8.
    progress : callable, optional
        Called with a short message at each stage (the slopes, the radius estimator with the
        share of its samples done, every ``PROGRESS_CHUNK`` samples on a long record, the
        refinement, the errors), as :func:`pimodel.diagnosis.diagnose`'s ``progress``.

    Returns
    -------
    Identification
        The model, its errors on the record and the reports.

    Raises
    ------
    ValueError
        Bad input (unequal lengths, a constant input, an unknown method, ``n_plays`` or
        ``passes`` out of range, ``dt <= 0``); the message names the argument.

    Warns
    -----
    RuntimeWarning
        When the record shows no hysteresis loop (slope-fit R^2 < 0.5) and when the joint fit
        has more plays than the data resolve (they are merged or dropped).
    UserWarning
        When the adaptive radius estimate fails its health check.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> v = 2 * np.sin(np.linspace(0, 6 * np.pi, 600))     # three periods
    >>> y = PIOperator([1.0, 0.5], [0.0, 0.4]).simulate(v)
    >>> ident = identify(v, y, dt=1e-3, n_plays=2, passes=2)
    >>> ident.weights.round(3), ident.radii.round(3), ident.health.ok
    (array([1. , 0.5]), array([0. , 0.4]), True)
    """
    # numpy's BLAS on one thread: the fits here are small least squares, which a BLAS thread per
    # core makes slower, up to 1.9x with another process busy (docs/identification.md)
    with threadpool_limits(1, user_api="blas"):
        v = as_signal(v, "v", min_length=10)
        y = as_signal(y, "y", min_length=10)
        if v.size != y.size:
            raise ValueError(f"v and y: expected equal lengths, got {v.size} and {y.size}")
        dt = positive_scalar(dt, "dt")
        if method not in METHODS:
            raise ValueError(f"method: expected one of {METHODS}, got {method!r}")
        if np.ptp(v) == 0:
            raise ValueError("v: the input is constant; identification needs a varying input")
        if n_plays is not None:
            n_plays = integer_in(n_plays, "n_plays", 1, MAX_PLAYS)
        if passes is not None:
            passes = integer_in(passes, "passes", 1, max_passes(v.size))
        max_segments = integer_in(max_segments, "max_segments", 1, MAX_PLAYS + 1)
        progress = progress or (lambda message: None)

        if method == "conventional":
            progress("conventional fit")
            n = 10 if n_plays is None else n_plays
            fit = fit_conventional(v, y, n, span=conventional_span)
            exc = check_excitation(v, fit.operator.weights, fit.operator.radii)
            offset, rms, mx = _errors(fit.operator, v, y)
            return Identification(fit.operator, offset, method, rms, mx, float(np.ptp(y)), exc,
                                  settings={"n_plays": n, "span": fit.span})

        progress("loop slopes (number and weights of plays)")
        slopes = identify_slopes(v, y, n_plays=n_plays, linear_play=linear_play,
                                 max_segments=max_segments)
        _warn_if_no_loop(slopes)
        if method == "joint":
            progress("joint estimation of weights and radii")
            return _identify_jointly(v, y, slopes, n_plays)
        p = slopes.weights
        exc = check_excitation(v, p, slopes.radii_guess)
        guess = PIOperator(p, slopes.radii_guess)
        offset, _, _ = _errors(guess, v, y)

        if gains is None:
            try:
                pp = _norm2(p)
            except ValueError as err:  # weights taken from y's loop slopes: y's scale is at fault
                raise ValueError(f"y: the loop slopes' {err}") from None
        g = 20.0 / pp if gains is None else gains
        rev = find_reversals(v, 0.01 * float(np.ptp(v)))
        first = rev[0] if rev else 0
        if passes is None:
            passes = min(max(3, int(np.ceil(200.0 / (dt * (v.size - first))))),
                         max(1, max_passes(v.size)))
        total = v.size + (passes - 1) * (v.size - first)
        guard_ = 0.002 * float(np.ptp(v)) if guard is None else guard
        est = RadiusEstimator(p, dt=dt, gains=g, initial_radii=slopes.radii_guess,
                              linear_play=slopes.linear_play, guard=guard_)
        progress(f"radius estimator ({passes} passes, {total:,} samples)")
        if total <= HISTORY_LIMIT:  # keep the history for the health report
            vv = np.concatenate([v] + [v[first:]] * (passes - 1))
            yy = np.concatenate([y] + [y[first:]] * (passes - 1)) - offset
            run = est.run(vv, yy)
            radii = run.history[vv.size // 2:].mean(axis=0)
            health = estimator_health(vv, p, run.history, linear_play=slopes.linear_play, y=yy,
                                      error=run.error)
        else:  # long record: bounded memory (the passes never joined), health from the final mean
            chunks = _repeated_chunks(
                v, y, offset, first, passes, PROGRESS_CHUNK,
                progress=lambda share: progress(f"radius estimator ({passes} passes, "
                                                f"{total:,} samples): {100 * share:.0f} %"))
            _, radii = stream_tail_average(est, chunks, total=total, tail=0.5)
            health = estimator_health(v, p, radii[None, :], linear_play=slopes.linear_play)
        radii_from = "average of the estimate over the last half"
        if v.size * p.size <= REFINE_LIMIT:  # the batch refinement holds N x n arrays
            progress("batch refinement of the radii")
            offset = float(np.mean(y - PIOperator(p, radii).simulate(v)))
            # the last half, as the online mean: a real stage's start-up (creep from its initial
            # state) is not in the model (shared real record, held-out RMS: 0.113 um fitting all
            # of it, 0.086 um fitting the last half, 0.089 um for the online mean alone)
            radii = refine_radii(v, y - offset, p, radii, tail=0.5, linear_play=slopes.linear_play)
            health = refined_health(v, y - offset, p, radii, linear_play=slopes.linear_play)
            radii_from = ("batch refinement (refine_radii, last half of the record) from the "
                          "average over the last half")
        if not health.ok:
            warnings.warn("identify: radius estimate health: " + "; ".join(health.messages),
                          UserWarning, stacklevel=2)
        progress("errors on the record")
        op = PIOperator(p, radii)
        offset, rms, mx = _errors(op, v, y)
        settings = {"gains": np.broadcast_to(g, p.shape).tolist(), "passes": passes,
                    "guard": guard_, "radii_from": radii_from}
        return Identification(op, offset, method, rms, mx, float(np.ptp(y)), exc, slopes, settings,
                              health)


def _identify_jointly(v: np.ndarray, y: np.ndarray, slopes: SlopeIdentification,
                      n_plays: int | None) -> Identification:
    threshold = 0.01 * float(np.ptp(v))
    est = JointEstimator(slopes.weights.size, linear_play=slopes.linear_play,
                         initial_weights=np.maximum(slopes.weights, 0.0),
                         initial_radii=slopes.radii_guess, threshold=threshold,
                         refit_every=1_000_000)  # offline: the first update and the final one
    est.run(v, y)
    res = est.finish()
    if n_plays is not None and res.update_index.size:
        # more plays asked than the data may show: merge or drop the unresolved ones
        red = reduce_plays(*est.binned(), res.weights, res.radii,
                           linear_play=slopes.linear_play)
    else:  # the slopes chose the number: only a zero weight is dropped
        keep = res.weights > 0
        red = PlayReduction(res.weights[keep], res.radii[keep], dropped=[
            (float(r), float(w)) for r, w in zip(res.radii[~keep], res.weights[~keep],
                                                 strict=True)])
    if red.changed:
        asked = f"n_plays={n_plays}" if n_plays is not None else "the slopes' choice"
        warnings.warn(f"joint estimation: fitted {res.weights.size} plays ({asked}), the data "
                      f"resolve {red.weights.size}: {red.describe()}; the model has "
                      f"{red.weights.size} plays", RuntimeWarning, stacklevel=3)
    op = PIOperator(red.weights, red.radii)
    exc = check_excitation(v, op.weights, op.radii)
    offset, rms, mx = _errors(op, v, y)
    settings = {"threshold": threshold, "updates": int(res.update_index.size),
                "branches_used": res.branches_used, "samples_used": res.samples_used,
                "branch_fit_rms": res.fit_rms}
    return Identification(op, offset, "joint", rms, mx, float(np.ptp(y)), exc, slopes, settings)
