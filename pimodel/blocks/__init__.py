"""python-control blocks: discrete-time ``NonlinearIOSystem`` objects.

Every block is built on :mod:`pimodel.blocks.framework` (parameters in ``params``, the own
initial state from :func:`initial_state`, 1-based signal names).

Modules
-------

::

    framework  Block, stepped_block, BlockSettings, initial_state: what every block uses
    pi         PI operator, inverse, radius estimator, adaptive compensator and PID blocks
    operators  blocks of the generalized, asymmetric, rate-dependent and creep operators
"""

from .framework import (
    Block,
    BlockSettings,
    InitialStateWarning,
    initial_state,
    labelled_values,
    signal_labels,
    stepped_block,
    warn_if_zero_start,
)
from .operators import (
    asymmetric_pi_block,
    block_initial_state,
    creep_block,
    generalized_pi_block,
    rate_dependent_inverse_block,
    rate_dependent_pi_block,
)
from .pi import (
    adaptive_compensator_block,
    estimator_block,
    estimator_state_labels,
    inverse_pi_block,
    pi_block,
    pid_block,
    radius_estimator,
)

__all__ = [
    "Block",
    "BlockSettings",
    "InitialStateWarning",
    "initial_state",
    "labelled_values",
    "signal_labels",
    "stepped_block",
    "warn_if_zero_start",
    "adaptive_compensator_block",
    "estimator_block",
    "estimator_state_labels",
    "inverse_pi_block",
    "pi_block",
    "pid_block",
    "radius_estimator",
    "asymmetric_pi_block",
    "block_initial_state",
    "creep_block",
    "generalized_pi_block",
    "rate_dependent_inverse_block",
    "rate_dependent_pi_block",
]
