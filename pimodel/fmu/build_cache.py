"""A content-addressed cache of the compiler's outputs (objects, shared libraries) for
:func:`pimodel.fmu.build.build_fmus`, so that an identical object or binary is compiled once.

An entry's key (:func:`cache_key`) is the SHA-256 of everything that decides the output: the
flags, the compiler's identity (:func:`compiler_identity`: its resolved path and ``--version``),
the platform (:data:`PLATFORM_TAG`), and the names and contents of the input files (a source
and every header it can include; a link's objects as their own keys). A change in any of them
is a miss; the cache never looks at file times.

An entry is one file ``<key>``: a magic line, the SHA-256 of the payload, the payload. It is
written to a temporary name in the cache folder and renamed into place (atomic on POSIX), and
its digest is checked on every read, so a partial or corrupt entry (a crash, a full disk, a
truncated file) is a miss: the output is rebuilt and the entry rewritten. Processes sharing a
folder (pytest-xdist workers, parallel builds) need no lock: two that miss the same key both
compile, and the second rename replaces identical bytes.

The folder (:func:`cache_dir`): ``$PIMODEL_BUILD_CACHE`` when set (``off`` or an empty value
turns caching off), else ``$XDG_CACHE_HOME/pimodel/build`` (``~/.cache/pimodel/build``).
Entries are never evicted; deleting the folder is always safe.
"""

from __future__ import annotations

import functools
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path

__all__ = ["ENV_VAR", "PLATFORM_TAG", "cache_dir", "cache_key", "cached_file",
           "compiler_identity", "read_entry", "write_entry"]

ENV_VAR = "PIMODEL_BUILD_CACHE"  # the cache folder; "off" or "" turns caching off
PLATFORM_TAG = f"{sys.platform}-{platform.machine()}"  # what the binaries run on
_MAGIC = b"pimodel build cache 1\n"
_DIGEST = hashlib.sha256().digest_size


def cache_dir() -> Path | None:
    """The cache folder, or None when caching is off.

    Returns
    -------
    pathlib.Path or None
        ``$PIMODEL_BUILD_CACHE`` when set (None for ``off`` or an empty value), else
        ``$XDG_CACHE_HOME/pimodel/build`` (default ``~/.cache/pimodel/build``). Not created
        here.

    Examples
    --------
    >>> import os
    >>> from unittest import mock
    >>> with mock.patch.dict(os.environ, {"PIMODEL_BUILD_CACHE": "off"}):
    ...     cache_dir() is None
    True
    >>> with mock.patch.dict(os.environ, {"PIMODEL_BUILD_CACHE": "/tmp/pimodel-cache"}):
    ...     cache_dir().as_posix()
    '/tmp/pimodel-cache'
    """
    value = os.environ.get(ENV_VAR)
    if value is not None:
        return None if value.strip() in ("", "off") else Path(value).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "pimodel" / "build"


def compiler_identity(cc: str) -> str:
    """The compiler's identity for cache keys: its resolved path and its ``--version`` output.

    Parameters
    ----------
    cc : str
        The compiler command (a name on PATH or a path).

    Returns
    -------
    str
        ``"<resolved path>\\n<--version output>"`` (``--version`` asked once per process and
        resolved path).

    Raises
    ------
    RuntimeError
        When ``cc`` is not found or ``cc --version`` fails.

    Examples
    --------
    >>> from pimodel.fmu.build import find_compiler
    >>> compiler_identity(find_compiler()).startswith("/")
    True
    """
    path = shutil.which(cc)
    if path is None:
        raise RuntimeError(f"compiler: {cc!r} not found on PATH")
    return _identity(os.path.realpath(path))


@functools.cache
def _identity(path: str) -> str:
    proc = subprocess.run([path, "--version"], capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"compiler: '{path} --version' failed: {proc.stderr.strip()}")
    return f"{path}\n{proc.stdout}"


