"""Whether a fitted ``dynamics`` acts as a pure delay on the records: a tie-break between the
names ``dynamics`` and ``delay``.

A pure delay has unit gain and a phase linear in frequency; a mode changes the gain near its
resonance. A fast, heavily damped mode (or a few of them in parallel) fitted to a delay of a
sample or two has a gain within a few percent of 1 over the band the records excite and fits
about as well as the delay; the diagnosis then names ``delay`` (one parameter) instead of
``dynamics`` (:func:`pimodel.diagnosis.diagnose`). The check is on the fitted linear part after
the hysteresis (:mod:`.lti`), over ``0 < f <= BAND * Nyquist``.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import freqz

from .lti import element_coefficients

__all__ = ["BAND", "GAIN_TOLERANCE", "is_delay_like", "lti_gain"]

BAND = 0.25  # share of the Nyquist frequency the gain is checked over
GAIN_TOLERANCE = 0.1  # |G| within 1 +- this over the band: delay-like
POINTS = 256


def lti_gain(params: dict, dt: float, band: float = BAND) -> np.ndarray:
    """``|G(e^{j w dt})|`` of a fitted Hammerstein linear part over ``0 < f <= band / (2 dt)``.

    Parameters
    ----------
    params : dict
        The ``dynamics`` model's parameters: ``mode_hz``, ``mode_damping`` and optionally
        ``lti_elements``, ``lti_gains`` (:func:`.lti.describe_lti`).
    dt : float
        Sample time [s].
    band : float
        Share of the Nyquist frequency.

    Returns
    -------
    numpy.ndarray
        The gain at ``POINTS`` frequencies [-].

    Examples
    --------
    >>> g = lti_gain({"mode_hz": 2000.0, "mode_damping": 0.05}, 1e-4)
    >>> round(float(g.max()), 1)  # a light 2 kHz mode at 10 kHz: gain 1.6 at 1.25 kHz
    1.6
    """
    w = np.linspace(0.0, band * np.pi, POINTS + 1)[1:]
    base = freqz(*element_coefficients(("mode", params["mode_hz"], params["mode_damping"]), dt),
                 worN=w)[1]
    g = base.copy()
    for el, gain in zip(params.get("lti_elements", ()), params.get("lti_gains", ()),
                        strict=True):
        g += float(gain) * (freqz(*element_coefficients(tuple(el), dt), worN=w)[1] - base)
    return np.abs(g)


def is_delay_like(params: dict, dt: float) -> bool:
    """True when a fitted ``dynamics`` after the hysteresis has a gain within
    ``GAIN_TOLERANCE`` of 1 over the band (module docstring); False for a filter before the
    hysteresis or a model without a base mode.

    Parameters
    ----------
    params : dict
        The ``dynamics`` model's parameters (a report's ``verdict["model"]``).
    dt : float
        Sample time [s].

    Returns
    -------
    bool

    Examples
    --------
    >>> is_delay_like({"mode_hz": 4000.0, "mode_damping": 0.5}, 1e-4)  # fast, damped
    True
    >>> is_delay_like({"mode_hz": 2000.0, "mode_damping": 0.05}, 1e-4)  # a resonance
    False
    """
    if "mode_hz" not in params or params.get("dynamics_position") == "before":
        return False
    return bool(np.max(np.abs(lti_gain(params, dt) - 1.0)) <= GAIN_TOLERANCE)
