"""The FMU limits a model file must meet before ``pimodel fmu build --model`` builds it:
:func:`check_fmu_limits`.

The numbers are the C core's (:data:`pimodel._native.LIMITS` through
:mod:`pimodel.diagnosis.limits`), never retyped: an operator's FMU takes at most ``NMAX``
plays (and creep lags), a DiagnosedModel's ``2 NMAX`` plays and ``NMAX`` creep lags. Python
itself runs larger models; the FMUs declare fixed-size arrays.
"""

from __future__ import annotations

from ..diagnosis.limits import NMAX

__all__ = ["check_fmu_limits", "fmu_play_limit"]


def fmu_play_limit(operator) -> int:
    """Most plays the FMU of ``operator`` takes (a DiagnosedModel ``2 NMAX``, else ``NMAX``).

    Parameters
    ----------
    operator : object
        One stage of a model.

    Returns
    -------
    int

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> fmu_play_limit(PIOperator([1.0], [0.0]))
    64
    """
    return 2 * NMAX if type(operator).__name__ == "DiagnosedModel" else NMAX


def _stages(op, where: str):
    stages = getattr(op, "stages", None)
    if stages is not None:
        for i, stage in enumerate(stages):
            yield from _stages(stage, f"{where}.stages[{i}]")
    elif getattr(op, "forward", None) is not None and getattr(op, "weights", None) is None:
        yield from _stages(op.forward, f"{where}.operator")
    else:
        yield op, where


def check_fmu_limits(model, path=None) -> None:
    """Raise ValueError when a stage of ``model`` has more plays or creep lags than its FMU
    takes ("at most N plays", naming the file and the key).

    Parameters
    ----------
    model : object
        A :class:`~pimodel.model_files.file_model.Model` or an operator.
    path : str or Path, optional
        The model file, for the message.

    Raises
    ------
    ValueError
        ``<path>: model.weights: 65 plays; the FMU takes at most 64 plays``.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> check_fmu_limits(PIOperator([1.0] * 65, [0.1 * i for i in range(65)]))
    Traceback (most recent call last):
    ...
    ValueError: model.weights: 65 plays; the FMU takes at most 64 plays
    """
    prefix = f"{path}: " if path is not None else ""
    for op, where in _stages(getattr(model, "operator", model), "model"):
        limit = fmu_play_limit(op)
        for key, what, most in (("weights", "plays", limit), ("gains", "creep lags", NMAX)):
            values = getattr(op, key, None)
            if values is not None and len(values) > most:
                raise ValueError(f"{prefix}{where}.{key}: {len(values)} {what}; the FMU takes "
                                 f"at most {most} {what}")
        lags = getattr(op, "params", {}).get("creep_lag_gains") \
            if isinstance(getattr(op, "params", None), dict) else None
        if lags is not None and len(lags) > NMAX:
            raise ValueError(f"{prefix}{where}.params.creep_lag_gains: {len(lags)} creep lags; "
                             f"the FMU takes at most {NMAX} creep lags")
