"""A third stage generator, written independently of ``pi_stage`` and ``preisach_stage`` (no
shared code, inputs or effect shapes), for records shaped like users' experiments: a 2 kHz
stage driven by random-phase multisines, logarithmic chirps, ramps to held levels and
band-limited random input.

Signal path, one sample ``k`` at a time (``dt = 1 / FS``; input ``v`` in V, output in um)::

    v -> smooth PI density (rate-dependent radii) -> output map (asymmetry)
      -> creep (long lags) -> mode + real pole -> delay
      -> + thermal drift + second input -> clipping -> sensor gain -> + noise

- hysteresis: ``h[k] = a v[k] + sum_i w_i z_i[k]`` over ``N_PLAYS`` plays with radii
  ``r_i = (i + 1/2) R / N_PLAYS`` and a smooth density ``w_i = c r_i exp(-r_i / r0) R /
  N_PLAYS``; each play ``z_i[k] = min(max(z_i[k-1], v[k] - rho_i[k]), v[k] + rho_i[k])``
  starts at ``z_i[-1] = 0`` (rest at 0 V; :func:`density_records` starts each record at
  0 V). With ``rate``, ``rho_i[k] = r_i (1 + beta s[k] / (1 + s[k]))`` (saturating: at most
  ``1 + beta``), ``s`` the input speed ``|v[k] - v[k-1]| / dt / RATE_REF`` low-passed with
  time constant ``tau_rate``; without it ``rho_i = r_i``.
- asymmetry: ``h -> h + q (h - h_mid)^2 / H`` (``H`` the nominal output span), a quadratic
  map with a sign of its own.
- creep: ``c_j`` times first-order lags of ``h`` with time constants ``CREEP_LAGS`` (up to
  100 s), ``y = h + sum_j c_j (L_j[h] - h[0])``, each lag exact for a zero-order hold.
- dynamics: a second-order mode (``fn``, ``zeta``) in series with a real pole ``fp``, static
  gain 1, discretised with the bilinear transform prewarped at ``fn``.
- delay: ``y[k] -> y(k dt - delay)`` by linear interpolation between samples (the first
  sample is held before the record).
- drift: thermal settling ``D (1 - exp(-t / T))`` on the clock the records share (``t`` as
  given; train starts at 0).
- outside the diagnosis' vocabulary: an unmeasured second input (band-limited random, a few
  Hz) added to the output; clipping of the output at a level inside its span (a sensor's
  range); a sensor gain that differs between records (``gain`` multiplies the output of the
  record it is given for).
- noise: white Gaussian plus quantisation to ``quantum``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.signal import bilinear, lfilter

__all__ = [
    "DensityStage",
    "INPUT_KINDS",
    "density_input",
    "density_records",
    "random_density_stage",
]

FS = 2000.0  # Hz
V_MAX = 120.0  # V, input range 0..V_MAX
N_PLAYS = 240
RATE_REF = 500.0  # V/s
CREEP_LAGS = (0.5, 5.0, 30.0, 100.0)  # s
INPUT_KINDS = ("multisine", "chirp", "ramps", "random")
EFFECTS = ("creep", "dynamics", "delay", "asymmetry", "drift", "rate")
OUTSIDE = ("clipping", "second_input", "sensor_gain")


@dataclass
class DensityStage:
    """A stage with a smooth PI density of many plays and optional effects; ``None`` switches
    an effect off (the module docstring gives each formula). Input in V, output in um.

    Parameters
    ----------
    a_lin : float
        Linear part ``a`` [um/V].
    density_c, density_r0 : float
        Density scale ``c`` [um/V^2] and decay radius ``r0`` [V].
    rate_beta, rate_tau : float or None
        Largest relative radius growth with the low-passed speed, and its time constant [s].
    asymmetry : float or None
        Quadratic output map coefficient ``q`` (signed).
    creep : tuple of float or None
        Gains ``c_j`` of the lags ``CREEP_LAGS`` (fractions of ``h``).
    mode : tuple of float or None
        ``(fn [Hz], zeta, fp [Hz])`` of the mode and the real pole.
    delay_s : float or None
        Delay [s].
    thermal : tuple of float or None
        ``(D [um], T [s])`` of the settling drift.
    second_input : float or None
        RMS [um] of the unmeasured second input's contribution.
    clip : float or None
        Output clipping level as a fraction of the nominal span (from its low end).
    noise : float
        White noise standard deviation [um].
    quantum : float
        Quantisation step [um].

    Examples
    --------
    >>> t, v = density_input("ramps", seed=0, duration=1.0)
    >>> y = DensityStage().simulate(t, v, np.random.default_rng(0))
    >>> y.shape == v.shape and bool(np.all(np.isfinite(y)))
    True
    """

    a_lin: float = 0.06
    density_c: float = 0.004
    density_r0: float = 12.0
    rate_beta: float | None = None
    rate_tau: float = 0.03
    asymmetry: float | None = None
    creep: tuple | None = None
    mode: tuple | None = None
    delay_s: float | None = None
    thermal: tuple | None = None
    second_input: float | None = None
    clip: float | None = None
    noise: float = 0.004
    quantum: float = 0.001
    radii: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        half = V_MAX / 2
        self.radii = (np.arange(N_PLAYS) + 0.5) * half / N_PLAYS
        self.weights = self.density_c * self.radii * np.exp(-self.radii / self.density_r0) * \
            half / N_PLAYS
        lo = self.hysteresis(np.array([0.0, V_MAX]), 1.0 / FS)
        self.span = float(lo[-1] - lo[0])

    def hysteresis(self, v: np.ndarray, dt: float) -> np.ndarray:
        """``h[k]`` of ``v[k]`` (plays start at 0: rest at 0 V), with rate-dependent radii when
        ``rate_beta`` is set.

        Parameters
        ----------
        v : numpy.ndarray
            Input [V].
        dt : float
            Sample time [s].

        Returns
        -------
        numpy.ndarray
            Hysteresis output [um].
        """
        z = np.zeros(N_PLAYS)
        h = np.empty(v.size)
        s = 0.0
        alpha = 1.0 - np.exp(-dt / self.rate_tau)
        for k in range(v.size):
            rho = self.radii
            if self.rate_beta is not None:
                speed = abs(v[k] - v[k - 1]) / dt / RATE_REF if k else 0.0
                s += alpha * (speed - s)
                rho = self.radii * (1.0 + self.rate_beta * s / (1.0 + s))
            z = np.minimum(np.maximum(z, v[k] - rho), v[k] + rho)
            h[k] = self.a_lin * v[k] + self.weights @ z
        return h

    def simulate(self, t: np.ndarray, v: np.ndarray, rng: np.random.Generator,
                 gain: float = 1.0) -> np.ndarray:
        """Measured output ``y[k]`` of input ``v[k]`` at times ``t[k]`` (uniform ``dt``).

        Parameters
        ----------
        t, v : numpy.ndarray
            Times [s] (on the clock the records share) and input [V].
        rng : numpy.random.Generator
            Noise and second-input draws.
        gain : float
            Sensor gain of this record (1: nominal).

        Returns
        -------
        numpy.ndarray
            Output [um].
        """
        t, v = np.asarray(t, float), np.asarray(v, float)
        dt = float(t[1] - t[0])
        y = self.hysteresis(v, dt)
        if self.asymmetry is not None:
            mid = 0.5 * self.span + self.hysteresis(np.array([0.0]), dt)[0]
            y = y + self.asymmetry * (y - mid) ** 2 / self.span
        if self.creep is not None:
            y0 = self.hysteresis(np.array([0.0]), dt)[0]  # rest
            add = np.zeros_like(y)
            for c, tau in zip(self.creep, CREEP_LAGS, strict=True):
                p = np.exp(-dt / tau)
                add += c * (lfilter([1 - p], [1, -p], y - y0, zi=[0.0])[0])
            y = y + add
        if self.mode is not None:
            fn, zeta, fp = self.mode
            wn, wp = 2 * np.pi * fn, 2 * np.pi * fp
            num, den = np.polymul([wn**2], [wp]), np.polymul([1, 2 * zeta * wn, wn**2], [1, wp])
            fs_w = wn / (2 * np.tan(wn * dt / 2))  # prewarped at fn
            b, a = bilinear(num, den, fs=fs_w)
            y = y[0] + lfilter(b, a, y - y[0])
        if self.delay_s is not None:
            y = np.interp(np.arange(y.size) - self.delay_s / dt, np.arange(y.size), y)
        if self.thermal is not None:
            d, tau = self.thermal
            y = y + d * (1.0 - np.exp(-t / tau))
        if self.second_input is not None:
            w = lfilter(*_lowpass(3.0, dt), rng.standard_normal(y.size + 4000))[4000:]
            y = y + self.second_input * w / np.std(w)
        if self.clip is not None:
            base = self.hysteresis(np.array([0.0]), dt)[0]
            y = np.minimum(y, base + self.clip * self.span)
        y = gain * y + self.noise * rng.standard_normal(y.size)
        return np.round(y / self.quantum) * self.quantum


def _lowpass(fc: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """A second-order Butterworth low-pass at ``fc`` [Hz] (bilinear, prewarped)."""
    wc = 2 * np.pi * fc
    return bilinear([wc**2], [1, np.sqrt(2) * wc, wc**2], fs=wc / (2 * np.tan(wc * dt / 2)))


def density_input(kind: str, seed: int, duration: float = 5.0,
                  fs: float = FS) -> tuple[np.ndarray, np.ndarray]:
    """An input ``(t, v)`` [s, V] of one kind, in ``0..V_MAX``, starting at times 0.

    ``multisine``: 12 random-phase sines on a log grid 0.3-40 Hz with falling amplitudes;
    ``chirp``: a logarithmic chirp 0.5-50 Hz with an amplitude that decays and grows back;
    ``ramps``: ramps of random speed to held levels (holds 0.1-0.6 s); ``random``:
    band-limited (8 Hz) Gaussian noise. Each is scaled to span 5-95 % of ``V_MAX``.

    Parameters
    ----------
    kind : str
        One of ``INPUT_KINDS``.
    seed : int
        Random seed.
    duration : float
        Length [s].
    fs : float
        Sample rate [Hz].

    Returns
    -------
    tuple of numpy.ndarray
        ``(t, v)``.

    Raises
    ------
    ValueError
        If ``kind`` is not in ``INPUT_KINDS``.

    Examples
    --------
    >>> t, v = density_input("chirp", seed=1, duration=2.0)
    >>> t.size, bool(v.min() >= 0 and v.max() <= V_MAX)
    (4000, True)
    """
    if kind not in INPUT_KINDS:
        raise ValueError(f"kind: expected one of {INPUT_KINDS}, got {kind!r}")
    rng = np.random.default_rng(seed)
    n = int(round(duration * fs))
    t = np.arange(n) / fs
    if kind == "multisine":
        f = np.geomspace(0.3, 40.0, 12)
        x = sum(f0 ** -0.6 * np.sin(2 * np.pi * f0 * t + rng.uniform(0, 2 * np.pi)) for f0 in f)
    elif kind == "chirp":
        f0, f1 = 0.5, 50.0
        phase = 2 * np.pi * f0 * duration / np.log(f1 / f0) * ((f1 / f0) ** (t / duration) - 1)
        env = 0.35 + 0.65 * np.abs(np.cos(np.pi * t / duration + rng.uniform(-0.3, 0.3)))
        x = env * np.sin(phase + rng.uniform(0, 2 * np.pi))
    elif kind == "ramps":
        x = np.empty(n)
        k, level = 0, 0.0
        while k < n:
            target = rng.uniform(-1, 1)
            n_ramp = max(int(abs(target - level) / rng.uniform(0.5, 6.0) * fs), 2)
            n_hold = int(rng.uniform(0.1, 0.6) * fs)
            seg = np.concatenate((np.linspace(level, target, n_ramp), np.full(n_hold, target)))
            x[k:k + seg.size] = seg[:n - k]
            k += seg.size
            level = target
    else:
        b, a = _lowpass(8.0, 1.0 / fs)
        x = lfilter(b, a, rng.standard_normal(n + 2000))[2000:]
    x = (x - x.min()) / np.ptp(x)
    return t, V_MAX * (0.05 + 0.9 * x)


def random_density_stage(effects, seed: int) -> DensityStage:
    """A random stage with the named effects (``EFFECTS`` and ``OUTSIDE``; ``sensor_gain``
    is applied by :func:`density_records`).

    Parameters
    ----------
    effects : iterable of str
        Effects to switch on.
    seed : int
        Random seed.

    Returns
    -------
    DensityStage
        The stage.

    Raises
    ------
    ValueError
        If an effect name is unknown.

    Examples
    --------
    >>> random_density_stage(["delay"], 0).delay_s is not None
    True
    """
    effects = set(effects)
    unknown = effects - set(EFFECTS) - set(OUTSIDE)
    if unknown:
        raise ValueError(f"effects: unknown {sorted(unknown)}; expected from "
                         f"{EFFECTS + OUTSIDE}")
    rng = np.random.default_rng(50_000 + seed)
    kw: dict = {"a_lin": rng.uniform(0.04, 0.08), "density_c": rng.uniform(0.003, 0.005),
                "density_r0": rng.uniform(8.0, 20.0)}
    span = DensityStage(**kw).span
    kw["noise"] = rng.uniform(5e-4, 1.5e-3) * span  # 0.05-0.15 % of the span
    if "rate" in effects:
        kw["rate_beta"] = rng.uniform(0.3, 0.6)
        kw["rate_tau"] = rng.uniform(0.02, 0.06)
    if "asymmetry" in effects:
        kw["asymmetry"] = rng.uniform(0.06, 0.12) * rng.choice([-1, 1])
    if "creep" in effects:
        kw["creep"] = tuple(rng.uniform(0.004, 0.012, len(CREEP_LAGS)))
    if "dynamics" in effects:
        kw["mode"] = (rng.uniform(120, 300), rng.uniform(0.08, 0.3), rng.uniform(100, 250))
    if "delay" in effects:
        kw["delay_s"] = rng.uniform(0.6e-3, 1.6e-3)
    if "drift" in effects:
        kw["thermal"] = (rng.uniform(0.01, 0.025) * span * rng.choice([-1, 1]),
                         rng.uniform(10.0, 40.0))
    if "second_input" in effects:
        kw["second_input"] = rng.uniform(0.01, 0.02) * span
    if "clipping" in effects:
        kw["clip"] = rng.uniform(0.8, 0.88)
    return DensityStage(**kw)


def density_records(effects, seed: int, kind: str = "mixed", duration: float = 5.0):
    """Train and validate records of a random stage with the named effects.

    Train starts at ``t = 0``; validate starts 2 s after train ends (one clock). Each record
    starts at rest at 0 V and ramps to its first level in 0.2 s. With
    ``kind="mixed"`` train is a multisine then ramps to held levels, validate a chirp then
    band-limited random input (each part ``duration / 2``); otherwise both records are of
    that kind (other seeds). ``sensor_gain`` scales the validate record by 1.04-1.08.

    Parameters
    ----------
    effects : iterable of str
        Effects (see :func:`random_density_stage`).
    seed : int
        Random seed of the stage, the inputs and the noise.
    kind : str
        ``"mixed"`` or one of ``INPUT_KINDS``.
    duration : float
        Length of each record [s].

    Returns
    -------
    tuple
        ``(train, validate)``, each a :class:`pimodel.records.Record`.

    Examples
    --------
    >>> tr, va = density_records([], 0, duration=1.0)
    >>> round(float(va.t[0] - tr.t[-1]), 4), tr.t.size
    (2.0, 2400)
    """
    from ..records import Record

    if kind == "mixed":
        parts = (("multisine", "ramps"), ("chirp", "random"))
    elif kind in INPUT_KINDS:
        parts = ((kind,), (kind,))
    else:
        raise ValueError(f"kind: expected 'mixed' or one of {INPUT_KINDS}, got {kind!r}")
    stage = random_density_stage(set(effects) - {"sensor_gain"}, seed)
    rng = np.random.default_rng(90_000 + seed)
    gain = rng.uniform(1.04, 1.08) if "sensor_gain" in effects else 1.0
    out, t0 = [], 0.0
    for i, kinds in enumerate(parts):
        vs = [density_input(k, 7 * seed + 3 * i + j, duration / len(kinds))[1]
              for j, k in enumerate(kinds)]
        v = np.concatenate([np.linspace(0.0, vs[0][0], int(0.2 * FS), endpoint=False)] + vs)
        t = t0 + np.arange(v.size) / FS
        y = stage.simulate(t, v, rng, gain=gain if i == 1 else 1.0)
        out.append(Record(t, v, y, source=f"density-{('train', 'validate')[i]}"))
        t0 = t[-1] + 2.0
    return out[0], out[1]
