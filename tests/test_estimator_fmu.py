"""One radius law everywhere: from the issue's starts, the python-control estimator block and
the RadiusEstimator FMU (FMI 2 and FMI 3) give the C core's numbers (estimate_radii) to 1e-12,
under the default data-driven law and under the paper's law (the FMU's `law` parameter), on a
record long enough for the branch profile to be fitted and to drive the estimate. The FMU's
health output and the warning it logs at terminate say what estimate_radii's health report
says."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pimodel import PIOperator, estimate_radii
from pimodel.blocks import estimator_block
from pimodel.fmu.unit import FMUUnit
from pimodel.loops.simulation import simulate
from pimodel.signals import sinusoid

P = np.array([0.3, 0.5, 0.8, 0.3, 0.2])
R = np.array([0.4, 1.0, 1.5, 2.0, 3.6])
TS = 1e-3
STARTS = {"below": [0.1, 0.2, 0.3, 0.4, 0.5], "zero": [0.0] * 5,
          "mixed": [0.2, 1.5, 1.6, 3.0, 3.2]}
SETTINGS = dict(gains=10.0, guard=0.0, threshold=0.0, slope_window=8)
LAWS = {"data": 0, "paper": 1}  # the FMU's law parameter


@pytest.fixture(scope="module")
def fmus(built_fmus) -> Path:
    return built_fmus


@pytest.fixture(scope="module")
def record():
    t, v = sinusoid(30, 1, fs=1 / TS, duration=3)
    return t, v, PIOperator(P, R).simulate(v)


def core(record, start, law="data"):
    t, v, y = record
    ref = estimate_radii(v, y, P, dt=TS, initial_radii=STARTS[start], law=law, polish=False,
                         **SETTINGS)
    assert ref.used.sum() > 1000  # the law adapted (data law: profile fitted, regimes found)
    assert np.max(np.abs(ref.radii - ref.history[0])) > 0.05  # and moved the estimate
    return ref


def fmu_params(fmi, initial_radii, **extra) -> tuple[str, dict]:
    """(file name, start values) of the RadiusEstimator FMU for the paper's weights P."""
    params = {"Ts": TS, "n": P.size, "gain": SETTINGS["gains"], "guard": 0.0, **extra}
    if fmi == "2.0":
        params.update({f"p[{i + 1}]": float(x) for i, x in enumerate(P)})
        params.update({f"r[{i + 1}]": float(x) for i, x in enumerate(initial_radii)})
        return "RadiusEstimator.fmu", params
    params.update({"p": P, "r": initial_radii})
    return "RadiusEstimator_fmi3.fmu", params


def run_fmu(fmus, fmi, initial_radii, v, y, names, **extra):
    """The FMU stepped sample by sample; returns (outputs after each sample, the unit closed,
    its log in unit.log_entries)."""
    file, params = fmu_params(fmi, initial_radii, **extra)
    unit = FMUUnit(fmus / file, params)
    out = []
    for a, b in zip(v, y, strict=True):
        unit.set({"v": a, "y": b})
        unit.step(TS)
        out.append(unit.get(names))
    unit.close()
    return np.array(out), unit


