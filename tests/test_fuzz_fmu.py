"""FMU robustness (issue 14), FMI 2 and FMI 3, all units (issue 19 added GeneralizedPI,
AsymmetricPI, RateDependentPI and CreepOperator, each with its inverse flag, and
DiagnosedModel, signed weights, up to 128 plays, and its feedforward DiagnosedInverse), every
call in a
child process (tests/fmu_driver.py) so that a crash or a hang fails
the test instead of killing pytest:

- each crash or hang case of the issue, with the logged reason: corrupted FMU states (n = 10^6,
  n = -5, NaN radius, random bytes, bit flips, truncation), Ts = 1e-300, too many samples per
  doStep, t = 2^53 Ts, t + h == t, a t that is not the FMU's time, negative t, doStep after
  terminate, a non-finite start time, unknown value references, calls in the wrong state;
- an exact FMU-state round trip (get, serialize, deserialize, set) for every unit;
- a random life-cycle fuzzer: random call sequences, parameters, communication points, step
  sizes and corrupted states; 0 crashes, 0 hangs, every failure fmi2Error/fmi3Error with a
  logged message, every corrupted state rejected.
"""

from __future__ import annotations

import ctypes
import math
import random
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))

from fmu_driver import (  # noqa: E402
    NMAX,
    STATUS_SKIPPED,
    DriverFailure,
    StateHeader,
    UnitPrefix,
    read_field,
    run_job,
)

from pimodel import PIOperator  # noqa: E402
from pimodel.fmu import MODELS, build_fmus  # noqa: E402
from pimodel.fmu.build import NMAX as BUILD_NMAX  # noqa: E402
from pimodel.fmu.unit import FMUUnit  # noqa: E402

TS = 1e-3
P, R = [1.0, 0.5, 0.3], [0.0, 0.2, 0.6]
CONFIGS = [(name, fmi) for name in MODELS for fmi in ("2.0", "3.0")]
IDS = [f"{name}-fmi{fmi[0]}" for name, fmi in CONFIGS]
OK, ERROR = 0, 3
VR = {"Ts": 0, "n": 1, "z0": 2, "adaptive": 3, "gain": 4, "linear_play": 5, "guard": 6,
      "slope_window": 7, "inverse": 8, "time": 9, "in1": 10, "out1": 11, "in2": 12, "out2": 13,
      "law": 14, "health": 15, "in_kind": 20, "in_c0": 21, "in_c1": 22, "in_c2": 23,
      "in_c3": 24, "rate_gain": 40, "p": 100, "r": 200, "r_hat": 300, "n_lags": 52,
      "asymmetry_quadratic": 53, "rate_scale": 57, "drift_clock": 60, "lti_order": 61,
      "delay_samples": 62, "creep_gain": 500, "creep_tau": 600, "rate_band_gain": 700,
      "lti_b": 800, "lti_a": 900, "rate_family": 63, "rate_tau": 64, "n_lti_elements": 65,
      "lti_gain": 1400, "lti_element_b": 1500, "lti_element_a": 1600, "n_wiener_elements": 66,
      "wiener_element_b": 1700, "wiener_element_a": 1800, "reference_range": 67, "latency": 68,
      "delay_fraction": 69, "n_sections": 70, "section": 1900, "n_post_sections": 71,
      "post_section": 2000}
OPERATOR_UNITS = ("GeneralizedPI", "AsymmetricPI", "RateDependentPI", "CreepOperator")
DIAG_UNITS = ("DiagnosedModel", "DiagnosedInverse")  # signed weights, up to 128 plays
TAU = [0.01, 0.2, 0.6]  # creep time constants (the r array of CreepOperator)
CREEP_GAINS = [0.05, 0.03, 0.02]  # minimum phase at every Ts (sum < 1)
# the DiagnosedModel's further LTI elements: sections M_1, E_1 (modes) and E_2 (a low-pass),
# stable, a[0] = 1 each
SECTIONS_B = [0.0, 0.0155, 0.0150, 0.0, 0.0689, 0.0617, 0.0, 0.3935, 0.0]
SECTIONS_A = [1.0, -1.8779, 0.9084, 1.0, -1.6065, 0.7371, 1.0, -0.6065, 0.0]
# a Wiener model's filter before the plays: F_1 a low-pass, F_2 a mode (in series on v)
WIENER_B = [0.0, 0.3935, 0.0, 0.0, 0.0155, 0.0150]
WIENER_A = [1.0, -0.6065, 0.0, 1.0, -1.8779, 0.9084]
# the DiagnosedInverse's prefilter (a mode's approximate inverse at dt = 1 ms, lti.inverse_sos
# of 40 Hz, zeta 0.3, rounded) and a pass-through: sections b0 b1 b2 a0 a1 a2
INVERSE_SOS = [2.7875, -5.0285, 2.4023, 1.0, -1.1966, 0.358,
               1.0, 0.0, 0.0, 1.0, 0.0, 0.0]


def bad_weight(name: str):
    """A weight value the unit refuses (DiagnosedModel: any sign is valid, NaN is not)."""
    return "nan" if name in DIAG_UNITS else -1.0


