"""Rate-dependent Prandtl-Ishlinskii operator: play radii that grow with the input rate, and
its exact inverse.

Discrete-time semantics (C core ``fmu/src/pim_rate_dependent.h``), input ``v[k]`` sampled every
``dt`` seconds::

    rate[k] = lam rate[k-1] + (1 - lam) |v[k-1] - v[k-2]| / dt     (input unit / s)
    r_i[k]  = alpha_i (1 + beta rate[k])
    z_i[k]  = max(v[k] - r_i[k], min(v[k] + r_i[k], z_i[k-1]))
    y[k]    = sum_i p_i z_i[k]

with ``lam = exp(-dt / rate_time_constant)`` (``rate_time_constant = 0``: ``lam = 0``, the rate
of the last sample interval). The state is ``z[1..n]``, ``v[k-1]`` and ``rate[k]`` (by default
``initial_input`` and 0). The thresholds follow Al Janaideh, Su & Rakheja ("Development of
the rate-dependent Prandtl-Ishlinskii model for smart actuators", Smart Mater. Struct. 17, 2008)
in the proportional form ``r_i(vdot) = alpha_i (1 + beta |vdot|)``, which keeps ``r_1 = 0``
(a linear play) at every rate when ``alpha_1 = 0``.

When the inverse is exact: the radii at step k use the rate of the *previous* interval, so
they are fixed before ``v[k]``; ``y[k]`` is then a continuous piecewise-linear function of
``v[k]`` with slope at least ``p_1 > 0`` (``alpha_1 = 0``). :meth:`RateDependentPI.inverse`
solves it in closed form per sample (interpolation between the breakpoints ``z_i -+ r_i[k]``)
and advances the same forward state with the ``v[k]`` it found, so it needs the rate of its own
output ``v`` (which it has), not of ``y_d``: ``inverse().simulate(op.simulate(v)) == v`` in exact
arithmetic, for any input. Limits, stated rather than hidden:

- with ``alpha_1 > 0`` there is no inverse (flat stretches; ValueError);
- a rate taken from the current interval ``|v[k] - v[k-1]|`` would make the step map
  non-monotone once ``beta alpha_i > dt`` and is not offered;
- rounding: an error ``e`` in ``v[k-1]`` moves radius i at step k by ``(1 - lam) beta alpha_i
  e / dt``; with plays 1..m on their envelope the solve turns that into an error of ``kappa e``
  in ``v[k]``, ``kappa = (1 - lam) (beta / dt) sum_{j<=m} p_j alpha_j / sum_{j<=m} p_j``, and
  (for ``lam = 0``) ``e[k] = kappa (e[k-1] - e[k-2])``, stable iff ``kappa < 1``.
  :attr:`RateDependentPI.rate_sensitivity` is the largest ``kappa`` over m. Below 1 the round
  trip holds to 1e-9 (tests); above it the forward model itself is ill-conditioned (its output
  reacts more to the previous input than to the current one) and the inverse drifts from
  rounding: filter the rate (a larger ``rate_time_constant``).

The continuous-time inverse of Al Janaideh & Krejci (IEEE/ASME Trans. Mechatronics 18(5),
2013) computes the thresholds from the rate of ``v`` in the same way.

Units: ``v``, ``alpha`` and states in the input unit, ``beta`` in s per input unit, ``y`` in the
output unit, weights in output per input unit.
"""

from __future__ import annotations

import numpy as np

from .. import _native
from ..checks import as_signal, positive_scalar
from .base import (
    InverseStreaming,
    Streaming,
    check_finite,
    operator_repr,
    read_only,
    size_of,
    streaming_state,
)
from .pi import PIOperator

__all__ = ["RateDependentPI", "RateDependentPIInverse"]


