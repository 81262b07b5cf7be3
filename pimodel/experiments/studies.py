"""Running the scripts in ``studies/``: discovery, output folders, result tables.

A study is a file ``studies/NAME.py`` that either is a sweep, defining

- ``cases(quick: bool) -> list[dict]``: its cases, plain JSON parameter dicts with their seeds;
- ``run_case(params: dict) -> dict``: one case (seeds its own generators from ``params``);
- ``aggregate(out: Path, quick: bool, cases, results) -> StudyResult``: tables, numbers and
  figures from the results (in case order), run in this process;

or, for a single computation, ``run(out: Path, quick: bool) -> StudyResult``. ``pimodel study
NAME`` and ``python studies/NAME.py`` both call :func:`run_study`, which maps a sweep's cases
with :func:`pimodel.experiments.sweeps.run_cases` (serially, on a local Dask cluster or on a given
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

from .sweeps import CaseFailed, plain, run_cases

__all__ = [
    "add_run_options",
    "available_studies",
    "is_sweep",
    "load_study",
    "run_study",
    "study_main",
    "StudyResult",
    "Table",
]

STUDIES_DIR = Path(__file__).resolve().parents[2] / "studies"


@dataclass
class Table:
    """A results table: ``columns`` names and ``rows`` of values (numbers or text).

    Parameters
    ----------
    title : str
        Caption (bold in Markdown).
    columns : list of str
        Column names.
    rows : list of list
        One list per row, one value (number or text) per column.

    Examples
    --------
    >>> table = Table("Errors", ["model", "rms"], [["a", 0.123456], ["b", 2.0]])
    >>> table.to_markdown(3).splitlines()[2:]
    ['| model | rms |', '|---|---|', '| a | 0.123 |', '| b | 2 |']
    """

    title: str
    columns: list[str]
    rows: list[list]

    def to_markdown(self, digits: int = 4) -> str:
        """The table in Markdown: bold title, a blank line, then the pipe table.

        Parameters
        ----------
        digits : int, optional
            Significant digits of float values (``g`` format). Default 4.

        Returns
        -------
        str
            The Markdown lines joined by newlines (no final newline).

        Examples
        --------
        >>> table = Table("Errors", ["model", "rms"], [["a", 0.123456], ["b", 2.0]])
        >>> table.to_markdown().splitlines()[0], table.to_markdown().splitlines()[4]
        ('**Errors**', '| a | 0.1235 |')
        """
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
    """What a study returns: tables, key numbers (checked by tests), figure paths, notes.

    Parameters
    ----------
    name : str
        The study's name.
    tables : list of Table, optional
        Result tables.
    numbers : dict, optional
        Key numbers by name (checked by tests), JSON-convertible by
        :func:`pimodel.experiments.sweeps.plain`.
    figures : list of Path, optional
        Figure files (PNG) written into the output folder.
    notes : list of str, optional
        Sentences for the report.
    quick : bool, optional
        Whether the reduced (CI) size was run.

    Examples
    --------
    >>> table = Table("Errors", ["model", "rms"], [["a", 0.123456], ["b", 2.0]])
    >>> res = StudyResult("demo", tables=[table], numbers={"x": 1.5}, notes=["a note"])
    >>> res.to_json()["numbers"], res.to_markdown().splitlines()[:3]
    ({'x': 1.5}, ['# Study `demo`', '', '- a note'])
    """

    name: str
    tables: list[Table] = field(default_factory=list)
    numbers: dict = field(default_factory=dict)
    figures: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    quick: bool = False

    def to_json(self) -> dict:
        """The result as a JSON-ready dict (what ``results.json`` holds; no timings).

        Returns
        -------
        dict
            ``name``, ``quick``, ``numbers``, ``tables`` (title, columns, rows), ``figures``
            (file names) and ``notes``.

        Examples
        --------
        >>> StudyResult("demo", numbers={"x": np.float64(1.5)}).to_json()["numbers"]
        {'x': 1.5}
        """
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
        """The report (what ``results.md`` holds): heading, notes, tables, figure links.

        Returns
        -------
        str
            Markdown text ending in a newline.

        Examples
        --------
        >>> print(StudyResult("demo", notes=["a note"], quick=True).to_markdown(), end="")
        # Study `demo` (quick size)
        <BLANKLINE>
        - a note
        """
        parts = [f"# Study `{self.name}`" + (" (quick size)" if self.quick else ""), ""]
        parts += [f"- {n}" for n in self.notes]
        for t in self.tables:
            parts += ["", t.to_markdown()]
        for p in self.figures:
            parts += ["", f"![{p.stem}]({p.name})"]
        return "\n".join(parts) + "\n"


def available_studies() -> list[str]:
    """Names of the study scripts in ``studies/`` (files not starting with ``_``).

    Returns
    -------
    list of str
        Sorted study names (empty when ``studies/`` is absent, e.g. in an installed wheel).

    Examples
    --------
    >>> "compensation" in available_studies()
    True
    """
    if not STUDIES_DIR.is_dir():
        return []
    return sorted(p.stem for p in STUDIES_DIR.glob("*.py") if not p.stem.startswith("_"))


def load_study(name: str) -> ModuleType:
    """Import ``studies/NAME.py`` as a module; ValueError naming the study when absent.

    Parameters
    ----------
    name : str
        The study's name (file stem in ``studies/``).

    Returns
    -------
    types.ModuleType
        The executed study module.

    Raises
    ------
    ValueError
        No such study (the message lists the available ones).

    Examples
    --------
    >>> load_study("compensation").__name__
    'pimodel_study_compensation'
    """
    path = STUDIES_DIR / f"{name}.py"
    if not path.exists():
        known = ", ".join(available_studies()) or f"none found in {STUDIES_DIR}"
        raise ValueError(f"study '{name}' not found; available: {known}")
    spec = importlib.util.spec_from_file_location(f"pimodel_study_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def is_sweep(module: ModuleType) -> bool:
    """Whether a study module declares ``cases``, ``run_case`` and ``aggregate``.

    Parameters
    ----------
    module : types.ModuleType
        A study module (:func:`load_study`).

    Returns
    -------
    bool
        True for a sweep, False for a single computation (``run``).

    Examples
    --------
    >>> is_sweep(load_study("sim_to_real")), is_sweep(load_study("compensation"))
    (True, False)
    """
    return all(callable(getattr(module, f, None)) for f in ("cases", "run_case", "aggregate"))


def run_study(name: str, out_dir=None, *, quick: bool = False, workers: int | None = 0,
              scheduler: str | None = None, fresh: bool = False,
              memory_limit: str | None = None, counts: dict | None = None) -> StudyResult:
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
        Where a sweep's cases run, as in :func:`pimodel.experiments.sweeps.run_cases`
        (``workers=0``:
        here, serially; ``None``: a local cluster with one worker per core). ``memory_limit``
        ``None`` means :data:`pimodel.experiments.sweeps.DEFAULT_MEMORY_LIMIT`.
    fresh : bool
        Recompute every case instead of reusing the finished ones in ``out_dir/cases``.
    counts : dict, optional
        For a sweep: filled with the reused and computed case counts
        (:func:`pimodel.experiments.sweeps.run_cases`).

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
    from .sweeps import DEFAULT_MEMORY_LIMIT

    module = load_study(name)
    out = Path(out_dir or Path("out") / "studies" / name).resolve()
    out.mkdir(parents=True, exist_ok=True)
    if is_sweep(module):
        cases = module.cases(quick)
        results = run_cases(module.run_case, cases, scheduler=scheduler,
                            workers=None if scheduler is not None else workers,
                            cache_dir=out / "cases", fresh=fresh,
                            memory_limit=memory_limit or DEFAULT_MEMORY_LIMIT, desc=name,
                            counts=counts)
        result: StudyResult = module.aggregate(out, quick, cases, results)
    else:
        result = module.run(out, quick=quick)
    result.quick = quick
    (out / "results.json").write_text(json.dumps(result.to_json(), indent=2))
    (out / "results.md").write_text(result.to_markdown())
    return result


def add_run_options(ap: argparse.ArgumentParser) -> None:
    """Options shared by ``pimodel study``, ``pimodel sweep`` and ``python studies/NAME.py``:
    ``--workers``, ``--scheduler``, ``--memory-limit``, ``--fresh``.

    Parameters
    ----------
    ap : argparse.ArgumentParser
        The parser to add them to (``--workers`` and ``--scheduler`` exclude each other).

    Examples
    --------
    >>> import argparse
    >>> ap = argparse.ArgumentParser()
    >>> add_run_options(ap)
    >>> ap.parse_args(["--workers", "0"])
    Namespace(workers=0, scheduler=None, memory_limit=None, fresh=False)
    """
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
    [--workers N | --scheduler ADDRESS] [--fresh]``.

    Runs :func:`run_study`, prints the Markdown report and where the results are.

    Parameters
    ----------
    name : str
        The study's name.
    argv : list of str, optional
        The arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0, or 2 when the study or a case failed (the error is printed on
        stderr).

    Raises
    ------
    ValueError
        If there is no study ``name``.

    Examples
    --------
    A quick run of a study takes seconds to minutes, hence skipped here:

    >>> study_main("compensation", ["--quick", "--workers", "0"])  # doctest: +SKIP
    0
    """
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
