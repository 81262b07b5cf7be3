"""Any FMI 2.0 or 3.0 co-simulation FMU as a discrete-time python-control block.

``fmu_block(path, dt, ...)`` returns a ``control.NonlinearIOSystem`` whose inputs and outputs
are the FMU's (by name). Semantics: at step k the block sets the inputs ``u[k]`` and calls
``doStep(k dt, dt)``; the outputs after that step are ``y[k]`` (so a unit that samples its input
at the start of the step, as ours do, has direct feedthrough). python-control asks for outputs
before the update, so the output function rolls the FMU back after evaluating (it needs
``canGetAndSetFMUstate``); the block's single state is the FMU time ``time`` [s], own initial
state 0 (:func:`pimodel.blocks.initial_state`). The FMU's internal state lives in the instance,
not in the python-control state, so the block runs forward from time 0: a simulation that
starts again at time 0 restores the instance to its state after initialisation (repeated
``input_output_response`` calls give the same result); a state time other than the instance's
raises ValueError. FMU parameters are fixed at initialisation (``start``), so the block has no
python-control ``params``. Vector signals keep the FMU's 1-based names (``r_hat[1]`` ...), the
names of the native blocks, so FMU and native blocks connect by name in one ``interconnect``.
"""

from __future__ import annotations

import control
import numpy as np

from ..blocks.framework import Block, signal_labels
from ..checks import positive_scalar
from .unit import FMUUnit

__all__ = ["fmu_block"]


def _signals(unit: FMUUnit, causality: str) -> list[str]:
    """Scalar signal names of that causality; FMI 3 arrays as ``name[1]`` ... ``name[N]``."""
    names = []
    for v in unit.md.modelVariables:
        if v.causality == causality:
            size = unit._size(v) if v.dimensions else 0
            names += signal_labels(v.name, size) if size else [v.name]
    return names


def fmu_block(path, dt: float, *, start: dict | None = None, inputs=None, outputs=None,
              name: str | None = None, feedthrough: bool = True) -> control.NonlinearIOSystem:
    """Wrap the FMU at ``path`` (communication step ``dt``) as a python-control block.

    Parameters
    ----------
    path : str or Path
        A co-simulation FMU (FMI 2.0 or 3.0) with ``canGetAndSetFMUstate``.
    dt : float
        Communication step [s]; step k calls ``doStep(k dt, dt)``.
    start : dict, optional
        Parameters and start values by variable name (``{"Ts": 1e-3, "n": 2, "p[1]": 1.0}``).
    inputs, outputs : list of str, optional
        Variable names to expose (default: every input / output variable, in model-description
        order; FMI 3 arrays element-wise as ``name[1]`` ...).
    name : str, optional
        Block and instance name (default: the model identifier).
    feedthrough : bool
        True (default): the outputs at step k are those after ``doStep`` with ``u[k]`` (FMU
        state rolled back). False: the outputs the FMU holds before that step (after step
        k-1, the initial values at k = 0), so the block has no direct feedthrough. Use False for
        the RadiusEstimator FMU feeding an adaptive compensator: its ``r_hat`` is then the
        estimate used at step k, as the native :func:`~pimodel.blocks.estimator_block`'s, and
        the loop has no algebraic cycle (``y_hat`` and ``e`` are then those of step k-1).

    Returns
    -------
    control.NonlinearIOSystem
        Inputs and outputs named as the FMU's variables; one state, ``time``.

    Raises
    ------
    ValueError
        If the FMU cannot save and restore its state, or is simulated out of sequence.
    KeyError
        If a named input or output is not a variable of the FMU.

    Examples
    --------
    >>> from pimodel.fmu.block import fmu_block
    >>> est = fmu_block("fmus/RadiusEstimator.fmu", 1e-3, name="est",
    ...                 start={"Ts": 1e-3, "n": 2, "p[1]": 1.0, "p[2]": 0.5},
    ...                 outputs=["r_hat[1]", "r_hat[2]", "y_hat", "e"])  # doctest: +SKIP
    """
    dt = positive_scalar(dt, "dt")
    unit = FMUUnit(path, start, instance_name=name or "fmu")
    if not unit.md.coSimulation.canGetAndSetFMUstate:
        raise ValueError(f"{unit.path.name}: the wrapper needs canGetAndSetFMUstate")
    ins = inputs or _signals(unit, "input")
    outs = outputs or _signals(unit, "output")
    for n in (*ins, *outs):
        unit._var(n)  # KeyError naming the variable when absent
    initial = unit.get_state()
    label = name or unit.md.coSimulation.modelIdentifier

    def sync(x) -> None:
        t = float(x[0])
        if t == unit.time:
            return
        if t == 0.0:
            unit.set_state(initial)  # a new run from time 0
            return
        raise ValueError(f"block {label!r}: evaluated at FMU time {t:g} but the instance is at "
                         f"{unit.time:g}; an FMU block only runs forward from time 0")

    def advance(u):
        unit.set(dict(zip(ins, np.asarray(u, float), strict=True)))
        unit.step(dt)

    def upd(t, x, u, params):
        sync(x)
        advance(u)
        return np.array([unit.time])

    def out(t, x, u, params):
        sync(x)
        if not feedthrough:
            return unit.get(outs)
        saved = unit.get_state()
        advance(u)
        y = unit.get(outs)
        unit.set_state(saved)
        unit.free_state(saved)
        return y

    sys = Block(upd, out, own_state=lambda params: np.zeros(1),
                 aliases={f"{name or 'fmu'}_time": "time"}, inputs=list(ins),
                 outputs=list(outs), states=["time"], dt=dt, name=label)
    sys.fmu_unit = unit
    return sys
