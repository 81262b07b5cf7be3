"""DiagnosisReport.model(): the nominal and augmented models as objects, their forward
simulation (equal to the diagnosis' own predictions), inverse feedforward and JSON form."""

import numpy as np
import pytest

from pimodel.diagnosis import diagnose
from pimodel.diagnosis.model import DiagnosedModel, load_diagnosed_model
from pimodel.diagnosis.monotone import is_monotone, monotone_model
from pimodel.stages.pi_stage import excitation, random_truth

N_ROUND_TRIP = 3000  # samples of the validate input in the round trips (the solve is per sample)


def _report(effect: str, seed: int = 0):
    truth = random_truth([effect], seed)
    tt, vt = excitation("train", seed=1)
    tv, vv = excitation("validate", seed=2)
    rec = truth.record(tv, vv, 2)
    return diagnose([truth.record(tt, vt, 1)], [rec]), rec


@pytest.fixture(scope="module", params=["creep", "asymmetry"])
def invertible(request):
    return request.param, *_report(request.param)


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_model_equals_the_diagnosis_prediction(invertible):
    effect, rep, rec = invertible
    assert rep.verdict["effects"] == [effect]
    aug, nom = rep.model(), rep.model(augmented=False)
    assert aug.effects == (effect,) and nom.effects == ()
    scale = float(np.ptp(rec.y))
    assert np.max(np.abs(aug.simulate(rec.v, rec.t) - rep.after[0])) < 1e-10 * scale
    assert np.max(np.abs(nom.simulate(rec.v, rec.t) - rep.before[0])) < 1e-10 * scale


def test_inverse_round_trip_is_exact(invertible):
    """Exact for a monotone model; a model that folds (signed weights with a partial sum <= 0,
    here the asymmetry record's nominal fit) is inverted through its nearest monotone model
    (:mod:`pimodel.diagnosis.monotone`), whose round trip is exact."""
    _, rep, rec = invertible
    v = rec.v[:N_ROUND_TRIP]
    for model in (rep.model(), rep.model(augmented=False)):
        monotone = monotone_model(model)
        if monotone is model:
            assert np.max(np.abs(model.inverse().simulate(model.simulate(v)) - v)) < 1e-9
        else:
            assert is_monotone(monotone.weights)
            assert np.max(np.abs(model.inverse().simulate(monotone.simulate(v)) - v)) < 1e-9


def test_json_round_trip(invertible, tmp_path):
    _, rep, rec = invertible
    model = rep.model()
    again = load_diagnosed_model(model.save(tmp_path / "m.json"))
    v = rec.v[:N_ROUND_TRIP]
    assert np.array_equal(again.simulate(v), model.simulate(v))
    assert again.effects == model.effects


@pytest.mark.slow
@pytest.mark.parametrize("effect", ["delay", "dynamics", "drift", "rate"])
def test_other_effects_equal_the_diagnosis_prediction(effect):
    rep, rec = _report(effect)
    if rep.verdict["effects"] != [effect]:
        pytest.skip(f"verdict {rep.verdict['effects']} (not this test's subject)")
    aug = rep.model()
    assert np.max(np.abs(aug.simulate(rec.v, rec.t) - rep.after[0])) < 1e-9 * np.ptp(rec.y)
    v_ff = aug.inverse().simulate(aug.simulate(rec.v[:N_ROUND_TRIP]))
    assert v_ff.shape == (N_ROUND_TRIP,) and np.all(np.isfinite(v_ff))


def test_synthetic_creep_asymmetry_round_trip():
    params = {"creep_lag_gains": [0.04, -0.01], "creep_time_constants_s": [0.01, 0.2],
              "asymmetry_quadratic": 0.05, "asymmetry_cubic": -0.01, "center": 0.8,
              "half_range": 1.0}
    m = DiagnosedModel([0.0, 0.2, 0.5], [1.0, 0.4, 0.3], 0.2, dt=1e-3,
                       effects=("creep", "asymmetry"), reference_weights=[0.9, 0.45, 0.3],
                       reference_offset=0.1, params=params)
    t = np.arange(4000) * 1e-3
    v = np.sin(2 * np.pi * 1.3 * t) * (1 + 0.5 * np.sin(2 * np.pi * 0.2 * t))
    assert np.max(np.abs(m.inverse().simulate(m.simulate(v)) - v)) < 1e-9


