"""The import paths of pimodel 0.1 that the layout of 0.2 replaced, kept for one release.

``import pimodel.truth`` (or ``from pimodel.estimator import RadiusEstimator``) still works: a
finder on ``sys.meta_path`` loads the new module (``pimodel.stages.pi_stage``), registers it
under the old name as well and emits a :class:`DeprecationWarning` naming the new path. The old
name is the same module object, so state, ``isinstance`` and ``monkeypatch`` behave as before.
``pimodel.blocks``, ``pimodel.reference`` and ``pimodel.loops`` are packages now and re-export
the public names the old modules held, without a warning.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

__all__ = ["MOVED", "install"]

#: old module -> new module
MOVED: dict[str, str] = {
    "pimodel.data": "pimodel.records",
    "pimodel.models": "pimodel.model_files",
    "pimodel._operator_base": "pimodel.operators.base",
    "pimodel.operator": "pimodel.operators.pi",
    "pimodel.envelopes": "pimodel.operators.envelopes",
    "pimodel.generalized": "pimodel.operators.generalized",
    "pimodel.asymmetric": "pimodel.operators.asymmetric",
    "pimodel.rate_dependent": "pimodel.operators.rate_dependent",
    "pimodel.creep": "pimodel.operators.creep",
    "pimodel.cascade": "pimodel.operators.cascade",
    "pimodel.reference_operators": "pimodel.reference.extended_operators",
    "pimodel.estimator_reference": "pimodel.reference.radius_estimator",
    "pimodel.identify": "pimodel.identification.chain",
    "pimodel.fmu.compare": "pimodel.experiments.fmu_comparison",
    "pimodel.fmu.fmi3": "pimodel.fmu.description",  # model_description3, TYPES, token
    "pimodel.slopes": "pimodel.identification.slopes",
    "pimodel.segmented": "pimodel.identification.piecewise_linear",
    "pimodel.conventional": "pimodel.identification.conventional",
    "pimodel.excitation": "pimodel.identification.identifiability",
    "pimodel.play_reduction": "pimodel.identification.play_reduction",
    "pimodel.fit_operators": "pimodel.identification.extended_operators",
    "pimodel.branches": "pimodel.identification.branches",
    "pimodel.plots_identify": "pimodel.identification.plots",
    "pimodel.estimator": "pimodel.identification.adaptive.radius_estimator",
    "pimodel.estimator_settings": "pimodel.identification.adaptive.settings",
    "pimodel.estimator_health": "pimodel.identification.adaptive.health",
    "pimodel.joint": "pimodel.identification.adaptive.joint",
    "pimodel.blocks_extra": "pimodel.blocks.operators",
    "pimodel.simulation": "pimodel.loops.simulation",
    "pimodel.actuators": "pimodel.loops.actuators",
    "pimodel.describing": "pimodel.loops.describing",
    "pimodel.truth": "pimodel.stages.pi_stage",
    "pimodel.truth_alt": "pimodel.stages.preisach_stage",
    "pimodel.truth_steps": "pimodel.stages.stepper",
    "pimodel.long_records": "pimodel.stages.long_records",
    "pimodel.study_runner": "pimodel.experiments.studies",
    "pimodel.sweep": "pimodel.experiments.sweeps",
    "pimodel.truth_sweep": "pimodel.experiments.stage_sweeps",
    "pimodel.compensation": "pimodel.experiments.compensation",
    "pimodel.demo": "pimodel.experiments.demo",
    "pimodel.diagnosis.stream": "pimodel.diagnosis.native_model",
    "pimodel.diagnosis.inverse_native": "pimodel.diagnosis.native_inverse",
    "pimodel.diagnosis.inverse_stream": "pimodel.diagnosis.reference_inverse",
}


class _Alias(importlib.abc.Loader):
    def __init__(self, new: str):
        self.new = new

    def create_module(self, spec):
        return None  # default module; exec_module swaps in the real one

    def exec_module(self, module) -> None:
        old = module.__name__
        warnings.warn(f"{old} is deprecated and will be removed in pimodel 0.3; import "
                      f"{self.new} instead", DeprecationWarning, stacklevel=_caller_level())
        sys.modules[old] = importlib.import_module(self.new)


def _caller_level() -> int:
    """The stack level of the first frame outside importlib (the importing line)."""
    frame, level = sys._getframe(2), 3
    while frame is not None and frame.f_code.co_filename.startswith("<frozen"):
        frame, level = frame.f_back, level + 1
    return level


class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        new = MOVED.get(fullname)
        if new is None:
            return None
        return importlib.util.spec_from_loader(fullname, _Alias(new))


def install() -> None:
    """Put the finder of the old paths on ``sys.meta_path`` (once).

    Returns
    -------
    None

    Examples
    --------
    >>> import importlib, warnings
    >>> install()
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", DeprecationWarning)
    ...     old = importlib.import_module("pimodel.slopes")
    >>> old is importlib.import_module("pimodel.identification.slopes")
    True
    """
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.append(_Finder())
