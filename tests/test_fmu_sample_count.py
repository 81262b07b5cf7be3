"""The number of samples a doStep processes (fmu/src/fmi/pim_unit.h): the fast count through
the reciprocal 1/Ts (unit_end_sample) gives the sampling rule's count exactly, also for step
ends in the bands around its tolerances and beyond 2^32 samples, where it falls back to the
division.

The rule, in double precision as the C code: a step ending at t_end processes the samples up
to ``ceil(x - min(1e-9 + x^2 eps, 1e-3))`` with ``x = t_end / Ts``.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from pimodel.fmu import build_fmus
from pimodel.operators import PIOperator

sys.path.insert(0, str(Path(__file__).parent))

from fmu_driver import edit_field, read_field  # noqa: E402  (the state layout's mirror)

EPS = 2.220446049250313e-16
P = np.array([0.6, 0.3, 0.2])
R = np.array([0.0, 0.25, 0.7])
# offsets of a step's end from a sample instant, in samples: on the grid, within and across
# half the smallest tolerance (1e-9), within and across the largest (1e-3), and far from both
OFFSETS = [0.0, 1e-12, -1e-12, 3e-10, -3e-10, 4.9e-10, 5.1e-10, -5.1e-10, 9e-10, 1.1e-9,
           -1.1e-9, 1e-6, 9.9e-4, 1.0e-3, 1.009e-3, 1.011e-3, -1.011e-3, 0.25, 0.5, 0.999999]
# and offsets of the rule's tolerance at the step's end times these factors, just inside and
# outside it (beyond the fast count's margin, a relative 1e-6, and the resolution of t / Ts)
TOL_FACTORS = [0.999, 0.99999, 1.00001, 1.001]
# offsets of a one-sample step's end across the edges of doStep's one-sample fast path
# (unit_one_sample: ends 3.906e-3 .. 1 + 4e-10 samples after the step's sample instant), and
# across the edge of the window it must stay within (1.02e-3)
WINDOW_OFFSETS = [-0.996095, -0.9960937, -0.99609, 3.9e-10, 4e-10, 4.1e-10, -0.5, 0.0,
                  -0.998985, -0.99898, -0.998975]


def tolerance(x: float) -> float:
    """The sampling rule's tolerance at sample x (unit_sample_tol)."""
    return min(1e-9 + x * x * EPS, 1e-3)


def end_sample(t_end: float, ts: float) -> int:
    """The sampling rule of pim_unit.h (unit_first_sample) in Python's doubles."""
    x = t_end / ts
    return math.ceil(x - tolerance(x))


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    (path,) = build_fmus(tmp_path_factory.mktemp("sample_count"), ["PIHysteresis"])
    return path


def run(fmu, ts: float, t0: float, seed: int, offsets: list[float] = OFFSETS,
        tol_factors: list[float] = TOL_FACTORS, most: int = 3) -> tuple[list, list, list, list]:
    """Steps of 1 to `most` samples whose ends sit at `offsets` samples or `tol_factors`
    tolerances (shuffled) from a sample instant, with a random input held over each step; per
    step the sample counter (from the serialized FMU state), the rule's count, the input and the
    output."""
    md = read_model_description(fmu)
    refs = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="count")
    slave.instantiate()
    rng = np.random.default_rng(seed)
    got, want, inputs, outputs = [], [], [], []
    try:
        slave.setupExperiment(startTime=t0)
        slave.enterInitializationMode()
        slave.setReal([refs["Ts"]], [ts])
        slave.setInteger([refs["n"]], [P.size])
        slave.setReal([refs[f"p[{i + 1}]"] for i in range(P.size)], list(P))
        slave.setReal([refs[f"r[{i + 1}]"] for i in range(R.size)], list(R))
        slave.exitInitializationMode()
        t, k = t0, end_sample(t0, ts)
        ends = [(x, False) for x in offsets] + [(f, True) for f in tol_factors]
        for i in rng.permutation(len(ends) * 6):
            x, of_tolerance = ends[i % len(ends)]
            end = k + int(rng.integers(1, most + 1))  # k: the next sample
            h = (end + (x * tolerance(end) if of_tolerance else x)) * ts - t
            v = float(rng.uniform(-1.0, 1.0))
            slave.setReal([refs["v"]], [v])
            slave.doStep(t, h)
            t += h
            k = max(k, end_sample(t, ts))
            state = slave.getFMUstate()
            blob = slave.serializeFMUstate(state)
            slave.freeFMUstate(state)
            got.append(read_field(blob, "k_next"))
            want.append(k)
            inputs.append(v)
            outputs.append(slave.getReal([refs["y"]])[0])
        slave.terminate()
    finally:
        slave.freeInstance()
    return got, want, inputs, outputs


