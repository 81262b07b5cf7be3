"""``pimodel split``: cut one record into a train part and a validate part."""

from __future__ import annotations

import argparse

from .common import add_columns_option, columns_for, load_inputs, refuse_overwrite

__all__ = [
    "HELP",
    "register",
    "run",
]

HELP = "cut one record into a train part (the first samples) and a validate part (the rest)"


def register(sub) -> None:
    p = sub.add_parser(
        "split",
        help=HELP,
        description="Cut DATA in two at a share of its samples: the first FRACTION of the "
        "samples (the earlier times) go to --train, the rest (the later times) to --validate, "
        "for 'pimodel diagnose --train TRAIN --validate VALIDATE'. Time stamps and every "
        "column are kept as they are; the validate part starts in whatever state the train "
        "part left the stage (diagnose --initial-state unknown leaves that start-up out). "
        "Each output's format follows its suffix (.csv, .npz, .mat).",
    )
    p.add_argument("data", help="record (CSV with header, NPZ or MATLAB .mat)")
    p.add_argument("--fraction", type=float, default=0.5,
                   help="share of the samples in the train part, 0 < F < 1 (default 0.5)")
    p.add_argument("--train", required=True, help="output: the first part (for fitting)")
    p.add_argument("--validate", required=True, help="output: the second part (held out)")
    add_columns_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..records import save_record

    refuse_overwrite({"DATA": [args.data]}, {"--train": args.train, "--validate": args.validate})
    if args.train == args.validate:
        raise ValueError(f"--train and --validate: both {args.train}; give two file names")
    (rec,) = load_inputs(args, [args.data])
    try:
        train, validate = rec.split(args.fraction)
    except ValueError as exc:
        raise ValueError(f"--fraction {args.fraction}: {exc}") from None
    names = columns_for(args, args.data, [args.data])
    first = 0
    for part, path, what in ((train, args.train, "train"), (validate, args.validate, "validate")):
        written = save_record(part, path, columns=names)
        print(f"wrote {what} part: samples {first}..{first + len(part) - 1} of {len(rec)} "
              f"(t = {part.t[0]:.6g} .. {part.t[-1]:.6g} s) to {written}")
        first += len(part)
    return 0