def n_max(name: str) -> int:
    """The largest number of plays of the unit."""
    return 2 * NMAX if name in DIAG_UNITS else NMAX


def weight_message(name: str, i: int, value) -> str:
    """The logged reason for weight (creep: gain) i (1-based) of a bad value."""
    if name in DIAG_UNITS:
        return f"weight p[{i}] = {value} is not finite"
    if name == "CreepOperator":
        return f"gain c[{i}] = {value:g} is not positive"
    if name == "AsymmetricPI":
        return f"weight p[{i}] = {value:g} is negative"
    return f"weight p[{i}] = {value:g} is not positive"


def radius_message(name: str, i: int) -> str:
    """The logged reason for radius (creep: time constant) i (1-based) = nan."""
    if name == "CreepOperator":
        return f"time constant tau[{i}] = nan is not positive"
    return f"radius r[{i}] = nan is not finite"


@pytest.fixture(scope="module")
def fmu_dir(built_fmus) -> Path:
    return built_fmus


def fmu_path(fmu_dir: Path, name: str, fmi: str) -> Path:
    return fmu_dir / f"{name}{'_fmi3' if fmi == '3.0' else ''}.fmu"


# ---- action builders ----------------------------------------------------------------------

def set_array(fmi3: bool, base: int, values, pad: float) -> list:
    """Actions setting the array with reference ``base`` (FMI 2 element-wise, FMI 3 whole)."""
    values = [x if isinstance(x, str) else float(x) for x in values]  # "nan": JSON-safe
    if fmi3:
        return [["set_real", base, *values, *[pad] * (NMAX - len(values))]]
    return [["set_real", base + i, x] for i, x in enumerate(values)]


def init(name: str, fmi3: bool, *, n=3, p=None, r=None, Ts=TS, t0=0.0, extra=()) -> list:
    """The actions of a full initialisation (the last is exit_init)."""
    if p is None:
        p = CREEP_GAINS if name == "CreepOperator" else P
    if r is None:
        r = TAU if name == "CreepOperator" else R
    acts = [["enter_init", t0]] if fmi3 else [["setup", t0], ["enter_init"]]
    acts += [["set_int", VR["n"], n], ["set_real", VR["Ts"], Ts]]
    acts += set_array(fmi3, VR["p"], p, 1.0)
    acts += set_array(fmi3, VR["r"], r, r[-1] if len(r) else 0.0)
    if name == "RadiusEstimator":
        acts += [["set_real", VR["gain"], 5.0]]
    acts += list(extra)
    return acts + [["exit_init"]]


def inputs(name: str, fmi3: bool, v: float) -> list:
    acts = [["set_real", VR["in1"], v]]
    if name == "RadiusEstimator":
        acts.append(["set_real", VR["in2"], 0.8 * v])
    if name == "InversePI":
        acts += set_array(fmi3, VR["r_hat"], R, R[-1])
    return acts


def expect(actions: list, status: int = OK, message: str | None = None) -> list:
    """(action, expected status, expected log substring) triples."""
    return [(a, status, message) for a in actions]


