"""The whole-record stages before the choice hold a few columns of the record (issue 31): the
nominal's errors, where the validate residual lies (pimodel.diagnosis.where), the noise floor
(pimodel.diagnosis.noise), the nominal's parameters and a record's checks of its clock each
peak at a few columns of the record's length (traced memory on a 300,000-sample record, in
columns, with a margin), with the numbers of the whole-array formulas they replace, to the bit.
"""

import importlib
import sys
import tracemalloc
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from pimodel.diagnosis.effects import nominal_params
from pimodel.diagnosis.noise import measure_noise_floor
from pimodel.diagnosis.where import _region_masks, residual_breakdown
from pimodel.identification.branches import find_reversals
from pimodel.records import Record, sample_time
from pimodel.stages.pi_stage import random_truth

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from bench_diagnosis import long_record  # noqa: E402

dg = importlib.import_module("pimodel.diagnosis.diagnose")  # not the function it exports

N = 300_000


@pytest.fixture(scope="module")
def long_pair():
    truth = random_truth(["creep", "dynamics"], 0)
    tr, va = long_record("train", N, truth, 1), long_record("validate", N, truth, 100, 40.0)
    segs = dg._bare([tr, va], "rest")
    outputs = [r.y * 0.98 + 0.001 for r in (tr, va)]  # a model output near y
    return tr, va, segs, outputs


def _peak_columns(f) -> float:
    """Traced peak of ``f()`` above what was held before, in columns of N float64 samples."""
    tracemalloc.start()
    base = tracemalloc.get_traced_memory()[0]
    f()
    peak = tracemalloc.get_traced_memory()[1] - base
    tracemalloc.stop()
    return peak / (8 * N)


def test_where_peaks_at_a_few_columns(long_pair):
    _, _, segs, outputs = long_pair
    r = segs[1].y - outputs[1]
    # the FFT of the residual (its mean removed, the complex half spectrum, the power: about
    # 3 columns) and one region's mask with its temporaries at a time; before: every region's
    # mask and the per-sample distances at once (9.3 columns measured)
    assert _peak_columns(lambda: residual_breakdown(segs[1:], [r])) < 6.0


def test_noise_floor_peaks_at_a_few_columns(long_pair):
    _, _, segs, outputs = long_pair
    signals = [(s.v, s.y) for s in segs]
    # the repeated differences of two records and their concatenation, its medians in place;
    # before: index and count columns per period tried and the median's copies (6.4 measured)
    assert _peak_columns(lambda: measure_noise_floor(signals, outputs)) < 4.5


def test_errors_hold_one_column_of_residuals_per_record(long_pair):
    _, _, segs, outputs = long_pair
    assert _peak_columns(lambda: dg._errors(segs, outputs)) < 3.0  # before: 4.0 (2 records)
    r = np.concatenate([s.y - o for s, o in zip(segs, outputs, strict=True)])
    rng = float(np.ptp(np.concatenate([s.y for s in segs])))
    rms, mx = float(np.sqrt(np.mean(r**2))), float(np.max(np.abs(r)))
    assert dg._errors(segs, outputs) == {"rms": rms, "max": mx, "rms_percent": 100 * rms / rng,
                                         "max_percent": 100 * mx / rng, "range": rng}
    assert dg._bic(segs, outputs, 7) == float(r.size * np.log(np.mean(r**2)) + 7 * np.log(r.size))


def test_errors_of_masked_records_equal_the_concatenated_formula(long_pair):
    tr, va, _, outputs = long_pair
    segs = dg._bare([tr, va], "unknown")
    assert all(s.mask is not None and not s.mask.all() for s in segs)
    r = np.concatenate([(s.y - o)[s.used] for s, o in zip(segs, outputs, strict=True)])
    rng = float(np.ptp(np.concatenate([s.y[s.used] for s in segs])))
    assert dg._errors(segs, outputs)["rms"] == float(np.sqrt(np.mean(r**2)))
    assert dg._errors(segs, outputs)["max_percent"] == 100 * float(np.max(np.abs(r))) / rng


def test_nominal_params_peak_and_numbers(long_pair):
    _, _, segs, outputs = long_pair
    coef = np.array([0.5, 0.25, 0.1])
    assert _peak_columns(lambda: nominal_params(coef, outputs[:1], segs[:1])) < 2.5  # before 3.2
    got = nominal_params(coef, outputs, segs)
    h = np.concatenate(outputs)
    rate = np.concatenate([np.abs(np.diff(s.v)) / s.dt for s in segs])
    moving = rate[rate > 1e-9 * float(np.ptp(rate))]
    assert got["center"] == float(np.mean(h))
    assert got["half_range"] == float(np.ptp(h)) / 2
    assert got["rate_scale"] == float(np.percentile(moving, 95))


def test_a_records_clock_checks_hold_no_column(long_pair):
    tr = long_pair[0]
    # the time column's checks a block at a time; before: the intervals, their deviations
    # and the rounded clock as columns (3.0 columns measured for each)
    assert _peak_columns(lambda: sample_time(tr.t)) < 0.8
    assert _peak_columns(lambda: Record(tr.t, tr.v, tr.y)) < 2.0  # the intervals' median
    assert sample_time(tr.t) == 1e-4
    assert sample_time(np.arange(131_073) / 3000 + 1e9) == 1 / 3000


def _loop_masks(t, v):
    """The two masks the diagnosis built with a loop over the samples (the reference)."""
    rng = float(np.ptp(v)) or 1.0
    dv = np.diff(v, prepend=v[0])
    moving = np.abs(dv) > 1e-9 * rng
    since_rev = np.full(v.size, np.inf)
    last, rset = None, set(find_reversals(v, 0.01 * rng))
    for k in range(v.size):
        if k in rset:
            last = v[k]
        if last is not None:
            since_rev[k] = abs(v[k] - last)
    steps = np.flatnonzero(np.abs(dv) > 0.05 * rng)
    since_step = np.full(v.size, np.inf)
    for s in steps:
        end = steps[steps > s][0] if np.any(steps > s) else v.size
        since_step[s:end] = t[s:end] - t[s]
    return {"near a reversal (travel < 10 % of range)": since_rev < 0.1 * rng,
            "hold after a step (first 50 ms)": (~moving) & (since_step < 0.05),
            "hold after a step (after 50 ms)": (~moving) & (since_step >= 0.05)
            & np.isfinite(since_step)}


@pytest.mark.parametrize("kind", ["sine", "steps", "walk", "hold then ramp"])
def test_region_masks_equal_the_loops(kind):
    rng = np.random.default_rng(3)
    n = 70_001  # more than one block of the masks, not a whole number of them
    t = 5.0 + np.arange(n) * 1e-3
    v = {"sine": lambda: np.sin(np.linspace(0, 30, n)),
         "steps": lambda: np.repeat(rng.normal(size=n // 50 + 1), 50)[:n],
         "walk": lambda: np.cumsum(rng.normal(size=n)),
         "hold then ramp": lambda: np.r_[np.zeros(n // 2), np.linspace(0, 1, n - n // 2)]}[kind]()
    masks = dict(_region_masks(t, v, 1e3))
    for name, mask in _loop_masks(t, v).items():
        assert np.array_equal(masks[name], mask), name
    seg = SimpleNamespace(t=t, v=v, dt=1e-3)
    out = residual_breakdown([seg], [rng.normal(size=n)])
    assert abs(sum(b["energy_share"] for b in out["spectrum"]) - 1.0) < 1e-12