@pytest.mark.parametrize("start", list(STARTS))
def test_estimator_block_equals_c_core(record, start):
    t, v, y = record
    ref = core(record, start)
    blk = estimator_block(P, TS, initial_radii=STARTS[start], **SETTINGS)
    res = simulate(blk, t, {"v": v, "y": y})
    hist = np.column_stack([res[f"r_hat[{i + 1}]"] for i in range(P.size)])
    np.testing.assert_allclose(hist, ref.history, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res["y_hat"], ref.model_output, rtol=0, atol=1e-12)


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
@pytest.mark.parametrize("start", list(STARTS))
def test_estimator_fmu_equals_c_core(fmus, record, start, fmi):
    t, v, y = record
    ref = core(record, start)
    names = [f"r_hat[{i + 1}]" for i in range(P.size)] + ["y_hat"]
    out, _ = run_fmu(fmus, fmi, STARTS[start], v, y, names)
    np.testing.assert_allclose(out[:, :-1], np.vstack((ref.history[1:], ref.radii)), rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(out[:, -1], ref.model_output, rtol=0, atol=1e-12)


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
@pytest.mark.parametrize("start", ["below", "mixed"])
def test_estimator_fmu_paper_law_equals_c_core(fmus, record, start, fmi):
    """law = 1 runs the paper's law: the estimate_radii(law="paper") numbers to 1e-12, and
    not the data law's (the parameter switches the law)."""
    t, v, y = record
    ref = core(record, start, law="paper")
    data_law = core(record, start)
    assert np.max(np.abs(ref.history - data_law.history)) > 0.05
    names = [f"r_hat[{i + 1}]" for i in range(P.size)] + ["y_hat", "e"]
    out, _ = run_fmu(fmus, fmi, STARTS[start], v, y, names, law=LAWS["paper"])
    np.testing.assert_allclose(out[:, :P.size], np.vstack((ref.history[1:], ref.radii)),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[:, P.size], ref.model_output, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[:, P.size + 1], ref.error, rtol=0, atol=1e-12)


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
@pytest.mark.parametrize("law", [2, -1, 1000])
def test_estimator_fmu_refuses_a_bad_law(fmus, fmi, law):
    file, params = fmu_params(fmi, STARTS["below"], law=law)
    with pytest.raises(ValueError, match=rf"initialisation failed: parameter law = {law} out "
                                         r"of range: 0 data .*, 1 paper"):
        FMUUnit(fmus / file, params)


# ---- health: the FMU's `health` output and its warning at terminate --------------------------

WARNING = 1  # fmi2Warning == fmi3Warning
HEALTH_CASES = {  # law, initial radii, input amplitude, record length [s], bits that must be set
    "healthy, from the truth": ("data", R, 30.0, 3.0, 0),
    "degenerate start (all 0), short record": ("data", [0.0] * 5, 30.0, 0.2, 1 | 2 | 4),
    "from below, record too short": ("data", STARTS["below"], 30.0, 3.0, 8),
    "input range below 2 r_n": ("data", R, 2.0, 3.0, 1),
    "paper's law from below: a wrong fixed point": ("paper", STARTS["below"], 30.0, 3.0, 16),
}
PHRASES = {1: "cannot excite every play", 2: "plays merged", 4: "pinned at the projection bound",
           8: "still moving", 16: "does not fit the data"}


def python_health_bits(health) -> int:
    """estimate_radii's health report as the FMU's bit mask."""
    return ((not health.excitation_ok) * 1 | bool(health.merged) * 2 | bool(health.pinned) * 4
            | bool(health.still_moving) * 8 | (not health.fit_ok) * 16)


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
@pytest.mark.parametrize("case", list(HEALTH_CASES))
def test_estimator_fmu_health_output_and_log_equal_python(fmus, case, fmi):
    law, r0, amplitude, duration, must = HEALTH_CASES[case]
    t, v = sinusoid(amplitude, 1, fs=1 / TS, duration=duration)
    y = PIOperator(P, R).simulate(v)
    ref = estimate_radii(v, y, P, dt=TS, initial_radii=r0, law=law, polish=False, **SETTINGS)
    want = python_health_bits(ref.health)
    assert want & must == must and (want != 0) == (must != 0), (want, ref.health.messages)
    out, unit = run_fmu(fmus, fmi, r0, v, y, ["health"], law=LAWS[law])
    assert int(out[-1, 0]) == want
    warnings = [(cat, msg) for status, cat, msg in unit.log_entries if status == WARNING]
    if want == 0:
        assert warnings == []
        return
    assert len(warnings) == 1 and warnings[0][0] == "logStatusWarning", unit.log_entries
    message = warnings[0][1]
    assert f"radius estimate health after {v.size} samples (health = {want})" in message
    for bit, phrase in PHRASES.items():
        assert (phrase in message) == bool(want & bit), (bit, message)
    for a, b in ref.health.merged:
        assert f"r_hat[{a}] = r_hat[{b}]" in message
    assert "%" not in message  # hosts may use it as a format string


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_simulate_fmu_logger_receives_the_health_warning(fmus, fmi):
    """fmpy.simulate_fmu with a logger callback, the FMU's default start (all radii 0) on a
    record too short to move them: the run ends with the warning (logStatusWarning), and the
    health output says the same."""
    from fmpy import simulate_fmu

    weights = np.ones(5)  # the FMU's default weights: only scalar start values below
    t, v = sinusoid(30, 1, fs=1 / TS, duration=0.2)
    y = PIOperator(weights, R).simulate(v)
    signals = np.array(list(zip(t, v, y, strict=True)),
                       dtype=[("time", float), ("v", float), ("y", float)])
    records = []

    def logger(*args):  # FMI 2: (env, instance, status, category, message); FMI 3: no instance
        records.append((int(args[-3]), args[-2].decode(), args[-1].decode()))

    file = "RadiusEstimator.fmu" if fmi == "2.0" else "RadiusEstimator_fmi3.fmu"
    res = simulate_fmu(str(fmus / file), start_values={"Ts": TS, "n": 5, "gain": 10.0},
                       input=signals, output=["health", "y_hat"], step_size=TS,
                       output_interval=TS, stop_time=0.2, logger=logger)
    bits = int(res["health"][-1])
    assert bits & 2 and bits & 4  # merged and pinned at 0
    warnings = [(cat, msg) for status, cat, msg in records if status == WARNING]
    assert len(warnings) == 1 and warnings[0][0] == "logStatusWarning", records
    assert f"(health = {bits})" in warnings[0][1] and "pinned at the projection bound" in \
        warnings[0][1]


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_fmu_with_self_tuned_settings_equals_estimate_radii(fmus, fmi):
    """Issue 27: estimate_radii's settings chosen from a noisy record (gain, guard, threshold,
    slope window) reach the FMU through RadiusEstimate.fmu_start_values; the FMU then gives
    the online iterate (polish=False) to 1e-12."""
    t, v = sinusoid(30, 1, fs=1 / TS, duration=3)
    rng = np.random.default_rng(27)
    v = v + rng.normal(0, 0.05, v.size)  # input noise: a threshold above 0
    y0 = PIOperator(P, R).simulate(v)
    y = y0 + rng.normal(0, np.std(y0) / 10, v.size)
    ref = estimate_radii(v, y, P, dt=TS, initial_radii=STARTS["zero"], polish=False)
    start = ref.fmu_start_values()
    assert start["threshold"] > 0 and start["guard"] > 0 and start["gain"] != 10.0
    out, _ = run_fmu(fmus, fmi, STARTS["zero"], v, y,
                     [f"r_hat[{i + 1}]" for i in range(P.size)], **start)
    np.testing.assert_allclose(out, np.vstack((ref.history[1:], ref.radii)), rtol=0,
                               atol=1e-12)
    assert np.max(np.abs(ref.radii - ref.history[0])) > 0.05  # the estimate moved