def scenarios(name: str, fmi3: bool) -> dict[str, list]:
    """Every crash/hang case of issue 14 as (action, status, message) lists."""
    ok_init = expect(init(name, fmi3))
    step = expect(inputs(name, fmi3, 0.7) + [["step_next", TS]])
    nan, inf = "nan", "inf"
    state = ok_init + step + expect([["get_state", 0], ["serialize", 0, 0]])

    def bad_state(mutation, message):
        return [(["deserialize", 0, 1, mutation], ERROR, message)]

    edit = {"kind": "edit"}
    cases = {
        "corrupted serialized state": state + [
            *bad_state({**edit, "field": "n", "value": 10**6},
                       f"parameter n = 1000000 out of range: 1 <= n <= {n_max(name)}"),
            *bad_state({**edit, "field": "n", "value": -5}, "parameter n = -5 out of range"),
            *bad_state({**edit, "field": "r", "index": 0, "value": nan},
                       radius_message(name, 1)),
            *bad_state({**edit, "field": "p", "index": 2, "value": bad_weight(name)},
                       weight_message(name, 3, bad_weight(name))),
            *bad_state({**edit, "field": "Ts", "value": 1e-300}, "parameter Ts = 1e-300"),
            *bad_state({**edit, "field": "time", "value": nan}, "time nan must be finite"),
            *bad_state({**edit, "field": "k_next", "value": 2**62}, "sample counter"),
            *bad_state({**edit, "field": "mode", "value": 7}, "unknown mode 7"),
            *bad_state({**edit, "field": "out1", "value": inf}, "an output is not finite"),
            *bad_state({"kind": "random", "seed": 1}, "not a pimodel FMU state (bad magic)"),
            *bad_state({"kind": "flip", "bit": 8 * 5000}, "checksum mismatch"),
            *bad_state({"kind": "truncate", "length": 100}, "bytes, expected"),
            *bad_state({"kind": "extend", "extra": 3}, "bytes, expected"),
            (["deserialize", 0, 1], OK, None),  # the intact state is accepted
            *expect([["set_state", 1]] + inputs(name, fmi3, 0.1) + [["step_next", TS]]),
        ],
        "corrupted in-memory state": state + [
            (["corrupt_state", 0, {**edit, "field": "n", "value": 10**6}], OK, None),
            (["set_state", 0], ERROR, "parameter n = 1000000 out of range"),
            (["get_state", 0], OK, None),
            (["corrupt_state", 0, {**edit, "field": "r", "index": 1, "value": nan}], OK, None),
            (["set_state", 0], ERROR, radius_message(name, 2)),
            (["get_state", 0], OK, None),
            (["corrupt_state", 0, {"kind": "random", "seed": 2}], OK, None),
            (["set_state", 0], ERROR, "bad magic"),
            *step,  # the instance is unharmed
        ],
        "Ts = 1e-300": expect(init(name, fmi3, Ts=1e-300)[:-1]) + [
            (["exit_init"], ERROR, "parameter Ts = 1e-300: the sample time must be > 0")],
        "too many samples per doStep": ok_init + expect(inputs(name, fmi3, 0.3)) + [
            (["step_next", 1e5], ERROR, "spans 100000000 samples of Ts = 0.001; at most "
                                        "10000000 per doStep"),
            (["step_next", TS], OK, None)],
        "start at 2^53 Ts": expect(init(name, fmi3, t0=2.0**53 * TS)[:-1]) + [
            (["exit_init"], ERROR, "beyond the sample counter's range")],
        "start at 1e20": expect(init(name, fmi3, t0=1e20)[:-1]) + [
            (["exit_init"], ERROR, "beyond the sample counter's range")],
        "t + h == t": expect(init(name, fmi3, Ts=1e3, t0=1e12) + inputs(name, fmi3, 0.2)) + [
            (["step_next", 1e-5], ERROR, "no progress: t + h == t"),
            (["step_next", 1e3], OK, None)],
        "t is not the FMU's time": ok_init + expect(inputs(name, fmi3, 0.5)) + [
            (["step", 2.0**53 * TS, TS], ERROR, "does not match the FMU's time"),
            (["step", 0.5, TS], ERROR, "communication point t = 0.5 does not match"),
            (["step", -TS, TS], ERROR, "communication point t = -0.001: must be finite"),
            (["step", nan, TS], ERROR, "must be finite and >= 0"),
            (["step_next", 0.0], ERROR, "step size h = 0: must be finite and > 0"),
            (["step_next", -TS], ERROR, "step size h = -0.001"),
            (["step_next", nan], ERROR, "step size h = nan"),
            (["step_next", inf], ERROR, "step size h = inf"),
            (["step_next", TS], OK, None)],
        "after terminate": ok_init + step + [
            (["terminate"], OK, None),
            (["step_next", TS], ERROR, "doStep is not allowed now: the FMU is terminated"),
            (["set_real", VR["in1"], 1.0], ERROR, "after terminate"),
            (["get_real", VR["out1"]], OK, None)],
        "non-finite or negative start time": [
            *([(["enter_init", nan], ERROR, "start time = nan: must be finite and >= 0"),
               (["enter_init", -1.0], ERROR, "start time = -1"),
               (["enter_init", inf], ERROR, "start time = inf")] if fmi3 else
              [(["setup", nan], ERROR, "start time = nan: must be finite and >= 0"),
               (["setup", -1.0], ERROR, "start time = -1"),
               (["setup", inf], ERROR, "start time = inf")]),
            *ok_init],
        "unknown value references": ok_init + [
            (["get_real", 99], ERROR, "no Real variable with value reference 99"),
            (["set_real", 99, 1.0], ERROR, "value reference 99"),
            (["get_int", 99], ERROR, "no Integer variable with value reference 99"),
            (["get_bool", 99], ERROR, "no Boolean variable with value reference 99"),
            (["get_real", VR["n"]], ERROR, "variable n (value reference 1) is not a Real"),
            (["get_real", VR["time"]], OK if fmi3 else ERROR,
             None if fmi3 else "value reference 9"),
            (["get_real", VR["p"] + (1 if fmi3 else NMAX)], ERROR,
             f"value reference {VR['p'] + (1 if fmi3 else NMAX)}"),
            *([(["get_real", VR["gain"]], ERROR, "value reference 4"),
               (["get_real", VR["r_hat"]], ERROR, "value reference 300")]
              if name == "PIHysteresis" else []),
            *([(["get_bool", VR["linear_play"]], ERROR, "value reference 5")]
              if name != "RadiusEstimator" else [])],
        "calls in the wrong state": [
            (["step_next", TS], ERROR, "doStep is not allowed now: the FMU is instantiated"),
            (["exit_init"], ERROR, "ExitInitializationMode is not allowed now"),
            *ok_init,
            (["set_real", VR["Ts"], 1.0], ERROR,
             "cannot set parameter Ts (value reference 0) after initialization"),
            (["set_int", VR["n"], 2], ERROR, "cannot set parameter n"),
            (["set_real", VR["out1"], 1.0], ERROR, "is an output and cannot be set"),
            *([(["set_real", VR["time"], 1.0], ERROR, "variable time (value reference 9) is "
                "the independent variable and cannot be set")] if fmi3 else []),
            (["enter_init", 0.0], ERROR, "EnterInitializationMode is not allowed now"),
            *step],
        "indexed parameter messages": expect(init(name, fmi3, p=[1.0, 0.5, bad_weight(name)])
                                             [:-1]) + [
            (["exit_init"], ERROR, weight_message(name, 3, bad_weight(name)))],
        "n = n_max + 1": expect(init(name, fmi3, n=n_max(name) + 1)[:-1]) + [
            (["exit_init"], ERROR, f"parameter n = {n_max(name) + 1} out of range: 1 <= n <= "
                                   f"{n_max(name)}")],
    }
    if name == "RadiusEstimator":
        cases["law out of range"] = expect(init(name, fmi3, extra=[
            ["set_int", VR["law"], 2]])[:-1]) + [
            (["exit_init"], ERROR, "parameter law = 2 out of range: 0 data"),
            (["set_int", VR["law"], 1], OK, None), (["exit_init"], OK, None),
            (["set_int", VR["health"], 1], ERROR, "variable health (value reference 15) is an "
                                                  "output and cannot be set"), *step]
    return cases


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_driver_reports_crashes_and_hangs(fmu_dir):
    """The harness itself: a segfault or a hang in the child fails with the run named."""
    fmu = fmu_path(fmu_dir, "PIHysteresis", "2.0")
    with pytest.raises(DriverFailure, match=r"crash: exit status -?\d+ after 1 of 2 runs"):
        run_job(fmu, [[["get_real", VR["out1"]]], [["_segfault"]]])
    with pytest.raises(DriverFailure, match=r"hang: no answer within 3 s; run 0"):
        run_job(fmu, [[["_sleep", 60]]], timeout=3)


