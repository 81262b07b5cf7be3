"""Asymmetric generalized Prandtl-Ishlinskii operator: generalized plays with distinct loading
(ascending) and unloading (descending) envelopes, and its exact inverse.

Discrete-time semantics (C core ``fmu/src/pim_asymmetric.h``), input ``v[k]``::

    s[k]   = phi(v[k])                                    shape function (an Envelope)
    z_i[k] = max(gamma_l(v[k]) - r_i, min(gamma_r(v[k]) + r_i, z_i[k-1]))
    y[k]   = p0 s[k] + sum_i p_i z_i[k]

with the envelopes ``gamma_l = a_l phi + d_l`` (ascending branches) and ``gamma_r = a_r phi +
d_r`` (descending branches), ``a_l, a_r > 0``: the generalized play of Al Janaideh, Rakheja &
Su (IEEE/ASME Trans. Mechatronics 16(4), 2011), which gives asymmetric and saturating loops
(with ``phi = tanh``, the branches saturate at different levels), restricted to envelopes
that share one shape function. ``p0 phi(v)`` is the direct term of their generalized PI model.

Exact inverse: the radii and the state fix, at step k, ``y[k]`` as a continuous, strictly
increasing (``p0 > 0``) function of ``s[k]`` that is piecewise *linear* in ``s`` (kinks where a
play meets one of its envelopes, or where the envelopes cross). The inverse finds the segment
that holds ``y_d[k]`` among the sorted kinks, solves the linear equation on it, returns
``v[k] = phi^-1(s[k])`` and advances the forward state with ``s[k]``: exact to rounding for
every input and state, causal, no iteration. A ``y_d`` beyond the range of ``phi`` (a tanh's
saturation level) has no input and raises ValueError. With ``a_l = a_r`` and ``d_l = d_r`` the
operator is a :class:`~pimodel.operators.generalized.GeneralizedPI` with the linear-play weight
``p0``.

Units: ``s``, states, radii, ``d_l``, ``d_r`` in the unit of ``phi``; ``y`` in the output unit.
"""

from __future__ import annotations

import numpy as np

from .. import _native
from ..checks import as_signal, as_vector, positive_scalar, scalar_or_vector
from .base import (
    InverseStreaming,
    Streaming,
    check_finite,
    freeze,
    operator_repr,
    read_only,
    size_of,
    streaming_state,
)
from .envelopes import Envelope

__all__ = ["AsymmetricPI", "AsymmetricPIInverse"]

_MAX_PLAYS = _native.LIMITS["PIM_MAX_PLAYS"]


