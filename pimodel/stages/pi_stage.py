"""Truth simulator for tests and studies: a piezo stage with PI hysteresis (optionally
asymmetric) plus any combination of unmodelled effects, and a set of excitations.

Signal path, sampled at ``dt``: ``v -> PI -> h -> asymmetry -> creep -> mode -> delay -> + drift
+ noise -> y``. Magnitudes follow real piezo stages: creep 1-2 % of the last move per decade of
time, first mode 0.5-3 kHz with damping 0.02-0.1, delays of tens to hundreds of microseconds,
sensor noise of a few nm to 0.1 um. This module only generates data; the diagnosis never
imports it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import control
import numpy as np
from scipy.signal import lfilter, lfilter_zi

from ..checks import positive_scalar
from ..loops.actuators import delay_samples, second_order_mode
from ..operators.pi import PIOperator
from ..records import Record

__all__ = [
    "creep_lag_filters",
    "excitation",
    "random_truth",
    "rate_dependent_pi",
    "Truth",
    "zoh_coefficients",
]

STAGE_WEIGHTS = (6.3460, 1.6735, 1.1552, 0.4477)
STAGE_RADII = (0.0, 0.1945, 0.4826, 0.5707)
EFFECTS = ("creep", "dynamics", "delay", "asymmetry", "drift", "rate")
CREEP_T_MIN = 0.01  # s: the first creep lag's time constant, one lag per decade from it
CREEP_DECADES = 4  # lags at 10 ms, 100 ms, 1 s and 10 s
RATE_REFERENCE = 250.0  # V/s: the fastest validate sine (1 V at 40 Hz)
STEP_SHARE = 0.05  # a one-sample jump above this share of the input range is a step


@dataclass
class Truth:
    """A simulated stage (input in V, output in um). ``None`` switches an effect off.

    Parameters
    ----------
    weights : tuple of float
        PI play weights [um/V].
    radii : tuple of float
        PI play radii [V], ascending, the first 0 (a linear play).
    creep_percent_per_decade : float or None
        Creep: percent of the last move added per decade of time.
    mode_hz : float or None
        First mechanical mode: natural frequency [Hz] (unit static gain).
    mode_damping : float
        Its damping ratio [-].
    delay_s : float or None
        Output delay [s], rounded to whole samples.
    asymmetry : float or None
        Quadratic output term ``asymmetry h**2 / half``, ``half`` the half range of ``h``.
    drift_um_per_s : float or None
        Linear drift [um/s].
    drift_clock : str
        ``"record"``: drift on ``t - t[0]`` of each record; ``"absolute"``: on ``t`` as given.
    rate_gain : float or None
        Play radii grow with the input rate (:func:`rate_dependent_pi`).
    noise_um : float
        Standard deviation of the white output noise [um].
    extra : dict
        Free annotations (not used by the simulation).

    Examples
    --------
    >>> Truth(creep_percent_per_decade=1.5, delay_s=2e-4).effects
    ['creep', 'delay']
    """

    weights: tuple = STAGE_WEIGHTS
    radii: tuple = STAGE_RADII
    creep_percent_per_decade: float | None = None
    mode_hz: float | None = None
    mode_damping: float = 0.05
    delay_s: float | None = None
    asymmetry: float | None = None  # quadratic output term, fraction of the half range
    drift_um_per_s: float | None = None
    drift_clock: str = "record"  # "record": t - t[0] of each record; "absolute": t as given
    rate_gain: float | None = None  # play radii r_i (1 + rate_gain |dv/dt| / RATE_REFERENCE)
    noise_um: float = 0.005
    extra: dict = field(default_factory=dict)

    @property
    def effects(self) -> list[str]:
        on = {"creep": self.creep_percent_per_decade, "dynamics": self.mode_hz,
              "delay": self.delay_s, "asymmetry": self.asymmetry,
              "drift": self.drift_um_per_s, "rate": self.rate_gain}
        return [k for k, v in on.items() if v is not None]

    def simulate(self, t: np.ndarray, v: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Measured output ``y[k]`` [um] for input ``v[k]`` [V] at times ``t`` [s].

        The path ``v -> PI -> asymmetry -> creep -> mode -> delay -> + drift + noise``, plays
        and filters starting at rest (plays at 0, filters around the first sample). Creep and
        mode are zero-order-hold discretisations of their continuous systems: the creep
        (:func:`creep_lag_filters`) gives ``c[k] = x[k] + sum_i l_i[k]`` of its input ``x``
        (the lags act from the next sample), the mode is a strictly proper filter of ``c`` (one
        sample of ZOH lag).

        Parameters
        ----------
        t : numpy.ndarray
            Sample times [s], constant step.
        v : numpy.ndarray
            Input ``v[k]`` [V].
        rng : numpy.random.Generator
            Source of the noise.

        Returns
        -------
        numpy.ndarray
            ``y[k]`` [um], same length as ``v``.

        Examples
        --------
        >>> t = np.arange(4) * 1e-3
        >>> y = Truth(weights=(2.0,), radii=(0.0,), noise_um=0.0).simulate(
        ...     t, np.array([0.0, 0.5, 1.0, 0.5]), np.random.default_rng(0))
        >>> y.tolist()
        [0.0, 1.0, 2.0, 1.0]
        """
        dt = float(t[1] - t[0])
        if self.rate_gain is None:
            y = PIOperator(self.weights, self.radii).simulate(v)
        else:
            y = rate_dependent_pi(self.weights, self.radii, v, dt, self.rate_gain)
        if self.asymmetry is not None:
            half = 0.5 * float(np.sum(self.weights)) * 1.0
            y = y + self.asymmetry * (y**2) / half
        if self.creep_percent_per_decade is not None:
            y = _creep(y, self.creep_percent_per_decade, dt)
        if self.mode_hz is not None:
            y = _filter(second_order_mode(self.mode_hz, self.mode_damping), y, dt)
        if self.delay_s is not None:
            d = delay_samples(self.delay_s, dt)
            y = np.concatenate((np.full(d, y[0]), y[: y.size - d])) if d else y
        if self.drift_um_per_s is not None:
            y = y + self.drift_um_per_s * (t - t[0] if self.drift_clock == "record" else t)
        return y + rng.normal(0.0, self.noise_um, y.size)

    def record(self, t, v, seed: int, name: str = "truth") -> Record:
        """A :class:`pimodel.records.Record` of the simulated stage.

        Parameters
        ----------
        t : numpy.ndarray
            Sample times [s].
        v : numpy.ndarray
            Input [V].
        seed : int
            Seed of the noise.
        name : str
            The record's ``source``.

        Returns
        -------
        Record
            ``t``, ``v`` and the output of :meth:`simulate` [um].

        Examples
        --------
        >>> t = np.arange(3) * 1e-3
        >>> rec = Truth(weights=(2.0,), radii=(0.0,), noise_um=0.0).record(t, np.ones(3), seed=0)
        >>> rec.y.tolist()
        [2.0, 2.0, 2.0]
        """
        return Record(t, v, self.simulate(t, v, np.random.default_rng(seed)), source=name)


