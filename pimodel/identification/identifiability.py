"""Excitation check (Lemma 2, Prop. 2): can the record identify all the plays?

Radius convergence needs reversals and an input range above ``2 r_n``; Lemma 2 bounds
``2 r_n < (sum p / p_n) rho`` by the loop width ``rho``, so a range below rho surely cannot
excite all plays.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass

import numpy as np

from .branches import find_reversals

__all__ = [
    "check_excitation",
    "ExcitationReport",
]


@dataclass
class ExcitationReport:
    """Result of :func:`check_excitation`: what the record can excite.

    Parameters
    ----------
    input_range : float
        ``max v - min v`` (input unit).
    reversals : int
        Number of input reversals.
    loop_width : float or None
        Loop width ``rho = 2 sum p_i r_i / sum p_i`` of the model (Lemma 2); None without one.
    largest_radius_bound : float or None
        Lemma 2's bound on ``r_n``: ``(sum p / p_n) rho / 2``; None without a model.
    ok : bool
        False when convergence cannot be expected.
    messages : list of str
        The reasons, in words.

    Examples
    --------
    >>> from pimodel import check_excitation
    >>> rep = check_excitation(np.sin(np.linspace(0, 4 * np.pi, 400)), [1.0, 0.5], [0.0, 0.3])
    >>> rep.ok, rep.reversals, round(rep.to_json()["loop_width"], 12)
    (True, 4, 0.2)
    """

    input_range: float
    reversals: int
    loop_width: float | None
    largest_radius_bound: float | None
    ok: bool
    messages: list[str]

    def to_json(self) -> dict:
        """The report as a JSON-ready dict (field name to value).

        Returns
        -------
        dict
            The fields of the report.

        Examples
        --------
        >>> from pimodel import check_excitation
        >>> sorted(check_excitation([0.0, 1.0, 0.0]).to_json())[:3]
        ['input_range', 'largest_radius_bound', 'loop_width']
        """
        return asdict(self)


def check_excitation(v, weights=None, radii=None, *, threshold: float | None = None,
                     warn: bool = True) -> ExcitationReport:
    """Check reversals and input range against the loop width of a (guessed) operator.

    Radius convergence needs reversals and an input range above ``2 r_n`` (Prop. 2); a range
    below the loop width ``rho`` surely cannot excite every play (Lemma 2).

    Parameters
    ----------
    v : array_like of float, shape (N,)
        Input samples (input unit).
    weights : array_like of float, optional
        Weights of a model or guess (e.g. from the loop slopes). Without ``weights`` and
        ``radii`` only the reversals are checked.
    radii : array_like of float, optional
        Radii of the model or guess (input unit), ascending.
    threshold : float, optional
        Reversal threshold (input unit; default 1 % of the input range).
    warn : bool, optional
        Issue a ``UserWarning`` with the reasons when ``ok`` is False.

    Returns
    -------
    ExcitationReport
        Range, reversals, loop width, the bound on ``r_n``, ``ok`` and the messages.

    Warns
    -----
    UserWarning
        When ``warn`` and the record cannot be expected to identify every play.

    Examples
    --------
    >>> import warnings
    >>> from pimodel import check_excitation
    >>> v = 0.2 * np.sin(np.linspace(0, 4 * np.pi, 400))     # range 0.4 < 2 r_n = 0.6
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     rep = check_excitation(v, [1.0, 0.5], [0.0, 0.3])
    >>> rep.ok
    False
    """
    v = np.asarray(v, float)
    rng = float(np.ptp(v))
    thr = 0.01 * rng if threshold is None else threshold
    nrev = len(find_reversals(v, thr)) if rng > 0 else 0
    msgs: list[str] = []
    ok = True
    if rng == 0:
        ok = False
        msgs.append("the input is constant: no loop, nothing can be identified")
    elif nrev == 0:
        ok = False
        msgs.append("the input has no reversal: the loop slopes and radii cannot be identified")
    rho = bound = None
    if weights is not None and radii is not None and len(weights) > 0:
        p = np.asarray(weights, float)
        r = np.asarray(radii, float)
        rho = float(2 * (p @ r) / p.sum())
        bound = float(p.sum() / p[-1] * rho / 2)
        if rng <= rho:
            ok = False
            msgs.append(f"input range {rng:.4g} is below the loop width rho = {rho:.4g} "
                        "(Lemma 2): the largest plays cannot be excited")
        elif rng <= 2 * r[-1]:
            ok = False
            msgs.append(f"input range {rng:.4g} does not exceed 2 r_n = {2 * r[-1]:.4g} "
                        "(Prop. 2): radius estimates cannot be expected to converge")
        else:
            msgs.append(f"input range {rng:.4g} exceeds 2 r_n = {2 * r[-1]:.4g} and "
                        f"rho = {rho:.4g}; {nrev} reversals")
    if warn and not ok:
        warnings.warn("excitation check: " + "; ".join(msgs), UserWarning, stacklevel=2)
    return ExcitationReport(rng, nrev, rho, bound, ok, msgs)
