"""Simulated piezo stages for tests and studies: the true stages a diagnosis or an identification
is checked against, with unmodelled effects, stepped sample by sample or made in chunks.

Modules
-------

::

    pi_stage        Truth: a piezo stage with PI hysteresis and unmodelled effects
    preisach_stage  AltTruth: an independently written Preisach stage (numpy/scipy only)
    density_stage   DensityStage: a third, independent 2 kHz stage (smooth PI density,
                    multisine/chirp/ramp/random inputs, thermal drift, out-of-vocabulary effects)
    stepper         both stages sample by sample, for feedback loops
    long_records    long noisy records made chunk by chunk
"""

from .density_stage import (
    DensityStage,
    density_input,
    density_records,
    random_density_stage,
)
from .long_records import (
    noisy_output_chunks,
    record_length,
)
from .pi_stage import (
    Truth,
    creep_lag_filters,
    excitation,
    random_truth,
    rate_dependent_pi,
    zoh_coefficients,
)
from .preisach_stage import (
    AltTruth,
    excitations,
    random_alt_truth,
)
from .stepper import (
    noise_free,
    stage_stepper,
)

__all__ = [
    "creep_lag_filters",
    "excitation",
    "random_truth",
    "rate_dependent_pi",
    "Truth",
    "zoh_coefficients",
    "DensityStage",
    "density_input",
    "density_records",
    "random_density_stage",
    "AltTruth",
    "excitations",
    "random_alt_truth",
    "noise_free",
    "stage_stepper",
    "noisy_output_chunks",
    "record_length",
]
