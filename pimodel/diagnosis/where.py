"""Where the residual concentrates: regions of the validate records ranked by their share of
the residual energy relative to their share of the samples (concentration > 1: the gap lives
there), plus the residual spectrum and its correlation with the input and the input rate."""

from __future__ import annotations

import numpy as np

from ..identification.branches import find_reversals

__all__ = [
    "residual_breakdown",
    "startup_length",
]

STARTUP_SPAN = 0.9  # the start-up region ends when the input first spans this share of its range
STARTUP_REGION = "start-up (until the input first spans 90 % of its range)"


def startup_length(v: np.ndarray) -> int:
    """Samples of the start-up region of a record: before index ``k`` the input has not yet
    spanned ``STARTUP_SPAN`` of its range, so the memory of plays with large radii still
    depends on the (unknown) state before the record.

    Parameters
    ----------
    v : numpy.ndarray
        Input ``v[k]`` of one record.

    Returns
    -------
    int
        First sample index after the start-up region.

    Examples
    --------
    >>> startup_length(np.array([0.0, 0.5, 1.0, -1.0, 0.0]))
    3
    """
    v = np.asarray(v, float)
    span = np.maximum.accumulate(v) - np.minimum.accumulate(v)
    return int(np.argmax(span >= STARTUP_SPAN * float(np.ptp(v))))


BLOCK = 1 << 16  # samples per block of the masks built from the latest reversal or step


def _last_index(n: int, marks) -> np.ndarray:
    """For each sample ``k`` the largest index in ``marks`` at or before ``k`` (-1: none)."""
    last = np.full(n, -1, dtype=np.int32 if n < 2**31 - 1 else np.int64)
    marks = np.asarray(marks, dtype=np.int64)
    last[marks] = marks
    return np.maximum.accumulate(last, out=last)


def _since_masks(x: np.ndarray, last: np.ndarray, absolute: bool, *tests):
    """For each ``test``, the mask ``test(d)`` of ``d[k] = x[k] - x[last[k]]`` (its magnitude
    when ``absolute``; ``inf`` where ``last[k] < 0``), built a block of samples at a time."""
    masks = [np.empty(x.size, bool) for _ in tests]
    for i in range(0, x.size, BLOCK):
        c = slice(i, i + BLOCK)
        lc = last[c]
        d = x[c] - x[np.maximum(lc, 0)]
        if absolute:
            np.abs(d, out=d)
        d[lc < 0] = np.inf
        for m, test in zip(masks, tests, strict=True):
            m[c] = test(d)
    return masks


def _region_masks(t: np.ndarray, v: np.ndarray, fs: float):
    """``(region, mask)`` of each region of one record, one mask at a time (each built when
    asked for, its temporaries freed before the next: a few columns of the record at most).

    "Near a reversal" is the travel ``|v[k] - v[j]|`` from the latest reversal ``j <= k``
    (:func:`~pimodel.identification.branches.find_reversals`); a hold after a step is timed
    ``t[k] - t[j]`` from the latest step ``j <= k`` (a sample change above 5 % of the range)."""
    rng = float(np.ptp(v)) or 1.0
    dv = np.diff(v, prepend=v[0])
    moving = np.abs(dv) > 1e-9 * rng
    yield "ascending branches", moving & (dv > 0)
    yield "descending branches", moving & (dv < 0)
    last = _last_index(v.size, find_reversals(v, 0.01 * rng))
    near, = _since_masks(v, last, True, lambda d: d < 0.1 * rng)
    del last
    yield "near a reversal (travel < 10 % of range)", near
    del near
    mid = 0.5 * (v.max() + v.min())
    yield "input extremes (outer 20 % of range)", np.abs(v - mid) > 0.4 * rng
    rate = np.abs(dv) * fs
    fast = rate > np.percentile(rate[moving], 75) if moving.any() else np.zeros_like(moving)
    del rate
    yield "fast input (top quarter of |dv/dt|)", fast & moving
    del fast
    last = _last_index(v.size, np.flatnonzero(np.abs(dv) > 0.05 * rng))
    del dv
    first, after = _since_masks(t, last, False, lambda d: d < 0.05,
                                lambda d: (d >= 0.05) & np.isfinite(d))
    del last
    np.logical_not(moving, out=moving)  # (moving is not read again: now "holding")
    yield "hold after a step (first 50 ms)", moving & first
    del first
    yield "hold after a step (after 50 ms)", moving & after
    del after, moving
    tt = t - t[0]
    yield "late in the record (last third)", tt > 2 * tt[-1] / 3
    del tt
    start = np.zeros(v.size, bool)
    start[:startup_length(v)] = True
    yield STARTUP_REGION, start


