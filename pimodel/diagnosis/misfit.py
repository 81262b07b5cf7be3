"""The chosen rate's own misfit on the validate records, set aside when a drift is judged
beside it (issue 28: a second effect only when it is real, and then whenever it is).

The ``rate`` candidate is fitted on train and extrapolated to the validate records; where the
train records' speeds do not pin its saturation, the extrapolation to faster validate input
leaves several noise floors (docs/diagnosis.md, ``density_stage`` seeds 8 and 9). A drift
judged against that residual must cut an error that is not its own: a real thermal drift cut
the validate RMS by 3-6 % beside it, under the 20 % the diagnosis asks.

The yardstick: the rate refined **on the validate records** in its continuous parameters only
(growth ``G``, saturation ``S`` and filter ``tau``; its weights and gains still fitted on
train at each point), by the residual with each record's level and linear trend in time
removed (:func:`detrended_rss`), so that the refinement cannot stand in for a level or a
trend (what a drift or an offset gives). Its change of the validate outputs
(:func:`rate_correction`) is added to both models being compared: the drift must then pass
on the same terms against what is left once the rate's own extrapolation error is set aside.
Only the drift is judged so (:mod:`.diagnose`): the refinement leaves out exactly what the
drift models, while an effect of the input history can take part of the rate's misfit the
refinement leaves. The refinement is a yardstick only, never the model kept (that would fit
validate), and only a refinement: it must lower the plain validate RSS as well.

Discrete-time form: for validate record ``j`` with fitted samples ``k``, the detrended
residual is ``e[k] - a_j - b_j (t[k] - tbar_j)`` with ``a_j, b_j`` the least-squares level and
slope of ``e = y - o`` over those samples.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .lti import nelder_mead

__all__ = ["CONTINUOUS_KEYS", "CORRECTION_EVALS", "detrended_rss", "rate_correction"]

CONTINUOUS_KEYS = ("rate_growth", "rate_saturation", "rate_tau")  # what the yardstick refines
CORRECTION_EVALS = 60  # fits at most in the refinement's Nelder-Mead (as the scaled search)
CORRECTION_STEP = 2**0.25  # its first steps: a quarter octave in each parameter


def detrended_rss(segs, outputs) -> float:
    """The residual sum of squares of ``y - o`` over the fitted samples of each record, after
    removing that record's least-squares level and linear trend in time.

    Parameters
    ----------
    segs : list
        The records (each with ``t``, ``y`` and ``used``: the fitted samples).
    outputs : list of numpy.ndarray
        A model's output on each record.

    Returns
    -------
    float
        The sum over records [output units squared].

    Examples
    --------
    >>> from types import SimpleNamespace as S
    >>> t = np.arange(5.0)
    >>> seg = S(t=t, y=2.0 + 0.5 * t + np.array([0, 1, 0, -1, 0.0]), used=slice(None))
    >>> round(detrended_rss([seg], [np.zeros(5)]), 6)  # the level and trend are not counted
    2.0
    """
    total = 0.0
    for s, o in zip(segs, outputs, strict=True):
        t, e = s.t[s.used], (s.y - o)[s.used]
        A = np.column_stack((np.ones_like(t), t - t.mean()))
        coef, *_ = np.linalg.lstsq(A, e, rcond=None)
        total += float(np.sum((e - A @ coef) ** 2))
    return total


def rate_correction(effects: tuple[str, ...], fixed: dict, fit: Callable, va
                    ) -> list[np.ndarray] | None:
    """The change of the validate outputs that refining the chosen rate on the validate
    records makes, its level and trend left out of the search (module docstring).

    Parameters
    ----------
    effects : tuple of str
        The chosen effects (the model whose rate is refined).
    fixed : dict
        Their grid parameters (``rate_family``, ``rate_tau``, ``rate_saturation``, and for the
        exact shape ``rate_growth``, ...).
    fit : callable
        ``fit(name, combo, fixed) -> (model, validate outputs)``: the diagnosis' fit of the
        effects ``combo + (name,)`` on train with the grid parameters ``fixed`` held.
    va : list
        The validate records (segments with ``t``, ``y``, ``used``).

    Returns
    -------
    list of numpy.ndarray or None
        One array per validate record (outputs at the refined parameters minus those at
        ``fixed``); None without a rate among ``effects``, without a positive continuous
        parameter to refine, or when the refined rate does not also lower the plain validate
        RSS (its level and trend counted): a change that fits validate worse is no refinement,
        and beside another effect of the input history it set aside what that effect then
        took (``preisach_stage`` rate + creep: a spurious asymmetry).

    Examples
    --------
    >>> rate_correction(("creep",), {}, None, [])  # no rate: nothing to set aside
    """
    if "rate" not in effects:
        return None
    keys = [k for k in CONTINUOUS_KEYS if isinstance(fixed.get(k), (int, float)) and fixed[k] > 0]
    if not keys:
        return None

    def outputs(x) -> list[np.ndarray]:
        point = {**fixed, **{k: float(v) for k, v in zip(keys, np.exp(x), strict=True)}}
        return fit(effects[-1], effects[:-1], point)[1]

    x0 = np.log([float(fixed[k]) for k in keys])
    step = np.log(CORRECTION_STEP)
    start = outputs(x0)
    rss0 = detrended_rss(va, start)
    r = nelder_mead(lambda x: detrended_rss(va, outputs(x)), x0,
                    initial_simplex=[x0, *(x0 + step * np.eye(len(keys))[i]
                                           for i in range(len(keys)))],
                    xatol=1e-3, fatol=1e-9 * rss0, maxfev=CORRECTION_EVALS)
    refined = outputs(r.x)
    if not (r.fun < rss0 and _rss(va, refined) < _rss(va, start)):
        return None  # no refinement on these records: a change that fits validate worse
    return [o - o0 for o, o0 in zip(refined, start, strict=True)]


def _rss(segs, outputs) -> float:
    return sum(float(np.sum((s.y - o)[s.used] ** 2)) for s, o in zip(segs, outputs, strict=True))
