"""Which plays validate drives on loops that train moved only in its start-up or never (issue 28):
where the nominal extrapolates.

The plays are updated at each sample ``k`` from ``v[k]``:
``z[k] = min(max(z[k-1], v[k] - r), v[k] + r)``, ``z[-1] = v[0]`` (at rest at the record's first
sample). A play of radius ``r`` moves at ``k`` when ``|v[k] - z[k-1]| > r``, and when it does not,
no larger play (started likewise) does. Once the input has spanned more than ``2 r``
(``max(v[:k+1]) - min(v[:k+1]) > 2 r``) the play's state no longer depends on its start: its
later moves are *loop* moves. With ``h`` half the train input range (the train records
together), train moves the plays of radius up to ``h`` on loops; those above ``h`` only in a
record's start-up (once, from the assumed rest) and those beyond the train input's largest
travel from its first sample (``reach``) never: their output is ``v[0]``, one level with the
offset. A validate record that spans more than ``2 h`` drives plays above ``h`` on loops; a
stage with weight there is not identified by train, whatever the model fitted on it (measured
on ramps to held levels at 500 Hz, clean stages: the records where the nominal misses validate
by 0.07-0.34 um are those whose stage has plays above ``h``; docs/diagnosis.md).
:func:`coverage` measures it; :func:`.summary.hints` and :func:`.summary.confidence` name it
when the verdict is not ``none``.
"""

from __future__ import annotations

import numpy as np

from ..operators.pi import PIOperator
from ..records import Record
from .effects import play_chunks

__all__ = ["LOOP_TOL", "coverage", "informed_radii", "play_travel", "span_and_reach"]

LOOP_TOL = 1e-9  # plays "above h" are those above h (1 + LOOP_TOL): a validate record spanning
# exactly the train range (to rounding) drives none on loops


def span_and_reach(train: list[Record]) -> tuple[float, float]:
    """The train input's span ``max v - min v`` over its records together and its ``reach``,
    the largest travel ``|v[k] - v[0]|`` of a record from its first sample (the nominal's grids,
    :mod:`.diagnose`, and :func:`coverage` read both).

    Parameters
    ----------
    train : list of Record
        The train records (their inputs ``v`` only).

    Returns
    -------
    tuple of float
        ``(span, reach)`` in input units.

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel.records import Record
    >>> t = np.arange(3) * 1e-3
    >>> span_and_reach([Record(t, np.array([1.0, 0.0, 2.0]), np.zeros(3))])
    (2.0, 1.0)
    """
    span = float(np.ptp(np.concatenate([r.v for r in train])))
    return span, max(float(np.max(np.abs(r.v - r.v[0]))) for r in train)


def play_travel(train: list[Record], r: float, at_rest: bool = True) -> float:
    """The largest travel of the play of radius ``r`` over the train records: ``max z - min z``
    of its output ``z[-1..N-1]`` (``z[-1]``, the start, counted), the play at rest at ``v[0]``
    (``at_rest``) or at 0, updated at each sample ``k`` from ``v[k]``.

    Parameters
    ----------
    train : list of Record
        The train records (their inputs ``v`` only).
    r : float
        The play's radius (input units), ``>= 0``.
    at_rest : bool, optional
        The play starts at rest at each record's ``v[0]`` (default) or at 0.

    Returns
    -------
    float
        The travel (input units), the largest over the records.

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel.records import Record
    >>> t = np.arange(4) * 1e-3
    >>> rec = Record(t, np.array([0.0, 1.0, -1.0, 1.0 + 1e-6]), np.zeros(4))
    >>> [round(play_travel([rec], r), 6) for r in (0.5, 1.0)]  # the top play: a sliver
    [1.000001, 1e-06]
    """
    travel = 0.0
    for rec in train:
        lo = hi = float(rec.v[0]) if at_rest else 0.0  # the start, z[-1]
        for _, rows in play_chunks(rec.v, [float(r)], at_rest=at_rest):
            lo, hi = min(lo, float(rows[0].min())), max(hi, float(rows[0].max()))
        travel = max(travel, hi - lo)
    return travel


