"""Strictly increasing envelope functions with closed-form inverses, for :class:`GeneralizedPI`.

Four kinds, each defined by coefficients ``c`` (the C core, ``fmu/src/pim_generalized.h``,
evaluates them; :meth:`Envelope.reference` is the NumPy spec)::

    poly2      f(x) = c0 + c1 x + c2 x^2                on c1 + 2 c2 x > 0
    tanh       f(x) = c0 tanh(c1 x + c2) + c3           c0 > 0, c1 > 0, all x (saturates)
    poly2_inv  f(x) = 2 (x - c0) / (c1 + sqrt(c1^2 + 4 c2 (x - c0)))   inverse of poly2
    tanh_inv   f(x) = (atanh((x - c3) / c0) - c2) / c1                 inverse of tanh

Outside its domain an envelope is undefined; :meth:`Envelope.__call__` then raises ValueError
naming the first sample. The identity is ``poly2`` with ``c = (0, 1, 0)``.
"""

from __future__ import annotations

import numpy as np

from .. import _native
from ..checks import as_signal, as_vector

__all__ = ["Envelope"]

_KINDS = _native.ENVELOPE_KINDS
_INVERSE = {"poly2": "poly2_inv", "tanh": "tanh_inv", "poly2_inv": "poly2", "tanh_inv": "tanh"}


