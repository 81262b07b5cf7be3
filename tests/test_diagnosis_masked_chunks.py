"""The fitted samples of a chunk under a mask (:func:`pimodel.diagnosis.effects.fitted_in`):
a start-up region left out is one run per chunk, taken as a view of the play rows; any other
mask as the boolean mask. Either way the fit is the one on the fitted samples alone."""

from __future__ import annotations

import numpy as np
import pytest

from pimodel.diagnosis.chunked import chunks
from pimodel.diagnosis.effects import fit_nominal, fitted_in, make_segment
from pimodel.stages.pi_stage import excitation, random_truth


def _masks(rng, n):
    k = int(rng.integers(1, n - 1))
    scattered = rng.random(n) < 0.7
    middle = np.zeros(n, bool)
    middle[k // 2:k] = True
    return {"start-up left out": np.arange(n) >= k, "one run inside": middle,
            "scattered": scattered, "none fitted": np.zeros(n, bool),
            "all fitted": np.ones(n, bool)}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_fitted_samples_of_every_chunk_are_those_of_the_mask(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(50, 40_000))
    X = rng.standard_normal((3, n))
    cuts = list(chunks(n)) + [slice(a, a + int(rng.integers(1, 300)))
                             for a in rng.integers(0, n - 1, 5)]
    for name, mask in _masks(rng, n).items():
        for c in cuts:
            m = fitted_in(mask, c)
            np.testing.assert_array_equal(X[:, c][:, m], X[:, c][:, mask[c]], err_msg=name)
            run = np.flatnonzero(mask[c])
            if run.size == 0 or run[-1] - run[0] + 1 == run.size:  # one run: a view
                assert isinstance(m, slice), name
                assert run.size == 0 or np.shares_memory(X[:, c][:, m], X), name


def test_a_fit_without_the_start_up_is_the_fit_on_the_samples_after_it():
    truth = random_truth(["creep"], 3)
    t, v = excitation("train", seed=4)
    rec = truth.record(t, v, 4)
    radii = np.linspace(0.0, np.ptp(v) / 2, 20)
    k = rec.t.size // 3
    seg = make_segment(rec.t, rec.v, rec.y, radii, np.arange(rec.t.size) >= k)
    coef = fit_nominal([seg]).coef
    Z = np.column_stack([seg.Z, np.ones(rec.t.size)])[k:]
    ref = np.linalg.lstsq(Z, rec.y[k:], rcond=None)[0]
    scale = np.max(np.abs(Z @ ref))
    np.testing.assert_allclose(Z @ coef, Z @ ref, atol=1e-8 * scale)
