"""The rate candidate's columns (``pimodel.diagnosis.rate``) against the rate-dependent PI they
linearise: play radii ``r_i (1 + a rho_f[k])`` and weights ``w_i (1 + c rho_f[k])`` with a
low-passed rate, simulated directly here; and the model the diagnosis keeps for ``rate``."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel.diagnosis.model import DiagnosedModel
from pimodel.diagnosis.rate import RateBasis, input_rate, rate_columns
from pimodel.operators.pi import PIOperator

DT = 1e-4
RADII = np.linspace(0.0, 0.5, 6)
WEIGHTS = np.array([2.0, 1.0, 0.8, 0.5, 0.3, 0.2])


def _input() -> np.ndarray:
    """Sines at two rates, a ramp that stops (a hold without a jump), a decaying minor loop."""
    t = np.arange(4000) * DT
    parts = [np.sin(2 * np.pi * 5 * t[:2000]), np.sin(2 * np.pi * 40 * t[:1000]),
             np.linspace(0.0, 0.8, 400), np.full(600, 0.8),
             0.8 - 0.6 * np.sin(2 * np.pi * 20 * t[:1500]) * np.linspace(1, 0.2, 1500)]
    return np.concatenate(parts)


def _rate_dependent(v, tau, radius_gain, scale):
    """Plays with radii ``r_i (1 + radius_gain rho_f[k])`` (the rate of the current interval,
    low-passed), from rest at 0: the play outputs, shape (N, n)."""
    rho = input_rate(v, DT, scale, tau)
    z = np.zeros(RADII.size)
    out = np.empty((v.size, RADII.size))
    for k, vk in enumerate(v):
        rk = RADII * (1 + radius_gain * rho[k])
        z = np.clip(z, vk - rk, vk + rk)
        out[k] = z
    return out


@pytest.mark.parametrize("tau", [0.0, 3e-3, 30e-3])
def test_radius_columns_are_the_first_order_change(tau):
    """Radii growing with the (filtered) rate: the output change is the radius columns times
    the gain to first order, also at a hold after a ramp, where the filtered rate decays and the
    plays in contact follow their shrinking radii."""
    v = _input()
    scale = float(np.percentile(np.abs(np.diff(v)) / DT, 95))
    Z = PIOperator(np.ones(RADII.size), RADII).play_outputs(v)
    R = rate_columns(Z, RADII, v, DT, scale, WEIGHTS, tau, "radius", RADII.size)
    for a in (1e-3, 1e-2):
        change = (_rate_dependent(v, tau, a, scale) - Z) @ WEIGHTS
        err = change - a * (R * WEIGHTS).sum(axis=1)
        # second order in a: the error falls 10-fold faster than the change
        assert np.sqrt(np.mean(err**2)) < 30 * a * np.sqrt(np.mean(change**2)), a
    hold = slice(3000 + 400 + 300, 3000 + 1000)  # the hold, 30 ms after the ramp stopped
    decay = np.exp(-30e-3 / tau) if tau > 0 else 0.0
    near = R[:, 1:3]  # the plays of radius 0.1 and 0.2, in contact at the end of the ramp
    assert np.max(np.abs(near[hold])) <= (decay + 1e-6) * np.max(np.abs(near[3300:3400]))


def test_weight_columns_scale_the_bands():
    """Weights growing with the rate, ``w_i (1 + c_b rho_f)``: the weight columns are exact."""
    v = _input()
    Z = PIOperator(np.ones(RADII.size), RADII).play_outputs(v)
    basis = RateBasis(Z, RADII, v, DT, 50.0, WEIGHTS, 3)
    rho = basis.rate(0.01)
    gains = np.array([0.3, -0.1, 0.2])
    per_play = np.repeat(gains, 2)
    exact = (Z * (WEIGHTS * (1 + per_play * rho[:, None]))).sum(axis=1) - Z @ WEIGHTS
    assert np.max(np.abs(basis.columns(0.01, "weight") @ gains - exact)) < 1e-12
    assert basis.columns(0.01, "weight") is basis.columns(0.01, "weight")  # memoised
    with pytest.raises(ValueError, match="family"):
        basis.columns(0.01, "width")


def test_step_counts_only_with_a_filter():
    v = np.r_[np.zeros(10), np.ones(10)]
    assert np.all(input_rate(v, DT, 1.0, 0.0) == 0)  # a sampled step: no rate
    assert input_rate(v, DT, 1.0, 1e-3)[10] > 0  # low-passed: the step moved the input


def test_bad_rate_parameters():
    v = np.linspace(0, 1, 5)
    with pytest.raises(ValueError, match="tau"):
        input_rate(v, DT, 1.0, -1e-3)
    with pytest.raises(ValueError, match="rate_scale"):
        input_rate(v, DT, 0.0, 0.0)
    m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=DT, effects=("rate",),
                       params={"rate_band_gains": [0.1], "rate_scale": 1.0})
    with pytest.raises(ValueError, match="rate_band_gains"):
        m.simulate(v)
    params = {"rate_gains": [0.1], "rate_family": "width", "rate_time_constant_s": 0.0,
              "rate_scale": 1.0}
    m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.0, dt=DT, effects=("rate",), params=params)
    with pytest.raises(ValueError, match="rate_family"):
        m.simulate(v)


@pytest.mark.parametrize("family,gains", [("radius", [0.05, 0.1]), ("weight", [0.02, 0.04])])
def test_model_inverse_of_rate_is_causal_and_close(family, gains):
    """The kept model's rate term (a family, filtered rate) and its causal inverse: ``v[k]`` of
    the inverse does not change when later references change, and the round trip stays close
    to the input (the fresh rate of each sample from the rate-free inverse)."""
    v = _input()[:3000]
    params = {"rate_gains": gains, "rate_family": family, "rate_time_constant_s": 3e-3,
              "rate_scale": 60.0}
    m = DiagnosedModel(RADII, WEIGHTS, 0.1, dt=DT, effects=("rate",), params=params)
    y = m.simulate(v)
    Z = PIOperator(np.ones(RADII.size), RADII).play_outputs(v)
    R = rate_columns(Z, RADII, v, DT, 60.0, WEIGHTS, 3e-3, family, 2)
    assert np.max(np.abs(y - (Z @ WEIGHTS + 0.1 + R @ gains))) < 1e-12
    assert not m.is_exactly_invertible
    inv = m.inverse()
    v_ff = inv.simulate(y)
    assert np.sqrt(np.mean((v_ff - v) ** 2)) < 0.01 * np.ptp(v)
    later = y.copy()
    later[2000:] += 0.3
    assert np.max(np.abs(inv.simulate(later)[:2000] - v_ff[:2000])) < 1e-12


def test_inverse_of_an_instantaneous_rate_beats_ignoring_it():
    """Radius family without a filter, gains as ``pimodel.stages.pi_stage``'s rate (linearised, the
    model ``A v[k] + B' (v[k] - v[k-1])`` has its zero at ``z = B' / (A + B') = 2``, outside the
    unit circle, so no exact causal inverse is stable): the inverse takes the fresh rate from the
    rate-free inverse and recovers the input about 3x better than that inverse (measured 0.005
    against 0.016 RMS; a rate held from sample k - 1 oscillated here, 0.031), and leaves about
    a quarter of the rate term in the round trip (held: 1.1 times it)."""
    v = _input()[:3000]
    scale, span = 60.0, float(np.ptp(v))
    gain = 2.0 * WEIGHTS.sum() * DT * scale / RADII.sum()  # B' = -2 A with every play pushed
    params = {"rate_gains": [gain, gain], "rate_family": "radius",
              "rate_time_constant_s": 0.0, "rate_scale": scale}
    m = DiagnosedModel(RADII, WEIGHTS, 0.1, dt=DT, effects=("rate",), params=params)
    rate_free = DiagnosedModel(RADII, WEIGHTS, 0.1, dt=DT)
    y = m.simulate(v, input_range=span)
    v_ff = m.inverse().simulate(y, input_range=span)
    v0 = rate_free.inverse().simulate(y)

    def rms(x):
        return float(np.sqrt(np.mean(x**2)))

    assert rms(v_ff - v) < 0.5 * rms(v0 - v)
    miss = m.simulate(v_ff, input_range=span) - y
    assert rms(miss) < 0.5 * rms(y - rate_free.simulate(v))


def test_a_screens_contacts_and_band_sums_are_found_once_for_every_fit(monkeypatch):
    """The last contacts and band sums of a screen's basis do not depend on the filter: a
    fit's ``release()`` keeps them for the next fit and other threads (found once, the
    columns the same to the bit), ``forget()`` drops them; a long record's are not kept."""
    import threading

    from pimodel.diagnosis import rate

    v = np.sin(np.linspace(0.0, 20.0, 3000)) + 0.1 * np.sin(np.linspace(0.0, 300.0, 3000))
    radii = np.linspace(0.0, 0.8, 8)
    calls = []
    found = RateBasis._contact_chunks
    monkeypatch.setattr(RateBasis, "_contact_chunks",
                        lambda self: calls.append(1) or found(self))
    basis = RateBasis(None, radii, v, 1e-3, 1.0, np.ones(8), at_rest=True)
    first = {(tau, fam): basis.columns(tau, fam).copy() for tau in (1e-3, 3e-2)
             for fam in ("radius", "weight")}
    basis.release()
    other = []
    t = threading.Thread(target=lambda: other.append(basis.columns(1e-3, "radius").copy()))
    t.start()
    t.join()
    again = {(tau, fam): basis.columns(tau, fam).copy() for tau in (1e-3, 3e-2)
             for fam in ("radius", "weight")}
    assert len(calls) == 1 and np.array_equal(other[0], first[1e-3, "radius"])
    assert all(np.array_equal(first[k], again[k]) for k in first)
    basis.forget()
    assert np.array_equal(basis.columns(3e-2, "radius"), first[3e-2, "radius"])
    assert len(calls) == 2
    monkeypatch.setattr(rate, "CONTACT_BYTES", 1000)  # a long record: found at each call
    long = RateBasis(None, radii, v, 1e-3, 1.0, np.ones(8), at_rest=True)
    long.columns(1e-3, "radius")
    long.release()
    long.columns(1e-3, "radius")
    assert len(calls) == 4 and long._shared == {}