class AsymmetricPI(Streaming):
    """Generalized PI with distinct ascending/descending envelopes (module docstring).

    Parameters
    ----------
    direct_weight : float
        ``p0 > 0``, weight of ``phi(v)``.
    weights, radii : array_like
        ``p_i >= 0`` and ``r_i >= 0`` (same length n >= 1; sorted by radius).
    ascending, descending : tuple of float
        ``(a_l, d_l)`` and ``(a_r, d_r)``: ``gamma_l = a_l phi + d_l``, ``gamma_r = a_r phi +
        d_r`` (``a > 0``).
    shape : Envelope, optional
        ``phi`` (default identity).
    initial_state : float or array_like
        Play states ``z_i[-1]`` (scalar or n). Default 0.

    Raises
    ------
    ValueError
        Non-positive ``p0`` or envelope slopes, negative weights or radii, bad lengths.

    Examples
    --------
    >>> op = AsymmetricPI(0.5, [1.0, 0.6], [0.0, 0.3], ascending=(1.0, 0.0),
    ...                   descending=(1.3, 0.2), shape=Envelope.tanh(1.0, 0.4))
    >>> v = 3 * np.sin(np.linspace(0, 12, 600))
    >>> bool(np.max(np.abs(op.inverse().simulate(op.simulate(v)) - v)) < 1e-12)
    True
    """

    def __init__(self, direct_weight: float, weights, radii, *, ascending=(1.0, 0.0),
                 descending=(1.0, 0.0), shape: Envelope | None = None, initial_state=0.0):
        p0 = positive_scalar(direct_weight, "direct_weight")
        p = as_vector(weights, "weights")
        r = as_vector(radii, "radii", length=p.size)
        if np.any(p < 0):
            raise ValueError(f"weights: weight {int(np.flatnonzero(p < 0)[0]) + 1} is negative; "
                             "expected >= 0")
        if np.any(r < 0):
            raise ValueError(f"radii: radius {int(np.flatnonzero(r < 0)[0]) + 1} is negative; "
                             "expected >= 0")
        al, dl = as_vector(ascending, "ascending", length=2)
        ar, dr = as_vector(descending, "descending", length=2)
        positive_scalar(al, "ascending slope a_l")
        positive_scalar(ar, "descending slope a_r")
        shape = Envelope.identity() if shape is None else shape
        if not isinstance(shape, Envelope):
            raise TypeError(f"shape: expected a pimodel.operators.envelopes.Envelope, got "
                            f"{type(shape).__name__}")
        z0 = scalar_or_vector(initial_state, "initial_state", p.size)
        order = np.argsort(r, kind="stable")
        self._p, self._r, self._z0 = p[order], r[order], z0[order]
        freeze(self._p, self._r, self._z0)
        self.direct_weight = p0
        self.ascending = (float(al), float(dl))
        self.descending = (float(ar), float(dr))
        self.shape = shape
        self._c = _native.AsymParams(p0, al, dl, ar, dr, shape.code,
                                     (_native.c_double * 4)(*shape.coefficients),
                                     shape.inverse().code)
        self.reset()

    weights = read_only("_p", "Play weights ``p_i`` (read-only), ordered by radius.")
    radii = read_only("_r", "Radii ``r_i`` (read-only), non-decreasing.")
    n = size_of("_p", "Number of plays.")
    initial_state = read_only("_z0", "Play states before the first sample.")

    def __repr__(self) -> str:
        return operator_repr("AsymmetricPI", self.direct_weight, self._p, self._r,
                             ascending=self.ascending, descending=self.descending,
                             shape=self.shape)

    def _check_state(self, value) -> np.ndarray:
        return scalar_or_vector(value, "state", self.n)

    state = streaming_state("Streaming play states (a copy).")

    def reset(self) -> None:
        """Return the streaming state to :attr:`initial_state`.

        Examples
        --------
        >>> op = AsymmetricPI(1.0, [0.5], [0.2], ascending=(1.0, 0.0), descending=(2.0, 0.0))
        >>> _ = op.step(1.0)
        >>> op.reset()
        >>> op.state
        array([0.])
        """
        self._restart()

    def _run(self, x: np.ndarray, z: np.ndarray, *, inverse: bool, name: str = "v") -> np.ndarray:
        out, bad = _native.asym_run(self._c, self._p, self._r, z, x, inverse=inverse)
        if bad > x.size:  # AsymmetricPIInverse checks first; kept for a direct _run
            raise ValueError(f"weights: the inverse handles at most {_MAX_PLAYS} plays, got "
                             f"{self.n}")
        if bad:
            k = bad - 1
            what = ("has no input: it lies beyond the range of the shape function"
                    if inverse else "lies outside the domain of the shape function")
            raise ValueError(f"{name}: sample {k} ({float(x[k])!r}) {what} {self.shape!r}")
        return check_finite(out, x, name, state=z)

    def simulate(self, v, *, state=None, return_state: bool = False):
        """Output ``y[k]`` for ``v[k]`` from ``state`` (default the initial state).

        Parameters
        ----------
        v : array_like
            Input samples.
        state : float or array_like, optional
            Play states to start from.
        return_state : bool
            Also return the final play states.

        Returns
        -------
        numpy.ndarray or tuple
            ``y[k]`` (depends on ``v[0..k]``), or ``(y, z_final)`` with ``return_state``.

        Raises
        ------
        ValueError
            Non-finite input, or a sample outside the shape function's domain (named).

        Examples
        --------
        >>> op = AsymmetricPI(1.0, [0.5], [0.2], ascending=(1.0, 0.0), descending=(2.0, 0.0))
        >>> op.simulate([0.0, 1.0, 0.4])
        array([0. , 1.4, 0.8])
        """
        x = as_signal(v, "v")
        z = self._start_state(state)
        y = self._run(x, z, inverse=False, name="v")
        return (y, z) if return_state else y

    def step(self, v: float) -> float:
        """Advance one sample with ``v[k]`` and return ``y[k]``.

        Parameters
        ----------
        v : float
            Input sample ``v[k]``.

        Returns
        -------
        float
            Output ``y[k]``, from the updated play states ``z_i[k]``.

        Raises
        ------
        ValueError
            Non-finite input, or a sample outside the shape function's domain.

        Examples
        --------
        >>> op = AsymmetricPI(1.0, [0.5], [0.2], ascending=(1.0, 0.0), descending=(2.0, 0.0))
        >>> op.step(1.0), op.state
        (1.4, array([0.8]))
        """
        return self._advance(self._run, as_signal(v, "v"), "v", inverse=False)

    def to_dict(self) -> dict:
        """JSON-ready parameters.

        Returns
        -------
        dict
            ``type``, ``direct_weight``, ``weights``, ``radii``, ``ascending``, ``descending``,
            ``shape`` and ``initial_state`` (see :func:`pimodel.model_files.model_to_dict`).

        Examples
        --------
        >>> op = AsymmetricPI(1.0, [0.5], [0.2], ascending=(1.0, 0.0), descending=(2.0, 0.0))
        >>> op.to_dict()["descending"]
        [2.0, 0.0]
        """
        return {"type": "AsymmetricPI", "direct_weight": self.direct_weight,
                "weights": self._p.tolist(), "radii": self._r.tolist(),
                "ascending": list(self.ascending), "descending": list(self.descending),
                "shape": self.shape.to_dict(), "initial_state": self._z0.tolist()}

    def inverse(self) -> AsymmetricPIInverse:
        """Exact causal inverse (module docstring).

        Returns
        -------
        AsymmetricPIInverse
            ``simulate(y_d)`` gives ``v`` with ``self.simulate(v) == y_d`` to rounding.

        Examples
        --------
        >>> op = AsymmetricPI(1.0, [0.5], [0.2], ascending=(1.0, 0.0), descending=(2.0, 0.0))
        >>> y_d = np.array([0.0, 1.5, 1.0])
        >>> bool(np.allclose(op.simulate(op.inverse().simulate(y_d)), y_d))
        True
        """
        return AsymmetricPIInverse(self)


