"""The creep's start as a variant (issue 28, pimodel.diagnosis.creep): a stage parked between
records has its creep lags at rest at one level per lag shared by the records (where it rested),
not at each record's first output. Stages drawn here: a few plays (at rest at each record's
first input, as the diagnosis' nominal assumes) and creep through lags on the diagnosis' grid
for 2 s records at 1 kHz (30 ms, 0.3 s, 3 s), ``y = h + sum_i g_i (L_i[h] - h)``; train and
validate records start at different inputs. Parked: every ``L_i[-1]`` is the output at rest at
the park input 0; at rest: ``L_i[-1] = h[0]`` of each record (the diagnosis' first start).
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from pimodel.diagnosis import diagnose
from pimodel.diagnosis.creep import creep_start_levels, creep_starts, start_columns
from pimodel.diagnosis.filters import lag
from pimodel.diagnosis.model import DiagnosedModel
from pimodel.operators.pi import PIOperator
from pimodel.records import Record

D = sys.modules["pimodel.diagnosis.diagnose"]  # the module (the package exports the function)
DT = 1e-3
TAUS = (0.03, 0.3, 3.0)  # the diagnosis' lags for 2 s records at 1 kHz
NOISE = 0.005


def _stage(seed: int):
    rng = np.random.default_rng(seed)
    radii = np.concatenate(([0.0], np.sort(rng.uniform(0.1, 1.0, 3))))
    weights = rng.uniform(0.4, 1.0, 4)
    gains = rng.uniform(0.02, 0.04, 3)  # 2-4 % per lag
    return rng, radii, weights, gains


def _record(rng, radii, weights, gains, v0: float, source: str, parked: bool) -> Record:
    """One 2 s record from ``v0``: a sine of amplitude 2 through ``v0`` plus a small tone (so
    train and validate cover one range from different starts; plays at rest at ``v0``), the
    creep's lags at rest at the park output 0 (``parked``) or at the record's ``h[0]``."""
    t = np.arange(2000) * DT
    f1, f2 = rng.uniform(0.8, 1.2), rng.uniform(3.0, 5.0)
    ph = np.arcsin(v0 / 2.0)
    ph = ph if rng.uniform() < 0.5 else np.pi - ph
    ph2 = rng.uniform(0, 2 * np.pi)
    v = 2.0 * np.sin(2 * np.pi * f1 * t + ph) + 0.2 * (np.sin(2 * np.pi * f2 * t + ph2)
                                                      - np.sin(ph2))
    h = PIOperator(weights, radii, initial_state=v0).simulate(v)
    y = h.copy()
    for g, tau in zip(gains, TAUS, strict=True):
        y += g * (lag(h, tau, DT, 0.0 if parked else None) - h)
    return Record(t, v, y + NOISE * rng.standard_normal(t.size), source=source)


def records(seed: int, parked: bool = True) -> tuple[list[Record], list[Record]]:
    """Train and validate records of stage ``seed``, starting 1.6-3.2 input units apart."""
    rng, radii, weights, gains = _stage(seed)
    v0 = rng.uniform(0.8, 1.6) * np.array([1.0, -1.0])[rng.permutation(2)]
    return ([_record(rng, radii, weights, gains, v0[0], "train", parked)],
            [_record(rng, radii, weights, gains, v0[1], "validate", parked)])


def _rest_only(monkeypatch) -> None:
    """The diagnosis as before the variant: the creep's lags at rest at each record's first
    output only."""
    monkeypatch.setattr(D, "creep_starts", lambda effects, held=None, n_validate=1: [{}])


def test_start_columns_and_levels_give_the_lag_from_its_rest():
    """The common start's columns: the lag from 0 plus ``s a^(k+1)`` is the lag at rest at
    ``s``; the levels are checked and read from the model's params."""
    rng = np.random.default_rng(0)
    h = rng.standard_normal(500).cumsum() * 0.01
    a = start_columns(np.arange(h.size), DT, TAUS)
    for i, tau in enumerate(TAUS):
        s = 0.7 - i
        assert np.max(np.abs(lag(h, tau, DT, 0.0) + s * a[i] - lag(h, tau, DT, s))) < 1e-12
    assert creep_starts(("delay",)) == [{}]
    assert [x["creep_start"] for x in creep_starts(("creep", "drift"))] == ["rest", "common",
                                                                         "record"]
    p = {"creep_lag_gains": [0.1, 0.2], "creep_time_constants_s": [0.03, 0.3]}
    assert creep_start_levels(p) is None
    assert creep_start_levels({**p, "creep_start": "common",
                               "creep_start_levels": [1.0, -2.0]}).tolist() == [1.0, -2.0]
    with pytest.raises(ValueError, match="creep_start_levels: expected 2 finite"):
        DiagnosedModel([0.0], [1.0], 0.0, dt=DT, effects=("creep",),
                       params={**p, "creep_start": "common", "creep_start_levels": [1.0]})
    with pytest.raises(ValueError, match="creep_start: expected one of"):
        DiagnosedModel([0.0], [1.0], 0.0, dt=DT, effects=("creep",),
                       params={**p, "creep_start": "parked"})


