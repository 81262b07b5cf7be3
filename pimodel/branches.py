"""Monotone branches of a sampled input: reversal detection with a hysteresis threshold.

A reversal is declared when the input has moved back from its running extreme by more than
``threshold`` (input unit); the reversal sample is the extreme itself. Robust to input noise
smaller than the threshold.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from ._native import F64
from ._native import lib as _lib

_lib.pim_rev_scan_sizeof.restype = ctypes.c_size_t
_lib.pim_rev_scan_init.restype = None
_lib.pim_rev_scan_init.argtypes = [ctypes.c_void_p]
_lib.pim_rev_scan_run.restype = ctypes.c_size_t
_I64 = np.ctypeslib.ndpointer(dtype=np.int64, flags="C_CONTIGUOUS")
_lib.pim_rev_scan_run.argtypes = [ctypes.c_void_p, ctypes.c_size_t, F64, ctypes.c_double, _I64,
                                  _I64]


@dataclass(frozen=True)
class Branch:
    """Samples ``start..stop-1`` move monotonically in ``direction`` (+1 up, -1 down) from the
    reversal sample ``start`` (an input extreme; for the first branch, the first sample)."""

    start: int
    stop: int
    direction: int
    from_reversal: bool


class ReversalScanner:
    """Streaming reversal detection (C core ``fmu/src/pim_reversals.c``): feed chunks of the
    input with :meth:`scan`; returns the absolute indices of the reversals declared in them."""

    def __init__(self, threshold: float = 0.0):
        if not np.isfinite(threshold) or threshold < 0:
            raise ValueError(f"threshold: expected a finite number >= 0, got {threshold!r}")
        self.threshold = float(threshold)
        self._buf = ctypes.create_string_buffer(_lib.pim_rev_scan_sizeof())
        _lib.pim_rev_scan_init(self._buf)

    def scan(self, v: np.ndarray) -> np.ndarray:
        """Absolute sample indices (int64) of the input extremes at which the direction
        changed, for the reversals declared within these samples."""
        return self.scan_with_declaration(v)[0]

    def scan_with_declaration(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(extremes, declared)``: for each reversal declared within these samples, the
        absolute index of its extreme and of the sample at which it was declared."""
        x = np.ascontiguousarray(v, dtype=float)
        ext = np.empty(max(x.size, 1), dtype=np.int64)
        decl = np.empty_like(ext)
        cnt = _lib.pim_rev_scan_run(self._buf, x.size, x, self.threshold, ext, decl)
        return ext[:cnt].copy(), decl[:cnt].copy()


def find_reversals(v: np.ndarray, threshold: float) -> list[int]:
    """Indices of the input extremes at which the direction changes."""
    return ReversalScanner(threshold).scan(v).tolist()


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
