"""The ``dynamics`` candidate's linear part (``pimodel.diagnosis.lti``): its order chosen by the
train BIC, on records of both generators; its forward form against an independent
discretisation; its approximate inverse; the diagnosed model simulating what was fitted."""

from __future__ import annotations

import control
import numpy as np
import pytest
from scipy.signal import cont2discrete, lfilter, lfilter_zi, zpk2tf

from pimodel import Record
from pimodel.diagnosis import diagnose
from pimodel.diagnosis.effects import fit_effect, make_segment
from pimodel.diagnosis.lti import (
    approximate_inverse,
    continuous_zpk,
    element_coefficients,
    lti_columns,
)
from pimodel.diagnosis.model import load_diagnosed_model
from pimodel.stages.pi_stage import excitation, random_truth
from pimodel.stages.preisach_stage import excitations, random_alt_truth

ONE_MODE_SHRINK_TODAY = 0.75  # truth_alt dynamics, seed 0, with the one-mode candidate


def _g(x, fn, zeta, elements, gains, dt):
    """The linear part applied to x, as the diagnosis models it (base mode + columns)."""
    b, a = element_coefficients(("mode", fn, zeta), dt)
    base = lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])[0]
    return base + lti_columns(x, fn, zeta, elements, dt) @ np.asarray(gains, float)


def test_forward_equals_the_zoh_of_the_continuous_system():
    # ZOH discretisation is linear, so the sum of the discretised elements must equal the
    # discretisation of G(s) built from its zeros and poles
    fn, zeta, dt = 40.0, 0.1, 1e-3
    elements, gains = [("mode", 90.0, 0.2), ("lowpass", 2e-3), ("direct",)], [0.3, 0.2, 0.1]
    z, p, k = continuous_zpk(fn, zeta, elements, gains)
    num, den = zpk2tf(z, p, k)
    bd, ad, _ = cont2discrete((num, den), dt, method="zoh")
    x = np.r_[np.zeros(5), np.ones(2000)]
    ref = lfilter(np.ravel(bd), ad, x)
    assert np.max(np.abs(_g(x, fn, zeta, elements, gains, dt) - ref)) < 1e-7
    assert abs(ref[-1] - 1.0) < 1e-6  # static gain 1


def test_one_mode_inverse_equals_the_python_control_form():
    # M(s)^-1 / (s / (2 w) + 1)^2 built with python-control (the one-mode inverse)
    fn, zeta, dt = 1200.0, 0.04, 1e-4
    w = 2 * np.pi * fn
    d = control.sample_system(control.tf([1 / w**2, 2 * zeta / w, 1.0],
                                         [1 / (2 * w) ** 2, 1 / w, 1.0]), dt, method="tustin")
    b, a = np.ravel(d.num[0][0]), np.ravel(d.den[0][0])
    t = np.arange(3000) * dt
    x = np.sin(2 * np.pi * 20 * t) + (t > 0.1)
    ref = lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])[0]
    ref = np.r_[ref[1:], ref[-1]]
    assert np.max(np.abs(approximate_inverse(x, fn, zeta, [], [], dt) - ref)) < 1e-9


@pytest.mark.parametrize("elements,gains", [
    ([("mode", 1500.0, 0.1)], [0.25]),  # two modes
    ([("mode", 1500.0, 0.1), ("lowpass", 1e-4)], [0.25, 0.1]),
    ([("direct",)], [-0.5]),  # a zero in the right half plane: mirrored, stays stable
])
def test_approximate_inverse_is_stable_and_inverts_slow_signals(elements, gains):
    dt = 1e-4
    t = np.arange(20000) * dt
    u = np.sin(2 * np.pi * 5 * t) + 0.3 * np.sin(2 * np.pi * 23 * t)
    y = _g(u, 600.0, 0.05, elements, gains, dt)
    u_hat = approximate_inverse(y, 600.0, 0.05, elements, gains, dt)
    assert np.all(np.isfinite(u_hat)) and np.max(np.abs(u_hat)) < 2 * np.max(np.abs(u))
    err = np.abs(u_hat - u)[2000:-2]
    # a minimum-phase G is inverted at 5-23 Hz; the mirrored zero costs phase, not stability
    assert np.max(err) < (0.02 if gains[-1] > 0 else 0.5)


