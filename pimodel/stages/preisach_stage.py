"""A second truth generator, written independently of the diagnosis' candidate library and of
pimodel's operator code (numpy and scipy only), for testing the diagnosis on data it was not
built from.

Signal path, sampled at ``dt`` (input in V, output in um):
``v -> [dead zone] -> Preisach hysteresis (rate-dependent width) -> static map (asymmetry)
-> log-law creep -> two modes -> fractional delay -> + drift + [second input] + AR(1) noise``.

- hysteresis: ``y_h = k v + P[v]``, ``P`` a Preisach model with the density
  ``mu(a, b) = c exp(-(a - b) / h0)`` on ``-U <= b <= a <= U``, evaluated exactly from its
  Everett function and the memory of alternating dominant extrema (wiping-out property),
  starting from negative saturation; ``rate`` scales the hysteretic part ``P`` by
  ``1 + rate rho[k]``, ``rho`` the input rate over RATE_REF low-passed at 20 ms, so loops widen
  at high input rates; ``bouc_wen`` (outside the PI class) replaces ``P`` by a Bouc-Wen
  element ``dz/dt = A v' - beta |v'| z - gamma v' |z|``;
- asymmetry: the fixed map ``u -> (exp(a u) - 1) / a`` on the normalised output;
- creep: log law, each output increment ``dh`` at time ``t_j`` adds
  ``c dh log10(1 + (t - t_j) / TAU0)`` (superposition, FFT convolution);
- dynamics: two modes in parallel (static gain 1);
- delay: fractional, by linear interpolation;
- drift: ``d t`` on the clock the records share (``"absolute"``) or ``d (t - t[0])`` on each
  record's own clock (``"record"``);
- outside the diagnosis' vocabulary: a dead zone on the input, and a second input (a random
  slow disturbance) the model does not see;
- noise: white plus first-order autoregressive (coloured) noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import cont2discrete, fftconvolve, lfilter

__all__ = [
    "AltTruth",
    "excitations",
    "random_alt_truth",
]

FS = 5000.0  # Hz
RATE_REF = 100.0  # V/s
TAU0 = 0.01  # s, creep log-law time scale
U_SAT = 1.2  # V, Preisach saturation
EFFECTS = ("creep", "dynamics", "delay", "asymmetry", "drift", "rate")
OUTSIDE = ("dead_zone", "second_input", "bouc_wen")


@dataclass
class AltTruth:
    """A stage with Preisach (or Bouc-Wen) hysteresis and optional unmodelled effects;
    ``None`` switches an effect off (see the module docstring). Input in V, output in um.

    Parameters
    ----------
    k_lin : float
        Linear part ``k`` [um/V].
    preisach_c : float
        Preisach density scale ``c`` [um/V^2].
    preisach_h0 : float
        Decay ``h0`` of the density in ``a - b`` [V].
    bouc_wen : bool
        Bouc-Wen instead of Preisach hysteresis.
    bw_a : float
        Bouc-Wen ``A`` [um/V].
    bw_beta : float
        Bouc-Wen ``beta`` [1/V].
    bw_gamma : float
        Bouc-Wen ``gamma`` [1/V].
    rate : float or None
        Relative growth of the Preisach part per ``RATE_REF`` of (low-passed) input rate.
    asymmetry : float or None
        Exponent ``a`` of the static map ``u -> (exp(a u) - 1) / a``.
    creep : float or None
        Fraction of a move added per decade of time (log law).
    modes : tuple or None
        ``((f1, zeta1, gain1), (f2, zeta2, gain2))``: modes in parallel [Hz, -, -].
    delay_s : float or None
        Fractional output delay [s].
    drift : float or None
        Linear drift [um/s].
    drift_clock : str
        ``"absolute"``: on ``t`` as given; ``"record"``: on ``t - t[0]`` of each record.
    dead_zone : float or None
        Half width of a dead zone on the input [V].
    second_input : float or None
        Amplitude of a slow random disturbance the model does not see [um].
    noise : float
        Standard deviation of the white noise [um]; the AR(1) part has the same size.
    noise_ar : float
        Pole of the AR(1) noise.

    Examples
    --------
    >>> AltTruth(creep=0.01, dead_zone=0.2).effects  # the dead zone is outside the vocabulary
    ['creep']
    """

    k_lin: float = 6.0  # um/V
    preisach_c: float = 8.0  # um/V^2, density scale
    preisach_h0: float = 0.3  # V, density decay in a - b
    bouc_wen: bool = False
    bw_a: float = 4.0  # um/V
    bw_beta: float = 3.0  # 1/V
    bw_gamma: float = 1.0  # 1/V
    rate: float | None = None
    asymmetry: float | None = None
    creep: float | None = None  # fraction of a move per decade of time
    modes: tuple | None = None  # ((f1, zeta1, gain1), (f2, zeta2, gain2))
    delay_s: float | None = None
    drift: float | None = None  # um/s
    drift_clock: str = "absolute"
    dead_zone: float | None = None  # V, half width
    second_input: float | None = None  # um, amplitude of the unseen disturbance
    noise: float = 0.005  # um, white part; the AR(1) part has the same size
    noise_ar: float = 0.7

    @property
    def effects(self) -> list[str]:
        on = {"creep": self.creep, "dynamics": self.modes, "delay": self.delay_s,
              "asymmetry": self.asymmetry, "drift": self.drift, "rate": self.rate}
        return [k for k, v in on.items() if v is not None]

    def everett(self, a: float, b: float) -> float:
        """Preisach weight of the triangle ``b <= beta <= alpha <= a`` (``a >= b``).

        Parameters
        ----------
        a : float
            Upper switching value [V].
        b : float
            Lower switching value [V].

        Returns
        -------
        float
            The Everett function ``E(a, b)`` [um].

        Examples
        --------
        >>> truth = AltTruth()
        >>> float(truth.everett(0.5, 0.5)), round(float(truth.everett(1.0, 0.0)), 4)
        (0.0, 1.7057)
        """
        d, h0 = a - b, self.preisach_h0
        return self.preisach_c * h0 * (d - h0 * (1.0 - np.exp(-d / h0)))

    def preisach(self, v: np.ndarray) -> np.ndarray:
        """Preisach output ``P[v][k]`` from negative saturation: ``-E(U, -U) + 2 sum_k
        (E(M_k, m_{k-1}) - E(M_k, m_k))`` over the alternating dominant extrema.

        Parameters
        ----------
        v : numpy.ndarray
            Input ``v[k]`` [V], clipped to ``+-U_SAT``.

        Returns
        -------
        numpy.ndarray
            ``P[v][k]`` [um]; ``y[k]`` depends on ``v[0..k]``.

        Examples
        --------
        >>> p = AltTruth().preisach(np.array([-1.2, 1.2, 0.0, 1.2]))
        >>> bool(np.isclose(p[0], -p[1])), bool(np.isclose(p[3], p[1]))  # saturations
        (True, True)
        """
        ext = [-U_SAT]  # m0, M1, m1, M2, ...: even index a minimum, odd a maximum; last = input
        out = np.empty(v.size)
        e_sat = self.everett(U_SAT, -U_SAT)
        for k, u in enumerate(np.clip(v, -U_SAT, U_SAT)):
            out[k] = self.preisach_step(ext, u, e_sat)
        return out

    def preisach_step(self, ext: list, u: float, e_sat: float) -> float:
        """One sample of :meth:`preisach`: ``ext`` (the alternating dominant extrema, from
        ``[-U_SAT]`` at negative saturation) is updated in place with the input ``u``.

        Parameters
        ----------
        ext : list of float
            The memory, ``[m0, M1, m1, M2, ...]``, the last entry the previous input.
        u : float
            Input [V], within ``+-U_SAT``.
        e_sat : float
            ``everett(U_SAT, -U_SAT)``.

        Returns
        -------
        float
            ``P`` after ``u`` [um].

        Examples
        --------
        >>> truth, ext = AltTruth(), [-U_SAT]
        >>> e_sat = truth.everett(U_SAT, -U_SAT)
        >>> ys = [truth.preisach_step(ext, u, e_sat) for u in (0.0, 0.5, 0.2)]
        >>> bool(np.allclose(ys, truth.preisach(np.array([0.0, 0.5, 0.2])))), len(ext)
        (True, 3)
        """
        last_is_max = len(ext) % 2 == 0
        if len(ext) == 1:
            if u > ext[0]:
                ext.append(u)
        elif (last_is_max and u >= ext[-1]) or (not last_is_max and u <= ext[-1]):
            ext[-1] = u
        else:
            ext.append(u)
        while len(ext) >= 4 and ((len(ext) % 2 == 0 and ext[-1] >= ext[-3]) or
                                 (len(ext) % 2 == 1 and ext[-1] <= ext[-3])):
            del ext[-3:-1]
        if len(ext) == 3 and ext[-1] <= ext[0]:
            del ext[1:]
        y = -e_sat
        for i in range(1, len(ext), 2):
            y += 2 * self.everett(ext[i], ext[i - 1])
            if i + 1 < len(ext):
                y -= 2 * self.everett(ext[i], ext[i + 1])
        return y

    def hysteresis(self, v: np.ndarray, dt: float) -> np.ndarray:
        """``k v[k] + P[v][k]`` (Preisach, rate-dependent width) or, with ``bouc_wen``, the
        Bouc-Wen output ``k v[k] + z[k]`` (explicit sub-stepped integration, ``z = 0`` at the
        start).

        Parameters
        ----------
        v : numpy.ndarray
            Input ``v[k]`` [V].
        dt : float
            Sample time [s] (for the rate dependence).

        Returns
        -------
        numpy.ndarray
            The hysteresis output [um].

        Examples
        --------
        >>> AltTruth(preisach_c=0.0).hysteresis(np.array([0.0, 0.5]), 2e-4).tolist()
        [0.0, 3.0]
        """
        if not self.bouc_wen:
            p = self.preisach(v)
            if self.rate is not None:
                rho = np.abs(np.diff(v, prepend=v[0])) / dt / RATE_REF
                a = np.exp(-dt / 0.02)
                rho = lfilter([1 - a], [1, -a], rho)
                p = p * (1.0 + self.rate * rho)
            return self.k_lin * v + p
        z = 0.0
        out = np.empty(v.size)
        dv = np.diff(v, prepend=v[0])
        for i in range(v.size):
            z = self.bouc_wen_step(z, dv[i])
            out[i] = self.k_lin * v[i] + z
        return out

    def bouc_wen_step(self, z: float, dv: float) -> float:
        """One sample of the Bouc-Wen element (20 explicit sub-steps of the input change).

        Parameters
        ----------
        z : float
            The element's state before the sample [um].
        dv : float
            Input change over the sample [V].

        Returns
        -------
        float
            The state after the sample [um].

        Examples
        --------
        >>> round(AltTruth().bouc_wen_step(0.0, 0.01), 6)  # about bw_a dv, less the damping
        0.039249
        """
        sub = 20
        step = dv / sub
        for _ in range(sub):
            z += self.bw_a * step - (self.bw_beta * abs(step) * z
                                     + self.bw_gamma * step * abs(z))
        return z

    def simulate(self, t: np.ndarray, v: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Measured output ``y[k]`` [um] for input ``v[k]`` [V] at times ``t[k]`` [s].

        Parameters
        ----------
        t : numpy.ndarray
            Sample times [s], constant step.
        v : numpy.ndarray
            Input ``v[k]`` [V].
        rng : numpy.random.Generator
            Source of the noise and of the second input.

        Returns
        -------
        numpy.ndarray
            ``y[k]`` [um], same length as ``v``.

        Examples
        --------
        >>> t = np.arange(3) * 2e-4
        >>> AltTruth(preisach_c=0.0, noise=0.0).simulate(t, np.array([0.0, 0.5, 1.0]),
        ...                                              np.random.default_rng(0)).tolist()
        [0.0, 3.0, 6.0]
        """
        dt = float(t[1] - t[0])
        x = v
        if self.dead_zone is not None:
            x = np.sign(v) * np.maximum(np.abs(v) - self.dead_zone, 0.0)
        y = self.hysteresis(x, dt)
        if self.asymmetry is not None:
            c, half = 0.0, 6.0
            u = (y - c) / half
            a = self.asymmetry
            y = c + half * (np.exp(a * u) - 1.0) / a
        if self.creep is not None:
            kern = self.creep * np.log10(1.0 + np.arange(y.size) * dt / TAU0)
            dh = np.diff(y, prepend=y[0])
            y = y + fftconvolve(dh, kern)[: y.size]
        if self.modes is not None:
            out = np.zeros_like(y)
            for fn, zeta, gain in self.modes:
                w = 2 * np.pi * fn
                b, a, _ = cont2discrete(([gain * w * w], [1.0, 2 * zeta * w, w * w]), dt)
                b = np.ravel(b)
                out += lfilter(b, a, y - y[0]) + gain * y[0]
            y = out
        if self.delay_s is not None:
            y = np.interp(t - self.delay_s, t, y)
        if self.drift is not None:
            y = y + self.drift * (t if self.drift_clock == "absolute" else t - t[0])
        if self.second_input is not None:
            u2 = lfilter([0.002], [1, -0.998], rng.normal(0, 1, y.size))
            y = y + self.second_input * u2 / (np.std(u2) or 1.0)
        ar = lfilter([np.sqrt(1 - self.noise_ar**2)], [1, -self.noise_ar],
                     rng.normal(0, self.noise, y.size))
        return y + rng.normal(0, self.noise, y.size) + ar


