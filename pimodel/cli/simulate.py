"""``pimodel simulate``: run a PI operator (or its inverse) on a record's input column."""

from __future__ import annotations

import argparse

from .common import add_columns_option, float_list, load_inputs, refuse_overwrite, unique_name

__all__ = [
    "HELP",
    "register",
    "run",
]

HELP = "run a PI operator on a record's input"


def register(sub) -> None:
    p = sub.add_parser(
        "simulate",
        help=HELP,
        description="Run y = PI[v] on the input column of DATA (CSV or NPZ) and write a record "
        "t,v,y (y = model output; the measured output, if any, is kept as 'y_measured'; a "
        "new column whose name the input already uses gets a suffix _1, _2, ... with a "
        "warning). The output file must not be the input file.",
    )
    p.add_argument("data", help="input record (CSV with header, NPZ or MATLAB .mat)")
    p.add_argument("--model", default=None, metavar="MODEL.json",
                   help="a model file (pimodel identify --json, save_model): its operator and "
                   "offset, instead of --weights and --radii")
    p.add_argument("--weights", type=float_list, default=None, help="weights p_i, e.g. 1,0.5")
    p.add_argument("--radii", type=float_list, default=None, help="radii r_i, e.g. 0,0.2")
    p.add_argument("--initial-state", type=float, default=0.0,
                   help="initial play state z_i[-1] (default 0)")
    p.add_argument("--inverse", action="store_true",
                   help="apply the exact inverse instead (input column read as desired output)")
    p.add_argument("--out", required=True, help="output record (.csv or .npz)")
    add_columns_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..operators.pi import PIOperator
    from ..records import Record, save_record

    if (args.model is None) == (args.weights is None or args.radii is None) or \
            (args.model is not None and (args.weights or args.radii)):
        raise ValueError("give either --model or both --weights and --radii")
    refuse_overwrite({"DATA": [args.data], "--model": [args.model] if args.model else []},
                     {"--out": args.out})
    (rec,) = load_inputs(args, [args.data], output_required=False)
    if args.model is not None:
        from ..model_files import load_model

        op = load_model(args.model)
    else:
        op = PIOperator(args.weights, args.radii, initial_state=args.initial_state)
    if args.inverse:
        op = op.inverse()
    y = op.simulate(rec.v)
    taken = list(rec.extra)
    names = [unique_name(n, taken) for n in ("t", "v", "y")]
    extra = dict(rec.extra)
    if rec.has_output:
        extra = {unique_name("y_measured", taken + names): rec.y, **extra}
    out = Record(rec.t, rec.v, y, extra, source=args.out)
    written = save_record(out, args.out, columns=tuple(names))  # exactly args.out
    print(f"wrote {len(out)} samples to {written}")
    return 0
