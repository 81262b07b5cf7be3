"""The PIHysteresis FMU of an earlier commit, for ``bench_fmu.py --against REV``: the issue's
own yardstick (issue 29: 16.4 ns per sample at commit 0501d52) built again on this machine and
timed in the same run as the current build, by the same C host.

The commit's ``pimodel/`` and ``fmu/`` trees come out of git (``git archive``) into a temporary
folder; that commit's own ``pimodel/fmu/build.py`` (its sources, compiler flags, variable table
and GUID) builds the FMU there, with the compiler on this machine. The package is not
installed: its ``build`` module is imported under a private package name whose ``__init__`` is
never run, so nothing else of the old package (native libraries, the current ``pimodel``) is
loaded. The host's value references come from each FMU's own ``modelDescription.xml``.
"""

from __future__ import annotations

import importlib
import io
import subprocess
import sys
import tarfile
import types
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

UNIT = "PIHysteresis"  # the n-play PI unit, so called since the first FMU
HOST_VARIABLES = ("Ts", "n", "v", "y")  # scalars the host sets or reads; p and r: arrays
PACKAGING = ("setup.py", "pyproject.toml", "README.md", "LICENSE")  # to build a compiled core


class Unavailable(RuntimeError):
    """The revision cannot be built here: no git history, the revision is not in it, or it has
    no FMU sources."""


@dataclass(frozen=True)
class Binary:
    """An FMU binary as the C host needs it: the shared object, its GUID, and the host's
    ``config.h`` (the value references of ``Ts``, ``n``, ``v``, ``y``, ``p[1]``, ``r[1]``)."""

    so: Path
    guid: str
    config_h: str


def host_binary(fmu: Path, out_dir: Path) -> Binary:
    """Extract the FMI 2 binary of ``fmu`` into ``out_dir`` with the value references of its
    ``modelDescription.xml``; ValueError when the variables the host uses are missing or the
    arrays ``p[i]``, ``r[i]`` (i = 1..16) do not have consecutive value references."""
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
        ident = root.find("CoSimulation").get("modelIdentifier")
        member = f"binaries/linux64/{ident}.so"
        z.extract(member, out_dir)
    vr = {v.get("name"): int(v.get("valueReference")) for v in root.iter("ScalarVariable")}
    missing = [n for n in (*HOST_VARIABLES, "p[1]", "r[1]") if n not in vr]
    if missing:
        raise ValueError(f"{fmu.name}: no variable(s) {missing} for the host")
    for a in ("p", "r"):
        if any(vr.get(f"{a}[{i + 1}]") != vr[f"{a}[1]"] + i for i in range(16)):
            raise ValueError(f"{fmu.name}: {a}[1..16] do not have consecutive value references")
    enum = ",\n".join(f"    vr_{n} = {vr[n]}" for n in HOST_VARIABLES)
    config = ("/* fmu_host.c's value references, from the FMU's modelDescription.xml */\n"
              f"typedef enum {{\n{enum},\n    vr_p = {vr['p[1]']},\n    vr_r = {vr['r[1]']}\n"
              "} ValueReference;\n")
    return Binary(out_dir / member, root.get("guid"), config)


def commit_of(repo: Path, rev: str) -> str:
    """The full commit id of ``rev`` in ``repo``'s git history; Unavailable saying why not."""
    try:
        out = subprocess.run(["git", "-C", str(repo), "rev-parse", "--verify", "--quiet",
                              f"{rev}^{{commit}}"], capture_output=True, text=True)
    except FileNotFoundError:
        raise Unavailable("git is not installed") from None
    if out.returncode != 0:
        inside = subprocess.run(["git", "-C", str(repo), "rev-parse", "--git-dir"],
                                capture_output=True, text=True).returncode == 0
        raise Unavailable(f"commit {rev} is not in this checkout's git history" if inside else
                        f"{repo} has no git history (a source archive?): "
                          "the comparison needs a git clone that holds the commit")
    return out.stdout.strip()


def build_at(repo: Path, rev: str, out_dir: Path) -> Path:
    """The PIHysteresis FMU (FMI 2.0) of commit ``rev``, built by that commit's
    ``pimodel/fmu/build.py`` from that commit's sources into ``out_dir``; Unavailable when the
    commit or its FMU sources are not available.

    Where that ``build.py`` needs the package's compiled core (later commits read the C limits
    through ``pimodel._native``), the commit's own ``setup.py build_ext --inplace`` builds it in
    the temporary tree first."""
    commit = commit_of(repo, rev)
    if not _has(commit, repo, "pimodel/fmu/build.py"):
        raise Unavailable(f"commit {rev} has no FMU sources (pimodel/fmu/build.py, fmu/)")
    tree = out_dir / f"src-{commit[:12]}"
    tree.mkdir(parents=True)
    paths = [p for p in ("pimodel", "fmu", *PACKAGING) if _has(commit, repo, p)]
    tar = subprocess.run(["git", "-C", str(repo), "archive", "--format=tar", commit, *paths],
                         capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(tar)) as t:
        t.extractall(tree, filter="data")
    name = f"_pimodel_at_{commit[:12]}"
    try:
        build = _load_build(tree, name)
    except ImportError:
        if not (tree / "setup.py").exists():
            raise
        for mod in [m for m in sys.modules if m == name or m.startswith(f"{name}.")]:
            del sys.modules[mod]
        subprocess.run([sys.executable, "setup.py", "-q", "build_ext", "--inplace"], cwd=tree,
                       capture_output=True, check=True)
        build = _load_build(tree, name)
    (fmu,) = build.build_fmus(out_dir / f"fmu-{commit[:12]}", [UNIT])
    return Path(fmu)


def _has(commit: str, repo: Path, path: str) -> bool:
    return subprocess.run(["git", "-C", str(repo), "cat-file", "-e", f"{commit}:{path}"],
                          capture_output=True).returncode == 0


def _load_build(tree: Path, name: str) -> types.ModuleType:
    """``pimodel.fmu.build`` of the extracted ``tree`` as ``name.fmu.build``: the packages are
    empty stand-ins (their ``__init__`` is not run), so that the module's relative imports find
    the old siblings and nothing else of the old package is imported."""
    for pkg, path in ((name, tree / "pimodel"), (f"{name}.fmu", tree / "pimodel" / "fmu")):
        mod = types.ModuleType(pkg)
        mod.__path__ = [str(path)]
        sys.modules[pkg] = mod
    return importlib.import_module(f"{name}.fmu.build")
