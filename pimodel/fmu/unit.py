"""A small co-simulation handle on an FMI 2.0 CS unit (ours or any other), over fmpy's
``FMU2Slave``: parameters and signals by name, fixed-step stepping, state save/restore."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)


class FMUUnit:
    """An instantiated, initialised co-simulation FMU.

    ``start`` sets parameters and start values by variable name before initialisation
    (``n``, ``Ts``, ``p[1]`` ...). :meth:`set` / :meth:`get` take variable names; :meth:`step`
    calls ``doStep(t, h)`` and advances the unit's time. Errors from the FMU (fmi2Error) raise
    fmpy's ``FMICallException``; the FMU's log lines are kept in :attr:`log`.
    """

    def __init__(self, path, start: dict | None = None, *, instance_name: str = "unit"):
        self.path = Path(path)
        if not self.path.exists():
            raise FileNotFoundError(f"{self.path}: no such FMU")
        self.md = read_model_description(str(self.path))
        if self.md.coSimulation is None:
            raise ValueError(f"{self.path}: not a co-simulation FMU")
        self._dir = extract(str(self.path), tempfile.mkdtemp(prefix="pimodel_fmu_"))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.log: list[str] = []
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self._dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=instance_name)
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = fmi2CallbackLoggerTYPE(self._logger)
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.fmu.instantiate(loggingOn=True, callbacks=self._callbacks)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        if start:
            self.set(start)
        try:
            self.fmu.exitInitializationMode()
        except Exception as exc:
            self.fmu.freeInstance()
            raise ValueError(f"{self.path.name}: initialisation failed: "
                             f"{'; '.join(self.log) or exc}") from None
        self.time = 0.0

    def _logger(self, env, instance, status, category, message) -> None:
        self.log.append(message.decode(errors="replace") if message else "")

    def _var(self, name: str):
        try:
            return self.vars[name]
        except KeyError:
            raise KeyError(f"{self.path.name}: no variable {name!r}") from None

    def set(self, values: dict) -> None:
        """Set variables by name (Real, Integer or Boolean)."""
        for name, value in values.items():
            v = self._var(name)
            if v.type == "Real":
                self.fmu.setReal([v.valueReference], [float(value)])
            elif v.type == "Integer":
                self.fmu.setInteger([v.valueReference], [int(value)])
            elif v.type == "Boolean":
                self.fmu.setBoolean([v.valueReference], [bool(value)])
            else:
                raise TypeError(f"{name}: unsupported type {v.type}")

    def get(self, names) -> np.ndarray:
        """Real values of the named variables."""
        refs = [self._var(n).valueReference for n in names]
        return np.array(self.fmu.getReal(refs))

    def step(self, h: float) -> None:
        """One communication step of length ``h`` from the current time."""
        try:
            self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=h)
        except Exception:
            raise ValueError(f"{self.path.name}: doStep at t = {self.time:g} failed: "
                             f"{'; '.join(self.log[-3:])}") from None
        self.time += h

    def get_state(self):
        return self.fmu.getFMUState(), self.time

    def set_state(self, state) -> None:
        self.fmu.setFMUState(state[0])
        self.time = state[1]

    def close(self) -> None:
        try:
            self.fmu.terminate()
        finally:
            self.fmu.freeInstance()
            shutil.rmtree(self._dir, ignore_errors=True)