@pytest.mark.slow
def test_fit_recovers_two_modes_on_a_linear_stage():
    dt = 1e-4
    rng = np.random.default_rng(1)
    levels = rng.uniform(-1, 1, 12)
    v = np.concatenate([np.full(800, lv) for lv in levels])
    v = v + 0.3 * np.sin(2 * np.pi * 7 * np.arange(v.size) * dt)
    h = 2.0 * v
    y = _g(h, 500.0, 0.08, [("mode", 1300.0, 0.1)], [0.3], dt) + rng.normal(0, 1e-3, v.size)
    seg = make_segment(np.arange(v.size) * dt, v, y, [0.0, 0.2])
    m = fit_effect("dynamics", [seg])
    modes = sorted(m.params["dynamics_modes"], key=lambda d: d["hz"])
    assert m.params["dynamics_order"] == 2, m.params["dynamics_modes"]
    assert abs(modes[0]["hz"] / 500.0 - 1) < 0.05 and abs(modes[1]["hz"] / 1300.0 - 1) < 0.05
    assert abs(modes[1]["share"] - 0.3) < 0.05
    assert m.k == 2 + 3


def _alt(effects, seed):
    (tt, vt), (tv, vv) = excitations(seed + 1)
    truth = random_alt_truth(list(effects), seed)
    rng = np.random.default_rng(3 + seed)
    return ([Record(tt, vt, truth.simulate(tt, vt, rng), source="alt-train")],
            [Record(tv, vv, truth.simulate(tv, vv, rng), source="alt-validate")])


@pytest.fixture(scope="module")
def alt_dynamics():
    train, validate = _alt(["dynamics"], 0)
    return diagnose(train, validate, initial_state="unknown"), validate[0]


def test_two_mode_stage_gets_a_higher_order_and_a_larger_shrink(alt_dynamics):
    rep, _ = alt_dynamics
    v = rep.verdict
    assert v["effects"] == ["dynamics"]
    assert v["model"]["dynamics_order"] >= 2
    assert v["shrink"] >= ONE_MODE_SHRINK_TODAY + 0.1
    cand = next(c for c in rep.candidates if c["effect"] == "dynamics")
    assert cand["k"] == 2 + sum({"mode": 3, "lowpass": 2, "direct": 1}[e[0]]
                                for e in v["model"]["lti_elements"])


def test_diagnosed_model_simulates_the_fitted_linear_part(alt_dynamics, tmp_path):
    rep, rec = alt_dynamics
    aug = rep.model()
    assert aug.params["lti_elements"]
    y = aug.simulate(rec.v, rec.t)
    assert np.max(np.abs(y - rep.after[0])) < 1e-10 * np.ptp(rec.y)
    again = load_diagnosed_model(aug.save(tmp_path / "m.json"))
    assert np.array_equal(again.simulate(rec.v, rec.t), y)
    v_ff = aug.inverse().simulate(y[:3000])
    assert np.all(np.isfinite(v_ff)) and np.ptp(v_ff) < 2 * np.ptp(rec.v)


def test_one_mode_stage_is_not_overfitted():
    truth = random_truth(["dynamics"], 0)
    tt, vt = excitation("train", seed=1)
    tv, vv = excitation("validate", seed=2)
    v = diagnose([truth.record(tt, vt, 1)], [truth.record(tv, vv, 2)]).verdict
    assert v["effects"] == ["dynamics"] and v["shrink"] >= 0.9
    assert v["model"]["dynamics_order"] == 1
    assert len(v["model"]["lti_elements"]) <= 1


@pytest.mark.slow
def test_two_mode_model_exports_to_a_block_and_an_fmu_equal_to_simulate(alt_dynamics, tmp_path):
    """The diagnosed truth_alt stage (order 2 or more): ``diagnose --export``'s FMU validates
    and, in the co-simulation master, equals simulate to 1e-12; so do the C stream on the whole
    validate record and the python-control block (the end-to-end path of issue 19); the
    inverse's block equals its simulate delayed by one sample."""
    from fmpy.validation import validate_fmu

    from pimodel.blocks import initial_state
    from pimodel.cli.diagnose import export_models
    from pimodel.diagnosis.native_model import stream_simulate
    from pimodel.fmu.model_fmu import cosimulate_chain

    rep, rec = alt_dynamics
    paths = export_models(rep, tmp_path)
    fmu = tmp_path / "augmented_1_DiagnosedModel.fmu"
    assert fmu in paths and validate_fmu(str(fmu)) == []
    aug = load_diagnosed_model(tmp_path / "augmented.json")
    assert aug.params["lti_elements"] and "dynamics" in aug.effects
    want = aug.simulate(rec.v, rec.t)
    scale = max(1.0, float(np.max(np.abs(want))))
    assert np.max(np.abs(stream_simulate(aug, rec.v, rec.t) - want)) < 1e-12 * scale
    v = rec.v[:3000]
    assert np.max(np.abs(cosimulate_chain([fmu], v, aug.dt) - want[:3000])) < 1e-12 * scale
    blk = aug.block()
    t = np.arange(1000) * aug.dt
    res = control.input_output_response(blk, t, v[:1000], initial_state=initial_state(blk))
    assert np.max(np.abs(res.outputs - want[:1000])) < 1e-12 * scale
    # the feedforward as a block: simulate delayed by the latency (1: the ZOH advance)
    inv = aug.inverse()
    y_d = want[:800]
    ff = inv.block(reference_range=float(np.ptp(inv.prefilter(y_d))))
    assert ff.latency == 1
    res = control.input_output_response(ff, t[:800], y_d, initial_state=initial_state(ff))
    assert np.max(np.abs(res.outputs[1:] - inv.simulate(y_d)[:-1])) < 1e-9 * np.ptp(rec.v)


