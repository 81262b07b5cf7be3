"""Records of :mod:`pimodel.stages.pi_stage` stages taken under feedback (issue 28), for the
tests of the diagnosis: an integral controller tracks a reference on the measured output.

The stage is stepped sample by sample (:func:`pimodel.stages.stepper.stage_stepper`, plays at
rest at 0); the controller is strictly causal: ``v[k] = v[k-1] + KI dt e[k]`` with
``e[k] = ref[k] - y[k-1]`` (``y[-1] = 0``, so ``v[0] = 0`` when ``ref[0] = 0``), ``y[k]`` the
stage's output for ``v[0..k]`` plus the stage's own white noise. ``KI`` (60/s over the stage's
total weight, a bandwidth near 10 Hz) keeps a gain margin of at least 2.2 on every mode (500-3000
Hz, damping 0.02-0.1) and delay (100-400 us) of :func:`pimodel.stages.pi_stage.random_truth`, at
10 and 2 kHz. References: train, a 1 Hz triangle of +-7 um, a random-phase multisine (1, 2, 3,
5 Hz) of peak 7 um and four held levels (0.25 s each); validate, another multisine (1.5, 2.5,
4 Hz), a 2 Hz triangle of +-5 um and three held levels; validate starts 1 s after train ends on
the clock the records share (a drift runs on it).
"""

from __future__ import annotations

import numpy as np

from pimodel.records import Record
from pimodel.stages.pi_stage import STAGE_WEIGHTS, random_truth
from pimodel.stages.stepper import stage_stepper

KI = 60.0 / float(np.sum(STAGE_WEIGHTS))  # V/(um s)
PEAK = 7.0  # um, the references' peak (the stage's output for +-0.8 V)


def reference(kind: str, fs: float, rng: np.random.Generator) -> np.ndarray:
    """The train or validate reference [um] at ``fs`` [Hz], starting at 0."""
    dt = 1.0 / fs

    def tri(f, amp):  # one period from 0
        ph = (np.arange(int(round(fs / f))) * dt * f) % 1.0
        return amp * np.where(ph < 0.25, 4 * ph, np.where(ph < 0.75, 2 - 4 * ph, 4 * ph - 4))

    def multisine(freqs):  # 1 s from 0, random phases, peak PEAK
        tt = np.arange(int(round(fs))) * dt
        ph = rng.uniform(0, 2 * np.pi, len(freqs))
        s = sum(np.sin(2 * np.pi * f * tt + p) - np.sin(p) for f, p in zip(freqs, ph, strict=True))
        return PEAK * s / np.max(np.abs(s))

    def holds(n):
        return np.repeat(rng.uniform(-6.5, 6.5, n), int(round(0.25 * fs)))

    if kind == "train":
        return np.concatenate((tri(1.0, PEAK), multisine((1.0, 2.0, 3.0, 5.0)), holds(4)))
    return np.concatenate((multisine((1.5, 2.5, 4.0)), tri(2.0, 5.0), holds(3)))


def closed_loop(truth, t: np.ndarray, ref: np.ndarray, rng: np.random.Generator):
    """Input ``v`` [V] and measured output ``y`` [um] of ``truth`` under the integral controller."""
    fs = 1.0 / float(t[1] - t[0])
    stage = stage_stepper(truth, 1.0 / fs)
    v, y = np.empty_like(t), np.empty_like(t)
    u, meas = 0.0, 0.0
    for k in range(t.size):
        u += KI * (ref[k] - meas) / fs
        v[k] = u
        meas = stage.step(t[k], u) + rng.normal(0.0, truth.noise_um)
        y[k] = meas
    return v, y


def records(effects, seed: int, fs: float, validate_scale: float = 1.0):
    """``(truth, train, validate)``: ``random_truth(effects, seed)`` (a drift on the shared
    clock) recorded in closed loop at ``fs``; the validate reference times ``validate_scale``."""
    truth = random_truth(effects, seed, drift_clock="absolute")
    rng = np.random.default_rng(7000 + seed)
    rt, rv = reference("train", fs, rng), validate_scale * reference("validate", fs, rng)
    tt = np.arange(rt.size) / fs
    tv = tt[-1] + 1.0 + np.arange(rv.size) / fs
    train = Record(tt, *closed_loop(truth, tt, rt, rng), source="train")
    validate = Record(tv, *closed_loop(truth, tv, rv, rng), source="validate")
    return truth, train, validate
