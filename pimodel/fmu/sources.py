"""Where the FMUs' C sources live (``fmu/src``) and which of them an FMU compiles.

Layout of ``fmu/src`` (as the Modelica Reference-FMUs: shared code, then one folder per unit):

- ``core/``: the numeric core ``pim_*.c`` / ``pim_*.h`` shared with the Python extension
  (``pimodel._pim_core``), with every limit in ``core/pim_limits.h``;
- ``fmi/``: the FMI 2 / FMI 3 glue (``fmi2_pimodel.c``, ``fmi3_pimodel.c``) and the
  version-independent unit framework ``pim_unit.h`` (modes, sampling rule, step and rollback,
  state format, logging, the variable lookup), with no unit-specific code;
- ``units/<Unit>/``: one unit's own code: ``fields.h`` (its fields of ``pim_unit``) and
  ``unit.h`` (its hooks ``model_*``: defaults, parameter check, derive, setup, sample, state
  check, ...), included by the framework; ``units/shared/``: code shared by some units (the
  plays' rule, the play states, the ``inverse`` flag, the inverse PI, the envelope check, the
  section chains, the static part of the DiagnosedModel and DiagnosedInverse units).

An FMU's ``sources/`` holds these files flat, with the generated ``config.h``
(:func:`pimodel.fmu.spec.config_h`) and a ``model.c`` including its unit and glue.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["CORE_SOURCES", "FRAMEWORK", "GLUE", "HEADERS", "SHARED_UNIT_FILES", "UNIT_FILES",
           "source_dir", "source_files", "unit_dir"]

CORE_SOURCES = ("pim_pi.c", "pim_estimator.c", "pim_est_health.c", "pim_loops.c",
                "pim_generalized.c", "pim_asymmetric.c", "pim_rate_dependent.c", "pim_creep.c",
                "pim_diagnosed.c", "pim_diag_inverse.c")  # compiled into every FMU (core/)
HEADERS = ("pim_limits.h", "pim_core.h", "pim_estimator.h", "pim_est_health.h", "pim_loops.h",
           "pim_generalized.h", "pim_asymmetric.h", "pim_rate_dependent.h", "pim_creep.h",
           "pim_diagnosed.h", "pim_diag_inverse.h")  # core/
FRAMEWORK = ("pim_unit.h",)  # fmi/
GLUE = {"2.0": "fmi2_pimodel.c", "3.0": "fmi3_pimodel.c"}  # fmi/, #included by model.c
UNIT_FILES = ("fields.h", "unit.h")  # units/<Unit>/: its own fields of pim_unit, its hooks
SHARED_UNIT_FILES = ("plays.h", "play_states.h", "play_state_hooks.h", "inverse_flag.h",
                     "inverse_pi.h", "envelope_check.h", "sections.h", "diag_fields.h",
                     "diag_static.h")  # units/shared/: code shared by some units


def source_dir() -> Path:
    """The C sources: ``fmu/src`` beside the package (editable install) or packaged copy.

    Returns
    -------
    pathlib.Path
        The folder holding ``core/``, ``fmi/`` and ``units/``.

    Raises
    ------
    FileNotFoundError
        When neither location holds the sources.

    Examples
    --------
    >>> (source_dir() / "core" / "pim_pi.c").is_file()
    True
    """
    here = Path(__file__).resolve()
    for cand in (here.parents[2] / "fmu" / "src", here.parent / "src"):
        if (cand / "fmi" / GLUE["2.0"]).exists():
            return cand
    raise FileNotFoundError("pimodel FMU sources (fmu/src) not found; install pimodel from a "
                            "source checkout ('pip install -e .')")


def unit_dir(unit: str) -> Path:
    """The folder of a unit's C code, ``fmu/src/units/<unit>``.

    Parameters
    ----------
    unit : str
        The unit (``MODELS`` name), e.g. ``"PIHysteresis"``.

    Returns
    -------
    pathlib.Path
        The folder (it holds ``fields.h`` and ``unit.h``).

    Examples
    --------
    >>> (unit_dir("PIHysteresis") / "unit.h").is_file()
    True
    """
    return source_dir() / "units" / unit


def source_files(unit: str, fmi_version: str) -> list[Path]:
    """The files an FMU of ``unit`` copies into its ``sources/`` (flat), besides the generated
    ``config.h`` and ``model.c``.

    Parameters
    ----------
    unit : str
        The unit (``MODELS`` name; a model's operator FMU passes its unit).
    fmi_version : {"2.0", "3.0"}
        The FMI version (picks the glue).

    Returns
    -------
    list of pathlib.Path
        The glue, the framework, the unit's files, the core's sources and headers.

    Examples
    --------
    >>> [p.name for p in source_files("PIHysteresis", "2.0")][:4]
    ['fmi2_pimodel.c', 'pim_unit.h', 'fields.h', 'unit.h']
    """
    src = source_dir()
    return [src / "fmi" / GLUE[fmi_version], *[src / "fmi" / f for f in FRAMEWORK],
            *[unit_dir(unit) / f for f in UNIT_FILES],
            *[src / "units" / "shared" / f for f in SHARED_UNIT_FILES],
            *[src / "core" / f for f in (*CORE_SOURCES, *HEADERS)]]
