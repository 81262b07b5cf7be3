"""Any FMI 2.0 or 3.0 co-simulation FMU as a discrete-time python-control block.

``fmu_block(path, dt, ...)`` returns a ``control.NonlinearIOSystem`` whose inputs and outputs
are the FMU's (by name). Semantics: at step k the block sets the inputs ``u[k]`` and calls
``doStep(k dt, dt)``; the outputs after that step are ``y[k]`` (so a unit that samples its input
at the start of the step, as ours do, has direct feedthrough). python-control asks for outputs
before the update, so the output function rolls the FMU back after evaluating (it needs
``canGetAndSetFMUstate``); the block's single state is the FMU time.
"""

from __future__ import annotations

import control
import numpy as np

from ..checks import positive_scalar
from .unit import FMUUnit


def _signals(unit: FMUUnit, causality: str) -> list[str]:
    """Scalar signal names of that causality; FMI 3 arrays as ``name[1]`` ... ``name[N]``."""
    names = []
    for v in unit.md.modelVariables:
        if v.causality == causality:
            size = unit._size(v) if v.dimensions else 0
            names += [f"{v.name}[{i + 1}]" for i in range(size)] if size else [v.name]
    return names


def fmu_block(path, dt: float, *, start: dict | None = None, inputs=None, outputs=None,
              name: str | None = None) -> control.NonlinearIOSystem:
    """Wrap the FMU at ``path`` (communication step ``dt``) as a python-control block.

    ``inputs``/``outputs``: variable names to expose (default: every input / output variable of
    the FMU, in model-description order). The block keeps the instance alive; signals use the
    FMU's variable names (rename with ``control.interconnect``'s connection lists if needed).
    """
    dt = positive_scalar(dt, "dt")
    unit = FMUUnit(path, start, instance_name=name or "fmu")
    if not unit.md.coSimulation.canGetAndSetFMUstate:
        raise ValueError(f"{unit.path.name}: the wrapper needs canGetAndSetFMUstate")
    ins = inputs or _signals(unit, "input")
    outs = outputs or _signals(unit, "output")
    for n in (*ins, *outs):
        unit._var(n)  # KeyError naming the variable when absent

    def advance(u):
        unit.set(dict(zip(ins, np.asarray(u, float), strict=True)))
        unit.step(dt)

    def upd(t, x, u, params):
        unit.time = float(x[0])
        advance(u)
        return np.array([unit.time])

    def out(t, x, u, params):
        saved = unit.get_state()
        unit.time = float(x[0])
        advance(u)
        y = unit.get(outs)
        unit.set_state(saved)
        unit.free_state(saved)
        return y

    sys = control.nlsys(upd, out, inputs=list(ins), outputs=list(outs),
                        states=[f"{name or 'fmu'}_time"], dt=dt,
                        name=name or unit.md.coSimulation.modelIdentifier)
    sys.x0 = np.zeros(1)
    sys.fmu_unit = unit
    return sys