def excitations(seed: int) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """Train and validate inputs ``(t, v)`` [s, V] at 5 kHz on one clock (validate starts 1 s
    after train ends). Train: three 8 Hz sine cycles, a 25 Hz sine with decaying amplitude,
    holds; validate: three 12.5 Hz triangle cycles, nested decaying 5 Hz minor loops, holds.

    Parameters
    ----------
    seed : int
        Seed of the hold levels.

    Returns
    -------
    tuple
        ``((t_train, v_train), (t_validate, v_validate))``, arrays [s] and [V].

    Examples
    --------
    >>> (t_tr, v_tr), (t_va, v_va) = excitations(seed=0)
    >>> round(float(t_va[0] - t_tr[-1]), 6), t_tr.size, t_va.size
    (1.0, 8275, 9200)
    """
    rng = np.random.default_rng(seed)
    dt = 1.0 / FS

    def sine(f, n_cyc, amp):
        tt = np.arange(int(round(n_cyc * FS / f))) * dt
        return amp * np.sin(2 * np.pi * f * tt)

    def holds(n):
        return np.concatenate([np.full(int(0.2 * FS), lv) for lv in rng.uniform(-0.8, 0.8, n)])

    tr = np.concatenate((sine(8, 3, 1.0), sine(25, 12, 1.0) * np.linspace(1, 0.2, int(
        round(12 * FS / 25))), holds(4)))
    f = 12.5
    tt = np.arange(int(round(3 * FS / f))) * dt
    tri = 0.9 * (2 / np.pi) * np.arcsin(np.sin(2 * np.pi * f * tt))
    n5 = int(round(4 * FS / 5))
    dec = np.sin(2 * np.pi * 5 * np.arange(n5) * dt) * np.linspace(0.9, 0.1, n5)
    va = np.concatenate((tri, dec, holds(4)))
    t_tr = np.arange(tr.size) * dt
    t_va = t_tr[-1] + 1.0 + np.arange(va.size) * dt
    return (t_tr, tr), (t_va, va)


