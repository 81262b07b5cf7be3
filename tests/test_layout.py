"""The house rules of the package layout (docs/DEVELOPING.md), checked on the import graph.

Every ``import`` of a pimodel module by a pimodel module is an edge, wherever it stands (module
level, inside a function, under ``TYPE_CHECKING``): 0 cycles; no edge from a lower layer to a
higher one; at most 12 modules directly under ``pimodel/``; every public module has an
``__all__``; the 0.1 import paths still load the new modules, with a DeprecationWarning.
"""

from __future__ import annotations

import ast
import importlib
import sys
import warnings
from pathlib import Path

import pytest

import pimodel
from pimodel._deprecated import MOVED

PKG = Path(pimodel.__file__).resolve().parent

# bottom to top: a module may import from its own layer or below (pimodel/__init__ is the top)
LAYERS = ["cores", "checks", "signals", "plotting", "records", "_native", "_deprecated",
          "operators", "reference", "identification", "blocks", "loops", "stages", "diagnosis",
          "model_files", "fmu", "experiments", "cli", "__main__"]


def _modules() -> dict[str, Path]:
    mods = {}
    for path in PKG.rglob("*.py"):
        parts = path.relative_to(PKG.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        mods[name] = path
    return mods


MODULES = _modules()


def _edges() -> dict[str, set[str]]:
    edges = {m: set() for m in MODULES}
    for mod, path in MODULES.items():
        is_pkg = path.name == "__init__.py"
        package = mod if is_pkg else mod.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    hit = sub if sub in MODULES else target if target in MODULES else None
                    if hit and hit != mod:
                        edges[mod].add(hit)
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name in MODULES and alias.name != mod:
                        edges[mod].add(alias.name)
    return edges


EDGES = _edges()


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(root):
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges[w]))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))

    for m in sorted(edges):
        if m not in index:
            visit(m)
    return out


def _layer(mod: str) -> int:
    parts = mod.split(".")
    return len(LAYERS) if len(parts) == 1 else LAYERS.index(parts[1])


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles():
    assert _cycles(EDGES) == []


def test_every_top_level_name_has_a_layer():
    tops = {m.split(".")[1] for m in MODULES if m != "pimodel"}
    assert tops <= set(LAYERS), tops - set(LAYERS)


def test_no_upward_imports_between_layers():
    upward = sorted((m, t) for m, ts in EDGES.items() for t in ts if _layer(t) > _layer(m))
    assert upward == []


def test_at_most_twelve_modules_directly_under_pimodel():
    top = sorted(p.name for p in PKG.glob("*.py"))
    assert len(top) <= 12, top


def test_every_public_module_has_all():
    missing = [m for m, p in MODULES.items()
               if not any(part.startswith("_") for part in m.split(".")[1:])
               and "__all__" not in p.read_text()]
    assert missing == []


def test_every_name_in_all_exists():
    for mod in sorted(m for m in MODULES if m != "pimodel.__main__"):
        module = importlib.import_module(mod)
        for name in getattr(module, "__all__", []):
            assert hasattr(module, name), f"{mod}.__all__ names {name!r}, which it lacks"


@pytest.mark.parametrize("old", sorted(MOVED))
def test_old_path_loads_the_new_module_with_a_deprecation_warning(old):
    new = importlib.import_module(MOVED[old])
    saved = sys.modules.pop(old, None)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            module = importlib.import_module(old)
        assert module is new
        assert any(issubclass(w.category, DeprecationWarning) and MOVED[old] in str(w.message)
                   for w in caught)
    finally:
        if saved is not None:
            sys.modules[old] = saved


def test_new_paths_import_without_deprecation_warnings():
    code = ("import warnings; warnings.simplefilter('error', DeprecationWarning); "
            + "; ".join(f"import {m}" for m in sorted(MODULES) if m != "pimodel.__main__"))
    import subprocess

    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]


def test_old_paths_leave_the_package_names_alone():
    """``import pimodel.identify`` (the 0.1 module) must not replace the function
    ``pimodel.identify``, as 0.1's import never did."""
    before = {name: getattr(pimodel, name) for name in pimodel.__all__}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        for old in sorted(MOVED):
            sys.modules.pop(old, None)
            importlib.import_module(old)
    assert {name: getattr(pimodel, name) for name in pimodel.__all__} == before
    assert pimodel.identify.__module__ == "pimodel.identification.chain"