@pytest.mark.parametrize("d", [1, 4, 2.5])
@pytest.mark.parametrize("start", ["rest", "record", "common"])
def test_a_delay_delays_the_input_of_every_term(d, start):
    """The delay acts on the input: a model with creep, asymmetry and a delay of ``d`` samples
    is the model without the delay, its output delayed (held at its first sample before the
    start; a fractional ``d`` interpolates ``h0`` between the two whole delays, so only the
    terms linear in ``h0`` commute with it: no asymmetry there). Before, the creep and the
    asymmetry took ``h0`` undelayed beside the delayed hysteresis."""
    params = {"creep_lag_gains": [0.04, -0.01], "creep_time_constants_s": [0.01, 0.2],
              "asymmetry_quadratic": 0.05, "asymmetry_cubic": -0.01, "center": 0.8,
              "half_range": 1.0}
    if start != "rest":
        params["creep_start"] = start
    if start == "common":
        params["creep_start_levels"] = [0.3, -0.2]

    def model(effects, **more):
        return DiagnosedModel([0.0, 0.2, 0.5], [1.0, 0.4, 0.3], 0.2, dt=1e-3, effects=effects,
                              reference_weights=[0.9, 0.45, 0.3], reference_offset=0.1,
                              params={**params, **more})

    t = np.arange(3000) * 1e-3
    v = 0.3 + np.sin(2 * np.pi * 1.3 * t) * (1 + 0.5 * np.sin(2 * np.pi * 0.2 * t))
    v[1500:] += np.where(np.arange(1500) % 300 < 150, 0.4, -0.2)  # steps
    terms = ("creep", "asymmetry") if d == int(d) else ("creep",)
    plain = model(terms).simulate(v)
    delayed = model((*terms, "delay"), delay_samples=d).simulate(v)
    lo, f = int(np.floor(d)), d - np.floor(d)
    want = (1 - f) * np.concatenate([np.full(lo, plain[0]), plain[:plain.size - lo]]) + \
        f * np.concatenate([np.full(lo + 1, plain[0]), plain[:plain.size - lo - 1]])
    if start == "common":  # the lags' free response from their rest runs on time, undelayed
        assert np.max(np.abs(delayed - want)) < 0.05 * np.ptp(plain)
        free = model((*terms, "delay"), delay_samples=d, creep_lag_gains=[0, 0])
        assert np.max(np.abs(free.simulate(v) - want)) > 1e-3  # the creep is there
    else:
        assert np.max(np.abs(delayed - want)) < 1e-12 * np.ptp(plain)


@pytest.mark.parametrize("u", [-1.3, -0.6, 0.0, 0.45, 1.3])
def test_unknown_initial_state_recovers_the_memory_of_a_reversal(u):
    """A stage that went from rest to ``u`` and back to 0 before the reference starts (the
    memory the rest inverse gets wrong): the inverse with ``initial_state="unknown"`` finds
    that memory from ``y_d[0]`` and returns the input after the excursion exactly."""
    params = {"asymmetry_quadratic": 0.05, "asymmetry_cubic": -0.01, "center": 0.3,
              "half_range": 1.5}
    m = DiagnosedModel([0.0, 0.2, 0.5], [1.0, 0.4, 0.3], 0.2, dt=1e-3, effects=("asymmetry",),
                       reference_weights=[0.9, 0.45, 0.3], reference_offset=0.1, params=params)
    prelude = np.concatenate((np.linspace(0.0, u, 50), np.linspace(u, 0.0, 50)[1:]))
    t = np.arange(2000) * 1e-3
    v = 0.8 * np.sin(2 * np.pi * 1.7 * t) * np.exp(-t)
    y = m.simulate(np.concatenate((prelude, v)))[prelude.size:]
    z = m.inverse().initial_memory(y[0])
    expect = np.clip(np.clip(0.0, u - m.radii, u + m.radii), -m.radii, m.radii)
    assert np.max(np.abs(z - expect)) < 1e-9
    assert np.max(np.abs(m.inverse().simulate(y, initial_state="unknown") - v)) < 1e-9
    if u != 0.0:  # from rest, the first inputs differ (the memory is not the rest's)
        assert np.max(np.abs(m.inverse().simulate(y) - v)) > 1e-3


def test_initial_state_comes_from_the_diagnosis(tmp_path):
    m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3, initial_state="unknown")
    again = load_diagnosed_model(m.save(tmp_path / "m.json"))
    assert again.initial_state == "unknown"
    old = m.to_dict()
    del old["initial_state"]  # a model written before the field: at rest
    assert DiagnosedModel.from_dict(old).initial_state == "rest"
    # y_d[0] below the output at rest: the unknown memory starts on an ascending branch
    y_d = np.array([-0.1, 0.3, 0.6])
    assert m.inverse().simulate(y_d)[0] == pytest.approx(0.0, abs=1e-12)
    # from rest, the input moves there (only the linear play follows a move below 0.5)
    assert m.inverse().simulate(y_d, initial_state="rest")[0] == pytest.approx(-0.1)


def test_bad_input():
    m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3)
    with pytest.raises(ValueError, match="y_d"):
        m.inverse().simulate([1.0, np.nan, 2.0])
    with pytest.raises(ValueError, match="initial_state"):
        m.inverse().simulate([1.0, 2.0], initial_state="saturated")
    with pytest.raises(ValueError, match="initial_state"):
        DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3, initial_state="cold")
    with pytest.raises(ValueError, match="weights"):
        DiagnosedModel([0.0, 0.5], [1.0], 0.0, dt=1e-3)
    with pytest.raises(ValueError, match="effects"):
        DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3, effects=("wobble",))
    with pytest.raises(ValueError, match="missing key 'weights'"):
        DiagnosedModel.from_dict({"type": "DiagnosedModel", "radii": [0.0]})


def test_simulate_names_a_measured_output_of_the_wrong_length():
    """``measured`` is checked for every model (a creep with an unknown start reads its first
    sample): a length other than ``v``'s is a ValueError naming it."""
    m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=1e-3, effects=("creep",),
                       params={"creep_lag_gains": [0.05], "creep_time_constants_s": [0.1]},
                       initial_state="unknown")
    with pytest.raises(ValueError, match="measured: expected 3 samples like v"):
        m.simulate([0.0, 1.0, 0.0], measured=[0.0, 1.0])
    y = m.simulate([0.0, 1.0, 0.0], measured=[0.3, 1.0, 0.0])
    assert np.all(np.isfinite(y)) and not np.allclose(y, m.simulate([0.0, 1.0, 0.0]))
