"""``pimodel demo``: the headline chain with a one-page report."""

from __future__ import annotations

import argparse

__all__ = [
    "HELP",
    "register",
    "run",
]

HELP = "run the headline chain on the embedded piezo-like stage"


def register(sub) -> None:
    p = sub.add_parser(
        "demo",
        help=HELP,
        description="Run the headline chain on the embedded piezo-like stage and write a "
        "one-page Markdown report with figures; prints the report's path.",
    )
    p.add_argument("--out", default="pimodel-demo", help="output folder (default: pimodel-demo)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..experiments.demo import run_demo

    report = run_demo(args.out)
    print(f"report: {report}")
    return 0
