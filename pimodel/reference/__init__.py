"""Plain NumPy references: the readable specification of each compiled algorithm.

Tests hold the C core equal to these (``tests/test_native_equals_reference.py``).

Modules
-------

::

    operators           play, PI, time-dependent PI and the PI inverse
    extended_operators  generalized, rate-dependent, asymmetric and creep operators
    radius_estimator    the radius estimator, one Python step per sample
    joint               the joint estimator's per-branch statistics
"""

from .extended_operators import (
    asym_inverse_reference,
    asym_reference,
    creep_inverse_reference,
    creep_reference,
    gpi_reference,
    rdpi_inverse_reference,
    rdpi_reference,
)
from .joint import branch_shape_reference, joint_add_reference, joint_select_reference
from .operators import (
    pi_inverse_reference,
    pi_reference,
    play_reference,
    tdpi_reference,
)
from .radius_estimator import (
    BranchProfile,
    estimate_radii_reference,
    project_ordered_reference,
)

__all__ = [
    "pi_inverse_reference",
    "pi_reference",
    "play_reference",
    "tdpi_reference",
    "asym_inverse_reference",
    "asym_reference",
    "creep_inverse_reference",
    "creep_reference",
    "gpi_reference",
    "rdpi_inverse_reference",
    "rdpi_reference",
    "BranchProfile",
    "estimate_radii_reference",
    "project_ordered_reference",
    "branch_shape_reference",
    "joint_add_reference",
    "joint_select_reference",
]
