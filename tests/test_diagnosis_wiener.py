"""The ``dynamics`` candidate with a filter *before* the hysteresis (Wiener form,
``pimodel.diagnosis.wiener``): its filter and approximate inverse against python-control, the
diagnosed model's forward form, inverse and its stream on the C core, and the verdict on stages
whose amplifier low-passes the input (written here, independently of the candidate library:
the filter by python-control's zero-order hold, then the PI stage of ``pimodel.stages.pi_stage`` or
the
Preisach stage of ``pimodel.stages.preisach_stage``)."""

from __future__ import annotations

import control
import numpy as np
import pytest
from scipy.signal import lfilter, lfilter_zi

from pimodel import Record
from pimodel.blocks import initial_state
from pimodel.diagnosis import diagnose
from pimodel.diagnosis.model import DiagnosedModel, load_diagnosed_model
from pimodel.diagnosis.wiener import inverse_prefilter, prefilter, search_filter
from pimodel.operators.pi import PIOperator
from pimodel.stages.pi_stage import excitation, random_truth, zoh_coefficients
from pimodel.stages.preisach_stage import excitations, random_alt_truth

TAU = 1 / (2 * np.pi * 300.0)  # a 300 Hz first-order low-pass [s]


def _driver(v, G, dt):
    """``v`` through the continuous system ``G`` (ZOH by python-control), at rest at v[0]."""
    b, a = zoh_coefficients(G, dt)
    return lfilter(b, a, v, zi=lfilter_zi(b, a) * v[0])[0]


@pytest.mark.parametrize("element,G", [
    (("lowpass", TAU), control.tf([1.0], [TAU, 1.0])),
    (("mode", 400.0, 1.3), control.tf([(2 * np.pi * 400) ** 2],
                                      [1.0, 2 * 1.3 * 2 * np.pi * 400, (2 * np.pi * 400) ** 2])),
])
def test_prefilter_is_the_zoh_of_the_continuous_filter(element, G):
    dt = 1e-4
    t = np.arange(3000) * dt
    v = 0.3 + np.sin(2 * np.pi * 30 * t) + (t > 0.1)
    assert np.max(np.abs(prefilter(v, [element], dt) - _driver(v, G, dt))) < 1e-9


def test_inverse_prefilter_equals_the_python_control_form():
    # (tau s + 1) / (s / wf + 1), wf = 2 / tau, Tustin, advanced one sample
    dt = 1e-4
    d = control.sample_system(control.tf([TAU, 1.0], [TAU / 2, 1.0]), dt, method="tustin")
    b, a = np.ravel(d.num[0][0]), np.ravel(d.den[0][0])
    x = np.sin(2 * np.pi * 20 * np.arange(2000) * dt) + 0.5
    ref = lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])[0]
    assert np.max(np.abs(inverse_prefilter(x, [("lowpass", TAU)], dt) - np.r_[ref[1:],
                                                                            ref[-1]])) < 1e-9


@pytest.mark.parametrize("element", [("lowpass", TAU), ("mode", 500.0, 0.3)])
def test_inverse_prefilter_inverts_slow_signals(element):
    dt = 1e-4
    t = np.arange(20000) * dt
    v = np.sin(2 * np.pi * 5 * t) + 0.3 * np.sin(2 * np.pi * 23 * t)
    v_hat = inverse_prefilter(prefilter(v, [element], dt), [element], dt)
    # what is left is the phase of the added low-pass (twice the fastest pole: 600 Hz for the
    # low-pass, 1 kHz for the mode), about 2 degrees at 23 Hz
    assert np.max(np.abs(v_hat - v)[:-2]) < 0.025


def test_search_filter_refuses_a_band_below_its_slowest_filter():
    with pytest.raises(ValueError, match="fmax"):
        search_filter(lambda els: 1.0, 10.0, 100)


def _wiener_model(elements):
    return DiagnosedModel([0.0, 0.2, 0.5], [2.0, 0.6, 0.3], 0.1, dt=1e-4,
                          effects=("dynamics",),
                          params={"dynamics_position": "before", "wiener_elements": elements})


