"""``pimodel diagnose``: where the sim-to-real gap lies and which effect causes it."""

from __future__ import annotations

import argparse
import json

from ..data import load_record
from .common import add_columns_option, refuse_overwrite


def register(sub) -> None:
    p = sub.add_parser(
        "diagnose",
        help="diagnose the gap between a PI model and measured records",
        description="Fit a PI model on the --train records, measure the residual on the "
        "--validate records (never used for fitting), rank where it concentrates, test the "
        "candidate effects (creep, dynamics, delay, asymmetry, drift, rate) and report how far "
        "the validate gap shrinks, against a noise floor measured from repeated input periods "
        "(else a local model); a gap no effect explains is reported as 'unexplained'. All "
        "records must share one sample time; t is used as given.",
    )
    p.add_argument("--train", action="append", required=True, metavar="CSV",
                   help="train record (repeatable)")
    p.add_argument("--validate", action="append", required=True, metavar="CSV",
                   help="validate record (repeatable)")
    p.add_argument("--json", required=True, help="output JSON report")
    p.add_argument("--plots", default=None, metavar="DIR", help="write figures (PNG) here")
    p.add_argument("--initial-state", choices=("rest", "unknown"), default="rest",
                   help="'unknown': leave each record's start-up region (until the input first "
                   "spans 90 %% of its range) out of fitting and scoring (default: rest)")
    add_columns_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..diagnosis import diagnose

    refuse_overwrite({"--train": args.train, "--validate": args.validate},
                     {"--json": args.json}, {"--plots": args.plots})
    train = [load_record(f, columns=args.columns) for f in args.train]
    validate = [load_record(f, columns=args.columns) for f in args.validate]
    rep = diagnose(train, validate, initial_state=args.initial_state)
    rep.save_json(args.json)
    if args.plots:
        from ..diagnosis.plots import plot_diagnosis

        for path in plot_diagnosis(rep, args.plots):
            print(f"figure: {path}")
    v = rep.verdict
    print(json.dumps({k: v[k] for k in ("effects", "gap_before", "gap_after", "shrink",
                                        "noise_floor", "noise_floor_method")}, indent=1))
    print(f"wrote {args.json}")
    return 0