class RateDependentPI(Streaming):
    """Rate-dependent PI operator with radii ``r_i[k] = alpha_i (1 + beta rate[k])``.

    Parameters
    ----------
    weights : array_like
        ``p_i > 0``.
    base_radii : array_like
        ``alpha_i >= 0`` (the radii at rate 0), same length; sorted with the weights.
    rate_gain : float
        ``beta >= 0`` [s per input unit].
    dt : float
        Sample time [s] of the input.
    initial_state : float or array_like
        Play states ``z_i[-1]`` (scalar or one per play). Default 0.
    rate_time_constant : float
        Time constant [s] of the first-order rate filter; 0 (default) uses the rate of the
        last sample interval.
    initial_input : float
        ``v[-1]``; the rate starts at 0. Default 0.

    Raises
    ------
    ValueError
        Bad weights, radii, states, a negative or non-finite ``rate_gain``, ``dt <= 0``.

    Examples
    --------
    >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
    >>> v = np.sin(np.linspace(0, 20, 400))
    >>> bool(np.max(np.abs(op.inverse().simulate(op.simulate(v)) - v)) < 1e-12)
    True
    """

    def __init__(self, weights, base_radii, *, rate_gain: float, dt: float,
                 rate_time_constant: float = 0.0, initial_state=0.0, initial_input: float = 0.0):
        self._pi = PIOperator(weights, base_radii, initial_state=initial_state)
        self._p, self._r = self._pi.weights, self._pi.radii
        beta = float(rate_gain)
        if not np.isfinite(beta) or beta < 0:
            raise ValueError(f"rate_gain: expected a finite number >= 0, got {rate_gain!r}")
        self.rate_gain = beta
        self.dt = positive_scalar(dt, "dt")
        tau = float(rate_time_constant)
        if not np.isfinite(tau) or tau < 0:
            raise ValueError("rate_time_constant: expected a finite number >= 0 [s], got "
                             f"{rate_time_constant!r}")
        self.rate_time_constant = tau
        self.rate_decay = float(np.exp(-self.dt / tau)) if tau > 0 else 0.0
        v0 = float(initial_input)
        if not np.isfinite(v0):
            raise ValueError(f"initial_input: expected a finite number, got {initial_input!r}")
        self.initial_input = v0
        self.reset()

    weights = read_only("_p", "Weights ``p_i`` (read-only), ordered by base radius.")
    base_radii = read_only("_r", "Radii at rate 0, ``alpha_i`` (read-only), non-decreasing.")
    n = size_of("_p", "Number of plays.")

    @property
    def initial_state(self) -> np.ndarray:
        """Full initial state: play states ``z[1..n]``, then ``v[-1]`` and ``rate[0] = 0``."""
        return np.concatenate((self._pi.initial_state, [self.initial_input, 0.0]))

    @property
    def rate_sensitivity(self) -> float:
        """Rounding-error gain of the inverse per step, ``max_m kappa_m`` with ``kappa_m =
        (1 - lam) (beta / dt) sum_{j<=m} p_j alpha_j / sum_{j<=m} p_j`` (module docstring; the
        inverse is numerically exact when it is below 1)."""
        p, a = self.weights, self.base_radii
        ratio = float(np.max(np.cumsum(p * a) / np.cumsum(p)))
        return (1.0 - self.rate_decay) * self.rate_gain * ratio / self.dt

    def radii_at_rate(self, rate: float) -> np.ndarray:
        """Radii ``alpha_i (1 + beta |rate|)`` at an input rate [input unit / s].

        Parameters
        ----------
        rate : float
            Input rate [input unit / s]; its sign does not matter.

        Returns
        -------
        numpy.ndarray of float, shape (n,)
            The radii (input unit).

        Examples
        --------
        >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
        >>> op.radii_at_rate(100.0)
        array([0. , 0.4])
        """
        return self.base_radii * (1.0 + self.rate_gain * abs(float(rate)))

    def __repr__(self) -> str:
        return operator_repr("RateDependentPI", weights=self._p, base_radii=self._r,
                             rate_gain=self.rate_gain, dt=self.dt,
                             rate_time_constant=self.rate_time_constant)

    # -- state --------------------------------------------------------------------------
    def _check_state(self, value) -> np.ndarray:
        s = np.asarray(value, float).ravel()
        if s.size != self.n + 2 or not np.all(np.isfinite(s)):
            raise ValueError(f"state: expected {self.n + 2} finite values (z[1..{self.n}], "
                             f"v[k-1], rate[k]), got {s.size}")
        return s.copy()

    state = streaming_state("Streaming state (a copy): ``z[1..n]``, ``v[k-1]``, ``rate[k]``.")

    def reset(self) -> None:
        """Return the streaming state to :attr:`initial_state`.

        Examples
        --------
        >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
        >>> _ = op.step(1.0)
        >>> op.reset()
        >>> op.state
        array([0., 0., 0., 0.])
        """
        self._restart()

    # -- simulation ---------------------------------------------------------------------
    def _check_rates(self, x: np.ndarray, s: np.ndarray) -> None:
        """ValueError naming the first sample whose rate ``|v[k] - v[k-1]| / dt`` or radius
        ``alpha_n (1 + beta rate)`` float64 cannot hold (checked before the C core runs)."""
        with np.errstate(over="ignore"):
            rate = np.abs(np.diff(np.concatenate(([s[self.n]], x)))) / self.dt
            radius = self._r[-1] * (1.0 + self.rate_gain * np.maximum(rate, s[-1]))
            bad = ~np.isfinite(rate) | ~np.isfinite(radius) | ~np.isfinite(np.abs(x) + radius)
        if np.any(bad):
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(
                f"v: sample {k} ({float(x[k]):.6g}) moves at a rate |v[k] - v[k-1]| / dt = "
                f"{float(rate[k]):.3g} whose play radius alpha_n (1 + rate_gain rate) overflows "
                "float64; expected a smaller step, a longer dt or a smaller rate_gain")

    def _run(self, x: np.ndarray, s: np.ndarray) -> np.ndarray:
        self._check_rates(x, s)
        z, hist = s[:self.n].copy(), s[self.n:].copy()
        y = _native.rdpi_run(self.weights, self.base_radii, self.rate_gain, self.rate_decay,
                             self.dt, z, hist, x)
        check_finite(y, x, "v", state=np.concatenate((z, hist)))
        s[:self.n], s[self.n:] = z, hist
        return y

    def simulate(self, v, *, state=None, return_state: bool = False):
        """Output ``y[k]`` for the samples ``v[k]``, k = 0..N-1.

        Parameters
        ----------
        v : array_like
            Input samples (input unit), one every ``dt``.
        state : array_like, optional
            Full state to start from (default :attr:`initial_state`).
        return_state : bool
            Also return the final full state.

        Returns
        -------
        numpy.ndarray or tuple
            ``y`` (output unit; ``y[k]`` depends on ``v[0..k]``), or ``(y, final_state)``.

        Raises
        ------
        ValueError
            Non-finite input, or a ``state`` of the wrong length.

        Examples
        --------
        >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
        >>> op.simulate([0.0, 1.0, 0.5])
        array([0. , 1.4, 0.9])
        """
        x = as_signal(v, "v")
        s = self._start_state(state)
        y = self._run(x, s)
        return (y, s) if return_state else y

    def step(self, v: float) -> float:
        """Advance one sample with ``v[k]`` and return ``y[k]``.

        Parameters
        ----------
        v : float
            Input sample ``v[k]`` (input unit).

        Returns
        -------
        float
            Output ``y[k]`` (output unit); the state (plays, ``v[k]``, rate) advances.

        Raises
        ------
        ValueError
            If ``v`` is not finite.

        Examples
        --------
        >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
        >>> op.step(1e-3), op.state
        (0.001, array([0.001, 0.   , 0.001, 1.   ]))
        """
        return self._advance(self._run, as_signal(v, "v"))

    def to_dict(self) -> dict:
        """JSON-ready parameters.

        Returns
        -------
        dict
            ``type``, ``weights``, ``base_radii``, ``rate_gain``, ``dt``,
            ``rate_time_constant``, ``initial_state`` and ``initial_input``.

        Examples
        --------
        >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
        >>> op.to_dict()["rate_gain"]
        0.01
        """
        return {"type": "RateDependentPI", "weights": self.weights.tolist(),
                "base_radii": self.base_radii.tolist(), "rate_gain": self.rate_gain,
                "dt": self.dt, "rate_time_constant": self.rate_time_constant,
                "initial_state": self._pi.initial_state.tolist(),
                "initial_input": self.initial_input}

    def inverse(self) -> RateDependentPIInverse:
        """Exact causal inverse (module docstring: when and why it is exact).

        Returns
        -------
        RateDependentPIInverse
            ``simulate(y_d)`` gives ``v`` with ``self.simulate(v) == y_d`` to rounding.

        Raises
        ------
        ValueError
            When ``alpha_1 > 0`` (no linear play: the step map has flat stretches).

        Examples
        --------
        >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
        >>> v = np.array([0.0, 1.0, 0.5])
        >>> bool(np.allclose(op.inverse().simulate(op.simulate(v)), v))
        True
        """
        if self.base_radii[0] != 0.0:
            raise ValueError("RateDependentPI.inverse: not invertible, the smallest base radius "
                             f"is {float(self.base_radii[0])!r}; the exact inverse needs a linear "
                             "play (alpha_1 = 0)")
        return RateDependentPIInverse(self)


