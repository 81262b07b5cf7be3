"""Describing function and linearised views of a PI operator, in python-control's terms.

A play of radius ``r`` is a friction-dominated backlash of width ``2 r``
(``control.friction_backlash_nonlinearity(2 r)``). In the periodic steady state of the input
``v(t) = v0 + A sin(w t)`` its first harmonic is ``N_r(A) A sin(w t + arg N_r(A))`` with
(Gelb & Vander Velde, backlash no. 48; ``x = 1 - 2 r / A``)::

    N_r(A) = (1 + f(x)) / 2 - j (4 r / A - 4 r^2 / A^2) / pi      for A > r
    N_r(A) = 0                                                   for A <= r
    f(x)   = 2 / pi (asin x + x sqrt(1 - x^2))

independent of ``w`` and of the bias ``v0`` (the play is rate independent and shift
invariant). The PI operator ``y = sum_i p_i Gamma_{r_i}[v]`` is a sum of plays, so its
describing function is exactly ``N(A) = sum_i p_i N_{r_i}(A)``, signed weights (the exact
inverse) included. For sampled inputs the same holds when a sample falls on each peak of the
sine (the discrete play equals the continuous one at the samples).

Linearised views (paper Lemma 1): along any input the output's increments are
``y[k] - y[k-1] = kappa[k] (v[k] - v[k-1])`` with ``kappa[k]`` in the **sector**
``[min slope, max slope]`` of the loop-branch slopes (``0`` included when ``r_1 > 0``); for
signed weights the slopes are the partial sums ``p_1 + ... + p_i``. (Exact when the play states
satisfy ``|z_i - z_j| <= |r_i - r_j|``, which holds for a scalar initial state and is kept by
the dynamics.) The **static gain** at amplitude ``A`` is the ratio of the output and input
half ranges of the symmetric loop, ``phi(A) / A`` with the initial loading curve
``phi(A) = sum_i p_i max(A - r_i, 0)``. :func:`circle_criterion` applies the sector to the
differenced loop, :func:`harmonic_balance` solves ``1 + N(A) L(jw) = 0``.

Units: ``A`` in input units (those of the radii), ``N`` and gains in output per input unit,
frequencies in rad/s.
"""

from __future__ import annotations

import math
from typing import Protocol

import control
import numpy as np

__all__ = [
    "PIDescribingFunction",
    "play_describing_function",
    "sector",
    "static_gain",
]


class PILike(Protocol):
    """What this module reads of a :class:`~pimodel.operators.pi.PIOperator` (annotation only)."""

    weights: np.ndarray
    radii: np.ndarray


def _amplitudes(A, name: str = "A") -> np.ndarray:
    a = np.asarray(A, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"{name}: expected finite amplitudes >= 0, got {A!r}")
    return a


def play_describing_function(radius: float, A) -> np.ndarray | complex:
    """Exact describing function of one play (a backlash of width ``2 radius``).

    Parameters
    ----------
    radius : float
        Play radius ``r >= 0`` (input units).
    A : float or array_like
        Amplitudes ``A >= 0`` of the sinusoidal input.

    Returns
    -------
    complex or ndarray of complex
        ``N_r(A)``: 0 for ``A <= r``, 1 for ``r = 0``; phase in (-90, 0] degrees.

    Raises
    ------
    ValueError
        If ``radius`` or an amplitude is negative or not finite.

    Examples
    --------
    >>> import control, numpy as np
    >>> complex(np.round(play_describing_function(0.5, 2.0), 4))
    (0.8045-0.2387j)
    >>> complex(np.round(control.friction_backlash_nonlinearity(1.0).describing_function(2.0), 4))
    (0.8045-0.2387j)
    """
    r = float(radius)
    if not math.isfinite(r) or r < 0:
        raise ValueError(f"radius: expected a finite number >= 0, got {radius!r}")
    a = _amplitudes(A)
    out = np.zeros(a.shape, dtype=complex)
    on = a > r
    if r == 0.0:
        out[on] = 1.0
    else:
        q = 2.0 * r / a[on]  # backlash width over amplitude, in (0, 2)
        x = 1.0 - q
        f = (np.arcsin(x) + x * np.sqrt(1.0 - x * x)) * 2.0 / np.pi
        out[on] = (1.0 + f) / 2.0 - 1j * (2.0 * q - q * q) / np.pi
    return complex(out) if out.ndim == 0 else out


def sector(op: PILike) -> tuple[float, float]:
    """Sector of incremental gains of a PI operator (paper Lemma 1).

    Parameters
    ----------
    op : PIOperator
        Any PI operator, signed weights included.

    Returns
    -------
    (float, float)
        ``(k_min, k_max)``: the smallest and largest loop-branch slope, ``0`` included when
        ``r_1 > 0``. Every increment obeys ``k_min <= (y[k] - y[k-1]) / (v[k] - v[k-1]) <=
        k_max`` (output per input unit).

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> sector(PIOperator([1.0, 0.5], [0.0, 0.2]))
    (1.0, 1.5)
    >>> sector(PIOperator([1.0, 0.5], [0.1, 0.2]))
    (0.0, 1.5)
    """
    s = _operator(op).slopes()
    return float(s.min()), float(s.max())


