"""Prandtl-Ishlinskii hysteresis for smart-material actuators.

The PI operator and its exact inverse, identification of a PI model from measured loops (loop
slopes, adaptive radius estimator, joint estimator), python-control blocks, C FMUs and a
sim-to-real gap diagnosis. Signals are sampled: ``y[k]`` is the response to ``v[0..k]``.
Units follow the data (e.g. V in, um out); time is in seconds.

**The names a user types first** (re-exported here)

==================  ===============================================================
PIOperator          PI operator: weighted plays, exact inverse, streaming state
TimeDependentPI     PI operator with radii per sample (the estimator's model)
GeneralizedPI       plays between input/output envelopes, exact inverse
AsymmetricPI        distinct loading and unloading envelopes
RateDependentPI     radii growing with the input rate
CreepOperator       a sum of first-order lags, exact inverse
Cascade             operators in series and the chain's inverse
identify            fit y = PI[v] + offset to a record (adaptive, conventional, joint)
Identification      identify's result: operator, offset, errors, JSON
identify_slopes     number of plays and weights from the loop slopes (BIC)
check_excitation    does the input excite every play? (reversals, range, loop width)
fit_conventional    conventional baseline: preset radii, least-squares weights
RadiusEstimator     the adaptive radius law (regime from the data), streaming (C core)
estimate_radii      the radius law over a whole record
RadiusEstimate      estimate_radii's result: final radii and history
JointEstimator      online estimation of weights and radii together, streaming
estimate_jointly    the joint estimator over a whole record
stream_jointly      the joint estimator over (v, y) chunks of any size
JointEstimate       the joint estimators' result
Record              a sampled record t, v, y (validated)
load_record         read a record from CSV (header) or NPZ
save_record         write a record to CSV or NPZ
load_model          read a model file: a Model (operator, offset, dt, units, provenance)
save_model          write a model file
diagnose            where the sim-to-real gap lies and which effect causes it
DiagnosisReport     diagnose's result
pi_reference        plain NumPy PI operator (the C core's specification)
play_reference      plain NumPy play (backlash) operator
==================  ===============================================================

**The map** (each subpackage's docstring maps its modules)

===============================  =================================================================
pimodel.operators                the operators: PI, generalized, asymmetric, rate-dependent, creep
pimodel.identification           identify(), slopes, conventional, identifiability, fits
pimodel.identification.adaptive  the radius estimator, its settings and health, joint
pimodel.blocks                   python-control blocks and the block framework
pimodel.loops                    compiled loops, simulation, actuator dynamics, describing
pimodel.stages                   simulated piezo stages for tests and studies
pimodel.reference                plain NumPy references of the compiled algorithms
pimodel.diagnosis                sim-to-real gap diagnosis: where, which effect, how far
pimodel.fmu                      build FMUs; drive them; wrap them as blocks; co-simulate
pimodel.experiments              studies, sweeps (serial or Dask), compensation, demo
pimodel.cli                      the ``pimodel`` command line
pimodel.records                  measured records: load, save, validate
pimodel.model_files              the JSON form of a model (load_model, save_model)
pimodel.signals                  test inputs: sinusoid, triangle, minor loops, staircase
pimodel.checks                   argument validation (errors name the argument)
pimodel.plotting                 matplotlib helpers (headless, consistent saving)
===============================  =================================================================

Layers, bottom to top (a module imports only from its own layer or below):
``checks, signals, plotting, records, _native`` < ``operators`` < ``reference`` <
``identification`` < ``blocks`` < ``loops`` < ``stages`` < ``diagnosis`` < ``model_files`` <
``fmu`` < ``experiments`` < ``cli``. The 0.1 module paths (``pimodel.truth``,
``pimodel.estimator``, ...) still import, with a DeprecationWarning (:mod:`pimodel._deprecated`).
"""

import sys as _sys
import types as _types

from ._deprecated import install as _install_deprecated_paths

__all__ = [
    "AsymmetricPI",
    "Cascade",
    "CreepOperator",
    "DiagnosisReport",
    "GeneralizedPI",
    "Identification",
    "JointEstimate",
    "JointEstimator",
    "PIOperator",
    "RadiusEstimate",
    "RadiusEstimator",
    "RateDependentPI",
    "Record",
    "TimeDependentPI",
    "check_excitation",
    "diagnose",
    "estimate_jointly",
    "estimate_radii",
    "fit_conventional",
    "identify",
    "identify_slopes",
    "load_model",
    "load_record",
    "pi_reference",
    "play_reference",
    "save_model",
    "save_record",
    "stream_jointly",
]
__version__ = "0.1.0"

# Every public name is imported on first use (``import pimodel`` loads no NumPy, so that
# ``pimodel --help`` and ``--version`` are quick): name -> module.
_LAZY = {
    "JointEstimate": "pimodel.identification.adaptive.joint",
    "JointEstimator": "pimodel.identification.adaptive.joint",
    "estimate_jointly": "pimodel.identification.adaptive.joint",
    "stream_jointly": "pimodel.identification.adaptive.joint",
    "RadiusEstimate": "pimodel.identification.adaptive.radius_estimator",
    "RadiusEstimator": "pimodel.identification.adaptive.radius_estimator",
    "estimate_radii": "pimodel.identification.adaptive.radius_estimator",
    "Identification": "pimodel.identification.chain",
    "identify": "pimodel.identification.chain",
    "fit_conventional": "pimodel.identification.conventional",
    "check_excitation": "pimodel.identification.identifiability",
    "identify_slopes": "pimodel.identification.slopes",
    "AsymmetricPI": "pimodel.operators.asymmetric",
    "Cascade": "pimodel.operators.cascade",
    "CreepOperator": "pimodel.operators.creep",
    "GeneralizedPI": "pimodel.operators.generalized",
    "PIOperator": "pimodel.operators.pi",
    "TimeDependentPI": "pimodel.operators.pi",
    "RateDependentPI": "pimodel.operators.rate_dependent",
    "Record": "pimodel.records",
    "load_record": "pimodel.records",
    "save_record": "pimodel.records",
    "pi_reference": "pimodel.reference.operators",
    "play_reference": "pimodel.reference.operators",
    "diagnose": "pimodel.diagnosis.diagnose",
    "DiagnosisReport": "pimodel.diagnosis.diagnose",
    "load_model": "pimodel.model_files",
    "save_model": "pimodel.model_files",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'pimodel' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))




class _Package(_types.ModuleType):
    """pimodel's module type: the function ``pimodel.identify`` keeps its name when the 0.1
    module path ``pimodel.identify`` is imported (the import system would set the attribute to
    the module, as 0.1 never did: there the function shadowed its module)."""

    def __setattr__(self, name: str, value) -> None:
        if name == "identify" and isinstance(value, _types.ModuleType):
            return
        super().__setattr__(name, value)


_sys.modules[__name__].__class__ = _Package
_install_deprecated_paths()
