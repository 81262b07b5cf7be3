"""Figures of an identification: measured and model loop, residual, slope fit."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plotting import new_figure, save_figure
from .chain import Identification

__all__ = [
    "plot_identification",
]


def plot_identification(idn: Identification, t, v, y, out_dir, *, units=("V", "um")) -> list[Path]:
    """Figures of an identification: loop (measured vs model), residual, branch fit.

    Writes ``identify_<method>.png`` (loop and residual over time) and, when the
    identification has a slope fit, ``identify_slopes.png`` (the branch shape and its
    breakpoints).

    Parameters
    ----------
    idn : Identification
        The result of :func:`pimodel.identification.identify`.
    t : array_like of float, shape (N,)
        Sample times [s].
    v : array_like of float, shape (N,)
        Input samples.
    y : array_like of float, shape (N,)
        Measured output samples.
    out_dir : str or pathlib.Path
        Folder for the PNG files (created if missing).
    units : tuple of str, optional
        Input and output units for the axis labels.

    Returns
    -------
    list of pathlib.Path
        The PNG files written.

    Examples
    --------
    >>> import tempfile
    >>> from pimodel import PIOperator, identify
    >>> from pimodel.identification.plots import plot_identification
    >>> from pimodel.signals import triangle
    >>> t, v = triangle(1.0, 1.0, fs=1000.0, duration=3.0)
    >>> y = PIOperator([1.0, 0.5], [0.0, 0.3]).simulate(v)
    >>> idn = identify(v, y, dt=1e-3)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     [p.name for p in plot_identification(idn, t, v, y, tmp)]
    ['identify_adaptive.png', 'identify_slopes.png']
    """
    uv, uy = units
    yhat = idn.predict(v)
    fig, ax = new_figure(2, 1)
    ax[0, 0].plot(v, y, ".", ms=1.5, alpha=0.4, label="measured")
    ax[0, 0].plot(v, yhat, lw=1.0, label=f"{idn.method} model, n = {idn.operator.n}")
    ax[0, 0].set(xlabel=f"input v [{uv}]", ylabel=f"output y [{uy}]", title="Hysteresis loop")
    ax[0, 0].legend()
    ax[0, 0].grid(alpha=0.3)
    ax[0, 1].plot(t, yhat - y, lw=0.8, label="model - measured")
    ax[0, 1].set(xlabel="time t [s]", ylabel=f"residual [{uy}]",
                 title=f"Residual: RMS {idn.rms_error:.3g} {uy}, max {idn.max_error:.3g} {uy}")
    ax[0, 1].legend()
    ax[0, 1].grid(alpha=0.3)
    paths = [save_figure(fig, Path(out_dir) / f"identify_{idn.method}.png")]
    if idn.slopes is not None:
        s = idn.slopes
        fig, ax = new_figure()
        x = np.linspace(0, max(float(np.ptp(v)), 1e-12), 400)
        knots = np.concatenate(([0.0], s.breakpoints))
        curve = np.zeros_like(x)
        for i, slope in enumerate(s.slopes):
            lo = knots[i]
            hi = knots[i + 1] if i + 1 < knots.size else np.inf
            curve += slope * np.clip(x - lo, 0, hi - lo)
        ax[0, 0].plot(x, curve, label=f"segmented fit, {s.slopes.size} segments (BIC)")
        for b in s.breakpoints:
            ax[0, 0].axvline(b, color="0.7", lw=0.8)
        ax[0, 0].set(xlabel=f"input travel from the reversal |v - v_rev| [{uv}]",
                     ylabel=f"output change [{uy}]",
                     title="Branch shape: slopes give the weights, breakpoints 2 r_j")
        ax[0, 0].legend()
        ax[0, 0].grid(alpha=0.3)
        paths.append(save_figure(fig, Path(out_dir) / "identify_slopes.png"))
    return paths
