"""Docstrings of the modules held to the full standard (``STRICT_MODULES`` in docs/conf.py):
numpydoc sections on every public name (checked with ``numpydoc.validate``), Examples that run
(doctest), and a package docstring that maps every exported name."""

from __future__ import annotations

import ast
import doctest
import importlib
import inspect
from pathlib import Path

import numpy as np
import pytest

import pimodel

validate = pytest.importorskip("numpydoc.validate", reason="the docs extra is not installed")

CONF = Path(__file__).resolve().parent.parent / "docs" / "conf.py"
# GL08 no docstring, SS01 no summary, PR01/PR02 parameters missing/unknown, PR10 "x:int",
# RT01 no Returns, EX01 no Examples
CHECKS = {"GL08", "SS01", "PR01", "PR02", "PR10", "RT01", "EX01"}


def strict_modules() -> list[str]:
    """STRICT_MODULES from docs/conf.py, read without running the Sphinx configuration."""
    for node in ast.parse(CONF.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "STRICT_MODULES":
            return ast.literal_eval(node.value)
    raise AssertionError("docs/conf.py defines no STRICT_MODULES")


def public_names(module_name: str) -> list[str]:
    """Functions and classes the module defines (no leading underscore) and their methods."""
    mod = importlib.import_module(module_name)
    names = []
    for name, obj in vars(mod).items():
        if name.startswith("_") or getattr(obj, "__module__", None) != module_name:
            continue
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        names.append(f"{module_name}.{name}")
        if inspect.isclass(obj):
            names += [f"{module_name}.{name}.{m}" for m, f in vars(obj).items()
                      if not m.startswith("_") and inspect.isfunction(f)]
    return names


SUBMODULES = [m for m in strict_modules() if m != "pimodel"]
NAMES = [n for m in SUBMODULES for n in public_names(m)]


def test_strict_modules_are_listed_and_have_names():
    assert len(SUBMODULES) >= 10
    assert len(NAMES) >= 30, NAMES


@pytest.mark.parametrize("name", NAMES)
def test_numpydoc_sections(name):
    report = validate.validate(name)
    errors = [f"{code}: {msg}" for code, msg in report["errors"] if code in CHECKS]
    assert not errors, f"{name}:\n" + "\n".join(errors)


@pytest.mark.parametrize("module_name", SUBMODULES)
def test_examples_run(module_name):
    mod = importlib.import_module(module_name)
    np.set_printoptions(precision=8, legacy=False)
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE,
                             extraglobs={"np": np})
    assert result.attempted > 0, f"{module_name}: no example ran"
    assert result.failed == 0, f"{module_name}: {result.failed} example(s) failed"


def test_package_docstring_maps_every_exported_name():
    doc = pimodel.__doc__
    missing = [n for n in pimodel.__all__ if f"\n{n} " not in doc]
    assert not missing, f"pimodel's docstring does not list {missing}"
