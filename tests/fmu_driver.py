"""Drive a pimodel FMU through raw FMI 2 / FMI 3 calls from JSON action lists, in a subprocess.

A crash (SIGSEGV) or a hang inside the FMU must fail a test, not kill pytest, so the calls run
in a child process (``python tests/fmu_driver.py`` reading a job from stdin) with a timeout;
:func:`run_job` starts it and returns one result list per run, or raises
:class:`DriverFailure` naming the run that crashed or hung.

A run is a list of actions ``[name, *args]``; each gives ``{"call", "status", "log", ...}``
with ``status`` the FMI status (0 OK, 3 Error, -1 skipped by the driver) and ``log`` the
messages the FMU logged during the call. Serialized states can be corrupted (:data:`MUTATIONS`):
bit flips, truncation, extension, random bytes, or a field edit with the checksum recomputed, so
that the FMU's semantic checks (not only its checksum) are exercised. The field offsets come
from a ctypes mirror of the common part of ``pim_unit`` (``fmu/src/fmi/pim_unit.h``), verified
against a real state by ``tests/test_fuzz_fmu.py``.
"""

from __future__ import annotations

import ctypes
import json
import math
import random
import shutil
import struct
import subprocess
import sys
import tempfile

NMAX = 64
STATUS_SKIPPED = -1
MUTATIONS = ("flip", "truncate", "extend", "random", "edit")


class StateHeader(ctypes.Structure):
    """Header of a serialized pimodel FMU state (pim_state_header)."""

    _fields_ = [("magic", ctypes.c_char * 8), ("version", ctypes.c_uint32),
                ("byte_order", ctypes.c_uint32), ("model", ctypes.c_uint32),
                ("fmi", ctypes.c_uint32), ("nmax", ctypes.c_uint32),
                ("est_win", ctypes.c_uint32), ("unit_size", ctypes.c_uint64),
                ("est_size", ctypes.c_uint64), ("token", ctypes.c_char * 64)]


class UnitPrefix(ctypes.Structure):
    """The common part of pim_unit, the same in every unit (fmu/src/fmi/pim_unit.h); the unit's
    own fields (fmu/src/units/<Unit>/fields.h) and the message follow."""

    _fields_ = [("Ts", ctypes.c_double), ("z0", ctypes.c_double),
                ("p", ctypes.c_double * NMAX), ("r", ctypes.c_double * NMAX),
                ("in1", ctypes.c_double), ("in2", ctypes.c_double), ("out1", ctypes.c_double),
                ("out2", ctypes.c_double), ("time", ctypes.c_double),
                ("k_next", ctypes.c_int64), ("n", ctypes.c_int), ("mode", ctypes.c_int),
                ("n_plays", ctypes.c_uint64), ("inv_Ts", ctypes.c_double),
                ("t_tol", ctypes.c_double), ("fast_t_tol", ctypes.c_double),
                ("fast_in_vr", ctypes.c_uint64), ("x_next", ctypes.c_double)]


FIELD_FORMAT = {"n": "i", "mode": "i", "k_next": "q", "n_plays": "Q",
                "fast_in_vr": "Q"}  # others are doubles


def field_offset(field: str, index: int = 0) -> int:
    """Byte offset of ``field[index]`` in a serialized state."""
    return ctypes.sizeof(StateHeader) + getattr(UnitPrefix, field).offset + 8 * index


def read_field(blob: bytes, field: str, index: int = 0):
    fmt = FIELD_FORMAT.get(field, "d")
    return struct.unpack_from("=" + fmt, blob, field_offset(field, index))[0]


def fnv1a(data: bytes) -> int:
    h = 0xCBF29CE484222325
    for b in data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


def edit_field(blob: bytes, field: str, value, index: int = 0) -> bytes:
    """``blob`` with ``field[index]`` set to ``value`` and the checksum recomputed."""
    out = bytearray(blob)
    struct.pack_into("=" + FIELD_FORMAT.get(field, "d"), out, field_offset(field, index), value)
    struct.pack_into("=Q", out, len(out) - 8, fnv1a(bytes(out[:-8])))
    return bytes(out)


