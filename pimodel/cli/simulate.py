"""``pimodel simulate``: run a PI operator (or its inverse) on a record's input column."""

from __future__ import annotations

import argparse

from ..data import Record, load_record, save_record
from ..operator import PIOperator
from .common import add_columns_option, float_list


def register(sub) -> None:
    p = sub.add_parser(
        "simulate",
        help="run a PI operator on a record's input",
        description="Run y = PI[v] on the input column of DATA (CSV or NPZ) and write a record "
        "t,v,y (y = model output; the measured output, if any, is kept as 'y_measured').",
    )
    p.add_argument("data", help="input record (CSV with header, or NPZ)")
    p.add_argument("--weights", type=float_list, required=True, help="weights p_i, e.g. 1,0.5")
    p.add_argument("--radii", type=float_list, required=True, help="radii r_i, e.g. 0,0.2")
    p.add_argument("--initial-state", type=float, default=0.0,
                   help="initial play state z_i[-1] (default 0)")
    p.add_argument("--inverse", action="store_true",
                   help="apply the exact inverse instead (input column read as desired output)")
    p.add_argument("--out", required=True, help="output record (.csv or .npz)")
    add_columns_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    rec = load_record(args.data, columns=args.columns)
    op = PIOperator(args.weights, args.radii, initial_state=args.initial_state)
    if args.inverse:
        op = op.inverse()
    y = op.simulate(rec.v)
    out = Record(rec.t, rec.v, y, {"y_measured": rec.y, **rec.extra}, source=args.out)
    save_record(out, args.out)
    print(f"wrote {len(out)} samples to {args.out}")
    return 0
