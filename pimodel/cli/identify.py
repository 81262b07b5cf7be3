"""``pimodel identify``: slopes, then radii (or the conventional baseline), to JSON."""

from __future__ import annotations

import argparse
import json
import sys

from .common import (
    add_columns_option,
    float_list,
    load_inputs,
    progress_line,
    refuse_overwrite,
)

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
    p.add_argument("--json", required=True,
                   help="output model file (pimodel.model_files: the PI operator, its offset, "
                   "sample time, units, provenance and the fit report)")
    p.add_argument("--method", choices=["adaptive", "conventional", "joint"], default="adaptive",
                   help="adaptive: the paper's (slopes, then radii); conventional: preset radii, "
                   "least-squares weights; joint: weights and radii estimated together")
    p.add_argument("--plays", type=int, default=None,
                   help="number of plays (default: BIC on the slopes; conventional: 10)")
    p.add_argument("--gains", type=float_list, default=None,
                   help="estimator gains, one or one per play (default 20 / sum p^2)")
    p.add_argument("--passes", type=int, default=None, help="repetitions of the record")
    p.add_argument("--plots", default=None, metavar="DIR", help="write figures (PNG) here")
    p.add_argument("--quiet", action="store_true",
                   help="no progress line on stderr (it is shown only when stderr is a "
                   "terminal)")
    add_columns_option(p)
    p.set_defaults(func=run)


def _unit(column: str) -> str | None:
    """The unit in a column name ``quantity_unit`` (``voltage_V`` -> ``V``), else None."""
    head, sep, tail = column.rpartition("_")
    return tail if sep and head and tail else None


def _save_model_file(idn, rec, args: argparse.Namespace) -> None:
    """Write the identified model as a model file (``--json``)."""
    from pathlib import Path

    from ..model_files import Model, save_model
    from .common import columns_for

    tcol, vcol, ycol = columns_for(args, args.data)
    units = {k: u for k, u in (("time", _unit(tcol) or "s"), ("input", _unit(vcol)),
                               ("output", _unit(ycol))) if u}
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    save_model(Model(idn.operator, offset=idn.offset, dt=rec.dt, units=units), args.json,
               source={"record": str(args.data), "columns": [tcol, vcol, ycol],
                       "method": idn.method}, report=idn.to_json())


def run(args: argparse.Namespace) -> int:
    from ..identification.chain import identify

    refuse_overwrite({"DATA": [args.data]}, {"--json": args.json}, {"--plots": args.plots})
    (rec,) = load_inputs(args, [args.data])
    gains = None
    if args.gains is not None:
        gains = args.gains[0] if len(args.gains) == 1 else args.gains
    show = progress_line(args.quiet, label="identify")
    idn = identify(rec.v, rec.y, dt=rec.dt, n_plays=args.plays, method=args.method,
                   gains=gains, passes=args.passes, progress=show)
    if show is not None:
        show("done")
        sys.stderr.write("\n")
    _save_model_file(idn, rec, args)
    if args.plots:
        from ..identification.plots import plot_identification

        for path in plot_identification(idn, rec.t, rec.v, rec.y, args.plots):
            print(f"figure: {path}")
    print(json.dumps({k: idn.to_json()[k] for k in ("method", "weights", "radii", "fit")},
                     indent=1))
    # a failed health check is identify()'s UserWarning, printed once by the CLI
    print(f"wrote {args.json}")
    return 0
