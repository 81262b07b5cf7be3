"""Running the scripts in ``studies/``: discovery, output folders, result tables.

A study is a file ``studies/NAME.py`` that either is a sweep, defining

- ``cases(quick: bool) -> list[dict]``: its cases, plain JSON parameter dicts with their seeds;
- ``run_case(params: dict) -> dict``: one case (seeds its own generators from ``params``);
- ``aggregate(out: Path, quick: bool, cases, results) -> StudyResult``: tables, numbers and
  figures from the results (in case order), run in this process;

or, for a single computation, ``run(out: Path, quick: bool) -> StudyResult``. ``pimodel study
NAME`` and ``python studies/NAME.py`` both call :func:`run_study`, which maps a sweep's cases
with :func:`pimodel.sweep.run_cases` (serially, on a local Dask cluster or on a given
scheduler), keeps each finished case in ``OUT/cases/<key>.json`` (a rerun computes only the
missing ones) and writes ``results.md``, ``results.json`` and the figures (PNG) into ``OUT``.
``results.json`` holds no timings, so runs compare equal wherever they ran.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import numpy as np

from .sweep import CaseFailed, plain, run_cases

STUDIES_DIR = Path(__file__).resolve().parent.parent / "studies"


@dataclass
class Table:
    """A results table: ``columns`` names and ``rows`` of values (numbers or text)."""

    title: str
    columns: list[str]
    rows: list[list]

    def to_markdown(self, digits: int = 4) -> str:
        def fmt(x):
            if isinstance(x, float | np.floating):
                return f"{x:.{digits}g}"
            return str(x)

        lines = [f"**{self.title}**", "", "| " + " | ".join(self.columns) + " |",
                 "|" + "---|" * len(self.columns)]
        lines += ["| " + " | ".join(fmt(x) for x in row) + " |" for row in self.rows]
        return "\n".join(lines)


@dataclass
class StudyResult:
    """What a study returns: tables, key numbers (checked by tests), figure paths, notes."""

    name: str
    tables: list[Table] = field(default_factory=list)
    numbers: dict = field(default_factory=dict)
    figures: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    quick: bool = False

    def to_json(self) -> dict:
        return {
            "name": self.name,
            "quick": self.quick,
            "numbers": plain(self.numbers),
            "tables": [{"title": t.title, "columns": t.columns, "rows": plain(t.rows)}
                       for t in self.tables],
            "figures": [p.name for p in self.figures],
            "notes": self.notes,
        }

    def to_markdown(self) -> str:
        parts = [f"# Study `{self.name}`" + (" (quick size)" if self.quick else ""), ""]
        parts += [f"- {n}" for n in self.notes]
        for t in self.tables:
            parts += ["", t.to_markdown()]
        for p in self.figures:
            parts += ["", f"![{p.stem}]({p.name})"]
        return "\n".join(parts) + "\n"


def available_studies() -> list[str]:
    """Names of the study scripts in ``studies/`` (files not starting with ``_``)."""
    if not STUDIES_DIR.is_dir():
        return []
    return sorted(p.stem for p in STUDIES_DIR.glob("*.py") if not p.stem.startswith("_"))


def load_study(name: str) -> ModuleType:
    """Import ``studies/NAME.py`` as a module; ValueError naming the study when absent."""
    path = STUDIES_DIR / f"{name}.py"
    if not path.exists():
        known = ", ".join(available_studies()) or f"none found in {STUDIES_DIR}"
        raise ValueError(f"study '{name}' not found; available: {known}")
    spec = importlib.util.spec_from_file_location(f"pimodel_study_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def is_sweep(module: ModuleType) -> bool:
    """Whether a study module declares ``cases``, ``run_case`` and ``aggregate``."""
    return all(callable(getattr(module, f, None)) for f in ("cases", "run_case", "aggregate"))


def run_study(name: str, out_dir=None, *, quick: bool = False, workers: int | None = 0,
              scheduler: str | None = None, fresh: bool = False,
              memory_limit: str | None = None) -> StudyResult:
    """Run study ``name``; writes results.md/json and figures to ``out_dir``.

    Parameters
    ----------
    name : str
        A study in ``studies/`` (see :func:`available_studies`).
    out_dir : path or None
        Output folder (default ``out/studies/NAME``); a sweep keeps its finished cases in
        ``out_dir/cases``.
    quick : bool
        The reduced size run in CI.
    workers, scheduler, memory_limit
        Where a sweep's cases run, as in :func:`pimodel.sweep.run_cases` (``workers=0``:
        here, serially; ``None``: a local cluster with one worker per core). ``memory_limit``
        ``None`` means :data:`pimodel.sweep.DEFAULT_MEMORY_LIMIT`.
    fresh : bool
        Recompute every case instead of reusing the finished ones in ``out_dir/cases``.

    Returns
    -------
    StudyResult
        What the study found (also written to ``results.json`` and ``results.md``).

    Raises
    ------
    ValueError
        Unknown study or bad settings.
    CaseFailed
        A case of a sweep raised (the message names it; finished cases are kept).

    Examples
    --------
    >>> res = run_study("sim_to_real", "out/studies/sim_to_real", quick=True, workers=2)
    ... # doctest: +SKIP
    """
    from .sweep import DEFAULT_MEMORY_LIMIT

    module = load_study(name)
    out = Path(out_dir or Path("out") / "studies" / name).resolve()
    out.mkdir(parents=True, exist_ok=True)
    if is_sweep(module):
        cases = module.cases(quick)
        results = run_cases(module.run_case, cases, scheduler=scheduler,
                            workers=None if scheduler is not None else workers,
                            cache_dir=out / "cases", fresh=fresh,
                            memory_limit=memory_limit or DEFAULT_MEMORY_LIMIT, desc=name)
        result: StudyResult = module.aggregate(out, quick, cases, results)
    else:
        result = module.run(out, quick=quick)
    result.quick = quick
    (out / "results.json").write_text(json.dumps(result.to_json(), indent=2))
    (out / "results.md").write_text(result.to_markdown())
    return result


def add_run_options(ap: argparse.ArgumentParser) -> None:
    """Options shared by ``pimodel study``, ``pimodel sweep`` and ``python studies/NAME.py``:
    ``--workers``, ``--scheduler``, ``--memory-limit``, ``--fresh``."""
    where = ap.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, metavar="N",
                       help="local Dask worker processes (default: one per core); "
                            "0 runs serially in this process without Dask")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="address of a running Dask scheduler (tcp://host:8786) to run "
                            "the cases on instead of a local cluster")
    ap.add_argument("--memory-limit", default=None, metavar="SIZE",
                    help="memory limit per local worker (default 2GiB)")
    ap.add_argument("--fresh", action="store_true",
                    help="recompute every case (default: reuse the finished cases kept in "
                         "OUT/cases)")


def study_main(name: str, argv: list[str] | None = None) -> int:
    """Command line of a study script: ``python studies/NAME.py [--quick] [--out DIR]
    [--workers N | --scheduler ADDRESS] [--fresh]``."""
    ap = argparse.ArgumentParser(prog=f"studies/{name}.py",
                                 description=load_study(name).__doc__)
    ap.add_argument("--quick", action="store_true", help="reduced size (as run in CI)")
    ap.add_argument("--out", default=None, help=f"output folder (default out/studies/{name})")
    add_run_options(ap)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    try:
        result = run_study(name, args.out, quick=args.quick, workers=args.workers,
                           scheduler=args.scheduler, fresh=args.fresh,
                           memory_limit=args.memory_limit)
    except (ValueError, CaseFailed) as exc:
        print(f"studies/{name}.py: error: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out or Path("out") / "studies" / name).resolve()
    print(result.to_markdown())
    print(f"results: {out / 'results.md'} ({time.perf_counter() - t0:.1f} s)")
    return 0