def informed_radii(train: list[Record], radii: np.ndarray, at_rest: bool = True) -> np.ndarray:
    """``radii`` (a grid of spacing ``d = radii[1] - radii[0]``, ascending) without the top
    plays whose train travel (:func:`play_travel`) is positive but below ``d``.

    Such a play moves only by a sliver, in the start-up of a record whose input ends a little
    further on one side of its first sample than ``S / 2`` (``S`` the train span): on a record
    taken in closed loop, the controller's output starting at the centre of its range, the
    half-range grid's top play (radius ``S / 2``) moves by 2e-6-6e-3 V (a grid spacing of
    0.01 V), its least-squares weight is the noise (and any unmodelled effect) over that
    sliver (-5958 um/V, measured) and a validate record that reaches a little further
    mispredicts by tens of um (docs/diagnosis.md, "Records taken under feedback"). A play
    within one grid spacing of never moving is, at the grid's resolution, one that does not
    move: it is left out. The grid is scanned from its top down to the first play that
    travels ``d`` or more (the travel does not grow with the radius); plays that never move
    (travel 0: their output is ``v[0]``, one level with the offset, as before) are kept.
    The nominal applies it to its grids up to ``S / 2`` only: on a grid that reaches above (the
    extension, the one play above), plays that move only in a start-up are the point, and
    cutting them there lost a clean band-limited stage at 500 Hz (nominal 0.015 um, the test
    allows 0.0075; ``tests/test_diagnosis_inputs.py``). On the ``sim_to_real`` study's records
    and the real splits the nominal's chosen grids are the same as before.

    Parameters
    ----------
    train : list of Record
        The train records.
    radii : numpy.ndarray
        The grid, ascending from 0, at least two radii.
    at_rest : bool, optional
        The plays start at rest at ``v[0]`` (default) or at 0.

    Returns
    -------
    numpy.ndarray
        The radii kept, in order (``radii`` itself when none is left out).

    Raises
    ------
    ValueError
        ``radii`` is not a 1-D grid of at least two finite radii, ascending from 0 or above.

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel.records import Record
    >>> t = np.arange(4) * 1e-3
    >>> rec = Record(t, np.array([0.0, 1.0, -1.0, 1.0 + 1e-6]), np.zeros(4))
    >>> informed_radii([rec], np.linspace(0.0, 1.0, 5)).tolist()
    [0.0, 0.25, 0.5, 0.75]
    """
    radii = np.asarray(radii, dtype=float)
    if (radii.ndim != 1 or radii.size < 2 or not np.all(np.isfinite(radii)) or radii[0] < 0
            or np.any(np.diff(radii) <= 0)):
        raise ValueError(f"radii: expected a 1-D grid of at least two finite radii, ascending "
                         f"from 0 or above, got {np.array2string(radii, threshold=8)}")
    d = float(radii[1] - radii[0])
    drop = []
    for i in range(radii.size - 1, 0, -1):
        travel = play_travel(train, float(radii[i]), at_rest)
        if travel >= d:
            break
        if travel > 0:
            drop.append(i)
    return np.delete(radii, drop) if drop else radii


def _moves(v: np.ndarray, r: float) -> np.ndarray:
    """Per sample, whether the play of radius ``r`` at rest at ``v[0]`` moves (False at k = 0)."""
    z = PIOperator([1.0], [r], initial_state=float(v[0])).simulate(v)
    m = np.zeros(v.size, bool)
    m[1:] = z[1:] != z[:-1]
    return m


def coverage(train: list[Record], validate: list[Record]) -> dict:
    """How much each validate record drives plays that train does not identify.

    Parameters
    ----------
    train, validate : list of Record
        The diagnosis' records (their inputs ``v`` and times ``t`` only).

    Returns
    -------
    dict
        ``train_range`` ``[min, max]`` of the train input, ``half_range`` (``h``, half its
        span), ``reach`` (the train input's largest ``|v[k] - v[0]|`` over its records) and
        ``records``: per validate record ``source``, ``range`` ``[min, max]``, ``loops_above``
        (the share of its samples at which plays of radius above ``h`` move on loops: plays
        train moved only in its start-up or never), ``beyond_reach`` (the share at which
        plays above ``reach`` move, start-up included, the plays at rest at ``v[0]``: plays
        train never moved) and ``first_loop_s`` (the time [s] from the record's start of the
        first loop move above ``h``; None when none).

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel.records import Record
    >>> t = np.arange(400) * 1e-3
    >>> tr = Record(t, np.sin(2 * np.pi * 4 * t), np.zeros(400))
    >>> va = Record(t, 1.5 * np.sin(2 * np.pi * 4 * t), np.zeros(400))
    >>> [r["loops_above"] > 0 for r in coverage([tr], [tr, va])["records"]]
    [False, True]
    """
    v_tr = np.concatenate([r.v for r in train])
    span, reach = span_and_reach(train)
    h, reach = span / 2 * (1 + LOOP_TOL), reach * (1 + LOOP_TOL)
    out = []
    for r in validate:
        spanned = np.maximum.accumulate(r.v) - np.minimum.accumulate(r.v) > 2 * h
        loops = _moves(r.v, h) & spanned
        out.append({"source": r.source, "range": [float(r.v.min()), float(r.v.max())],
                    "loops_above": float(loops.mean()),
                    "beyond_reach": float(_moves(r.v, reach).mean()),
                    "first_loop_s": float(r.t[np.argmax(loops)] - r.t[0]) if loops.any()
                    else None})
    return {"train_range": [float(v_tr.min()), float(v_tr.max())],
            "half_range": span / 2, "reach": reach / (1 + LOOP_TOL),
            "records": out}
