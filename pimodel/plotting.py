"""Matplotlib helpers shared by plots: headless backend, consistent figure saving."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless: figures are written to files, never shown

import matplotlib.pyplot as plt  # noqa: E402


def new_figure(ncols: int = 1, nrows: int = 1, size=(6.4, 4.2)):
    """A figure with ``nrows x ncols`` axes, sized per axis."""
    fig, axes = plt.subplots(nrows, ncols, figsize=(size[0] * ncols, size[1] * nrows),
                             squeeze=False)
    return fig, axes


def readability_problems(fig) -> list[str]:
    """What keeps ``fig`` from being readable: axes with data but no x or y label, or with
    several labelled curves and no legend."""
    problems = []
    for i, ax in enumerate(fig.get_axes()):
        if not ax.get_visible() or not (ax.lines or ax.collections or ax.patches or ax.images):
            continue
        name = f"axes {i} ({ax.get_title() or 'untitled'})"
        if not ax.get_xlabel():
            problems.append(f"{name}: no x label")
        if not ax.get_ylabel():
            problems.append(f"{name}: no y label")
        labelled = [a for a in (*ax.lines, *ax.collections, *ax.containers)
                    if not str(a.get_label()).startswith("_")]
        if len(labelled) > 1 and ax.get_legend() is None:
            problems.append(f"{name}: {len(labelled)} labelled series but no legend")
    return problems


def save_figure(fig, path) -> Path:
    """Save ``fig`` as PNG (150 dpi, tight) and close it; returns the path. Refuses (ValueError)
    a figure with unlabelled axes or a missing legend (:func:`readability_problems`)."""
    path = Path(path)
    problems = readability_problems(fig)
    if problems:
        plt.close(fig)
        raise ValueError(f"{path.name}: figure not readable: {'; '.join(problems)}")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path
