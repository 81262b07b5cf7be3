"""Sim-to-real gap diagnosis: why measured records differ from the nominal PI model.

:func:`diagnose` fits the nominal PI model on train records, measures the noise floor, ranks
where the validate residual lies, and adds candidate effects (creep, dynamics, delay,
asymmetry, drift, rate) while each lowers the Bayesian information criterion (BIC) on the
validate records by a clear margin;
it returns a :class:`DiagnosisReport`. The submodules:

- :mod:`pimodel.diagnosis.diagnose`: :func:`diagnose` and :class:`DiagnosisReport`;
- :mod:`pimodel.diagnosis.effects`: the records as segments, the nominal model and the
  candidate effects, each fitted jointly with the hysteresis weights;
- :mod:`pimodel.diagnosis.rate`: the ``rate`` candidate's columns (play radii and weights
  growing with a low-passed input rate, to first order);
- :mod:`pimodel.diagnosis.lti`: the linear part of the ``dynamics`` candidate (modes, a
  low-pass, a direct term), its order chosen by the train BIC, and its approximate inverse;
- :mod:`pimodel.diagnosis.wiener`: the ``dynamics`` candidate with a filter before the
  hysteresis (a Wiener model: a driver's low-pass or a mode on the input);
- :mod:`pimodel.diagnosis.delaylike`: whether a fitted ``dynamics`` acts as a pure delay (the
  tie-break between the names ``dynamics`` and ``delay``);
- :mod:`pimodel.diagnosis.noise`: the measurement-noise floor of the records;
- :mod:`pimodel.diagnosis.where`: the regions, bands and correlations of the residual;
- :mod:`pimodel.diagnosis.plots`: the figures of a report;
- :mod:`pimodel.diagnosis.model`: :class:`~pimodel.diagnosis.model.DiagnosedModel`, the model a
  report chose (:meth:`DiagnosisReport.model`), with its causal feedforward inverse;
- :mod:`pimodel.diagnosis.stream`: that model streamed sample by sample on the C core, as a
  python-control block and as the DiagnosedModel FMU unit's values;
- :mod:`pimodel.diagnosis.inverse_stream`: the model's feedforward inverse as a causal
  python-control block;
- :mod:`pimodel.diagnosis.feedforward`: open-loop feedforward with such a model, tried on a
  simulated true stage.

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