def residual_breakdown(segments, residuals) -> dict:
    """Ranked regions, spectrum bands and correlations of the validate residuals.

    Each sample ``k`` of each record belongs to zero or more regions (ascending or descending
    branches, near a reversal, input extremes, fast input, holds after a step, late in the
    record, the start-up region of :func:`startup_length`). A region's concentration is its
    share of the residual energy ``sum r[k]**2`` divided by its share of the samples; above 1
    the residual lives there.

    Parameters
    ----------
    segments : list of Segment
        The validate records: ``t`` [s], input ``v[k]`` and sample time ``dt`` [s] each (see
        :class:`pimodel.diagnosis.effects.Segment`).
    residuals : list of numpy.ndarray
        Residual ``r[k] = y[k] - model[k]`` of each record (output units), same lengths.

    Returns
    -------
    dict
        ``regions``: list of dicts (``region``, ``energy_share``, ``sample_share``,
        ``concentration``), highest concentration first, empty regions left out;
        ``spectrum``: share of the residual energy in the bands < 1 Hz, 1-10 Hz, 10-100 Hz,
        100-1000 Hz, > 1 kHz (``band``, ``energy_share``); ``corr_input`` and
        ``corr_input_rate``: correlation of ``r[k + lag]`` with ``v[k]`` and with
        ``v[k] - v[k-1]`` (``lag_samples``, ``corr``), averaged over the records.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> t = np.arange(400) * 1e-3
    >>> seg = SimpleNamespace(t=t, v=np.sin(2 * np.pi * 5 * t), dt=1e-3)
    >>> r = np.where(t > 0.3, 0.01 * seg.v, 0.0)  # a gap that appears late in the record
    >>> top = residual_breakdown([seg], [r])["regions"][0]
    >>> top["region"], round(top["concentration"], 2)
    ('late in the record (last third)', 3.01)
    """
    regions: dict[str, list[float]] = {}
    total_e = sum(float(np.sum(np.square(r))) for r in residuals) or 1e-300
    total_n = sum(r.size for r in residuals)
    for seg, r in zip(segments, residuals, strict=True):
        fs = 1.0 / seg.dt
        for name, mask in _region_masks(seg.t, seg.v, fs):
            e, n = regions.get(name, [0.0, 0])
            g = r[mask]
            regions[name] = [e + float(np.sum(np.square(g, out=g))), n + int(mask.sum())]
            del g, mask
    ranked = []
    for name, (e, n) in regions.items():
        if n == 0:
            continue
        share_e, share_n = e / total_e, n / total_n
        ranked.append({"region": name, "energy_share": share_e, "sample_share": share_n,
                       "concentration": share_e / share_n})
    ranked.sort(key=lambda d: d["concentration"], reverse=True)

    bands = {"< 1 Hz": (0, 1), "1-10 Hz": (1, 10), "10-100 Hz": (10, 100),
             "100-1000 Hz": (100, 1000), "> 1 kHz": (1000, np.inf)}
    band_e = dict.fromkeys(bands, 0.0)
    for seg, r in zip(segments, residuals, strict=True):
        f = np.fft.rfftfreq(r.size, seg.dt)
        F = np.fft.rfft(r - r.mean())
        P = np.abs(F)
        del F
        np.square(P, out=P)
        for name, (lo, hi) in bands.items():
            band_e[name] += float(P[(f >= lo) & (f < hi)].sum())
    tot = sum(band_e.values()) or 1e-300
    spectrum = [{"band": k, "energy_share": e / tot} for k, e in band_e.items()]

    lags = [0, 1, 2, 5, 10, 20]
    cv: list[list[float]] = [[] for _ in lags]  # per lag, one value per record
    cd: list[list[float]] = [[] for _ in lags]
    for seg, r in zip(segments, residuals, strict=True):
        v = seg.v
        dv = np.diff(v, prepend=v[0])
        for i, lag in enumerate(lags):
            if lag:
                cv[i].append(_corr(r[lag:], v[:-lag]))
                cd[i].append(_corr(r[lag:], dv[:-lag]))
            else:
                cv[i].append(_corr(r, v))
                cd[i].append(_corr(r, dv))
    corr_v = [{"lag_samples": lag, "corr": float(np.mean(c))}
               for lag, c in zip(lags, cv, strict=True)]
    corr_dv = [{"lag_samples": lag, "corr": float(np.mean(c))}
                for lag, c in zip(lags, cd, strict=True)]
    return {"regions": ranked, "spectrum": spectrum, "corr_input": corr_v,
            "corr_input_rate": corr_dv}


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    sa, sb = np.std(a), np.std(b)
    if sa == 0 or sb == 0:
        return 0.0
    return float(np.mean((a - a.mean()) * (b - b.mean())) / (sa * sb))
