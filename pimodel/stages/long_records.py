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

from ..checks import integer_in, positive_scalar
from ..operators.pi import PIOperator

__all__ = [
    "noisy_output_chunks",
    "record_length",
]


def record_length(fs: float, duration: float) -> int:
    """Number of samples of a record: ``N = round(fs * duration)``.

    Parameters
    ----------
    fs : float
        Sampling rate [Hz], ``> 0``.
    duration : float
        Record length [s], ``> 0``.

    Returns
    -------
    int
        ``N``, at least 2.

    Raises
    ------
    ValueError
        If ``fs`` or ``duration`` is not ``> 0``, or the record would have fewer than 2
        samples.

    Examples
    --------
    >>> from pimodel.stages.long_records import record_length
    >>> record_length(1e4, 6000)
    60000000
    """
    n = int(round(positive_scalar(fs, "fs") * positive_scalar(duration, "duration")))
    if n < 2:
        raise ValueError(f"fs * duration: expected at least 2 samples, got {n}")
    return n


def _clean_chunks(op: PIOperator, input_at: Callable[[np.ndarray], np.ndarray], fs: float,
                  n: int, chunk: int) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    state = None
    for a in range(0, n, chunk):
        t = np.arange(a, min(n, a + chunk), dtype=float)  # exact integers, then in place:
        t /= fs  # the values of np.arange(a, b) / fs without a temporary integer array
        v = np.asarray(input_at(t), dtype=float)
        if v.shape != t.shape:
            raise ValueError(f"input_at: expected an array shaped like its argument {t.shape}, "
                             f"got {v.shape}")
        y, state = op.simulate(v, state=state, return_state=True)
        yield v, y


def noisy_output_chunks(op: PIOperator, input_at: Callable[[np.ndarray], np.ndarray], *,
                        fs: float, duration: float, snr_db: float, rng: np.random.Generator,
                        chunk: int = 1_000_000) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield a long noisy record of ``op``'s output in chunks.

    The record is sampled at ``fs`` for ``duration``; chunk ``(v, y)`` holds
    ``v[k] = input_at(k / fs)`` and ``y[k] = PI[v][k] + w[k]`` for consecutive global indices
    ``k``, the operator continuing from chunk to chunk (from its initial state). The noise ``w``
    is white Gaussian at ``snr_db`` over the whole record (module docstring), so the clean
    output is simulated twice: once for its variance, once to yield.

    Parameters
    ----------
    op : PIOperator
        The operator that makes the clean output.
    input_at : callable
        ``input_at(t)`` maps an array of times [s] to the inputs at those times (same shape).
    fs : float
        Sampling rate [Hz], ``> 0``.
    duration : float
        Record length [s], ``> 0``.
    snr_db : float
        Signal-to-noise ratio of the whole record [dB], finite.
    rng : numpy.random.Generator
        Source of the noise.
    chunk : int, optional
        Largest chunk, in samples (``>= 2``).

    Yields
    ------
    v : numpy.ndarray of float
        The input samples of the chunk.
    y : numpy.ndarray of float
        The noisy output samples of the chunk.

    Raises
    ------
    ValueError
        If ``fs``, ``duration`` or ``chunk`` is out of range, ``snr_db`` is not finite, or
        ``input_at`` returns an array of another shape.

    See Also
    --------
    pimodel.identification.adaptive.radius_estimator.stream_tail_average
        Consumes such chunks with a RadiusEstimator.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> from pimodel.stages.long_records import noisy_output_chunks
    >>> op = PIOperator([1.0, 0.5], [0.0, 0.3])
    >>> chunks = noisy_output_chunks(op, lambda t: np.sin(2 * np.pi * t), fs=1000.0,
    ...                              duration=2.5, snr_db=30, rng=np.random.default_rng(0),
    ...                              chunk=1000)
    >>> [v.size for v, y in chunks]
    [1000, 1000, 500]
    """
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
