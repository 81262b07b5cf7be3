"""A gain per validate record, outside the diagnosis' vocabulary: the test that tells a sensor
gain that changes between records from a level (or drift) per record.

A level per record leaves a validate residual ``e = y - y_hat`` that is constant on the record.
A gain ``1 + c`` on one record leaves ``e[k] = c y_hat[k] + level``: the residual correlates
with the model's output beyond what a level explains. Per validate record, sample by sample (no
memory), the level and the gain are fitted by least squares, ``e[k] ~ l + c (y_hat[k] -
mean(y_hat))``; the gains explain the gap when, pooled over the records, what is left is within
``GAIN_REST_NOISE`` noise floors and at most ``GAIN_REST_SHARE`` of what the levels alone leave,
with some ``|c|`` at least ``GAIN_MIN``. On the train records the hysteresis weights absorb any
common gain, so the test reads the validate records only. Measured on
``pimodel.stages.density_stage`` (a gain 1.04-1.08 on the validate record): the level leaves
0.79 um (8.8 noise floors), level and gain 0.094 um (1.05 floors), ``c`` = 0.069 (seed 0).
"""

from __future__ import annotations

import numpy as np

GAIN_MIN = 0.01  # a gain per record this far from 1 (relative)
GAIN_REST_NOISE = 2.0  # ... leaving at most this factor of the noise floor
GAIN_REST_SHARE = 0.5  # ... and at most this share of the RMS that the levels alone leave

__all__ = ["GAIN_MIN", "GAIN_REST_NOISE", "GAIN_REST_SHARE", "gain_note", "record_gains"]


def record_gains(records, outputs, noise: float) -> dict | None:
    """The gain per validate record that explains the residual (module docstring), or None.

    Parameters
    ----------
    records : list
        Validate records (``.y``, the measured output).
    outputs : list of numpy.ndarray
        The model's predictions ``y_hat``, one per record, shaped like its ``y``.
    noise : float
        The noise floor (RMS, output units).

    Returns
    -------
    dict or None
        ``per_record`` (``c`` of each record: its gain is ``1 + c`` relative to the model),
        ``rms_levels`` (the residual's RMS around a level per record) and ``rms_gains``
        (around a level and a gain per record); None when the gains do not explain the
        residual.

    Raises
    ------
    ValueError
        ``outputs`` not one array per record, shaped like its ``y``.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> y_hat = np.sin(np.linspace(0.0, 20.0, 400))
    >>> rec = SimpleNamespace(y=1.05 * y_hat + 0.3)  # a gain 5 % higher and a level
    >>> round(record_gains([rec], [y_hat], 0.01)["per_record"][0], 3)
    0.05
    >>> record_gains([SimpleNamespace(y=y_hat + 0.3)], [y_hat], 0.01) is None  # a level only
    True
    """
    if len(outputs) != len(records):
        raise ValueError(f"outputs: expected one prediction per record ({len(records)}), got "
                         f"{len(outputs)}")
    gains, e_level, e_gain, n = [], 0.0, 0.0, 0
    for i, (rec, out) in enumerate(zip(records, outputs, strict=True)):
        y, yh = np.asarray(rec.y, float), np.asarray(out, float)
        if yh.shape != y.shape:
            raise ValueError(f"outputs[{i}]: expected shape {y.shape} like the record's y, got "
                             f"{yh.shape}")
        # two columns of the record: the centred output and the residual, centred, then
        # less the gain's part, in place (the same numbers as the expressions written out)
        yc = yh - yh.mean()
        ec = y - yh
        ec -= ec.mean()
        c = float(ec @ yc / (yc @ yc)) if yc @ yc > 0 else 0.0
        gains.append(c)
        e_level += float(ec @ ec)
        rest = np.subtract(ec, np.multiply(c, yc, out=yc), out=ec)  # ec - c * yc
        e_gain += float(rest @ rest)
        del yc, ec, rest
        n += y.size
    rms_levels, rms_gains = np.sqrt(e_level / max(n, 1)), np.sqrt(e_gain / max(n, 1))
    if not (gains and max(abs(c) for c in gains) >= GAIN_MIN
            and rms_gains <= GAIN_REST_NOISE * noise
            and rms_gains <= GAIN_REST_SHARE * rms_levels):
        return None
    return {"per_record": gains, "rms_levels": float(rms_levels), "rms_gains": float(rms_gains)}


def gain_note(gain: dict) -> str:
    """The gains of :func:`record_gains` in words.

    Parameters
    ----------
    gain : dict
        :func:`record_gains`' result.

    Returns
    -------
    str

    Examples
    --------
    >>> gain_note({"per_record": [0.062], "rms_levels": 0.8, "rms_gains": 0.09})[:70]
    'the validate output is scaled against the model (validate record 0: +6'
    """
    parts = ", ".join(f"validate record {i}: {100 * c:+.1f} %"
                      for i, c in enumerate(gain["per_record"]) if abs(c) >= GAIN_MIN)
    return (f"the validate output is scaled against the model ({parts}): a gain per record "
            f"leaves {gain['rms_gains']:.3g} of the {gain['rms_levels']:.3g} a level per "
            "record leaves; a sensor gain that changes between records is outside the "
            "candidates")
