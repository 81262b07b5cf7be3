"""Running the scripts in ``studies/``: discovery, output folders, result tables.

A study is a file ``studies/NAME.py`` defining ``run(out: Path, quick: bool) -> StudyResult``
(and a ``main()`` so it runs on its own). ``pimodel study NAME`` and ``python studies/NAME.py``
both call :func:`run_study`, which writes ``results.md``, ``results.json`` and the study's
figures (PNG) into the output folder.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import numpy as np

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
            "numbers": _jsonable(self.numbers),
            "tables": [{"title": t.title, "columns": t.columns, "rows": _jsonable(t.rows)}
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


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, Path):
        return str(x)
    return x


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


def run_study(name: str, out_dir=None, *, quick: bool = False) -> StudyResult:
    """Run study ``name``; writes results.md/json and figures to ``out_dir``."""
    module = load_study(name)
    out = Path(out_dir or Path("out") / "studies" / name).resolve()
    out.mkdir(parents=True, exist_ok=True)
    result: StudyResult = module.run(out, quick=quick)
    result.quick = quick
    (out / "results.json").write_text(json.dumps(result.to_json(), indent=2))
    (out / "results.md").write_text(result.to_markdown())
    return result


def study_main(name: str, argv: list[str] | None = None) -> int:
    """Command line of a study script: ``python studies/NAME.py [--quick] [--out DIR]``."""
    ap = argparse.ArgumentParser(prog=f"studies/{name}.py",
                                 description=load_study(name).__doc__)
    ap.add_argument("--quick", action="store_true", help="reduced size (as run in CI)")
    ap.add_argument("--out", default=None, help=f"output folder (default out/studies/{name})")
    args = ap.parse_args(argv)
    result = run_study(name, args.out, quick=args.quick)
    out = Path(args.out or Path("out") / "studies" / name).resolve()
    print(result.to_markdown())
    print(f"results: {out / 'results.md'}")
    return 0
