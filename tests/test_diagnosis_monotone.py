"""The inverse feedforward of a diagnosed model that folds (signed weights with a partial sum
<= 0) goes through the nearest monotone model (:mod:`pimodel.diagnosis.monotone`): the
projection is monotone on every branch, close to the model in branch shape, the identity on a
monotone model, and the inverse's one-sample step is bounded by the reference's step over the
projected slope floor (no jumps). The shared real record's nominal fit is such a model."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.monotone import (
    FLOOR_SHARE,
    is_monotone,
    monotone_error,
    monotone_model,
    monotone_weights,
)
from pimodel.operators.pi import PIOperator


def _floor(weights) -> float:
    return FLOOR_SHARE * float(np.median(np.cumsum(weights)))


def _input(seed: int, n: int = 600) -> np.ndarray:
    """A random input with reversals at all amplitudes (minor loops inside major ones)."""
    rng = np.random.default_rng(seed)
    turns = rng.uniform(-1.0, 1.0, 12) * np.linspace(1.0, 0.3, 12)
    return np.interp(np.linspace(0, 11, n), np.arange(12), turns)


signed_models = st.integers(3, 30).flatmap(lambda n: st.tuples(
    st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n),
    st.lists(st.floats(0.01, 0.2), min_size=n - 1, max_size=n - 1),
    st.integers(0, 2**16)))


@given(signed_models)
def test_projection_is_monotone_on_every_branch(model):
    s_steps, gaps, seed = model
    S = 0.5 + np.asarray(s_steps)  # partial sums, some <= 0 (a fold), median > 0 mostly
    if not np.median(S) > 0:
        return
    w = np.diff(S, prepend=0.0)
    r = np.concatenate(([0.0], np.cumsum(gaps)))
    p = monotone_weights(w, r)
    assert is_monotone(p)
    if is_monotone(w):
        assert np.array_equal(p, w)
        return
    f = _floor(w)
    assert np.all(np.cumsum(p) >= f * (1 - 1e-9))
    assert np.isclose(np.sum(p), max(np.sum(w), f))  # branches longer than the span: kept
    # every sample's secant slope is a mix of partial sums, so on every branch the output
    # moves with the input at a slope of at least the floor
    v = 2 * r[-1] * _input(seed)
    y = PIOperator(p, r, signed_weights=True).simulate(v)
    dv, dy = np.diff(v), np.diff(y)
    moving = np.abs(dv) > 1e-12
    assert np.all(dy[moving] / dv[moving] >= f * (1 - 1e-6))
    # Abel summation: y' - y = sum_m (S'_m - S_m)(z_m - z_{m+1}), |z_m - z_{m+1}| <= r_{m+1} - r_m
    # (the last term (S'_n - S_n) z_n, |z_n| <= max |v|, when S_n is raised to the floor)
    y0 = DiagnosedModel(r, w, 0.0, 1.0).simulate(v)
    dS = np.cumsum(p - w)
    bound = np.sum(np.abs(dS[:-1]) * np.diff(r)) + abs(dS[-1]) * np.max(np.abs(v))
    assert np.max(np.abs(y - y0)) <= bound * (1 + 1e-9) + 1e-12


def test_projection_keeps_the_branch_curve():
    # a fold of area 0.2 x 0.4 on a unit slope, and a negative reversal slope
    r = np.linspace(0.0, 2.0, 11)
    S = np.ones(11)
    S[0], S[5] = -0.2, -1.0
    w = np.diff(S, prepend=0.0)
    p = monotone_weights(w, r)
    E = monotone_error(w, p, r)
    # the fold's depth (1 + floor) x 0.2 split between the sides of the L-infinity projection,
    # the start pinned at 0 (the reversal slope raised to the floor over its cell)
    assert E <= max(0.5 * (1.0 + _floor(w)) * 0.2, (0.2 + _floor(w)) * 0.2) + 1e-12
    # a major loop: the outputs differ by at most twice that plus one cell
    v = 2.0 * np.sin(np.linspace(0, 6 * np.pi, 900))
    dy = DiagnosedModel(r, p, 0.0, 1.0).simulate(v) - DiagnosedModel(r, w, 0.0, 1.0).simulate(v)
    cell = np.max(np.abs(np.cumsum(p - w)) * np.append(np.diff(r), 0.0))
    assert np.max(np.abs(dy[300:])) <= 2 * E + cell + 1e-12


def test_folding_model_inverse_has_no_jumps():
    """A PI with signed weights (partial sums dip below 0) folds back on its branches at a
    branch length of 1; its inverse follows the nearest monotone model: each step at most the
    reference's step over the floor slope, and exact for that model."""
    r = np.linspace(0.0, 1.0, 21)
    S = np.full(21, 0.8)
    S[0], S[10], S[11] = -0.1, -0.6, -0.3
    m = DiagnosedModel(r, np.diff(S, prepend=0.0), 0.1, dt=1e-3)
    assert not is_monotone(m.weights)
    t = np.arange(3000) * 1e-3
    y_d = 0.8 * np.sin(2 * np.pi * t) * (1 - 0.3 * t / t[-1])  # reversals shrink: minor loops
    v = m.inverse().simulate(y_d)
    steps = np.abs(np.diff(v))
    assert np.max(steps) <= np.max(np.abs(np.diff(y_d))) / _floor(m.weights) * (1 + 1e-9)
    assert np.max(np.abs(monotone_model(m).simulate(v) - y_d)) < 1e-9
    # the model itself cannot follow the reference continuously: it misses it where it folds
    assert np.max(np.abs(m.simulate(v) - y_d)) > 1e-3


