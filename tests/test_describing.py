"""The PI operator's describing function against the simulated first harmonic, its use in
python-control's describing-function tools, the Lemma 1 sector and static gain, the circle
criterion, the harmonic balance, and the residual hysteresis of a wrong inverse."""

from __future__ import annotations

import control
import numpy as np
import pytest

from pimodel.experiments.compensation import STAGE
from pimodel.loops.describing import (
    PIDescribingFunction,
    circle_criterion,
    harmonic_balance,
    play_describing_function,
    residual_hysteresis,
    sector,
    static_gain,
)
from pimodel.operators.pi import PIOperator

SIGNED = STAGE.inverse()  # signed weights, radii in um
NO_LINEAR_PLAY = PIOperator([0.7, 0.2, 0.1], [0.05, 0.3, 0.8])


def simulated_first_harmonic(op: PIOperator, A: float, per_period: int = 2**15,
                             periods: int = 3) -> complex:
    """First harmonic of the periodic steady state to ``A sin``, by quadrature over the last
    period (a sample on each peak, so the discrete plays equal the continuous ones)."""
    theta = 2 * np.pi * np.arange(per_period * periods) / per_period
    y = op.simulate(A * np.sin(theta))[-per_period:]
    th = theta[-per_period:]
    return 2.0 / per_period * (y @ np.sin(th) + 1j * (y @ np.cos(th))) / A


@pytest.mark.parametrize(("op", "amplitudes"), [
    # below r_2 (only the linear play moves), between radii, and above all radii
    (STAGE, [0.1, 0.3, 0.5, 0.9, 3.0]),
    # the exact inverse: signed weights; below its radii and beyond
    (SIGNED, [0.5, 1.5, 4.0, 8.0, 20.0]),
    # no linear play: N = 0 below r_1
    (NO_LINEAR_PLAY, [0.03, 0.2, 0.5, 1.0, 4.0]),
])
def test_describing_function_equals_simulated_first_harmonic(op, amplitudes):
    F = op.describing_function()
    for A in amplitudes:
        n_sim = simulated_first_harmonic(op, A)
        assert abs(F.describing_function(A) - n_sim) < 1e-6, A
    # vectorised call agrees with the scalar calls
    np.testing.assert_allclose(F.describing_function(np.array(amplitudes)),
                               [F.describing_function(A) for A in amplitudes], rtol=0,
                               atol=1e-15)


def test_amplitudes_below_radii_and_signed_weights_are_covered():
    """The parametrised amplitudes above include some below radii and the signed case."""
    assert np.any(SIGNED.weights < 0)
    assert STAGE.radii[1] > 0.1 and abs(STAGE.describing_function().describing_function(0.1)
                                        - STAGE.weights[0]) < 1e-15
    assert NO_LINEAR_PLAY.describing_function().describing_function(0.03) == 0
    # the inverse hysteresis is clockwise: phase lead, the forward one lags
    assert SIGNED.describing_function().describing_function(4.0).imag > 0
    assert STAGE.describing_function().describing_function(0.5).imag < 0


def test_play_is_python_controls_backlash():
    for r in (0.1, 0.5, 2.0):
        bl = control.friction_backlash_nonlinearity(2 * r)
        for A in (0.05, r, 1.01 * r, 1.5 * r, 3 * r, 40 * r):
            assert abs(play_describing_function(r, A) - bl.describing_function(A)) < 1e-14


def test_is_a_python_control_nonlinearity_and_streams():
    F = STAGE.describing_function()
    assert isinstance(F, control.DescribingFunctionNonlinearity) and not F._isstatic()
    assert isinstance(F, PIDescribingFunction)
    # python-control's own entry point uses the analytic method
    np.testing.assert_allclose(control.describing_function(F, [0.3, 1.0]),
                               F.describing_function([0.3, 1.0]), rtol=0, atol=1e-15)
    # __call__ streams the operator: python-control's numerical describing function agrees
    for A in (0.3, 1.0):
        F.reset()
        num = complex(np.ravel(control.describing_function(F, A, num_points=4000,
                                                          try_method=False))[0])
        assert abs(num - F.describing_function(A)) < 1e-4
    F.reset()
    v = np.sin(np.linspace(0, 9, 200))
    np.testing.assert_allclose([F(x) for x in v], STAGE.simulate(v), rtol=0, atol=1e-12)


