"""The test processes run numpy's BLAS on one thread (tests/conftest.py): quickstart.sh already
runs one pytest-xdist worker per core, and OpenBLAS' own thread per core then competes with the
other workers and spins, which made small least squares 5-10 times slower. Also the segment
programme of the piecewise-linear fit, vectorised over the end bins, against its loop form."""

from __future__ import annotations

import os

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from pimodel.identification import piecewise_linear


def test_blas_runs_on_one_thread_in_the_tests_and_their_subprocesses():
    blas = [p for p in threadpool_info() if p["user_api"] == "blas"]
    assert blas and all(p["num_threads"] == 1 for p in blas)
    assert os.environ["OPENBLAS_NUM_THREADS"] == os.environ["OMP_NUM_THREADS"] == "1"


def cuts_loop(seg, m):
    """The dynamic programme's loop over end bins j (the form before the vectorised one)."""
    G = seg.shape[0] - 1
    cost = np.full((m + 1, G + 1), np.inf)
    arg = np.zeros((m + 1, G + 1), dtype=int)
    cost[0, 0] = 0.0
    for s in range(1, m + 1):
        for j in range(1, G + 1):
            cand = cost[s - 1, :j] + seg[:j, j]
            arg[s, j] = int(np.argmin(cand))
            cost[s, j] = cand[arg[s, j]]
    cuts, j = [], G
    for s in range(m, 0, -1):
        j = arg[s, j]
        cuts.append(j)
    return sorted(cuts)[1:]


@pytest.mark.parametrize("seed", range(6))
def test_segment_programme_equals_its_loop_form_to_the_bit(seed):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 10, 1500)
    if seed % 2:
        x = np.round(x)  # ties: many equal quantile edges
    Y = x + 2 * np.maximum(0, x - 3) + rng.normal(0, 0.1, x.size)
    if seed == 4:
        Y[::7] = 1e300  # overflowing sums: NaN segment costs
    with np.errstate(all="ignore"):
        for m, bins in ((1, 300), (3, 50), (6, 300)):
            _, seg = piecewise_linear._segment_costs(x, Y, bins)
            assert piecewise_linear._best_cuts(seg, m) == cuts_loop(seg, m)