@pytest.mark.parametrize("growth", [0.2, 1.0, 2.0])
def test_folding_scaled_rate_model_inverse_has_no_jumps(growth):
    """The rate's exact shape (plays whose radii all scale by one factor per sample) folds as
    the plain PI does; its inverse follows the nearest monotone weights, the rate kept, and is
    exact for that model. Its largest one-sample step, in reference steps over the floor
    slope: 1.2-4.4 (the radii move with the rate, so not at most 1 as without it); before, the
    folding weights were inverted as they are and the feedforward jumped 21-37 of them."""
    r = np.linspace(0.0, 1.0, 21)
    S = np.full(21, 0.8)
    S[0], S[10], S[11] = -0.1, -0.6, -0.3
    m = DiagnosedModel(r, np.diff(S, prepend=0.0), 0.1, dt=1e-3, effects=("rate",),
                       params={"rate_family": "scaled", "rate_gains": [1.0],
                               "rate_growth": growth, "rate_time_constant_s": 5e-3,
                               "rate_saturation": 2.0, "rate_scale": 2.0})
    mono = monotone_model(m)
    assert is_monotone(mono.weights) and mono.params == m.params
    t = np.arange(3000) * 1e-3
    y_d = 0.8 * np.sin(2 * np.pi * t) * (1 - 0.3 * t / t[-1])
    v = m.inverse().simulate(y_d)
    ref_step = np.max(np.abs(np.diff(y_d))) / _floor(m.weights)
    assert np.max(np.abs(np.diff(v))) <= 8 * ref_step
    assert np.max(np.abs(mono.simulate(v) - y_d)) < 1e-9
    assert np.max(np.abs(m.simulate(v) - y_d)) > 1e-3


def test_monotone_model_is_the_identity_on_monotone_models():
    m = DiagnosedModel([0.0, 0.5, 1.0], [1.0, -0.3, 0.2], 0.1, dt=1e-3)
    assert monotone_model(m) is m
    # with an effect a sample's slope is not a partial sum: such models are left alone
    fold = DiagnosedModel([0.0, 0.5, 1.0], [1.0, -1.5, 1.0], 0.1, dt=1e-3, effects=("creep",),
                          params={"creep_lag_gains": [0.05], "creep_time_constants_s": [0.1]})
    assert monotone_model(fold) is fold
    first_order = replace(fold, effects=("rate",), params={"rate_gains": [0.1],
                                                         "rate_family": "radius"})
    assert monotone_model(first_order) is first_order
    assert monotone_model(replace(fold, effects=("delay",))) is not fold
    v = np.sin(np.linspace(0, 12, 800))
    assert np.max(np.abs(m.inverse().simulate(m.simulate(v)) - v)) < 1e-9


def test_bad_input():
    with pytest.raises(ValueError, match="floor_share"):
        monotone_weights([-1.0, 2.0], [0.0, 1.0], floor_share=0.0)
    with pytest.raises(ValueError, match="weights"):
        monotone_weights([1.0, 2.0], [0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match="radii"):
        monotone_weights([-1.0, 2.0], [1.0, 0.0])
    with pytest.raises(ValueError, match="median partial sum"):
        monotone_weights([-1.0, 0.0, 0.0], [0.0, 1.0, 2.0])


@pytest.mark.slow
def test_real_record_nominal_inverse_is_jump_free(real_record_path):
    """The shared real record's nominal fit folds (fine-grid least squares); the twin's output
    (its augmented model, as in studies/augmented_feedforward.py) is inverted through the nominal
    model without jumps, and the projection stays near the model on the record."""
    from pimodel import load_record
    from pimodel.diagnosis import diagnose
    from pimodel.diagnosis.where import startup_length

    rec = load_record(real_record_path)
    k0 = int(np.argmax(np.abs(rec.v) > 1))
    mid = k0 + (len(rec) - k0) // 2
    train, validate = rec.slice(k0, mid), rec.slice(mid, None)
    rep = diagnose([train], [validate], initial_state="rest")  # plays from rest, as the check
    nom, twin = rep.model(augmented=False), rep.model()
    n = int(round(2.0 / float(validate.t[1] - validate.t[0])))
    t, v_ref = validate.t[:n], validate.v[:n]
    span = 2.0 * float(twin.radii[-1])
    y_d = twin.simulate(v_ref, t, input_range=span)
    v = nom.inverse().simulate(y_d)
    mono = monotone_model(nom)
    f = _floor(nom.weights) if mono is not nom else float(np.min(np.cumsum(nom.weights)))
    assert np.max(np.abs(np.diff(v))) <= np.max(np.abs(np.diff(y_d))) / f * (1 + 1e-9)
    assert np.max(np.abs(mono.simulate(v) - y_d)) < 1e-9
    if mono is not nom:  # on the validate half (major loops): within 2 E plus a cell
        E = monotone_error(nom.weights, mono.weights, nom.radii)
        dS = np.cumsum(mono.weights - nom.weights)
        cell = np.max(np.abs(dS[:-1]) * np.diff(nom.radii))
        start = startup_length(validate.v)
        dy = mono.simulate(validate.v) - nom.simulate(validate.v)
        assert np.max(np.abs(dy[start:])) <= 2 * E + cell + 1e-9