def mutate(blob: bytes, spec: dict) -> bytes:
    """Corrupt a serialized state as ``spec`` says (kind in :data:`MUTATIONS`)."""
    kind = spec["kind"]
    rng = random.Random(spec.get("seed", 0))
    if kind == "flip":
        out = bytearray(blob)
        bit = spec.get("bit", rng.randrange(8 * len(blob))) % (8 * len(blob))
        out[bit // 8] ^= 1 << (bit % 8)
        return bytes(out)
    if kind == "truncate":
        return blob[: spec.get("length", rng.randrange(len(blob)))]
    if kind == "extend":
        return blob + bytes(rng.randrange(256) for _ in range(spec.get("extra", 8)))
    if kind == "random":
        return bytes(rng.randrange(256) for _ in range(spec.get("length", len(blob))))
    if kind == "edit":
        index = 0
        if spec["field"] in ("p", "r"):  # an element in use (index < n)
            n = read_field(blob, "n")
            index = spec.get("index", 0) % n if 1 <= n <= NMAX else 0
        return edit_field(blob, spec["field"], decode_float(spec["value"]), index)
    raise ValueError(f"mutation kind: expected one of {MUTATIONS}, got {kind!r}")


def decode_float(x):
    """JSON carries nan/inf as strings."""
    if isinstance(x, str):
        return float(x)
    return x


class Driver:
    """One FMU binary, instantiated anew for each run."""

    def __init__(self, fmu_path: str):
        from fmpy import extract, read_model_description

        self.md = read_model_description(fmu_path)
        self.fmi3 = self.md.fmiVersion.startswith("3")
        self.dir = extract(fmu_path, tempfile.mkdtemp(prefix="pimodel_fuzz_"))
        ident = self.md.coSimulation.modelIdentifier
        if self.fmi3:
            from fmpy.fmi3 import FMU3Slave

            self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=self.dir,
                                 modelIdentifier=ident, instanceName="fuzz")
        else:
            from fmpy.fmi2 import FMU2Slave

            self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                                 modelIdentifier=ident, instanceName="fuzz")
        self.log: list[str] = []

    # -- callbacks ---------------------------------------------------------------------------
    def _log2(self, env, instance, status, category, message) -> None:
        self.log.append(message.decode(errors="replace") if message else "")

    def _log3(self, env, status, category, message) -> None:
        self._log2(env, None, status, category, message)

    def instantiate(self) -> None:
        if self.fmi3:
            self.fmu.instantiate(loggingOn=True, logMessage=self._log3)
        else:
            from fmpy import calloc, free
            from fmpy.fmi2 import (
                fmi2CallbackAllocateMemoryTYPE,
                fmi2CallbackFreeMemoryTYPE,
                fmi2CallbackFunctions,
                fmi2CallbackLoggerTYPE,
            )

            cb = fmi2CallbackFunctions()
            cb.logger = fmi2CallbackLoggerTYPE(self._log2)
            cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            self._cb2 = cb
            self.fmu.instantiate(loggingOn=True, callbacks=cb)
        if not self.fmu.component:
            raise RuntimeError("instantiation failed")

    # -- one run -----------------------------------------------------------------------------
    def run(self, actions: list) -> list[dict]:
        self.states: dict[int, object] = {}  # slot -> FMU state handle
        self.blobs: dict[int, bytes] = {}  # slot -> serialized bytes
        self.time = 0.0  # the time a correct master would pass to the next doStep
        self.instantiate()
        out = []
        try:
            for action in actions:
                out.append(self._do(action))
        finally:
            for st in self.states.values():
                self._call(lambda s=st: self.fmu.freeFMUState(s))
            (self.fmu.fmi3FreeInstance if self.fmi3 else self.fmu.fmi2FreeInstance)(
                self.fmu.component)
        return out

    def _call(self, fn):
        """(status, value) of an FMI call through fmpy (exceptions carry the status)."""
        from fmpy.fmi1 import FMICallException

        try:
            return 0, fn()
        except FMICallException as exc:
            return int(exc.status), None

    def _state_blob(self, handle) -> bytes:
        size = ctypes.c_size_t()
        fn = (self.fmu.fmi3SerializedFMUStateSize if self.fmi3
              else self.fmu.fmi2SerializedFMUstateSize)
        fn(self.fmu.component, handle, ctypes.byref(size))
        return ctypes.string_at(handle.value, size.value)

    def _do(self, action: list) -> dict:
        name, *args = action
        args = [decode_float(a) for a in args]
        first_log = len(self.log)
        rec: dict = {"call": name}
        status, value = self._dispatch(name, args, rec)
        rec["status"] = status
        if value is not None:
            rec["value"] = [x if math.isfinite(x) else str(x) for x in value] \
                if isinstance(value, list) else value
        rec["log"] = self.log[first_log:]
        return rec

    def _dispatch(self, name: str, args: list, rec: dict):  # noqa: C901 - one branch per call
        f = self.fmu
        if name == "setup":  # FMI 2 setupExperiment(t0[, tStop])
            if self.fmi3:
                return STATUS_SKIPPED, None
            st = self._call(lambda: f.setupExperiment(startTime=args[0],
                                                      stopTime=args[1] if len(args) > 1
                                                      else None))
            if st[0] == 0:
                self.time = args[0]
            return st
        if name == "enter_init":
            if self.fmi3:
                t0 = args[0] if args else 0.0
                st = self._call(lambda: f.enterInitializationMode(startTime=t0))
                if st[0] == 0:
                    self.time = t0
                return st
            return self._call(f.enterInitializationMode)
        if name == "exit_init":
            return self._call(f.exitInitializationMode)
        if name == "terminate":
            return self._call(f.terminate)
        if name == "reset":
            st = self._call(f.reset)
            self.time = 0.0
            return st
        if name in ("set_real", "get_real"):
            vr, values = int(args[0]), [float(x) for x in args[1:]]
            if name == "set_real":
                setter = f.setFloat64 if self.fmi3 else f.setReal
                return self._call(lambda: setter([vr], values))
            count = int(values[0]) if values else 1
            return self._call(lambda: f.getFloat64([vr], nValues=count) if self.fmi3
                              else f.getReal([vr]))
        if name in ("set_int", "get_int"):
            vr = int(args[0])
            if name == "set_int":
                setter = f.setInt32 if self.fmi3 else f.setInteger
                return self._call(lambda: setter([vr], [int(args[1])]))
            return self._call(lambda: (f.getInt32 if self.fmi3 else f.getInteger)([vr]))
        if name in ("set_bool", "get_bool"):
            vr = int(args[0])
            if name == "set_bool":
                return self._call(lambda: f.setBoolean([vr], [bool(args[1])]))
            return self._call(lambda: [int(x) for x in f.getBoolean([vr])])
        if name in ("step", "step_next"):  # step(t, h) / step_next(h) at the master's time
            t, h = (args[0], args[1]) if name == "step" else (self.time, args[0])
            st = self._call(lambda: f.doStep(currentCommunicationPoint=t,
                                             communicationStepSize=h))
            if st[0] == 0:
                self.time = t + h
            return st[0], None
        if name == "get_state":
            slot = int(args[0])
            old = self.states.pop(slot, None)
            if old is not None:
                self._call(lambda: f.freeFMUState(old))
            st, handle = self._call(f.getFMUState)
            if st == 0:
                self.states[slot] = handle
            return st, None
        if name == "set_state":
            handle = self.states.get(int(args[0]))
            if handle is None:
                return STATUS_SKIPPED, None
            blob = self._state_blob(handle)
            st = self._call(lambda: f.setFMUState(handle))
            if st[0] == 0:
                self.time = read_field(blob, "time")
            return st
        if name == "serialize":
            handle = self.states.get(int(args[0]))
            if handle is None:
                return STATUS_SKIPPED, None
            st, blob = self._call(lambda: f.serializeFMUState(handle))
            if st == 0:
                self.blobs[int(args[1])] = blob
            return st, None
        if name == "deserialize":  # deserialize(blob slot, state slot[, mutation])
            blob = self.blobs.get(int(args[0]))
            if blob is None:
                return STATUS_SKIPPED, None
            rec["blob_mode"] = read_field(blob, "mode")
            if len(args) > 2:
                blob = mutate(blob, args[2])
            rec["changed"] = blob != self.blobs[int(args[0])]
            des = f.deserializeFMUState if self.fmi3 else f.deSerializeFMUstate
            st, handle = self._call(lambda: des(blob))
            if st == 0:
                slot = int(args[1])
                old = self.states.pop(slot, None)
                if old is not None:
                    self._call(lambda: f.freeFMUState(old))
                self.states[slot] = handle
            return st, None
        if name == "corrupt_state":  # corrupt_state(state slot, mutation): in memory, same size
            handle = self.states.get(int(args[0]))
            if handle is None:
                return STATUS_SKIPPED, None
            blob = self._state_blob(handle)
            rec["blob_mode"] = read_field(blob, "mode")
            new = mutate(blob, args[1])[: len(blob)]
            new = new + blob[len(new):]
            rec["changed"] = new != blob
            ctypes.memmove(handle.value, new, len(new))
            return 0, None
        if name == "_segfault":  # proves that run_job turns a crash into a failure
            ctypes.string_at(1)
        if name == "_sleep":  # proves that run_job turns a hang into a failure
            import time

            time.sleep(args[0])
            return 0, None
        raise ValueError(f"unknown action {name!r}")