def rate_dependent_pi(weights, radii, v: np.ndarray, dt: float, gain: float) -> np.ndarray:
    """PI output ``y[k] = sum_i w_i z_i[k]`` with play radii that grow with the input rate,
    ``r_i[k] = r_i (1 + gain |v[k] - v[k-1]| / (dt RATE_REFERENCE))``; plays start at 0. A
    sampled step (a jump of more than ``STEP_SHARE`` of the input range in one sample) is no
    rate the stage follows: its rate counts as 0.

    Parameters
    ----------
    weights : array_like
        Play weights ``w_i`` [output units / input units].
    radii : array_like
        Play radii ``r_i`` at rest [input units].
    v : numpy.ndarray
        Input ``v[k]``.
    dt : float
        Sample time [s].
    gain : float
        Relative radius growth at the input rate ``RATE_REFERENCE`` [V/s].

    Returns
    -------
    numpy.ndarray
        ``y[k]``, same length as ``v``.

    Examples
    --------
    >>> v = np.linspace(0.0, 1.0, 41)  # a ramp at 250 V/s with dt = 0.1 ms
    >>> round(float(rate_dependent_pi([1.0], [0.1], v, 1e-4, 0.0)[-1]), 6)
    0.9
    >>> round(float(rate_dependent_pi([1.0], [0.1], v, 1e-4, 1.0)[-1]), 6)  # radius 0.2
    0.8
    """
    w, r = np.asarray(weights, float), np.asarray(radii, float)
    z = np.zeros(r.size)
    y = np.empty(v.size)
    dv = np.abs(np.diff(v, prepend=v[0]))
    rate = np.where(dv <= STEP_SHARE * float(np.ptp(v)), dv / dt / RATE_REFERENCE, 0.0)
    for k, vk in enumerate(v):
        rk = r * (1.0 + gain * rate[k])
        z = np.minimum(np.maximum(z, vk - rk), vk + rk)
        y[k] = w @ z
    return y


