"""Long noisy records made chunk by chunk, so that 10^8-sample studies fit in bounded memory.

A chunk is ``(v, y)`` with ``v[k] = input_at(k / fs)`` for the global sample index k and
``y[k] = PI[v][k] + w[k]``, ``w`` white Gaussian noise. The noise level is set exactly as
:func:`pimodel.signals.add_noise_snr` sets it on the whole record:
``SNR = 10 log10(var(PI[v]) / sigma^2)`` dB, the variance taken over all N samples (a first
pass over the clean output, chunk by chunk).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np

from .checks import integer_in, positive_scalar
from .operator import PIOperator


def record_length(fs: float, duration: float) -> int:
    """Number of samples ``N = round(fs * duration)`` (at least 2)."""
    n = int(round(positive_scalar(fs, "fs") * positive_scalar(duration, "duration")))
    if n < 2:
        raise ValueError(f"fs * duration: expected at least 2 samples, got {n}")
    return n


def _clean_chunks(op: PIOperator, input_at: Callable[[np.ndarray], np.ndarray], fs: float,
                  n: int, chunk: int) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    state = None
    for a in range(0, n, chunk):
        t = np.arange(a, min(n, a + chunk)) / fs
        v = np.asarray(input_at(t), dtype=float)
        if v.shape != t.shape:
            raise ValueError(f"input_at: expected an array shaped like its argument {t.shape}, "
                             f"got {v.shape}")
        y, state = op.simulate(v, state=state, return_state=True)
        yield v, y


def noisy_output_chunks(op: PIOperator, input_at: Callable[[np.ndarray], np.ndarray], *,
                        fs: float, duration: float, snr_db: float, rng: np.random.Generator,
                        chunk: int = 1_000_000) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield ``(v, y)`` chunks of at most ``chunk`` samples of a record sampled at ``fs`` [Hz]
    for ``duration`` [s]; ``input_at(t)`` maps times [s] to inputs; ``op`` starts from its
    initial state. See the module docstring for the noise."""
    n = record_length(fs, duration)
    chunk = integer_in(chunk, "chunk", 2)
    if not np.isfinite(snr_db):
        raise ValueError(f"snr_db: expected a finite number, got {snr_db!r}")
    count, mean, m2 = 0, 0.0, 0.0
    for _, y in _clean_chunks(op, input_at, fs, n, chunk):  # Chan et al. pairwise variance
        nb, mb = y.size, float(y.mean())
        delta = mb - mean
        m2 += float(((y - mb) ** 2).sum()) + delta**2 * count * nb / (count + nb)
        mean += delta * nb / (count + nb)
        count += nb
    sigma = np.sqrt(m2 / count / 10 ** (snr_db / 10))
    for v, y in _clean_chunks(op, input_at, fs, n, chunk):
        yield v, y + rng.normal(0.0, sigma, y.size)
