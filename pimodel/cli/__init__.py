"""The ``pimodel`` command line. Each subcommand lives in its own module of this package
with ``HELP`` (its one-line help) and ``register(subparsers)``; add a module name to
``COMMANDS`` to expose a new one. The modules import nothing heavy at their top: only the
chosen command is registered with its options, so ``pimodel --help`` loads no NumPy."""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from collections.abc import Iterable

__all__ = ["COMMANDS", "build_parser", "main"]

COMMANDS = ["simulate", "identify", "fmu", "diagnose", "split", "demo", "study", "sweep"]


def build_parser(full: Iterable[str] | None = None) -> argparse.ArgumentParser:
    """The argument parser; ``full`` names the commands registered with all their options
    (default: every command); the others are listed with their help line only."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        __version__ = version("pimodel")
    except PackageNotFoundError:  # pragma: no cover - run from a source tree, not installed
        __version__ = "unknown (not installed)"
    parser = argparse.ArgumentParser(
        prog="pimodel",
        description="Prandtl-Ishlinskii hysteresis: simulate, identify, compensate, build FMUs.",
    )
    parser.add_argument("--version", action="version", version=f"pimodel {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    full = set(COMMANDS if full is None else full)
    for name in COMMANDS:
        module = importlib.import_module(f"pimodel.cli.{name}")
        if name in full:
            module.register(sub)
        else:
            sub.add_parser(name, help=module.HELP)
    return parser


def _print_warnings_once(command: str):
    """A ``warnings.showwarning`` that prints each distinct warning once, as one line."""
    seen: set[str] = set()

    def show(message, category, filename, lineno, file=None, line=None):
        text = f"{category.__name__}: {message}"
        if text not in seen:
            seen.add(text)
            print(f"pimodel {command}: warning: {text}", file=sys.stderr)

    return show


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser([argv[0]] if argv and argv[0] in COMMANDS else [])
    args = parser.parse_args(argv)
    with warnings.catch_warnings():
        warnings.simplefilter("default")
        warnings.showwarning = _print_warnings_once(args.command)
        try:
            return int(args.func(args) or 0)
        except (ValueError, OSError) as exc:
            print(f"pimodel {args.command}: error: {exc}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:  # a sweep or study says what it kept before this
            print(f"pimodel {args.command}: interrupted", file=sys.stderr)
            return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
