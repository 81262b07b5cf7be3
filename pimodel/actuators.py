"""Piezo stage dynamics after the hysteresis (Hammerstein structure), python-control systems.

``v -> PI -> h -> G(s) -> y``: the PI operator gives the quasi-static displacement ``h`` and
``G`` adds a second-order mode, creep and a delay. Each factor is built in continuous time and
discretised with ``control.c2d`` (zero-order hold on ``h``); a delay of ``tau`` seconds becomes
``round(tau / dt)`` whole samples (stated: sub-sample delays are rounded).
"""

from __future__ import annotations

from collections.abc import Sequence

import control
import numpy as np

from .checks import positive_scalar


def second_order_mode(fn_hz: float, damping: float, gain: float = 1.0) -> control.TransferFunction:
    """``gain wn^2 / (s^2 + 2 zeta wn s + wn^2)``, ``wn = 2 pi fn_hz`` (continuous time)."""
    fn = positive_scalar(fn_hz, "fn_hz")
    if not np.isfinite(damping) or damping < 0:
        raise ValueError(f"damping: expected a finite number >= 0, got {damping!r}")
    if not np.isfinite(gain) or gain == 0:
        raise ValueError(f"gain: expected a finite non-zero static gain, got {gain!r}")
    wn = 2 * np.pi * fn
    return control.tf([gain * wn**2], [1.0, 2 * damping * wn, wn**2])


def creep_lags(gains: Sequence[float], time_constants: Sequence[float]) -> control.TransferFunction:
    """Creep as ``1 + sum_i a_i / (tau_i s + 1)``: a step of the hysteresis output is followed
    by a slow rise of ``sum a_i`` (fractions of the step) with time constants ``tau_i`` [s]."""
    a = np.atleast_1d(np.asarray(gains, float))
    tau = np.atleast_1d(np.asarray(time_constants, float))
    if a.shape != tau.shape or a.size == 0:
        raise ValueError(f"gains and time_constants: expected equal non-empty lengths, got "
                         f"{a.size} and {tau.size}")
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError("gains: creep gains must be finite and >= 0")
    if not np.all(np.isfinite(tau)) or np.any(tau <= 0):
        raise ValueError("time_constants: must be finite and > 0 (seconds)")
    G = control.tf([1.0], [1.0])
    for ai, ti in zip(a, tau, strict=True):
        G = G + control.tf([ai], [ti, 1.0])
    return G


def creep_per_decade(percent_per_decade: float, t_min: float = 0.01,
                     decades: int = 4) -> control.TransferFunction:
    """Creep of about ``percent_per_decade`` % of the last move per decade of time, from
    ``t_min`` for ``decades`` decades: one lag per decade (``tau = t_min 10^i``)."""
    rate = float(percent_per_decade)
    if not np.isfinite(rate) or rate < 0:
        raise ValueError(f"percent_per_decade: expected >= 0, got {percent_per_decade!r}")
    if int(decades) < 1:
        raise ValueError(f"decades: expected >= 1, got {decades!r}")
    tau = positive_scalar(t_min, "t_min") * 10.0 ** np.arange(int(decades))
    return creep_lags(np.full(tau.size, rate / 100.0), tau)


def delay_samples(delay: float, dt: float) -> int:
    """Whole samples of a pure delay: ``round(delay / dt)``."""
    dt = positive_scalar(dt, "dt")
    if not np.isfinite(delay) or delay < 0:
        raise ValueError(f"delay: expected a finite number >= 0 (seconds), got {delay!r}")
    return int(round(delay / dt))


def stage_dynamics(dt: float, *, fn_hz: float | None = 1000.0, damping: float = 0.05,
                   gain: float = 1.0, creep: control.TransferFunction | None = None,
                   delay: float = 0.0, input: str = "h", output: str = "y",
                   name: str = "stage") -> control.StateSpace:
    """Discrete-time stage dynamics ``G(z)`` from the hysteresis output ``h`` to ``y``.

    ``fn_hz`` None: no mode (static ``gain``); ``creep`` a continuous factor (see
    :func:`creep_lags`); ``delay`` [s] rounded to samples. ZOH discretisation; with a mode the
    result has ``D = 0`` (usable inside a feedback loop).
    """
    dt = positive_scalar(dt, "dt")
    G = second_order_mode(fn_hz, damping, gain) if fn_hz is not None else control.tf([gain], [1])
    if creep is not None:
        G = G * creep
    Gd = control.c2d(control.ss(G), dt, method="zoh")
    d = delay_samples(delay, dt)
    if d > 0:
        shift = control.ss(np.diag(np.ones(d - 1), -1), np.eye(d)[:, :1], np.eye(d)[-1:, :],
                           0.0, dt)
        Gd = control.series(shift, Gd)
    return control.ss(Gd.A, Gd.B, Gd.C, Gd.D, dt, inputs=[input], outputs=[output], name=name)