def test_bad_input_is_refused():
    F = STAGE.describing_function()
    with pytest.raises(ValueError, match="A: expected finite amplitudes >= 0"):
        F.describing_function(-1.0)
    with pytest.raises(ValueError, match="radius: expected a finite number >= 0"):
        play_describing_function(-0.1, 1.0)
    with pytest.raises(TypeError, match="op: expected a PIOperator"):
        PIDescribingFunction([1.0, 2.0])
    with pytest.raises(ValueError, match="A: expected amplitudes > 0"):
        static_gain(STAGE, 0.0)
    with pytest.raises(ValueError, match="sector_bounds: expected 0 <= a < b"):
        circle_criterion(control.tf([1], [1, 1]), (2.0, 1.0))


@pytest.mark.parametrize("op", [STAGE, SIGNED, NO_LINEAR_PLAY])
def test_sector_bounds_every_increment(op):
    lo, hi = sector(op)
    assert (lo == 0.0) == (op.radii[0] > 0)
    rng = np.random.default_rng(1)
    scale = 3 * op.radii.max() + 1
    sweep = scale * np.concatenate([np.linspace(0, 1, 500), np.linspace(1, -1, 1000)])
    v = np.concatenate([sweep, sweep[-1] + np.cumsum(rng.normal(0, 0.05 * scale, 20_000))])
    y = op.simulate(v)
    dv, dy = np.diff(v), np.diff(y)
    k = dy[np.abs(dv) > 1e-6 * scale] / dv[np.abs(dv) > 1e-6 * scale]
    tol = 1e-7 * hi  # rounding of dy / dv (y ~ hi * scale, dv >= 1e-6 * scale)
    assert k.min() >= lo - tol and k.max() <= hi + tol
    # the bounds are reached (they are the extreme branch slopes, not loose bounds): the
    # sweep beyond every radius moves all plays, its reversal only the smallest
    assert k.min() < lo + tol and k.max() > hi - tol


@pytest.mark.parametrize("op", [STAGE, SIGNED, NO_LINEAR_PLAY])
def test_static_gain_is_the_loops_half_range_over_amplitude(op):
    for A in (0.2, 1.0, 5.0):
        per = 4000
        v = A * np.sin(2 * np.pi * np.arange(3 * per) / per) + 0.3  # a bias changes nothing
        y = op.simulate(v)[-per:]
        g = static_gain(op, A)
        assert abs(np.ptp(y) / 2 / A - g) < 1e-12
        lo, hi = sector(op)
        assert lo - 1e-12 <= g <= hi + 1e-12


def _mode_loop_continuous(ki: float) -> control.TransferFunction:
    wn = 2 * np.pi * 1000
    G = control.tf([wn**2], [1, 2 * 0.05 * wn, wn**2])  # the stage's 1 kHz mode
    C = control.tf([ki / (2 * np.pi * 3300), ki], [1, 0])  # integral-dominated PI
    return C * G


def test_python_control_describing_function_response_and_plot():
    """On the 1 kHz mode with a PI controller, python-control's harmonic balance finds the
    limit cycle harmonic_balance finds, and describing_function_plot draws the locus."""
    L = _mode_loop_continuous(ki=82.0)  # V/(um s): unstable at 9.62, stable at 6.35 um/V
    F = STAGE.describing_function()
    A = np.geomspace(0.05, 5.0, 200)
    omega = np.geomspace(2 * np.pi * 100, 2 * np.pi * 10_000, 4000)
    resp = control.describing_function_response(L, F, A, omega)
    ours = harmonic_balance(L, F, A, omega=omega)
    assert len(resp.intersections) == len(ours) == 1
    (a_pc, w_pc), lc = resp.intersections[0], ours[0]
    assert abs(a_pc / lc.amplitude - 1) < 1e-3 and abs(w_pc / lc.omega - 1) < 1e-3
    assert abs(1 + F.describing_function(lc.amplitude) * L(1j * lc.omega)) < 1e-8
    assert not lc.stable  # the gain grows with A here: a threshold, not an attractor
    np.testing.assert_allclose(resp.N_vals, -1 / F.describing_function(A))
    cplt = control.describing_function_plot(resp)
    np.testing.assert_allclose(cplt.lines[1][0].get_xdata(), resp.N_vals.real)
    import matplotlib.pyplot as plt

    plt.close(cplt.figure)


