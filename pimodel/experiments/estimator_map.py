"""Radius estimator on the inputs users apply: input kinds, random stages, one map cell.

The inputs (:func:`input_signal`), all scaled to the range ``[lo, lo + span]``:

- ``centred sine``: 1 Hz sine, centred;
- ``offset sine``: 0.7 Hz sine on an offset (the range starts at 0: a unipolar amplifier);
- ``triangle``: 1 Hz triangle;
- ``multisine``: 4 tones between 0.3 and 2.9 Hz, random phases;
- ``random``: white noise band-limited to 5 Hz (FFT brick-wall);
- ``stair steps``: a 1 Hz triangle quantised to 40 levels, held 5 ms;
- ``decaying loops``: ``e^{-t'} sin(4 pi t')``, ``t' = t mod 4 s`` (one major loop, then
  shrinking minor loops).

:func:`random_stage` draws 3 to 7 plays whose largest loop ``2 r_n`` is at most two thirds
of the span. :func:`run_cell` runs :func:`pimodel.estimate_radii` with its defaults on one
(stage, input, noise, start) and reports the largest radius error of the online estimate and
of the polished one, relative to the largest radius, and the ratio to the Cramer-Rao bound.
"""

from __future__ import annotations

import numpy as np

from ..identification.adaptive.polish import radius_bound
from ..identification.adaptive.radius_estimator import estimate_radii
from ..operators.pi import PIOperator

__all__ = ["INPUT_KINDS", "STARTS", "input_signal", "random_stage", "run_cell"]

INPUT_KINDS = ("centred sine", "offset sine", "triangle", "multisine", "random",
               "stair steps", "decaying loops")
STARTS = ("below", "zero", "far above")
NOISE_STREAM = 1  # :func:`run_cell`'s output noise: default_rng([seed, NOISE_STREAM])


def _unit(x: np.ndarray) -> np.ndarray:
    return (x - x.min()) / np.ptp(x)


def input_signal(kind: str, t: np.ndarray, *, span: float = 1.0, seed: int = 0) -> np.ndarray:
    """The named input at times ``t`` [s], between ``0`` and ``span`` (input unit).

    Examples
    --------
    >>> v = input_signal("multisine", np.arange(0, 10, 1e-3), span=3.0)
    >>> float(v.min()), float(v.max())
    (0.0, 3.0)
    """
    rng = np.random.default_rng(seed)
    if kind in ("centred sine", "offset sine"):
        f = 1.0 if kind == "centred sine" else 0.7
        u = np.sin(2 * np.pi * f * t)
    elif kind == "triangle":
        u = np.arcsin(np.sin(2 * np.pi * t))
    elif kind == "multisine":
        u = sum(np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
                for f in (0.3, 1.1, 1.9, 2.9))
    elif kind == "random":
        w = np.fft.rfft(rng.normal(size=t.size))
        dt = t[1] - t[0] if t.size > 1 else 1.0
        w[np.fft.rfftfreq(t.size, dt) > 5.0] = 0
        u = np.fft.irfft(w, t.size)
    elif kind == "stair steps":
        held = np.floor(t / 0.005) * 0.005
        u = np.round(20 * np.arcsin(np.sin(2 * np.pi * held)))
    elif kind == "decaying loops":
        tm = np.mod(t, 4.0)
        u = np.exp(-tm) * np.sin(4 * np.pi * tm)
    else:
        raise ValueError(f"kind: expected one of {INPUT_KINDS}, got {kind!r}")
    out = span * _unit(np.asarray(u, float))
    if kind == "centred sine" or kind == "triangle" or kind == "decaying loops":
        out -= span / 2  # centred on 0
    return out


def random_stage(rng: np.random.Generator, *, span: float = 1.0,
                 n: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Weights in [0.2, 1] and sorted distinct radii with ``2 r_n <= 2 span / 3`` (3-7 plays).

    Examples
    --------
    >>> p, r = random_stage(np.random.default_rng(1))
    >>> bool(3 <= p.size <= 7 and 2 * r[-1] <= 2 / 3 + 1e-12 and np.all(np.diff(r) > 0))
    True
    """
    n = int(rng.integers(3, 8)) if n is None else n
    p = rng.uniform(0.2, 1.0, n)
    r = np.sort(rng.uniform(0.0, span / 3, n))
    while np.min(np.diff(r)) < 0.02 * span:  # distinct plays, so the radii are identifiable
        r = np.sort(rng.uniform(0.0, span / 3, n))
    return p, r


def start_radii(name: str, r: np.ndarray) -> np.ndarray:
    """Initial radii: ``below`` (0.3 x truth), ``zero``, ``far above`` (3 x the largest)."""
    if name == "below":
        return 0.3 * r
    if name == "zero":
        return np.zeros_like(r)
    if name == "far above":
        return np.full_like(r, 3 * r[-1])
    raise ValueError(f"start: expected one of {STARTS}, got {name!r}")


def run_cell(kind: str, snr_db: float | None, start: str, seed: int, *, fs: float = 1000.0,
             duration: float = 60.0) -> dict:
    """One cell: a random stage (``seed``), its input, output noise at ``snr_db`` (None:
    clean; else white Gaussian noise of standard deviation ``std(y) / 10^(snr/20)``,
    independent of the input), :func:`estimate_radii` from ``start`` with its defaults.

    Returns a dict with ``online`` and ``polished`` (largest radius error relative to the
    largest radius), ``ratio`` (largest ``|error_j| / sd_j`` of the polished estimate, sd the
    Cramer-Rao bound; None when clean) and ``n``.
    """
    rng = np.random.default_rng(seed)
    p, r = random_stage(rng)
    t = np.arange(int(round(duration * fs))) / fs
    v = input_signal(kind, t, seed=seed)
    y = PIOperator(p, r).simulate(v)
    sigma = None
    if snr_db is not None:
        sigma = float(np.std(y) / 10 ** (snr_db / 20))
        # a stream of its own: rng continues default_rng(seed), the stream input_signal's
        # band-limited random input is made of, so its draws would be that white noise
        # shifted by a few samples: output noise correlated with the input (a bias)
        y = y + np.random.default_rng([seed, NOISE_STREAM]).normal(0.0, sigma, y.size)
    res = estimate_radii(v, y, p, dt=1 / fs, initial_radii=start_radii(start, r))
    out = {"kind": kind, "snr_db": snr_db, "start": start, "seed": seed, "n": p.size,
           "online": float(np.max(np.abs(res.online_radii - r)) / r[-1]),
           "polished": float(np.max(np.abs(res.radii - r)) / r[-1]), "ratio": None}
    if sigma is not None:
        sd = radius_bound(v, p, r, sigma=sigma).sd
        out["ratio"] = float(np.max(np.abs(res.radii - r) / sd))
    return out
