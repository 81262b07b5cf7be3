"""Argument helpers shared by subcommands."""

from __future__ import annotations

import argparse
import os
import warnings
from pathlib import Path

__all__ = [
    "add_columns_option",
    "check_outputs",
    "column_names",
    "column_spec",
    "columns_for",
    "float_list",
    "load_inputs",
    "progress_line",
    "refuse_overwrite",
    "unique_name",
]

DEFAULT_COLUMNS = ("t", "v", "y")


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


def column_spec(text: str) -> tuple[str | None, tuple[str, str, str]]:
    """Parse ``"T,V,Y"`` (every input file) or ``"FILE:T,V,Y"`` (one input file), for argparse
    ``type=``: ``(FILE or None, (T, V, Y))``."""
    file, _, names = text.rpartition(":")
    return (file or None), column_names(names)


def add_columns_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--columns", type=column_spec, action="append", default=[], metavar="[FILE:]T,V,Y",
        help="names of the time, input and output columns (default: t,v,y); FILE:T,V,Y names "
        "them for one input file (repeatable; the chosen columns are the record's t, v, y, "
        "other columns keep their own names)",
    )


def columns_for(args: argparse.Namespace, path: str,
                inputs: list[str] | None = None) -> tuple[str, str, str]:
    """The ``--columns`` names for input file ``path``: its ``FILE:`` entry, else the entry
    without a file, else ``t,v,y``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed options with ``columns`` from :func:`add_columns_option`.
    path : str
        The input file.
    inputs : list of str, optional
        Every input file of the command: a ``FILE:`` entry that names none of them, or two
        entries for one file, is an error.

    Returns
    -------
    tuple of str
        Time, input and output column names.

    Raises
    ------
    ValueError
        Naming the ``--columns`` entry.

    Examples
    --------
    >>> import argparse
    >>> args = argparse.Namespace(columns=[column_spec("a.csv:time,U,x"), column_spec("t,u,y")])
    >>> columns_for(args, "a.csv"), columns_for(args, "b.csv")
    (('time', 'U', 'x'), ('t', 'u', 'y'))
    """
    generic = [names for file, names in args.columns if file is None]
    if len(generic) > 1:
        raise ValueError(f"--columns: given {len(generic)} times without FILE:; give one "
                         "T,V,Y for every file, and FILE:T,V,Y for the others")
    for file, names in args.columns:
        if file is not None and inputs is not None and \
                not any(_same_file(Path(file), Path(p)) for p in inputs):
            raise ValueError(f"--columns {file}:{','.join(names)}: {file} is not an input file "
                             f"of this command (inputs: {', '.join(inputs)})")
    mine = [names for file, names in args.columns
            if file is not None and _same_file(Path(file), Path(path))]
    if len(mine) > 1:
        raise ValueError(f"--columns: {path} is named {len(mine)} times")
    return mine[0] if mine else (generic[0] if generic else DEFAULT_COLUMNS)


def load_inputs(args: argparse.Namespace, files: list[str], inputs: list[str] | None = None,
                **kwargs) -> list:
    """Load each file with its ``--columns`` (:func:`columns_for`); ``kwargs`` go to
    :func:`pimodel.records.load_record`."""
    from ..records import load_record

    return [load_record(f, columns=columns_for(args, f, inputs or files), **kwargs)
            for f in files]


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
    """Raise ValueError when an output would write over an input file or another output.

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
        Naming the output argument, its path and the input argument and file it names; two
        output arguments that name one file; or an output path that cannot be written
        (:func:`check_outputs`).

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
    given = [(arg, out) for arg, out in outputs.items() if out is not None]
    for i, (out_arg, out) in enumerate(given):
        for other_arg, other in given[:i]:
            if _same_file(Path(out), Path(other)):
                raise ValueError(f"{out_arg} {out} is also the output {other_arg} ({other}): "
                                 "one would write over the other; choose another output name")
    for out_arg, folder in (folders or {}).items():
        if folder is None:
            continue
        for in_arg, path in files:
            inside = path.suffix.lower() == ".png" and _same_file(Path(folder), path.parent)
            if _same_file(Path(folder), path) or inside:
                raise ValueError(f"{out_arg} {folder} would write over the input file {in_arg} "
                                 f"({path}); pimodel never writes over an input file: choose "
                                 "another folder")
    check_outputs(outputs, folders)


def _writable_folder(option: str, path: Path) -> None:
    """The nearest existing folder above ``path`` must be a folder we may write in."""
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise ValueError(f"{option} {path}: {parent} is a file, not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"{option} {path}: no permission to write in {parent}")


def check_outputs(files: dict[str, str | None],
                  folders: dict[str, str | None] | None = None) -> None:
    """Raise ValueError, before any work, when an output path cannot be written.

    Parameters
    ----------
    files : dict
        Option (``"--json"``) to an output file path (None: not given): it must not be a
        folder, and the folder it goes in must be a folder we may write in (missing folders
        are created later).
    folders : dict, optional
        Option (``"--plots"``) to an output folder: it must not be a file.

    Raises
    ------
    ValueError
        Naming the option, the path and what is wrong.

    Examples
    --------
    >>> import tempfile
    >>> try:
    ...     check_outputs({"--json": tempfile.gettempdir()})
    ... except ValueError as exc:
    ...     print(str(exc).split(":")[-1])
    ...
     a folder; expected a file name
    """
    for option, out in files.items():
        if out is None:
            continue
        path = Path(out)
        if path.is_dir():
            raise ValueError(f"{option} {out}: a folder; expected a file name")
        _writable_folder(option, path)
    for option, out in (folders or {}).items():
        if out is None:
            continue
        path = Path(out)
        if path.exists() and not path.is_dir():
            raise ValueError(f"{option} {out}: a file; expected a folder")
        _writable_folder(option, path)


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


def progress_line(quiet: bool = False, stream=None, *, label: str = "diagnose"):
    """A ``progress(message)`` callback that rewrites one line on ``stream`` (default stderr)
    with ``label``, the message and the seconds elapsed; None when ``quiet`` or the stream is
    not a terminal (logs and pipes stay clean)."""
    import sys
    import time

    stream = stream or sys.stderr
    if quiet or not stream.isatty():
        return None
    t0 = time.perf_counter()

    def show(message: str) -> None:
        stream.write(f"\r\x1b[K{label}: {message} [{time.perf_counter() - t0:.0f} s]")
        stream.flush()

    return show
