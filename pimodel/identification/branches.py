"""Monotone branches of a sampled input: reversal detection with a hysteresis threshold.

A reversal is declared when the input has moved back from its running extreme by more than
``threshold`` (input unit); the reversal sample is the extreme itself. Robust to input noise
smaller than the threshold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._native import lib as _lib
from .._native import reversal_scanner

__all__ = [
    "Branch",
    "find_reversals",
    "ReversalScanner",
    "split_branches",
]



@dataclass(frozen=True)
class Branch:
    """A monotone branch of the input: samples ``start..stop-1``.

    The samples move monotonically in ``direction`` from sample ``start``, an input extreme
    (for the first branch, the first sample).

    Parameters
    ----------
    start : int
        First sample (the reversal).
    stop : int
        One past the last sample.
    direction : int
        +1 (rising) or -1 (falling).
    from_reversal : bool
        False for the first branch, which does not start at a reversal.

    Examples
    --------
    >>> from pimodel.identification.branches import split_branches
    >>> split_branches(np.array([0.0, 1.0, 2.0, 1.0, 0.0]), 0.5)[1]
    Branch(start=2, stop=5, direction=-1, from_reversal=True)
    """

    start: int
    stop: int
    direction: int
    from_reversal: bool


class ReversalScanner:
    """Streaming reversal detection (C core ``fmu/src/pim_reversals.c``).

    Feed the input in chunks of any size to :meth:`scan`; it returns the absolute indices of
    the reversals declared within each chunk. A reversal is declared once the input has moved
    back from its running extreme by more than ``threshold``; its index is the extreme's.

    Parameters
    ----------
    threshold : float, optional
        Reversal threshold (input unit), finite, ``>= 0``.

    Raises
    ------
    ValueError
        If ``threshold`` is negative or not finite.

    Examples
    --------
    >>> from pimodel.identification.branches import ReversalScanner
    >>> scanner = ReversalScanner(0.5)
    >>> scanner.scan(np.array([0.0, 1.0, 2.0])), scanner.scan(np.array([1.0, 0.0, 0.0]))
    (array([], dtype=int64), array([2]))
    """

    def __init__(self, threshold: float = 0.0):
        if not np.isfinite(threshold) or threshold < 0:
            raise ValueError(f"threshold: expected a finite number >= 0, got {threshold!r}")
        self.threshold = float(threshold)
        self._buf = reversal_scanner()

    def scan(self, v: np.ndarray) -> np.ndarray:
        """Reversals declared within the next chunk of the input.

        Parameters
        ----------
        v : numpy.ndarray of float
            The next input samples (any number).

        Returns
        -------
        numpy.ndarray of int64
            Absolute sample indices of the input extremes at which the direction changed.

        Examples
        --------
        >>> from pimodel.identification.branches import ReversalScanner
        >>> ReversalScanner(0.5).scan(np.array([0.0, 2.0, 1.0, 0.0, 1.0]))
        array([1, 3])
        """
        return self.scan_with_declaration(v)[0]

    def scan_with_declaration(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reversals declared within the next chunk, with the sample that declared each.

        Parameters
        ----------
        v : numpy.ndarray of float
            The next input samples (any number).

        Returns
        -------
        extremes : numpy.ndarray of int64
            Absolute index of each reversal's extreme.
        declared : numpy.ndarray of int64
            Absolute index of the sample at which it was declared.

        Examples
        --------
        >>> from pimodel.identification.branches import ReversalScanner
        >>> ReversalScanner(0.5).scan_with_declaration(np.array([0.0, 2.0, 1.8, 1.0]))
        (array([1]), array([3]))
        """
        x = np.ascontiguousarray(v, dtype=float)
        ext = np.empty(max(x.size, 1), dtype=np.int64)
        decl = np.empty_like(ext)
        cnt = _lib.pim_rev_scan_run(self._buf, x.size, x, self.threshold, ext, decl)
        return ext[:cnt].copy(), decl[:cnt].copy()


def find_reversals(v: np.ndarray, threshold: float) -> list[int]:
    """Indices of the input extremes at which the direction changes.

    Parameters
    ----------
    v : numpy.ndarray of float
        Input samples.
    threshold : float
        Reversal threshold (input unit), ``>= 0``: moves back smaller than it are ignored.

    Returns
    -------
    list of int
        The reversal samples, ascending.

    Raises
    ------
    ValueError
        If ``threshold`` is negative or not finite.

    Examples
    --------
    >>> from pimodel.identification.branches import find_reversals
    >>> find_reversals(np.array([0.0, 1.0, 0.9, 2.0, 0.0]), threshold=0.5)
    [3]
    """
    return ReversalScanner(threshold).scan(v).tolist()


def split_branches(v: np.ndarray, threshold: float) -> list[Branch]:
    """Monotone branches between reversals; the last branch ends at the last sample.

    Parameters
    ----------
    v : numpy.ndarray of float
        Input samples.
    threshold : float
        Reversal threshold (input unit), ``>= 0``.

    Returns
    -------
    list of Branch
        The branches in order; branches of fewer than 2 samples are left out.

    Raises
    ------
    ValueError
        If ``threshold`` is negative or not finite.

    Examples
    --------
    >>> from pimodel.identification.branches import split_branches
    >>> v = np.array([0.0, 1.0, 2.0, 1.0, 0.0, 1.0])
    >>> [(b.start, b.stop, b.direction) for b in split_branches(v, 0.5)]
    [(0, 2, 1), (2, 4, -1), (4, 6, 1)]
    """
    rev = find_reversals(v, threshold)
    edges = [0, *rev, v.size]
    out = []
    for i, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        if b - a < 2:
            continue
        d = 1 if v[b - 1] >= v[a] else -1
        out.append(Branch(a, b, d, from_reversal=i > 0))
    return out
