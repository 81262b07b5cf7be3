"""Generalized Prandtl-Ishlinskii operator: a PI operator between strictly increasing envelope
functions, for asymmetric and saturating loops, with an exact analytic inverse.

Discrete-time semantics (C core ``fmu/src/pim_generalized.h``), input ``v[k]``::

    u[k]   = h(v[k])                                             input envelope
    z_i[k] = max(u[k] - r_i, min(u[k] + r_i, z_i[k-1])),  z_i[-1] = initial_state[i]
    y[k]   = g(sum_i p_i z_i[k])                                  output envelope

``y[k]`` depends on ``v[0..k]`` (no delay); the operator is rate independent. This is the
generalized play of Al Janaideh, Rakheja & Su (IEEE/ASME Trans. Mechatronics 16(4), 2011,
"An analytical generalized Prandtl-Ishlinskii model inversion for hysteresis compensation in
micropositioning control") with identical loading and unloading envelopes ``gamma_l = gamma_r
= h`` (e.g. ``h(v) = a0 tanh(a1 v + a2) + a3``: saturation, and asymmetric loops when ``h`` is
not odd), followed by Kuhnen's output (superposition) function ``g`` (Kuhnen, "Modeling,
identification and compensation of complex hysteretic nonlinearities: a modified
Prandtl-Ishlinskii approach", Eur. J. Control 9(4), 2003), which makes the ascending and
descending branches differ in shape at the same output level.

Exact inverse (both envelopes strictly increasing, ``r_1 = 0``, ``p_1 > 0``)::

    v = h^-1( PI^-1[ g^-1(y) ] )

with ``PI^-1`` the Krejci-Kuhnen inverse (:meth:`pimodel.PIOperator.inverse`), so the inverse
is again a generalized PI operator: input envelope ``g^-1``, signed weights, output envelope
``h^-1``. Distinct loading and unloading envelopes (``gamma_l != gamma_r``) have no closed-form
inverse and are not offered.

Units: ``v`` in the input unit (e.g. V); radii and play states in the unit of ``h(v)``
(the input unit when ``h`` is the identity); ``y`` in the output unit; weights in the unit of
``g``'s argument per unit of ``h``.
"""

from __future__ import annotations

import numpy as np

from .. import _native
from ..checks import as_signal, scalar_or_vector
from .base import Streaming, check_finite, operator_repr, read_only, size_of, streaming_state
from .envelopes import Envelope
from .pi import PIOperator

__all__ = ["GeneralizedPI"]


def _envelope(value, name: str) -> Envelope:
    if value is None:
        return Envelope.identity()
    if not isinstance(value, Envelope):
        raise TypeError(f"{name}: expected a pimodel.operators.envelopes.Envelope or None, got "
                        f"{type(value).__name__}")
    return value