def test_a_start_gone_by_the_first_scored_sample_gets_no_level():
    """A start-up mask longer than a lag's settling (1.2 s against 30 ms: its free response is
    e^-40 at the first scored sample): its common start's column is zero, its level 0, and the
    fit's output in the masked start-up stays near the record's range. Before, the column
    scaled to unit norm on the scored samples took a coefficient that drove that output far
    past it (1e159 on the blind generator's asymmetry + creep)."""
    from pimodel.diagnosis.effects import fit_effect, fit_nominal, make_segment

    k = np.arange(2000)
    assert np.array_equal(start_columns(k, DT, TAUS, None), start_columns(k, DT, TAUS))
    cut = start_columns(k, DT, TAUS, 1199)
    assert not cut[0].any()  # exp(-1.2 / 0.03) < 1e-8
    assert np.array_equal(cut[1:], start_columns(k, DT, TAUS)[1:])  # e^-4, e^-0.4: seen
    assert start_columns(k, DT, TAUS, 300)[0].any()  # e^-10 at 0.3 s: seen
    tr, _ = records(0)
    r = tr[0]
    seg = make_segment(r.t, r.v, r.y, np.linspace(0.0, 2.2, 21), k >= 1200)
    nominal = fit_nominal([seg])
    assert tuple(nominal.params["creep_taus"]) == TAUS
    m = fit_effect("creep", [seg], (), {"creep_start": "common"}, nominal)
    levels = m.params["creep_start_levels"]
    assert np.all(np.isfinite(levels)) and levels[1] != 0.0
    assert abs(levels[0]) < 1e-6 * np.ptp(r.y), levels  # 0 to the solve's rounding
    out = m.predict(seg)
    assert np.all(np.abs(out - r.y.mean()) < 2.0 * np.ptp(r.y)), np.abs(out).max()


