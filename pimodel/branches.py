"""Monotone branches of a sampled input: reversal detection with a hysteresis threshold.

A reversal is declared when the input has moved back from its running extreme by more than
``threshold`` (input unit); the reversal sample is the extreme itself. Robust to input noise
smaller than the threshold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Branch:
    """Samples ``start..stop-1`` move monotonically in ``direction`` (+1 up, -1 down) from the
    reversal sample ``start`` (an input extreme; for the first branch, the first sample)."""

    start: int
    stop: int
    direction: int
    from_reversal: bool


def find_reversals(v: np.ndarray, threshold: float) -> list[int]:
    """Indices of the input extremes at which the direction changes."""
    rev: list[int] = []
    direction = 0
    ext_i = 0
    for k in range(1, v.size):
        if direction == 0:
            if abs(v[k] - v[0]) > threshold:
                direction = 1 if v[k] > v[0] else -1
                ext_i = k
            continue
        if direction * (v[k] - v[ext_i]) > 0:
            ext_i = k
        elif abs(v[k] - v[ext_i]) > threshold:
            rev.append(ext_i)
            direction = -direction
            ext_i = k
    return rev


def split_branches(v: np.ndarray, threshold: float) -> list[Branch]:
    """Monotone branches between reversals; the last branch ends at the last sample."""
    rev = find_reversals(v, threshold)
    edges = [0, *rev, v.size]
    out = []
    for i, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        if b - a < 2:
            continue
        d = 1 if v[b - 1] >= v[a] else -1
        out.append(Branch(a, b, d, from_reversal=i > 0))
    return out