def creep_lag_filters(percent_per_decade: float, dt: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The truth's creep lags, one per decade from ``CREEP_T_MIN`` (``CREEP_DECADES`` of them,
    as :func:`pimodel.loops.actuators.creep_per_decade`), each discretised on its own with a
    zero-order hold (:func:`zoh_coefficients`).

    For the input ``x[k]`` (hysteresis output [um]) the creep output is
    ``c[k] = x[k] + sum_i l_i[k]``, lag ``i`` with gain ``g_i = percent_per_decade / 100``,
    time constant ``tau_i`` and ``a_i = exp(-dt / tau_i)``::

        l_i[k] = a_i l_i[k-1] + g_i (1 - a_i) x[k-1]      (b = [0, g_i (1 - a_i)], a = [1, -a_i])

    so the lags act from the next sample. Run in parallel, these are the ZOH transfer function
    ``1 + sum_i g_i (1 - a_i) / (z - a_i)`` of ``creep_per_decade``; multiplied out into one
    polynomial of degree 4 in ``z`` (poles between 0.99 and 0.99999 at 10 kHz) they lose most
    of their digits (measured in ``docs/design-notes.md``).

    Parameters
    ----------
    percent_per_decade : float
        Creep per decade of time [% of the move], finite, ``>= 0``.
    dt : float
        Sample time [s], ``> 0``.

    Returns
    -------
    list of (numpy.ndarray, numpy.ndarray)
        ``(b, a)`` of each lag, for :func:`scipy.signal.lfilter`, shortest time constant first.

    Raises
    ------
    ValueError
        If ``percent_per_decade`` or ``dt`` is out of range.

    Examples
    --------
    >>> from scipy.signal import lfilter
    >>> x = np.ones(30_001)  # a unit step held for 3 s at 10 kHz
    >>> y = x + sum(lfilter(b, a, x) for b, a in creep_lag_filters(1.5, 1e-4))
    >>> exact = 1 + np.sum(0.015 * (1 - np.exp(-3.0 / (0.01 * 10.0 ** np.arange(4)))))
    >>> bool(abs(y[-1] - exact) < 1e-12)  # y[30000]: 3 s after the step (and 1 sample)
    True
    """
    rate = float(percent_per_decade)
    if not np.isfinite(rate) or rate < 0:
        raise ValueError(f"percent_per_decade: expected a finite number >= 0, got "
                         f"{percent_per_decade!r}")
    dt = positive_scalar(dt, "dt")
    tau = CREEP_T_MIN * 10.0 ** np.arange(CREEP_DECADES)
    return [zoh_coefficients(control.tf([rate / 100.0], [ti, 1.0]), dt) for ti in tau]


def _creep(x: np.ndarray, percent_per_decade: float, dt: float) -> np.ndarray:
    """The truth's creep of ``x`` (:func:`creep_lag_filters`), lags at rest around x[0]."""
    y = x
    for b, a in creep_lag_filters(percent_per_decade, dt):
        y = y + lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])[0]
    return y


def zoh_coefficients(G, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """``(b, a)`` of a continuous SISO system discretised with a zero-order hold, for
    :func:`scipy.signal.lfilter` (coefficients of ``z^0, z^-1, ...``).

    One polynomial transfer function: fit for low orders such as the truth's mode (equal to a
    state-space ZOH simulation to ~1e-14 at 5 and 10 kHz), not for lags spread over decades
    (their poles crowd near ``z = 1``; see :func:`creep_lag_filters`).

    Parameters
    ----------
    G : control.TransferFunction or LTI system
        The continuous-time system.
    dt : float
        Sample time [s].

    Returns
    -------
    b, a : numpy.ndarray
        Numerator and denominator, of equal length.

    Examples
    --------
    >>> from pimodel.loops.actuators import second_order_mode
    >>> b, a = zoh_coefficients(second_order_mode(1000.0, 0.05), 1e-4)
    >>> b.size == a.size, round(float(b.sum() / a.sum()), 12)  # unit static gain
    (True, 1.0)
    """
    Gd = control.c2d(control.tf(G), dt, method="zoh")
    a = np.ravel(Gd.den[0][0])
    b = np.ravel(Gd.num[0][0])
    return np.concatenate((np.zeros(a.size - b.size), b)), a


def _filter(G, x: np.ndarray, dt: float) -> np.ndarray:
    """Apply a continuous SISO system (ZOH-discretised, :func:`zoh_coefficients`) to ``x``,
    starting at rest around x[0]."""
    b, a = zoh_coefficients(G, dt)
    out, _ = lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])
    return out