@pytest.mark.parametrize("ts", [1e-4, 1 / 3000], ids=["1e-4 s", "1/3 ms"])
@pytest.mark.parametrize("t0", [0.0, 123.4567, 1e4, 5e5, 1e11],
                         ids=["t0=0", "x~1e6", "x~1e8 (tolerance 1e-3)", "x>2^32", "x~1e15"])
def test_sample_count_is_the_rule(fmu, ts, t0):
    got, want, _, _ = run(fmu, ts, t0, seed=int(t0) + 7)
    assert got == want
    assert set(np.diff(want)) >= {1, 2, 3}  # steps of different sample counts


@pytest.mark.parametrize("ts", [1e-4, 1 / 3000], ids=["1e-4 s", "1/3 ms"])
@pytest.mark.parametrize("t0", [0.0, 123.4567, 1e4], ids=["t0=0", "x~1e6", "x~1e8"])
def test_one_sample_steps_across_the_fast_path_edges_are_the_rule(fmu, ts, t0):
    """One-sample steps whose ends straddle the edges of doStep's one-sample fast path count
    as the rule (inside it the fast path, outside the general path), and their outputs are the
    PI operator's on the held inputs."""
    got, want, inputs, outputs = run(fmu, ts, t0, seed=11, offsets=WINDOW_OFFSETS,
                                     tol_factors=[], most=1)
    assert got == want
    assert set(np.diff(want)) == {1}
    k = end_sample(t0, ts)
    y = PIOperator(P, R).simulate(np.repeat(inputs, np.diff([k, *got])))
    np.testing.assert_allclose(outputs, y[np.array(got) - k - 1], rtol=0, atol=1e-12)


def test_outputs_follow_the_held_inputs_without_a_shifted_sample(fmu):
    """From t = 0: the output after each step is the PI operator's at the step's last sample,
    on the input sequence that holds each step's input over its samples."""
    got, _, inputs, outputs = run(fmu, 1e-4, 0.0, seed=3)
    seq, last, k = [], [], 0
    for k_end, v in zip(got, inputs, strict=True):
        seq += [v] * (k_end - k)
        k = k_end
        last.append(k_end - 1)
    want = PIOperator(P, R).simulate(np.array(seq))[last]
    np.testing.assert_allclose(outputs, want, rtol=0, atol=1e-12)
    assert np.ptp(want) > 0.3


def test_derived_sampling_fields_are_recomputed_from_a_restored_state(fmu):
    """1/Ts, the time tolerance and the fast paths' fields are derived, not read: a serialized
    state whose copies of them are edited (checksum recomputed) resumes bit for bit like the
    intact one, a t off by more than the rule's tolerance is still refused, and so is setting
    the output."""
    md = read_model_description(fmu)
    refs = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="derived")
    slave.instantiate()
    ts, v = 1e-3, np.sin(np.arange(40) / 3.0)
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setReal([refs["Ts"]], [ts])
        slave.exitInitializationMode()
        t = 0.0
        for x in v[:10]:
            slave.setReal([refs["v"]], [float(x)])
            slave.doStep(t, 2 * ts)
            t += 2 * ts
        state = slave.getFMUstate()
        blob = slave.serializeFMUstate(state)
        slave.freeFMUstate(state)
        assert read_field(blob, "inv_Ts") == 1 / ts and read_field(blob, "t_tol") == 1e-9
        assert read_field(blob, "fast_t_tol") == 1e-9
        assert read_field(blob, "fast_in_vr") == refs["v"]
        assert read_field(blob, "x_next") == read_field(blob, "k_next") + 0.5 + 2.0**-9
        edits = {"inv_Ts": 0.5, "t_tol": 1e3, "fast_t_tol": 1e3, "fast_in_vr": refs["y"],
                 "x_next": 7.0}
        changed = blob
        for field, value in edits.items():
            changed = edit_field(changed, field, value)
        runs = []
        for edited in (blob, changed):
            state = slave.deSerializeFMUstate(edited)
            slave.setFMUstate(state)
            slave.freeFMUstate(state)
            t, ys = read_field(edited, "time"), []
            for x in v[10:]:
                slave.setReal([refs["v"]], [float(x)])
                slave.doStep(t, 2 * ts)
                t += 2 * ts
                ys.append(slave.getReal([refs["y"]])[0])
            runs.append(ys)
            with pytest.raises(Exception, match="status 3"):  # fmi2Error
                slave.doStep(t + 1e-6, 2 * ts)  # beyond min(1e-9 max(1, t), 1e-3 Ts)
            with pytest.raises(Exception, match="status 3"):
                slave.setReal([refs["y"]], [1.0])  # an output
        assert runs[0] == runs[1] and np.ptp(runs[0]) > 0.1
        slave.terminate()
    finally:
        slave.freeInstance()

