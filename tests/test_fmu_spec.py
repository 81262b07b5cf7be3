"""One source of truth for the FMU variables and the C limits.

The value references live in the Python spec (``pimodel.fmu.spec``), from which each FMU's
``config.h`` (the C ``ValueReference`` enum and variable table) and its ``modelDescription.xml``
are generated; the limits live in C (``fmu/src/core/pim_limits.h``) and Python reads them from
the compiled core (``pimodel._native.LIMITS``). These tests hold the generated C table equal to
the built model descriptions (FMI 2 and 3), and check that neither number is typed by hand in
the other language.
"""

from __future__ import annotations

import re
import subprocess
import zipfile
from pathlib import Path

import fmpy
import pytest

from pimodel._native import LIMITS
from pimodel.fmu import MODELS
from pimodel.fmu.build import find_compiler, fmu_filename
from pimodel.fmu.sources import source_dir

ROOT = Path(__file__).resolve().parents[1]

# Prints the table of config.h as C sees it (enum values, sizes), one variable a line.
HOST = r"""
#include <stdio.h>
#include "pim_limits.h"
#define PIM_NMAX PIM_MAX_PLAYS
#define PIM_PER_PLAY (-1)
#include "config.h"
#define ROW(name, vr, type, causality, size, member) \
    printf("%s %u %c %s %d\n", name, (unsigned)(vr), type, #causality, (int)(size));
int main(void)
{
    PIM_UNIT_VARIABLES(ROW)
    return 0;
}
"""


def _c_table(fmu: Path, tmp: Path) -> set[tuple[str, int, str, str, int]]:
    """The variable table compiled from the FMU's own sources/config.h."""
    with zipfile.ZipFile(fmu) as z:
        for f in ("config.h", "pim_limits.h"):
            (tmp / f).write_bytes(z.read(f"sources/{f}"))
    (tmp / "host.c").write_text(HOST)
    exe = tmp / "host"
    subprocess.run([find_compiler(), "-std=c99", "-Wall", "-Wextra", "-Werror", "-I", str(tmp),
                    str(tmp / "host.c"), "-o", str(exe)], check=True)
    rows = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    return {(name, int(vr), typ, causality.removeprefix("PIM_").lower(), int(size))
            for name, vr, typ, causality, size in (line.split() for line in rows.splitlines())}


@pytest.mark.parametrize("fmi_version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", list(MODELS))
def test_generated_c_table_equals_built_model_description(built_fmus, tmp_path, name,
                                                          fmi_version):
    """Every variable of the built modelDescription.xml has the name, value reference, type,
    causality and size of the C table compiled from the same FMU's config.h, and back; in FMI 3
    the per-play arrays (size -1 in C) have one dimension, the structural parameter n_plays."""
    fmu = built_fmus / fmu_filename(name, fmi_version)
    table = _c_table(fmu, tmp_path)
    types = ({"R": "Real", "I": "Integer", "B": "Boolean"} if fmi_version == "2.0"
             else {"R": "Float64", "I": "Int32", "B": "Boolean", "U": "UInt64"})
    n_plays = next((vr for vname, vr, *_ in table if vname == "n_plays"), None)
    assert (n_plays is not None) == (fmi_version == "3.0")
    want = set()
    for vname, vr, typ, causality, size in table:
        causality = "structuralParameter" if causality == "structural" else causality
        if fmi_version == "3.0":
            want.add((vname, vr, types[typ], causality, f"n_plays({n_plays})" if size == -1
                      else size))
        elif causality == "independent":
            continue  # FMI 2 Co-Simulation has no time variable
        elif size == 1:
            want.add((vname, vr, types[typ], causality, 1))
        else:
            want |= {(f"{vname}[{i + 1}]", vr + i, types[typ], causality, 1)
                     for i in range(size)}
    md = fmpy.read_model_description(str(fmu))
    got = {(v.name, v.valueReference, v.type, v.causality,
            (f"n_plays({v.dimensions[0].valueReference})" if v.dimensions[0].start is None
             else int(v.dimensions[0].start)) if v.dimensions else 1)
           for v in md.modelVariables}
    assert got == want, got ^ want
    assert all(len(v.dimensions) <= 1 for v in md.modelVariables)
    assert max(abs(size) for *_, size in table) in (1, LIMITS["PIM_MAX_PLAYS"])
    assert any(size == (-1 if fmi_version == "3.0" else LIMITS["PIM_MAX_PLAYS"])
               for *_, size in table)


def test_no_value_reference_typed_in_c():
    """fmu/src assigns no value reference by hand: no ValueReference enum, no `vr_x = 12`, no
    comparison of a reference with a number (config.h is generated at build time)."""
    pattern = re.compile(r"\bvr_\w+\s*=\s*\d|\bvr\s*[=!<>]=?\s*\d|ValueReference;")
    hits = [f"{f.relative_to(ROOT)}:{i}: {line.strip()}"
            for f in sorted(source_dir().rglob("*.[ch]"))
            for i, line in enumerate(f.read_text().splitlines(), 1) if pattern.search(line)]
    assert not hits, hits
    assert not list(source_dir().rglob("config.h"))


