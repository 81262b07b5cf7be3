"""The sim-to-real gap diagnosis: nominal PI model, where the residual lies, which unmodelled
effect explains it, and how far the gap shrinks on held-out records.

Train records fit every model; validate records only score. The nominal model is the PI
operator in the conventional parametrisation (20 plays on a radius grid over half the input
range, weights and an output offset by least squares: the identification chain's baseline,
linear in its parameters) so that each candidate effect can be refitted *jointly* with the
hysteresis weights (:mod:`.effects`). Effects are added greedily: each round fits every
remaining candidate on train (on top of those already chosen) and scores it on validate with
``BIC = N ln(RSS/N) + k ln N``; the best is kept if it lowers the BIC by more than 10, cuts the
validate RMS by at least 10 %, and the current RMS is above 1.5 times the noise floor
(estimated from sample-to-sample residual differences). No accepted effect: ``none``.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from ..data import Record
from .effects import EFFECTS, Model, Segment, fit_effect, fit_nominal, make_segment
from .where import residual_breakdown

N_GRID = 20
MIN_BIC_DROP = 10.0  # an effect must lower the validate BIC by more than this
MIN_RMS_CUT = 0.20  # ... and cut the validate RMS by at least this fraction
EFFECT_SIGNATURES = {
    "creep": ("hold after a step (after 50 ms)", "< 1 Hz"),
    "drift": ("late in the record (last third)", "< 1 Hz"),
    "dynamics": ("near a reversal (travel < 10 % of range)", "> 1 kHz"),
    "delay": ("fast input (top quarter of |dv/dt|)", "10-100 Hz"),
    "asymmetry": ("input extremes (outer 20 % of range)", "1-10 Hz"),
}


@dataclass
class DiagnosisReport:
    """Result of :func:`diagnose`; ``to_json()`` gives nominal, where, candidates, verdict."""

    nominal: dict
    where: dict
    candidates: list
    verdict: dict
    validate: list
    before: list
    after: list

    def to_json(self) -> dict:
        return {"nominal": self.nominal, "where": self.where, "candidates": self.candidates,
                "verdict": self.verdict}

    def save_json(self, path) -> Path:
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


def _errors(segs: list[Segment], outputs) -> dict:
    r = np.concatenate([s.y - o for s, o in zip(segs, outputs, strict=True)])
    rng = float(np.ptp(np.concatenate([s.y for s in segs]))) or 1.0
    rms, mx = float(np.sqrt(np.mean(r**2))), float(np.max(np.abs(r)))
    return {"rms": rms, "max": mx, "rms_percent": 100 * rms / rng,
            "max_percent": 100 * mx / rng, "range": rng}


def _bic(segs, outputs, k) -> float:
    r = np.concatenate([s.y - o for s, o in zip(segs, outputs, strict=True)])
    return float(r.size * np.log(max(np.mean(r**2), 1e-300)) + k * np.log(r.size))


def _noise_floor(segs, outputs) -> float:
    d = np.concatenate([np.diff(s.y - o) for s, o in zip(segs, outputs, strict=True)])
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2))


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
        from ..branches import find_reversals

        if not find_reversals(rec.v, 0.01 * float(np.ptp(rec.v))):
            raise ValueError(f"{rec.source}: the input has no reversal (no hysteresis loop)")


def diagnose(train: list[Record], validate: list[Record], *, max_effects: int = 3
             ) -> DiagnosisReport:
    """Diagnose the gap between a PI model fitted on ``train`` and the ``validate`` records.

    Warns (UserWarning) when a validate record is also a train record: nothing is held out.
    """
    shared = [r.source for r in validate if any(
        r.t.size == t.t.size and np.array_equal(r.v, t.v) and np.array_equal(r.y, t.y)
        for t in train)]
    if shared:
        warnings.warn(f"validate: {shared} also in train; nothing is held out, so the validate "
                      "gap is a training fit, not a test", UserWarning, stacklevel=2)
    with threadpool_limits(1, user_api="blas"):
        return _diagnose(train, validate, max_effects)


def _diagnose(train: list[Record], validate: list[Record], max_effects: int) -> DiagnosisReport:
    _check(train, "train")
    _check(validate, "validate")
    dts = [(r.source, r.dt) for r in train + validate]
    for src, dt in dts[1:]:
        if abs(dt - dts[0][1]) > 1e-6 * dts[0][1]:
            raise ValueError(f"{src}: sample time {dt:g} s differs from {dts[0][0]} "
                             f"({dts[0][1]:g} s); resample the records to one sample time")
    dt = dts[0][1]
    vt = np.concatenate([r.v for r in train])
    radii = np.linspace(0.0, float(np.ptp(vt)) / 2, N_GRID)
    tr = [make_segment(r.t, r.v, r.y, radii) for r in train]
    va = [make_segment(r.t, r.v, r.y, radii) for r in validate]
    nominal = fit_nominal(tr)
    out_tr = [nominal.predict(s) for s in tr]
    out_va = [nominal.predict(s) for s in va]
    before = _errors(va, out_va)
    nominal_json = {"model": {"kind": "PI, conventional parametrisation", "radii": radii,
                              "weights": nominal.coef[:N_GRID], "offset": nominal.coef[N_GRID]},
                    "train": _errors(tr, out_tr), "validate": before}
    where = residual_breakdown(va, [s.y - o for s, o in zip(va, out_va, strict=True)])
    noise = _noise_floor(va, out_va)

    cache: dict = {}

    def fit(name, combo=(), fixed_=None):
        key = (combo, name, tuple(sorted((fixed_ or {}).items())))
        if key not in cache:
            cache[key] = fit_effect(name, tr, combo, fixed_, nominal)
        return cache[key]

    candidates = []
    for name in EFFECTS:
        m = fit(name)
        o = [m.predict(s) for s in va]
        params = dict(m.params)
        if "delay_samples" in params:
            params["delay_s"] = params["delay_samples"] * dt
        candidates.append({"effect": name, "params": params, "k": m.k,
                           "validate": _errors(va, o),
                           "delta_bic": _bic(va, o, m.k) - _bic(va, out_va, 0)})
    candidates.sort(key=lambda c: c["delta_bic"])

    chosen: tuple[str, ...] = ()
    fixed: dict = {}
    current: Model = nominal
    cur_out = out_va
    for _ in range(max_effects):
        rms_now = _errors(va, cur_out)["rms"]
        if rms_now <= 1.5 * noise:
            break
        best = None
        for name in EFFECTS:
            if name in chosen:
                continue
            m = fit(name, chosen, {k: v for k, v in fixed.items()} if chosen else None)
            o = [m.predict(s) for s in va]
            dbic = _bic(va, o, m.k) - _bic(va, cur_out, current.k)
            if best is None or dbic < best[0]:
                best = (dbic, name, m, o)
        if best is None:
            break
        dbic, name, m, o = best
        if dbic > -MIN_BIC_DROP or _errors(va, o)["rms"] > (1 - MIN_RMS_CUT) * rms_now:
            break
        chosen += (name,)
        fixed.update(m.grid)
        current, cur_out = m, o
    after = _errors(va, cur_out)
    regions = {r["region"]: r for r in where["regions"]}
    bands = {b["band"]: b["energy_share"] for b in where["spectrum"]}
    evidence = []
    for name in chosen:
        reg, band = EFFECT_SIGNATURES[name]
        evidence.append({"effect": name, "region": reg,
                         "concentration": regions.get(reg, {}).get("concentration"),
                         "band": band, "band_energy_share": bands.get(band)})
    verdict = {"effects": list(chosen) or ["none"], "gap_before": before["rms"],
               "gap_after": after["rms"], "shrink": 1 - after["rms"] / before["rms"],
               "max_before": before["max"], "max_after": after["max"],
               "gap_before_percent": before["rms_percent"],
               "gap_after_percent": after["rms_percent"], "noise_floor": noise,
               "model": current.params, "evidence": evidence}
    return DiagnosisReport(nominal_json, where, candidates, verdict, va, out_va, cur_out)