def cache_key(*parts: str, files: Iterable[Path] = ()) -> str:
    """The key of an output: SHA-256 over ``parts`` (flags, compiler identity, other keys),
    :data:`PLATFORM_TAG` and the names and contents of ``files``.

    Parameters
    ----------
    *parts : str
        Everything else the output depends on, in a fixed order.
    files : iterable of pathlib.Path
        The input files (read whole); their names and order count.

    Returns
    -------
    str
        64 hexadecimal digits.

    Examples
    --------
    >>> a, b = cache_key("-O3"), cache_key("-O2")
    >>> len(a), a == b
    (64, False)
    """
    h = hashlib.sha256()

    def field(data: bytes) -> None:  # length-prefixed: no two inputs give the same stream
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)

    for part in (PLATFORM_TAG, *parts):
        field(part.encode())
    for f in files:
        field(Path(f).name.encode())
        field(Path(f).read_bytes())
    return h.hexdigest()


def read_entry(folder: Path, key: str) -> bytes | None:
    """The payload of the entry ``key`` in ``folder``, or None when it is absent, partial or
    corrupt (its digest does not match).

    Parameters
    ----------
    folder : pathlib.Path
        The cache folder.
    key : str
        The entry's key (:func:`cache_key`).

    Returns
    -------
    bytes or None
        The payload.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> write_entry(folder, "k", b"object code")
    >>> read_entry(folder, "k"), read_entry(folder, "other")
    (b'object code', None)
    >>> _ = (folder / "k").write_bytes((folder / "k").read_bytes()[:-3])  # truncated
    >>> read_entry(folder, "k") is None
    True
    """
    try:
        data = (folder / key).read_bytes()
    except OSError:
        return None
    head = len(_MAGIC) + _DIGEST
    if len(data) < head or not data.startswith(_MAGIC):
        return None
    payload = data[head:]
    if hashlib.sha256(payload).digest() != data[len(_MAGIC):head]:
        return None
    return payload


def write_entry(folder: Path, key: str, payload: bytes) -> None:
    """Store ``payload`` as the entry ``key`` in ``folder`` (created): written to a temporary
    file in the folder, then renamed into place, so a reader sees the old entry, no entry or
    the whole new one.

    Parameters
    ----------
    folder : pathlib.Path
        The cache folder.
    key : str
        The entry's key (:func:`cache_key`).
    payload : bytes
        The output's bytes.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> write_entry(folder, "k", b"x")
    >>> read_entry(folder, "k")
    b'x'
    """
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{key[:16]}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(_MAGIC + hashlib.sha256(payload).digest() + payload)
        os.replace(tmp, folder / key)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def cached_file(key: str, out: Path, make: Callable[[], None]) -> bool:
    """Write the output ``out`` from the cache entry ``key``, or by ``make()`` and then store it.

    Parameters
    ----------
    key : str
        The output's key (:func:`cache_key`).
    out : pathlib.Path
        The file to produce.
    make : callable
        Writes ``out`` (runs the compiler); called on a miss or when caching is off. A cache
        that cannot be written is skipped.

    Returns
    -------
    bool
        True for a hit (``make`` not called).

    Examples
    --------
    >>> import os, tempfile
    >>> from unittest import mock
    >>> out = Path(tempfile.mkdtemp()) / "a.o"
    >>> with mock.patch.dict(os.environ, {"PIMODEL_BUILD_CACHE": tempfile.mkdtemp()}):
    ...     cached_file("k", out, lambda: out.write_bytes(b"built")), cached_file("k", out, None)
    (False, True)
    """
    folder = cache_dir()
    payload = None if folder is None else read_entry(folder, key)
    if payload is not None:
        out.write_bytes(payload)
        return True
    make()
    if folder is not None:
        try:
            write_entry(folder, key, out.read_bytes())
        except OSError:  # an unwritable cache (read-only home, full disk) only costs time
            pass
    return False