def test_model_starts_the_lags_at_the_common_levels():
    """``DiagnosedModel.simulate`` and the C stream start each lag at its level: a loop written
    here, and not the at-rest start."""
    from pimodel.diagnosis.native_model import stream_simulate

    p = {"creep_lag_gains": [0.05, -0.02], "creep_time_constants_s": [0.01, 0.1]}
    common = {**p, "creep_start": "common", "creep_start_levels": [0.9, -0.4]}
    m = DiagnosedModel([0.0, 0.3], [1.0, 0.5], 0.1, dt=DT, effects=("creep",), params=common,
                       reference_weights=[0.9, 0.4], reference_offset=0.05)
    v = np.sin(np.linspace(0, 7, 600)) + 0.4
    h0 = PIOperator(np.array([0.9, 0.4]), np.array([0.0, 0.3])).simulate(v) + 0.05
    want = PIOperator(np.array([1.0, 0.5]), np.array([0.0, 0.3])).simulate(v) + 0.1
    for g, tau, s in zip(p["creep_lag_gains"], p["creep_time_constants_s"], [0.9, -0.4],
                         strict=True):
        a, state, L = np.exp(-DT / tau), s, np.empty_like(h0)
        for k, x in enumerate(h0):
            state = a * state + (1 - a) * x
            L[k] = state
        want += g * (L - h0)
    got = m.simulate(v)
    assert np.max(np.abs(got - want)) < 1e-12
    assert np.max(np.abs(stream_simulate(m, v) - want)) < 1e-12
    rest = DiagnosedModel(m.radii, m.weights, m.offset, dt=DT, effects=("creep",), params=p,
                          reference_weights=m.reference_weights, reference_offset=0.05)
    assert np.max(np.abs(rest.simulate(v) - got)) > 1e-2


@pytest.mark.slow  # two diagnoses per seed (1-5 s each on one core)
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_parked_creep_is_named_alone_with_the_common_start(seed, monkeypatch):
    """Parked: with the lags at rest at each record's first output only (the diagnosis before
    the variant) the verdict is not ``creep`` alone (a spurious drift, or the creep missed);
    with the variant it is, the common start chosen, and the gap closes to the noise
    (measured on seeds 0-4: 1.07-1.45 noise floors after, from 3.9-8.0; before the variant
    ``unexplained``, ``rate``, ``drift``, ``rate`` and ``unexplained`` or ``creep`` and
    ``unexplained``, 1.9-8.0 floors after)."""
    tr, va = records(seed, parked=True)
    rep = diagnose(tr, va, workers=1)
    v = rep.verdict
    assert v["effects"] == ["creep"], v["effects"]
    assert v["model"]["creep_start"] == "common"
    assert len(v["model"]["creep_start_levels"]) == len(v["model"]["creep_lag_gains"])
    assert v["gap_after"] < 2.0 * v["noise_floor"]
    aug = rep.model()  # the exported model predicts as the diagnosis
    assert np.max(np.abs(aug.simulate(va[0].v, va[0].t) - rep.after[0])) < 1e-9
    _rest_only(monkeypatch)
    # from rest, as before the variant: "auto"'s second look (the diagnosis without the
    # start-ups, which needs no creep start) can name creep alone too
    before = diagnose(tr, va, workers=1, initial_state="rest").verdict
    assert before["effects"] != ["creep"], before["effects"]
    assert "drift" in before["effects"] or "creep" not in before["effects"] or \
        before["gap_after"] > 2 * v["gap_after"]


@pytest.mark.parametrize("parked", [True, False])
def test_the_start_is_chosen_once_per_path(parked, monkeypatch):
    """The creep's start is scored where the creep enters a combination (the candidate alone
    here) and held for every fit built on it (creep61): with an asymmetry beside the creep
    (``y + 0.03 y^2``: ``asymmetry, creep``, as with the start chosen anew for every
    combination), the fits holding a creep at the start not chosen are few (2 of 22; 20 of
    40 when every combination scored both)."""
    tr, va = records(0, parked=parked)
    tr, va = ([Record(r.t, r.v, r.y + 0.03 * r.y**2, source=r.source) for r in x]
              for x in (tr, va))
    calls = []
    real = D.fit_effect

    def spy(name, train, combo, fixed, nominal):
        calls.append(((*combo, name), dict(fixed or {})))
        return real(name, train, combo, fixed, nominal)

    monkeypatch.setattr(D, "fit_effect", spy)
    # one diagnosis, from rest: "auto"'s second look would add a second one's fits
    v = diagnose(tr, va, workers=1, initial_state="rest").verdict
    assert sorted(v["effects"]) == ["asymmetry", "creep"], v["effects"]
    chosen = v["model"].get("creep_start", "rest")
    assert chosen == ("common" if parked else "rest")
    alone = [fx["creep_start"] for e, fx in calls
             if e == ("creep",) and set(fx) <= {"creep_start", "creep_levels"}]
    assert sorted(alone) == ["common", "record", "rest"]  # each scored for the candidate
    starts = [fx["creep_start"] for e, fx in calls if "creep" in e]
    at_chosen = starts.count(chosen)
    assert at_chosen >= 10
    assert len(starts) - at_chosen <= at_chosen / 4, (at_chosen, len(starts) - at_chosen)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_creep_at_rest_keeps_the_rest_start(seed):
    """Records that start at rest (each lag at the record's first output, the existing case):
    ``creep`` alone, the at-rest start kept (no ``creep_start`` in the model; seed 4 adds an
    ``asymmetry`` with either start, not asserted here)."""
    tr, va = records(seed, parked=False)
    v = diagnose(tr, va, workers=1).verdict
    assert v["effects"] == ["creep"], v["effects"]
    assert "creep_start" not in v["model"]


