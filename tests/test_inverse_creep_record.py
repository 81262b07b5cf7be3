"""The inverse of a model whose creep is counted from each record's start (``creep_start``
``"record"``, module creep: the rest start less ``sum_j g_j h0[0]``): exact round trip through
the NumPy reference and the C feedforward (``pim_diag_inverse.c``, ``lag_record``), on the first
sample too (``h0[0]`` itself there), the start kept in ``L0``. The C stream equals the NumPy
stream (``_InverseStream``, output and whole state) to 1e-9 on several input shapes and two
sample rates, with and without asymmetry and a rate effect; the DiagnosedInverse FMU
(``creep_start = 2``) equals them; ``diagnose --export`` builds it."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import control
import numpy as np
import pytest

import pimodel.diagnosis.model as model_module
from pimodel.blocks import initial_state
from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.native_inverse import NativeInverse
from pimodel.diagnosis.reference_inverse import StaticInverse, _InverseStream

sys.path.insert(0, str(Path(__file__).parent))
from test_inverse_native import (  # noqa: E402
    PARAMS,
    RADII,
    WEIGHTS,
    python_stream,
    single_roots,  # noqa: F401  (the fixture)
)

DT = 1e-3

CASES = {"creep": ("creep",), "creep_asymmetry": ("creep", "asymmetry"),
         "dynamics_delay_creep": ("dynamics", "delay", "creep")}

# the record start beside a rate effect: the radius family (the fresh rate of a nested
# rate-free solve, whose state holds its own L0) and the scaled family (exact)
SCALED = {"rate_family": "scaled", "rate_gains": [1.0], "rate_time_constant_s": 5e-3,
          "rate_saturation": 1.0, "rate_growth": 0.4}
STREAM_CASES = {"creep": (("creep",), {}),
                "creep_asymmetry": (("creep", "asymmetry"), {}),
                "creep_rate": (("creep", "rate"), {}),
                "creep_asymmetry_rate_scaled": (("creep", "asymmetry", "rate"), SCALED),
                "dynamics_delay_creep_asymmetry": (("dynamics", "delay", "creep", "asymmetry"),
                                                   {})}


def model(effects, plays_start: str = "zero", start: str = "record", dt: float = DT,
          **extra) -> DiagnosedModel:
    params = {"rate_scale": 8.0, "creep_start": start}
    for e in effects:
        params.update(PARAMS[e])
    params.update(extra)
    return DiagnosedModel(RADII, WEIGHTS, 0.05, dt=dt, effects=tuple(effects),
                          reference_weights=[0.8, 0.35, 0.3, 0.2, 0.15, 0.1],
                          reference_offset=0.02, params=params, plays_start=plays_start)


def signal(n: int = 800) -> np.ndarray:
    """An input away from 0 on its first sample (h0[0] well away from 0), with minor loops."""
    t = np.arange(n) * DT
    return 0.7 + 0.6 * np.sin(2 * np.pi * 2.5 * t) + 0.2 * np.sin(2 * np.pi * 11.0 * t + 0.4)


# input shapes over the record's phase s = k / n in [0, 1) (so that both sample rates see the
# same shape), each starting away from 0
def _multisine(s):
    return 0.7 + 0.6 * np.sin(2 * np.pi * 2 * s) + 0.2 * np.sin(2 * np.pi * 9 * s + 0.4)


def _ramps_with_holds(s):
    knots = [0.0, 0.1, 0.3, 0.4, 0.6, 0.7, 0.85, 1.0]
    level = [0.4, 0.4, 1.3, 1.3, -0.3, -0.3, 0.8, 0.8]  # hold, ramp up, hold, down, ...
    return np.interp(s, knots, level)


def _chirp(s):
    return 0.5 + 0.7 * np.sin(2 * np.pi * (1.0 * s + 7.0 * s**2) + 0.3)  # 1 -> 15 cycles


SHAPES = {"multisine": _multisine, "ramps_with_holds": _ramps_with_holds, "chirp": _chirp}
RATES = {"1kHz": (1e-3, 600), "4kHz": (2.5e-4, 1200)}


@pytest.mark.parametrize("plays_start", ["zero", "v0"])
@pytest.mark.parametrize("case", list(CASES))
def test_round_trip_is_exact(case, plays_start):
    """The static part's inverse (the whole model's with the dynamics' approximate inverse
    runs too) returns the input to 1e-9; the rest start's inverse misses it."""
    m = model(CASES[case], plays_start)
    rest = model(CASES[case], plays_start, start="rest")
    v = signal()
    assert np.max(np.abs(m.simulate(v) - rest.simulate(v))) > 1e-2  # the constant is visible
    static = m.static_part()
    y = static.simulate(v)
    assert np.max(np.abs(static.inverse().simulate(y) - v)) < 1e-9
    assert np.max(np.abs(rest.static_part().inverse().simulate(y) - v)) > 1e-3
    assert np.all(np.isfinite(m.inverse().simulate(m.simulate(v))))