def test_a_mode_behind_a_real_pole_gets_a_low_pass_element():
    """A 2 kHz linear stage whose linear part is a mode in series with a real pole (drawn at
    random, both below 300 Hz) driven by slow ramps and sines: one mode cannot follow it to the
    noise; the selection adds a low-pass element (in parallel form) and then does."""
    rng = np.random.default_rng(11)
    dt = 5e-4
    fn, zeta, fp = rng.uniform(120, 300), rng.uniform(0.08, 0.3), rng.uniform(100, 250)
    levels = rng.uniform(-1, 1, 10)
    ends = zip(levels[:-1], levels[1:], strict=True)
    v = np.concatenate([np.linspace(a, b, 300) for a, b in ends])
    t = np.arange(v.size) * dt
    v = v + 0.3 * np.sin(2 * np.pi * 11 * t)
    h, noise = 2.0 * v, 1e-3
    wn, wp = 2 * np.pi * fn, 2 * np.pi * fp
    sys = cont2discrete((np.polymul([wn**2], [wp]),
                         np.polymul([1, 2 * zeta * wn, wn**2], [1, wp])), dt, method="zoh")
    b, a = np.ravel(sys[0]), sys[1]
    y = h[0] + lfilter(b, a, h - h[0]) + rng.normal(0, noise, v.size)
    seg = make_segment(t, v, y, [0.0, 0.2])
    m = fit_effect("dynamics", [seg])
    kinds = [e[0] for e in m.params["lti_elements"]]
    assert "lowpass" in kinds, m.params
    rms = float(np.sqrt(np.mean((m.predict(seg) - y) ** 2)))
    assert rms < 1.5 * noise, (rms, m.params)


def test_nelder_mead_treats_a_broken_fit_as_inadmissible():
    """A cost that raises LinAlgError or returns NaN at some points (a mode search that ran to
    non-finite columns) does not stop the search: those points count as inf."""
    from pimodel.diagnosis.lti import nelder_mead

    def cost(x):
        if x[0] < -1.0:
            raise np.linalg.LinAlgError("SVD did not converge")
        if x[0] > 4.0:
            return float("nan")
        return float((x[0] - 2.0) ** 2)

    r = nelder_mead(cost, np.array([-0.9]), initial_simplex=[[-0.9], [-1.5]], xatol=1e-8,
                    fatol=1e-12)
    assert abs(float(r.x[0]) - 2.0) < 1e-4


def test_element_columns_memoised_per_base_mode_equal_fresh_ones():
    # _lti_block keeps each element's column for the last base mode (at most LTI_MEMO): sets of
    # elements in any order, past the memo's size and after a change of base mode, give the
    # columns lti_columns builds afresh, to the bit
    from pimodel.diagnosis.effects import LTI_MEMO, Model, _lti_block, base_features

    rng = np.random.default_rng(4)
    n = 3000
    v = np.cumsum(rng.normal(0, 0.05, n))
    seg = make_segment(np.arange(n) * 1e-4, v, np.zeros(n), np.linspace(0, np.ptp(v) / 2, 4))
    nominal = Model("nominal", 0, base_features, rng.uniform(0.5, 1.5, 5))
    h0 = nominal.predict(seg)
    freqs, dampings = rng.uniform(300, 3000, LTI_MEMO + 4), rng.uniform(0.05, 0.5, LTI_MEMO + 4)
    pool = [("mode", float(f), float(z)) for f, z in zip(freqs, dampings, strict=True)]
    pool += [("lowpass", 2e-4), ("direct",)]
    static: dict = {}
    for fn, zeta in ((150.0, 0.2), (150.0, 0.2), (410.0, 0.05)):
        for _ in range(8):
            els = tuple(pool[i] for i in rng.choice(len(pool), int(rng.integers(1, 4)),
                                                    replace=False))
            p = {"fn": fn, "zeta": zeta, "lti": els}
            got = _lti_block(seg, p, nominal, static)
            assert np.array_equal(got, lti_columns(h0, fn, zeta, els, seg.dt))
        assert len(static[("lti", id(seg))][1]) <= LTI_MEMO
