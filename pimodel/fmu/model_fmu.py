"""FMUs of a model (an operator, an inverse or a :class:`~pimodel.operators.cascade.Cascade`): one
FMU per operator, each a unit of ``pimodel.fmu.build.MODELS`` whose parameters' start values are the
operator's (in the model description and compiled into the binary), so that an importer that
sets nothing runs the model. A cascade becomes one FMU per stage, ``<stem>_<i>_<Unit>.fmu``
(i = 1.. in the order of the stages); connect stage i's output (``y``) to stage i+1's input
(``u``; ``v`` for a PIOperator stage, unit PIHysteresis); :func:`cosimulate_chain` does so, in
one communication step per sample.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..operators.cascade import Cascade
from .build import build_fmus
from .operators import unit_parameters
from .spec import MODEL_UNITS, MODELS, Var, check_fmi_version
from .unit import FMUUnit

__all__ = ["build_inverse_fmu", "build_model_fmus", "cosimulate_chain"]

def _c_value(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "1" if value else "0"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    return float(value).hex()  # exact C99 hexadecimal floating constant


def _xml_value(var: Var, value) -> str:
    if var.kind == "Boolean":
        return "true" if value else "false"
    if var.kind == "Integer":
        return str(int(value))
    return repr(float(value))


def _defaults(unit: str, params: dict) -> str:
    """C statements setting the parameters' start values in the unit's storage (Var.storage)."""
    variables = {v.name: v for v in MODELS[unit]["vars"]}
    out = []
    for name, value in params.items():
        field, rest = variables[name].storage, name.partition("[")[2]
        if rest:
            field = f"{field}[{int(rest[:-1]) - 1}]"
        out.append(f"(u)->{field} = {_c_value(value)};")
    return " ".join(out)


def _spec(unit: str, params: dict, salt: str, stop_time: float | None = None) -> dict:
    spec = MODELS[unit]
    names = {v.name for v in spec["vars"]}
    unknown = set(params) - names
    if unknown:
        raise ValueError(f"parameters {sorted(unknown)} are not variables of {unit}")
    variables = [replace(v, start=_xml_value(v, params[v.name])) if v.name in params else v
                 for v in spec["vars"]]
    return {**spec, "vars": variables, "salt": salt, "defaults": _defaults(unit, params),
            **({"stop_time": stop_time} if stop_time else {})}


def build_model_fmus(model, out_dir, *, fmi_version: str = "2.0", Ts: float | None = None,
                     stem: str = "model", compiler: str | None = None,
                     stop_time: float | None = None) -> list[Path]:
    """Build one FMU per operator of ``model`` with the operator's parameters as start values.

    Parameters
    ----------
    model : operator, inverse or Cascade
        See :func:`pimodel.fmu.operators.unit_parameters` for the supported operators.
    out_dir : str or Path
        Directory of the FMUs (created).
    fmi_version : {"2.0", "3.0"}
    Ts : float, optional
        Sample time [s] of the rate-independent stages (default: the ``dt`` of a rate-dependent
        or creep stage, else 1e-3).
    stem : str
        File name prefix (a C identifier).
    compiler : str, optional
        C compiler (default: found on PATH).
    stop_time : float, optional
        ``stopTime`` of the ``DefaultExperiment`` [s] (e.g. the length of the record the
        model was made from; its ``stepSize`` is ``Ts``); default 1000 samples.

    Returns
    -------
    list of Path
        ``<stem>_<i>_<Unit>[_fmi3].fmu``, in the order of the stages.

    Raises
    ------
    ValueError
        An unsupported or non-exportable operator (named by stage), stages with different
        ``dt``, a bad ``stem``.

    Examples
    --------
    >>> from pimodel.operators.creep import CreepOperator
    >>> import tempfile
    >>> paths = build_model_fmus(CreepOperator([0.05], [0.1], dt=1e-3), tempfile.mkdtemp())
    >>> paths[0].name
    'model_1_CreepOperator.fmu'
    """
    check_fmi_version(fmi_version)
    if not stem.isidentifier():
        raise ValueError(f"stem: expected a C identifier, got {stem!r}")
    if stop_time is not None and not (np.isfinite(stop_time) and stop_time > 0):
        raise ValueError(f"stop_time: expected a finite time > 0 [s], got {stop_time!r}")
    stages = model.stages if isinstance(model, Cascade) else (model,)
    dts = {s.dt for s in stages if hasattr(s, "dt")} | {s.forward.dt for s in stages
                                                        if hasattr(getattr(s, "forward", None),
                                                                   "dt")}
    dts |= {s.model.dt for s in stages if hasattr(getattr(s, "model", None), "dt")}
    if len(dts) > 1:
        raise ValueError(f"model: the stages have different sample times dt {sorted(dts)}")
    Ts = Ts if Ts is not None else (dts.pop() if dts else 1e-3)
    names = []
    try:
        for i, stage in enumerate(stages, start=1):
            try:
                unit, params = unit_parameters(stage, Ts=Ts)
            except (TypeError, ValueError) as err:
                raise ValueError(f"model stage {i}: {err}") from None
            ident = f"{stem}_{i}_{unit}"
            salt = hashlib.sha256(json.dumps(params, sort_keys=True).encode()).hexdigest()[:16]
            MODEL_UNITS[ident] = _spec(unit, params, salt, stop_time)
            names.append(ident)
        return build_fmus(out_dir, names, compiler=compiler, fmi_version=fmi_version)
    finally:
        for ident in names:
            MODEL_UNITS.pop(ident, None)


def build_inverse_fmu(model, out_dir, *, fmi_version: str = "2.0", stem: str = "model",
                      compiler: str | None = None, stop_time: float | None = None) -> list[Path]:
    """The feedforward FMU of a diagnosed model (unit DiagnosedInverse), beside its model FMU.

    Parameters
    ----------
    model : DiagnosedModel or other
        A :class:`~pimodel.diagnosis.model.DiagnosedModel`: its inverse is built as
        ``<stem>_1_DiagnosedInverse[_fmi3].fmu`` (input ``y_d``, output ``v``, delayed by its
        ``latency``); any other model has no such FMU (empty list).
    out_dir : str or Path
        Directory of the FMU (created).
    fmi_version : {"2.0", "3.0"}
    stem : str
        File name prefix (a C identifier), as :func:`build_model_fmus`.
    compiler : str, optional
        C compiler (default: found on PATH).
    stop_time : float, optional
        ``stopTime`` of the ``DefaultExperiment`` [s], as :func:`build_model_fmus`.

    Returns
    -------
    list of Path
        The inverse's FMU, or ``[]``.

    Raises
    ------
    ValueError
        A model whose inverse has no FMU (more than 10 prefilter sections, or 10 sections of
        a Wiener filter's inverse; more than 128 plays).

    Examples
    --------
    >>> from pimodel.diagnosis.model import DiagnosedModel
    >>> import tempfile
    >>> m = DiagnosedModel([0.0, 0.5], [1.0, 0.5], 0.1, dt=1e-3)
    >>> build_inverse_fmu(m, tempfile.mkdtemp())[0].name  # doctest: +SKIP
    'model_1_DiagnosedInverse.fmu'
    """
    from ..diagnosis.model import DiagnosedModel

    if not isinstance(model, DiagnosedModel):
        return []
    return build_model_fmus(model.inverse(), out_dir, fmi_version=fmi_version, stem=stem,
                            compiler=compiler, stop_time=stop_time)


def cosimulate_chain(paths, u, Ts: float) -> np.ndarray:
    """Run FMUs in series (stage i's first output into stage i+1's first input), one step of
    ``Ts`` per sample, with each FMU's own start values: ``y[k]`` of the last stage for input
    ``u[k]``.

    Parameters
    ----------
    paths : sequence of Path
        FMUs from :func:`build_model_fmus`, first stage first.
    u : array_like
        Input samples of the first stage.
    Ts : float
        Sample time [s] (the FMUs' ``Ts``).

    Returns
    -------
    numpy.ndarray of float, shape (N,)
        Output ``y[k]`` of the last stage after the step that took ``u[k]``.

    Examples
    --------
    The FMUs must be built first (seconds), hence skipped here:

    >>> from pimodel.operators.creep import CreepOperator
    >>> import tempfile
    >>> op = CreepOperator([0.05], [0.1], dt=1e-3)
    >>> paths = build_model_fmus(op, tempfile.mkdtemp())  # doctest: +SKIP
    >>> y = cosimulate_chain(paths, np.ones(4), 1e-3)  # doctest: +SKIP
    >>> bool(np.allclose(y, op.simulate(np.ones(4))))  # doctest: +SKIP
    True
    """
    units = [FMUUnit(p, instance_name=f"stage{i}") for i, p in enumerate(paths, start=1)]
    ports = [(next(v.name for v in unit.md.modelVariables if v.causality == "input"),
              next(v.name for v in unit.md.modelVariables if v.causality == "output"))
             for unit in units]
    out = np.empty(len(u))
    try:
        for k, x in enumerate(np.asarray(u, float)):
            for unit, (inp, outp) in zip(units, ports, strict=True):
                unit.set({inp: x})
                unit.step(Ts)
                x = unit.get([outp])[0]
            out[k] = x
    finally:
        for unit in units:
            unit.close()
    return out