def test_harmonic_balance_matches_python_control_example():
    L = control.tf([8.0], [1.0, 2.0, 2.0, 1.0])
    F = control.saturation_nonlinearity(1)
    A = np.linspace(1, 4, 40)
    (a_pc, w_pc), = control.describing_function_response(L, F, A).intersections
    (lc,) = harmonic_balance(L, F, A)
    # exact: L(j sqrt 2) = -8/3, so N(A) = 3/8; python-control's refinement is coarser
    assert abs(lc.omega - np.sqrt(2)) < 1e-9
    assert abs(F.describing_function(lc.amplitude) - 3 / 8) < 1e-9
    assert abs(lc.amplitude - a_pc) < 1e-3 and abs(lc.omega - w_pc) < 1e-3
    assert lc.stable  # saturation: gain falls with A, the classic stable limit cycle


def test_harmonic_balance_discrete_uses_the_unit_circle():
    """A discrete loop is evaluated at exp(j w dt): the same prediction as its continuous
    original when sampled fast."""
    L = _mode_loop_continuous(ki=82.0)
    Ld = control.c2d(L, 1e-6, "tustin")
    F = STAGE.describing_function()
    A = np.geomspace(0.05, 5.0, 200)
    (c,) = harmonic_balance(L, F, A)
    (d,) = harmonic_balance(Ld, F, A)
    assert abs(d.amplitude / c.amplitude - 1) < 1e-3 and abs(d.omega / c.omega - 1) < 1e-3


def test_circle_criterion_with_the_lemma_sector():
    F = STAGE.describing_function()
    A = np.geomspace(0.01, 10.0, 300)
    low = _mode_loop_continuous(ki=30.0)
    high = _mode_loop_continuous(ki=82.0)
    ok = circle_criterion(low, sector(STAGE))
    assert ok.holds and ok.margin > 0 and ok.stable_at_a
    assert harmonic_balance(low, F, A) == []  # consistent: no predicted cycle
    bad = circle_criterion(high, sector(STAGE))
    assert not bad.holds and bad.margin < 0
    # with a sector that excludes the destabilising gains the high-gain loop passes
    assert circle_criterion(high, (1.0, 6.0)).holds


def test_residual_hysteresis_is_the_cascade():
    rng = np.random.default_rng(3)
    u = np.cumsum(rng.normal(0, 0.4, 30_000))
    for model in (PIOperator(STAGE.weights, 0.8 * STAGE.radii),
                  PIOperator(STAGE.weights * [1.0, 1.1, 0.9, 1.2],
                             STAGE.radii * [1.0, 1.1, 0.8, 1.05]),
                  PIOperator([6.0, 2.0, 1.5], [0.0, 0.3, 0.5])):
        R = residual_hysteresis(STAGE, model)
        cascade = STAGE.simulate(model.inverse().simulate(u))
        assert np.max(np.abs(R.simulate(u) - cascade)) < 1e-9 * np.ptp(cascade)
    # a perfect model leaves the identity
    ident = residual_hysteresis(STAGE, STAGE)
    assert ident.n == 1 and ident.weights[0] == pytest.approx(1.0, abs=1e-12)
    assert ident.radii[0] == 0.0


def test_residual_hysteresis_refuses():
    with pytest.raises(ValueError, match="model: not invertible"):
        residual_hysteresis(STAGE, NO_LINEAR_PLAY)
    with pytest.raises(ValueError, match="truth: residual_hysteresis needs the virgin"):
        residual_hysteresis(PIOperator([1.0], [0.0], initial_state=0.5), STAGE)
