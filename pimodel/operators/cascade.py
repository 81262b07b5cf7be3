"""Operators in series, ``y = O_m[... O_2[O_1[v]]]``, and the inverse of the chain.

Discrete-time semantics: sample k of each stage's output is the next stage's input at sample
k (no added delay), so ``y[k]`` depends on ``v[0..k]``. The inverse runs the stages' inverses in
reverse order, ``v = O_1^-1[... O_m^-1[y_d]]``, each started from its forward stage's own
initial state, so ``Cascade.inverse().simulate(chain.simulate(v)) == v`` whenever every stage's
inverse is exact (PI, generalized, asymmetric, rate-dependent, creep operators).
"""

from __future__ import annotations

import numpy as np

from ..checks import as_signal
from .base import operator_repr

__all__ = ["Cascade"]


class Cascade:
    """Operators applied one after the other (each with ``simulate``, ``step``, ``reset`` and,
    for :meth:`inverse`, ``inverse()``).

    Parameters
    ----------
    *stages
        The operators, first applied first (e.g. a hysteresis operator, then creep).

    Raises
    ------
    ValueError
        No stages.
    TypeError
        A stage without ``simulate``.

    Examples
    --------
    >>> from pimodel.operators.generalized import GeneralizedPI
    >>> from pimodel.operators.creep import CreepOperator
    >>> chain = Cascade(GeneralizedPI([1.0, 0.5], [0.0, 0.3]),
    ...                 CreepOperator([0.05], [0.1], dt=1e-3))
    >>> v = np.sin(np.linspace(0, 10, 500))
    >>> bool(np.max(np.abs(chain.inverse().simulate(chain.simulate(v)) - v)) < 1e-12)
    True
    """

    def __init__(self, *stages):
        if not stages:
            raise ValueError("stages: expected at least one operator")
        for i, s in enumerate(stages):
            if not callable(getattr(s, "simulate", None)):
                raise TypeError(f"stages[{i}]: expected an operator with simulate(), got "
                                f"{type(s).__name__}")
        self.stages = tuple(stages)

    def __repr__(self) -> str:
        return operator_repr("Cascade", *self.stages)

    def simulate(self, v) -> np.ndarray:
        """Output of the chain for the samples ``v[k]`` (each stage from its initial state).

        Parameters
        ----------
        v : array_like of float, shape (N,)
            Input of the first stage, ``v[k]``.

        Returns
        -------
        numpy.ndarray of float, shape (N,)
            Output of the last stage; ``y[k]`` depends on ``v[0..k]`` (no delay added).

        Raises
        ------
        ValueError
            If ``v`` is not a finite 1-D signal.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> Cascade(PIOperator([1.0], [0.0]), PIOperator([2.0], [0.0])).simulate([0.0, 1.0])
        array([0., 2.])
        """
        x = as_signal(v, "v")
        for s in self.stages:
            x = s.simulate(x)
        return x

    def step(self, v: float) -> float:
        """Advance every stage one sample (streaming state of each stage).

        Parameters
        ----------
        v : float
            Input sample ``v[k]`` of the first stage.

        Returns
        -------
        float
            Output ``y[k]`` of the last stage.

        Raises
        ------
        ValueError
            When a stage refuses the sample (e.g. float64 overflow); every stage then keeps
            the state it had before this step.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> Cascade(PIOperator([1.0], [0.0]), PIOperator([2.0], [0.0])).step(0.5)
        1.0
        """
        kept = [s for s in self.stages if hasattr(s, "state")]
        saved = [s.state for s in kept]
        x = float(v)
        try:
            for s in self.stages:
                x = s.step(x)
        except ValueError:   # a stage refused: every stage keeps its state (base.py's rule)
            for s, z in zip(kept, saved, strict=True):
                s.state = z
            raise
        return x

    def reset(self) -> None:
        """Reset every stage's streaming state.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> chain = Cascade(PIOperator([1.0], [0.5]))
        >>> _ = chain.step(2.0)
        >>> chain.reset()
        >>> chain.step(0.0)
        0.0
        """
        for s in self.stages:
            s.reset()

    def inverse(self) -> Cascade:
        """The chain of the stages' inverses in reverse order (module docstring).

        Returns
        -------
        Cascade
            The inverse chain: ``inverse().simulate(simulate(v))`` returns ``v``.

        Examples
        --------
        >>> from pimodel import PIOperator
        >>> Cascade(PIOperator([1.0], [0.0]), PIOperator([2.0], [0.0])).inverse().stages
        (PIOperator(weights=[0.5], radii=[0.]), PIOperator(weights=[1.], radii=[0.]))
        """
        return Cascade(*(s.inverse() for s in reversed(self.stages)))