def _python_sources() -> list[Path]:
    return sorted((ROOT / "pimodel").rglob("*.py"))


def test_no_limit_typed_in_python():
    """pimodel types no C limit or code: no constant bound to a number beside a C name
    (``X = 64  # PIM_MAX_PLAYS``), and no limit-like name (NMAX, MAX_PLAYS, *_BINS, *_SECTIONS,
    ...) bound to a C limit's value. The C core exports them: ``pimodel._native.LIMITS``."""
    constant = re.compile(r"^\s*[A-Z_][A-Z0-9_]*(?:\s*,\s*[A-Z_][A-Z0-9_]*)*\s*(?::[^=]+)?="
                          r"\s*[-+(]?\s*(\d[\d_.e+-]*)")
    c_name = re.compile(r"PIM_[A-Z_]+|pim_\w+\.h|fmu/src")
    limit_like = re.compile(r"NMAX|MAX_(?:PLAYS|LAGS|DYN|DELAY|ORDER|ELEMENTS|SECTIONS|LATENCY|"
                            r"SUBSTEPS)|WINDOW|WIN\b|BINS|CHECKPOINTS")
    values = {float(v) for v in LIMITS.values() if v > 2}  # small numbers are everywhere
    hits = []
    for f in _python_sources():
        for i, line in enumerate(f.read_text().splitlines(), 1):
            m = constant.match(line)
            if not m:
                continue
            value = float(m.group(1).replace("_", "").rstrip("."))
            if c_name.search(line) or (limit_like.search(line.split("=")[0])
                                       and value in values):
                hits.append(f"{f.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not hits, hits


def test_limits_are_the_c_header():
    """LIMITS holds every limit of pim_limits.h, with the value the compiler sees."""
    header = (source_dir() / "core" / "pim_limits.h").read_text()
    defined = set(re.findall(r"^#define (PIM_\w+) ", header, flags=re.M)) - {"PIM_LIMITS_H"}
    codes = set(re.findall(r"X\((PIM_(?:LAW|ENV|DINV_RATE)_\w+), [01]\)", header))
    assert codes == {"PIM_LAW_DATA", "PIM_LAW_PAPER", "PIM_ENV_POLY2", "PIM_ENV_TANH",
                     "PIM_ENV_POLY2_INV", "PIM_ENV_TANH_INV", "PIM_DINV_RATE_FEEDBACK_CAP"}
    assert defined | codes == set(LIMITS)
    for name, literal in re.findall(r"^#define (PIM_\w+) ([\d.e+-]+)(?:LL)?\s", header, re.M):
        assert LIMITS[name] == float(literal), name
    assert LIMITS["PIM_DIAG_MAX_PLAYS"] == 2 * LIMITS["PIM_MAX_PLAYS"]
    assert isinstance(LIMITS["PIM_MAX_PLAYS"], int) and isinstance(LIMITS["PIM_TS_MIN"], float)


NUMBER_WORDS = ("zero one two three four five six seven eight nine ten eleven twelve "
                "thirteen fourteen fifteen").split()


def test_docs_name_the_unit_count_of_the_spec():
    """"the N units" / "all N units" in docs/fmu.md and fmu/README.md is len(MODELS)."""
    for doc in (ROOT / "docs" / "fmu.md", ROOT / "fmu" / "README.md"):
        words = re.findall(r"\b(?:the|all) (\w+)\s+units\b", doc.read_text(), re.IGNORECASE)
        counts = {NUMBER_WORDS.index(w.lower()) for w in words if w.lower() in NUMBER_WORDS}
        assert counts == {len(MODELS)}, (doc.name, words, len(MODELS))


def test_docs_name_the_state_format_version_of_the_code():
    """docs/fmu.md and fmu/README.md state the FMU state format version that the C code
    writes (PIM_STATE_VERSION), so the two cannot drift apart."""
    code = (source_dir() / "fmi" / "pim_unit.h").read_text()
    version = re.search(r"#define PIM_STATE_VERSION (\d+)u", code).group(1)
    for doc in (ROOT / "docs" / "fmu.md", ROOT / "fmu" / "README.md"):
        found = set(re.findall(r"format version (\d+)", doc.read_text()))
        assert found == {version}, (doc.name, found, version)


def test_ctypes_mirrors_have_the_c_structs_sizes():
    """The parameter structs that pimodel._native mirrors with ctypes have the C core's size
    (checked at import too; here the check itself is shown to compare something)."""
    import ctypes

    from pimodel import _native

    for mirror, name in ((_native.AsymParams, "pim_asym"), (_native.DiagParams, "pim_diag"),
                         (_native.InverseParams, "pim_dinv"), (_native.Loop, None)):
        size = (_native.lib.pim_struct_size(name.encode()) if name
                else _native.lib.pim_loop_sizeof())
        assert size > 0 and ctypes.sizeof(mirror) == size, name
    assert _native.lib.pim_struct_size(b"pim_unknown") == 0

    class Short(ctypes.Structure):
        _fields_ = [("p0", ctypes.c_double)]

    with pytest.raises(ImportError, match="pim_asym"):
        _native._check_layout(Short, "pim_asym")
