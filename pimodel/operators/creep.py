"""Creep operator: a sum of first-order lags with feedthrough 1, and its exact causal inverse.

Discrete-time semantics (C core ``fmu/src/pim_creep.h``), input ``u[k]`` (typically the
hysteresis output) sampled every ``dt``, lag i with gain ``c_i`` and time constant ``tau_i``,
``a_i = exp(-dt / tau_i)`` (zero-order hold)::

    y[k]     = u[k] + sum_i c_i x_i[k]
    x_i[k+1] = a_i x_i[k] + (1 - a_i) u[k],          x_i[0] = initial_state[i]

``G(z) = 1 + sum_i c_i (1 - a_i) / (z - a_i)``: a step of height h gives h at once and creeps
to ``(1 + sum c_i) h`` with the time constants ``tau_i`` (creep laws of piezo stages, e.g. a
few lags per decade of time, approximate the log law ``1 + gamma log10(t / t0)``; see
:func:`CreepOperator.log_law`). ``y`` and ``u`` share a unit; ``c`` is dimensionless.

Exact inverse: ``x_i[k]`` depends on ``u[0..k-1]`` only, so ``u[k] = y[k] - sum_i c_i x_i[k]``
is causal and exact, with the same state update. Its poles are the zeros of ``G``, the
eigenvalues of ``diag(a) - (1 - a) c^T`` (matrix determinant lemma), so the inverse is stable
iff ``G`` is minimum phase. Proof for ``c_i > 0`` and ``0 < a_i < 1``: between two consecutive
poles ``G`` runs from -inf to +inf (positive residues), so m - 1 zeros lie in ``(a_min, a_max)``
inside the unit disc; the last zero lies left of ``a_min``, where ``G`` decreases from 1 (at
-inf) to -inf, so it is inside the unit disc iff ``G(-1) > 0``, i.e.
``sum_i c_i (1 - a_i) / (1 + a_i) < 1`` (always true when every ``tau_i >> dt`` and
``sum c_i`` is moderate). For other signs the constructor checks the eigenvalues.
"""

from __future__ import annotations

import numpy as np

from .. import _native
from ..checks import as_signal, as_vector, positive_scalar, scalar_or_vector
from .base import (
    Streaming,
    check_finite,
    freeze,
    operator_repr,
    read_only,
    size_of,
    streaming_state,
)

__all__ = ["CreepOperator"]


