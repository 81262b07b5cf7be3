"""Sim-to-real gap diagnosis: why measured records differ from the nominal PI model.

:func:`diagnose` fits the nominal PI model on train records, measures the noise floor, ranks
where the validate residual lies, and adds candidate effects (creep, dynamics, delay,
asymmetry, drift, rate) while each lowers the Bayesian information criterion (BIC) on the
validate records by a clear margin;
it returns a :class:`DiagnosisReport`. The model it chose (:meth:`DiagnosisReport.model`) has its
blocks and FMU units on the C core; the NumPy forms stay as references that tests hold equal.

Modules
-------

::

    diagnose            diagnose() and the DiagnosisReport
    effects             records as segments, the nominal model, the candidate effects' fits
    chunked             least squares over chunks of a record (normal equations, running QR)
    filters             the discrete filters effects are built of: lag, mode, delay shift
    rate                the rate candidate's columns (radii or weights growing with the rate)
    misfit              a chosen rate's own misfit on validate, set aside to judge a further effect
    drift               the drift candidate: clocks, levels per record, its term
    lti                 the dynamics' linear part: elements, order by BIC, approximate inverse
    wiener              the dynamics as a filter before the hysteresis (a Wiener model)
    delaylike           whether a fitted dynamics acts as a pure delay
    noise               the measurement-noise floor of the records
    where               regions, bands and correlations of the residual
    coverage            which plays validate drives on loops that train did not identify
    plots               the figures of a report
    summary             the report in words (verdict, how sure, where, next step) and report.md
    model               DiagnosedModel and DiagnosedInverse: the chosen model, batch forms
    monotone            the nearest monotone PI weights (what the inverse solves)
    native_model        the model streamed on the C core: its block, runner and FMU values
    native_inverse      the causal feedforward on the C core: its block, runner and FMU values
    reference_inverse   the feedforward's NumPy reference: per-sample solver and block
    limits              the C core's limits the native forms respect
    checks              the check of the signals the model and its runners take
    feedforward         open-loop feedforward with a model, tried on a simulated stage

Examples
--------
>>> import pimodel.diagnosis as diagnosis
>>> diagnosis.__all__
['DiagnosisReport', 'diagnose']
>>> from pimodel.diagnosis.effects import EFFECTS
>>> EFFECTS
('creep', 'dynamics', 'delay', 'asymmetry', 'drift', 'rate')
"""

from .diagnose import DiagnosisReport, diagnose

__all__ = ["DiagnosisReport", "diagnose"]
