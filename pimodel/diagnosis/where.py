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


def _region_masks(t: np.ndarray, v: np.ndarray, fs: float) -> dict[str, np.ndarray]:
    rng = float(np.ptp(v)) or 1.0
    dv = np.diff(v, prepend=v[0])
    moving = np.abs(dv) > 1e-9 * rng
    rev = find_reversals(v, 0.01 * rng)
    since_rev = np.full(v.size, np.inf)
    last = None
    rset = set(rev)
    for k in range(v.size):
        if k in rset:
            last = v[k]
        if last is not None:
            since_rev[k] = abs(v[k] - last)
    steps = np.flatnonzero(np.abs(dv) > 0.05 * rng)
    since_step = np.full(v.size, np.inf)
    for s in steps:
        end = steps[steps > s][0] if np.any(steps > s) else v.size
        since_step[s:end] = t[s:end] - t[s]
    mid = 0.5 * (v.max() + v.min())
    rate = np.abs(dv) * fs
    fast = rate > np.percentile(rate[moving], 75) if moving.any() else np.zeros_like(moving)
    tt = t - t[0]
    return {
        "ascending branches": moving & (dv > 0),
        "descending branches": moving & (dv < 0),
        "near a reversal (travel < 10 % of range)": since_rev < 0.1 * rng,
        "input extremes (outer 20 % of range)": np.abs(v - mid) > 0.4 * rng,
        "fast input (top quarter of |dv/dt|)": fast & moving,
        "hold after a step (first 50 ms)": (~moving) & (since_step < 0.05),
        "hold after a step (after 50 ms)": (~moving) & (since_step >= 0.05) & np.isfinite(
            since_step),
        "late in the record (last third)": tt > 2 * tt[-1] / 3,
        STARTUP_REGION: np.arange(v.size) < startup_length(v),
    }


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
    total_e = sum(float(np.sum(r**2)) for r in residuals) or 1e-300
    total_n = sum(r.size for r in residuals)
    for seg, r in zip(segments, residuals, strict=True):
        fs = 1.0 / seg.dt
        for name, mask in _region_masks(seg.t, seg.v, fs).items():
            e, n = regions.get(name, [0.0, 0])
            regions[name] = [e + float(np.sum(r[mask] ** 2)), n + int(mask.sum())]
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
        P = np.abs(np.fft.rfft(r - r.mean())) ** 2
        for name, (lo, hi) in bands.items():
            band_e[name] += float(P[(f >= lo) & (f < hi)].sum())
    tot = sum(band_e.values()) or 1e-300
    spectrum = [{"band": k, "energy_share": e / tot} for k, e in band_e.items()]

    lags = [0, 1, 2, 5, 10, 20]
    corr_v, corr_dv = [], []
    for lag in lags:
        cv, cd = [], []
        for seg, r in zip(segments, residuals, strict=True):
            v = seg.v
            dv = np.diff(v, prepend=v[0])
            if lag:
                v, dv, rr = v[:-lag], dv[:-lag], r[lag:]
            else:
                rr = r
            cv.append(_corr(rr, v))
            cd.append(_corr(rr, dv))
        corr_v.append({"lag_samples": lag, "corr": float(np.mean(cv))})
        corr_dv.append({"lag_samples": lag, "corr": float(np.mean(cd))})
    return {"regions": ranked, "spectrum": spectrum, "corr_input": corr_v,
            "corr_input_rate": corr_dv}


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    sa, sb = np.std(a), np.std(b)
    if sa == 0 or sb == 0:
        return 0.0
    return float(np.mean((a - a.mean()) * (b - b.mean())) / (sa * sb))