class GeneralizedPI(Streaming):
    """Generalized PI operator ``y[k] = g(sum_i p_i Gamma_{r_i}[h(v)][k])``.

    Parameters
    ----------
    weights, radii : array_like
        ``p_i`` and ``r_i`` of the PI part (as :class:`pimodel.PIOperator`: same length,
        radii >= 0 in envelope units, sorted together with weights and states).
    input_envelope : Envelope, optional
        ``h``, applied to ``v`` before the plays (default: identity).
    output_envelope : Envelope, optional
        ``g``, applied to the weighted play sum (default: identity).
    initial_state : float or array_like
        Play states ``z_i[-1]`` in envelope units (scalar or one per play). Default 0.
    signed_weights : bool
        Allow signed weights with positive partial sums (the inverse's class).

    Raises
    ------
    ValueError
        Bad weights, radii or initial state (as :class:`pimodel.PIOperator`).
    TypeError
        An envelope that is not an :class:`~pimodel.operators.envelopes.Envelope`.

    Examples
    --------
    >>> from pimodel.operators.envelopes import Envelope
    >>> op = GeneralizedPI([1.0, 0.5], [0.0, 0.2], input_envelope=Envelope.tanh(2.0, 0.5),
    ...                    output_envelope=Envelope.poly2(0.0, 1.0, 0.05))
    >>> v = np.sin(np.linspace(0, 6, 50))
    >>> bool(np.max(np.abs(op.inverse().simulate(op.simulate(v)) - v)) < 1e-12)
    True
    """

    def __init__(self, weights, radii, *, input_envelope: Envelope | None = None,
                 output_envelope: Envelope | None = None, initial_state=0.0,
                 signed_weights: bool = False):
        self._pi = PIOperator(weights, radii, initial_state=initial_state,
                              signed_weights=signed_weights)
        self.input_envelope = _envelope(input_envelope, "input_envelope")
        self.output_envelope = _envelope(output_envelope, "output_envelope")
        self._p, self._r, self._z0 = self._pi.weights, self._pi.radii, self._pi.initial_state
        self._restart()

    # -- parameters ---------------------------------------------------------------------
    @property
    def pi(self) -> PIOperator:
        """The PI part (weights, radii, initial state in envelope units)."""
        return self._pi

    weights = read_only("_p", "Weights ``p_i`` (read-only), ordered by radius.")
    radii = read_only("_r", "Radii ``r_i`` in envelope units (read-only), non-decreasing.")
    n = size_of("_p", "Number of plays.")
    initial_state = read_only("_z0", "Play states before the first sample, ``z_i[-1]``.")

    def __repr__(self) -> str:
        return operator_repr("GeneralizedPI", weights=self._p, radii=self._r,
                             input_envelope=self.input_envelope,
                             output_envelope=self.output_envelope)

    # -- simulation ---------------------------------------------------------------------
    def _run(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        y, bad = _native.gpi_run(self.weights, self.radii, z, self.input_envelope.code,
                                 self.input_envelope.coefficients, self.output_envelope.code,
                                 self.output_envelope.coefficients, x)
        if bad:
            k = bad - 1
            raise ValueError(f"v: sample {k} ({float(x[k])!r}) leaves the domain of the input "
                             f"envelope {self.input_envelope!r} or, through the play sum, of the "
                             f"output envelope {self.output_envelope!r}")
        return check_finite(y, x, "v", state=z)

    def _check_state(self, value) -> np.ndarray:
        return scalar_or_vector(value, "initial_state", self.n, one_per="play")

    def simulate(self, v, *, state=None, return_state: bool = False):
        """Output ``y[k]`` for ``v[k]``, k = 0..N-1, from ``state`` (default the initial one).

        Parameters
        ----------
        v : array_like
            Input samples (input unit).
        state : float or array_like, optional
            Play states to start from (envelope units); the streaming state is untouched.
        return_state : bool
            Also return the final play states.

        Returns
        -------
        numpy.ndarray or tuple
            ``y`` (output unit), or ``(y, z_final)``.

        Raises
        ------
        ValueError
            Non-finite input, or a sample outside an envelope's domain (named).

        Examples
        --------
        >>> from pimodel.operators.envelopes import Envelope
        >>> op = GeneralizedPI([1.0, 0.5], [0.0, 0.2],
        ...                    output_envelope=Envelope.poly2(0.0, 1.0, 0.5))
        >>> op.simulate([0.0, 1.0, 0.5])
        array([0.     , 2.38   , 1.21125])
        """
        x = as_signal(v, "v")
        z = self._start_state(state)
        y = self._run(x, z)
        return (y, z) if return_state else y

    state = streaming_state(
        "Current streaming play states (a copy); settable with a scalar or n values.")

    def reset(self) -> None:
        """Return the streaming state to :attr:`initial_state`.

        Examples
        --------
        >>> op = GeneralizedPI([1.0, 0.5], [0.0, 0.2])
        >>> _ = op.step(1.0)
        >>> op.reset()
        >>> op.state
        array([0., 0.])
        """
        self._restart()

    def step(self, v: float) -> float:
        """Advance one sample with input ``v[k]`` and return ``y[k]``.

        Parameters
        ----------
        v : float
            Input sample ``v[k]`` (input unit).

        Returns
        -------
        float
            Output ``y[k]`` (output unit), from the updated play states ``z_i[k]``.

        Raises
        ------
        ValueError
            Non-finite input, or a sample outside an envelope's domain.

        Examples
        --------
        >>> from pimodel.operators.envelopes import Envelope
        >>> op = GeneralizedPI([1.0, 0.5], [0.0, 0.2],
        ...                    output_envelope=Envelope.poly2(0.0, 1.0, 0.5))
        >>> op.step(1.0), op.state
        (2.38, array([1. , 0.8]))
        """
        return self._advance(self._run, as_signal(v, "v"))

    # -- inverse ------------------------------------------------------------------------
    @property
    def is_invertible(self) -> bool:
        """True when the exact inverse exists (``r_1 = 0``, positive partial sums)."""
        return self._pi.is_invertible

    def inverse(self) -> GeneralizedPI:
        """Exact inverse ``v = h^-1(PI^-1[g^-1(y)])``, again a :class:`GeneralizedPI`.

        Its play states are made consistent with this operator's initial state, so
        ``op.inverse().simulate(op.simulate(v))`` returns ``v``.

        Returns
        -------
        GeneralizedPI
            Input envelope ``g^-1``, the Krejci-Kuhnen inverse PI (signed weights), output
            envelope ``h^-1``. Its ``simulate(y_d)`` is a causal feedforward.

        Raises
        ------
        ValueError
            When the PI part has no linear play (``r_1 > 0``).

        Examples
        --------
        >>> from pimodel.operators.envelopes import Envelope
        >>> op = GeneralizedPI([1.0, 0.5], [0.0, 0.2],
        ...                    output_envelope=Envelope.poly2(0.0, 1.0, 0.5))
        >>> v = np.array([0.0, 1.0, 0.5])
        >>> bool(np.allclose(op.inverse().simulate(op.simulate(v)), v))
        True
        """
        inv = self._pi.inverse()
        out = GeneralizedPI(inv.weights, inv.radii,
                            input_envelope=self.output_envelope.inverse(),
                            output_envelope=self.input_envelope.inverse(),
                            initial_state=inv.initial_state, signed_weights=True)
        out.forward = self  # the operator it inverts (FMU export, JSON form)
        return out

    def to_dict(self) -> dict:
        """JSON-ready parameters (weights, radii, initial state, envelopes).

        Returns
        -------
        dict
            ``type``, ``weights``, ``radii``, ``initial_state``, ``signed_weights``,
            ``input_envelope`` and ``output_envelope`` (see
            :func:`pimodel.model_files.model_to_dict`).

        Examples
        --------
        >>> d = GeneralizedPI([1.0], [0.0]).to_dict()
        >>> d["type"], d["weights"], d["output_envelope"]
        ('GeneralizedPI', [1.0], {'kind': 'poly2', 'coefficients': [0.0, 1.0, 0.0]})
        """
        return {"type": "GeneralizedPI", "weights": self.weights.tolist(),
                "radii": self.radii.tolist(), "initial_state": self.initial_state.tolist(),
                "signed_weights": self._pi.signed_weights,
                "input_envelope": self.input_envelope.to_dict(),
                "output_envelope": self.output_envelope.to_dict()}
