"""Hysteresis operators: the PI operator and its relatives, each with an exact inverse.

Modules
-------

::

    base                 what the operators share: parameter properties, repr, streaming state
    pi                   PIOperator (exact inverse) and TimeDependentPI (radii per sample)
    describing_function  a PI operator's describing function, sector and static gain
    envelopes            increasing envelope functions with closed-form inverses
    generalized          GeneralizedPI: plays between envelopes, exact inverse
    asymmetric           AsymmetricPI: distinct loading and unloading envelopes
    rate_dependent       RateDependentPI: radii growing with the input rate
    creep                CreepOperator: a sum of first-order lags, exact inverse
    cascade              Cascade: operators in series and the chain's inverse
"""

from .asymmetric import (
    AsymmetricPI,
    AsymmetricPIInverse,
)
from .base import (
    InverseStreaming,
    Streaming,
    freeze,
    operator_repr,
    read_only,
    size_of,
    streaming_state,
)
from .cascade import (
    Cascade,
)
from .creep import (
    CreepOperator,
)
from .describing_function import (
    PIDescribingFunction,
    play_describing_function,
    sector,
    static_gain,
)
from .envelopes import (
    Envelope,
)
from .generalized import (
    GeneralizedPI,
)
from .pi import (
    PIOperator,
    TimeDependentPI,
)
from .rate_dependent import (
    RateDependentPI,
    RateDependentPIInverse,
)

__all__ = [
    "freeze",
    "InverseStreaming",
    "operator_repr",
    "read_only",
    "size_of",
    "Streaming",
    "streaming_state",
    "PIOperator",
    "TimeDependentPI",
    "PIDescribingFunction",
    "play_describing_function",
    "sector",
    "static_gain",
    "Envelope",
    "GeneralizedPI",
    "AsymmetricPI",
    "AsymmetricPIInverse",
    "RateDependentPI",
    "RateDependentPIInverse",
    "CreepOperator",
    "Cascade",
]
