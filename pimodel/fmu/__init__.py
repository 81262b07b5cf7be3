"""FMI 2.0 Co-Simulation FMUs of the pimodel units (real C, the shared core) and FMU helpers."""

from .build import MODELS, build_fmus

__all__ = ["MODELS", "build_fmus"]
