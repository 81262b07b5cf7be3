"""A blind stage generator for issue 28: a piezo stack as a user who knows piezo stages records it.

Written without reading pimodel's generators (``pimodel/stages``, ``pimodel/truth*``) or the
test files' stage builders; it imports nothing from pimodel except :class:`pimodel.Record`.

Discrete-time semantics: every record is sampled at ``fs``; ``v[k]`` is the amplifier command
held over ``[t[k], t[k+1])`` and ``y[k]`` the sensor sample at ``t[k]``. The stage is

    u[k]  = amplifier(v)[k]        (identity, a first-order bandwidth, saturation, a delay)
    h[k]  = sum_i w_i play_{r_i}(u)[k] + a0 u[k]    (play radii possibly rate-scaled)
    h'[k] = h[k] + creep (log-spaced first-order lags of h) ; a quadratic output map
    z[k]  = mode(h')[k]            (a second-order resonance, ZOH-discretised at fs)
    y[k]  = g z[k] + drift(t[k]) + white + 1/f noise, quantised to 16 bits of the range

The plays start in the state the stage holds after sitting at ``v_bias`` and being driven to
``v[0]`` (a step before the record starts); ``t`` of the validate record follows the train
record on one clock, after a pause.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np
from scipy import signal

from pimodel import Record

EFFECTS = ("creep", "drift", "resonance", "bandwidth", "delay", "asymmetry", "rate")
OUTSIDE = ("saturation", "gain_change")
VOCAB = {"resonance": "dynamics", "bandwidth": "dynamics"}
KINDS = ("multisine", "linchirp", "logchirp", "triangle_hold", "staircase", "bandnoise",
         "offset_sine")


@dataclass
class Stage:
    """A piezo stack with its amplifier and sensor; ``effects`` maps an effect to its size."""

    radii: np.ndarray
    weights: np.ndarray
    a0: float
    gain: float
    v_bias: float
    noise: float
    effects: dict = field(default_factory=dict)

    # --- the signal chain -------------------------------------------------------------
    def _amplifier(self, v: np.ndarray, fs: float) -> np.ndarray:
        u = v.astype(float)
        if "bandwidth" in self.effects:
            fc = self.effects["bandwidth"]
            a = np.exp(-2 * np.pi * fc / fs)
            u = signal.lfilter([1 - a], [1, -a], u, zi=[a * u[0]])[0]
        if "saturation" in self.effects:
            lo, hi = self.effects["saturation"]
            u = np.clip(u, lo, hi)
        if "delay" in self.effects:
            d = int(self.effects["delay"])
            u = np.concatenate([np.full(d, u[0]), u[:-d]])
        return u

    def _plays(self, u: np.ndarray, fs: float) -> np.ndarray:
        r0 = self.radii
        # state after resting at v_bias and a step to u[0]
        z = np.full(r0.shape, self.v_bias)
        z = np.clip(z, u[0] - r0, u[0] + r0)
        out = np.empty(u.size)
        rate = self.effects.get("rate")
        if rate is not None:
            alpha, vref, fc = rate
            du = np.abs(np.diff(u, prepend=u[0])) * fs
            a = np.exp(-2 * np.pi * fc / fs)
            rl = signal.lfilter([1 - a], [1, -a], du)
            scale = 1.0 + alpha * np.tanh(rl / vref)
        for k in range(u.size):
            r = r0 * scale[k] if rate is not None else r0
            z = np.minimum(np.maximum(z, u[k] - r), u[k] + r)
            out[k] = self.weights @ z
        return out + self.a0 * u

    def clean(self, t: np.ndarray, v: np.ndarray, t_clock0: float) -> np.ndarray:
        """The noiseless output at the samples ``t`` (``t_clock0``: the clock's start)."""
        fs = 1.0 / (t[1] - t[0])
        h = self._plays(self._amplifier(v, fs), fs)
        if "creep" in self.effects:
            gamma, taus = self.effects["creep"]
            c = np.zeros_like(h)
            for tau in taus:
                a = np.exp(-1.0 / (tau * fs))
                # the lag sat at the bias output before the record
                c += signal.lfilter([1 - a], [1, -a], h - h[0], zi=[0.0])[0]
            h = h + gamma * c
        if "asymmetry" in self.effects:
            beta, hmid, span = self.effects["asymmetry"]
            x = (h - hmid) / span
            h = h + beta * span * x * x
        if "resonance" in self.effects:
            fn, zeta = self.effects["resonance"]
            wn = 2 * np.pi * fn
            b, a, *_ = signal.cont2discrete(([wn * wn], [1, 2 * zeta * wn, wn * wn]), 1 / fs,
                                            method="zoh")
            b = np.ravel(b)
            zi = signal.lfilter_zi(b, a) * h[0]
            h = signal.lfilter(b, a, h, zi=zi)[0]
        y = self.gain * h
        if "gain_change" in self.effects:
            y = y * self.effects["gain_change"]  # set per record by ``record``
        if "drift" in self.effects:
            kind, size, tc, t_on = self.effects["drift"]
            s = np.maximum(t - t_on, 0.0)
            if kind == "thermal":
                y = y + size * (1 - np.exp(-s / tc))
            else:  # polynomial settling on the clock
                x = np.minimum(s / tc, 1.0)
                y = y + size * (2 * x - x * x)
        return y

    def record(self, t, v, rng, *, gain=1.0) -> Record:
        """A record as the sensor gives it: white + 1/f noise, 16-bit quantisation."""
        eff = dict(self.effects)
        if "gain_change" in eff:
            self.effects["gain_change"] = gain
        y = self.clean(t, v, 0.0)
        self.effects = eff
        n = t.size
        white = rng.normal(0.0, self.noise, n)
        spec = np.fft.rfft(rng.normal(0.0, 1.0, n))
        f = np.fft.rfftfreq(n)
        f[0] = f[1]
        pink = np.fft.irfft(spec / np.sqrt(f), n)
        pink *= 0.4 * self.noise / (pink.std() + 1e-30)
        span = self.stroke * 1.3
        lsb = span / 2 ** 16
        ym = np.round((y + white + pink) / lsb) * lsb
        return Record(t, v, ym)

    @property
    def stroke(self) -> float:
        return float(self.gain * (self.weights.sum() + self.a0) * 100.0)


# --- inputs a user applies ------------------------------------------------------------
def excitation(kind: str, fs: float, dur: float, rng, lo: float, hi: float) -> np.ndarray:
    """An input in V between ``lo`` and ``hi`` of ``dur`` seconds at ``fs``."""
    n = int(round(dur * fs))
    t = np.arange(n) / fs
    mid, amp = 0.5 * (lo + hi), 0.5 * (hi - lo)
    fmax = min(rng.uniform(20, 80) * np.sqrt(fs / 1000.0), fs / 20)
    if kind == "multisine":
        f0 = 1.0 / dur
        freqs = np.arange(1, int(fmax / f0) + 1) * f0
        freqs = freqs[np.unique(np.round(np.geomspace(1, freqs.size, 40)).astype(int)) - 1]
        ph = rng.uniform(0, 2 * np.pi, freqs.size)
        x = np.sum(np.sin(2 * np.pi * freqs[:, None] * t + ph[:, None]) / np.sqrt(freqs[:, None]),
                   axis=0)
    elif kind == "linchirp":
        x = np.sin(2 * np.pi * (0.5 * t + 0.5 * (fmax / 2 - 0.5) * t * t / dur) - np.pi / 2)
    elif kind == "logchirp":
        x = signal.chirp(t, f0=0.3, t1=dur, f1=fmax / 2, method="logarithmic", phi=-90)
    elif kind == "triangle_hold":
        levels = rng.uniform(-1, 1, 6)
        levels[0], levels[1] = -1, 1
        x = _ramps_holds(levels, n, rng)
    elif kind == "staircase":
        steps = rng.integers(8, 20)
        lv = np.concatenate([np.linspace(-1, 1, steps), np.linspace(1, -1, steps)[1:]])
        per = n // lv.size + 1
        x = np.repeat(lv, per)[:n]
        # the amplifier's slew: a short ramp between steps
        k = max(int(0.002 * fs), 2)
        x = np.convolve(np.concatenate([np.full(k, x[0]), x]), np.ones(k) / k, "valid")[:n]
    elif kind == "bandnoise":
        b, a = signal.butter(4, fmax / (fs / 2))
        x = signal.filtfilt(b, a, rng.normal(size=n + 2000))[1000:1000 + n]
    elif kind == "offset_sine":
        f = rng.uniform(1, 10)
        x = 0.8 * np.sin(2 * np.pi * f * t + rng.uniform(0.3, 2.5)) + 0.2 * np.sin(
            2 * np.pi * 0.2 * f * t)
    else:
        raise ValueError(kind)
    x = x - 0.5 * (x.max() + x.min())
    x = x / (np.abs(x).max() + 1e-30)
    return mid + amp * x


def _ramps_holds(levels, n, rng):
    segs = []
    per = n // levels.size
    for a, b in zip(np.roll(levels, 1), levels, strict=True):
        ramp = int(per * rng.uniform(0.4, 0.7))
        segs += [np.linspace(a, b, ramp), np.full(per - ramp, b)]
    x = np.concatenate(segs)
    return np.concatenate([x, np.full(n - x.size, x[-1])])[:n]


# --- a case --------------------------------------------------------------------------
def random_stage(rng, effects=(), fs=5000.0) -> Stage:
    """A piezo stack of 1-20 um stroke over 0-100 V with the named effects at random sizes."""
    m = int(rng.integers(40, 90))
    radii = 45.0 * np.sort(rng.uniform(0.0, 1.0, m) ** rng.uniform(1.0, 2.0))
    radii[0] = 0.0
    w = np.exp(-radii / rng.uniform(5, 20)) * rng.uniform(0.5, 1.5, m)
    a0 = rng.uniform(0.0, 0.3) * w.sum()
    stroke = rng.uniform(1.0, 20.0)
    gain = stroke / ((w.sum() + a0) * 100.0)
    st = Stage(radii, w, a0, gain, v_bias=0.0, noise=stroke * rng.uniform(1e-4, 4e-4))
    half = 50.0 * (st.weights.sum() + st.a0)  # half the output range before the sensor gain
    for e in effects:
        if e == "creep":
            st.effects[e] = (rng.uniform(0.004, 0.012), np.geomspace(0.01, rng.uniform(20, 100), 9))
        elif e == "drift":
            if rng.uniform() < 0.5:
                st.effects[e] = ("thermal", rng.choice([-1, 1]) * stroke * rng.uniform(0.01, 0.03),
                                 rng.uniform(20, 120), rng.uniform(0, 3))
            else:
                st.effects[e] = ("poly", rng.choice([-1, 1]) * stroke * rng.uniform(0.01, 0.03),
                                 rng.uniform(30, 150), rng.uniform(0, 3))
        elif e == "resonance":
            st.effects[e] = (min(rng.uniform(500, 3000), 0.3 * fs), rng.uniform(0.05, 0.2))
        elif e == "bandwidth":
            st.effects[e] = rng.uniform(20, 120)
        elif e == "delay":
            st.effects[e] = int(rng.integers(1, 6))
        elif e == "asymmetry":
            st.effects[e] = (rng.choice([-1, 1]) * rng.uniform(0.04, 0.1), half, half)
        elif e == "rate":
            st.effects[e] = (rng.uniform(0.2, 0.5), rng.uniform(500, 2000), rng.uniform(5, 30))
        elif e == "saturation":
            st.effects[e] = (-1e9, rng.uniform(70, 82))
        elif e == "gain_change":
            st.effects[e] = 1.0
        else:
            raise ValueError(e)
    return st


@dataclass
class Case:
    name: str
    effects: tuple
    kind: str
    fs: float
    seed: int


def make_records(case: Case, scale: float = 1.0):
    """(train, validate, stage, info): one record each, independent draws of one input kind;
    validate later on the same clock. ``scale`` shortens the records (tests)."""
    rng = np.random.default_rng([48, case.seed, zlib.crc32(case.name.encode())])
    st = random_stage(rng, case.effects, case.fs)
    dur = {1000.0: rng.uniform(6, 12), 5000.0: rng.uniform(3, 5), 20000.0: rng.uniform(2, 2.5)}
    dur = dur[case.fs] * scale
    if rng.uniform() < 0.5:
        lo, hi = 0.0 + rng.uniform(0, 10), 100.0 - rng.uniform(0, 10)
    else:
        lo, hi = 10.0, 90.0  # bipolar about a 50 V offset
    st.v_bias = lo
    vt = excitation(case.kind, case.fs, dur, rng, lo, hi)
    vv = excitation(case.kind, case.fs, dur, rng, lo, hi)
    tt = np.arange(vt.size) / case.fs
    t_val0 = round((tt[-1] + rng.uniform(5, 60)) * case.fs) / case.fs
    tv = t_val0 + np.arange(vv.size) / case.fs
    g1 = 1.0
    g2 = (1.0 + rng.choice([-1, 1]) * rng.uniform(0.03, 0.06)
          if "gain_change" in case.effects else 1.0)
    rt = st.record(tt, vt, rng, gain=g1)
    rv = st.record(tv, vv, rng, gain=g2)
    # size of the effects: validate RMS of (with effects - without) in noise sigmas
    bare = Stage(st.radii, st.weights, st.a0, st.gain, st.v_bias, st.noise)
    eff_rms = float(np.sqrt(np.mean((st.clean(tv, vv, 0) * g2 - bare.clean(tv, vv, 0)) ** 2)))
    info = {"stroke_um": st.stroke, "noise_um": st.noise, "effect_rms_sigma": eff_rms / st.noise,
            "n_train": int(vt.size), "fs": case.fs, "dur": dur, "sizes": repr(st.effects)}
    return rt, rv, st, info
