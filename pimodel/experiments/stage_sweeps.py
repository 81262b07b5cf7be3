"""Users' sweeps over the truth simulator and the identification or diagnosis settings.

A case is a plain dict: any of the :class:`pimodel.stages.pi_stage.Truth` parameters
(:data:`TRUTH_PARAMS`, an effect switched off with ``None``), ``fs`` (sample rate of the
standard excitations, Hz), a ``seed``, and the settings of the target: :func:`pimodel.diagnose`
(``"diagnose"``, :data:`DIAGNOSE_SETTINGS`) or :func:`pimodel.identification.identify`
(``"identify"``,
:data:`IDENTIFY_SETTINGS`). Case ``seed`` makes the train excitation from seed ``2 seed + 1``,
the validate excitation from ``2 seed + 2`` (see :func:`pimodel.stages.pi_stage.excitation`, about
2.5 s
each), and their measurement noise from ``seed`` and ``100 + seed``, exactly as the
``sim_to_real`` study does, so a case's numbers depend on its dict alone.

:func:`truth_sweep` maps the cases with :func:`pimodel.experiments.sweeps.run_cases` and writes a
tidy table,
one row per case: its parameters, then the outcome (``diagnose``: verdict, whether it names the
truth's effects, gaps before/after the fix and their shrink, noise floor; ``identify``: plays,
train and validate RMS/max error in um, weights ``weights[1..n]`` and radii ``radii[1..n]``).
"""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path

import numpy as np

from ..stages.pi_stage import Truth
from .sweeps import DEFAULT_MEMORY_LIMIT, run_cases, tidy_rows, write_table

TRUTH_PARAMS = tuple(f.name for f in fields(Truth) if f.name not in ("weights", "radii", "extra"))
DIAGNOSE_SETTINGS = ("max_effects",)
IDENTIFY_SETTINGS = ("method", "n_plays", "linear_play", "gains", "passes", "guard",
                     "conventional_span", "max_segments")
TARGETS = {"diagnose": DIAGNOSE_SETTINGS, "identify": IDENTIFY_SETTINGS}

__all__ = ["DIAGNOSE_SETTINGS", "IDENTIFY_SETTINGS", "TARGETS", "TRUTH_PARAMS", "truth_case",
           "truth_sweep"]


def _check_case(params: dict, i: int | None = None) -> None:
    where = "params" if i is None else f"cases[{i}]"
    target = params.get("target")
    if target not in TARGETS:
        raise ValueError(f"{where}: 'target' must be one of {sorted(TARGETS)}, got {target!r}")
    known = {"target", "seed", "fs", *TRUTH_PARAMS, *TARGETS[target]}
    unknown = sorted(set(params) - known)
    if unknown:
        raise ValueError(f"{where}: unknown parameter(s) {unknown} for target {target!r}; "
                         f"known: {sorted(known)}")
    seed = params.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"{where}: 'seed' must be an integer >= 0, got {seed!r}")


def truth_case(params: dict) -> dict:
    """One case: simulate train/validate records of a truth, then diagnose or identify.

    Parameters
    ----------
    params : dict
        ``target`` (``"diagnose"`` or ``"identify"``), ``seed``, optional ``fs`` [Hz, default
        10000], truth parameters (:data:`TRUTH_PARAMS`) and the target's settings.

    Returns
    -------
    dict
        The outcome (see the module docstring); lengths in um.

    Raises
    ------
    ValueError
        Unknown keys or target, a bad seed, or an error of the simulator or target.

    Examples
    --------
    >>> r = truth_case({"target": "identify", "seed": 0, "noise_um": 0.01, "n_plays": 4})
    >>> r["n_plays"], r["validate_rms"] < 0.1
    (4, True)
    """
    from ..stages.pi_stage import excitation

    _check_case(params)
    seed, fs = params["seed"], params.get("fs", 10_000.0)
    truth = Truth(**{k: params[k] for k in TRUTH_PARAMS if k in params})
    tt, vt = excitation("train", fs=fs, seed=2 * seed + 1)
    tv, vv = excitation("validate", fs=fs, seed=2 * seed + 2)
    train = truth.record(tt, vt, seed, "train")
    validate = truth.record(tv, vv, 100 + seed, "validate")
    settings = {k: params[k] for k in TARGETS[params["target"]] if k in params}
    if params["target"] == "diagnose":
        from ..diagnosis import diagnose

        v = diagnose([train], [validate], **settings).verdict
        found = sorted(v["effects"])
        return {"verdict": "+".join(found), "correct": found == (sorted(truth.effects) or
                                                                  ["none"]),
                **{k: v[k] for k in ("gap_before", "gap_after", "shrink", "noise_floor")}}
    from ..identification.chain import identify

    idn = identify(train.v, train.y, dt=train.dt, **settings)
    r = idn.predict(validate.v) - validate.y
    r = r - np.mean(r)  # the offset is refitted on each record, as identify does
    return {"n_plays": idn.operator.n, "train_rms": idn.rms_error,
            "validate_rms": float(np.sqrt(np.mean(r**2))), "validate_max": float(np.abs(r).max()),
            "weights": idn.operator.weights, "radii": idn.operator.radii}