@pytest.mark.parametrize("plays_start", ["zero", "v0"])
@pytest.mark.parametrize("asymmetry", [False, True])
def test_inverse_is_exact_with_the_common_start(plays_start, asymmetry):
    """The feedforward of a model whose lags start at a common rest is exact (the creep acts
    on the first sample already: ``sum_j g_j a_j (s_j - h0[0])``), in NumPy and in C."""
    from pimodel.diagnosis.native_inverse import NativeInverse

    p = {"creep_lag_gains": [0.05, -0.02, 0.03], "creep_time_constants_s": [0.01, 0.1, 1.0],
         "creep_start": "common", "creep_start_levels": [0.9, -0.4, 1.5]}
    if asymmetry:
        p.update({"asymmetry_quadratic": 0.03, "asymmetry_cubic": -0.01, "center": 0.5,
                  "half_range": 1.5})
    m = DiagnosedModel([0.0, 0.3, 0.7], [1.0, 0.5, 0.3], 0.1, dt=DT,
                       effects=("creep", "asymmetry") if asymmetry else ("creep",), params=p,
                       reference_weights=[0.9, 0.45, 0.25], reference_offset=0.05,
                       plays_start=plays_start)
    v = np.sin(np.linspace(0, 7, 600)) + 0.4
    if plays_start == "zero":
        v[:5] = 0.0
    y = m.simulate(v)
    assert np.max(np.abs(m.inverse().simulate(y) - v)) < 1e-9
    if plays_start == "zero":
        assert np.max(np.abs(NativeInverse(m.inverse()).run(y) - v)) < 1e-9


def test_report_reads_the_asymmetry_beside_a_common_start():
    """Beside a creep at a common rest the asymmetry's coefficients are read from their own
    columns (after the lags' start columns): the model built from the report predicts as the
    fit, on train and on another record."""
    from pimodel.diagnosis.effects import fit_effect, fit_nominal, make_segment

    tr, va = records(0)
    radii = np.linspace(0.0, 2.2, 21)
    segs = [make_segment(r.t, r.v, r.y, radii) for r in (tr[0], va[0])]
    nominal = fit_nominal(segs[:1])
    m = fit_effect("asymmetry", segs[:1], ("creep",), {"creep_start": "common"}, nominal)
    assert m.grid == {"creep_start": "common"}
    ref, n = m.reference, radii.size
    model = DiagnosedModel(radii, m.coef[:n], float(m.coef[n]), dt=DT,
                           effects=("creep", "asymmetry"), reference_weights=ref.coef[:n],
                           reference_offset=float(ref.coef[n]), plays_start="v0",
                           params={**m.params, "center": ref.params["center"],
                                   "half_range": ref.params["half_range"]})
    assert len(m.params["creep_start_levels"]) == len(TAUS)
    for r, s in zip((tr[0], va[0]), segs, strict=True):
        assert np.max(np.abs(model.simulate(r.v) - m.predict(s))) < 1e-9
