"""FMI 2.0 / 3.0 Co-Simulation FMUs of the pimodel units (real C, the shared core) and helpers.

The spec
========
spec             -- the one source of the units' variables (Var, MODELS), value references,
                    identity (guid, token) and generated C header (config_h); limits from C
MODELS           -- unit name -> spec (id, description, vars), re-exported from spec
Var              -- one scalar variable of a unit (name, vr, kind, causality, start, field)
config_h         -- a unit's C config.h: ValueReference enum and variable table, at build time

Model descriptions and building
===============================
description      -- model_description(name, fmi_version): one writer for FMI 2.0 and 3.0,
                    default_experiment (stepSize Ts, stopTime)
units            -- the variables' physical units (V, um, s, ...) and UnitDefinitions
sources          -- where the C lives: fmu/src/core (numeric core), fmi (glue, framework),
                    units/<Unit> (each unit's own code); what an FMU compiles
build            -- build_fmus (compile and package), find_compiler, fmi_headers, fmu_filename
build_fmus       -- compile and package the FMUs into a folder, re-exported from build
build_cache      -- the compile cache: each object and binary compiled once per content, flags
                    and compiler ($PIMODEL_BUILD_CACHE, default ~/.cache/pimodel/build)
model_fmu        -- build_model_fmus / build_inverse_fmu: one FMU per operator of a model,
                    its parameters as start values; cosimulate_chain
operators        -- unit_parameters(op): the unit and parameter values of an operator

Running FMUs
============
unit             -- FMUUnit: a co-simulation handle (FMI 2 and 3, names as in the spec)
block            -- fmu_block: an FMU as a python-control block
cosim            -- cosimulate_adaptive_loop: estimator + compensator + stage as FMUs
compare          -- compare_with_native, plot_comparison, CosimComparison: FMU vs Python loop

Deprecated
==========
fmi3             -- alias of description.model_description3 and spec.token (one release)

The limits (``NMAX`` plays per array, ``MAX_SUBSTEPS`` samples per doStep, ...) come from the
C core, ``pimodel._native.LIMITS`` (``fmu/src/core/pim_limits.h``).

Examples
--------
>>> from pimodel.fmu import MODELS
>>> sorted(MODELS)[:4]
['AsymmetricPI', 'CreepOperator', 'DiagnosedInverse', 'DiagnosedModel']
"""

from .build import build_fmus
from .spec import MODELS, Var, config_h

__all__ = ["MODELS", "Var", "build_fmus", "config_h"]