class Envelope:
    """A strictly increasing scalar function with an exact inverse.

    Parameters
    ----------
    kind : {"poly2", "tanh", "poly2_inv", "tanh_inv"}
        The family (module docstring).
    coefficients : array_like
        ``c0, c1, c2`` (poly2 kinds) or ``c0, c1, c2, c3`` (tanh kinds).

    Raises
    ------
    ValueError
        Unknown kind, wrong number of coefficients, or coefficients that do not give a strictly
        increasing function (the message names the coefficient).

    Examples
    --------
    >>> e = Envelope.tanh(2.0, 0.5, 0.1, 0.3)
    >>> x = np.array([-1.0, 0.0, 2.0])
    >>> bool(np.allclose(e.inverse()(e(x)), x))
    True
    """

    def __init__(self, kind: str, coefficients):
        if kind not in _KINDS:
            raise ValueError(f"kind: expected one of {sorted(_KINDS)}, got {kind!r}")
        m = 4 if kind.startswith("tanh") else 3
        c = as_vector(coefficients, "coefficients", length=m)
        self.kind = kind
        self._c = np.zeros(4)
        self._c[:m] = c
        msg = _native.envelope_check(_KINDS[kind], self._c)
        if msg is not None:
            raise ValueError(f"coefficients: {msg} (kind {kind!r}, got {c.tolist()})")
        self._c.setflags(write=False)

    # -- constructors -------------------------------------------------------------------
    @classmethod
    def identity(cls) -> Envelope:
        """``f(x) = x``."""
        return cls("poly2", (0.0, 1.0, 0.0))

    @classmethod
    def affine(cls, slope: float, offset: float = 0.0) -> Envelope:
        """``f(x) = offset + slope x`` (slope > 0)."""
        return cls("poly2", (offset, slope, 0.0))

    @classmethod
    def poly2(cls, c0: float, c1: float, c2: float) -> Envelope:
        """``f(x) = c0 + c1 x + c2 x^2``, defined where ``c1 + 2 c2 x > 0``."""
        return cls("poly2", (c0, c1, c2))

    @classmethod
    def tanh(cls, a0: float, a1: float, a2: float = 0.0, a3: float = 0.0) -> Envelope:
        """``f(x) = a0 tanh(a1 x + a2) + a3`` (a0, a1 > 0): saturates at ``a3 -+ a0``."""
        return cls("tanh", (a0, a1, a2, a3))

    # -- values -------------------------------------------------------------------------
    @property
    def code(self) -> int:
        """The C core's kind code (``PIM_ENV_*``)."""
        return _KINDS[self.kind]

    @property
    def coefficients(self) -> np.ndarray:
        """The four coefficients passed to the C core (read-only; poly2 kinds pad with 0)."""
        return self._c

    @property
    def is_identity(self) -> bool:
        """True for ``f(x) = x``."""
        return self.kind in ("poly2", "poly2_inv") and tuple(self._c[:3]) == (0.0, 1.0, 0.0)

    def inverse(self) -> Envelope:
        """The exact inverse function, again an :class:`Envelope`.

        Returns
        -------
        Envelope
            ``poly2`` <-> ``poly2_inv``, ``tanh`` <-> ``tanh_inv``, same coefficients.

        Examples
        --------
        >>> Envelope.poly2(0.0, 1.0, 0.25).inverse()
        Envelope('poly2_inv', [0.0, 1.0, 0.25])
        """
        m = 4 if self.kind.startswith("tanh") else 3
        return Envelope(_INVERSE[self.kind], self._c[:m])

    def reference(self, x) -> np.ndarray:
        """NumPy spec of ``f(x)`` (NaN outside the domain), held equal to the C core by tests.

        Parameters
        ----------
        x : array_like of float
            Arguments.

        Returns
        -------
        numpy.ndarray of float
            ``f(x)`` elementwise, NaN where ``x`` lies outside the domain.

        Examples
        --------
        >>> Envelope.poly2(0.0, 1.0, 0.25).reference([0.0, 1.0, -3.0])
        array([0.  , 1.25,  nan])
        """
        x = np.asarray(x, float)
        c0, c1, c2, c3 = self._c
        with np.errstate(invalid="ignore", divide="ignore"):
            if self.kind == "poly2":
                return np.where(c1 + 2 * c2 * x > 0, c0 + c1 * x + c2 * x * x, np.nan)
            if self.kind == "tanh":
                return c0 * np.tanh(c1 * x + c2) + c3
            if self.kind == "poly2_inv":
                d = c1 * c1 + 4 * c2 * (x - c0)
                return np.where(d > 0, 2 * (x - c0) / (c1 + np.sqrt(np.abs(d))), np.nan)
            s = (x - c3) / c0
            return np.where(np.abs(s) < 1, (np.arctanh(np.clip(s, -1, 1)) - c2) / c1, np.nan)

    def __call__(self, x) -> np.ndarray:
        """``f(x)`` elementwise (C core).

        Raises
        ------
        ValueError
            When a sample lies outside the domain, naming the sample.
        """
        xs = as_signal(x, "x")
        y = np.array([_native.lib.pim_envelope(self.code, self._c, float(xi)) for xi in xs])
        bad = np.flatnonzero(np.isnan(y))
        if bad.size:
            raise ValueError(f"x: sample {bad[0]} is {float(xs[bad[0]])!r}, outside the domain "
                             f"of {self!r}")
        return y if np.ndim(x) else y[0]

    def to_dict(self) -> dict:
        """JSON-ready form ``{"kind": ..., "coefficients": [...]}``.

        Returns
        -------
        dict
            ``kind`` (str) and ``coefficients`` (list of float).

        Examples
        --------
        >>> Envelope.poly2(0.0, 1.0, 0.25).to_dict()
        {'kind': 'poly2', 'coefficients': [0.0, 1.0, 0.25]}
        """
        m = 4 if self.kind.startswith("tanh") else 3
        return {"kind": self.kind, "coefficients": self._c[:m].tolist()}

    def __eq__(self, other) -> bool:
        return (isinstance(other, Envelope) and self.kind == other.kind
                and np.array_equal(self._c, other._c))

    def __hash__(self) -> int:
        return hash((self.kind, self._c.tobytes()))

    def __repr__(self) -> str:
        m = 4 if self.kind.startswith("tanh") else 3
        return f"Envelope({self.kind!r}, {np.round(self._c[:m], 6).tolist()})"
