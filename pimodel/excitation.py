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


@dataclass
class ExcitationReport:
    """What the record can excite; ``ok`` False means convergence cannot be expected."""

    input_range: float
    reversals: int
    loop_width: float | None
    largest_radius_bound: float | None
    ok: bool
    messages: list[str]

    def to_json(self) -> dict:
        return asdict(self)


def check_excitation(v, weights=None, radii=None, *, threshold: float | None = None,
                     warn: bool = True) -> ExcitationReport:
    """Check reversals and input range against the loop width of a (guessed) operator.

    ``weights``/``radii``: a model or guess (e.g. from the loop slopes); without them only the
    reversals are checked. Issues a ``UserWarning`` with the reason when ``ok`` is False.
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
