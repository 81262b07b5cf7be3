"""FMI 2.0 Co-Simulation FMUs of the pimodel units (real C, the shared core) and FMU helpers.

``MODELS`` maps each unit name to its model description; ``build_fmus`` builds them.

Examples
--------
>>> from pimodel.fmu import MODELS
>>> sorted(MODELS)[:4]
['AsymmetricPI', 'CreepOperator', 'DiagnosedInverse', 'DiagnosedModel']
"""

from .build import MODELS, build_fmus

__all__ = ["MODELS", "build_fmus"]
