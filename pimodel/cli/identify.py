"""``pimodel identify``: slopes, then radii (or the conventional baseline), to JSON."""

from __future__ import annotations

import argparse
import json

from .common import add_columns_option, float_list, load_inputs, refuse_overwrite

__all__ = [
    "HELP",
    "register",
    "run",
]

HELP = "identify a PI model from a measured record"


def register(sub) -> None:
    p = sub.add_parser(
        "identify",
        help=HELP,
        description="Identify y = PI[v] + offset from DATA: number and weights of plays from "
        "the loop slopes, radii from the adaptive estimator (or the conventional baseline).",
    )
    p.add_argument("data", help="record (CSV with header, NPZ or MATLAB .mat)")
    p.add_argument("--json", required=True, help="output JSON file")
    p.add_argument("--method", choices=["adaptive", "conventional", "joint"], default="adaptive",
                   help="adaptive: the paper's (slopes, then radii); conventional: preset radii, "
                   "least-squares weights; joint: weights and radii estimated together")
    p.add_argument("--plays", type=int, default=None,
                   help="number of plays (default: BIC on the slopes; conventional: 10)")
    p.add_argument("--gains", type=float_list, default=None,
                   help="estimator gains, one or one per play (default 20 / sum p^2)")
    p.add_argument("--passes", type=int, default=None, help="repetitions of the record")
    p.add_argument("--plots", default=None, metavar="DIR", help="write figures (PNG) here")
    add_columns_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..identification.chain import identify

    refuse_overwrite({"DATA": [args.data]}, {"--json": args.json}, {"--plots": args.plots})
    (rec,) = load_inputs(args, [args.data])
    gains = None
    if args.gains is not None:
        gains = args.gains[0] if len(args.gains) == 1 else args.gains
    idn = identify(rec.v, rec.y, dt=rec.dt, n_plays=args.plays, method=args.method,
                   gains=gains, passes=args.passes)
    idn.save_json(args.json)
    if args.plots:
        from ..identification.plots import plot_identification

        for path in plot_identification(idn, rec.t, rec.v, rec.y, args.plots):
            print(f"figure: {path}")
    print(json.dumps({k: idn.to_json()[k] for k in ("method", "weights", "radii", "fit")},
                     indent=1))
    # a failed health check is identify()'s UserWarning, printed once by the CLI
    print(f"wrote {args.json}")
    return 0
