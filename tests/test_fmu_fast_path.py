"""The per-sample fast paths of a PIHysteresis FMU (fmu/src/fmi/pim_unit.h: unit_one_sample,
unit_main_real) refuse what the general paths refuse, with the same logged reasons, once the
FMU has run long enough for them to be taken (the FMU's time beyond the time tolerance); the
steps they take give the PI operator's outputs. FMI 2 and FMI 3, every call in a child
process (tests/fmu_driver.py).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))

from fmu_driver import NMAX, run_job  # noqa: E402

from pimodel import PIOperator  # noqa: E402
from pimodel._native import pi_run  # noqa: E402
from pimodel.fmu import build_fmus  # noqa: E402
from pimodel.fmu.unit import FMUUnit  # noqa: E402

TS = 1e-3
OK, ERROR = 0, 3
VR = {"Ts": 0, "n": 1, "in1": 10, "out1": 11, "p": 100, "r": 200}


@pytest.fixture(scope="module")
def fmus(tmp_path_factory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("fast_path")
    return {fmi: build_fmus(out, ["PIHysteresis"], fmi_version=fmi)[0] for fmi in ("2.0", "3.0")}


def init(fmi3: bool, p: np.ndarray, r: np.ndarray) -> list:
    """Actions that initialise the FMU with weights p and radii r (FMI 3: whole arrays)."""
    start = [["enter_init", 0.0]] if fmi3 else [["setup", 0.0], ["enter_init"]]
    params = [["set_real", VR["Ts"], TS], ["set_int", VR["n"], p.size]]
    for base, values, pad in ((VR["p"], p, 1.0), (VR["r"], r, float(r[-1]))):
        if fmi3:
            params.append(["set_real", base, *map(float, values), *[pad] * (NMAX - values.size)])
        else:
            params += [["set_real", base + i, float(x)] for i, x in enumerate(values)]
    return start + params + [["exit_init"]]


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
def test_fast_paths_refuse_what_the_general_paths_refuse(fmus, fmi):
    rng = np.random.default_rng(5)
    n = 6
    p = rng.uniform(0.1, 1.0, n)
    r = np.concatenate([[0.0], np.sort(rng.uniform(0.05, 1.0, n - 1))])
    good = [float(x) for x in rng.uniform(-2.0, 2.0, 12)]  # the inputs of the steps taken

    def step(v: float) -> list:
        return [(["set_real", VR["in1"], v], OK, None), (["step_next", TS], OK, None),
                (["get_real", VR["out1"]], OK, None)]

    run = [(a, OK, None) for a in init(fmi == "3.0", p, r)]
    for v in good[:4]:  # the FMU's time is then beyond its tolerance: the fast paths apply
        run += step(v)
    refusals = [
        (["step", 0.0, TS], ERROR, "does not match the FMU's time"),
        (["step", "nan", TS], ERROR, "communication point t = nan: must be finite"),
        (["step", "inf", TS], ERROR, "communication point t = inf: must be finite"),
        (["step_next", "nan"], ERROR, "step size h = nan"),
        (["step_next", "inf"], ERROR, "step size h = inf"),
        (["step_next", -TS], ERROR, "step size h = -0.001"),
        (["step_next", 0.0], ERROR, "step size h = 0: must be finite and > 0"),
        (["set_real", VR["out1"], 1.0], ERROR, "is an output and cannot be set"),
        (["set_real", VR["in1"], "nan"], OK, None),
        (["step_next", TS], ERROR, "input v = nan is not finite"),
        (["set_real", VR["in1"], 1e308], OK, None),  # beyond the safe bound: checked, overflows
        (["step_next", TS], ERROR, "the outputs overflowed"),
    ]
    for i, refusal in enumerate(refusals):  # each refused call between steps that are taken
        run.append(refusal)
        if refusal[1] == ERROR:
            run += step(good[4 + i % 8])
    run += [(["terminate"], OK, None),
            (["step_next", TS], ERROR, "doStep is not allowed now: the FMU is terminated"),
            (["set_real", VR["in1"], 0.5], ERROR, "cannot set input v (value reference 10) "
                                                 "after terminate"),
            (["reset"], OK, None),
            (["set_real", VR["in1"], 0.5], OK, None),
            (["step_next", TS], ERROR, "doStep is not allowed now: the FMU is instantiated")]
    (results,) = run_job(fmus[fmi], [[a for a, _, _ in run]], timeout=120)
    ys = []
    for (action, status, message), got in zip(run, results, strict=True):
        where = f"{action} gave status {got['status']}, log {got['log']}"
        assert got["status"] == status, where
        if message is not None:
            assert any(message in m for m in got["log"]), where
        elif status == OK:
            assert got["log"] == [], where
        if action[0] == "get_real" and status == OK:
            ys.append(got["value"][0])
    # the inputs held by the steps taken: the last one set before each successful step
    held, last = [], None
    for (action, _, _), got in zip(run, results, strict=True):
        if action[0] == "set_real" and action[1] == VR["in1"] and got["status"] == OK:
            last = float(action[2])
        if action[0] == "step_next" and got["status"] == OK:
            held.append(last)
    assert len(held) == len(ys) >= 12
    want = PIOperator(p, r).simulate(np.array(held))
    np.testing.assert_allclose(ys, want, rtol=0, atol=1e-12)
    assert np.ptp(want) > 0.5


def test_straight_play_code_is_the_cores_loop_to_the_last_bit(fmus):
    """The FMU runs its plays as straight code for each n <= 16 (pim_pi_step_small) and the
    loop beyond; both equal the core's loop (pim_pi_run, as Python runs it) bit for bit, signed
    zeros included, on inputs and radii on a coarse grid so that plays tie with v +- r."""
    rng = np.random.default_rng(29)
    for n in range(1, 19):
        p = rng.uniform(0.1, 1.0, n)
        r = np.concatenate([[0.0], np.sort(rng.integers(0, 8, n - 1) * 0.25)])
        v = rng.integers(-8, 9, 40) * 0.25
        start = {"Ts": TS, "n": n, **{f"p[{i + 1}]": float(x) for i, x in enumerate(p)},
                 **{f"r[{i + 1}]": float(x) for i, x in enumerate(r)}}
        unit = FMUUnit(fmus["2.0"], start)
        try:
            ys = []
            for x in v:
                unit.set({"v": float(x)})
                unit.step(TS)
                ys.append(unit.get(["y"])[0])
        finally:
            unit.close()
        want, _ = pi_run(p, r, np.zeros(n), v)
        assert np.array_equal(np.array(ys).view(np.int64), want.view(np.int64)), n
        assert np.ptp(want) > 0.5
