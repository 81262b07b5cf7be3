"""identify on long records: the estimator's passes and the slopes' pooled branches are never
built as whole arrays, and give the values of the joined arrays they replace."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from pimodel import PIOperator, identify
from pimodel.identification import chain
from pimodel.identification.branches import split_branches
from pimodel.identification.slopes import _pool_branches


@pytest.mark.parametrize("first", [0, 37])
@pytest.mark.parametrize("passes", [1, 2, 4])
@pytest.mark.parametrize("chunk", [1, 250, 963, 1000, 5000])
def test_repeated_chunks_are_the_joined_passes_sliced(first, passes, chunk):
    rng = np.random.default_rng(passes * 10_000 + chunk)
    v, y = rng.normal(size=1000), rng.normal(size=1000)
    offset = 0.3
    vv = np.concatenate([v] + [v[first:]] * (passes - 1))
    yy = np.concatenate([y] + [y[first:]] * (passes - 1)) - offset
    shares: list[float] = []
    got = list(chain._repeated_chunks(v, y, offset, first, passes, chunk, shares.append))
    assert len(got) == -(-vv.size // chunk)
    for j, (cv, cy) in enumerate(got):
        assert np.array_equal(cv, vv[j * chunk:(j + 1) * chunk])
        assert np.array_equal(cy, yy[j * chunk:(j + 1) * chunk])
    assert shares[0] == 0.0
    assert all(0 <= a < b < 1 for a, b in zip(shares, shares[1:], strict=False))


def _whole_pool(v, y, threshold, min_travel_fraction, max_points):
    """The definition: every kept branch's samples joined, then evenly thinned."""
    branches = [b for b in split_branches(v, threshold) if b.from_reversal]
    travel = np.array([abs(v[b.stop - 1] - v[b.start]) for b in branches])
    keep = [b for b, tr in zip(branches, travel, strict=True)
            if tr >= min_travel_fraction * travel.max()]
    x = np.concatenate([np.abs(v[b.start:b.stop] - v[b.start]) for b in keep])
    Y = np.concatenate([b.direction * y[b.start:b.stop] for b in keep])
    g = np.concatenate([np.full(b.stop - b.start, i) for i, b in enumerate(keep)])
    if x.size > max_points:
        sel = np.linspace(0, x.size - 1, max_points).astype(int)
        x, Y, g = x[sel], Y[sel], g[sel]
    return x, Y, g, len(keep)


@pytest.mark.parametrize("max_points", [50, 777, 10_000, 10**9])
def test_pooled_branches_are_the_whole_pool_thinned(max_points):
    rng = np.random.default_rng(max_points % 1000)
    v = np.cumsum(rng.normal(size=20_000))  # a random walk: branches of every length
    y = PIOperator([1.0, 0.5], [0.0, 2.0]).simulate(v) + rng.normal(0, 0.01, v.size)
    got = _pool_branches(v, y, 0.05 * np.ptp(v), 0.3, max_points)
    want = _whole_pool(v, y, 0.05 * np.ptp(v), 0.3, max_points)
    assert got[3] == want[3] > 5
    for a, b in zip(got[:3], want[:3], strict=True):
        assert np.array_equal(a, b)


def _record(n):
    t = np.arange(n) * 1e-4
    v = 10 * np.sin(2 * np.pi * 5 * t) * (1 + 0.3 * np.sin(2 * np.pi * 0.3 * t))
    y = PIOperator([1.0, 0.5, 0.3], [0.0, 1.0, 3.0]).simulate(v)
    return v, y + np.random.default_rng(0).normal(0, 0.01, n)


def _traced(func):
    """``func()``'s result and the peak of memory it traced [bytes] (from its start)."""
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        out = func()
        return out, tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()


def test_pooled_branches_hold_the_thinned_pool_only():
    """400k samples thinned to 10k: beyond finding the branches, the pool of every branch (3
    columns, joined: 6) is never built."""
    n = 400_000
    rng = np.random.default_rng(5)
    v = np.cumsum(rng.normal(size=n))
    y = PIOperator([1.0, 0.5], [0.0, 2.0]).simulate(v)
    thr = 0.05 * np.ptp(v)
    _, split = _traced(lambda: split_branches(v, thr))
    got, peak = _traced(lambda: _pool_branches(v, y, thr, 0.3, 10_000))
    assert got[0].size == 10_000
    extra = (peak - split) / (8 * n)
    assert extra < 0.5, f"the pool held {extra:.1f} columns of the record beyond the branches'"


@pytest.mark.slow  # over ~4 s: left out of the quick tier (quickstart.sh quick)
def test_estimator_passes_hold_no_repeated_record(monkeypatch):
    """identify's long-record path (history not kept, no batch refinement; forced here on a
    400k-sample record, chunks of 20k) runs the estimator's passes without joining them (2
    columns per pass held before); its tail mean does not depend on the chunking."""
    monkeypatch.setattr(chain, "HISTORY_LIMIT", 10_000)
    monkeypatch.setattr(chain, "REFINE_LIMIT", 0)
    monkeypatch.setattr(chain, "PROGRESS_CHUNK", 20_000)
    n = 400_000
    v, y = _record(n)
    stage: dict[str, float] = {}

    def progress(message):
        if "%" in message:
            return
        now = tracemalloc.get_traced_memory()[0]
        if message.startswith("loop slopes"):
            stage["before"] = now
        elif message.startswith("radius estimator"):
            tracemalloc.reset_peak()
            stage["start"] = now
        elif "start" in stage and "peak" not in stage:
            stage["peak"] = tracemalloc.get_traced_memory()[1] - stage["start"]
            stage["held"] = now - stage["before"]

    ident, _ = _traced(lambda: identify(v, y, dt=1e-4, progress=progress))
    assert ident.settings["passes"] >= 3
    held, peak = stage["held"] / (8 * n), stage["peak"] / (8 * n)
    assert held < 0.5, f"after the estimator identify still held {held:.1f} columns"
    assert peak < 3.0, f"the estimator's passes took {peak:.1f} columns of the record"
    np.testing.assert_allclose(ident.operator.radii, [0.0, 1.0, 3.0], atol=0.02)
    monkeypatch.setattr(chain, "PROGRESS_CHUNK", 7_777)  # chunks across the passes' joins
    again = identify(v, y, dt=1e-4)
    np.testing.assert_allclose(again.operator.radii, ident.operator.radii, rtol=1e-12)
    np.testing.assert_allclose(again.operator.weights, ident.operator.weights, rtol=1e-12)
