"""Figures of a diagnosis (:func:`plot_diagnosis`): residual versus time and input, loops
before and after the augmentation, ranked regions."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plotting import new_figure, save_figure

__all__ = [
    "plot_diagnosis",
]


def plot_diagnosis(rep, out_dir, *, prefix: str = "", units=("V", "um")) -> list[Path]:
    """Save the two figures of a diagnosis as PNG files.

    ``residuals.png``: the validate residual ``y[k] - model[k]`` of the nominal PI model and of
    the augmented model, against time and against the input. ``loops_and_regions.png``: the
    measured and modelled loops of the first validate record, and the regions of the validate
    records ranked by residual concentration (energy share over sample share; 1 is uniform).

    Parameters
    ----------
    rep : DiagnosisReport
        Result of :func:`pimodel.diagnosis.diagnose`; used are ``validate`` (records with
        ``t``, ``v``, ``y``), ``before`` and ``after`` (nominal and augmented model outputs,
        one array per validate record), ``verdict["effects"]`` and ``where["regions"]``.
    out_dir : str or pathlib.Path
        Directory of the figures (created if missing).
    prefix : str
        Prepended to each file name.
    units : tuple of str
        Units of the input and of the output, for the axis labels.

    Returns
    -------
    list of pathlib.Path
        The two saved files.

    Raises
    ------
    ValueError
        If a figure fails the readability check of :func:`pimodel.plotting.save_figure`.

    Examples
    --------
    >>> import tempfile
    >>> from types import SimpleNamespace
    >>> t = np.linspace(0.0, 0.01, 11)
    >>> seg = SimpleNamespace(t=t, v=np.sin(600 * t), y=np.sin(600 * t))
    >>> rep = SimpleNamespace(validate=[seg], before=[0.9 * seg.y], after=[seg.y],
    ...                       verdict={"effects": ["creep"]},
    ...                       where={"regions": [{"region": "late", "concentration": 1.5}]})
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     [p.name for p in plot_diagnosis(rep, tmp, prefix="stage_")]
    ['stage_residuals.png', 'stage_loops_and_regions.png']
    """
    uv, uy = units
    out = Path(out_dir)
    paths = []
    fig, ax = new_figure(2, 1)
    for seg, b, a in zip(rep.validate, rep.before, rep.after, strict=True):
        ax[0, 0].plot(seg.t, seg.y - b, lw=0.7, label="nominal PI")
        ax[0, 0].plot(seg.t, seg.y - a, lw=0.7, label="with " + "+".join(rep.verdict["effects"]))
        ax[0, 1].plot(seg.v, seg.y - b, ".", ms=1, label="nominal PI")
        ax[0, 1].plot(seg.v, seg.y - a, ".", ms=1, label="augmented")
    ax[0, 0].set(xlabel="time t [s]", ylabel=f"residual y - model [{uy}]",
                 title="Validate residual over time")
    ax[0, 1].set(xlabel=f"input v [{uv}]", ylabel=f"residual [{uy}]",
                 title="Validate residual against the input")
    for a in ax[0]:
        a.legend(markerscale=8)
        a.grid(alpha=0.3)
    paths.append(save_figure(fig, out / f"{prefix}residuals.png"))

    fig, ax = new_figure(2, 1)
    seg, b, a = rep.validate[0], rep.before[0], rep.after[0]
    ax[0, 0].plot(seg.v, seg.y, lw=0.8, color="0.3", label="measured")
    ax[0, 0].plot(seg.v, b, "--", lw=0.8, label="nominal PI")
    ax[0, 0].plot(seg.v, a, ":", lw=1.0, label="augmented")
    ax[0, 0].set(xlabel=f"input v [{uv}]", ylabel=f"output y [{uy}]", title="Loops")
    ax[0, 0].legend()
    ax[0, 0].grid(alpha=0.3)
    regions = rep.where["regions"]
    names = [r["region"] for r in regions][::-1]
    conc = [r["concentration"] for r in regions][::-1]
    ax[0, 1].barh(np.arange(len(names)), conc, color="tab:orange", label="energy / sample share")
    ax[0, 1].axvline(1.0, color="0.4", lw=0.8, label="uniform")
    ax[0, 1].set_yticks(np.arange(len(names)), names, fontsize=7)
    ax[0, 1].set(xlabel="residual concentration [-]", ylabel="region of the validate records",
                 title="Where the nominal residual lies")
    ax[0, 1].legend(fontsize=7)
    paths.append(save_figure(fig, out / f"{prefix}loops_and_regions.png"))
    return paths