def random_alt_truth(effects, seed: int, drift_clock: str = "absolute") -> AltTruth:
    """An :class:`AltTruth` with the named effects (from ``EFFECTS`` and ``OUTSIDE``) at random
    realistic magnitudes (seeded); a drift runs on ``drift_clock`` (``"absolute"``: the clock
    the records share, ``"record"``: each record's own).

    Parameters
    ----------
    effects : iterable of str
        Names from ``EFFECTS`` and ``OUTSIDE``.
    seed : int
        Seed of the magnitudes.
    drift_clock : str
        Clock of a drift.

    Returns
    -------
    AltTruth
        The stage (its hysteresis parameters are also drawn at random).

    Raises
    ------
    ValueError
        If an effect is in neither ``EFFECTS`` nor ``OUTSIDE``.

    Examples
    --------
    >>> truth = random_alt_truth(["creep", "dead_zone"], seed=0)
    >>> truth.effects, 0.15 <= truth.dead_zone <= 0.25
    (['creep'], True)
    """
    unknown = set(effects) - set(EFFECTS) - set(OUTSIDE)
    if unknown:
        raise ValueError(f"effects: unknown {sorted(unknown)}; known: {EFFECTS + OUTSIDE}")
    rng = np.random.default_rng(5000 + seed)
    kw: dict = {"k_lin": rng.uniform(5, 7), "preisach_c": rng.uniform(6, 10),
                "preisach_h0": rng.uniform(0.2, 0.4), "bouc_wen": "bouc_wen" in effects,
                "bw_a": rng.uniform(3, 5),
                "bw_beta": rng.uniform(2, 4), "bw_gamma": rng.uniform(0.5, 1.5),
                "noise": rng.uniform(0.003, 0.008)}
    if "rate" in effects:
        kw["rate"] = rng.uniform(0.5, 1.0)
    if "asymmetry" in effects:
        kw["asymmetry"] = rng.uniform(0.15, 0.3) * rng.choice([-1, 1])
    if "creep" in effects:
        kw["creep"] = rng.uniform(0.01, 0.02)
    if "dynamics" in effects:
        f1 = rng.uniform(300, 800)
        g2 = rng.uniform(0.1, 0.3)
        kw["modes"] = ((f1, rng.uniform(0.05, 0.2), 1 - g2),
                       (rng.uniform(1.5, 2.0) * f1, rng.uniform(0.05, 0.2), g2))
    if "delay" in effects:
        kw["delay_s"] = rng.uniform(0.4e-3, 1.2e-3)
    if "drift" in effects:
        kw["drift"] = rng.uniform(0.1, 0.2) * rng.choice([-1, 1])
        kw["drift_clock"] = drift_clock
    if "dead_zone" in effects:
        kw["dead_zone"] = rng.uniform(0.15, 0.25)
    if "second_input" in effects:
        kw["second_input"] = rng.uniform(0.2, 0.4)
    return AltTruth(**kw)
