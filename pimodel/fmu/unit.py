"""A small co-simulation handle on an FMI 2.0 or 3.0 CS unit (ours or any other), over fmpy's
``FMU2Slave`` / ``FMU3Slave``: parameters and signals by name, fixed-step stepping, state
save/restore. FMI 3 arrays are set whole by their name (``"p": [...]``, shorter sequences fill
the first elements) or element-wise with the FMI 2 style names (``"p[2]"``), so the same
names drive both versions."""

from __future__ import annotations

import shutil
import tempfile
import warnings
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
from fmpy.fmi3 import FMU3Slave

# FMU variables renamed in the pimodel FMUs; the old names work for one release with a warning.
RENAMED = {"known_linear": "linear_play"}


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
        self.fmi3 = self.md.fmiVersion.startswith("3")
        ident = self.md.coSimulation.modelIdentifier
        if self.fmi3:
            self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=self._dir,
                                 modelIdentifier=ident, instanceName=instance_name)
            self.fmu.instantiate(loggingOn=True, logMessage=self._logger3)
            self.fmu.enterInitializationMode(startTime=0.0)
        else:
            self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self._dir,
                                 modelIdentifier=ident, instanceName=instance_name)
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
            if self.fmi3:
                self.fmu.enterStepMode()
        except Exception as exc:
            self.fmu.freeInstance()
            raise ValueError(f"{self.path.name}: initialisation failed: "
                             f"{'; '.join(self.log) or exc}") from None
        self.time = 0.0

    def _logger(self, env, instance, status, category, message) -> None:
        self.log.append(message.decode(errors="replace") if message else "")

    def _logger3(self, env, status, category, message) -> None:
        self._logger(env, None, status, category, message)

    def _var(self, name: str):
        """(variable, element index or None) for ``name`` or an FMI 3 element ``base[i]``."""
        if name in self.vars:
            return self.vars[name], None
        if name in RENAMED and RENAMED[name] in self.vars:
            warnings.warn(f"FMU variable {name!r} is now {RENAMED[name]!r}; the old name will "
                          "be removed in the next release", DeprecationWarning, stacklevel=3)
            return self.vars[RENAMED[name]], None
        base, _, rest = name.partition("[")
        v = self.vars.get(base)
        if v is not None and v.dimensions and rest.endswith("]") and rest[:-1].isdigit():
            i = int(rest[:-1]) - 1
            if 0 <= i < self._size(v):
                return v, i
        raise KeyError(f"{self.path.name}: no variable {name!r}")

    @staticmethod
    def _size(v) -> int:
        return int(np.prod([int(d.start) for d in v.dimensions]))

    def _get_array(self, v) -> np.ndarray:
        return np.array(self.fmu.getFloat64([v.valueReference], nValues=self._size(v)))

    def set(self, values: dict) -> None:
        """Set variables by name (Real/Float64, Integer/Int32 or Boolean)."""
        for name, value in values.items():
            v, i = self._var(name)
            vr = [v.valueReference]
            if v.dimensions:
                arr = self._get_array(v)
                if i is None:
                    x = np.atleast_1d(np.asarray(value, float))
                    if x.size > arr.size:
                        raise ValueError(f"{name}: at most {arr.size} values, got {x.size}")
                    arr[: x.size] = x
                else:
                    arr[i] = float(value)
                self.fmu.setFloat64(vr, list(arr))
            elif v.type in ("Real", "Float64"):
                (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)(vr, [float(value)])
            elif v.type in ("Integer", "Int32"):
                (self.fmu.setInt32 if self.fmi3 else self.fmu.setInteger)(vr, [int(value)])
            elif v.type == "Boolean":
                self.fmu.setBoolean(vr, [bool(value)])
            else:
                raise TypeError(f"{name}: unsupported type {v.type}")

    def get(self, names) -> np.ndarray:
        """Real values of the named variables (FMI 3 array elements as ``base[i]``)."""
        if not self.fmi3:
            return np.array(self.fmu.getReal([self._var(n)[0].valueReference for n in names]))
        out, arrays = [], {}
        for name in names:
            v, i = self._var(name)
            if v.dimensions:
                if v.name not in arrays:
                    arrays[v.name] = self._get_array(v)
                out.extend(arrays[v.name] if i is None else [arrays[v.name][i]])
            else:
                out.append(self.fmu.getFloat64([v.valueReference])[0])
        return np.array(out)

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

    def free_state(self, state) -> None:
        self.fmu.freeFMUState(state[0])

    def close(self) -> None:
        try:
            self.fmu.terminate()
        finally:
            self.fmu.freeInstance()
            shutil.rmtree(self._dir, ignore_errors=True)