def test_model_simulates_the_plays_of_the_filtered_input(tmp_path):
    m = _wiener_model([["lowpass", TAU]])
    t = np.arange(4000) * 1e-4
    v = np.sin(2 * np.pi * 15 * t) * np.linspace(1, 0.3, t.size)
    x = _driver(v, control.tf([1.0], [TAU, 1.0]), 1e-4)
    ref = PIOperator([2.0, 0.6, 0.3], [0.0, 0.2, 0.5]).simulate(x) + 0.1
    y = m.simulate(v)
    assert np.max(np.abs(y - ref)) < 1e-9
    assert np.array_equal(load_diagnosed_model(m.save(tmp_path / "m.json")).simulate(v), y)
    # the inverse: the hysteresis for the filter's output, then the filter's approximate
    # inverse; close at 15 Hz under a 300 Hz low-pass
    v_hat = m.inverse().simulate(y)
    assert np.max(np.abs(v_hat - v)[:-2]) < 0.02 * np.ptp(v)
    assert not m.is_exactly_invertible


def test_stream_and_inverse_block_run_the_filter():
    """The forward model streams on the C core (tests/test_wiener_stream.py: block and FMU);
    the inverse's block runs the filter's inverse after its solver, one sample later than the
    batch (tests/test_inverse_block.py)."""
    from pimodel.diagnosis.native_model import stream_simulate

    m = _wiener_model([["mode", 800.0, 0.7]])
    v = np.sin(2 * np.pi * 15 * np.arange(500) * 1e-4)
    assert np.max(np.abs(stream_simulate(m, v) - m.simulate(v))) < 1e-12
    assert m.inverse().block().latency == 1


def truth_driver_records(seed: int):
    """A ``pimodel.stages.pi_stage`` PI stage (no other effect) behind an amplifier with a
    first-order
    bandwidth of 150-600 Hz (seeded)."""
    rng = np.random.default_rng(8000 + seed)
    fc = rng.uniform(150.0, 600.0)
    G = control.tf([1.0], [1 / (2 * np.pi * fc), 1.0])
    truth = random_truth([], seed)
    tt, vt = excitation("train", seed=2 * seed + 1)
    tv, vv = excitation("validate", seed=2 * seed + 2)
    tv = tv + tt[-1] + 1.0
    recs = [Record(t, v, truth.simulate(t, _driver(v, G, 1e-4), np.random.default_rng(s)),
                   source=name)
            for t, v, s, name in ((tt, vt, seed, "train"), (tv, vv, 100 + seed, "validate"))]
    return [recs[0]], [recs[1]], fc


def alt_driver_records(seed: int):
    """A ``pimodel.stages.preisach_stage`` Preisach stage behind a second-order low-pass (a driver
    with
    two poles, 200-500 Hz, damping 0.5-1.2, seeded)."""
    rng = np.random.default_rng(9000 + seed)
    w, zeta = 2 * np.pi * rng.uniform(200.0, 500.0), rng.uniform(0.5, 1.2)
    G = control.tf([w * w], [1.0, 2 * zeta * w, w * w])
    (tt, vt), (tv, vv) = excitations(seed + 1)
    truth = random_alt_truth([], seed)
    noise = np.random.default_rng(3 + seed)
    dt = float(tt[1] - tt[0])
    return ([Record(tt, vt, truth.simulate(tt, _driver(vt, G, dt), noise), source="train")],
            [Record(tv, vv, truth.simulate(tv, _driver(vv, G, dt), noise), source="validate")])


@pytest.fixture(scope="module")
def driver_report():
    train, validate, fc = truth_driver_records(0)
    return diagnose(train, validate), validate[0], fc


@pytest.mark.slow
def test_first_order_driver_is_a_lowpass_before_the_hysteresis(driver_report):
    rep, _, fc = driver_report
    v = rep.verdict
    assert v["effects"] == ["dynamics"] and v["shrink"] >= 0.5
    assert v["model"]["dynamics_position"] == "before"
    assert abs(v["model"]["lowpass_hz"] / fc - 1) < 0.2
    cand = next(c for c in rep.candidates if c["effect"] == "dynamics")
    assert cand["k"] == 1


@pytest.mark.slow
def test_diagnosed_wiener_model_simulates_what_was_fitted(driver_report):
    rep, rec, _ = driver_report
    aug = rep.model()
    assert aug.dynamics_before
    assert np.max(np.abs(aug.simulate(rec.v, rec.t) - rep.after[0])) < 1e-9 * np.ptp(rec.y)