class RateDependentPIInverse(InverseStreaming):
    """Exact inverse of a :class:`RateDependentPI`: ``y_d[k]`` in, ``v[k]`` out.

    Its state is the forward operator's state (plays ``z[1..n]``, ``v[k-1]``, ``rate[k]``),
    advanced with the ``v[k]`` it computes, so the radii follow the rate of ``v``.

    Parameters
    ----------
    forward : RateDependentPI
        The operator to invert (``alpha_1 = 0``).

    Examples
    --------
    >>> inv = RateDependentPI([1.0, 0.5], [0.0, 0.3], rate_gain=0.02, dt=1e-3).inverse()
    >>> round(float(inv.simulate([0.0, 1.5])[1]), 9)  # 1.0 v + 0.5 (v - 0.3) = 1.5
    1.1
    """

    def __init__(self, forward: RateDependentPI):
        if forward.base_radii[0] != 0.0:
            raise ValueError("forward: the smallest base radius must be 0 for an inverse")
        self.forward = forward
        self.reset()

    state = streaming_state("Streaming state (a copy), the forward layout.")

    def reset(self) -> None:
        """Return to the forward operator's initial state.

        Examples
        --------
        >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
        >>> inv = op.inverse()
        >>> _ = inv.step(1.5)
        >>> inv.reset()
        >>> inv.state
        array([0., 0., 0., 0.])
        """
        self._restart()

    def _run(self, yd: np.ndarray, s: np.ndarray) -> np.ndarray:
        f = self.forward
        z, hist = s[:f.n].copy(), s[f.n:].copy()
        v = _native.rdpi_inverse_run(f.weights, f.base_radii, f.rate_gain, f.rate_decay, f.dt,
                                     z, hist, yd)
        check_finite(v, yd, "y_d", state=np.concatenate((z, hist)))
        s[:f.n], s[f.n:] = z, hist
        return v

    def simulate(self, y_d, *, state=None, return_state: bool = False):
        """Input ``v[k]`` that makes the forward operator output ``y_d[k]``.

        Parameters
        ----------
        y_d : array_like
            Desired outputs (output unit), one every ``dt``.
        state : array_like, optional
            Forward state to start from (default the forward operator's initial state).
        return_state : bool
            Also return the final forward state.

        Returns
        -------
        numpy.ndarray or tuple
            ``v`` (input unit), or ``(v, final_state)``.

        Raises
        ------
        ValueError
            Non-finite ``y_d``, or a ``state`` of the wrong length.

        Examples
        --------
        >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
        >>> op.inverse().simulate([0.0, 1.5])
        array([0.        , 1.06666667])
        """
        x = as_signal(y_d, "y_d")
        s = self._start_state(state)
        v = self._run(x, s)
        return (v, s) if return_state else v

    def step(self, y_d: float) -> float:
        """Advance one sample with ``y_d[k]`` and return ``v[k]``.

        Parameters
        ----------
        y_d : float
            Desired output ``y_d[k]`` (output unit).

        Returns
        -------
        float
            Input ``v[k]`` (input unit) with forward output ``y[k] = y_d[k]``.

        Raises
        ------
        ValueError
            If ``y_d`` is not finite.

        Examples
        --------
        >>> op = RateDependentPI([1.0, 0.5], [0.0, 0.2], rate_gain=0.01, dt=1e-3)
        >>> round(op.inverse().step(1.5), 12)
        1.066666666667
        """
        return self._advance(self._run, as_signal(y_d, "y_d"), "y_d")
