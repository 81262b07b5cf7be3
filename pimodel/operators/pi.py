"""Prandtl-Ishlinskii operators: fixed radii (:class:`PIOperator`) and time-dependent radii
(:class:`TimeDependentPI`), backed by the shared C core.

Discrete-time semantics (paper eqs. 1-7, NOTES.md), for play i with radius r_i and state z_i::

    z_i[k] = max(v[k] - r_i, min(v[k] + r_i, z_i[k-1])),   z_i[-1] = initial_state[i]
    y[k]   = sum_i p_i z_i[k]

``y[k]`` depends on ``v[0..k]`` (no delay). The operator is rate independent: time stamps play
no role, only the sequence of input values. Units: ``v`` and the radii share the input unit
(e.g. V), ``y`` is in the output unit (e.g. um), weights in output per input unit.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from .. import _native
from ..checks import as_signal, as_vector, scalar_or_vector
from .base import (
    Streaming,
    check_finite,
    freeze,
    operator_repr,
    read_only,
    size_of,
    streaming_state,
)
from .describing_function import PIDescribingFunction

__all__ = [
    "PIOperator",
    "TimeDependentPI",
]

INVERSE_CONDITION_WARN = 1e6    # max/min branch slope above which inverse() warns
INVERSE_CONDITION_ERROR = 1e12  # ... and above which it raises (rounding dominates)
# The inverse's weights -p_i / (P_i P_(i-1)) need the product of two partial sums P_i = p_1 +
# ... + p_i to be a normal float64: P_i in [sqrt(tiny), sqrt(max)] = [1.49e-154, 1.34e154].
# Outside it the product overflows (weights -0.0) or loses digits (subnormal), silently.
INVERSE_WEIGHT_MIN = float(np.sqrt(np.finfo(float).tiny))
INVERSE_WEIGHT_MAX = float(np.sqrt(np.finfo(float).max))


def _check_parameters(weights, radii, *, signed_weights: bool) -> tuple[np.ndarray, np.ndarray]:
    p = as_vector(weights, "weights")
    r = as_vector(radii, "radii")
    if p.shape != r.shape:
        raise ValueError(
            f"weights and radii: expected the same length, got {p.size} weights and "
            f"{r.size} radii"
        )
    if np.any(r < 0):
        i = int(np.flatnonzero(r < 0)[0])
        raise ValueError(f"radii: radius {i + 1} (counted from 1) is {float(r[i])!r}; "
                         "radii must be >= 0")
    if signed_weights:
        P = np.cumsum(p)
        if np.any(P <= 0):
            i = int(np.flatnonzero(P <= 0)[0])
            raise ValueError(
                f"weights: partial sum p_1+...+p_{i + 1} = {float(P[i])!r}; a signed-weight PI "
                "operator needs every partial sum > 0"
            )
    elif np.any(p <= 0):
        i = int(np.flatnonzero(p <= 0)[0])
        raise ValueError(f"weights: weight {i + 1} (counted from 1) is {float(p[i])!r}; "
                         "weights must be > 0")
    return p, r


def _initial_state(value, n: int) -> np.ndarray:
    return scalar_or_vector(value, "initial_state", n, one_per="play")


class PIOperator(Streaming):
    """Weighted sum of play operators, ``y[k] = sum_i p_i Gamma_{r_i}[v][k]``.

    Parameters
    ----------
    weights : array_like of float, shape (n,)
        Weights ``p_i`` (output per input unit), n >= 1.
    radii : array_like of float, shape (n,)
        Radii ``r_i`` (input units), each >= 0. They are **sorted ascending together with their
        weights** (and with a per-play initial state) when given unsorted, so ``op.radii`` is
        always non-decreasing.
    initial_state : float or array_like of float, optional
        The plays' state before the first sample, ``z_i[-1]``: a scalar (the paper's initial
        condition x, same for all plays) or one value per play. Default 0.
    signed_weights : bool, optional
        Allow negative weights as long as every partial sum ``p_1 + ... + p_i`` is positive
        (the class of operators the exact inverse produces). Default False: all ``p_i > 0``.

    Raises
    ------
    ValueError
        If the lengths differ, a radius is negative, a weight (or, with ``signed_weights``, a
        partial sum) is not positive, or ``initial_state`` has the wrong length.

    Notes
    -----
    :meth:`simulate` is pure (starts from ``initial_state`` each call); :meth:`step` streams,
    reading and updating :attr:`state`.

    Examples
    --------
    >>> op = PIOperator([1.0, 0.5], [0.0, 0.3])
    >>> op.simulate([0.0, 0.5, 1.0, 0.6])
    array([0.  , 0.6 , 1.35, 0.95])
    """

    def __init__(self, weights, radii, *, initial_state=0.0, signed_weights: bool = False):
        p, r = _check_parameters(weights, radii, signed_weights=signed_weights)
        z0 = _initial_state(initial_state, p.size)
        order = np.argsort(r, kind="stable")
        self._p = np.ascontiguousarray(p[order])
        self._r = np.ascontiguousarray(r[order])
        self._z0 = np.ascontiguousarray(z0[order])
        self._restart()
        self.signed_weights = bool(signed_weights)
        freeze(self._p, self._r, self._z0)

    # -- parameters ---------------------------------------------------------------------
    weights = read_only("_p", "Weights ``p_i`` (read-only view), ordered by radius.")
    radii = read_only("_r", "Radii ``r_i`` (read-only view), non-decreasing.")
    n = size_of("_p", "Number of plays.")
    initial_state = read_only("_z0", "Play states before the first sample, ``z_i[-1]``.")

    def __repr__(self) -> str:
        return operator_repr("PIOperator", weights=self._p, radii=self._r, numpy_arrays=True)

    # -- whole-array simulation ---------------------------------------------------------
    def simulate(self, v, *, state=None, return_state: bool = False):
        """Output ``y[k]`` for the input samples ``v[k]``, k = 0..N-1.

        Starts from ``state`` (default :attr:`initial_state`) and leaves the streaming state
        untouched.

        Parameters
        ----------
        v : array_like of float, shape (N,)
            Input samples ``v[0..N-1]`` (input units), finite.
        state : float or array_like of float, optional
            Play states before ``v[0]``, ``z_i[-1]``; default :attr:`initial_state`.
        return_state : bool, optional
            Also return the play states after the last sample.

        Returns
        -------
        y : numpy.ndarray of float, shape (N,)
            Output ``y[k]`` (output units); ``y[k]`` depends on ``v[0..k]``.
        z_final : numpy.ndarray of float, shape (n,)
            Play states ``z_i[N-1]``; only with ``return_state=True``.

        Raises
        ------
        ValueError
            If ``v`` is not a finite 1-D signal, ``state`` has the wrong length, or the output
            overflows.

        Examples
        --------
        >>> op = PIOperator([1.0, 0.5], [0.0, 0.3])
        >>> y, z = op.simulate([0.0, 1.0, 0.6], return_state=True)
        >>> y, z
        (array([0.  , 1.35, 0.95]), array([0.6, 0.7]))
        """
        x = as_signal(v, "v")
        z = self._start_state(state)
        y, _ = _native.pi_run(self._p, self._r, z, x)
        check_finite(y, x, "v", state=z)
        return (y, z) if return_state else y

    def play_outputs(self, v, *, state=None) -> np.ndarray:
        """Play outputs ``z[k, i] = Gamma_{r_i}[v][k]``, shape (N, n).

        Parameters
        ----------
        v : array_like of float, shape (N,)
            Input samples (input units).
        state : float or array_like of float, optional
            Play states before ``v[0]``; default :attr:`initial_state`.

        Returns
        -------
        numpy.ndarray of float, shape (N, n)
            Row k holds the play states ``z_i[k]`` after sample k (input units).

        Raises
        ------
        ValueError
            If ``v`` is not a finite 1-D signal or ``state`` has the wrong length.

        Examples
        --------
        >>> PIOperator([1.0, 0.5], [0.0, 0.3]).play_outputs([0.0, 1.0, 0.6])
        array([[0. , 0. ],
               [1. , 0.7],
               [0.6, 0.7]])
        """
        x = as_signal(v, "v")
        z = self._start_state(state)
        _, zhist = _native.pi_run(self._p, self._r, z, x, with_plays=True)
        return zhist

    # -- streaming ----------------------------------------------------------------------
    state = streaming_state(
        "Current play states ``z_i[k]`` (a copy); settable with a scalar or n values.")

    def _check_state(self, value) -> np.ndarray:
        return _initial_state(value, self.n)

    def reset(self) -> None:
        """Return the streaming state to :attr:`initial_state`.

        Examples
        --------
        >>> op = PIOperator([1.0], [0.2])
        >>> _ = op.step(1.0)
        >>> op.reset()
        >>> op.state
        array([0.])
        """
        self._restart()

    def step(self, v: float) -> float:
        """Advance one sample: update the state with input ``v[k]`` and return ``y[k]``.

        Parameters
        ----------
        v : float
            Input sample ``v[k]`` (input units), finite.

        Returns
        -------
        float
            Output ``y[k]`` (output units), computed from the updated states ``z_i[k]``.

        Raises
        ------
        ValueError
            If ``v`` is not finite or the output overflows; the state is then unchanged.

        Examples
        --------
        >>> op = PIOperator([1.0, 0.5], [0.0, 0.3])
        >>> op.step(0.5), op.step(1.0), op.state
        (0.6, 1.35, array([1. , 0.7]))
        """
        vk = float(v)
        if not np.isfinite(vk):
            raise ValueError(f"v: input sample is {v!r}; expected a finite number")
        z = self._z.copy()   # the state moves only when the step succeeds (base.py's rule)
        y = _native.pi_step(self._p, self._r, z, vk)
        if not math.isfinite(y):   # a non-finite play state makes y non-finite too
            check_finite(np.array([y]), np.array([vk]), "v", state=z)
        self._z = z
        return y

    def output(self, state=None) -> float:
        """Output ``sum_i p_i z_i`` for a state (default: the current streaming state).

        Parameters
        ----------
        state : float or array_like of float, optional
            Play states ``z_i``; default the current streaming :attr:`state`.

        Returns
        -------
        float
            ``sum_i p_i z_i`` (output units).

        Raises
        ------
        ValueError
            If ``state`` has the wrong length.

        Examples
        --------
        >>> PIOperator([1.0, 0.5], [0.0, 0.3]).output([1.0, 0.7])
        1.35
        """
        z = self._z if state is None else self._check_state(state)
        return float(self._p @ z)

    # -- analysis -----------------------------------------------------------------------
    def slopes(self) -> np.ndarray:
        """Slopes of the loop branches (Lemma 1, Remark 1), ascending.

        With ``r_1 > 0``: the n + 1 values ``0, P_1, ..., P_n``; with ``r_1 = 0`` the n values
        ``P_1, ..., P_n``, where ``P_i = p_1 + ... + p_i``. Equal radii merge their slopes.

        Returns
        -------
        numpy.ndarray of float
            The branch slopes (output per input unit), ascending.

        Examples
        --------
        >>> PIOperator([1.0, 0.5], [0.0, 0.3]).slopes()
        array([1. , 1.5])
        >>> PIOperator([1.0, 0.5], [0.1, 0.3]).slopes()
        array([0. , 1. , 1.5])
        """
        P = np.cumsum(self._p)
        keep = np.append(self._r[1:] > self._r[:-1], True)  # last play of each radius group
        s = P[keep]
        return s if self._r[0] == 0 else np.concatenate(([0.0], s))

    def loop_width(self) -> float:
        """Lemma 2's loop width ``rho = 2 sum p_i r_i / sum p_i`` (input units).

        Returns
        -------
        float
            The loop width ``rho`` (input units).

        Examples
        --------
        >>> round(PIOperator([1.0, 0.5], [0.0, 0.3]).loop_width(), 12)
        0.2
        """
        return float(2.0 * (self._p @ self._r) / self._p.sum())

    @property
    def is_invertible(self) -> bool:
        """True when the exact inverse exists: ``r_1 = 0`` and every partial sum positive."""
        return bool(self._r[0] == 0.0 and np.all(np.cumsum(self._p) > 0))

    def inverse(self) -> PIOperator:
        """Exact analytic inverse (Krejci & Kuhnen, NOTES.md), again a PI operator.

        Requires ``r_1 = 0`` (a linear play) with ``p_1 > 0``; raises ValueError otherwise.
        The inverse's initial state is made consistent with this operator's initial state, so
        ``op.inverse().simulate(op.simulate(v))`` returns ``v``; its weights are signed.

        Returns
        -------
        PIOperator
            The inverse operator (signed weights, output units in, input units out).

        Raises
        ------
        ValueError
            If ``r_1 > 0``, a partial sum of weights is not positive or lies outside
            ``[INVERSE_WEIGHT_MIN, INVERSE_WEIGHT_MAX]`` (about 1.5e-154 to 1.3e154, where
            the products ``P_i P_(i-1)`` stay normal float64 numbers), the branch slopes range
            over more than ``INVERSE_CONDITION_ERROR`` (a RuntimeWarning above
            ``INVERSE_CONDITION_WARN``), or the inverse's parameters overflow float64.

        Examples
        --------
        >>> op = PIOperator([1.0, 0.5], [0.0, 0.3])
        >>> inv = op.inverse()
        >>> inv.weights.round(6), inv.radii
        (array([ 1.      , -0.333333]), array([0. , 0.3]))
        >>> v = np.array([0.0, 0.5, 1.0, 0.6])
        >>> np.allclose(inv.simulate(op.simulate(v)), v)
        True
        """
        if self._r[0] != 0.0:
            raise ValueError(
                "PIOperator.inverse: not invertible, the smallest radius is "
                f"{float(self._r[0])!r}; the exact inverse needs a linear play (r_1 = 0) with a "
                "positive weight"
            )
        res = _native.pi_inverse(self._p, self._r, self._z0)
        if res is None:
            raise ValueError(
                "PIOperator.inverse: not invertible, a partial sum of weights is not positive"
            )
        P = np.cumsum(self._p)
        if P.max() > INVERSE_WEIGHT_MAX or P.min() < INVERSE_WEIGHT_MIN:
            raise ValueError(
                "PIOperator.inverse: not representable in float64, the partial sums P_i = "
                f"p_1 + ... + p_i run from {float(P.min()):.3g} to {float(P.max()):.3g}; the "
                "inverse's weights -p_i / (P_i P_(i-1)) are representable only for P_i within "
                f"[{INVERSE_WEIGHT_MIN:.3g}, {INVERSE_WEIGHT_MAX:.3g}] (float64): rescale the "
                "output units")
        cond = float(P.max() / P.min())
        if cond > INVERSE_CONDITION_ERROR:
            raise ValueError(
                f"PIOperator.inverse: ill-conditioned, weights: the branch slopes range over "
                f"max P_i / min P_i = {cond:.3g} (P_i = p_1 + ... + p_i; p_1 = "
                f"{float(self._p[0]):.3g}); above {INVERSE_CONDITION_ERROR:.0e} rounding alone "
                "spoils the inverse. Expected p_1 no smaller than 1e-12 of the total weight"
            )
        if cond > INVERSE_CONDITION_WARN:
            warnings.warn(
                f"PIOperator.inverse: ill-conditioned, max P_i / min P_i = {cond:.3g} (p_1 = "
                f"{float(self._p[0]):.3g}): the inverse amplifies output errors up to "
                f"{cond:.3g} times (well-conditioned below {INVERSE_CONDITION_WARN:.0e})",
                RuntimeWarning, stacklevel=2)
        pinv, rinv, zinv = res
        if not (np.all(np.isfinite(pinv)) and np.all(np.isfinite(rinv))
                and np.all(np.isfinite(zinv))):
            raise ValueError(
                "PIOperator.inverse: not representable in float64, the inverse's weights "
                f"(1/p_1 = 1/{float(self._p[0]):.3g}, -p_i / (P_i P_(i-1))) or radii overflow; "
                "expected weights well inside the float64 range: rescale the output units"
            )
        return PIOperator(pinv, rinv, initial_state=zinv, signed_weights=True)

    def describing_function(self) -> PIDescribingFunction:
        """This operator as a python-control describing-function nonlinearity.

        Returns
        -------
        pimodel.operators.describing_function.PIDescribingFunction
            A ``control.DescribingFunctionNonlinearity``: ``F.describing_function(A)`` is the
            exact ``sum_i p_i N_{r_i}(A)`` (a play of radius r is a backlash of width 2 r),
            usable with ``control.describing_function_response`` and
            ``control.describing_function_plot``; see :mod:`pimodel.operators.describing_function`.

        Examples
        --------
        >>> F = PIOperator([1.0, 0.5], [0.0, 0.2]).describing_function()
        >>> abs(F.describing_function(1e-3))  # only the linear play moves
        1.0
        """

        return PIDescribingFunction(self)

    def inverse_state(self, state) -> np.ndarray:
        """Inverse-operator state consistent with forward play states ``state``.

        Parameters
        ----------
        state : float or array_like of float
            Forward play states ``z_i`` (a scalar or n values, input units).

        Returns
        -------
        numpy.ndarray of float, shape (n,)
            States of :meth:`inverse`'s plays (output units) such that the inverse continues
            exactly from where this operator is.

        Raises
        ------
        ValueError
            If the operator is not invertible or ``state`` has the wrong length.

        Examples
        --------
        >>> PIOperator([1.0, 0.5], [0.0, 0.3]).inverse_state(0.0)
        array([0., 0.])
        """
        z = _initial_state(state, self.n)
        res = _native.pi_inverse(self._p, self._r, z)
        if res is None:
            raise ValueError("PIOperator.inverse_state: the operator is not invertible")
        return res[2]


@dataclass(frozen=True)
class TimeDependentPI:
    """PI operator with radii given per sample (paper eq. 7), used by the radius estimator.

    ``z_i[k] = max(v[k] - R[k, i], min(v[k] + R[k, i], z_i[k-1]))``, ``y[k] = sum_i p_i z_i[k]``.

    Parameters
    ----------
    weights : array_like of float, shape (n,)
        Weights ``p_i`` (output per input unit).

    Raises
    ------
    ValueError
        If ``weights`` is not a finite non-empty vector.

    Examples
    --------
    >>> TimeDependentPI([1.0]).simulate([0.0, 1.0, 1.0], [[0.0], [0.5], [0.2]])
    array([0. , 0.5, 0.8])
    """

    weights: np.ndarray

    def __post_init__(self):
        p = as_vector(self.weights, "weights")
        object.__setattr__(self, "weights", p)

    def simulate(self, v, radii_per_sample, *, initial_state=0.0, return_plays: bool = False):
        """Output for inputs ``v`` (N) and radii ``radii_per_sample`` (N, n), each >= 0.

        Parameters
        ----------
        v : array_like of float, shape (N,)
            Input samples ``v[k]`` (input units).
        radii_per_sample : array_like of float, shape (N, n)
            Radius ``R[k, i]`` of play i at sample k (input units), finite and >= 0.
        initial_state : float or array_like of float, optional
            Play states before the first sample, ``z_i[-1]``. Default 0.
        return_plays : bool, optional
            Also return the play states ``z_i[k]``.

        Returns
        -------
        y : numpy.ndarray of float, shape (N,)
            Output ``y[k] = sum_i p_i z_i[k]`` (output units).
        z : numpy.ndarray of float, shape (N, n)
            Play states per sample; only with ``return_plays=True``.

        Raises
        ------
        ValueError
            If ``radii_per_sample`` has the wrong shape or a negative/non-finite radius, or ``v``
            is not a finite 1-D signal.

        Examples
        --------
        >>> y, z = TimeDependentPI([1.0, 0.5]).simulate(
        ...     [0.0, 1.0], [[0.0, 0.0], [0.0, 0.4]], return_plays=True)
        >>> y, z
        (array([0. , 1.3]), array([[0. , 0. ],
               [1. , 0.6]]))
        """
        x = as_signal(v, "v")
        n = self.weights.size
        R = np.ascontiguousarray(np.asarray(radii_per_sample, dtype=float))
        if R.shape != (x.size, n):
            raise ValueError(
                f"radii_per_sample: expected shape ({x.size}, {n}), got {R.shape}"
            )
        if not np.all(np.isfinite(R)) or np.any(R < 0):
            raise ValueError("radii_per_sample: every radius must be finite and >= 0")
        z = _initial_state(initial_state, n)
        y, zhist = _native.tdpi_run(self.weights, R, z, x, with_plays=return_plays)
        return (y, zhist) if return_plays else y