def truth_sweep(cases: Sequence[dict], *, target: str = "diagnose", out="out/sweeps/truth",
                table: str = "table.csv", workers: int | None = None,
                scheduler: str | None = None, fresh: bool = False,
                memory_limit: str | None = DEFAULT_MEMORY_LIMIT,
                progress: bool = True, counts: dict | None = None) -> list[dict]:
    """Run :func:`truth_case` over ``cases`` and write the tidy table ``out/table``.

    Parameters
    ----------
    cases : list of dict
        Truth parameters, target settings and a ``seed`` per case, e.g. from
        :func:`pimodel.experiments.sweeps.grid` or :func:`pimodel.experiments.sweeps.random_cases`.
    target : {"diagnose", "identify"}
        What each case runs; added to every case as ``"target"``.
    out : path
        Output folder: the table, and ``cases/`` with the finished cases (for resuming).
    table : str
        File name of the table in ``out``: ``.csv``, or ``.parquet`` (needs pyarrow).
    workers, scheduler, fresh, memory_limit, progress, counts
        Where and how the cases run, and the reused/computed counts, as in
        :func:`pimodel.experiments.sweeps.run_cases`.

    Returns
    -------
    list of dict
        The table's rows, one per case in case order.

    Raises
    ------
    ValueError
        Unknown target or parameter, a case without a seed, a bad table name.
    pimodel.experiments.sweeps.CaseFailed
        A case raised (finished cases stay in ``out/cases``).
    pimodel.experiments.sweeps.Interrupted
        Ctrl-C: the workers stopped, finished cases stay in ``out/cases``.

    Examples
    --------
    >>> from pimodel.experiments.sweeps import grid
    >>> rows = truth_sweep(grid(mode_hz=[800.0, 2500.0], seed=[0, 1]), target="diagnose",
    ...                    out="out/sweeps/modes", workers=2)  # doctest: +SKIP
    >>> import pandas as pd; pd.read_csv("out/sweeps/modes/table.csv")  # doctest: +SKIP
    """
    if target not in TARGETS:
        raise ValueError(f"target: expected one of {sorted(TARGETS)}, got {target!r}")
    if Path(table).suffix not in (".csv", ".parquet"):
        raise ValueError(f"table: expected a .csv or .parquet file name, got {table!r}")
    if Path(table).suffix == ".parquet" and importlib.util.find_spec("pyarrow") is None:
        raise ValueError(f"table {table!r}: Parquet needs pyarrow (pip install pyarrow); "
                         f"write a .csv instead")
    cases = [{**c, "target": target} for c in cases]
    for i, c in enumerate(cases):
        _check_case(c, i)
    out = Path(out)
    results = run_cases(truth_case, cases, workers=workers, scheduler=scheduler,
                        cache_dir=out / "cases", fresh=fresh, memory_limit=memory_limit,
                        progress=progress, desc=f"sweep ({target})", counts=counts)
    rows = tidy_rows(cases, results)
    write_table(rows, out / table)
    return rows
