"""Running python-control systems on records and returning named signals.

:func:`simulate` is a thin convenience over ``control.input_output_response``: inputs by name,
the initial state from :func:`pimodel.blocks.initial_state` (the path any python-control user
takes), ``params`` passed through, outputs and states returned by name.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import control
import numpy as np

from ..blocks.framework import initial_state as _initial_state

__all__ = [
    "Signals",
    "simulate",
]


@dataclass
class Signals:
    """Time ``t`` [s] and named signal arrays: ``res["y"]``, ``res.names``.

    Parameters
    ----------
    t : numpy.ndarray of float, shape (N,)
        Sample times [s].
    signals : dict of str to numpy.ndarray
        Signal name -> samples (one per time); ``res[name]`` looks one up (KeyError listing the
        names when unknown).
    aliases : dict of str to str, optional
        Deprecated signal names (before 1-based state labels) -> current ones; looking one up
        works with a DeprecationWarning.

    Examples
    --------
    >>> res = Signals(np.arange(2) * 1e-3, {"y": np.array([0.0, 0.5])})
    >>> res["y"], res.names
    (array([0. , 0.5]), ['y'])
    """

    t: np.ndarray
    signals: dict[str, np.ndarray]
    aliases: dict[str, str] = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self.signals and self.aliases.get(name) in self.signals:
            new = self.aliases[name]
            warnings.warn(f"signal name {name!r} is deprecated; use {new!r}", DeprecationWarning,
                          stacklevel=2)
            name = new
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"no signal {name!r}; available: {sorted(self.signals)}") from None

    @property
    def names(self) -> list[str]:
        return list(self.signals)


def _aliases(sys) -> dict[str, str]:
    """Deprecated names of the blocks' signals, for ``sys`` or the blocks it interconnects."""
    own = dict(getattr(sys, "_aliases", {}))
    for sub in getattr(sys, "syslist", None) or []:
        own.update({f"{sub.name}_{old}": f"{sub.name}_{new}"
                    for old, new in _aliases(sub).items()})
    return own


def simulate(sys: control.InputOutputSystem, t, inputs: dict[str, np.ndarray],
             initial_state=None, *, params: dict | None = None, x0=None) -> Signals:
    """Run ``sys`` (discrete, sample time ``sys.dt``) with the named ``inputs`` on times ``t``.

    Parameters
    ----------
    sys : control.InputOutputSystem
        A discrete-time system: a block, an interconnection, any python-control system.
    t : array_like
        Times [s], spaced exactly by ``sys.dt`` (python-control's rule).
    inputs : dict
        Input name -> samples (same length as ``t``); inputs not given are 0.
    initial_state : array_like, optional
        ``X0``; default :func:`pimodel.blocks.initial_state` ``(sys, params)``.
    params : dict, optional
        python-control params (``"<block>.<setting>"``, see :mod:`pimodel.blocks`).
    x0 : array_like, optional
        Deprecated name of ``initial_state``.

    Returns
    -------
    Signals
        The outputs and states by name.

    Raises
    ------
    ValueError
        If ``sys`` is not discrete, ``t`` is not spaced by ``dt``, or an input name or length
        is wrong.

    Examples
    --------
    >>> import numpy as np
    >>> from pimodel import PIOperator
    >>> from pimodel.blocks import pi_block
    >>> res = simulate(pi_block(PIOperator([1.0], [0.5]), 1e-3), np.arange(3) * 1e-3,
    ...                {"v": [0.0, 1.0, 0.0]})
    >>> res["y"].tolist(), res["z[1]"].tolist()
    ([0.0, 0.5, 0.5], [0.0, 0.0, 0.5])
    """
    if x0 is not None:
        warnings.warn("simulate(x0=...) is deprecated; use initial_state=", DeprecationWarning,
                      stacklevel=2)
        if initial_state is None:
            initial_state = x0
    t = np.asarray(t, float)
    dt = sys.dt
    if dt is None or dt is True or dt == 0:
        raise ValueError("sys: expected a discrete-time system with a numeric sample time dt")
    if t.ndim != 1 or t.size < 2 or not np.allclose(np.diff(t), dt, rtol=1e-9, atol=1e-12):
        raise ValueError(f"t: expected times spaced exactly by dt = {dt}")
    unknown = set(inputs) - set(sys.input_labels)
    if unknown:
        raise ValueError(f"inputs: {sorted(unknown)} are not inputs of {sys.name}; inputs: "
                         f"{sys.input_labels}")
    U = np.zeros((sys.ninputs, t.size))
    for i, label in enumerate(sys.input_labels):
        if label in inputs:
            u = np.asarray(inputs[label], float)
            if u.shape != t.shape:
                raise ValueError(f"inputs[{label!r}]: expected {t.size} samples, got {u.shape}")
            U[i] = u
    if initial_state is None:
        initial_state = _initial_state(sys, params)
    res = control.input_output_response(sys, t, U, initial_state=initial_state, params=params)
    sig = {lab: np.asarray(res.outputs).reshape(sys.noutputs, -1)[i]
           for i, lab in enumerate(sys.output_labels)}
    states = np.asarray(res.states).reshape(sys.nstates, -1)
    sig.update({lab: states[i] for i, lab in enumerate(sys.state_labels)})
    return Signals(t, sig, _aliases(sys))