@pytest.mark.parametrize(("name", "fmi"), CONFIGS, ids=IDS)
def test_issue_cases_give_logged_errors(fmu_dir, name, fmi):
    cases = scenarios(name, fmi == "3.0")
    results = run_job(fmu_path(fmu_dir, name, fmi), [[a for a, _, _ in c]
                                                     for c in cases.values()], timeout=120)
    for (case, steps), res in zip(cases.items(), results, strict=True):
        for (action, status, message), got in zip(steps, res, strict=True):
            if got["status"] == STATUS_SKIPPED:
                assert action[0] == "setup" and fmi == "3.0", (case, action)
                continue
            where = f"{case}: {action} gave status {got['status']}, log {got['log']}"
            assert got["status"] == status, where
            if status == ERROR:
                assert got["log"], where  # every error is logged
            if message is not None:
                assert any(message in line for line in got["log"]), where


@pytest.mark.parametrize(("name", "fmi"), CONFIGS, ids=IDS)
def test_state_round_trip_is_exact(fmu_dir, name, fmi):
    """get state, serialize, deserialize, set: the continuation equals the first run bit for
    bit (the estimator's state goes through its own checked get/set)."""
    fmi3 = fmi == "3.0"
    rng = random.Random(3)
    v = [2 * math.sin(0.05 * k) + 0.1 * rng.random() for k in range(120)]
    outs = [["get_real", VR["out1"]]]
    if name == "RadiusEstimator":
        outs.append(["get_real", VR["r_hat"] + (0 if fmi3 else 1), NMAX])
    def cont(xs):
        return [a for x in xs for a in inputs(name, fmi3, x) + [["step_next", TS]] + outs]
    run = (init(name, fmi3) + cont(v[:60]) + [["get_state", 0], ["serialize", 0, 0]]
           + cont(v[60:]) + [["deserialize", 0, 1], ["set_state", 1]] + cont(v[60:]))
    res = run_job(fmu_path(fmu_dir, name, fmi), [run])[0]
    assert all(r["status"] in (OK, STATUS_SKIPPED) for r in res), [r for r in res if r["log"]]
    values = [r["value"] for r in res if r["call"] == "get_real"]
    half = len(cont(v[60:])) // len(cont(v[:1])) * len(outs)
    first, second = values[-2 * half:-half], values[-half:]
    assert first == second
    assert len({str(x) for x in first}) > 10  # the output moved


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_state_layout_mirror_matches_a_real_state(fmu_dir, fmi):
    """The driver's ctypes mirror of pim_unit points at the right bytes (else the field-edit
    corruptions would test the wrong fields)."""
    unit = FMUUnit(fmu_path(fmu_dir, "PIHysteresis", fmi), {
        "Ts": 2e-3, "n": 3, **{f"p[{i + 1}]": x for i, x in enumerate(P)},
        **{f"r[{i + 1}]": x for i, x in enumerate(R)}})
    unit.set({"v": 0.9})
    unit.step(2e-3)
    handle = unit.fmu.getFMUState()
    blob = unit.fmu.serializeFMUState(handle)
    unit.fmu.freeFMUState(handle)
    unit.close()
    header = StateHeader.from_buffer_copy(blob)
    assert header.magic == b"PIMSTATE" and header.nmax == NMAX == BUILD_NMAX
    assert header.fmi == int(fmi[0]) and header.model == 1
    assert len(blob) == ctypes.sizeof(StateHeader) + header.unit_size + 8
    assert header.unit_size > ctypes.sizeof(UnitPrefix)
    assert (read_field(blob, "n"), read_field(blob, "Ts"), read_field(blob, "r", 2)) == \
        (3, 2e-3, 0.6)
    assert (read_field(blob, "mode"), read_field(blob, "k_next"), read_field(blob, "time")) == \
        (3, 1, 2e-3)
    assert read_field(blob, "out1") == PIOperator(P, R).simulate([0.9])[0]


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_sixty_four_plays_match_operator(fmu_dir, fmi):
    rng = np.random.default_rng(5)
    p = rng.uniform(0.1, 1.0, NMAX)
    r = np.concatenate(([0.0], np.sort(rng.uniform(0, 2, NMAX - 1))))
    unit = FMUUnit(fmu_path(fmu_dir, "PIHysteresis", fmi), {
        "Ts": TS, "n": NMAX, **{f"p[{i + 1}]": x for i, x in enumerate(p)},
        **{f"r[{i + 1}]": x for i, x in enumerate(r)}})
    v = 3 * np.sin(np.linspace(0, 12, 400))
    y = []
    for x in v:
        unit.set({"v": x})
        unit.step(TS)
        y.append(unit.get(["y"])[0])
    unit.close()
    np.testing.assert_allclose(y, PIOperator(p, r).simulate(v), rtol=0, atol=1e-12)


