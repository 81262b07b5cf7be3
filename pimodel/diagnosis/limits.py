"""The limits of the C core that the diagnosed model's native forms respect, in one place.

The forward stream and the DiagnosedModel FMU unit (``fmu/src/pim_diagnosed.h``,
:mod:`.native_model`) and the feedforward and the DiagnosedInverse FMU unit
(``fmu/src/pim_diag_inverse.h``, :mod:`.native_inverse`) refuse larger models; the Python side
checks these first so that the error names the parameter.

Examples
--------
>>> from pimodel.diagnosis.limits import MAX_DELAY, NMAX
>>> 2 * NMAX, MAX_DELAY  # plays of a diagnosed unit, longest delay [samples]
(128, 4094)
"""

from __future__ import annotations

__all__ = ["MAX_DELAY", "MAX_ELEMENTS", "MAX_LATENCY", "MAX_ORDER", "MAX_SECTIONS", "NMAX",
           "SECTION"]

# -- limits of the C core (fmu/src/pim_diagnosed.h); to be read from _native.LIMITS ----------
# (temporary: retyped from the C headers until the core exports them; the merge replaces this
# block by reads of pimodel._native.LIMITS)
NMAX = 64  # PIM_MAX_PLAYS: array size per FMU variable (p[1..64]); diagnosed units: 2 NMAX plays
MAX_ELEMENTS = 8  # PIM_DIAG_MAX_ELEMENTS: further elements of the linear part (and Wiener filter)
MAX_DELAY = 4094  # samples: PIM_DIAG_MAX_DELAY - 2
MAX_ORDER = 63  # LTI order: PIM_DIAG_MAX_ORDER
SECTION = 3  # coefficients per section of a further element: PIM_DIAG_SECTION
MAX_SECTIONS = 32  # PIM_DINV_MAX_SECTIONS (fmu/src/pim_diag_inverse.h): prefilter sections
MAX_LATENCY = 1_000_000  # samples: PIM_DINV_MAX_LATENCY
# -- end of the limits of the C core ----------------------------------------------------------
