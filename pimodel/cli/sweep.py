"""``pimodel sweep TARGET``: a grid or random sweep over the truth simulator's parameters and the
diagnosis' or identification's settings, on Dask, into a tidy table (one row per case)."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from .common import check_outputs

__all__ = [
    "HELP",
    "HELP_NAMES",
    "build_cases",
    "register",
    "run",
]

HELP = "sweep the truth simulator and diagnosis/identification settings (tidy table)"

# The names the description lists, written out so that ``pimodel sweep --help`` imports no
# simulator (pimodel.stages loads SciPy and python-control: ~10 s on a loaded machine).
# tests/test_cli_hygiene.py holds them equal to pimodel.experiments.stage_sweeps' tuples.
HELP_NAMES = {
    "Truth parameters": ("creep_percent_per_decade", "mode_hz", "mode_damping", "delay_s",
                         "asymmetry", "drift_um_per_s", "drift_clock", "rate_gain", "noise_um",
                         "fs"),
    "Diagnose settings": ("max_effects",),
    "Identify settings": ("method", "n_plays", "linear_play", "gains", "passes", "guard",
                          "conventional_span", "max_segments"),
}


def _value(text: str):
    """A command-line value: JSON (numbers, true/false/null, lists) or else the text itself."""
    try:
        return json.loads(text)
    except ValueError:
        return text


def _assignment(text: str) -> tuple[str, str]:
    name, sep, value = text.partition("=")
    if not sep or not name.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}")
    return name.strip(), value.strip()


def _grid_axis(text: str) -> tuple[str, list]:
    name, values = _assignment(text)
    return name, [_value(v.strip()) for v in values.split(",")]


def _range(text: str) -> tuple[str, tuple[float, float]]:
    name, value = _assignment(text)
    lo, sep, hi = value.partition(":")
    try:
        if not sep:
            raise ValueError
        return name, (float(lo), float(hi))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NAME=LOW:HIGH, got {text!r}") from None


def register(sub) -> None:
    from ..experiments.studies import add_run_options

    p = sub.add_parser(
        "sweep",
        help=HELP,
        description="Run the diagnosis or the identification on records of the truth simulator "
        "over a grid (--grid) or a random sample (--random) of parameters, on a local Dask "
        "cluster or a given scheduler, and write OUT/table.csv (one row per case; "
        ".parquet with pyarrow). Finished cases are kept in OUT/cases, so a rerun computes "
        "only the missing ones. "
        + " ".join(f"{what}: {', '.join(names)}." for what, names in HELP_NAMES.items()),
    )
    p.add_argument("target", choices=["diagnose", "identify"], help="what each case runs")
    p.add_argument("--grid", type=_grid_axis, action="append", default=[], metavar="NAME=V1,V2",
                   help="a grid axis (repeatable; the grid is every combination)")
    p.add_argument("--random", type=_range, action="append", default=[],
                   metavar="NAME=LOW:HIGH", help="a uniformly sampled parameter (repeatable)")
    p.add_argument("--samples", type=int, default=None, metavar="N",
                   help="number of random cases (with --random)")
    p.add_argument("--set", type=_assignment, action="append", default=[], metavar="NAME=VALUE",
                   help="a fixed parameter or setting for every case (repeatable)")
    p.add_argument("--seeds", type=int, default=1, metavar="N",
                   help="seeds 0..N-1 for every grid point (default 1); random cases get "
                        "seeds --seed, --seed+1, ...")
    p.add_argument("--seed", type=int, default=0, help="seed of the random sample (default 0)")
    p.add_argument("--out", default=None, help="output folder (default out/sweeps/TARGET)")
    p.add_argument("--table", default="table.csv",
                   help="table file name in OUT: .csv (default) or .parquet (needs pyarrow)")
    add_run_options(p)
    p.set_defaults(func=run)


def build_cases(args: argparse.Namespace) -> list[dict]:
    """The cases the options describe (grid x seeds, or a random sample), with --set values."""
    from ..experiments.sweeps import grid, random_cases

    fixed = {name: _value(v) for name, v in args.set}
    if args.random:
        if args.grid:
            raise ValueError("--grid and --random: give one of them")
        if args.samples is None or args.samples < 1:
            raise ValueError(f"--samples: expected an integer >= 1 with --random, got "
                             f"{args.samples}")
        cases = random_cases(args.samples, seed=args.seed, **dict(args.random))
    else:
        if args.samples is not None:
            raise ValueError("--samples needs --random")
        if args.seeds < 1:
            raise ValueError(f"--seeds: expected an integer >= 1, got {args.seeds}")
        cases = grid(**dict(args.grid), seed=list(range(args.seeds)))
    clash = sorted(set(fixed) & set(cases[0]))
    if clash:
        raise ValueError(f"--set {', '.join(clash)}: already swept")
    return [{**c, **fixed} for c in cases]


def run(args: argparse.Namespace) -> int:
    from ..experiments.stage_sweeps import truth_sweep
    from ..experiments.sweeps import DEFAULT_MEMORY_LIMIT, CaseFailed, Interrupted

    cases = build_cases(args)
    out = Path(args.out or Path("out") / "sweeps" / args.target)
    check_outputs({"--table": str(out / args.table)}, {"--out": str(out)})
    t0 = time.perf_counter()
    counts: dict = {}
    try:
        rows = truth_sweep(cases, target=args.target, out=out, table=args.table,
                           workers=args.workers, scheduler=args.scheduler, fresh=args.fresh,
                           memory_limit=args.memory_limit or DEFAULT_MEMORY_LIMIT,
                           counts=counts)
    except CaseFailed as exc:
        print(f"pimodel sweep: error: {exc}", file=sys.stderr)
        return 1
    except Interrupted as exc:
        print(f"pimodel sweep: {exc}", file=sys.stderr)
        return 130
    print(f"sweep {args.target}: {len(rows)} cases ({counts['reused']} reused from "
          f"{out / 'cases'}, {counts['computed']} computed) in "
          f"{time.perf_counter() - t0:.1f} s; table {(out / args.table).resolve()}")
    return 0
