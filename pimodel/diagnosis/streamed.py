"""A held model's regressors on a long record, chunk by chunk (issue 31): nothing of size
(samples x columns) is built for the whole-record refit and prediction of the chosen model.

A record longer than ``SCREEN_SAMPLES`` is refitted and predicted as a *streamed* segment
(:func:`attach_plays`): it holds ``t``, ``v``, ``y`` and its mask, not its play rows. Its
regressors come one chunk ``c`` of :func:`~.chunked.chunks` at a time (``CHUNK`` samples,
16,384), each block with exactly the values of the same samples of the whole record's blocks
(:func:`.effects._combo_features`), because every operation is a causal recursion whose state
is carried from one chunk to the next, or a per-sample map:

- the play rows ``[z_1[c]; ...; z_n[c]; 1]`` (or ``V^T z[c]`` for a projected nominal) from
  :func:`.effects.play_chunks`, the plays' states carried (as the whole record's rows are
  built, chunk by chunk);
- ``h0[c] = coef @ rows[c]``, the reference hysteresis (the nominal, or an asymmetry's
  reference), a per-sample product;
- the creep lags ``out[k] = a out[k-1] + (1 - a) h0[k]`` (``scipy.signal.lfilter`` with the
  previous chunk's final state ``zf`` as ``zi``: the same sample recursion); with the lags at
  a common rest (``creep_start`` ``"common"``, :mod:`.creep`) the lags from 0 and the columns
  ``a^(k+1)`` of the chunk's own sample indices ``k`` (:func:`.creep.start_columns`); counted
  from the record's start (``"record"``) less the lags' state before the first chunk;
- the mode after the hysteresis and the linear part's elements (the C core's biquad,
  ``pim_biquad_rows_carry``: ``s0[k-1], s1[k-1]`` carried);
- a delay of ``d`` samples (whole or fractional): the chunk's rows with the last
  ``floor(d) + 1`` samples before it (held at the record's first sample before the start);
- asymmetry ``u^2, u^3``, a drift's trend (its record clock from the record's ``t[0]``,
  :func:`.drift.drift_columns` ``t0``) and levels: per sample.

The sums that use the blocks (:func:`.effects._fit`'s normal equations and residuals, the
predictions ``coef @ B``) were already taken chunk by chunk over the same ``chunks``, so a
streamed refit gives the whole-record refit's coefficients, RSS and outputs to the bit
(``tests/test_diagnosis_streamed.py``). Not streamed (:func:`streamable`; the whole-record
rows are then built as before): the ``rate`` effect (its radius family's last contacts and
band sums over the whole record) and ``dynamics`` before the hysteresis (``wiener``: its
projected plays of the filtered input are one matrix product over the whole record).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np
from scipy.signal import lfilter

from .._native import biquad_rows_carry
from .chunked import combine, stack_rows
from .creep import creep_levels, first_scored, start_columns
from .drift import drift_columns, level_rows
from .filters import mode_coefficients, shift
from .lti import element_coefficients

__all__ = ["attach_plays", "combo_chunks", "is_streamed", "n_plays",
           "play_row_chunks", "stacked_times", "streamable"]

def attach_plays(s, rows: Callable[[], Iterator[tuple[slice, np.ndarray]]], n: int):
    """Make the segment ``s`` (``Z`` None: :func:`pimodel.diagnosis.diagnose._bare`) a streamed
    one: ``rows()`` gives its ``n`` play rows and the offset's row of ones chunk by chunk,
    ``(c, rows_c)`` of shape (n + 1, len(c)) for each chunk ``c`` of :func:`~.chunked.chunks`
    (the plays' states carried), with the values of the rows a whole-record segment holds.
    Returns ``s``."""
    s.__dict__["_play_chunks"] = rows
    s.__dict__["_plays"] = int(n)
    return s


def is_streamed(s) -> bool:
    """Whether ``s`` is a streamed segment (:func:`attach_plays`)."""
    return "_play_chunks" in s.__dict__


def n_plays(s) -> int:
    """The play rows of segment ``s`` (streamed or not)."""
    return s.__dict__["_plays"] if is_streamed(s) else s.Z.shape[1]


def play_row_chunks(s) -> Iterator[tuple[slice, np.ndarray]]:
    """``(c, rows)`` of a streamed segment: its play rows on the chunk ``c``, the offset's
    row of ones last, shape (n + 1, len(c))."""
    return s.__dict__["_play_chunks"]()


def streamable(effects, p: dict) -> bool:
    """Whether the model of ``effects`` with grid parameters ``p`` can be streamed (module
    docstring: not with the rate, nor with a filter before the hysteresis)."""
    return "rate" not in effects and not p.get("wiener")


class _Biquad:
    """A biquad (``b``, ``a``) on rows, chunk after chunk, at rest around the first sample."""

    def __init__(self, b, a):
        self.b, self.a, self.state = b, a, None

    def __call__(self, x: np.ndarray) -> np.ndarray:
        out, self.state = biquad_rows_carry(self.b, self.a, x, self.state)
        return out


class _Lag:
    """:func:`.filters.lag` of a 1-D signal, chunk after chunk."""

    def __init__(self, tau: float, dt: float, start: float | None):
        self.a, self.start, self.zi = np.exp(-dt / tau), start, None
        self.rest = 0.0  # the state before the first sample, set by the first chunk

    def __call__(self, x: np.ndarray) -> np.ndarray:
        a = self.a
        if self.zi is None:
            self.rest = float(x[0]) if self.start is None else float(self.start)
            self.zi = [a * self.rest]
        out, self.zi = lfilter([1 - a], [1, -a], x, axis=0, zi=self.zi)
        return out


class _Shift:
    """:func:`.filters.shift` of rows (signals as rows) by ``d`` samples, chunk after chunk:
    the chunk with the ``floor(d) + 1`` samples before it (fewer at the record's start, where
    the shift holds the first sample)."""

    def __init__(self, d: float):
        self.d, self.keep, self.past = d, int(np.floor(d)) + 1, None

    def __call__(self, x: np.ndarray) -> np.ndarray:
        if self.d == 0:
            return x
        both = x if self.past is None else np.concatenate((self.past, x), axis=-1)
        out = shift(both, self.d, axis=-1)[:, both.shape[1] - x.shape[1]:]
        self.past = both[:, max(both.shape[1] - self.keep, 0):]
        return np.ascontiguousarray(out)


def combo_chunks(effects, p: dict, nominal, s, train_record: int | None = None,
                 n_train: int = 1) -> Iterator[tuple[slice, tuple]]:
    """The blocks of rows of :func:`.effects._combo_features` (held grid ``p``, every play
    row) for the streamed segment ``s``, chunk by chunk: ``(c, (Z_c, others_c))`` with the
    values of ``feats.parts(s)``'s blocks on the samples ``c`` (module docstring).
    ``nominal`` gives ``h0`` (its ``coef`` on the play rows); ``train_record`` and
    ``n_train`` a drift's levels (:func:`.drift.drift_columns`)."""
    if not streamable(effects, p):
        raise ValueError(f"{'+'.join(effects)}: its columns are not streamed (module streamed)")
    dt = s.dt
    y0 = None if s.mask is None else float(s.y[0])
    taus = nominal.params["creep_taus"] if "creep" in effects else ()
    common = bool(taus) and p.get("creep_start") == "common"  # lags at a common rest
    record = bool(taus) and p.get("creep_start") == "record"  # counted from the start
    levels = creep_levels(effects, p) > 0
    lags = [_Lag(tau, dt, 0.0 if common else y0) for tau in taus]
    scored_from = first_scored(s.mask)  # a start gone by then: zero (creep.start_columns)
    mode_f = _Biquad(*mode_coefficients(p["fn"], p["zeta"], dt)) if "dynamics" in effects \
        else None
    delayed = _Shift(p["d"]) if "delay" in effects else None
    h0_delayed = _Shift(p["d"]) if "delay" in effects else None  # the effect rows' h0
    lti = p.get("lti") or ()
    if lti:
        base = _Biquad(*mode_coefficients(p["fn"], p["zeta"], dt))
        elements = []
        for el in lti:
            b, a = element_coefficients(tuple(el), dt)
            elements.append(b[0] / a[0] if a.size == 1 else _Biquad(b, a))
        lti_delayed = _Shift(p["d"]) if "d" in p else None
    t0 = float(s.t[0])
    for c, rows in play_row_chunks(s):
        Z = rows[:-1]
        if mode_f is not None:
            Z = mode_f(Z)
        if delayed is not None:
            Z = delayed(Z)
        h0 = combine((rows,), nominal.coef)
        hd = h0 if h0_delayed is None else h0_delayed(h0[None, :])[0]  # delayed as the plays
        out = [np.ones(h0.size)]
        out += [lag(hd) - hd - (lag.rest if record else 0.0) for lag in lags]
        if levels:  # a creep counted from each start: a level per train record after the first
            out += list(level_rows(train_record, n_train, h0.size))
        if common:
            out += list(start_columns(np.arange(c.start, c.stop), dt, taus, scored_from))
        if "asymmetry" in effects:
            u = (hd - nominal.params["center"]) / nominal.params["half_range"]
            out += [u**2, u**3]
        parts = [Z, np.vstack(out)]
        if lti:
            m1 = base(h0[None, :])[0]
            cols = np.empty((len(lti), h0.size))
            for j, el in enumerate(elements):
                cols[j] = (h0 * el if isinstance(el, float) else el(h0[None, :])[0]) - m1
            parts.append(cols if lti_delayed is None else lti_delayed(cols))
        if "drift" in effects:
            parts.append(drift_columns(s.t[c], p, train_record, n_train, t0=t0).T)
        yield c, (Z, parts[1] if len(parts) == 2 else stack_rows(parts[1:]))


def stacked_times(parts_chunks, feats, s, coef: np.ndarray) -> np.ndarray:
    """``feats(s) @ coef`` (the stacked regressors times ``coef``, as
    :func:`.drift.record_levels` takes it), a chunk at a time for a streamed segment."""
    if not is_streamed(s):
        return feats(s) @ coef
    out = np.empty(s.y.size)
    for c, P in parts_chunks(s):
        out[c] = stack_rows(P).T @ coef
    return out

