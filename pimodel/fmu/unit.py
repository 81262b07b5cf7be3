"""A small co-simulation handle on an FMI 2.0 or 3.0 CS unit (ours or any other), over fmpy's
``FMU2Slave`` / ``FMU3Slave``: parameters and signals by name, fixed-step stepping, state
save/restore. FMI 3 arrays are set whole by their name (``"p": [...]``, shorter sequences fill
the first elements) or element-wise with the FMI 2 style names (``"p[2]"``), so the same
names drive both versions. An FMI 3 structural parameter in ``start`` (the pimodel units'
``n_plays``, the size of their per-play arrays) is set in configuration mode, before the
others."""

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

__all__ = ["FMUUnit"]

# FMU variables renamed in the pimodel FMUs; the old names work for one release with a warning.
RENAMED = {"known_linear": "linear_play"}


class FMUUnit:
    """An instantiated, initialised co-simulation FMU.

    :meth:`set` / :meth:`get` take variable names; :meth:`step` calls ``doStep(t, h)`` and
    advances the unit's time. Errors from the FMU (fmi2Error) raise fmpy's
    ``FMICallException``; the FMU's log lines are kept in :attr:`log`, and with their FMI
    status and category in :attr:`log_entries` (``(status, category, message)``, e.g. the
    RadiusEstimator's health warning ``(1, "logStatusWarning", ...)`` at :meth:`close`).

    Parameters
    ----------
    path : str or Path
        The ``.fmu`` file (FMI 2.0 or 3.0, Co-Simulation).
    start : dict, optional
        Parameters and start values by variable name, set before initialisation (``n``,
        ``Ts``, ``p[1]`` ..., or a whole FMI 3 array ``"p": [...]``); FMI 3 structural
        parameters (``n_plays``) in configuration mode first.
    instance_name : str, optional
        The FMU instance's name (in its log). Default ``"unit"``.

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    ValueError
        Not a co-simulation FMU, or initialisation failed (the message holds the FMU's log).
    KeyError
        A ``start`` name that is no variable of the FMU.

    Examples
    --------
    The examples of this class need a built FMU (a compile of about a second), hence are
    skipped here; for PIHysteresis, ``doStep(0, Ts)`` processes the sample ``k = 0``:

    >>> import tempfile
    >>> from pimodel.fmu import build_fmus
    >>> path = build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0]  # doctest: +SKIP
    >>> unit = FMUUnit(path, {"n": 2, "p[2]": 0.5, "r[2]": 0.3})  # doctest: +SKIP
    >>> unit.set({"v": 1.0})  # doctest: +SKIP
    >>> unit.step(1e-3)  # doctest: +SKIP
    >>> unit.get(["y"])   # 1.0 * 1.0 + 0.5 * (1.0 - 0.3)  # doctest: +SKIP
    array([1.35])
    >>> unit.close()  # doctest: +SKIP
    >>> FMUUnit("missing.fmu")
    Traceback (most recent call last):
    ...
    FileNotFoundError: missing.fmu: no such FMU
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
        self.log_entries: list[tuple[int, str, str]] = []
        self.fmi3 = self.md.fmiVersion.startswith("3")
        ident = self.md.coSimulation.modelIdentifier
        if self.fmi3:
            self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=self._dir,
                                 modelIdentifier=ident, instanceName=instance_name)
            self.fmu.instantiate(loggingOn=True, logMessage=self._logger3)
            start = self._configure(start or {})
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
        text = message.decode(errors="replace") if message else ""
        self.log.append(text)
        self.log_entries.append((int(status), category.decode(errors="replace") if category
                                 else "", text))

    def _logger3(self, env, status, category, message) -> None:
        self._logger(env, None, status, category, message)

    def _configure(self, start: dict) -> dict:
        """Sets the structural parameters in ``start`` (FMI 3 configuration mode) and keeps
        their values for the array sizes; returns the other start values."""
        self.structural: dict[int, int] = {
            v.valueReference: int(v.start) for v in self.md.modelVariables
            if v.causality == "structuralParameter" and v.start is not None}
        items = [(k, x) for k, x in start.items()
                 if k in self.vars and self.vars[k].causality == "structuralParameter"]
        if items:
            self.fmu.enterConfigurationMode()
            try:
                for name, value in items:
                    v = self.vars[name]
                    if v.type != "UInt64":
                        raise TypeError(f"{name}: unsupported structural type {v.type}")
                    self.fmu.setUInt64([v.valueReference], [int(value)])
                    self.structural[v.valueReference] = int(value)
                self.fmu.exitConfigurationMode()
            except Exception as exc:
                self.fmu.freeInstance()
                raise ValueError(f"{self.path.name}: configuration failed: "
                                 f"{'; '.join(self.log) or exc}") from None
        done = {k for k, _ in items}
        return {k: x for k, x in start.items() if k not in done}

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

    def _size(self, v) -> int:
        """Elements of an FMI 3 array (a dimension bound to a structural parameter: its
        value as configured)."""
        return int(np.prod([int(d.start) if d.start is not None
                            else self.structural[d.valueReference] for d in v.dimensions]))

    def _get_array(self, v) -> np.ndarray:
        return np.array(self.fmu.getFloat64([v.valueReference], nValues=self._size(v)))

    def set(self, values: dict) -> None:
        """Set variables by name (Real/Float64, Integer/Int32 or Boolean).

        Parameters
        ----------
        values : dict
            Variable name -> value; an FMI 3 array takes a sequence (shorter ones fill the first
            elements) or element-wise names ``"p[2]"``. Old names in ``RENAMED`` work with a
            DeprecationWarning.

        Raises
        ------
        KeyError
            An unknown variable name.
        ValueError
            Too many values for an FMI 3 array.
        TypeError
            A variable of a type other than Real, Integer or Boolean.

        Examples
        --------
        >>> import tempfile
        >>> from pimodel.fmu import build_fmus
        >>> path = build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0]  # doctest: +SKIP
        >>> unit = FMUUnit(path, {"n": 2, "p[2]": 0.5, "r[2]": 0.3})  # doctest: +SKIP
        >>> unit.set({"v": 1.0})  # doctest: +SKIP
        >>> unit.step(1e-3)  # doctest: +SKIP
        >>> unit.get(["y"])  # doctest: +SKIP
        array([1.35])
        """
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
        """Values of the named Real or Integer variables (FMI 3 array elements as ``base[i]``).

        Parameters
        ----------
        names : sequence of str
            Variable names (1-based array elements ``"r_hat[1]"`` in both FMI versions; a
            whole FMI 3 array by its base name).

        Returns
        -------
        numpy.ndarray of float
            The values, in the order of ``names`` (a whole array contributes all its elements).

        Raises
        ------
        KeyError
            An unknown variable name.

        Examples
        --------
        >>> import tempfile
        >>> from pimodel.fmu import build_fmus
        >>> path = build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0]  # doctest: +SKIP
        >>> unit = FMUUnit(path, {"n": 2, "p[2]": 0.5, "r[2]": 0.3})  # doctest: +SKIP
        >>> unit.get(["p[2]", "r[2]"])  # doctest: +SKIP
        array([0.5, 0.3])
        """
        ints = [self._var(n)[0].type in ("Integer", "Int32") for n in names]
        if not self.fmi3:  # one getReal and one getInteger call
            vrs = np.array([self._var(n)[0].valueReference for n in names], dtype=np.int64)
            mask = np.array(ints, dtype=bool)
            out2 = np.empty(len(names))
            if not mask.all():
                out2[~mask] = self.fmu.getReal(vrs[~mask].tolist())
            if mask.any():
                out2[mask] = self.fmu.getInteger(vrs[mask].tolist())
            return out2
        out, arrays = [], {}
        for name, is_int in zip(names, ints, strict=True):
            v, i = self._var(name)
            if is_int:
                out.append(float(self.fmu.getInt32([v.valueReference])[0]))
            elif v.dimensions:
                if v.name not in arrays:
                    arrays[v.name] = self._get_array(v)
                out.extend(arrays[v.name] if i is None else [arrays[v.name][i]])
            else:
                out.append(self.fmu.getFloat64([v.valueReference])[0])
        return np.array(out)

    def step(self, h: float) -> None:
        """One communication step of length ``h`` from the current time.

        Parameters
        ----------
        h : float
            Communication step [s]; a pimodel unit processes every sample ``k`` with ``k Ts`` in
            ``[t, t + h)``.

        Raises
        ------
        ValueError
            The FMU's ``doStep`` failed (the message holds its last log lines).

        Examples
        --------
        >>> import tempfile
        >>> from pimodel.fmu import build_fmus
        >>> path = build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0]  # doctest: +SKIP
        >>> unit = FMUUnit(path, {"n": 2, "p[2]": 0.5, "r[2]": 0.3})  # doctest: +SKIP
        >>> unit.step(1e-3)  # doctest: +SKIP
        >>> unit.time  # doctest: +SKIP
        0.001
        """
        try:
            self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=h)
        except Exception:
            raise ValueError(f"{self.path.name}: doStep at t = {self.time:g} failed: "
                             f"{'; '.join(self.log[-3:])}") from None
        self.time += h

    def get_state(self):
        """Save the FMU's state (``fmi2GetFMUstate``) together with the unit's time.

        Returns
        -------
        tuple
            ``(FMU state handle, time)``, for :meth:`set_state`; release it with
            :meth:`free_state`.

        Examples
        --------
        >>> import tempfile
        >>> from pimodel.fmu import build_fmus
        >>> path = build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0]  # doctest: +SKIP
        >>> unit = FMUUnit(path, {"n": 2, "p[2]": 0.5, "r[2]": 0.3})  # doctest: +SKIP
        >>> unit.set({"v": 1.0})  # doctest: +SKIP
        >>> unit.step(1e-3)  # doctest: +SKIP
        >>> saved = unit.get_state()  # doctest: +SKIP
        >>> unit.set({"v": 0.0})  # doctest: +SKIP
        >>> unit.step(1e-3)  # doctest: +SKIP
        >>> unit.get(["y"])  # doctest: +SKIP
        array([0.15])
        >>> unit.set_state(saved)  # doctest: +SKIP
        >>> unit.set({"v": 0.0})  # doctest: +SKIP
        >>> unit.step(1e-3)  # doctest: +SKIP
        >>> unit.get(["y"])   # the same step again  # doctest: +SKIP
        array([0.15])
        >>> unit.free_state(saved)  # doctest: +SKIP
        """
        return self.fmu.getFMUState(), self.time

    def set_state(self, state) -> None:
        """Restore a state saved by :meth:`get_state` (the FMU's state, inputs and time).

        Parameters
        ----------
        state : tuple
            ``(FMU state handle, time)`` from :meth:`get_state`.

        Examples
        --------
        >>> import tempfile
        >>> from pimodel.fmu import build_fmus
        >>> path = build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0]  # doctest: +SKIP
        >>> unit = FMUUnit(path, {"n": 2, "p[2]": 0.5, "r[2]": 0.3})  # doctest: +SKIP
        >>> saved = unit.get_state()  # doctest: +SKIP
        >>> unit.step(1e-3)  # doctest: +SKIP
        >>> unit.set_state(saved)  # doctest: +SKIP
        >>> unit.time  # doctest: +SKIP
        0.0
        """
        self.fmu.setFMUState(state[0])
        self.time = state[1]

    def free_state(self, state) -> None:
        """Release a state saved by :meth:`get_state`.

        Parameters
        ----------
        state : tuple
            ``(FMU state handle, time)`` from :meth:`get_state`; not usable afterwards.

        Examples
        --------
        >>> import tempfile
        >>> from pimodel.fmu import build_fmus
        >>> path = build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0]  # doctest: +SKIP
        >>> unit = FMUUnit(path, {"n": 2, "p[2]": 0.5, "r[2]": 0.3})  # doctest: +SKIP
        >>> unit.free_state(unit.get_state())  # doctest: +SKIP
        """
        self.fmu.freeFMUState(state[0])

    def close(self) -> None:
        """Terminate and free the FMU instance and delete its extracted files.

        Examples
        --------
        >>> import tempfile
        >>> from pimodel.fmu import build_fmus
        >>> path = build_fmus(tempfile.mkdtemp(), ["PIHysteresis"])[0]  # doctest: +SKIP
        >>> unit = FMUUnit(path, {"n": 2, "p[2]": 0.5, "r[2]": 0.3})  # doctest: +SKIP
        >>> unit.close()  # doctest: +SKIP
        """
        try:
            self.fmu.terminate()
        finally:
            self.fmu.freeInstance()
            shutil.rmtree(self._dir, ignore_errors=True)
