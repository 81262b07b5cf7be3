"""One radius law everywhere: from the issue's starts, the python-control estimator block and
the RadiusEstimator FMU (FMI 2 and FMI 3) give the C core's numbers (estimate_radii) to 1e-12,
under the default data-driven law, on a record long enough for the branch profile to be fitted
and to drive the estimate."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pimodel import PIOperator, estimate_radii
from pimodel.blocks import estimator_block
from pimodel.fmu import build_fmus
from pimodel.fmu.unit import FMUUnit
from pimodel.signals import sinusoid
from pimodel.simulation import simulate

P = np.array([0.3, 0.5, 0.8, 0.3, 0.2])
R = np.array([0.4, 1.0, 1.5, 2.0, 3.6])
TS = 1e-3
STARTS = {"below": [0.1, 0.2, 0.3, 0.4, 0.5], "zero": [0.0] * 5,
          "mixed": [0.2, 1.5, 1.6, 3.0, 3.2]}
SETTINGS = dict(gains=10.0, guard=0.0, threshold=0.0, slope_window=8)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("estimator_fmus")
    build_fmus(out, ["RadiusEstimator"], fmi_version="2.0")
    build_fmus(out, ["RadiusEstimator"], fmi_version="3.0")
    return out


@pytest.fixture(scope="module")
def record():
    t, v = sinusoid(30, 1, fs=1 / TS, duration=3)
    return t, v, PIOperator(P, R).simulate(v)


def core(record, start):
    t, v, y = record
    ref = estimate_radii(v, y, P, dt=TS, initial_radii=STARTS[start], **SETTINGS)
    assert ref.used.sum() > 1000  # the data law adapted (profile fitted, regimes found)
    assert np.max(np.abs(ref.radii - ref.history[0])) > 0.05  # and moved the estimate
    return ref


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
    params = {"Ts": TS, "n": P.size, "gain": SETTINGS["gains"], "guard": 0.0}
    if fmi == "2.0":
        path = fmus / "RadiusEstimator.fmu"
        params.update({f"p[{i + 1}]": float(x) for i, x in enumerate(P)})
        params.update({f"r[{i + 1}]": float(x) for i, x in enumerate(STARTS[start])})
    else:
        path = fmus / "RadiusEstimator_fmi3.fmu"
        params.update({"p": P, "r": STARTS[start]})
    unit = FMUUnit(path, params)
    names = [f"r_hat[{i + 1}]" for i in range(P.size)] + ["y_hat"]
    out = []
    for a, b in zip(v, y, strict=True):
        unit.set({"v": a, "y": b})
        unit.step(TS)
        out.append(unit.get(names))
    unit.close()
    out = np.array(out)
    np.testing.assert_allclose(out[:, :-1], np.vstack((ref.history[1:], ref.radii)), rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(out[:, -1], ref.model_output, rtol=0, atol=1e-12)
