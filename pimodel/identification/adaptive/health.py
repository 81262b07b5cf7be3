"""Health report of a radius estimate: can it be trusted?

Five checks on a finished run (the estimate history ``rhat[k]`` over the record):

- excitation (Lemma 2, Prop. 2; :func:`pimodel.identification.identifiability.check_excitation`):
  reversals and an
  input range above the loop width and above ``2 rhat_n``;
- plays merged: adjacent estimates closer than ``1e-6 * max(rhat)`` (the ordering constraint
  of the projection is active: the record did not separate them, or the law is stuck);
- pinned at the projection bound: ``rhat_j = 0`` for a play not declared linear;
- still moving: the mean of the last quarter of the record differs from the mean of the
  quarter before it by more than 1 % of ``max(rhat)`` (the record is too short for the gains).
  The quarter boundaries are ``N - 2q`` and ``N - q`` (``q = N // 4``) rounded down to a grid
  of cumulative sums kept every ``block`` rows (1 while ``N <= 64``, then doubled as needed,
  so within ``N / 32`` rows), which the RadiusEstimator FMU can keep in bounded memory;
- model fits the data: the RMS of ``e[k] = yhat[k] - y[k]`` over the last quarter is at most
  ``1.1 sigma_y + 1e-4 range(y)`` (``sigma_y`` the noise level of y,
  :func:`pimodel.identification.adaptive.settings.noise_level`). A law stuck at a wrong fixed point
  (the
  paper's law from below) keeps the estimate still, so only this check sees it.

Merged, pinned and still moving are computed by the C core (``fmu/src/pim_est_health.c``), the
same code the RadiusEstimator FMU runs on its samples (its ``health`` output and the warning it
logs at terminate), so the two agree to the last bit. The FMU checks the excitation and the
fit in C too: reversals by the estimator's own rule, and the noise level of y from the mean
absolute second difference (a streaming stand-in for the median of ``noise_level``); tests hold
its flags equal to this report.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass, field

import numpy as np

from ..._native import HEALTH_MOVING, health_checks
from ..identifiability import check_excitation
from .settings import noise_level

__all__ = [
    "estimator_health",
    "refined_health",
    "EstimatorHealth",
]


@dataclass
class EstimatorHealth:
    """Result of :func:`estimator_health`; ``ok`` is False when any check failed.

    Parameters
    ----------
    ok : bool
        All checks passed.
    excitation_ok : bool
        The record excites all plays (Lemma 2, Prop. 2) for the estimated radii.
    merged : list of tuple of int
        1-based pairs ``(j, j + 1)`` of plays whose estimates coincide.
    pinned : list of int
        1-based plays whose estimate sits at the bound 0 (not declared linear).
    still_moving : bool
        The estimate drifted by more than 1 % of ``max(rhat)`` between the last two quarters.
    drift : float
        That drift, ``max_j |mean_Q4 - mean_Q3|`` [input unit].
    fit_ok : bool
        The model output fits y within the noise (True when not checked).
    fit_rms : float or None
        RMS of ``e`` over the last quarter [output unit] (None when not checked).
    messages : list of str
        One sentence per failed check.
    radii_sd : numpy.ndarray of float, optional
        After the batch refinement (:func:`refined_health`): the Cramer-Rao standard
        deviations of the radii at the estimate and the record's noise level (input unit);
        infinite when the record does not excite them (``J^T J`` singular).

    Examples
    --------
    >>> EstimatorHealth(ok=True, excitation_ok=True).fit_rms is None
    True
    """

    ok: bool
    excitation_ok: bool
    merged: list = field(default_factory=list)
    pinned: list = field(default_factory=list)
    still_moving: bool = False
    drift: float = 0.0
    fit_ok: bool = True
    fit_rms: float | None = None
    messages: list = field(default_factory=list)
    radii_sd: list | None = None

    def to_json(self) -> dict:
        """Plain dict of the fields.

        Returns
        -------
        dict
            Field name -> value (JSON-serialisable: lists, floats, bools, None).

        Examples
        --------
        >>> EstimatorHealth(ok=False, excitation_ok=True, pinned=[2]).to_json()["pinned"]
        [2]
        """
        return asdict(self)


def estimator_health(v, weights, history, *, linear_play: bool = False, y=None, error=None,
                     warn: bool = False) -> EstimatorHealth:
    """Check a radius estimate (see the module docstring).

    Parameters
    ----------
    v : array_like
        The input record.
    weights : array_like
        Play weights p_j.
    history : array_like, shape (N, n)
        ``rhat[k]``, the estimate used at each sample.
    linear_play : bool
        ``rhat_1 = 0`` was held on purpose (not reported as pinned).
    y, error : array_like, optional
        Measured output and model error ``e[k]``; with both, the fit is checked.
    warn : bool
        Issue a ``UserWarning`` with the messages when a check fails.

    Returns
    -------
    EstimatorHealth

    Raises
    ------
    ValueError
        A history with more than 64 plays (the C core's limit, as the estimator's).

    Examples
    --------
    >>> import numpy as np
    >>> h = estimator_health(np.sin(np.arange(0, 60, 0.01)), [1.0, 1.0],
    ...                      np.tile([0.2, 0.2], (6000, 1)))
    >>> h.merged
    [(1, 2)]
    """
    hist = np.asarray(history, float)
    final = hist[-1]
    scale = float(final.max()) if final.size else 0.0
    msgs: list[str] = []
    exc = check_excitation(v, weights, final, warn=False)
    if not exc.ok:
        msgs.extend(exc.messages)
    checks = health_checks(np.asarray(weights, float), hist, linear_play=linear_play)
    merged = [(j + 1, j + 2) for j in np.flatnonzero(checks["merged"]).tolist()]
    if merged:
        msgs.append("plays merged (equal estimates, the ordering constraint is active): "
                    + ", ".join(f"r_hat[{a}] = r_hat[{b}]" for a, b in merged))
    pinned = [j + 1 for j in np.flatnonzero(checks["pinned"]).tolist()]
    if pinned:
        msgs.append("radius pinned at the projection bound 0: "
                    + ", ".join(f"r_hat[{j}]" for j in pinned))
    q = hist.shape[0] // 4
    drift = checks["drift"]
    moving = bool(checks["flags"] & HEALTH_MOVING)
    if moving:
        msgs.append(f"estimate still moving at the end: drift {drift:.3g} between the last two "
                    f"quarters of the record (> 1 % of max r_hat = {scale:.3g}); use a longer "
                    "record or larger gains")
    fit_ok, fit_rms = True, None
    if y is not None and error is not None and q >= 1:
        m = np.asarray(y, float)
        fit_rms = float(np.sqrt(np.mean(np.asarray(error, float)[-q:] ** 2)))
        bound = 1.1 * noise_level(m) + 1e-4 * float(np.ptp(m))
        fit_ok = fit_rms <= bound
        if not fit_ok:
            msgs.append(f"the model does not fit the data: RMS error {fit_rms:.3g} over the "
                        f"last quarter exceeds the noise bound {bound:.3g} (a wrong fixed "
                        "point, weights that do not match the data, or dynamics the PI model "
                        "lacks, e.g. creep on a real record)")
    ok = exc.ok and not merged and not pinned and not moving and fit_ok
    if warn and not ok:
        warnings.warn("radius estimate health: " + "; ".join(msgs), UserWarning, stacklevel=2)
    return EstimatorHealth(ok, exc.ok, merged, pinned, moving, drift, fit_ok, fit_rms, msgs)


def refined_health(v, y, weights, radii, *, linear_play: bool = False,
                   initial_state: float = 0.0, warn: bool = False) -> EstimatorHealth:
    """Health of the batch-refined estimate ``radii`` (:func:`pimodel.estimate_radii`).

    Excitation: Lemma 2 at ``radii``
    (:func:`pimodel.identification.identifiability.check_excitation`) and the persistent
    excitation of the radii, ``J^T J`` nonsingular at ``radii``
    (:func:`pimodel.identification.adaptive.polish.radius_bound`, with ``sigma`` the noise
    level of y, or ``1e-12 range(y)`` on a clean record); merged and pinned from ``radii``;
    not still moving (a batch estimate); the fit over the last quarter with ``radii``.

    Parameters
    ----------
    v, y : array_like of float
        The record: input ``v[k]`` and measured output ``y[k]``.
    weights : array_like of float
        Play weights ``p_j`` (known).
    radii : array_like of float
        The refined radii ``r_j`` [input units].
    linear_play : bool, optional
        Whether the first play is the linear (radius 0) play.
    initial_state : float, optional
        Play states before ``v[0]``.
    warn : bool, optional
        Emit the report's messages as a UserWarning.

    Returns
    -------
    EstimatorHealth
        Excitation, convergence and fit of the refined estimate (``radii_sd`` from the bound).

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel import PIOperator
    >>> v = np.sin(np.arange(0, 60, 0.01))
    >>> y = PIOperator([1.0, 1.0], [0.1, 0.4]).simulate(v)
    >>> refined_health(v, y, [1.0, 1.0], [0.1, 0.4]).ok
    True
    """
    from .polish import play_sensitivity, radius_bound

    x, m = np.asarray(v, float), np.asarray(y, float)
    p, r = np.asarray(weights, float), np.asarray(radii, float)
    sig = max(noise_level(m), 1e-12 * float(np.ptp(m)), 1e-300)
    bound = radius_bound(x, p, r, sigma=sig, linear_play=linear_play,
                         initial_state=initial_state)
    lemma = check_excitation(x, p, r, warn=False)
    msgs = list(lemma.messages) if not lemma.ok else []
    exc = lemma.ok and bound.exciting
    if not bound.exciting:
        msgs.append("the record does not excite the radii: J^T J (the output's sensitivity "
                    "to the radii) is singular, so some radii are not identifiable from it")
    scale = float(r.max()) if r.size else 0.0
    merged = [(j + 1, j + 2) for j in range(r.size - 1)
              if r[j + 1] - r[j] <= 1e-6 * scale and not (linear_play and j == 0 and scale == 0)]
    if merged:
        msgs.append("plays merged (equal estimates): "
                    + ", ".join(f"r_hat[{a}] = r_hat[{b}]" for a, b in merged))
    pinned = [j + 1 for j in range(r.size) if r[j] == 0 and not (linear_play and j == 0)]
    if pinned:
        msgs.append("radius pinned at the bound 0: " + ", ".join(f"r_hat[{j}]" for j in pinned))
    q = max(x.size // 4, 1)
    e = play_sensitivity(x, r, initial_state=initial_state)[0][-q:] @ p - m[-q:]
    fit_rms = float(np.sqrt(np.mean(e ** 2)))
    limit = 1.1 * noise_level(m) + 1e-4 * float(np.ptp(m))
    fit_ok = fit_rms <= limit
    if not fit_ok:
        msgs.append(f"the model does not fit the data: RMS error {fit_rms:.3g} over the last "
                    f"quarter exceeds the noise bound {limit:.3g}")
    ok = exc and not merged and not pinned and fit_ok
    if warn and not ok:
        warnings.warn("radius estimate health: " + "; ".join(msgs), UserWarning, stacklevel=2)
    return EstimatorHealth(ok, exc, merged, pinned, False, 0.0, fit_ok, fit_rms, msgs,
                           bound.sd.tolist())