# ---- random life-cycle fuzzer -------------------------------------------------------------

RUNS_PER_CONFIG = 170  # x 18 configurations = 3060 random runs (about 1 s per configuration)
BAD_FLOATS = ["nan", "inf", "-inf", -1.0, 0.0, 1e308, -1e308, 5e-324, 1e-300]


def _pick_float(rng: random.Random, good: float, p_bad: float = 0.1):
    return rng.choice(BAD_FLOATS) if rng.random() < p_bad else good


def random_run(name: str, fmi3: bool, rng: random.Random) -> list:
    """A random FMU life: mostly valid, with bad values, wrong calls and corrupted states."""
    hostile = rng.random() < 0.5  # else the set-up is valid and the hostility comes later
    n = rng.choice([1, 2, 3, 4, 8, 64, 64, 0, -5, 65, 10**6, 2**31 - 1, -(2**31)]) \
        if hostile and rng.random() < 0.3 else rng.choice([rng.randint(1, 12), 64])
    m = max(1, min(n, NMAX))
    p = [_pick_float(rng, rng.uniform(0.05, 2.0), 0.05 * hostile) for _ in range(m)]
    r = sorted(rng.uniform(0, 2) for _ in range(m))
    if (rng.random() < 0.7 or not hostile) and name != "CreepOperator":
        r[0] = 0.0
    if hostile and rng.random() < 0.1:
        r[rng.randrange(m)] = rng.choice(BAD_FLOATS)
    if hostile and rng.random() < 0.05:
        r.reverse()
    Ts = rng.choice([1e-3, 1e-3, 1e-3, 1e-4, 0.37, 1e-12, 1e-300, 0.0, -1e-3, "nan", "inf",
                     1e3, 5e-324]) if hostile and rng.random() < 0.3 else \
        rng.choice([1e-3, 1e-4, 0.37])
    t0 = rng.choice([0.0, 0.0, 0.0, 0.5, 7e-3, "nan", -1.0, "inf", 2.0**53 * 1e-3, 1e12, 1e20]) \
        if hostile else rng.choice([0.0, 0.0, 0.5, 7e-3, 3 * Ts])
    extra = []
    if name == "RadiusEstimator":
        extra += [["set_real", VR["gain"], _pick_float(rng, rng.uniform(0, 50), 0.1 * hostile)],
                  ["set_real", VR["guard"], _pick_float(rng, rng.uniform(0, 0.1), 0.1 * hostile)],
                  ["set_int", VR["slope_window"], rng.choice([0, 8, 8, 63, 64, -1, 10**9])
                   if hostile else rng.choice([0, 8, 63])],
                  ["set_int", VR["law"], rng.choice([0, 1, 2, -1, 10**9]) if hostile else
                   rng.choice([0, 1])],
                  ["set_bool", VR["linear_play"], rng.random() < 0.5]]
    if name == "InversePI":
        extra.append(["set_bool", VR["adaptive"], rng.random() < 0.5])
    if name in OPERATOR_UNITS:
        extra.append(["set_bool", VR["inverse"], rng.random() < 0.5])
    if name in ("GeneralizedPI", "AsymmetricPI") and rng.random() < 0.5:  # a tanh envelope
        extra += [["set_int", VR["in_kind"], rng.choice([1, 3, 7, -1]) if hostile else 1],
                  ["set_real", VR["in_c0"], _pick_float(rng, rng.uniform(1, 5), 0.1 * hostile)],
                  ["set_real", VR["in_c1"], _pick_float(rng, rng.uniform(0.1, 2), 0.1 * hostile)]]
    if name == "RateDependentPI":
        extra.append(["set_real", VR["rate_gain"], _pick_float(rng, rng.uniform(0, 1e-3),
                                                               0.1 * hostile)])
    if name == "DiagnosedModel":  # effect terms: delay, creep, LTI, asymmetry, rate, drift
        extra += [["set_real", VR["delay_samples"], rng.choice([0.0, 1.0, 2.5, 7.0]) if not
                   hostile else rng.choice([0.0, 3.5, -1.0, 5000.0, "nan", "inf"])],
                  ["set_int", VR["n_lags"], rng.choice([0, 1, 2]) if not hostile else
                   rng.choice([0, 2, -1, 65])],
                  *set_array(fmi3, VR["creep_gain"], [0.05, -0.02], 0.0),
                  *set_array(fmi3, VR["creep_tau"], [_pick_float(rng, 0.01, 0.1 * hostile), 0.3],
                             1.0),
                  ["set_real", VR["asymmetry_quadratic"], _pick_float(rng, 0.1, 0.1 * hostile)],
                  ["set_int", VR["drift_clock"], rng.choice([0, 1, 2]) if not hostile else
                   rng.choice([0, 3, -1])]]
        if rng.random() < 0.5:
            extra += [["set_int", VR["lti_order"], 2 if not hostile else rng.choice([2, 64])],
                      *set_array(fmi3, VR["lti_b"], [0.0, 0.15, 0.1], 0.0),
                      *set_array(fmi3, VR["lti_a"], [_pick_float(rng, 1.0, 0.1 * hostile),
                                                     -1.2, 0.45], 0.0)]
        if rng.random() < 0.5:  # the linear part's further elements
            a = list(SECTIONS_A)
            a[rng.choice([0, 3, 6])] = _pick_float(rng, 1.0, 0.1 * hostile)
            extra += [["set_int", VR["n_lti_elements"], rng.choice([1, 2]) if not hostile else
                       rng.choice([1, 2, 8, 9, -1, 2**31 - 1])],
                      *set_array(fmi3, VR["lti_gain"],
                                 [_pick_float(rng, 0.2, 0.1 * hostile), -0.1], 0.0),
                      *set_array(fmi3, VR["lti_element_b"], SECTIONS_B, 0.0),
                      *set_array(fmi3, VR["lti_element_a"], a, 0.0)]
        if rng.random() < 0.5:  # a filter before the plays (Wiener)
            a = list(WIENER_A)
            i = rng.choice([0, 1, 3])
            a[i] = _pick_float(rng, a[i], 0.1 * hostile)
            if hostile and rng.random() < 0.1:
                a[1] = -1.0  # F_1 with a pole at z = 1 (no rest state)
            extra += [["set_int", VR["n_wiener_elements"], rng.choice([1, 2]) if not hostile else
                       rng.choice([1, 2, 8, 9, -1, 2**31 - 1])],
                      *set_array(fmi3, VR["wiener_element_b"],
                                 [0.0, _pick_float(rng, 0.3935, 0.1 * hostile), 0.0,
                                  *WIENER_B[3:]], 0.0),
                      *set_array(fmi3, VR["wiener_element_a"], a, 0.0)]
        if rng.random() < 0.5:
            extra += [*set_array(fmi3, VR["rate_band_gain"], [0.1] * m, 0.0),
                      ["set_real", VR["rate_scale"], _pick_float(rng, 2.0, 0.1 * hostile)],
                      ["set_int", VR["rate_family"], rng.choice([0, 1]) if not hostile else
                       rng.choice([0, 1, 2, -1])],
                      ["set_real", VR["rate_tau"], _pick_float(rng, rng.choice([0.0, 3e-3]),
                                                               0.1 * hostile)]]
    if name == "DiagnosedInverse":  # the feedforward: creep, asymmetry, rate, prefilter
        extra += [["set_int", VR["latency"], rng.choice([0, 1, 3]) if not hostile else
                   rng.choice([0, 2, -1, 10**7])],
                  ["set_real", VR["delay_fraction"], rng.choice([0.0, 0.5]) if not hostile else
                   rng.choice([0.0, 0.5, 1.0, -0.1, "nan"])],
                  ["set_real", VR["reference_range"], _pick_float(rng, rng.uniform(0, 3),
                                                                  0.1 * hostile)],
                  ["set_int", VR["n_lags"], rng.choice([0, 1, 2]) if not hostile else
                   rng.choice([0, 2, -1, 65])],
                  *set_array(fmi3, VR["creep_gain"], [0.05, -0.02], 0.0),
                  *set_array(fmi3, VR["creep_tau"], [_pick_float(rng, 0.01, 0.1 * hostile), 0.3],
                             1.0),
                  ["set_real", VR["asymmetry_quadratic"], _pick_float(rng, 0.05, 0.1 * hostile)]]
        if rng.random() < 0.5:
            sos = list(INVERSE_SOS)
            i = rng.choice([0, 3, 4])
            sos[i] = _pick_float(rng, sos[i], 0.1 * hostile)
            extra += [["set_int", VR["n_sections"], rng.choice([1, 2]) if not hostile else
                       rng.choice([1, 2, 10, 11, -1])],
                      *set_array(fmi3, VR["section"], sos, 0.0)]
        if rng.random() < 0.5:  # a Wiener filter's inverse after the solve (latency >= 1)
            sos = list(INVERSE_SOS)
            i = rng.choice([0, 3, 5])
            sos[i] = _pick_float(rng, sos[i], 0.1 * hostile)
            extra += [["set_int", VR["n_post_sections"], rng.choice([1, 2]) if not hostile else
                       rng.choice([1, 2, 10, 11, -1])],
                      *set_array(fmi3, VR["post_section"], sos, 0.0)]
        if rng.random() < 0.5:
            extra += [*set_array(fmi3, VR["rate_band_gain"], [0.1] * m, 0.0),
                      ["set_real", VR["rate_scale"], _pick_float(rng, 2.0, 0.1 * hostile)],
                      ["set_int", VR["rate_family"], rng.choice([0, 1]) if not hostile else
                       rng.choice([0, 1, 2, -1])],
                      ["set_real", VR["rate_tau"], _pick_float(rng, rng.choice([0.0, 3e-3]),
                                                               0.1 * hostile)]]
    acts = init(name, fmi3, n=n, p=p, r=r, Ts=Ts, t0=t0, extra=extra)
    if hostile and rng.random() < 0.2:  # drop or repeat a life-cycle call
        acts.insert(rng.randrange(len(acts) + 1), rng.choice(
            [["exit_init"], ["enter_init", 0.0], ["terminate"], ["reset"], ["step_next", 1e-3]]))
    h_base = Ts if isinstance(Ts, float) and 1e-6 < Ts < 10 else 1e-3
    bad_vrs = [8, 9, 16, 99, 164, 264, 364, 400, 1664, 1700, 2**31, 2**32 - 1]
    for _ in range(rng.randint(5, 40)):
        k = rng.random()
        if k < 0.35:
            h = rng.choice([h_base, h_base, h_base * 2.5, h_base * 0.3, h_base * 10,
                            h_base * rng.uniform(0, 50)]) if rng.random() < 0.85 else \
                rng.choice([0.0, -h_base, "nan", "inf", 1e-300, h_base * 2e7, 1e30])
            acts.append(["step_next", h])
        elif k < 0.4:
            acts.append(["step", rng.choice([-1.0, "nan", "inf", 1e20, 2.0**53 * h_base,
                                             0.0, rng.uniform(0, 1)]), h_base])
        elif k < 0.6:
            v = _pick_float(rng, rng.gauss(0, 3))
            acts += [["set_real", VR["in1"], v]]
            if name == "RadiusEstimator":
                acts.append(["set_real", VR["in2"], _pick_float(rng, rng.gauss(0, 3))])
            if name == "InversePI":
                rh = sorted(rng.uniform(0, 2) for _ in range(m))
                rh[0] = 0.0 if rng.random() < 0.9 else rh[0]
                if rng.random() < 0.1:
                    rh[rng.randrange(m)] = rng.choice(BAD_FLOATS)
                acts += set_array(fmi3, VR["r_hat"], rh, rh[-1])
        elif k < 0.7:
            acts.append(["get_real", VR["out1"]])
        elif k < 0.75:
            vr = rng.choice(bad_vrs + list(VR.values()))
            acts.append([rng.choice(["get_real", "get_int", "get_bool"]), vr] if rng.random() <
                        0.5 else [rng.choice(["set_real", "set_int", "set_bool"]), vr,
                                  rng.choice([1, 0, 3])])
        elif k < 0.82:
            acts.append(["get_state", rng.randrange(2)])
        elif k < 0.86:
            acts.append(["set_state", rng.randrange(3)])
        elif k < 0.9:
            acts.append(["serialize", rng.randrange(2), 0])
        elif k < 0.96:
            acts.append(["deserialize", 0, 2, random_mutation(rng)])
            acts.append(["set_state", 2])
        elif k < 0.98:
            slot = rng.randrange(2)
            acts += [["corrupt_state", slot, random_mutation(rng, same_size=True)],
                     ["set_state", slot]]
        else:
            acts.append(rng.choice([["terminate"], ["reset"], ["exit_init"], ["setup", 0.0],
                                    ["enter_init", 0.0]]))
    return acts


