"""Running python-control systems on records and returning named signals."""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np


@dataclass
class Signals:
    """Time ``t`` [s] and named signal arrays: ``res["y"]``, ``res.names``."""

    t: np.ndarray
    signals: dict[str, np.ndarray]

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"no signal {name!r}; available: {sorted(self.signals)}") from None

    @property
    def names(self) -> list[str]:
        return list(self.signals)


def simulate(sys: control.InputOutputSystem, t, inputs: dict[str, np.ndarray],
             x0=None) -> Signals:
    """Run ``sys`` (discrete, sample time ``sys.dt``) with the named ``inputs`` on times ``t``.

    ``t`` must be spaced exactly by ``sys.dt`` (python-control's rule); inputs not given are 0.
    ``x0`` defaults to the blocks' own initial states (``x0`` attributes, else 0). Returns the
    outputs and states by name.
    """
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
    if x0 is None:
        x0 = _initial_states(sys)
    res = control.input_output_response(sys, t, U, X0=x0)
    sig = {lab: np.asarray(res.outputs).reshape(sys.noutputs, -1)[i]
           for i, lab in enumerate(sys.output_labels)}
    states = np.asarray(res.states).reshape(sys.nstates, -1)
    sig.update({lab: states[i] for i, lab in enumerate(sys.state_labels)})
    return Signals(t, sig)


def _initial_states(sys) -> np.ndarray:
    subs = getattr(sys, "syslist", None)
    if subs is None:
        return np.asarray(getattr(sys, "x0", np.zeros(sys.nstates)), float)
    return np.concatenate([np.asarray(getattr(s, "x0", np.zeros(s.nstates)), float).ravel()
                           for s in subs]) if subs else np.zeros(0)
