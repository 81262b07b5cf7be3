"""Prandtl-Ishlinskii hysteresis for smart-material actuators.

The PI operator and its exact inverse, identification of a PI model from measured loops (loop
slopes, adaptive radius estimator, joint estimator), python-control blocks, C FMUs and a
sim-to-real gap diagnosis. Signals are sampled: ``y[k]`` is the response to ``v[0..k]``.
Units follow the data (e.g. V in, um out); time is in seconds.

**Operators**

==================  ===============================================================
PIOperator          PI operator: weighted plays, exact inverse, streaming state
TimeDependentPI     PI operator with radii per sample (the estimator's model)
pi_reference        plain NumPy PI operator (the C core's specification)
play_reference      plain NumPy play (backlash) operator
==================  ===============================================================

**Identification**

==================  ===============================================================
identify            fit y = PI[v] + offset to a record (adaptive, conventional, joint)
Identification      identify's result: operator, offset, errors, JSON
identify_slopes     number of plays and weights from the loop slopes (BIC)
check_excitation    does the input excite every play? (reversals, range, loop width)
fit_conventional    conventional baseline: preset radii, least-squares weights
==================  ===============================================================

**Estimators**

==================  ===============================================================
RadiusEstimator     the adaptive radius law (regime from the data), streaming (C core)
estimate_radii      the radius law over a whole record
RadiusEstimate      estimate_radii's result: final radii and history
JointEstimator      online estimation of weights and radii together, streaming
estimate_jointly    the joint estimator over a whole record
stream_jointly      the joint estimator over (v, y) chunks of any size
JointEstimate       the joint estimators' result
==================  ===============================================================

**Records**

==================  ===============================================================
Record              a sampled record t, v, y (validated)
load_record         read a record from CSV (header) or NPZ
save_record         write a record to CSV or NPZ
==================  ===============================================================

**Submodules**

============================  ==========================================================
pimodel.signals               test inputs: sinusoid, triangle, minor loops, staircase
pimodel.blocks                python-control blocks: PI, inverse, estimator, PID
pimodel.simulation            simulate a python-control system from its initial states
pimodel.actuators             stage dynamics: mode, creep, delay (discretised)
pimodel.describing            describing function, sector, circle criterion, limit cycles
pimodel.loops                 compiled loops: feedforward, adaptive inverse, PID
pimodel.long_records          long noisy records made in chunks
pimodel.estimator_settings    radius estimator settings chosen from the record
pimodel.estimator_health      health report of a radius estimate: can it be trusted?
pimodel.play_reduction        joint fit: merge or drop the plays the data do not resolve
pimodel.envelopes             input/output envelopes (poly2, tanh) with exact inverses
pimodel.generalized           GeneralizedPI: plays between envelopes, exact inverse
pimodel.asymmetric            AsymmetricPI: distinct loading/unloading envelopes
pimodel.rate_dependent        RateDependentPI: radii growing with the input rate
pimodel.creep                 CreepOperator: sum of first-order lags, exact inverse
pimodel.cascade               Cascade: operators in series and the chain's inverse
pimodel.fit_operators         identify the generalized, rate-dependent and creep operators
pimodel.blocks_extra          python-control blocks of those operators
pimodel.models                the JSON form of a model (load_model, save_model)
pimodel.sweep                 sweeps over cases, serially or on Dask (run_cases, grid)
pimodel.truth_sweep           sweeps of identify/diagnose over simulated stages
pimodel.diagnosis             sim-to-real gap diagnosis: where, which effect, how far
pimodel.truth                 simulated stages with creep, dynamics, delay, ...
pimodel.fmu                   build FMUs; drive them; wrap them as blocks; co-simulate
pimodel.fmu.operators         FMU unit and parameter values for an operator or inverse
pimodel.fmu.model_fmu         FMUs of a model, one per stage; co-simulate the chain
============================  ==========================================================
"""

from .conventional import fit_conventional
from .data import Record, load_record, save_record
from .estimator import RadiusEstimate, RadiusEstimator, estimate_radii
from .excitation import check_excitation
from .identify import Identification, identify
from .joint import JointEstimate, JointEstimator, estimate_jointly, stream_jointly
from .operator import PIOperator, TimeDependentPI
from .reference import pi_reference, play_reference
from .slopes import identify_slopes

__all__ = [
    "Identification",
    "check_excitation",
    "fit_conventional",
    "identify",
    "identify_slopes",
    "JointEstimate",
    "JointEstimator",
    "estimate_jointly",
    "stream_jointly",
    "RadiusEstimate",
    "RadiusEstimator",
    "estimate_radii",
    "PIOperator",
    "TimeDependentPI",
    "Record",
    "load_record",
    "save_record",
    "pi_reference",
    "play_reference",
]
__version__ = "0.1.0"
