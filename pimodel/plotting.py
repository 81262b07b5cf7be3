"""Matplotlib helpers shared by plots: headless backend, consistent figure saving."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless: figures are written to files, never shown

import matplotlib.pyplot as plt  # noqa: E402

__all__ = [
    "new_figure",
    "readability_problems",
    "save_figure",
]


def new_figure(ncols: int = 1, nrows: int = 1, size=(6.4, 4.2)):
    """A figure with ``nrows x ncols`` axes, sized per axis.

    Parameters
    ----------
    ncols : int, optional
        Number of columns of axes.
    nrows : int, optional
        Number of rows of axes.
    size : tuple of float, optional
        Width and height of one axes [inch].

    Returns
    -------
    fig : matplotlib.figure.Figure
        The figure.
    axes : numpy.ndarray of matplotlib.axes.Axes, shape (nrows, ncols)
        The axes, always two-dimensional.

    Examples
    --------
    >>> from pimodel.plotting import new_figure
    >>> fig, axes = new_figure(2, 1)
    >>> axes.shape, fig.get_size_inches().round(1).tolist()
    ((1, 2), [12.8, 4.2])
    """
    fig, axes = plt.subplots(nrows, ncols, figsize=(size[0] * ncols, size[1] * nrows),
                             squeeze=False)
    return fig, axes


def readability_problems(fig) -> list[str]:
    """What keeps ``fig`` from being readable.

    Axes with data but no x or y label, or with several labelled curves and no legend.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to check.

    Returns
    -------
    list of str
        One message per problem; empty when the figure is readable.

    Examples
    --------
    >>> from pimodel.plotting import new_figure, readability_problems
    >>> fig, ax = new_figure()
    >>> _ = ax[0, 0].plot([0, 1], [0, 1])
    >>> readability_problems(fig)
    ['axes 0 (untitled): no x label', 'axes 0 (untitled): no y label']
    """
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
    """Save ``fig`` as PNG (150 dpi, tight layout) and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or pathlib.Path
        Where to write it; missing parent folders are created.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ValueError
        If the figure has unlabelled axes or a missing legend
        (:func:`readability_problems`); the figure is closed and nothing is written.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from pimodel.plotting import new_figure, save_figure
    >>> fig, ax = new_figure()
    >>> _ = ax[0, 0].plot([0, 1], [0, 1])
    >>> _ = ax[0, 0].set(xlabel="time t [s]", ylabel="y [um]")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     save_figure(fig, Path(tmp) / "line.png").name
    'line.png'
    """
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
