"""An FMU estimator block and native blocks in one python-control interconnection, connected by
signal name (``r_hat[1]`` ... on both sides)."""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest
from fmpy import read_model_description

from pimodel import PIOperator
from pimodel.blocks import (
    adaptive_compensator_block,
    estimator_block,
    initial_state,
    pi_block,
    radius_estimator,
)
from pimodel.fmu import build_fmus
from pimodel.fmu.block import fmu_block
from pimodel.loops.compiled import run_loop
from pimodel.signals import sinusoid

STAGE = PIOperator([6.3460, 1.6735, 1.1552, 0.4477], [0.0, 0.1945, 0.4826, 0.5707])
DT = 1e-3
R0 = [0.0, 0.3, 0.4, 0.8]


@pytest.fixture(scope="module")
def estimator_fmu(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("fmus")
    build_fmus(out, ["RadiusEstimator"])
    return out / "RadiusEstimator.fmu"


def fmu_estimator(path):
    names = [f"r_hat[{i}]" for i in range(1, 5)]
    start = {"Ts": DT, "n": 4, "gain": 20.0,
             **{f"p[{i + 1}]": w for i, w in enumerate(STAGE.weights)},
             **{f"r[{i + 1}]": r for i, r in enumerate(R0)}}
    names_in_fmu = {v.name for v in read_model_description(str(path)).modelVariables}
    flag = "linear_play" if "linear_play" in names_in_fmu else "known_linear"  # before rename
    return fmu_block(path, DT, name="est", start={**start, flag: True}, outputs=names,
                     feedthrough=False)


def adaptive_loop(est):
    comp = adaptive_compensator_block(STAGE.weights, DT, name="comp", input="y_d", output="v")
    plant = pi_block(STAGE, DT, name="plant", input="v", output="y")
    return control.interconnect([comp, plant, est], inputs=["y_d"], outputs=["y", "v"],
                                check_unused=False)


def test_fmu_estimator_and_native_compensator_connect_by_name(estimator_fmu):
    est = fmu_estimator(estimator_fmu)
    assert est.output_labels == [f"r_hat[{i}]" for i in range(1, 5)]
    loop = adaptive_loop(est)
    comp = loop.syslist[0]
    assert comp.input_labels[1:] == est.output_labels  # one naming convention
    t, yd = sinusoid(8, 5, fs=1 / DT, duration=0.4)
    x0 = initial_state(loop)
    res = control.input_output_response(loop, t, yd, initial_state=x0)
    native = run_loop(yd, STAGE, DT, feedforward="adaptive",
                      estimator=radius_estimator(STAGE.weights, dt=DT, gains=20.0,
                                                 initial_radii=R0, linear_play=True))
    np.testing.assert_allclose(res.outputs[0], native.y, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.outputs[1], native.v, rtol=0, atol=1e-12)
    assert np.ptp(native.radii[:, 1]) > 1e-3  # the radii did adapt during the run
    # a second run from time 0 restarts the FMU: the same result
    again = control.input_output_response(loop, t, yd, initial_state=x0)
    np.testing.assert_allclose(again.outputs, res.outputs, rtol=0, atol=0)
    # the native estimator block drops in under the same names
    nat = estimator_block(STAGE.weights, DT, name="est", gains=20.0, initial_radii=R0,
                          linear_play=True)
    swapped = adaptive_loop(nat)
    res2 = control.input_output_response(swapped, t, yd, initial_state=initial_state(swapped))
    np.testing.assert_allclose(res2.outputs, res.outputs, rtol=0, atol=1e-12)


def test_fmu_block_out_of_sequence_is_an_error(estimator_fmu):
    est = fmu_estimator(estimator_fmu)
    with pytest.raises(ValueError, match="only runs forward from time 0"):
        est.dynamics(0.5, [0.5], [0.0, 0.0])