EDITS = [("n", [0, -5, 65, 10**6, 2**31 - 1]), ("Ts", [0.0, -1.0, "nan", "inf", 1e-300]),
         ("r", ["nan", -1.0, "inf"]), ("p", [0.0, -1.0, "nan"]), ("time", ["nan", -1.0, "inf"]),
         ("k_next", [-1, 2**62]), ("mode", [0, 5, -1, 2**31 - 1]), ("out1", ["nan", "inf"])]
ALWAYS_CHECKED = {"time", "mode", "out1"}  # checked in every mode; the rest once initialized


def random_mutation(rng: random.Random, same_size: bool = False) -> dict:
    kinds = ["flip", "random", "edit", "edit"] + ([] if same_size else ["truncate", "extend"])
    kind = rng.choice(kinds)
    spec: dict = {"kind": kind, "seed": rng.randrange(2**31)}
    if kind == "edit":
        field, values = rng.choice(EDITS)
        spec.update(field=field, value=rng.choice(values), index=rng.randrange(NMAX))
    return spec


def must_reject(mutation: dict, blob_mode: int, name: str = "") -> bool:
    """Whether the FMU is bound to reject this corrupted state."""
    if mutation["kind"] != "edit":
        return True  # checksum, size or magic
    if name == "AsymmetricPI" and mutation["field"] == "p" and mutation["value"] == 0.0:
        return False  # a zero play weight is valid there
    if name in DIAG_UNITS and (mutation["field"], mutation["value"]) in (
            ("p", 0.0), ("p", -1.0), ("n", 65)):
        return False  # signed weights and up to 128 plays are valid there
    return mutation["field"] in ALWAYS_CHECKED or blob_mode >= 3


