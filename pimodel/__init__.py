"""pimodel: Prandtl-Ishlinskii hysteresis for smart-material actuators."""

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
