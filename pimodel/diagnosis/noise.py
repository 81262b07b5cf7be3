"""The measurement-noise floor of a set of records, and how it was measured.

Two methods, in order of preference:

``"repeated periods"``
    When the input repeats exactly (a period ``P`` with ``v[k + P] == v[k]`` over at least one
    full period before ``k``), the outputs ``y[k]`` and ``y[k + P]`` differ only by noise (the
    hysteresis memory is the same after one identical period) and by slow changes (drift,
    creep) that are removed by subtracting a straight line per repeated run. The floor is the
    robust standard deviation (1.4826 times the median absolute deviation) of
    ``y[k + P] - y[k]`` divided by ``sqrt(2)``. No model is involved.
``"local model"``
    Otherwise the model residual ``r`` is explained as far as a flexible local model can: a
    linear system from the model output to ``r`` (ARX of orders 6/24 by least squares, then
    simulated; catches fast unmodelled linear dynamics: modes, lags, low-pass), then a
    Savitzky-Golay smoothing fit (catches everything smooth in time: creep, drift, static
    maps, dead zones). The floor is the robust standard deviation of what remains, corrected
    for the noise the smoothing absorbs (divided by ``sqrt(1 - h0)``, ``h0`` the centre tap of
    the smoothing filter).

First differences alone are never used: they count fast unmodelled dynamics as noise.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter, savgol_coeffs, savgol_filter
from scipy.stats import rankdata

__all__ = [
    "measure_noise_floor",
    "robust_std",
]

ARX_NA, ARX_NB, ARX_LEAD = 6, 24, 4  # linear model of the residual on the model output
SG_WINDOW = 9  # Savitzky-Golay window [samples] and polynomial order
SG_ORDER = 3
FEEDBACK_CORR = 0.1  # |rank corr| of h's fast part one sample ahead with r's fast part: feedback
MIN_REPEATED = 400  # samples of repeated input needed for the "repeated periods" method
MAX_PERIODS_TRIED = 6


def robust_std(x: np.ndarray, overwrite_input: bool = False) -> float:
    """1.4826 times the median absolute deviation: the standard deviation for Gaussian ``x``.

    Insensitive to a few outliers, unlike :func:`numpy.std`.

    Parameters
    ----------
    x : array_like
        Samples (any shape; flattened by the median).
    overwrite_input : bool, optional
        Reorder and overwrite ``x`` (a float array) instead of a copy, as
        :func:`numpy.median`'s: the same value (the medians are order statistics), no
        temporary of ``x``'s size. Default False.

    Returns
    -------
    float
        ``1.4826 * median(|x - median(x)|)``, in the units of ``x``.

    Examples
    --------
    >>> robust_std([1.0, 2.0, 3.0, 4.0, 100.0])
    1.4826
    """
    x = np.asarray(x, float) if overwrite_input else np.array(x, float)
    med = np.median(x, overwrite_input=True)
    np.subtract(x, med, out=x)
    np.abs(x, out=x)
    return float(1.4826 * np.median(x, overwrite_input=True))


def _candidate_periods(v: np.ndarray) -> list[int]:
    """Most frequent index distances between consecutive input reversals of the same kind at
    the same level (a repeated input repeats its reversals), at least 10 samples."""
    s = np.sign(np.diff(v))
    k = np.flatnonzero(s)
    if k.size < 3:
        return []
    turn = k[1:][s[k[1:]] != s[k[:-1]]]  # first sample of each new direction
    if turn.size < 2:
        return []
    tol = 1e-6 * (float(np.ptp(v)) or 1.0)
    counts: dict[int, int] = {}
    last: dict[tuple, int] = {}  # (level, direction) -> index of its latest reversal
    for k in turn:
        key = (int(np.round(v[k] / tol)), int(s[k]))
        if key in last and k - last[key] >= 10:
            P = int(k - last[key])
            counts[P] = counts.get(P, 0) + 1
        last[key] = int(k)
    return sorted(counts, key=lambda P: -counts[P])[:MAX_PERIODS_TRIED]


def _repeated_differences(v: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
    """Detrended ``y[k + P] - y[k]`` on every run where the input repeated over the whole
    previous period, for the candidate periods of ``v``; each sample ``k`` used once."""
    rng = float(np.ptp(v)) or 1.0
    tol = 1e-6 * rng
    used = np.zeros(v.size, bool)
    out = []
    for P in _candidate_periods(v):
        d = v[P:] - v[:-P]
        np.abs(d, out=d)
        same = d <= tol  # index k: v[k + P] == v[k]
        del d
        # k usable when v repeated over [k - P, k] (same memory) and the period moves the input:
        # no sample of [k - P, k] differs, c[k + 1] == c[k - P] with c the count of differing
        # samples before each index
        m = same.size
        c = np.zeros(m + 1, np.int32 if m < 2**31 - 1 else np.int64)
        np.cumsum(~same, out=c[1:])
        del same
        ok = np.zeros(m, bool)
        if m > P:
            np.equal(c[P + 1:], c[:m - P], out=ok[P:])
        del c
        ok &= ~used[:m]
        if ok.sum() < MIN_REPEATED:
            continue
        idx = np.flatnonzero(ok)
        breaks = np.flatnonzero(np.diff(idx) > 1) + 1
        for run in np.split(idx, breaks):
            if run.size < 20:
                continue
            span = float(np.ptp(v[run[0] - P: run[-1] + 1]))
            if span < 0.1 * rng:
                continue  # a hold repeats trivially; its output creeps
            d = y[run[0] + P: run[-1] + P + 1] - y[run[0]: run[-1] + 1]  # run: consecutive
            x = np.arange(run.size, dtype=float)
            d = d - np.polyval(np.polyfit(x, d, 1), x)
            out.append(d)
            used[run] = True
    return out


def _fast(x: np.ndarray) -> np.ndarray:
    return x - savgol_filter(x, SG_WINDOW, SG_ORDER)


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    sa, sb = float(np.std(a)), float(np.std(b))
    return 0.0 if sa == 0 or sb == 0 else float(np.mean((a - a.mean()) * (b - b.mean())) / sa / sb)


def _feedback(h: np.ndarray, r: np.ndarray) -> bool:
    """Whether the record was taken in closed loop: the fast part of the model output one sample
    ahead, ``h[k + 1]``, follows the fast part of the residual ``r[k]`` (the controller fed the
    measured noise back into the input), and far more than ``h[k - 1]`` does (an open-loop
    effect, a delay at a step, is about symmetric). Under feedback the ARX's leads would
    predict the noise from the next input and the floor would come out low (3x on clean
    closed-loop records, ``docs/diagnosis.md``). Spearman's rank correlation: under a slow loop
    the few spikes of a stepped reference hide the loop's response to the noise from Pearson's
    (0.04-0.17 there, against 0.68-0.70 in rank)."""
    hf, rf = rankdata(_fast(h)), rankdata(_fast(r))
    ahead = abs(_corr(hf[1:], rf[:-1]))
    behind = abs(_corr(hf[:-1], rf[1:]))
    return ahead > FEEDBACK_CORR and ahead > 2.0 * behind


def _local_model_residual(h: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, bool]:
    """What neither a linear model of the model output ``h`` nor a smoothing fit explains.

    The linear model is ``B(q) / A(q)`` from ``h`` (``ARX_LEAD`` samples ahead, so it may also
    lead; no lead on a record taken in closed loop, :func:`_feedback`) to ``r``: first fitted
    in equation-error (ARX) form by least squares, then simulated in output-error form (stable
    poles only; else the ARX residual itself is kept). Returns that residual and whether the
    record was taken in closed loop (``False`` on a record too short to tell)."""
    n, na, nb, m = r.size, ARX_NA, ARX_NB, ARX_LEAD
    if n <= 10 * (na + nb) + SG_WINDOW:
        return r - savgol_filter(r, SG_WINDOW, SG_ORDER), False
    closed = _feedback(h, r)
    if closed:
        m = 0  # the leads would explain the noise the loop fed back into the input
    u = np.concatenate((h[m:], np.full(m, h[-1]))) - h.mean()
    k0 = max(na, nb)
    cols = [np.ones(n - k0)]
    cols += [r[k0 - i: n - i] for i in range(1, na + 1)]
    cols += [u[k0 - j: n - j] for j in range(nb + 1)]
    A = np.column_stack(cols)
    c, *_ = np.linalg.lstsq(A, r[k0:], rcond=None)
    a = np.concatenate(([1.0], -c[1:na + 1]))
    b = c[na + 1:]
    e = None
    if np.all(np.abs(np.roots(a)) < 0.999):
        sim = lfilter(b, a, u) + c[0] / np.sum(a)
        e = (r - sim)[k0:]
        if np.sum(e**2) > np.sum((r[k0:] - A @ c) ** 2) * 4:
            e = None
    if e is None:
        e = r[k0:] - A @ c
    return e - savgol_filter(e, SG_WINDOW, SG_ORDER), closed


def measure_noise_floor(signals, outputs) -> dict:
    """Noise floor of measured outputs around model outputs ``outputs`` (same units).

    Parameters
    ----------
    signals : list of ``(v, y)`` pairs, one per record
        Input ``v[k]`` and measured output ``y[k]`` at sample ``k`` (1-D arrays, equal length).
    outputs : list of 1-D arrays
        Model output ``h[k]`` for each record (used by the ``"local model"`` method only).

    Returns
    -------
    dict
        ``value`` (standard deviation of the noise, output units), ``method``
        (``"repeated periods"`` or ``"local model"``), ``samples`` (how many samples the
        estimate rests on), ``detail`` (a sentence saying how it was measured) and, with the
        local model, ``closed_loop``: the indices of the records that look taken in closed
        loop (the fast part of ``h[k + 1]`` follows that of the residual ``y[k] - h[k]``).

    Examples
    --------
    >>> import numpy as np
    >>> v = np.tile(np.sin(np.linspace(0, 2 * np.pi, 200, endpoint=False)), 5)
    >>> y = 3 * v + np.random.default_rng(0).normal(0, 0.01, v.size)
    >>> nf = measure_noise_floor([(v, y)], [3 * v])
    >>> nf["method"], round(nf["value"], 2)
    ('repeated periods', 0.01)
    """
    diffs = [d for v, y in signals for d in _repeated_differences(np.asarray(v, float),
                                                             np.asarray(y, float))]
    n_rep = sum(d.size for d in diffs)
    if n_rep >= MIN_REPEATED:
        d = np.concatenate(diffs)
        del diffs
        value = float(robust_std(d, overwrite_input=True) / np.sqrt(2))
        return {"value": value, "method": "repeated periods", "samples": n_rep,
                "detail": "robust std of y[k+P] - y[k] over sample pairs one input period P "
                          "apart (input identical over the period before), detrended per "
                          "run, divided by sqrt(2)"}
    h0 = float(savgol_coeffs(SG_WINDOW, SG_ORDER)[SG_WINDOW // 2])
    res, closed = zip(*(_local_model_residual(np.asarray(h, float),
                                              np.asarray(y, float) - np.asarray(h, float))
                        for (_, y), h in zip(signals, outputs, strict=True)), strict=True)
    e = np.concatenate(res)
    value = float(robust_std(e) / np.sqrt(1.0 - h0))
    return {"value": value, "method": "local model", "samples": int(e.size),
            "closed_loop": [i for i, c in enumerate(closed) if c],
            "detail": f"robust std of the model residual after a linear model of the model "
                      f"output (ARX {ARX_NA}/{ARX_NB}, simulated) and a Savitzky-Golay fit (window "
                      f"{SG_WINDOW}, order {SG_ORDER}), corrected by 1/sqrt(1 - {h0:.3f})"}