def check_run(actions: list, results: list, counts: dict, name: str = "") -> None:
    """Every status OK or Error (errors logged), outputs finite, corrupted states rejected."""
    for i, (action, res) in enumerate(zip(actions, results, strict=True)):
        where = f"{action} -> {res}"
        assert res["status"] in (OK, ERROR, STATUS_SKIPPED), where
        if res["status"] == ERROR:
            counts["errors"] += 1
            assert res["log"] and all(res["log"]), f"error without a logged reason: {where}"
        elif res["status"] == OK:
            counts["ok"] += 1
            if action[0] in ("step", "step_next"):
                counts["steps"] += 1
        corrupted = action[0] in ("deserialize", "corrupt_state") and res.get("changed")
        if corrupted and must_reject(action[-1], res["blob_mode"], name):
            # deserialize rejects it; a corrupted in-memory state is rejected by set_state
            got = res if action[0] == "deserialize" else results[i + 1]
            assert got["status"] == ERROR, f"corrupted state accepted: {where} / {got}"
            counts["rejected_states"] += 1
        if action[0] == "get_real" and action[1] == VR["out1"] and res["status"] == OK:
            assert all(not isinstance(x, str) for x in res["value"]), where  # nan -> "nan"


@pytest.mark.slow
@pytest.mark.parametrize(("name", "fmi"), CONFIGS, ids=IDS)
def test_random_lifecycle_fuzz(fmu_dir, name, fmi):
    """RUNS_PER_CONFIG random runs per unit and FMI version in one child process (timeout:
    a hang fails); 0 crashes, 0 hangs, every error logged, every corrupted state rejected."""
    rng = random.Random(f"{name}-{fmi}")
    runs = [random_run(name, fmi == "3.0", rng) for _ in range(RUNS_PER_CONFIG)]
    results = run_job(fmu_path(fmu_dir, name, fmi), runs, timeout=240)
    counts = {"ok": 0, "steps": 0, "errors": 0, "rejected_states": 0}
    for actions, res in zip(runs, results, strict=True):
        check_run(actions, res, counts, name)
    # the fuzzer reached both sides: successful steps and many clean rejections
    print(f"{name} FMI {fmi}: {len(runs)} runs, {counts}")
    assert counts["steps"] > 2 * RUNS_PER_CONFIG and counts["errors"] > RUNS_PER_CONFIG, counts
    assert counts["rejected_states"] > 20, counts


