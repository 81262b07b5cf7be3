"""Plain NumPy specification of the joint estimator's per-branch statistics.

Implements exactly the rules of ``fmu/src/core/pim_joint.h`` (``pimodel._native.joint_select``
and ``joint_add``, used by :class:`pimodel.identification.adaptive.joint.JointEstimator`); a
test holds the two equal to 1e-12 (``tests/test_native_equals_reference.py``). A finished branch
has inputs ``v[0..N-1]`` from its reversal extreme ``v[0]`` (input unit), outputs ``y`` (output
unit) and direction ``s`` (+1 rising, -1 falling); sample k has travel ``x = |v[k] - v[0]|``
and signed output ``Y = s y[k]``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "branch_shape_reference",
    "joint_add_reference",
    "joint_select_reference",
]


def branch_shape_reference(x: np.ndarray, weights: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """``g(x) = sum_j p_j max(0, x - 2 r_j)``, the specification of
    :func:`pimodel.identification.adaptive.joint.branch_shape` (whose hinge matrix the C core
    builds: ``pim_joint_hinges``).

    Parameters
    ----------
    x : numpy.ndarray of float, shape (N,)
        Travel of each sample since the branch's reversal (input unit).
    weights, radii : numpy.ndarray of float, shape (n,)
        The estimate in force: ``p_j`` and ``r_j`` (input unit).

    Returns
    -------
    numpy.ndarray of float, shape (N,)
        The shape at each travel (output unit).

    Examples
    --------
    >>> branch_shape_reference(np.array([0.0, 0.5, 1.0]), np.array([1.0, 0.5]),
    ...                        np.array([0.0, 0.4]))
    array([0. , 0.5, 1.1])
    """
    return np.maximum(0.0, x[:, None] - 2.0 * radii[None, :]) @ weights


def joint_select_reference(v: np.ndarray, y: np.ndarray, s: float, keep_limit: float,
                           travel_range: float) -> tuple[np.ndarray, np.ndarray, int]:
    """The samples of a finished branch that the joint estimator's fit uses.

    Parameters
    ----------
    v : numpy.ndarray of float, shape (N,)
        The branch's inputs, ``v[0]`` its reversal extreme (input unit).
    y : numpy.ndarray of float, shape (N,)
        Their outputs (output unit).
    s : float
        +1 on a rising branch, -1 on a falling one.
    keep_limit : float
        Largest travel used (the previous branch's travel, with its margin; input unit).
    travel_range : float
        The bins' travel range (input unit).

    Returns
    -------
    x : numpy.ndarray of float, shape (m,)
        Travels ``|v[k] - v[0]|`` of the samples with ``x <= keep_limit`` and
        ``x <= travel_range``, in order (input unit).
    Y : numpy.ndarray of float, shape (m,)
        Their signed outputs ``s y[k]`` (output unit).
    outside : int
        Samples with ``x <= keep_limit`` beyond ``travel_range``.

    Examples
    --------
    >>> joint_select_reference(np.array([1.0, 1.5, 2.5, 3.0]), np.array([0.0, 1.0, 2.0, 3.0]),
    ...                        1.0, 1.6, 1.2)
    (array([0. , 0.5]), array([0., 1.]), 1)
    """
    xs = np.abs(v - v[0])
    keep = xs <= keep_limit
    inside = keep & (xs <= travel_range)
    return xs[inside], s * y[inside], int(np.count_nonzero(keep & ~inside))


def joint_add_reference(x: np.ndarray, Y: np.ndarray, e: np.ndarray, c: float,
                        stats: np.ndarray, travel_range: float, forgetting: float) -> float:
    """Selected branch samples centred and added to the binned statistics.

    ``e = Y - g(x)`` are the samples' errors about the estimate in force (``g`` its branch
    shape, :func:`pimodel.identification.adaptive.joint.branch_shape`) and ``c = mean(e)``;
    the statistics are multiplied by ``forgetting``, then bin
    ``b = min(floor(x bins / travel_range), bins - 1)`` gains count 1, ``x`` and ``Y - c``.

    Parameters
    ----------
    x : numpy.ndarray of float, shape (m,)
        Travels (input unit), ``m >= 1``.
    Y : numpy.ndarray of float, shape (m,)
        Signed outputs (output unit).
    e : numpy.ndarray of float, shape (m,)
        Their errors about the estimate in force (output unit).
    c : float
        The branch's offset, ``mean(e)`` (output unit).
    stats : numpy.ndarray of float, shape (3, bins)
        Count, sum of x and sum of centred Y per bin; updated in place.
    travel_range : float
        The bins' travel range (input unit).
    forgetting : float
        Factor on the older statistics, in (0, 1].

    Returns
    -------
    float
        ``sum (e - c)^2`` (output unit squared).

    Examples
    --------
    >>> stats = np.zeros((3, 4))
    >>> joint_add_reference(np.array([0.5, 1.5]), np.array([1.0, 2.0]), np.array([0.5, 1.5]),
    ...                     1.0, stats, 2.0, 1.0)
    0.5
    >>> stats[0]
    array([0., 1., 0., 1.])
    """
    d = e - c
    bins = stats.shape[1]
    idx = np.minimum((x * (bins / travel_range)).astype(np.int64), bins - 1)
    stats *= forgetting
    for row, w in enumerate((None, x, Y - c)):
        stats[row] += np.bincount(idx, weights=w, minlength=bins)
    return float(d @ d)