@pytest.mark.slow
def test_diagnosed_wiener_inverse_block_equals_its_batch(driver_report):
    """The inverse of the model the diagnosis chose (a low-pass before 40 plays) as a block:
    the batch feedforward delayed by one sample, for the first 3000 samples of the validate
    record's output as the reference."""
    rep, rec, _ = driver_report
    inv = rep.model().inverse()
    y_d = rec.y[:3000]
    want = inv.simulate(y_d)
    blk = inv.block(reference_range=float(np.ptp(inv.prefilter(y_d))))
    t = np.arange(y_d.size) * rep.model().dt
    res = control.input_output_response(blk, t, y_d, initial_state=initial_state(blk))
    a = blk.latency
    assert a == 1
    assert np.max(np.abs(res.outputs[a:] - want[:y_d.size - a])) < 1e-9 * np.ptp(want)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_first_order_driver_on_other_seeds(seed):
    train, validate, _ = truth_driver_records(seed)
    v = diagnose(train, validate).verdict
    assert v["effects"] == ["dynamics"] and v["shrink"] >= 0.5


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_second_order_driver_before_preisach_is_dynamics(seed):
    v = diagnose(*alt_driver_records(seed), initial_state="unknown").verdict
    assert v["effects"] == ["dynamics"] and v["shrink"] >= 0.5


def ramp_hold(rng: np.random.Generator, fs: float, duration: float) -> np.ndarray:
    """Ramps of 0.05-0.4 s between random levels in [-1, 1] V, each held 0.02-0.3 s, from a
    50 ms rest at 0 V (a user's positioning moves)."""
    parts, level = [np.zeros(int(0.05 * fs))], 0.0
    while sum(p.size for p in parts) < duration * fs:
        new = rng.uniform(-1.0, 1.0)
        parts.append(np.linspace(level, new, int(rng.uniform(0.05, 0.4) * fs), endpoint=False))
        parts.append(np.full(int(rng.uniform(0.02, 0.3) * fs), new))
        level = new
    return np.concatenate(parts)[: int(duration * fs)]


def amplifier_ramp_records(seed: int):
    """A PI stage behind an amplifier of a 40-150 Hz bandwidth, ``u[k] = a u[k-1] + (1 - a)
    v[k]`` (not the ZOH form of the candidate), ramps to held levels at 5 kHz."""
    fs = 5000.0
    rng = np.random.default_rng(7000 + seed)
    fc = rng.uniform(40.0, 150.0)
    a = np.exp(-2 * np.pi * fc / fs)
    truth = random_truth([], seed)
    recs = []
    for j, duration in enumerate((3.0, 2.5)):
        v = ramp_hold(rng, fs, duration)
        t = np.arange(v.size) / fs
        u = lfilter([1 - a], [1.0, -a], v, zi=[a * v[0]])[0]
        y = truth.simulate(t, u, np.random.default_rng(100 * seed + j))
        recs.append(Record(t, v, y, source=("train", "validate")[j]))
    return [recs[0]], [recs[1]], fc


@pytest.mark.slow
@pytest.mark.parametrize("seed", [int(s) for s in np.random.default_rng(70).integers(0, 1000, 2)])
def test_amplifier_bandwidth_under_ramps_and_holds_is_a_lowpass_before(seed):
    """The filter before the hysteresis is searched with every play column: with the leading
    12 (principal directions of the unfiltered plays) the hysteresis itself misfit by some 200
    times the noise and such stages read ``delay`` (0 of 7 measured)."""
    train, validate, fc = amplifier_ramp_records(seed)
    v = diagnose(train, validate, workers=1).verdict
    assert v["effects"] == ["dynamics"]
    assert v["model"]["dynamics_position"] == "before"
    assert abs(v["model"]["lowpass_hz"] / fc - 1) < 0.2
    assert v["gap_after"] < 1.5 * v["noise_floor"] < 0.5 * v["gap_before"]


@pytest.mark.parametrize("kinds", [(), ("lowpass", "notch")])
def test_search_filter_names_a_bad_kind(kinds):
    with pytest.raises(ValueError, match=r"^kinds: expected some of \['lowpass'"):
        search_filter(lambda els: 1.0, 2000.0, 100, kinds=kinds)
