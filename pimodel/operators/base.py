"""What the operator classes share, written once (private module).

:class:`~pimodel.PIOperator`, :class:`~pimodel.operators.generalized.GeneralizedPI`,
:class:`~pimodel.operators.asymmetric.AsymmetricPI`,
:class:`~pimodel.operators.rate_dependent.RateDependentPI` and
:class:`~pimodel.operators.creep.CreepOperator` keep their parameters in read-only arrays; they and
the
inverse classes keep a streaming state ``self._z`` that ``step`` advances and ``simulate``
leaves alone:

- :func:`read_only` and :func:`size_of` make the parameter properties (``weights``, ``radii``,
  ``n``, ``initial_state``, ...) with the docstring each class gives, so ``help()`` and the API
  pages show the class's own text (autodoc lists no inherited members);
- :func:`operator_repr` writes ``Name(args, key=value)`` with the arrays rounded to 6 digits;
- :class:`Streaming` holds the streaming-state bookkeeping: the start state of ``simulate``,
  ``reset`` and one ``step`` on a copy of the state (the state changes only when the step
  succeeds, and only when the outputs and the new state are finite);
  :func:`streaming_state` makes the ``state`` property with the class's docstring;
  :class:`InverseStreaming` is the same for an inverse that runs its forward operator's state.

The numerical-range rule, the same for every operator and model (docs/reliability.md): a result
that float64 cannot represent raises a ValueError naming the argument and the sample
(:func:`check_finite`); no operator returns inf or NaN from finite input, and a step that raises
leaves the state as it was.

A class using :class:`Streaming` defines ``_check_state(value)`` (the state's form and its
error message) and, when its initial state is not ``self.initial_state``, ``_fresh_state()``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = [
    "check_finite",
    "freeze",
    "InverseStreaming",
    "operator_repr",
    "read_only",
    "size_of",
    "Streaming",
    "streaming_state",
]


def check_finite(out: np.ndarray, x: np.ndarray, name: str, *, state=None,
                 what: str = "output") -> np.ndarray:
    """``out`` when it and ``state`` are finite; else ValueError naming ``name``'s first sample
    whose result overflowed float64 (the numerical-range rule of the module docstring).

    ``x`` is the (finite) input the operator ran on, ``out`` its output, one sample each;
    ``state`` the operator's state after the last sample (checked too, since an overflowed
    state would spoil the next sample).
    """
    bad = ~np.isfinite(out)
    if state is not None and not np.all(np.isfinite(state)):
        bad[-1] = True
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"{name}: sample {k} ({float(x[k]):.6g}) makes the {what} or the state overflow "
            f"float64 (got {float(out[k])!r}); expected inputs and parameters whose results stay "
            f"below {np.finfo(float).max:.3g}: scale the signal or the parameters down")
    return out


def read_only(attribute: str, doc: str) -> property:
    """A property that returns ``self.<attribute>`` (an array made read-only by the class)."""

    def get(self) -> np.ndarray:
        return getattr(self, attribute)

    return property(get, doc=doc)


def size_of(attribute: str, doc: str) -> property:
    """A property that returns the size of the array ``self.<attribute>`` (plays, lags)."""

    def get(self) -> int:
        return getattr(self, attribute).size

    return property(get, doc=doc)


def freeze(*arrays: np.ndarray) -> None:
    """Make the parameter arrays read-only (the properties hand them out without copying)."""
    for arr in arrays:
        arr.setflags(write=False)


def operator_repr(name: str, *args, numpy_arrays: bool = False, **fields) -> str:
    """``name(arg, ..., key=value, ...)``: arrays rounded to 6 digits, other values by ``repr``.

    Arrays are shown as lists (``[0.0, 0.3]``), or with ``numpy_arrays`` as NumPy prints them
    (``[0. , 0.3]``, :class:`~pimodel.PIOperator`'s form).
    """

    def show(value) -> str:
        if not isinstance(value, np.ndarray):
            return repr(value)
        if numpy_arrays:
            return np.array2string(value, precision=6, separator=", ")
        return repr(np.round(value, 6).tolist())

    parts = [show(a) for a in args] + [f"{key}={show(v)}" for key, v in fields.items()]
    return f"{name}({', '.join(parts)})"


class Streaming:
    """Streaming-state bookkeeping of an operator whose state is ``self._z``."""

    _z: np.ndarray

    def _check_state(self, value) -> np.ndarray:
        """``value`` as a full state (a new array), or ValueError naming the argument."""
        raise NotImplementedError

    def _fresh_state(self) -> np.ndarray:
        """A new copy of the state before the first sample."""
        return self.initial_state.copy()

    def _start_state(self, state) -> np.ndarray:
        """The state a ``simulate`` starts from: ``state`` checked, default the initial one."""
        return self._fresh_state() if state is None else self._check_state(state)

    def _restart(self) -> None:
        """Return the streaming state to the initial state (the body of ``reset``)."""
        self._z = self._fresh_state()

    def _advance(self, run: Callable[..., np.ndarray], x: np.ndarray, name: str = "v",
                 **options) -> float:
        """One ``step``: ``run(x, z, **options)`` on a copy ``z`` of the streaming state, which
        it advances in place; the copy becomes the state once ``run`` returned and both its
        output and ``z`` are finite (:func:`check_finite`, else ValueError and the state is
        unchanged). Returns the first output sample."""
        z = self._z.copy()
        out = check_finite(run(x, z, **options), x, name, state=z)
        self._z = z
        return float(out[0])


class InverseStreaming(Streaming):
    """Streaming state of an inverse operator that runs its forward operator's state
    (``self.forward``): same form, same initial state."""

    forward: Streaming

    def _check_state(self, value) -> np.ndarray:
        return self.forward._check_state(value)

    def _fresh_state(self) -> np.ndarray:
        return self.forward._fresh_state()


def streaming_state(doc: str) -> property:
    """The ``state`` property of a :class:`Streaming` operator: a copy of ``self._z``;
    setting it checks the value with ``self._check_state``."""

    def get(self) -> np.ndarray:
        return self._z.copy()

    def set_(self, value) -> None:
        self._z = self._check_state(value)

    return property(get, set_, doc=doc)
