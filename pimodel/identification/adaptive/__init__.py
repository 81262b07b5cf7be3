"""Online estimators: the adaptive radius law (Al Janaideh & Tan, Sec. III), its settings and
health report, and the joint estimator of weights and radii.

Modules
-------

::

    radius_estimator  RadiusEstimator (C core) and estimate_radii
    settings          estimator settings chosen from the record
    health            health report of a radius estimate: can it be trusted?
    joint             JointEstimator: weights and radii together, online
"""

from .health import (
    EstimatorHealth,
    estimator_health,
)
from .joint import (
    JointEstimate,
    JointEstimator,
    branch_shape,
    estimate_jointly,
    stream_jointly,
)
from .radius_estimator import (
    RadiusEstimate,
    RadiusEstimator,
    estimate_radii,
    project_ordered,
    run_tail_average,
    stream_tail_average,
)
from .settings import (
    check_gains,
    check_weights,
    default_settings,
    noise_level,
    stability_bound,
)

__all__ = [
    "estimate_radii",
    "project_ordered",
    "RadiusEstimate",
    "RadiusEstimator",
    "run_tail_average",
    "stream_tail_average",
    "check_gains",
    "check_weights",
    "default_settings",
    "noise_level",
    "stability_bound",
    "estimator_health",
    "EstimatorHealth",
    "branch_shape",
    "estimate_jointly",
    "JointEstimate",
    "JointEstimator",
    "stream_jointly",
]