@pytest.mark.parametrize("rate", list(RATES))
@pytest.mark.parametrize("shape", list(SHAPES))
@pytest.mark.parametrize("case", list(STREAM_CASES))
def test_c_stream_equals_the_python_stream(case, shape, rate, single_roots):  # noqa: F811
    """``NativeInverse`` (C, ``lag_record``) equals ``_InverseStream`` (NumPy) to 1e-9, output
    and whole state (``L0`` after ``L[m]``, in the rate source's state too), on multisines,
    ramps with holds and chirps at 1 and 4 kHz; the record term is visible (the rest start's
    feedforward differs by more than 1e-3)."""
    effects, extra = STREAM_CASES[case]
    dt, n = RATES[rate]
    m = model(effects, dt=dt, **extra)
    v = SHAPES[shape](np.arange(n) / n)
    y_d = m.simulate(v)
    inv = m.inverse()
    rr = float(np.ptp(inv.prefilter(y_d)))
    native = NativeInverse(inv, reference_range=rr)
    labels = native.labels()
    assert labels == _InverseStream(m, None, rr).labels()
    assert labels[labels.index("solver.L[2]") + 1] == "solver.L0"
    want, x_want = python_stream(m, y_d, rr)
    x = native.initial_state()
    got = np.array([native.step(x, float(y)) for y in y_d])
    assert min(single_roots) > 1e-6  # no near-tie of the branch rule
    assert np.max(np.abs(got - want)) < 1e-9
    assert np.max(np.abs(x - x_want)) < 1e-9
    assert np.array_equal(native.run(y_d), got)
    rest = NativeInverse(model(effects, start="rest", dt=dt, **extra).inverse(),
                         reference_range=rr).run(y_d)
    assert np.max(np.abs(rest - got)) > 1e-3


@pytest.mark.parametrize("case", ["creep", "creep_asymmetry", "creep_asymmetry_rate_scaled"])
@pytest.mark.parametrize("shape", list(SHAPES))
def test_c_round_trip_is_exact(case, shape):
    """The C feedforward of the static part returns the input to 1e-9 (the model maps it back
    onto the reference), from the first sample on."""
    effects, extra = STREAM_CASES[case]
    static = model(effects, **extra).static_part()
    v = SHAPES[shape](np.arange(600) / 600)
    y = static.simulate(v)
    native = NativeInverse(static.inverse(), reference_range=float(np.ptp(y)))
    got = native.run(y)
    assert np.max(np.abs(got - v)) < 1e-9
    assert np.max(np.abs(static.simulate(got) - y)) < 1e-9


def test_stream_keeps_the_start_and_the_c_feedforward_takes_it(monkeypatch):
    """The NumPy stream and the C one keep ``h0[0]`` in ``L0``; ``DiagnosedInverse.simulate``
    solves on C (no fallback to the NumPy solver)."""
    m = model(("creep", "asymmetry"))
    solver = StaticInverse(m)
    assert solver.labels()[-1] == "L0"
    assert "L0" not in StaticInverse(replace(m, params={**m.params, "creep_start": "rest"})
                                     ).labels()
    v = signal(50)
    y = m.simulate(v)
    x = solver.initial_state()
    out = [solver.step(x, yk) for yk in y]
    h0_first = float(np.clip(0.0, v[0] - m.radii, v[0] + m.radii) @ m.reference_weights
                     + m.reference_offset)
    assert abs(x[solver.labels().index("L0")] - h0_first) < 1e-12
    assert np.max(np.abs(np.array(out) - v)) < 1e-9
    native = NativeInverse(m.inverse())
    assert native.labels()[-1] == "solver.L0"
    xc = native.initial_state()
    got = [native.step(xc, float(yk)) for yk in y]
    assert abs(xc[-1] - h0_first) < 1e-12
    assert np.max(np.abs(np.array(got) - v)) < 1e-9

    def no_fallback(*args, **kwargs):
        raise AssertionError("the NumPy solver ran: the C feedforward refused the model")

    monkeypatch.setattr(model_module, "solve_static", no_fallback)
    assert np.max(np.abs(m.inverse().simulate(y) - v)) < 1e-9


def test_block_then_model_block_tracks_as_the_batch():
    """``inverse.block()`` (C) into ``model.block()`` (C, record start too): the tracking error
    against the reference delayed by the latency equals the batch's to 1e-9."""
    m = model(("dynamics", "delay", "creep", "asymmetry"))
    inv = m.inverse()
    v = signal(700)
    y_d = m.simulate(np.concatenate((np.full(20, v[0]), v[:680])))  # at rest at its start
    v_batch = inv.simulate(y_d)
    e_batch = m.simulate(v_batch) - y_d
    ff = inv.block(reference_range=float(np.ptp(inv.prefilter(y_d))))
    loop = control.interconnect([ff, m.block()], inputs=["y_d"], outputs=["y", "v"])
    t = np.arange(y_d.size) * DT
    res = control.input_output_response(loop, t, y_d, initial_state=initial_state(loop))
    a = ff.latency
    assert a > 0
    e_loop = res.outputs[0][a:] - y_d[:y_d.size - a]
    assert np.max(np.abs(e_loop - e_batch[:y_d.size - a])) < 1e-9
    assert np.sqrt(np.mean(e_batch**2)) < 0.1 * np.ptp(y_d)  # it does track


