"""The compensation comparison on the piezo-like stage (used by tests and the study).

Models are identified on a 1 Hz triangle of 2 V peak to peak (+-1 V, the paper's 17 um
range) of the stage (no dynamics); each model's exact
inverse is then used as feedforward for a reference with major and minor loops, on the plant
without and with a second-order mode, and with a PID loop.
"""

from __future__ import annotations

import numpy as np

from ..identification.chain import identify
from ..loops.actuators import stage_dynamics
from ..loops.compiled import PID, run_loop
from ..operators.pi import PIOperator
from ..signals import major_minor_loops, triangle

__all__ = [
    "chord_gain",
    "compensation_table",
    "identified_models",
    "reference",
]

STAGE = PIOperator([6.3460, 1.6735, 1.1552, 0.4477], [0.0, 0.1945, 0.4826, 0.5707])
AMPLITUDE = 1.0  # V: 2 V peak to peak


def chord_gain() -> float:
    """Linear feedforward gain [V/um] of the uncompensated loop: input over output range of the
    major loop (the best a static gain can do on average).

    Returns
    -------
    float
        Peak-to-peak of the 1 Hz triangle input over peak-to-peak of :data:`STAGE`'s output
        [V/um].

    Examples
    --------
    >>> round(chord_gain(), 5)
    0.11787
    """
    t, v = triangle(AMPLITUDE, 1, fs=1000, duration=2)
    return float(np.ptp(v) / np.ptp(STAGE.simulate(v)))


def identified_models(snr_db: float | None = None, seed: int = 0) -> dict[str, PIOperator]:
    """Proposed (slopes + adaptive radii, n = 4) and conventional (n = 4, 7, 10) models.

    Identified on 3 s of the 1 Hz triangle (+-1 V, sampled at 1 kHz) through :data:`STAGE`.

    Parameters
    ----------
    snr_db : float, optional
        Output noise added before identification, as a signal-to-noise ratio [dB]; default
        none.
    seed : int, optional
        Seed of the noise generator. Default 0.

    Returns
    -------
    dict of str to PIOperator
        ``"proposed n=4"``, ``"conventional n=4"``, ``"conventional n=7"``,
        ``"conventional n=10"``.

    Examples
    --------
    >>> list(identified_models())
    ['proposed n=4', 'conventional n=4', 'conventional n=7', 'conventional n=10']
    """
    t, v = triangle(AMPLITUDE, 1, fs=1000, duration=3)
    y = STAGE.simulate(v)
    if snr_db is not None:
        from ..signals import add_noise_snr

        y = add_noise_snr(y, snr_db, np.random.default_rng(seed))
    models = {"proposed n=4": identify(v, y, dt=1e-3, n_plays=4).operator}
    for n in (4, 7, 10):
        models[f"conventional n={n}"] = identify(v, y, dt=1e-3, method="conventional",
                                                 n_plays=n).operator
    return models


def reference(fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Desired displacement [um]: the stage's response to major and minor 1 Hz loops.

    Parameters
    ----------
    fs : float
        Sample rate [Hz].

    Returns
    -------
    t : numpy.ndarray of float
        Sample times [s], spaced ``1 / fs``.
    y_d : numpy.ndarray of float
        :data:`STAGE`'s output for major and minor loops of the input, zero mean [um].

    Examples
    --------
    >>> t, y_d = reference(1000.0)
    >>> float(t[1]), round(float(np.ptp(y_d)), 2)
    (0.001, 16.97)
    """
    t, v = major_minor_loops(AMPLITUDE, 1, fs=fs, minor_fractions=(0.6, 0.3, 0.15))
    return t, STAGE.simulate(v) - STAGE.simulate(v).mean()


def compensation_table(models: dict[str, PIOperator], *, fs: float = 10_000.0,
                       fn_hz: float = 1000.0, damping: float = 0.05,
                       pid: PID | None = None) -> dict[str, dict[str, dict[str, float]]]:
    """Tracking errors (max and RMS, um and % of range) for each feedforward, in three
    settings: ``static`` (no dynamics), ``mode`` (with the second-order mode), ``mode+PID``
    (default PID: integral action ``ki = 20 V/(um s)``, crossover about 25 Hz).

    Besides ``models``, the rows ``"none (gain)"`` (the :func:`chord_gain`) and
    ``"exact inverse"`` (of :data:`STAGE` itself) are always included.

    Parameters
    ----------
    models : dict of str to PIOperator
        Feedforward models by name (e.g. :func:`identified_models`).
    fs : float, optional
        Sample rate [Hz]. Default 10 kHz.
    fn_hz : float, optional
        Natural frequency of the second-order mode [Hz]. Default 1 kHz.
    damping : float, optional
        Damping ratio of the mode. Default 0.05.
    pid : PID, optional
        Feedback gains of ``mode+PID``; default ``PID(0.0, 20.0)``.

    Returns
    -------
    dict
        ``table[feedforward][setting]`` is :meth:`pimodel.loops.compiled.LoopResult.tracking`'s dict
        (``max``, ``rms`` [um], ``max_percent``, ``rms_percent``).

    Examples
    --------
    >>> table = compensation_table({}, fs=1000.0)
    >>> list(table), list(table["exact inverse"])
    (['none (gain)', 'exact inverse'], ['static', 'mode', 'mode+PID'])
    >>> bool(table["exact inverse"]["static"]["max"] < 1e-9)
    True
    """
    pid = PID(0.0, 20.0) if pid is None else pid
    dt = 1.0 / fs
    t, yd = reference(fs)
    G = stage_dynamics(dt, fn_hz=fn_hz, damping=damping)
    ffs: dict[str, object] = {"none (gain)": "none", "exact inverse": STAGE, **models}
    table: dict[str, dict[str, dict[str, float]]] = {}
    gain = chord_gain()
    for name, ff in ffs.items():
        row = {
            "static": run_loop(yd, STAGE, dt, feedforward=ff, ff_gain=gain).tracking(),
            "mode": run_loop(yd, STAGE, dt, dynamics=G, feedforward=ff, ff_gain=gain).tracking(),
            "mode+PID": run_loop(yd, STAGE, dt, dynamics=G, feedforward=ff, ff_gain=gain,
                                 pid=pid).tracking(),
        }
        table[name] = row
    return table