def _sanitizer_runtime() -> str | None:
    """LD_PRELOAD value for ASan + UBSan of the C compiler, or None when it has none."""
    import subprocess

    from pimodel.fmu.build import find_compiler

    try:
        cc = find_compiler()
    except RuntimeError:
        return None
    libs = []
    for name in ("libasan.so", "libubsan.so"):
        out = subprocess.run([cc, f"-print-file-name={name}"], capture_output=True, text=True)
        lib = Path(out.stdout.strip())
        if not lib.is_absolute() or not lib.exists():
            return None
        libs.append(str(lib))
    return ":".join(libs)


@pytest.mark.slow
def test_fuzz_under_address_sanitizer(tmp_path, monkeypatch):
    """The FMUs built with -fsanitize=address,undefined: the issue cases and 60 random runs
    per unit and FMI version find no invalid memory access and no undefined behaviour (a
    finding aborts the child, which fails the test)."""
    import os

    from pimodel.fmu import build as fmu_build

    preload = _sanitizer_runtime()
    if preload is None:
        pytest.skip("the C compiler has no AddressSanitizer/UBSan runtime")
    flags = [f for f in fmu_build.CFLAGS if f != "-O2"]
    monkeypatch.setattr(fmu_build, "CFLAGS", flags + [
        "-O1", "-g", "-fno-omit-frame-pointer", "-fsanitize=address,undefined",
        "-fno-sanitize-recover=undefined"])
    build_fmus(tmp_path, fmi_version="2.0")
    build_fmus(tmp_path, fmi_version="3.0")
    env = {**os.environ, "LD_PRELOAD": preload, "ASAN_OPTIONS": "detect_leaks=0:abort_on_error=1",
           "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1"}
    for name, fmi in CONFIGS:
        rng = random.Random(f"asan-{name}-{fmi}")
        runs = [random_run(name, fmi == "3.0", rng) for _ in range(60)]
        runs += [[a for a, _, _ in case] for case in scenarios(name, fmi == "3.0").values()]
        counts = {"ok": 0, "steps": 0, "errors": 0, "rejected_states": 0}
        results = run_job(fmu_path(tmp_path, name, fmi), runs, timeout=300, env=env)
        for actions, res in zip(runs[:60], results[:60], strict=True):
            check_run(actions, res, counts, name)
        assert counts["steps"] > 60, (name, fmi, counts)