class AsymmetricPIInverse(InverseStreaming):
    """Exact inverse of an :class:`AsymmetricPI`: ``y_d[k]`` in, ``v[k]`` out; its state is the
    forward operator's play state, advanced with the ``v[k]`` it returns.

    Parameters
    ----------
    forward : AsymmetricPI
        The operator to invert (kept as ``.forward``).

    Examples
    --------
    >>> op = AsymmetricPI(1.0, [0.5], [0.2], ascending=(1.0, 0.0), descending=(2.0, 0.0))
    >>> float(op.simulate(op.inverse().simulate([0.0, 1.0, 0.4]))[2])
    0.4
    """

    def __init__(self, forward: AsymmetricPI):
        if forward.n > _MAX_PLAYS:  # the C solve sorts its kinks in a fixed-size array
            raise ValueError(f"forward: {forward.n} plays; the inverse (and the FMU) takes at "
                             f"most {_MAX_PLAYS}")
        self.forward = forward
        self.reset()

    state = streaming_state("Streaming (forward) play states (a copy).")

    def reset(self) -> None:
        """Return to the forward operator's initial state.

        Examples
        --------
        >>> op = AsymmetricPI(1.0, [0.5], [0.2], ascending=(1.0, 0.0), descending=(2.0, 0.0))
        >>> inv = op.inverse()
        >>> _ = inv.step(1.5)
        >>> inv.reset()
        >>> inv.state
        array([0.])
        """
        self._restart()

    def simulate(self, y_d, *, state=None, return_state: bool = False):
        """Input ``v[k]`` that makes the forward operator output ``y_d[k]``.

        Parameters
        ----------
        y_d : array_like
            Desired outputs.
        state : float or array_like, optional
            Forward play states to start from.
        return_state : bool
            Also return the final forward play states.

        Returns
        -------
        numpy.ndarray or tuple

        Raises
        ------
        ValueError
            A ``y_d`` sample no input reaches (beyond a saturation level), named.

        Examples
        --------
        >>> op = AsymmetricPI(1.0, [0.5], [0.2], ascending=(1.0, 0.0), descending=(2.0, 0.0))
        >>> op.inverse().simulate([0.0, 1.5, 1.0])
        array([0.        , 1.06666667, 0.56666667])
        """
        x = as_signal(y_d, "y_d")
        z = self._start_state(state)
        v = self.forward._run(x, z, inverse=True, name="y_d")
        return (v, z) if return_state else v

    def step(self, y_d: float) -> float:
        """Advance one sample with ``y_d[k]`` and return ``v[k]``.

        Parameters
        ----------
        y_d : float
            Desired output ``y_d[k]``.

        Returns
        -------
        float
            Input ``v[k]`` with forward output ``y[k] = y_d[k]``; the state advances with it.

        Raises
        ------
        ValueError
            A ``y_d`` sample no input reaches (beyond a saturation level).

        Examples
        --------
        >>> op = AsymmetricPI(1.0, [0.5], [0.2], ascending=(1.0, 0.0), descending=(2.0, 0.0))
        >>> inv = op.inverse()
        >>> round(inv.step(1.5), 12), inv.state
        (1.066666666667, array([0.86666667]))
        """
        return self._advance(self.forward._run, as_signal(y_d, "y_d"), "y_d", inverse=True)
