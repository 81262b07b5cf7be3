"""Experiments: the study runner, sweeps (serial or on Dask), the compensation comparison and the
demo.

Modules
-------

::

    studies       running the scripts in studies/: discovery, output, tables
    sweeps        cases mapped over a function, serially or on Dask
    stage_sweeps  sweeps of identify/diagnose over simulated stages
    compensation  the compensation comparison on the piezo-like stage
    demo          pimodel demo: the headline chain in under a minute
"""

from .compensation import (
    chord_gain,
    compensation_table,
    identified_models,
    reference,
)
from .demo import (
    run_demo,
    step_compensate,
    step_diagnose,
    step_fmu,
    step_identify,
)
from .stage_sweeps import (
    DIAGNOSE_SETTINGS,
    IDENTIFY_SETTINGS,
    TARGETS,
    TRUTH_PARAMS,
    truth_case,
    truth_sweep,
)
from .studies import (
    StudyResult,
    Table,
    add_run_options,
    available_studies,
    is_sweep,
    load_study,
    run_study,
    study_main,
)
from .sweeps import (
    DEFAULT_MEMORY_LIMIT,
    WORKER_ENV,
    CaseFailed,
    available_cores,
    case_key,
    grid,
    plain,
    random_cases,
    run_cases,
    tidy_rows,
    write_table,
)

__all__ = [
    "add_run_options",
    "available_studies",
    "is_sweep",
    "load_study",
    "run_study",
    "study_main",
    "StudyResult",
    "Table",
    "DEFAULT_MEMORY_LIMIT",
    "WORKER_ENV",
    "CaseFailed",
    "available_cores",
    "case_key",
    "grid",
    "plain",
    "random_cases",
    "run_cases",
    "tidy_rows",
    "write_table",
    "DIAGNOSE_SETTINGS",
    "IDENTIFY_SETTINGS",
    "TARGETS",
    "TRUTH_PARAMS",
    "truth_case",
    "truth_sweep",
    "chord_gain",
    "compensation_table",
    "identified_models",
    "reference",
    "run_demo",
    "step_compensate",
    "step_diagnose",
    "step_fmu",
    "step_identify",
]
