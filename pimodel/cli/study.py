"""``pimodel study NAME``: run a study script from ``studies/``."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

__all__ = [
    "HELP",
    "register",
    "run",
]

HELP = "run a study (figures and results tables into an output folder)"


def register(sub) -> None:
    from ..experiments.studies import add_run_options, available_studies

    names = ", ".join(available_studies()) or "none found"
    p = sub.add_parser(
        "study",
        help=HELP,
        description=f"Run a study from studies/ and write its figures (PNG) and results "
        f"(Markdown and JSON) to an output folder. A sweep study maps its cases on Dask "
        f"(--workers, --scheduler) and keeps each finished case in OUT/cases, so a rerun "
        f"computes only the missing ones. Studies: {names}.",
    )
    p.add_argument("name", nargs="?", help="study name ('all' runs every study)")
    p.add_argument("--quick", action="store_true", help="reduced size (as run in CI)")
    p.add_argument("--out", default=None,
                   help="output folder (default out/studies/NAME; with 'all', a parent folder)")
    p.add_argument("--list", action="store_true", help="list the studies and exit")
    add_run_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..experiments.studies import available_studies, run_study
    from ..experiments.sweeps import CaseFailed, Interrupted

    if args.list or not args.name:
        for name in available_studies():
            print(name)
        return 0
    names = available_studies() if args.name == "all" else [args.name]
    for name in names:
        out = None
        if args.out:
            out = Path(args.out) / name if args.name == "all" else Path(args.out)
        t0 = time.perf_counter()
        counts: dict = {}
        try:
            result = run_study(name, out, quick=args.quick, workers=args.workers,
                               scheduler=args.scheduler, fresh=args.fresh,
                               memory_limit=args.memory_limit, counts=counts)
        except CaseFailed as exc:
            print(f"pimodel study: error in study {name}: {exc}", file=sys.stderr)
            return 1
        except Interrupted as exc:
            print(f"pimodel study {name}: {exc}", file=sys.stderr)
            return 130
        print(result.to_markdown())
        cases = (f"{counts['reused']} cases reused, {counts['computed']} computed; "
                 if counts else "")
        print(f"study {name}: results in {Path(out or Path('out') / 'studies' / name).resolve()}"
              f" ({cases}{time.perf_counter() - t0:.1f} s)")
    return 0
