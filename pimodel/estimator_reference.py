"""Plain NumPy specification of the radius estimator (one Python step per sample).

Implements exactly the law of :mod:`pimodel.estimator` / ``fmu/src/pim_estimator.c``; a test
holds the two equal to 1e-12. Slow on purpose: it is the readable version.
"""

from __future__ import annotations

import numpy as np


def project_ordered_reference(x: np.ndarray, w: np.ndarray, fix_first: bool) -> np.ndarray:
    """Weighted projection onto ``0 <= x_1 <= ... <= x_n`` by pooling adjacent violators."""
    x = np.array(x, dtype=float)
    start = 1 if fix_first else 0
    if fix_first:
        x[0] = 0.0
    blocks: list[list[float]] = []  # [value, weight, count]
    for i in range(start, x.size):
        blocks.append([x[i], w[i], 1])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            v2, w2, c2 = blocks.pop()
            v1, w1, c1 = blocks[-1]
            blocks[-1] = [(w1 * v1 + w2 * v2) / (w1 + w2), w1 + w2, c1 + c2]
    out = [max(v, 0.0) for v, _, c in blocks for _ in range(c)]
    x[start:] = out
    return x


def estimate_radii_reference(v, y, weights, *, dt, gains, initial_radii, known_linear_play=False,
                             threshold=0.0, max_step=None, anneal_time=None, guard=0.0,
                             slope_window=8, slope_tol=0.5, initial_state=0.0):
    """Returns ``(history, yhat, e, e_delta, used, final radii)`` as in the C batch loop."""
    p = np.asarray(weights, float)
    n = p.size
    g = np.broadcast_to(np.asarray(gains, float), (n,)).copy()
    w = 1.0 / np.maximum(g, 1e-300)
    rhat = project_ordered_reference(np.asarray(initial_radii, float), w, known_linear_play)
    zhat = np.full(n, float(initial_state))
    sat = np.zeros(n)
    started = False
    direction = 0.0
    have_rev = False
    v_first = v_start = v_ext = v_rev = 0.0
    time = 0.0
    nseg = 0
    past_v: list[float] = []  # inputs and outputs before sample k
    past_y: list[float] = []
    N = len(v)
    hist, yhat, e, ed, used = np.empty((N, n)), np.empty(N), np.empty(N), np.zeros(N), np.zeros(N)
    for k in range(N):
        vk, yk = float(v[k]), float(y[k])
        hist[k] = rhat
        zhat = np.maximum(vk - rhat, np.minimum(vk + rhat, zhat))
        yhat[k] = sum(p[j] * zhat[j] for j in range(n))  # sequential sum, as in C
        e[k] = yhat[k] - yk
        usable = False
        if not started:
            started, v_first, v_start, v_ext = True, vk, vk, vk
        elif direction == 0.0:
            if abs(vk - v_first) > threshold:
                direction = 1.0 if vk > v_first else -1.0
                v_ext = vk
        elif direction * (vk - v_ext) >= 0.0:
            if direction * (vk - v_ext) > 0.0:
                v_ext = vk
            usable = have_rev
        elif abs(vk - v_ext) > threshold:
            travel = abs(v_ext - v_start)
            sat = (travel >= 2.0 * rhat + guard).astype(float)
            v_rev = v_start = v_ext
            have_rev = True
            direction = -direction
            v_ext = vk
            nseg = 0
            usable = True
        if usable and slope_window > 0:
            m = slope_window
            if nseg < m + 1:
                usable = False
            else:
                da, db = abs(past_v[-1 - m] - v_rev), abs(past_v[-1] - v_rev)
                if db - da > 0:
                    model = sum(p[j] * max(0.0, db - max(da, 2.0 * rhat[j])) for j in range(n))
                    meas = direction * (past_y[-1] - past_y[-1 - m])
                    usable = abs(meas - model) <= slope_tol * p.min() * (db - da)
        if usable:
            s, d = direction, abs(vk - v_rev)
            phi = np.empty(n)
            ybar = 0.0
            valid = True
            for j in range(n):
                if abs(d - 2.0 * rhat[j]) < guard:
                    valid = False
                    break
                if d >= 2.0 * rhat[j]:
                    phi[j] = p[j]
                    ybar += p[j] * (vk - s * rhat[j])
                else:
                    if sat[j] == 0.0:
                        valid = False
                        break
                    phi[j] = -p[j]
                    ybar += p[j] * (v_rev + s * rhat[j])
            if valid:
                err = ybar - yk
                scale = 1.0 / (1.0 + time / anneal_time) if anneal_time else 1.0
                step = dt * g * scale * err * s * phi
                if max_step:
                    step = np.clip(step, -max_step, max_step)
                rhat = project_ordered_reference(rhat + step, w, known_linear_play)
                ed[k] = err
                used[k] = 1.0
        time += dt
        nseg += 1
        past_v.append(vk)
        past_y.append(yk)
    return hist, yhat, e, ed, used.astype(bool), rhat
