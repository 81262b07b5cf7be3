"""Argument helpers shared by subcommands."""

from __future__ import annotations

import argparse


def float_list(text: str) -> list[float]:
    """Parse ``"1,2.5,3"`` (commas or spaces) into floats, for argparse ``type=``."""
    parts = [s for s in text.replace(",", " ").split() if s]
    try:
        return [float(s) for s in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected numbers separated by commas, got {text!r}"
        ) from None


def column_names(text: str) -> tuple[str, str, str]:
    """Parse ``"time,input,output"`` into three column names, for argparse ``type=``."""
    names = tuple(s.strip() for s in text.split(","))
    if len(names) != 3 or not all(names):
        raise argparse.ArgumentTypeError(
            f"expected three column names 'time,input,output', got {text!r}"
        )
    return names  # type: ignore[return-value]


def add_columns_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--columns", type=column_names, default=("t", "v", "y"), metavar="T,V,Y",
        help="names of the time, input and output columns (default: t,v,y)",
    )