class CreepOperator(Streaming):
    """Sum-of-lags creep ``y = G[u]``, ``G(z) = 1 + sum_i c_i (1 - a_i) / (z - a_i)``.

    Parameters
    ----------
    gains : array_like
        ``c_i`` (dimensionless; creep > 0).
    time_constants : array_like
        ``tau_i > 0`` [s], same length.
    dt : float
        Sample time [s].
    initial_state : float or array_like
        Lag states ``x_i[0]`` (scalar or one per lag): the input held before the first sample
        in steady state. Default 0.
    inverted : bool
        Internal: the object computes ``u`` from ``y`` (use :meth:`inverse`).

    Raises
    ------
    ValueError
        Bad lengths, non-positive time constants, or a non-minimum-phase ``G`` (its inverse
        would be unstable; the message gives the largest zero modulus).

    Examples
    --------
    >>> cr = CreepOperator([0.05, 0.03], [0.1, 2.0], dt=1e-3)
    >>> u = np.ones(2000)
    >>> bool(np.max(np.abs(cr.inverse().simulate(cr.simulate(u)) - u)) < 1e-12)
    True
    """

    def __init__(self, gains, time_constants, *, dt: float, initial_state=0.0,
                 inverted: bool = False):
        c = as_vector(gains, "gains")
        tau = as_vector(time_constants, "time_constants", length=c.size)
        if np.any(tau <= 0):
            i = int(np.flatnonzero(tau <= 0)[0])
            raise ValueError(f"time_constants: tau[{i + 1}] is {float(tau[i])!r}; expected > 0")
        self.dt = positive_scalar(dt, "dt")
        self._c, self._tau = c.copy(), tau.copy()  # frozen below: not the caller's arrays
        self._a = np.exp(-self.dt / tau)
        self._x0 = scalar_or_vector(initial_state, "initial_state", c.size)
        freeze(self._c, self._tau, self._a, self._x0)
        self.inverted = bool(inverted)
        zmax = float(np.max(np.abs(self.zeros())))
        if zmax >= 1.0:
            raise ValueError(f"gains: the creep G(z) has a zero of modulus {zmax:.6g} >= 1 (not "
                             "minimum phase), its inverse would be unstable; for c_i > 0 keep "
                             "sum c_i (1 - a_i) / (1 + a_i) < 1")
        self.reset()

    @classmethod
    def log_law(cls, percent_per_decade: float, *, dt: float, t_min: float = 0.01,
                decades: int = 4, initial_state=0.0) -> CreepOperator:
        """Lags that approximate the log law ``y(t) = h (1 + gamma log10(t / t_min))``.

        One lag per decade, ``tau_j = t_min 10^j`` (j = 0..decades-1), each with gain
        ``gamma = percent_per_decade / 100``: a step of height h then creeps by about
        ``gamma h`` per decade between ``t_min`` and ``t_min 10^decades`` (the convention of
        :func:`pimodel.loops.actuators.creep_per_decade`, discretised with a zero-order hold).

        Parameters
        ----------
        percent_per_decade : float
            Creep per decade of time, in percent of the step (> 0).
        dt : float
            Sample time [s].
        t_min : float
            Shortest time constant [s].
        decades : int
            Number of decades covered.
        initial_state : float or array_like
            As for the constructor.

        Returns
        -------
        CreepOperator
        """
        gamma = positive_scalar(percent_per_decade, "percent_per_decade") / 100.0
        if int(decades) < 1:
            raise ValueError(f"decades: expected an integer >= 1, got {decades!r}")
        tau = positive_scalar(t_min, "t_min") * 10.0 ** np.arange(int(decades))
        return cls(np.full(tau.size, gamma), tau, dt=dt, initial_state=initial_state)

    # -- parameters ---------------------------------------------------------------------
    gains = read_only("_c", "Lag gains ``c_i`` (read-only).")
    time_constants = read_only("_tau", "Lag time constants ``tau_i`` [s] (read-only).")
    poles = read_only("_a", "``a_i = exp(-dt / tau_i)``, the poles of ``G`` (read-only).")
    m = size_of("_c", "Number of lags.")
    initial_state = read_only("_x0", "Lag states ``x_i[0]`` (read-only).")

    def zeros(self) -> np.ndarray:
        """Zeros of ``G`` (poles of the inverse): eigenvalues of ``diag(a) - (1 - a) c^T``.

        Returns
        -------
        numpy.ndarray
            The m zeros (complex in general); all inside the unit circle for a valid operator.

        Examples
        --------
        >>> cr = CreepOperator([0.5], [1e-3], dt=1e-3)
        >>> cr.zeros().round(6)
        array([0.051819])
        """
        return np.linalg.eigvals(np.diag(self._a) - np.outer(1.0 - self._a, self._c))

    def static_gain(self) -> float:
        """``G(1) = 1 + sum c_i`` (for the inverse, its reciprocal).

        Returns
        -------
        float
            The steady-state gain (output per input unit, dimensionless here).

        Examples
        --------
        >>> cr = CreepOperator([0.5], [1e-3], dt=1e-3)
        >>> cr.static_gain(), round(cr.inverse().static_gain(), 12)
        (1.5, 0.666666666667)
        """
        g = 1.0 + float(self._c.sum())
        return 1.0 / g if self.inverted else g

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` of ``x[k+1] = A x[k] + B u[k]``, ``y[k] = C x[k] + D u[k]``.

        For the inverse (``inverted``) the input is ``y`` and the output ``u``.

        Returns
        -------
        A, B, C, D : numpy.ndarray
            Discrete-time state-space matrices, shapes (m, m), (m, 1), (1, m), (1, 1), with
            sample time ``dt`` (e.g. ``control.ss(A, B, C, D, dt)``).

        Examples
        --------
        >>> cr = CreepOperator([0.5], [1e-3], dt=1e-3)
        >>> A, B, C, D = cr.state_space()
        >>> A.round(6), B.round(6), C, D
        (array([[0.367879]]), array([[0.632121]]), array([[0.5]]), array([[1.]]))
        """
        a, c = self._a, self._c
        B = (1.0 - a)[:, None]
        if self.inverted:
            return np.diag(a) - B @ c[None, :], B, -c[None, :], np.ones((1, 1))
        return np.diag(a), B, c[None, :].copy(), np.ones((1, 1))

    def __repr__(self) -> str:
        name = "CreepOperator.inverse" if self.inverted else "CreepOperator"
        return operator_repr(name, gains=self._c, time_constants=self._tau, dt=self.dt)

    # -- simulation ---------------------------------------------------------------------
    def simulate(self, u, *, state=None, return_state: bool = False):
        """Output for the samples ``u[k]`` (``y`` for the forward operator, ``u`` from ``y``
        for the inverse), k = 0..N-1.

        Parameters
        ----------
        u : array_like
            Input samples, one every ``dt``.
        state : float or array_like, optional
            Lag states to start from (default :attr:`initial_state`).
        return_state : bool
            Also return the final lag states.

        Returns
        -------
        numpy.ndarray or tuple
            The output samples (``y[k] = u[k] + sum_i c_i x_i[k]``: direct feedthrough, the
            lags act from the next sample), or ``(output, final lag states)``.

        Raises
        ------
        ValueError
            Non-finite input, or a ``state`` of the wrong length.

        Examples
        --------
        >>> cr = CreepOperator([0.5], [1e-3], dt=1e-3)
        >>> cr.simulate([1.0, 1.0, 1.0])
        array([1.        , 1.31606028, 1.43233236])
        """
        x = as_signal(u, "u")
        s = self._start_state(state)
        out = self._run(x, s)
        return (out, s) if return_state else out

    def _run(self, x: np.ndarray, s: np.ndarray) -> np.ndarray:
        return check_finite(_native.creep_run(self._a, self._c, s, x, inverse=self.inverted), x,
                            "u", state=s)

    def _check_state(self, value) -> np.ndarray:
        return scalar_or_vector(value, "state", self.m)

    state = streaming_state("Streaming lag states (a copy).")

    def reset(self) -> None:
        """Return the streaming state to :attr:`initial_state`.

        Examples
        --------
        >>> cr = CreepOperator([0.5], [1e-3], dt=1e-3)
        >>> _ = cr.step(1.0)
        >>> cr.reset()
        >>> cr.step(1.0)
        1.0
        """
        self._restart()

    def step(self, u: float) -> float:
        """Advance one sample and return the output.

        Parameters
        ----------
        u : float
            Input sample ``u[k]`` (``y_d[k]`` for the inverse).

        Returns
        -------
        float
            Output at sample k; the lag states advance to ``x[k+1]``.

        Raises
        ------
        ValueError
            If ``u`` is not finite.

        Examples
        --------
        >>> cr = CreepOperator([0.5], [1e-3], dt=1e-3)
        >>> cr.step(1.0), round(cr.step(1.0), 8)
        (1.0, 1.31606028)
        """
        return self._advance(self._run, as_signal(u, "u"), "u")

    def inverse(self) -> CreepOperator:
        """The exact causal inverse ``u = G^-1[y]`` (same lags and state; module docstring).

        Returns
        -------
        CreepOperator
            With ``inverted`` flipped: ``inverse().simulate(self.simulate(u)) == u``.

        Examples
        --------
        >>> cr = CreepOperator([0.5], [1e-3], dt=1e-3)
        >>> cr.inverse().simulate([1.0, 1.31606028, 1.43233236]).round(6)
        array([1., 1., 1.])
        """
        return CreepOperator(self._c, self._tau, dt=self.dt, initial_state=self._x0,
                             inverted=not self.inverted)

    def to_dict(self) -> dict:
        """JSON-ready parameters.

        Returns
        -------
        dict
            ``type``, ``gains``, ``time_constants``, ``dt``, ``initial_state``, ``inverted``.

        Examples
        --------
        >>> cr = CreepOperator([0.5], [1e-3], dt=1e-3)
        >>> cr.to_dict()["time_constants"]
        [0.001]
        """
        return {"type": "CreepOperator", "gains": self._c.tolist(),
                "time_constants": self._tau.tolist(), "dt": self.dt,
                "initial_state": self._x0.tolist(), "inverted": self.inverted}