class DriverFailure(AssertionError):
    """The child process crashed, hung or died before reporting every run."""


def run_job(fmu_path, runs: list[list], *, timeout: float = 120.0,
            env: dict | None = None) -> list[list[dict]]:
    """Run ``runs`` (lists of actions) against the FMU in a child process (environment
    ``env``, default this one's).

    Returns one result list per run. Raises :class:`DriverFailure` on a crash (signal or
    non-zero exit), a hang (``timeout`` seconds) or missing results, naming the first run
    without a result."""
    job = json.dumps({"fmu": str(fmu_path), "runs": runs}, allow_nan=False,
                     default=_json_default)
    try:
        proc = subprocess.run([sys.executable, __file__], input=job, capture_output=True,
                              text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired as exc:
        done = (exc.stdout or b"").count(b"\n") if isinstance(exc.stdout, bytes) else \
            (exc.stdout or "").count("\n")
        raise DriverFailure(f"hang: no answer within {timeout} s; run {done} did not finish: "
                            f"{_short(runs[done] if done < len(runs) else '?')}") from None
    results = [json.loads(line) for line in proc.stdout.splitlines() if line.strip()]
    if proc.returncode != 0 or len(results) != len(runs):
        k = len(results)
        raise DriverFailure(f"crash: exit status {proc.returncode} after {k} of {len(runs)} "
                            f"runs; run {k}: {_short(runs[k] if k < len(runs) else '?')}\n"
                            f"{proc.stderr[-2000:]}")
    return results


def _short(run) -> str:
    """The last actions of a run (the crash or hang is at its end)."""
    text = repr(run)
    return text if len(text) < 1500 else "[... " + text[-1500:]


def _json_default(x):
    raise TypeError(f"not JSON serialisable: {x!r}")


def main() -> int:
    job = json.loads(sys.stdin.read())
    drv = Driver(job["fmu"])
    try:
        for actions in job["runs"]:
            print(json.dumps(drv.run(actions)), flush=True)
    finally:
        drv.fmu.freeLibrary()
        shutil.rmtree(drv.dir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
