"""Experiments: the study runner, sweeps (serial or on Dask), the compensation comparison and the
demo.

The top layer: it may import every other subpackage, so its names load on first use
(``import pimodel.experiments`` stays light).

Modules
-------

::

    studies         running the scripts in studies/: discovery, output, tables
    sweeps          cases mapped over a function, serially or on Dask
    stage_sweeps    sweeps of identify/diagnose over simulated stages
    compensation    the compensation comparison on the piezo-like stage
    demo            pimodel demo: the headline chain in under a minute
    fmu_comparison  the adaptive loop as an FMU co-simulation against the compiled loop
"""

from __future__ import annotations

import importlib

#: public name -> module of this package that defines it
_WHERE = {
    "add_run_options": "studies",
    "available_studies": "studies",
    "is_sweep": "studies",
    "load_study": "studies",
    "run_study": "studies",
    "study_main": "studies",
    "StudyResult": "studies",
    "Table": "studies",
    "DEFAULT_MEMORY_LIMIT": "sweeps",
    "WORKER_ENV": "sweeps",
    "CaseFailed": "sweeps",
    "available_cores": "sweeps",
    "case_key": "sweeps",
    "grid": "sweeps",
    "plain": "sweeps",
    "random_cases": "sweeps",
    "run_cases": "sweeps",
    "tidy_rows": "sweeps",
    "write_table": "sweeps",
    "DIAGNOSE_SETTINGS": "stage_sweeps",
    "IDENTIFY_SETTINGS": "stage_sweeps",
    "TARGETS": "stage_sweeps",
    "TRUTH_PARAMS": "stage_sweeps",
    "truth_case": "stage_sweeps",
    "truth_sweep": "stage_sweeps",
    "chord_gain": "compensation",
    "compensation_table": "compensation",
    "identified_models": "compensation",
    "reference": "compensation",
    "run_demo": "demo",
    "step_compensate": "demo",
    "step_diagnose": "demo",
    "step_fmu": "demo",
    "step_identify": "demo",
    "compare_with_native": "fmu_comparison",
    "CosimComparison": "fmu_comparison",
    "plot_comparison": "fmu_comparison",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_WHERE))
