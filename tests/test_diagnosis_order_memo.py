"""Issue 31's time goal: the refined dynamics' fit reuses the plain one's work
(:func:`pimodel.diagnosis.effects._order_memo`, ``select_order(memo=)``) with the same result."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from pimodel.diagnosis.effects import fit_effect, fit_nominal, make_segment
from pimodel.diagnosis.lti import element_coefficients, lti_columns, select_order
from pimodel.stages.pi_stage import excitation, random_truth


def _two_modes(seed: int):
    """A linear part with two modes drawn at random: fit, regressors and column callables of
    :func:`select_order`, counting the fits made."""
    rng = np.random.default_rng(seed)
    dt = 1e-4
    f1, f2 = rng.uniform(300, 500), rng.uniform(900, 1500)
    h = np.r_[0.0, np.cumsum(rng.normal(size=4000))] * 1e-2
    y = sum(g * lfilter(*element_coefficients(("mode", f, z), dt), h)
            for g, f, z in ((0.7, f1, 0.1), (0.3, f2, 0.08))) + rng.normal(0.0, 1e-4, h.size)
    calls = [0]

    def regressors(f, z, els):
        m = lfilter(*element_coefficients(("mode", f, z), dt), h)
        return [np.column_stack((m, lti_columns(h, f, z, els, dt)))], [y]

    def fit(f, z, els):
        calls[0] += 1
        A = regressors(f, z, els)[0][0]
        return float(np.sum((A @ np.linalg.lstsq(A, y, rcond=None)[0] - y) ** 2))

    def column(f, z, el):
        return [lti_columns(h, f, z, [el], dt)[:, 0]]

    return f1 * 1.05, fit, regressors, column, calls


@pytest.mark.parametrize("seed", [0, 1])
def test_select_order_memo_goes_on_where_the_plain_selection_stopped(seed):
    fn, fit, regressors, column, calls = _two_modes(seed)
    args = (fit, regressors, column, fn, 0.12, 4000.0, (0.005, 0.9))
    plain = select_order(*args)
    forced_fresh = select_order(*args, min_elements=len(plain[2]) + 1)
    memo: dict = {}
    assert select_order(*args, memo=memo) == plain  # a memo changes nothing of the result
    before = calls[0]
    forced = select_order(*args, min_elements=len(plain[2]) + 1, memo=memo)
    made = calls[0] - before
    calls[0] = 0
    select_order(*args, min_elements=len(plain[2]) + 1)
    assert forced == forced_fresh  # the same steps, to the bit
    assert made < calls[0]  # fewer fits: the plain selection's steps are not made again


def _segments(truth_effects, seed):
    truth = random_truth(truth_effects, seed)
    (tt, vt), (tv, vv) = excitation("train", seed=seed + 1), excitation("validate", seed=seed + 2)
    return truth.record(tt[:12000], vt[:12000], seed), truth.record(tv, vv, seed + 1)


def test_refined_dynamics_fit_equals_a_fresh_one():
    tr, _ = _segments(["dynamics"], 3)
    radii = np.linspace(0.0, np.ptp(tr.v) / 2, 12)

    def segs():
        return [make_segment(tr.t, tr.v, tr.y, radii)]

    memo_segs = segs()
    nominal = fit_nominal(memo_segs)
    plain = fit_effect("dynamics", memo_segs, (), {}, nominal)
    lti_min = len(plain.grid.get("lti", ())) + 1
    refined = fit_effect("dynamics", memo_segs, (), {"lti_min": lti_min}, nominal)
    fresh_segs = segs()
    fresh = fit_effect("dynamics", fresh_segs, (), {"lti_min": lti_min}, fit_nominal(fresh_segs))
    assert np.array_equal(refined.coef, fresh.coef)
    assert refined.grid == fresh.grid and refined.params == fresh.params
    refined.params["changed"] = True  # each call's model its own
    again = fit_effect("dynamics", memo_segs, (), {"lti_min": lti_min}, nominal)
    assert "changed" not in again.params and np.array_equal(again.coef, fresh.coef)