def excitation(kind: str, *, fs: float = 10_000.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Standard excitations (input in V, peak 1 V): ``train`` (triangles at 2 and 20 Hz, minor
    loops, steps with 0.2 s holds) and ``validate`` (sines at 5 and 40 Hz, minor loops, steps
    with holds); ``train`` lasts 3.0 s, ``validate`` 2.4 s.

    Parameters
    ----------
    kind : str
        ``"train"`` or ``"validate"``.
    fs : float
        Sample rate [Hz].
    seed : int
        Seed of the step levels.

    Returns
    -------
    t, v : numpy.ndarray
        Sample times from 0 [s] and input [V].

    Raises
    ------
    ValueError
        If ``kind`` is neither ``"train"`` nor ``"validate"``.

    Examples
    --------
    >>> t, v = excitation("train", fs=1000.0)
    >>> round(float(t[-1]), 1), round(float(np.max(np.abs(v))), 3)
    (3.0, 1.0)
    """
    rng = np.random.default_rng(seed)
    dt = 1.0 / fs
    parts = []

    def tri(freq, amp, periods):
        n = int(round(periods * fs / freq))
        tt = np.arange(n) * dt
        ph = (tt * freq + 0.25) % 1.0
        return -amp * (4 * np.abs(ph - 0.5) - 1)

    def sine(freq, amp, periods):
        tt = np.arange(int(round(periods * fs / freq))) * dt
        return amp * np.sin(2 * np.pi * freq * tt)

    def steps(levels, hold):
        return np.concatenate([np.full(int(round(hold * fs)), lv) for lv in levels])

    lv = rng.uniform(-0.9, 0.9, 6)
    if kind == "train":
        parts = [tri(2, 1.0, 2), tri(20, 1.0, 10), tri(20, 0.5, 6), steps(lv, 0.2)]
    elif kind == "validate":
        parts = [sine(5, 1.0, 3), sine(40, 1.0, 16), sine(40, 0.6, 8), steps(lv, 0.2)]
    else:
        raise ValueError(f"kind: expected 'train' or 'validate', got {kind!r}")
    v = np.concatenate(parts)
    return np.arange(v.size) * dt, v


def random_truth(effects, seed: int, drift_clock: str = "record") -> Truth:
    """A truth with the named effects at random realistic magnitudes (seeded); a drift runs on
    ``drift_clock`` (``"record"``: each record's own clock, ``"absolute"``: ``t`` as given).

    Parameters
    ----------
    effects : iterable of str
        Names from ``EFFECTS``.
    seed : int
        Seed of the magnitudes.
    drift_clock : str
        Clock of a drift.

    Returns
    -------
    Truth
        The nominal stage (``STAGE_WEIGHTS``, ``STAGE_RADII``) with those effects and a noise
        of 3-10 nm.

    Raises
    ------
    ValueError
        If an effect is not in ``EFFECTS``.

    Examples
    --------
    >>> truth = random_truth(["dynamics", "delay"], seed=1)
    >>> truth.effects, 500 <= truth.mode_hz <= 3000
    (['dynamics', 'delay'], True)
    """
    rng = np.random.default_rng(1000 + seed)
    unknown = set(effects) - set(EFFECTS)
    if unknown:
        raise ValueError(f"effects: unknown {sorted(unknown)}; known: {EFFECTS}")
    kw = {}
    if "creep" in effects:
        kw["creep_percent_per_decade"] = rng.uniform(1.0, 2.0)
    if "dynamics" in effects:
        kw["mode_hz"] = rng.uniform(500, 3000)
        kw["mode_damping"] = rng.uniform(0.02, 0.1)
    if "delay" in effects:
        kw["delay_s"] = rng.uniform(100e-6, 400e-6)
    if "asymmetry" in effects:
        kw["asymmetry"] = rng.uniform(0.03, 0.08) * rng.choice([-1, 1])
    if "drift" in effects:
        kw["drift_um_per_s"] = rng.uniform(0.05, 0.15) * rng.choice([-1, 1])
    if "rate" in effects:
        kw["rate_gain"] = rng.uniform(0.3, 0.6)
    return Truth(noise_um=rng.uniform(0.003, 0.01), drift_clock=drift_clock, **kw)
