"""The inverse of a model whose creep is counted from each record's start (``creep_start``
``"record"``, module creep: the rest start less ``sum_j g_j h0[0]``): exact round trip through
the NumPy reference (the C feedforward refuses it, so ``DiagnosedInverse`` falls back to the
reference), on the first sample too (``h0[0]`` itself there), the start kept in ``L0``."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.native_inverse import NativeInverse
from pimodel.diagnosis.reference_inverse import StaticInverse

sys.path.insert(0, str(Path(__file__).parent))
from test_inverse_native import PARAMS, RADII, WEIGHTS  # noqa: E402

DT = 1e-3

CASES = {"creep": ("creep",), "creep_asymmetry": ("creep", "asymmetry"),
         "dynamics_delay_creep": ("dynamics", "delay", "creep")}


def model(effects, plays_start: str = "zero", start: str = "record") -> DiagnosedModel:
    params = {"rate_scale": 8.0, "creep_start": start}
    for e in effects:
        params.update(PARAMS[e])
    return DiagnosedModel(RADII, WEIGHTS, 0.05, dt=DT, effects=tuple(effects),
                          reference_weights=[0.8, 0.35, 0.3, 0.2, 0.15, 0.1],
                          reference_offset=0.02, params=params, plays_start=plays_start)


def signal(n: int = 800) -> np.ndarray:
    """An input away from 0 on its first sample (h0[0] well away from 0), with minor loops."""
    t = np.arange(n) * DT
    return 0.7 + 0.6 * np.sin(2 * np.pi * 2.5 * t) + 0.2 * np.sin(2 * np.pi * 11.0 * t + 0.4)


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


def test_stream_keeps_the_start_and_the_c_feedforward_refuses():
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
    with pytest.raises(ValueError, match="creep_start 'record'"):
        NativeInverse(m.inverse())


def test_model_file_keeps_the_record_start(tmp_path):
    """A model file holds ``creep_start`` ``"record"`` (the schema takes it); the loaded model
    simulates as the saved one and exports ``creep_start`` 2 to the DiagnosedModel FMU."""
    from pimodel.diagnosis.native_model import fmu_parameters
    from pimodel.model_files import load_model, save_model

    m = model(("creep", "asymmetry"))
    save_model(m, tmp_path / "m.json")
    loaded = load_model(tmp_path / "m.json")
    v = signal(300)
    assert np.max(np.abs(loaded.simulate(v) - m.simulate(v))) < 1e-12
    assert fmu_parameters(m)[1]["creep_start"] == 2
    assert "creep_start" not in fmu_parameters(model(("creep",), start="rest"))[1]
