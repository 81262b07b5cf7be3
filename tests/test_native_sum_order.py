"""The C core's play step sums in the order pim_core.h states, bit for bit: the Python
extension's loop, the SSE2 code and the scalar code (PIM_NO_SIMD) against that formula in plain
Python floats."""

from __future__ import annotations

import random
import subprocess
from pathlib import Path

import numpy as np
import pytest

from pimodel import PIOperator
from pimodel.fmu.build import find_compiler

CORE = Path(__file__).resolve().parent.parent / "fmu" / "src" / "core"

# Reads n, N, then p, r, z (n each) and v (N) as numbers (C99 hex floats); prints y[k] and the
# final z as hex floats, one per line.
STEP_C = r"""
#include <stdio.h>
#include <stdlib.h>
#include "pim_core.h"
int main(void)
{
    size_t n, N;
    if (scanf("%zu %zu", &n, &N) != 2) return 1;
    double *x = malloc((3 * n + N) * sizeof *x);
    for (size_t i = 0; i < 3 * n + N; ++i)
        if (scanf("%lf", &x[i]) != 1) return 1;
    double *p = x, *r = x + n, *z = x + 2 * n, *v = x + 3 * n;
    for (size_t k = 0; k < N; ++k) printf("%a\n", pim_pi_step_inline(n, p, r, z, v[k]));
    for (size_t i = 0; i < n; ++i) printf("%a\n", z[i]);
    free(x);
    return 0;
}
"""


def stated_order(p: list[float], r: list[float], z: list[float],
                 v: list[float]) -> list[float]:
    """y[k] by pim_core.h's formula: plays clamped into [v - r_i, v + r_i] by comparisons,
    s_c = p_c z_c + p_(c+4) z_(c+4) + ... (each started by its first term, 0 while empty),
    y = (s_1 + s_3) + (s_2 + s_4); z updated in place."""
    y = []
    for vk in v:
        s: list[float | None] = [None] * 4
        for i in range(len(p)):
            a = z[i] if z[i] < vk + r[i] else vk + r[i]
            a = a if a > vk - r[i] else vk - r[i]
            z[i] = a
            c = s[i % 4]
            s[i % 4] = p[i] * a if c is None else c + p[i] * a
        s1, s2, s3, s4 = (0.0 if c is None else c for c in s)
        y.append((s1 + s3) + (s2 + s4))
    return y


def draw(seed: int, n: int, positive: bool = False, N: int = 300) -> tuple[list[float], ...]:
    """Weights (> 0, or of both signs and signed zeros), sorted radii (some 0), states, and
    inputs that cross and hit zero (of both signs)."""
    rng = random.Random(f"sum-order-{seed}-{n}")
    p = [rng.uniform(0.1, 2) if positive else rng.choice([0.0, -0.0, rng.uniform(-2, 2)])
         for _ in range(n)]
    r = sorted(rng.choice([0.0, rng.uniform(0, 3)]) for _ in range(n))
    z = [rng.uniform(-1, 1) for _ in range(n)]
    v, x = [], 0.0
    for _ in range(N):
        x = rng.choice([0.0, -0.0, x + rng.gauss(0, 0.7)])
        v.append(x)
    return p, r, z, v


def bits(x) -> list[int]:
    return np.asarray(x, dtype=np.float64).view(np.int64).tolist()


@pytest.fixture(scope="module")
def step_programs(tmp_path_factory) -> dict[str, Path]:
    """The step compiled as the library is (SSE2 on x86-64) and with the scalar code."""
    tmp = tmp_path_factory.mktemp("sum_order")
    (tmp / "step.c").write_text(STEP_C)
    out = {}
    for name, flags in (("default", []), ("scalar", ["-DPIM_NO_SIMD"])):
        out[name] = tmp / name
        subprocess.run([find_compiler(), "-std=c99", "-O3", "-Wall", "-Wextra", "-Werror",
                        *flags, "-I", str(CORE), str(tmp / "step.c"), "-o", str(out[name])],
                       check=True)
    return out


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("variant", ["default", "scalar"])
def test_c_step_sums_in_the_stated_order(step_programs, variant, seed):
    for n in range(1, 22):
        p, r, z, v = draw(seed, n, positive=seed == 2)
        text = f"{n} {len(v)}\n" + "\n".join(x.hex() for x in [*p, *r, *z, *v]) + "\n"
        out = subprocess.run([str(step_programs[variant])], input=text, capture_output=True,
                             text=True, check=True).stdout.split()
        got = [float.fromhex(x) for x in out]
        want = stated_order(p, r, z, v)
        assert bits(got[:len(v)]) == bits(want), (variant, n)
        assert bits(got[len(v):]) == bits(z), (variant, n)


@pytest.mark.parametrize("seed", range(3))
def test_python_path_sums_in_the_stated_order(seed):
    """PIOperator.simulate (the extension's pim_pi_run) against the formula, every n up to 21
    and one beyond the fixed-size limit (its general path)."""
    for n in [*range(1, 22), 70]:
        p, r, z, v = draw(seed + 3, n, positive=True)
        y = PIOperator(p, r, initial_state=z).simulate(np.array(v))
        assert bits(y) == bits(stated_order(p, r, list(z), v)), n


@pytest.mark.parametrize("seed", range(3))
def test_play_outputs_as_rows_are_the_runs_own(seed):
    """pim_pi_run_rows (the diagnosis' play rows, module effects.play_chunks) writes exactly
    pim_pi_run's play outputs, transposed, with the same outputs and final states, for n up to
    and beyond the fixed-size limit (its general path), through its buffer in blocks of
    samples (777 samples: a last block shorter) and stored straight (600 plays); a wrong shape
    is refused by name."""
    from pimodel import _native
    rng = np.random.default_rng(seed)
    for n in (1, 7, 80, _native.LIMITS["PIM_MAX_PLAYS"] + 3, 600):
        p, r = rng.uniform(0.1, 1.0, n), np.sort(rng.uniform(0.0, 3.0, n))
        v = np.cumsum(rng.normal(0.0, 0.3, 777))
        z0 = rng.uniform(-1.0, 1.0, n)
        z1, z2 = z0.copy(), z0.copy()
        y1, plays = _native.pi_run(p, r, z1, v, with_plays=True)
        rows = np.empty((n, v.size))
        y2 = _native.pi_run_rows(p, r, z2, v, rows)
        assert bits(rows.ravel()) == bits(plays.T.ravel()), n
        assert bits(y1) == bits(y2) and bits(z1) == bits(z2), n
    with pytest.raises(ValueError, match="rows: expected shape"):
        _native.pi_run_rows(p, r, z2, v, np.empty((v.size, n)))
