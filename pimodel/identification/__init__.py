"""Identification of a PI model from measured records.

The chain (:func:`identify`): number and weights of plays from the loop slopes, then the radii
(adaptive estimator, the conventional baseline or the joint estimator). The online estimators
live in :mod:`pimodel.identification.adaptive`.

Modules
-------

::

    chain               identify(): slopes, then radii; the Identification result
    branches            monotone branches: reversal detection with a threshold
    slopes              number and weights of plays from the loop slopes (Lemma 1)
    piecewise_linear    optimal continuous piecewise-linear regression (the slope fit)
    conventional        the baseline: preset radii, least-squares weights
    identifiability     can the record identify every play? (Lemma 2, Prop. 2)
    play_reduction      merge or drop the plays the data do not resolve
    extended_operators  fits of the generalized, rate-dependent and creep operators
    plots               figures of an identification
"""

from .branches import (
    Branch,
    ReversalScanner,
    find_reversals,
    split_branches,
)
from .chain import (
    Identification,
    identify,
    max_passes,
)
from .conventional import (
    ConventionalFit,
    fit_conventional,
)
from .extended_operators import (
    OperatorFit,
    fit_asymmetric,
    fit_creep,
    fit_generalized,
    fit_hysteresis_with_creep,
    fit_rate_dependent,
)
from .identifiability import (
    ExcitationReport,
    check_excitation,
)
from .piecewise_linear import (
    SegmentedFit,
    fit_binned,
    fit_hinges,
    fit_segmented,
    polish_fit,
)
from .play_reduction import (
    PlayReduction,
    reduce_plays,
)
from .plots import (
    plot_identification,
)
from .slopes import (
    SlopeIdentification,
    identify_slopes,
    plays_from_slopes,
)

__all__ = [
    "Identification",
    "identify",
    "max_passes",
    "Branch",
    "find_reversals",
    "ReversalScanner",
    "split_branches",
    "identify_slopes",
    "plays_from_slopes",
    "SlopeIdentification",
    "fit_binned",
    "fit_hinges",
    "fit_segmented",
    "polish_fit",
    "SegmentedFit",
    "ConventionalFit",
    "fit_conventional",
    "check_excitation",
    "ExcitationReport",
    "PlayReduction",
    "reduce_plays",
    "OperatorFit",
    "fit_asymmetric",
    "fit_creep",
    "fit_generalized",
    "fit_hysteresis_with_creep",
    "fit_rate_dependent",
    "plot_identification",
]
