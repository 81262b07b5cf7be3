"""pimodel: Prandtl-Ishlinskii hysteresis for smart-material actuators."""

from .data import Record, load_record, save_record
from .estimator import RadiusEstimate, RadiusEstimator, estimate_radii
from .operator import PIOperator, TimeDependentPI
from .reference import pi_reference, play_reference

__all__ = [
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
