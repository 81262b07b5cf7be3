"""Sim-to-real gap diagnosis (see :mod:`pimodel.diagnosis.diagnose`)."""

from .diagnose import DiagnosisReport, diagnose

__all__ = ["DiagnosisReport", "diagnose"]
