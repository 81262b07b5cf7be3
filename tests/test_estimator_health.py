"""The health checks of a radius estimate (pimodel.identification.adaptive.health) run in the C core
(fmu/src/pim_est_health.c), the code the RadiusEstimator FMU runs: the still-moving check's
quarters are exact up to 64 rows and on a grid within N / 32 rows beyond."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel._native import HEALTH_FIT, HEALTH_MERGED, HEALTH_MOVING, HEALTH_PINNED, health_checks
from pimodel.identification.adaptive.health import estimator_health


def exact_drift(hist: np.ndarray) -> float:
    """max_j |mean of the last quarter - mean of the quarter before| (q = N // 4)."""
    q = hist.shape[0] // 4
    return float(np.max(np.abs(hist[-q:].mean(axis=0) - hist[-2 * q:-q].mean(axis=0))))


@pytest.mark.parametrize("rows", [4, 5, 17, 63, 64])
def test_drift_is_exact_up_to_64_rows(rows):
    hist = np.cumsum(np.random.default_rng(rows).uniform(0, 1, (rows, 3)), axis=0)
    got = health_checks(np.ones(3), hist, linear_play=False)["drift"]
    assert got == pytest.approx(exact_drift(hist), rel=1e-12)


@pytest.mark.parametrize("rows", [65, 1000, 100_003, 1_048_577])
def test_drift_quarters_are_within_a_32nd_of_the_record(rows):
    """On a ramp rhat[k] = k / N the exact drift is q / N; the grid moves the start of the
    quarter before back by less than N / 32 rows, adding less than 1 / 64."""
    hist = (np.arange(rows) / rows)[:, None] * np.array([1.0, 2.0])
    q = rows // 4
    got = health_checks(np.ones(2), hist, linear_play=False)["drift"] / 2.0
    assert q / rows - 1e-12 <= got < q / rows + 1 / 64


def test_flags_of_the_checks():
    hist = np.tile([0.0, 0.3, 0.3, 0.9], (64, 1))
    hist[-16:, 3] = 1.0  # moved by 0.1 > 1 % of max r_hat in the last quarter
    res = health_checks(np.ones(4), hist, linear_play=False)
    assert res["flags"] & HEALTH_MERGED and res["flags"] & HEALTH_PINNED
    assert res["flags"] & HEALTH_MOVING and res["drift"] == pytest.approx(0.1)
    assert res["merged"].tolist() == [False, True, False]
    assert res["pinned"].tolist() == [True, False, False, False]
    held = health_checks(np.ones(4), hist, linear_play=True)
    assert not held["flags"] & HEALTH_PINNED  # r_hat[1] = 0 held on purpose


def test_report_uses_the_c_checks():
    v = np.sin(np.arange(0, 60, 0.01))
    hist = np.tile([0.2, 0.2], (6000, 1))
    hist[-1500:, 1] = 0.25
    h = estimator_health(v, [1.0, 1.0], hist)
    assert h.merged == [] and h.still_moving and 0.05 * (1 - 1 / 16) < h.drift <= 0.05
    assert any("still moving" in m for m in h.messages)


def test_more_plays_than_the_core_holds_is_an_error():
    with pytest.raises(ValueError, match="history: n: must be between 1 and 64"):
        estimator_health(np.sin(np.arange(0, 6, 0.01)), np.ones(65), np.ones((600, 65)))


def test_fit_check_of_the_core_matches_the_python_report():
    """The C fit check (the FMU's; noise level from the mean absolute second difference) on
    estimate_radii's own run: the RMS over the last quarter is Python's exactly up to 64 rows,
    and its noise bound is within 5 % of Python's (median based) on a noisy record."""
    from pimodel import PIOperator, estimate_radii
    from pimodel.identification.adaptive.settings import noise_level
    from pimodel.signals import add_noise_snr, sinusoid

    p, r = np.array([0.3, 0.5, 0.8]), np.array([0.4, 1.0, 1.5])
    t, v = sinusoid(5, 1, fs=1000, duration=20)
    y = add_noise_snr(PIOperator(p, r).simulate(v), 20, np.random.default_rng(0))
    res = estimate_radii(v, y, p, dt=1e-3, initial_radii=[0.1, 0.2, 0.3], law="paper",
                         polish=False)
    short = health_checks(p, res.history[:64], linear_play=False, y=y[:64],
                          error=res.error[:64])
    assert short["fit"][0] == pytest.approx(np.sqrt(np.mean(res.error[48:64] ** 2)), rel=1e-12)
    full = health_checks(p, res.history, linear_play=False, y=y, error=res.error)
    bound = 1.1 * noise_level(y) + 1e-4 * np.ptp(y)
    assert full["fit"][1] == pytest.approx(bound, rel=0.05)
    assert bool(full["flags"] & HEALTH_FIT) == (not res.health.fit_ok)
