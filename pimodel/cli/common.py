"""Argument helpers shared by subcommands."""

from __future__ import annotations

import argparse
import os
import warnings
from pathlib import Path

__all__ = [
    "add_columns_option",
    "column_names",
    "float_list",
    "refuse_overwrite",
    "unique_name",
]


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


def _same_file(a: Path, b: Path) -> bool:
    """Whether two paths name one file (resolved: relative paths, ``..`` and symlinks; hard
    links too when both exist)."""
    if a.resolve() == b.resolve():
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def refuse_overwrite(inputs: dict[str, list[str]], outputs: dict[str, str | None],
                     folders: dict[str, str | None] | None = None) -> None:
    """Raise ValueError when an output would write over an input file.

    Parameters
    ----------
    inputs : dict
        Argument name (e.g. ``"DATA"``, ``"--train"``) to the input file paths it gave.
    outputs : dict
        Argument name (e.g. ``"--json"``) to the output file path (None: not given).
    folders : dict, optional
        Argument name (e.g. ``"--plots"``) to an output folder: an error when it is an input
        file, or when an input file inside it has a suffix the command writes there (``.png``).

    Raises
    ------
    ValueError
        Naming the output argument, its path and the input argument and file it names.

    Examples
    --------
    >>> refuse_overwrite({"DATA": ["d.csv"]}, {"--json": "out.json"})
    >>> try:
    ...     refuse_overwrite({"DATA": ["d.csv"]}, {"--json": "./d.csv"})
    ... except ValueError as exc:
    ...     print(str(exc)[:41])
    --json ./d.csv is the input file DATA (d.csv)
    """
    files = [(arg, Path(p)) for arg, paths in inputs.items() for p in paths]
    for out_arg, out in outputs.items():
        if out is None:
            continue
        for in_arg, path in files:
            if _same_file(Path(out), path):
                raise ValueError(f"{out_arg} {out} is the input file {in_arg} ({path}); pimodel "
                                 "never writes over an input file: choose another output name")
    for out_arg, folder in (folders or {}).items():
        if folder is None:
            continue
        for in_arg, path in files:
            inside = path.suffix.lower() == ".png" and _same_file(Path(folder), path.parent)
            if _same_file(Path(folder), path) or inside:
                raise ValueError(f"{out_arg} {folder} would write over the input file {in_arg} "
                                 f"({path}); pimodel never writes over an input file: choose "
                                 "another folder")


def unique_name(name: str, taken, what: str = "column") -> str:
    """``name``, or ``name_1``, ``name_2``, ... when ``name`` is taken (with a warning).

    Examples
    --------
    >>> unique_name("y", ["t", "v"])
    'y'
    """
    if name not in taken:
        return name
    k = 1
    while f"{name}_{k}" in taken:
        k += 1
    warnings.warn(f"{what} '{name}' exists in the input; the new {what} is written as "
                  f"'{name}_{k}'", UserWarning, stacklevel=2)
    return f"{name}_{k}"
