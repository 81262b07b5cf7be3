"""The simulated true stages of :mod:`pimodel.stages.pi_stage` and
:mod:`pimodel.stages.preisach_stage`, sample by
sample and without noise, for feedback loops.

The generators compute whole records; a feedback loop needs ``y[k]`` before it chooses
``v[k + 1]``. :func:`stage_stepper` returns an object whose ``step(t_k, v_k)`` gives the
noise-free output ``y[k]`` [um] for the input ``v[k]`` [V] at time ``t[k]`` [s], from the same
initial state as the generator's ``simulate`` (plays at rest, filters around the first sample;
the Preisach model from negative saturation) and with the same arithmetic per effect (the same
filter coefficients, play updates and Preisach memory). ``tests/test_truth_steps.py`` holds every
stepper equal to its generator's ``simulate`` with the noise off, for every effect.

Two things a whole record gives the generators that a stepper must be told: the input range of
``pimodel.stages.pi_stage``'s step rule for the rate effect (``STEP_SHARE`` of ``ptp(v)``), and the
record length for ``pimodel.stages.preisach_stage``'s log-law creep kernel.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.signal import cont2discrete, lfilter, lfilter_zi

from ..loops.actuators import delay_samples, second_order_mode
from ..operators.pi import PIOperator
from .pi_stage import (
    RATE_REFERENCE,
    STEP_SHARE,
    Truth,
    creep_lag_filters,
    zoh_coefficients,
)
from .preisach_stage import RATE_REF, TAU0, U_SAT, AltTruth

__all__ = ["noise_free", "stage_stepper"]


def noise_free(truth):
    """A copy of a generator's stage with its noise switched off.

    Parameters
    ----------
    truth : pimodel.stages.pi_stage.Truth or pimodel.stages.preisach_stage.AltTruth
        The stage.

    Returns
    -------
    Truth or AltTruth
        The same stage, ``noise_um = 0`` (``Truth``) or ``noise = 0`` (``AltTruth``).

    Examples
    --------
    >>> noise_free(Truth(noise_um=0.01)).noise_um
    0.0
    """
    return replace(truth, noise_um=0.0) if isinstance(truth, Truth) else replace(truth, noise=0.0)


def stage_stepper(truth, dt: float, *, input_range: float = 2.0, length: int = 100_000):
    """A stepper of ``truth`` (noise-free): ``step(t_k, v_k) -> y_k``.

    Parameters
    ----------
    truth : pimodel.stages.pi_stage.Truth or pimodel.stages.preisach_stage.AltTruth
        The stage (its noise is ignored).
    dt : float
        Sample time [s].
    input_range : float, optional
        ``Truth`` with a rate effect: the range whose ``STEP_SHARE`` makes a one-sample jump
        a step (the batch simulation takes ``ptp(v)`` of the record). Default 2 V (the
        standard excitations' +-1 V).
    length : int, optional
        ``AltTruth`` with creep: the most samples the stepper will be asked for.

    Returns
    -------
    object
        With ``step(t_k, v_k) -> float``: ``y[k]`` [um] after ``v[0..k]``.

    Raises
    ------
    ValueError
        ``dt`` not positive, an ``AltTruth`` with a second input (random, not steppable) or
        a type that is neither generator.

    Examples
    --------
    >>> t = np.arange(200) * 1e-4
    >>> v = np.sin(2 * np.pi * 20 * t)
    >>> truth = Truth(creep_percent_per_decade=1.5, mode_hz=900.0, noise_um=0.0)
    >>> stage = stage_stepper(truth, 1e-4)
    >>> y = [stage.step(tk, vk) for tk, vk in zip(t, v)]
    >>> bool(np.allclose(y, truth.simulate(t, v, np.random.default_rng(0)), atol=1e-12))
    True
    """
    if not dt > 0:
        raise ValueError(f"dt: expected > 0, got {dt!r}")
    if isinstance(truth, Truth):
        return _TruthStepper(truth, float(dt), float(input_range))
    if isinstance(truth, AltTruth):
        if truth.second_input is not None:
            raise ValueError("truth: the second input of an AltTruth is random noise the "
                             "stepper cannot reproduce; set second_input=None")
        return _AltTruthStepper(truth, float(dt), int(length))
    raise ValueError(f"truth: expected a Truth or an AltTruth, got {type(truth).__name__}")


class _Filter:
    """``lfilter(b, a, x)`` one sample at a time; the state starts on the first sample as the
    batch call's ``zi`` (``around``: ``lfilter_zi(b, a) * x[0]``; else at rest)."""

    def __init__(self, b, a, around: bool):
        self.b, self.a, self.around, self.zi = np.asarray(b), np.asarray(a), around, None

    def step(self, x: float) -> float:
        if self.zi is None:
            n = max(self.a.size, self.b.size) - 1
            self.zi = lfilter_zi(self.b, self.a) * x if self.around else np.zeros(n)
        y, self.zi = lfilter(self.b, self.a, [x], zi=self.zi)
        return float(y[0])


class _Creep:
    """The truth's creep one sample at a time: ``x[k]`` plus its lag filters
    (:func:`pimodel.stages.pi_stage.creep_lag_filters`), each around the first sample as in the
    batch
    call, summed in the same order."""

    def __init__(self, percent_per_decade: float, dt: float):
        self.lags = [_Filter(b, a, around=True)
                     for b, a in creep_lag_filters(percent_per_decade, dt)]

    def step(self, x: float) -> float:
        y = x
        for lag in self.lags:
            y = y + lag.step(x)
        return y


class _TruthStepper:
    """``Truth.simulate`` per sample: PI (rate) -> asymmetry -> creep -> mode -> delay -> drift."""

    def __init__(self, truth: Truth, dt: float, input_range: float):
        self.truth, self.dt = truth, dt
        self.w, self.r = np.asarray(truth.weights, float), np.asarray(truth.radii, float)
        self.pi = PIOperator(truth.weights, truth.radii)
        self.step_limit = STEP_SHARE * input_range
        self.z = np.zeros(self.r.size)
        self.filters = []
        if truth.creep_percent_per_decade is not None:
            self.filters.append(_Creep(truth.creep_percent_per_decade, dt))
        if truth.mode_hz is not None:
            G = second_order_mode(truth.mode_hz, truth.mode_damping)
            self.filters.append(_Filter(*zoh_coefficients(G, dt), around=True))
        self.delay = delay_samples(truth.delay_s, dt) if truth.delay_s is not None else 0
        self.before_delay: list[float] = []
        self.v_prev = self.t0 = None

    def step(self, t: float, v: float) -> float:
        tr = self.truth
        if self.v_prev is None:
            self.v_prev, self.t0 = v, t
        if tr.rate_gain is None:  # the compiled PI, as Truth.simulate (same rounding)
            y = self.pi.step(v)
        else:  # rate_dependent_pi's update
            dv = abs(v - self.v_prev)
            rate = dv / self.dt / RATE_REFERENCE if dv <= self.step_limit else 0.0
            rk = self.r * (1.0 + tr.rate_gain * rate)
            self.z = np.minimum(np.maximum(self.z, v - rk), v + rk)
            y = float(self.w @ self.z)
        if tr.asymmetry is not None:
            y = y + tr.asymmetry * y**2 / (0.5 * float(np.sum(tr.weights)))
        for f in self.filters:
            y = f.step(y)
        self.before_delay.append(y)
        k = len(self.before_delay) - 1
        y = self.before_delay[k - self.delay] if k >= self.delay else self.before_delay[0]
        if tr.drift_um_per_s is not None:
            y = y + tr.drift_um_per_s * (t - self.t0 if tr.drift_clock == "record" else t)
        self.v_prev = v
        return y


class _AltTruthStepper:
    """``AltTruth.simulate`` per sample: dead zone -> Preisach (rate) or Bouc-Wen -> static map
    -> log-law creep -> two modes -> fractional delay -> drift."""

    def __init__(self, truth: AltTruth, dt: float, length: int):
        self.truth, self.dt = truth, dt
        self.ext = [-U_SAT]
        self.e_sat = truth.everett(U_SAT, -U_SAT)
        self.bw_z = 0.0
        self.rho, self.a_rho = 0.0, np.exp(-dt / 0.02)
        if truth.creep is not None:
            self.kernel = truth.creep * np.log10(1.0 + np.arange(length) * dt / TAU0)
            self.dh = np.zeros(length)
        self.modes = []
        for fn, zeta, gain in truth.modes or ():
            w = 2 * np.pi * fn
            b, a, _ = cont2discrete(([gain * w * w], [1.0, 2 * zeta * w, w * w]), dt)
            self.modes.append((_Filter(np.ravel(b), a, around=False), gain))
        self.t_hist: list[float] = []
        self.y_hist: list[float] = []
        self.k = 0
        self.x_prev = self.h_prev = self.y0 = self.t0 = None

    def step(self, t: float, v: float) -> float:
        tr, k = self.truth, self.k
        x = v if tr.dead_zone is None else float(np.sign(v) * max(abs(v) - tr.dead_zone, 0.0))
        if self.x_prev is None:
            self.x_prev, self.t0 = x, t
        if tr.bouc_wen:
            self.bw_z = tr.bouc_wen_step(self.bw_z, x - self.x_prev)
            y = tr.k_lin * x + self.bw_z
        else:
            p = tr.preisach_step(self.ext, min(max(x, -U_SAT), U_SAT), self.e_sat)
            if tr.rate is not None:
                raw = abs(x - self.x_prev) / self.dt / RATE_REF
                self.rho = self.a_rho * self.rho + (1 - self.a_rho) * raw
                p = p * (1.0 + tr.rate * self.rho)
            y = tr.k_lin * x + p
        if tr.asymmetry is not None:
            y = 6.0 * (np.exp(tr.asymmetry * y / 6.0) - 1.0) / tr.asymmetry
        if tr.creep is not None:
            if k >= self.dh.size:
                raise ValueError(f"length: the stepper was built for {self.dh.size} samples")
            self.dh[k] = 0.0 if self.h_prev is None else y - self.h_prev
            self.h_prev = y
            y = y + float(self.dh[:k + 1] @ self.kernel[k::-1])
        if self.modes:
            if self.y0 is None:
                self.y0 = y
            y = sum(f.step(y - self.y0) + gain * self.y0 for f, gain in self.modes)
        self.t_hist.append(t)
        self.y_hist.append(y)
        if tr.delay_s is not None:
            lo = max(0, k - int(np.ceil(tr.delay_s / self.dt)) - 2)
            y = float(np.interp(t - tr.delay_s, self.t_hist[lo:], self.y_hist[lo:]))
            if lo > 0 and t - tr.delay_s < self.t_hist[lo]:  # pragma: no cover - guard
                raise RuntimeError("delay window too short")
        if tr.drift is not None:
            y = y + tr.drift * (t if tr.drift_clock == "absolute" else t - self.t0)
        self.x_prev, self.k = x, k + 1
        return float(y)