def static_gain(op: PILike, A) -> np.ndarray | float:
    """Static (chord) gain ``phi(A) / A`` of the symmetric loop of amplitude ``A``.

    In the periodic steady state of an input oscillating between ``v0 - A`` and ``v0 + A``
    the output oscillates with half range ``phi(A) = sum_i p_i max(A - r_i, 0)``; the ratio is
    the gain a linear model fitted to that loop's end points would use. It lies in
    :func:`sector` and tends to ``sum p_i`` for large ``A``.

    Parameters
    ----------
    op : PIOperator
        The operator.
    A : float or array_like
        Amplitudes ``A > 0`` (input units).

    Returns
    -------
    float or ndarray
        The gain (output per input unit).

    Raises
    ------
    ValueError
        If an amplitude is not finite and > 0.

    Examples
    --------
    >>> from pimodel import PIOperator
    >>> float(static_gain(PIOperator([1.0, 0.5], [0.0, 0.2]), 1.0))
    1.4
    """
    op = _operator(op)
    a = _amplitudes(A)
    if np.any(a <= 0):
        raise ValueError(f"A: expected amplitudes > 0, got {A!r}")
    phi = np.maximum(a[..., None] - op.radii, 0.0) @ op.weights
    g = phi / a
    return float(g) if g.ndim == 0 else g


def _pi_class(op) -> type:
    """The :class:`~pimodel.operators.pi.PIOperator` class in ``op``'s MRO (this module is
    imported by ``pi.py``, so it does not import ``PIOperator`` itself)."""
    for cls in type(op).__mro__:
        if cls.__name__ == "PIOperator" and cls.__module__ == "pimodel.operators.pi":
            return cls
    raise TypeError(f"op: expected a PIOperator, got {type(op).__name__}")


def _operator(op) -> PILike:
    _pi_class(op)
    return op


class PIDescribingFunction(control.DescribingFunctionNonlinearity):
    """A PI operator as a python-control describing-function nonlinearity.

    Usually made by :meth:`PIOperator.describing_function`. ``describing_function(A)`` is the
    exact ``sum_i p_i N_{r_i}(A)`` (module docstring); calling the object with a scalar input
    ``v[k]`` streams the operator (``y[k]`` of ``v[0..k]``, starting from the operator's
    initial state), like ``control.friction_backlash_nonlinearity``, so python-control's
    numerical ``describing_function(F, A, try_method=False)`` also works.

    Parameters
    ----------
    op : PIOperator
        The operator (copied; later changes to ``op``'s streaming state do not matter).

    Examples
    --------
    >>> import control, numpy as np
    >>> from pimodel import PIOperator
    >>> F = PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function()
    >>> complex(np.round(control.describing_function(F, 1.0), 4))
    (1.4288-0.1019j)
    """

    def __init__(self, op: PILike):
        super().__init__()
        op = _operator(op)
        self.operator = _pi_class(op)(op.weights, op.radii, initial_state=op.initial_state,
                                   signed_weights=op.signed_weights)

    def __call__(self, x) -> float:
        """One streaming step: ``y[k]`` for the input sample ``x = v[k]``."""
        return self.operator.step(float(np.squeeze(x)))

    def reset(self) -> None:
        """Return the streaming state to the operator's initial state.

        Returns
        -------
        None

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> F = PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function()
        >>> F(1.0), F.reset(), F(1.0)
        (1.4, None, 1.4)
        """
        self.operator.reset()

    def _isstatic(self) -> bool:
        return False

    def describing_function(self, A):
        """Exact describing function ``N(A) = sum_i p_i N_{r_i}(A)``.

        Parameters
        ----------
        A : float or array_like
            Amplitudes ``A >= 0`` (input units).

        Returns
        -------
        complex or ndarray of complex
            ``N(A)`` (output per input unit); ``N(0)`` is the smallest-radius slope when
            ``r_1 = 0``, else 0.

        Raises
        ------
        ValueError
            If an amplitude is negative or not finite.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> F = PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function()
        >>> F.describing_function([0.1, 1.0]).round(4)
        array([1.    +0.j    , 1.4288-0.1019j])
        """
        a = _amplitudes(A)
        op = self.operator
        n = sum(p * play_describing_function(r, a) for p, r in zip(op.weights, op.radii,
                                                                       strict=True))
        n = np.asarray(n, dtype=complex)
        return complex(n) if n.ndim == 0 else n

    def sector(self) -> tuple[float, float]:
        """Incremental-gain sector, see :func:`sector`.

        Returns
        -------
        (float, float)
            ``(k_min, k_max)``, the smallest and largest loop-branch slope.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function().sector()
        (1.0, 1.5)
        """
        return sector(self.operator)

    def static_gain(self, A):
        """Static (chord) gain at amplitude ``A``, see :func:`static_gain`.

        Parameters
        ----------
        A : float or array_like
            Amplitudes ``A > 0`` (input units).

        Returns
        -------
        float or ndarray
            ``phi(A) / A`` (output per input unit).

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> float(PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function().static_gain(1.0))
        1.4
        """
        return static_gain(self.operator, A)

    def __repr__(self) -> str:
        return f"PIDescribingFunction({self.operator!r})"