@pytest.mark.parametrize("fmi", ["2.0", "3.0"])
@pytest.mark.parametrize("case", ["creep_asymmetry", "creep_rate",
                                  "dynamics_delay_creep_asymmetry"])
def test_inverse_fmu_equals_the_block(built_fmus, fmi, case):
    """The DiagnosedInverse unit takes ``creep_start = 2`` and equals the C block and the NumPy
    stream to 1e-9; with ``creep_start = 0`` (the rest start) it differs."""
    from test_inverse_fmu import run_inverse_unit, unit_path

    from pimodel.fmu.operators import unit_parameters

    effects, extra = STREAM_CASES[case]
    m = model(effects, **extra)
    y_d = m.simulate(signal(400))
    inv = m.inverse()
    name, params = unit_parameters(inv)
    assert name == "DiagnosedInverse" and params["creep_start"] == 2
    got = run_inverse_unit(unit_path(built_fmus, fmi), params, y_d, DT)
    blk = inv.block()
    t = np.arange(y_d.size) * DT
    block = control.input_output_response(blk, t, y_d, initial_state=initial_state(blk)).outputs
    want, _ = python_stream(m, y_d, None)
    assert np.max(np.abs(got - block)) < 1e-9
    assert np.max(np.abs(got - want)) < 1e-9
    rest = run_inverse_unit(unit_path(built_fmus, fmi), {**params, "creep_start": 0}, y_d, DT)
    assert np.max(np.abs(rest - got)) > 1e-3


def test_export_builds_the_inverse_fmu(tmp_path, capsys):
    """``diagnose --export`` (``_write_exports``) builds the inverse FMU of a record-start
    model beside its model FMU, without a "no inverse FMU" message."""
    from pimodel.cli.diagnose import _write_exports

    m = model(("creep", "asymmetry"))

    class Report:  # what _write_exports reads of a DiagnosisReport
        validate = ()

        def model(self, augmented=True):
            return m

    paths = _write_exports(Report(), tmp_path, fmu=True)
    names = {Path(p).name for p in paths}
    assert {"augmented_1_DiagnosedInverse.fmu", "nominal_1_DiagnosedInverse.fmu",
            "augmented_1_DiagnosedModel.fmu"} <= names
    assert "no inverse FMU" not in capsys.readouterr().out


def test_model_file_keeps_the_record_start(tmp_path):
    """A model file holds ``creep_start`` ``"record"`` (the schema takes it); the loaded model
    simulates as the saved one and exports ``creep_start`` 2 to the DiagnosedModel FMU and the
    DiagnosedInverse FMU."""
    from pimodel.diagnosis.native_inverse import inverse_fmu_parameters
    from pimodel.diagnosis.native_model import fmu_parameters
    from pimodel.model_files import load_model, save_model

    m = model(("creep", "asymmetry"))
    save_model(m, tmp_path / "m.json")
    loaded = load_model(tmp_path / "m.json")
    v = signal(300)
    assert np.max(np.abs(loaded.simulate(v) - m.simulate(v))) < 1e-12
    assert fmu_parameters(m)[1]["creep_start"] == 2
    assert inverse_fmu_parameters(loaded.inverse())[1]["creep_start"] == 2
    assert "creep_start" not in fmu_parameters(model(("creep",), start="rest"))[1]
    assert "creep_start" not in inverse_fmu_parameters(model(("creep",), start="rest")
                                                       .inverse())[1]


def test_c_check_takes_only_a_record_flag_of_0_or_1_without_a_common_rest():
    """``pim_dinv_check``: ``lag_record`` 0 or 1, and not beside ``lag_start`` (the record
    start has its lags at rest at ``h0[0]``)."""
    from pimodel import _native

    native = NativeInverse(model(("creep",)).inverse())
    d = native.params
    assert d.lag_record == 1 and _native.inverse_check(d) is None
    for bad in (2, -1):
        d.lag_record = bad
        assert "lag_record must be 0 or 1" in _native.inverse_check(d)
    common = NativeInverse(model(("creep",), start="common",
                                 creep_start_levels=[0.4, -0.3]).inverse())
    assert common.params.lag_record == 0 and _native.inverse_check(common.params) is None
    common.params.lag_record = 1
    assert "no lag_start" in _native.inverse_check(common.params)
