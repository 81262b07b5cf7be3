"""Closed loops and their analysis: compiled loops, simulation of python-control systems,
actuator dynamics and the describing-function view of a PI operator in a loop.

Modules
-------

::

    compiled    compiled closed loops (C core) and their python-control twins
    simulation  simulate a python-control system from its own initial state
    actuators   stage dynamics after the hysteresis: mode, creep, delay
    describing  circle criterion, harmonic balance, residual hysteresis
"""

from .actuators import (
    creep_lags,
    creep_per_decade,
    delay_samples,
    second_order_mode,
    stage_dynamics,
)
from .compiled import (
    PID,
    LoopResult,
    loop_system,
    run_loop,
)
from .describing import (
    CircleCriterion,
    LimitCycle,
    PIDescribingFunction,
    circle_criterion,
    harmonic_balance,
    play_describing_function,
    residual_hysteresis,
    sector,
    static_gain,
)
from .simulation import (
    Signals,
    simulate,
)

__all__ = [
    "loop_system",
    "LoopResult",
    "PID",
    "run_loop",
    "Signals",
    "simulate",
    "creep_lags",
    "creep_per_decade",
    "delay_samples",
    "second_order_mode",
    "stage_dynamics",
    "CircleCriterion",
    "LimitCycle",
    "PIDescribingFunction",
    "circle_criterion",
    "harmonic_balance",
    "play_describing_function",
    "residual_hysteresis",
    "sector",
    "static_gain",
]
