"""Build the pimodel FMUs (FMI 2.0 / 3.0 Co-Simulation, Linux binary + sources) with a C compiler.

Each FMU holds ``modelDescription.xml`` (:mod:`pimodel.fmu.description`),
``binaries/<platform>/<id>.so``, ``sources/`` (the C core, the FMI glue, the unit framework, the
unit's ``unit.h``, its generated ``config.h`` (:func:`pimodel.fmu.spec.config_h`: identity,
value references, variable table) and a ``model.c`` including them, listed in the model
description and in ``sources/buildDescription.xml`` so that ``fmpy compile`` rebuilds it
elsewhere) and ``documentation/index.html``. The FMI headers come from the installed fmpy
(``fmpy/c-code``). The spec names are re-exported here for the older import paths.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from xml.sax.saxutils import escape

from .build_cache import cache_key, cached_file, compiler_identity
from .description import LOG_CATEGORIES, PLATFORM, model_description
from .sources import CORE_SOURCES, GLUE, HEADERS, source_dir, source_files
from .spec import (
    ENVELOPE_KINDS,
    FMI_VERSIONS,
    HEALTH_BITS,
    MAX_INVERSE_SECTIONS,
    MAX_LTI_ELEMENTS,
    MAX_SUBSTEPS,
    MODEL_UNITS,
    MODELS,
    NMAX,
    Var,
    check_fmi_version,
    config_h,
    guid,
    spec_of,
    unit_of,
)

__all__ = ["CFLAGS", "CORE_SOURCES", "ENVELOPE_KINDS", "FMI_VERSIONS", "GLUE", "HEADERS",
           "HEALTH_BITS", "LOG_CATEGORIES", "MAX_INVERSE_SECTIONS", "MAX_LTI_ELEMENTS",
           "MAX_SUBSTEPS", "MODELS", "MODEL_UNITS", "NMAX", "SAMPLING", "SUFFIX", "Var",
           "build_description", "build_fmus", "check_fmi_version", "find_compiler",
           "fmi_headers", "fmu_filename", "guid", "model_description", "source_dir", "spec_of"]

SUFFIX = {"2.0": "", "3.0": "_fmi3"}  # file NAME{suffix}.fmu per FMI version


def fmu_filename(name: str, fmi_version: str = "2.0") -> str:
    """File name of a unit's FMU as :func:`build_fmus` writes it (``NAME.fmu``,
    ``NAME_fmi3.fmu``).

    Parameters
    ----------
    name : str
        The unit (model identifier), e.g. ``"PIHysteresis"``.
    fmi_version : {"2.0", "3.0"}, optional
        The FMI version. Default ``"2.0"``.

    Returns
    -------
    str
        The file name.

    Raises
    ------
    ValueError
        An unsupported ``fmi_version``.

    Examples
    --------
    >>> fmu_filename("PIHysteresis"), fmu_filename("PIHysteresis", "3.0")
    ('PIHysteresis.fmu', 'PIHysteresis_fmi3.fmu')
    """
    return f"{name}{SUFFIX[check_fmi_version(fmi_version)]}.fmu"
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-fvisibility=hidden", "-DPIM_CORE_HIDDEN",
          "-O3", "-fPIC", "-shared"]
# only the FMI functions leave the binary (the core's pim_* stay inside: PIM_CORE_HIDDEN, and
# this version script for the linker)
EXPORTS = "{\n  global: fmi2*; fmi3*;\n  local: *;\n};\n"

SAMPLING = ("Internal sample k at time k*Ts; doStep(t, h) processes every sample with k*Ts in "
            "[t, t+h) (up to a master's rounding of the grid) using the inputs set before the "
            "call; outputs hold the last sample's values, and after initialization the first "
            "sample's response to the inputs set so far.")


def fmi_headers() -> Path:
    """The FMI headers shipped with the installed fmpy (``fmpy/c-code``).

    Returns
    -------
    pathlib.Path
        The folder holding ``fmi2Functions.h`` (and the FMI 3 headers).

    Raises
    ------
    FileNotFoundError
        When the fmpy installation has no FMI 2 headers.

    Examples
    --------
    >>> (fmi_headers() / "fmi2Functions.h").is_file()
    True
    """
    import fmpy

    path = Path(fmpy.__file__).parent / "c-code"
    if not (path / "fmi2Functions.h").exists():
        raise FileNotFoundError(f"FMI 2 headers not found in {path} (fmpy installation)")
    return path


def find_compiler() -> str:
    """A C compiler on PATH ($CC, cc, gcc or clang); RuntimeError naming them when none.

    Returns
    -------
    str
        The first of ``$CC``, ``cc``, ``gcc``, ``clang`` found on PATH.

    Raises
    ------
    RuntimeError
        When none is found.

    Examples
    --------
    >>> import os
    >>> find_compiler() in (os.environ.get("CC"), "cc", "gcc", "clang")
    True
    """
    for cand in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cand and shutil.which(cand):
            return cand
    raise RuntimeError("no C compiler found: set CC or put cc, gcc or clang on PATH")



def build_description(name: str) -> str:
    """``sources/buildDescription.xml``: the C files ``fmpy compile`` needs to rebuild the unit.

    Parameters
    ----------
    name : str
        The unit's model identifier.

    Returns
    -------
    str
        The XML text (FMI 3 build description, also read for FMI 2 by fmpy).

    Examples
    --------
    >>> build_description("PIHysteresis").splitlines()[2]
    '  <BuildConfiguration modelIdentifier="PIHysteresis">'
    """
    files = "\n".join(f'        <SourceFile name="{s}"/>' for s in ("model.c", *CORE_SOURCES))
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<fmiBuildDescription fmiVersion="3.0">\n'
        f'  <BuildConfiguration modelIdentifier="{name}">\n'
        '    <SourceFileSet language="C99">\n'
        f"{files}\n"
        '        <PreprocessorDefinition name="PIM_CORE_HIDDEN"/>\n'
        "    </SourceFileSet>\n  </BuildConfiguration>\n</fmiBuildDescription>\n"
    )


def _model_c(name: str, fmi_version: str) -> str:
    unit = unit_of(name)
    return (f"/* {name}: the unit {unit} (units/{unit}/unit.h) in the shared FMI {fmi_version} "
            "glue;\n * its identity and variables are in config.h, generated from "
            "pimodel.fmu.spec. */\n"
            f'#include "config.h"\n#include "{GLUE[fmi_version]}"\n')


def _documentation(name: str) -> str:
    spec = spec_of(name)
    rows = "".join(f"<tr><td>{v.name}</td><td>{v.causality}</td><td>{escape(v.description)}"
                   "</td></tr>" for v in spec["vars"] if "[" not in v.name or "[1]" in v.name)
    return (f"<html><body><h1>{name}</h1><p>{escape(spec['description'])}.</p>"
            f"<p>{escape(SAMPLING)} Arrays are declared up to index {NMAX}; the first n are "
            "used (FMI 3: the per-play arrays have n_plays elements, a structural parameter "
            "set in configuration mode, default 64). Bad parameters or non-finite inputs "
            "return an error status (fmi2Error, fmi3Error) with a logged message, as do a call "
            "in the wrong state, an unknown value reference, a doStep whose t is not the "
            "FMU's time, a step of more than "
            f"{MAX_SUBSTEPS:,} samples, and an FMU state that fails its checks (format, "
            "checksum, parameters, finite states)."
            f"</p><table>{rows}</table></body></html>\n")


def build_fmus(out_dir, which=None, *, compiler: str | None = None,
               fmi_version: str = "2.0") -> list[Path]:
    """Compile and package the FMUs named in ``which`` (default all) into ``out_dir``.

    Parameters
    ----------
    out_dir : str or Path
        Folder of the FMUs (created; existing files overwritten).
    which : iterable of str, optional
        Units to build (names of ``MODELS`` or ``MODEL_UNITS``); default all of ``MODELS``.
    compiler : str, optional
        C compiler; default :func:`find_compiler`.
    fmi_version : {"2.0", "3.0"}, optional
        ``"2.0"`` (files ``NAME.fmu``) or ``"3.0"`` (files ``NAME_fmi3.fmu``, arrays as FMI 3
        arrays); the model identifier is ``NAME`` in both. Default ``"2.0"``.

    Returns
    -------
    list of pathlib.Path
        The FMU files, in the order of ``which``.

    Raises
    ------
    ValueError
        An unknown unit or FMI version.
    RuntimeError
        No compiler found, or compiling failed (the message holds the compiler's output).
    FileNotFoundError
        The C sources or the FMI headers are missing.

    Examples
    --------
    Compiling takes about a second per unit, hence skipped here:

    >>> import tempfile
    >>> build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0].name  # doctest: +SKIP
    'PIHysteresis.fmu'
    """
    names = list(MODELS) if which is None else list(which)
    unknown = [n for n in names if n not in MODELS and n not in MODEL_UNITS]
    if unknown:
        raise ValueError(f"which: unknown FMU(s) {unknown}; available: {list(MODELS)}")
    check_fmi_version(fmi_version)
    cc = compiler or find_compiler()
    inc = fmi_headers()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    platform = PLATFORM[fmi_version]
    paths = []
    for name in names:
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            (tmp / "model.c").write_text(_model_c(name, fmi_version))
            (tmp / "config.h").write_text(config_h(name, fmi_version))
            files = source_files(unit_of(name), fmi_version)
            for f in files:
                shutil.copy(f, tmp / f.name)
            so = _compile(cc, tmp, name, files, inc, what=f"{name} (FMI {fmi_version})")
            fmu = out / fmu_filename(name, fmi_version)
            with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as z:
                z.writestr("modelDescription.xml", model_description(name, fmi_version))
                z.write(so, f"binaries/{platform}/{name}.so")
                for f in ("model.c", "config.h", *[f.name for f in files]):
                    z.write(tmp / f, f"sources/{f}")
                z.writestr("sources/buildDescription.xml", build_description(name))
                z.writestr("documentation/index.html", _documentation(name))
            paths.append(fmu)
    return paths


def _run(cmd: list[str], cwd: Path, what: str) -> None:
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"compiling {what} failed:\n{proc.stderr}")


def _compile(cc: str, tmp: Path, name: str, files: list[Path], inc: Path, what: str) -> Path:
    """Compile and link the unit whose sources are flat in ``tmp`` into ``tmp/<name>.so``,
    through the build cache (:mod:`pimodel.fmu.build_cache`): one object per C file (run in
    ``tmp`` with relative names, so the output does not depend on the folder), keyed on
    ``CFLAGS``, the compiler and the files the C file can include: a core source its core
    headers (it includes no other file: ``tests/test_fmu_build_cache.py``), ``model.c``
    everything else of the FMU's sources and the FMI headers. The link is keyed on the objects'
    keys. Missing objects compile in parallel, one process per core."""
    flags, ident = list(CFLAGS), compiler_identity(cc)  # CFLAGS read now: tests may patch it
    (tmp / "exports.map").write_text(EXPORTS)
    core = [tmp / h for h in HEADERS]
    rest = [tmp / "model.c", tmp / "config.h",
            *[tmp / f.name for f in files if f.name not in CORE_SOURCES],
            *sorted(inc.glob("*.h"))]
    units = [("model.c", rest), *[(c, [tmp / c, *core]) for c in CORE_SOURCES]]
    objects = [(tmp / f"{Path(c).stem}.o", c, cache_key("object", *flags, ident, files=deps))
               for c, deps in units]

    def compile_object(job: tuple[Path, str, str]) -> bool:
        obj, c, key = job
        return cached_file(key, obj, lambda: _run(
            [cc, *flags, "-I", ".", "-I", str(inc), "-c", c, "-o", obj.name], tmp, what))

    def link() -> None:
        with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
            list(pool.map(compile_object, objects))
        _run([cc, *flags, *[obj.name for obj, _, _ in objects], "-o", so.name, "-lm",
              "-Wl,--version-script=exports.map"], tmp, what)

    so = tmp / f"{name}.so"
    cached_file(cache_key("shared library", *flags, ident, EXPORTS,
                          *[key for _, _, key in objects]), so, link)
    so.chmod(0o755)  # as the linker writes it, also when it came from the cache
    return so
