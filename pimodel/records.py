"""Measured records: load and save ``t, v, y`` data (CSV, NPZ, MATLAB ``.mat``), validated.

A record holds time ``t`` [s], actuator input ``v`` (e.g. V) and measured output ``y``
(e.g. um), sampled at the same instants; extra columns are kept in ``Record.extra`` under their
own names (a leftover column named ``t``, ``v`` or ``y`` never replaces the chosen ones).
Validation: at least two samples, equal lengths, finite numbers, strictly increasing time,
uniform sampling (every interval within 1 % of the median).

File formats (by suffix):

- CSV (any other suffix): a header line of column names, then one data row per line.
- ``.npz``: one array per column, the key is the column name (``np.savez(f, t=t, v=v, y=y)``;
  :func:`save_record` writes this).
- ``.mat``: MATLAB v5 (read with ``scipy.io``) or v7.3 (HDF5: needs ``h5py``): one numeric
  vector variable per column, the variable name is the column name.

In ``.npz`` and ``.mat`` files a column may be shaped (N,), (N, 1) or (1, N); other variables
(scalars, matrices, text, vectors of another length) are left out unless chosen as a column.
Errors name the file, the line as an editor counts it (the header is line 1) with the data row
(1-based, header excluded), and the column.
"""

from __future__ import annotations

import bisect
import csv
import io
import warnings
import zipfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "DataError",
    "load_record",
    "Record",
    "sample_time",
    "save_record",
]

DEFAULT_COLUMNS = ("t", "v", "y")
SAMPLING_TOLERANCE = 0.01  # largest relative deviation of a sample interval from the median
CHUNK_ROWS = 1 << 16  # CSV rows parsed per block (bounds the Python objects alive at once)
FAST_BLOCK_BYTES = 1 << 23  # bytes of a regular CSV file parsed per block by NumPy (8 MiB)


class DataError(ValueError):
    """A record file or array that does not meet the record rules (a ``ValueError``).

    The message names the source, the row and the column.

    Examples
    --------
    >>> try:
    ...     Record(np.array([0.0, 0.0]), np.zeros(2), np.zeros(2))
    ... except DataError as err:
    ...     print(err)
    <array>: row 2, column 't': time 0.0 does not increase strictly (previous 0.0)
    """


def _vector(name: str, values, source: str) -> np.ndarray:
    """``values`` as a 1-D float array; (N,), (N, 1) and (1, N) are accepted."""
    arr = np.asarray(values)
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.reshape(-1)
    if arr.ndim != 1:
        raise DataError(f"{source}: column '{name}' must be a vector of shape (N,), (N, 1) or "
                        f"(1, N), got shape {arr.shape}")
    if arr.dtype.kind not in "biuf":
        raise DataError(f"{source}: column '{name}' has dtype {arr.dtype}; expected numbers")
    return arr.astype(float, copy=False)


@dataclass
class Record:
    """A sampled input/output record: ``v[k]`` applied and ``y[k]`` measured at ``t[k]``.

    Parameters
    ----------
    t : array_like of float, shape (N,)
        Sample times [s], strictly increasing and evenly spaced, N >= 2.
    v : array_like of float, shape (N,)
        Input samples (input unit).
    y : array_like of float, shape (N,)
        Measured output samples (output unit).
    extra : dict of str to array_like, optional
        Further columns of the same length, by name (any name, ``"y"`` included: an extra
        column never replaces ``t``, ``v`` or ``y``).
    source : str, optional
        Where the record came from (named in error messages).
    has_output : bool, optional
        False when the file had no output column and ``y`` is zeros.

    Raises
    ------
    DataError
        If a column is not 1-D or finite, the lengths differ, there are fewer than 2 samples,
        or ``t`` does not increase evenly.

    Examples
    --------
    >>> rec = Record(np.arange(4) * 0.1, [0.0, 1.0, 2.0, 1.0], [0.0, 0.5, 1.5, 1.0])
    >>> len(rec), round(rec.dt, 12)
    (4, 0.1)
    """

    t: np.ndarray
    v: np.ndarray
    y: np.ndarray
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    source: str = "<array>"
    has_output: bool = True  # False: the file had no output column and ``y`` is zeros

    def __post_init__(self):
        names = ["t", "v", "y", *self.extra]
        arrays = _validate_columns(names, [self.t, self.v, self.y, *self.extra.values()],
                                   self.source)
        self.t, self.v, self.y = arrays[:3]
        self.extra = dict(zip(self.extra, arrays[3:], strict=True))

    @classmethod
    def from_arrays(cls, t, v, y=None, extra: Mapping | None = None, *,
                    source: str = "<array>") -> Record:
        """A record from vectors shaped (N,), (N, 1) or (1, N), e.g. from ``scipy.io.loadmat``.

        Parameters
        ----------
        t, v : array_like of float
            Sample times [s] and input samples.
        y : array_like of float, optional
            Output samples; None gives zeros and ``has_output=False``.
        extra : dict of str to array_like, optional
            Further columns, each shaped like ``t``.
        source : str, optional
            Named in error messages.

        Returns
        -------
        Record
            The validated record with 1-D columns.

        Raises
        ------
        DataError
            A column of another shape, non-numeric, or the rules of :class:`Record`.

        Examples
        --------
        >>> rec = Record.from_arrays(np.arange(3.0)[None, :] * 0.1, [[0.0], [1.0], [0.0]])
        >>> rec.t.shape, rec.v.shape, rec.has_output
        ((3,), (3,), False)
        """
        tt, vv = _vector("t", t, source), _vector("v", v, source)
        yy = np.zeros(vv.shape) if y is None else _vector("y", y, source)
        more = {k: _vector(k, a, source) for k, a in (extra or {}).items()}
        return cls(tt, vv, yy, more, source=source, has_output=y is not None)

    def __len__(self) -> int:
        return self.t.size

    @property
    def dt(self) -> float:
        """Sample time [s]: exact where the clock is regular (:func:`sample_time`); computed
        once per time column (the diagnosis asks for it per segment)."""
        key = (id(self.t), self.t.size, float(self.t[0]), float(self.t[-1]))
        cached = self.__dict__.get("_dt_cache")
        if cached is None or cached[0] != key:
            cached = self.__dict__["_dt_cache"] = (key, sample_time(self.t))
        return cached[1]

    def slice(self, start: int | None = None, stop: int | None = None) -> Record:
        """Samples ``start:stop`` as a new record (extras included).

        Parameters
        ----------
        start : int, optional
            First sample kept (Python slice rules).
        stop : int, optional
            Sample after the last one kept.

        Returns
        -------
        Record
            The sliced record; its ``source`` says ``[start:stop]``.

        Raises
        ------
        DataError
            If the slice keeps fewer than 2 samples.

        Examples
        --------
        >>> rec = Record(np.arange(4) * 0.1, [0.0, 1.0, 2.0, 1.0], [0.0, 0.5, 1.5, 1.0])
        >>> part = rec.slice(1, 3)
        >>> part.v, part.source
        (array([1., 2.]), '<array>[1:3]')
        """
        s = slice(start, stop)
        return Record(
            self.t[s], self.v[s], self.y[s], {k: a[s] for k, a in self.extra.items()},
            source=f"{self.source}[{start}:{stop}]", has_output=self.has_output,
        )

    def split(self, fraction: float = 0.5) -> tuple[Record, Record]:
        """Cut the record in two at a fraction of its samples: (train, validate).

        The first part, samples ``0 .. k-1`` with ``k = round(fraction * N)``, is for fitting
        (train); the second, samples ``k .. N-1``, for validation. Time stamps are kept as
        recorded, so the validate part starts at ``t[k]``, in whatever state the first part
        left the stage (``pimodel diagnose --initial-state unknown`` leaves its start-up out).

        Parameters
        ----------
        fraction : float
            Share of the samples in the train part, ``0 < fraction < 1``.

        Returns
        -------
        tuple of Record
            ``(train, validate)``; their sources say ``[0:k]`` and ``[k:None]``.

        Raises
        ------
        ValueError
            ``fraction`` outside (0, 1), or a part with fewer than 2 samples.

        Examples
        --------
        >>> rec = Record(np.arange(10) * 0.1, np.arange(10.0), np.arange(10.0))
        >>> train, validate = rec.split(0.6)
        >>> len(train), len(validate), round(float(validate.t[0]), 12)
        (6, 4, 0.6)
        """
        if isinstance(fraction, bool) or not isinstance(fraction, int | float) or \
                not 0 < fraction < 1:
            raise ValueError(f"fraction: expected a number between 0 and 1 (the train share), "
                             f"got {fraction!r}")
        k = round(fraction * len(self))
        if k < 2 or len(self) - k < 2:
            raise ValueError(f"fraction: {fraction} of {len(self)} samples leaves {k} train and "
                             f"{len(self) - k} validate samples; each part needs at least 2")
        return self.slice(0, k), self.slice(k, None)


CHECK_CHUNK = 1 << 16  # samples per block of the time column's checks (their temporaries)


def _blocks(n: int):
    """Slices of ``CHECK_CHUNK`` samples covering ``range(n)``: the checks of a long time
    column are made a block at a time (a maximum or an "all" does not depend on the
    grouping), so they hold a few blocks, not columns of the record's length."""
    return (slice(i, min(i + CHECK_CHUNK, n)) for i in range(0, n, CHECK_CHUNK))


def _largest_magnitude(t: np.ndarray) -> float:
    """``max |t[k]|`` without a column of magnitudes (``max(t)`` or ``-min(t)``: exact)."""
    return max(float(np.max(t)), -float(np.min(t)))


def _resolution(t: np.ndarray) -> float:
    """The time column's resolution [s]: the coarsest decimal step all its values sit on (to a
    few ulps), else a few ulps of its largest value."""
    ulps = 8.0 * np.spacing(_largest_magnitude(t) or 1.0)
    for digits in range(16):
        if all(np.all(np.abs(t[c] - np.round(t[c], digits)) <= ulps) for c in _blocks(t.size)):
            return max(0.5 * 10.0 ** -digits, ulps)
    return ulps


def sample_time(t) -> float:
    """The sample time [s] of the times ``t``: exact where the clock is regular.

    The rate ``1 / mean(diff(t))`` (and the interval itself) rounded to the fewest significant
    digits such that every ``t[k]`` equals ``t[0] + k * Ts`` to the resolution of the time
    column (its decimal step, or a few ulps) plus the rounding of a clock that adds ``Ts`` per
    sample (one ulp per sample); e.g. ``2e-4`` for a 5 kHz record rather than
    ``1.9999999999997797e-4``, and ``1 / 3000`` for a 3 kHz one. When no rounding fits (a
    jittering clock), the median interval.

    Parameters
    ----------
    t : array_like of float, shape (N,)
        Strictly increasing sample times [s], N >= 2.

    Returns
    -------
    float
        The sample time [s].

    Raises
    ------
    ValueError
        If ``t`` has fewer than 2 values or does not increase strictly.

    Examples
    --------
    >>> sample_time(np.arange(12_000) * 2e-4), sample_time(np.arange(9) / 3000) == 1 / 3000
    (0.0002, True)
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2 or not all(np.all(t[c.start + 1:c.stop + 1] > t[c])
                                            for c in _blocks(t.size - 1)):
        raise ValueError(f"t: expected at least 2 strictly increasing times, got {t.size}")
    mean = (t[-1] - t[0]) / (t.size - 1)
    # the column's resolution plus the rounding a clock accumulates as t[k] = t[k-1] + Ts
    # (at most one ulp of max |t| per sample), and never more than 1e-3 samples
    ulp = np.spacing(_largest_magnitude(t) or 1.0)
    tol = min(_resolution(t) + t.size * ulp, 1e-3 * mean)
    for digits in range(1, 16):
        for ts in (float(f"{mean:.{digits}g}"), 1.0 / float(f"{1.0 / mean:.{digits}g}")):
            if max(float(np.max(np.abs(t[c] - (t[0] + np.arange(c.start, c.stop) * ts))))
                   for c in _blocks(t.size)) <= tol:
                return ts
    return float(np.median(np.diff(t)))


def _row(k: int) -> str:
    return f"row {k + 1}"


def _resolution_hint(t: np.ndarray, dt: float) -> str:
    """Why intervals jitter when the time stamps are large (epoch times): float64 rounding."""
    res = float(np.spacing(np.max(np.abs(t))))
    if res <= 0.05 * SAMPLING_TOLERANCE * dt:
        return ""
    return (f"; the cause is float64 resolution: time stamps near {float(np.max(np.abs(t))):.3g} "
            f"s are resolved only to {res:.2g} s ({100 * res / dt:.2g} % of the {dt:.3g} s "
            "interval), e.g. epoch times; write the times relative to the start (t - t[0])")


def _validate_columns(names: list[str], values: list, source: str,
                      where: Callable[[int], str] = _row) -> list[np.ndarray]:
    """The columns as contiguous float vectors, checked; ``where(k)`` names data row ``k``
    (0-based) in messages."""
    out = []
    length = None
    for name, col in zip(names, values, strict=True):
        arr = np.asarray(col, dtype=float)
        if arr.ndim != 1:
            raise DataError(f"{source}: column '{name}' must be 1-D, got shape {arr.shape}")
        if length is None:
            length = arr.size
        elif arr.size != length:
            raise DataError(
                f"{source}: column '{name}' has {arr.size} samples, expected {length} "
                "(all columns must have equal lengths)"
            )
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise DataError(
                f"{source}: {where(int(bad[0]))}, column '{name}': "
                f"value {float(arr[bad[0]])!r} is not a finite number"
            )
        out.append(np.ascontiguousarray(arr))
    if length is None or length < 2:
        raise DataError(f"{source}: at least two samples are needed, got {length or 0}")
    t = out[0]
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise DataError(
            f"{source}: {where(k)}, column '{names[0]}': time {float(t[k])!r} does not "
            f"increase strictly (previous {float(t[k - 1])!r})"
            + _resolution_hint(t, float(np.median(np.abs(dt))) or 1.0)
        )
    med = float(np.median(dt, overwrite_input=True))  # (dt reordered: not read again)
    del dt
    # the intervals off the median, counted a block at a time; found again whole for a message
    if any(np.any(np.abs(np.diff(t[c.start:c.stop + 1]) - med) > SAMPLING_TOLERANCE * med)
           for c in _blocks(t.size - 1)):
        dt = np.diff(t)
        off = np.flatnonzero(np.abs(dt - med) > SAMPLING_TOLERANCE * med)
        change = np.flatnonzero(np.abs(dt - dt[0]) > SAMPLING_TOLERANCE * med)
        k = int(change[0]) if change.size else int(off[0])
        raise DataError(
            f"{source}: {where(k + 1)}, column '{names[0]}': the sample interval changes there "
            f"from {float(dt[max(k - 1, 0)]):.6g} s to {float(dt[k]):.6g} s (median {med:.6g} "
            f"s; {off.size} interval(s) more than {100 * SAMPLING_TOLERANCE:g} % off the "
            "median)" + (_resolution_hint(t, med) or "; the methods need uniform sampling: "
                         "resample the record or split it where the rate changes")
        )
    return out


def _delimiter(path: Path, header_line: str) -> str:
    """``,`` unless the header has no comma but semicolons or tabs (then that, with a
    warning saying so)."""
    if "," in header_line:
        return ","
    for sep, name in ((";", "semicolon"), ("\t", "tab")):
        if sep in header_line:
            warnings.warn(f"{path}: the header has no comma but {name}s; read as "
                          f"{name}-separated", UserWarning, stacklevel=5)
            return sep
    return ","


class _Lines:
    """Line numbers of data rows (blank lines are skipped, so rows and lines drift apart)."""

    def __init__(self):
        self.rows: list[int] = []  # first data row (0-based) of each run of consecutive lines
        self.lines: list[int] = []  # its line number (1-based, the header is line 1)

    def mark(self, row: int, line: int) -> None:
        if not self.rows or self.line(row) != line:
            self.rows.append(row)
            self.lines.append(line)

    def line(self, row: int) -> int:
        i = bisect.bisect_right(self.rows, row) - 1
        return self.lines[i] + row - self.rows[i]

    def where(self, row: int) -> str:
        return f"line {self.line(row)} (data row {row + 1})"


class _Columns:
    """Growing float columns (preallocated from the file size; no Python list of rows)."""

    def __init__(self, width: int, capacity: int):
        self.cols = [np.empty(max(capacity, 16)) for _ in range(width)]
        self.n = 0

    def add(self, block: np.ndarray) -> None:
        m = block.shape[0]
        if self.n + m > self.cols[0].size:
            size = max(2 * self.cols[0].size, self.n + m)
            for c in self.cols:
                c.resize(size, refcheck=False)
        for j, c in enumerate(self.cols):
            c[self.n:self.n + m] = block[:, j]
        self.n += m

    def finish(self) -> list[np.ndarray]:
        for c in self.cols:
            c.resize(self.n, refcheck=False)
        return self.cols


def _ends_with_newline(path: Path) -> bool:
    with path.open("rb") as fh:
        fh.seek(0, 2)
        if fh.tell() == 0:
            return True
        fh.seek(-1, 2)
        return fh.read(1) in (b"\n", b"\r")


def _fast_csv(path: Path) -> tuple[list[str], list[np.ndarray], _Lines] | None:
    """A regular CSV file read by NumPy's C reader (``numpy.loadtxt``), block by block of
    bytes: a comma header without a trailing separator, then lines of exactly one number per
    column, no blank line, a line end after the last. Returns None at the first departure from
    that (the file is then read by :func:`_parse_csv`, whose messages name the line), so both
    readers give the same record; memory: the columns plus one block of ``FAST_BLOCK_BYTES``."""
    with path.open("rb") as fh:
        first = fh.readline()
        if not first.endswith(b"\n") or b"," not in first:
            return None
        try:
            text = first.decode("utf-8-sig")
        except UnicodeDecodeError:
            return None
        header = [h.strip() for h in next(csv.reader([text]))]
        if not all(header) or not _ends_with_newline(path):
            return None
        width, size, table = len(header), path.stat().st_size, None
        rest = b""
        while True:
            data = fh.read(FAST_BLOCK_BYTES)
            buf = rest + data
            end = buf.rfind(b"\n") + 1 if data else len(buf)
            block, rest = buf[:end], buf[end:]
            if block:
                parsed = _fast_block(block, width)
                if parsed is None:
                    return None
                if table is None:  # rows in the file as the first block has them
                    table = _Columns(width, int(1.05 * size * len(parsed) / len(block)) + 16)
                table.add(parsed)
            if not data:
                break
    if table is None:
        return None
    lines = _Lines()
    lines.mark(0, 2)  # no blank line: data row k (0-based) is on line k + 2
    return header, table.finish(), lines


def _fast_block(block: bytes, width: int) -> np.ndarray | None:
    """Rows of ``width`` numbers from whole lines of bytes (``numpy.loadtxt``, C-parsed), or None
    when a line is empty or has another number of commas, or a field is not a number."""
    raw = np.frombuffer(block, np.uint8)
    ends = np.flatnonzero(raw == 10)
    per_line = np.diff(np.searchsorted(np.flatnonzero(raw == 44), ends), prepend=0)
    starts = np.concatenate(([0], ends[:-1] + 1))
    if np.any(per_line != width - 1) or np.any(ends - starts < 1) or \
            np.any((ends - starts == 1) & (raw[starts] == 13)):
        return None
    try:
        values = np.loadtxt(io.BytesIO(block), delimiter=",", comments=None, ndmin=2,
                            dtype=float, encoding="utf-8")
    except ValueError:
        return None
    return values if values.shape == (ends.size, width) else None


def _read_csv(path: Path) -> tuple[list[str], list[np.ndarray], _Lines]:
    fast = _fast_csv(path)
    if fast is not None:
        return fast
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:  # a UTF-8 BOM is accepted
            first = fh.readline()
            fh.seek(0)
            sep = _delimiter(path, first)
            return _parse_csv(path, fh, sep, len(first.encode()))
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: not a UTF-8 text file (byte {exc.start}); expected a CSV "
                        "with a header line, an .npz or a MATLAB .mat file") from None


def _header(path: Path, reader) -> tuple[list[str], int]:
    """The column names and the number of trailing empty names (a trailing separator)."""
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise DataError(f"{path}: empty file, expected a header line") from None
    if not any(header):
        raise DataError(f"{path}: the first line is empty; expected a header line of column "
                        "names, e.g. t,v,y")
    named = len(header)
    while not header[named - 1]:
        named -= 1
    if not all(header[:named]):
        raise DataError(f"{path}: line 1: column {header.index('') + 1} has no name; expected "
                        f"a name for every column (header: {','.join(header)})")
    return header[:named], len(header) - named


def _parse_csv(path: Path, fh, sep: str, header_bytes: int):
    reader = csv.reader(fh, delimiter=sep)
    header, trailing = _header(path, reader)
    width = len(header)
    row_bytes = max(header_bytes, 2 * width)
    capacity = int(1.05 * path.stat().st_size / row_bytes) + 16
    table, lines = _Columns(width, capacity), _Lines()
    complete = _ends_with_newline(path)
    block: list[list[str]] = []
    block_lines: list[int] = []
    nrows = 0
    last_line = 1
    tail_blank = False
    for row in reader:
        if not row or all(not c.strip() for c in row):
            tail_blank = True
            continue
        tail_blank = False
        last_line = reader.line_num
        if len(row) > width and not any(c.strip() for c in row[width:width + trailing]) \
                and len(row) <= width + trailing:
            row = row[:width]
        lines.mark(nrows + len(block), last_line)
        block.append(row)
        block_lines.append(last_line)
        if len(block) > CHUNK_ROWS:  # keep the newest row back: it may be the cut last one
            table.add(_parse_block(path, block[:-1], block_lines[:-1], header, nrows))
            nrows += len(block) - 1
            block, block_lines = block[-1:], block_lines[-1:]
    if block and not complete and not tail_blank:  # a cut last row: never read a cut number
        warnings.warn(f"{path}: line {last_line} has no line end, as in a file still being "
                      f"written; its data row {nrows + len(block)} is left out (end the file "
                      "with a newline to keep it)", UserWarning, stacklevel=5)
        block.pop()
        block_lines.pop()
    if block:
        table.add(_parse_block(path, block, block_lines, header, nrows))
    return header, table.finish(), lines


def _parse_block(path: Path, block: list[list[str]], block_lines: list[int], header: list[str],
                 first_row: int) -> np.ndarray:
    try:
        return np.array(block, dtype=float).reshape(len(block), len(header))
    except ValueError:
        pass
    for i, (row, line) in enumerate(zip(block, block_lines, strict=True)):
        at = f"line {line} (data row {first_row + i + 1})"
        if len(row) != len(header):
            hint = ""
            if len(header) == 1 and any(c in header[0] for c in ";\t"):
                hint = " (is the file separated by something other than commas?)"
            raise DataError(
                f"{path}: {at} has {len(row)} fields, expected {len(header)} "
                f"(header: {','.join(header)}){hint}"
            )
        for c, name in zip(row, header, strict=True):
            try:
                float(c)
            except ValueError:
                hint = " (a decimal comma? write decimal points)" if "," in c else ""
                raise DataError(
                    f"{path}: {at}, column '{name}': {c!r} is not a number{hint}"
                ) from None
    raise DataError(f"{path}: lines {block_lines[0]}-{block_lines[-1]}: not a table of "
                    "numbers")  # pragma: no cover - every row was checked above


def _npz_shape(npz, key: str) -> tuple[int, ...] | None:
    """The shape of array ``key`` of an open ``.npz`` from its header alone (nothing else is
    read); None when it is not a ``.npy`` member of format 1.0 or 2.0 (it is then read whole)."""
    fmt = np.lib.format
    if key + ".npy" not in npz.zip.namelist():
        return None
    with npz.zip.open(key + ".npy") as fh:
        version = fmt.read_magic(fh)
        if version not in ((1, 0), (2, 0)):
            return None
        read = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
        return read(fh)[0]


def _read_npz(path: Path, columns: tuple[str, str, str]
              ) -> tuple[list[str], dict[str, np.ndarray]]:
    """The names of the arrays and, read one by one, the chosen columns and the arrays of as
    many elements as the time column (the candidates for ``Record.extra``); other arrays (a
    long matrix, another record's vectors) are not read."""
    with path.open("rb") as fh:
        magic = fh.read(4)
    if magic[:2] != b"PK":
        kind = "looks like a text (CSV?) file; rename it to .csv" if \
            magic and all(32 <= b < 127 or b in (9, 10, 13) for b in magic) else \
            "is not a zip archive"
        raise DataError(f"{path}: not a valid .npz file: it {kind}")
    try:
        with np.load(path, allow_pickle=False) as npz:
            shapes = {k: _npz_shape(npz, k) for k in npz.files}
            n = int(np.prod(shapes[columns[0]])) if shapes.get(columns[0]) else None
            wanted = [k for k, shape in shapes.items() if k in columns or shape is None
                      or (len(shape) in (1, 2) and int(np.prod(shape)) == n)]
            return list(npz.files), {k: npz[k] for k in wanted}  # one column at a time
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, KeyError) as exc:
        raise DataError(f"{path}: corrupt .npz file ({type(exc).__name__}: {exc})") from None


def _read_mat(path: Path) -> dict[str, np.ndarray]:
    from scipy.io import loadmat
    from scipy.io.matlab import MatReadError

    try:
        raw = loadmat(path)
    except NotImplementedError:  # scipy reads v4 to v7.2; v7.3 is HDF5
        return _read_mat73(path)
    except (MatReadError, ValueError, OSError, TypeError) as exc:
        raise DataError(f"{path}: not a readable MATLAB .mat file ({exc})") from None
    return {k: a for k, a in raw.items() if not k.startswith("__")}


def _read_mat73(path: Path) -> dict[str, np.ndarray]:
    try:
        import h5py
    except ImportError:
        raise DataError(f"{path}: a MATLAB v7.3 (HDF5) file; reading it needs the h5py package "
                        "(pip install h5py), or save it from MATLAB with save(FILE, '-v7')") \
            from None
    with h5py.File(path, "r") as f:
        return {k: np.asarray(d) for k, d in f.items() if isinstance(d, h5py.Dataset)}


def _signals(path: Path, data: dict, columns: tuple[str, str, str]) -> tuple[list, dict]:
    """The chosen columns as vectors and the other vectors of their length (.npz, .mat)."""
    chosen = [_vector(c, data[c], str(path)) if c in data else None for c in columns]
    n = chosen[0].size if chosen[0] is not None else None
    extra = {}
    for k, a in data.items():
        if k in columns:
            continue
        arr = np.asarray(a)
        if arr.ndim in (1, 2) and arr.size == n and (arr.ndim == 1 or 1 in arr.shape) \
                and arr.dtype.kind in "biuf":
            extra[k] = arr.reshape(-1).astype(float, copy=False)
    return chosen, extra


def load_record(path, columns: tuple[str, str, str] = DEFAULT_COLUMNS, *,
                output_required: bool = True) -> Record:
    """Load a record from CSV (header line), NPZ or MATLAB ``.mat``; ``columns`` names time,
    input, output.

    Parameters
    ----------
    path : str or pathlib.Path
        By suffix: ``.npz`` (one array per column, keyed by name), ``.mat`` (MATLAB v5, or
        v7.3 with h5py installed: one vector variable per column) or else a CSV file with a
        header line (comma-separated; a header without commas but with semicolons or tabs is
        read with that separator, with a warning; a UTF-8 BOM and a trailing separator are
        accepted). A last line without a line end (a file still being written) is left out,
        with a warning, rather than read with a possibly cut number.
    columns : tuple of str
        Names of the time [s], input and output columns. These are the record's ``t``,
        ``v`` and ``y``; every other column goes to ``Record.extra`` under its own name.
    output_required : bool
        When False, a file without the output column loads with ``y`` zeros and
        ``has_output=False`` (e.g. an input to simulate).

    Returns
    -------
    Record
        Columns other than the three named are kept in ``Record.extra``.

    Raises
    ------
    DataError
        Naming the file, line (data row) and column on any violation (also: a corrupt
        ``.npz``, a text file named ``.npz``, a sampling interval that changes mid-record, a
        v7.3 ``.mat`` without h5py).

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "r.csv"
    >>> _ = f.write_text("t,v\\n0,0\\n0.1,1\\n0.2,0\\n")
    >>> load_record(f, output_required=False).has_output
    False
    """
    path = Path(path)
    if isinstance(columns, str) or len(columns) != 3 or len(set(columns)) != 3:
        raise DataError(f"columns: expected three distinct names (time, input, output), got "
                        f"{columns!r}")
    if not path.exists():
        raise DataError(f"{path}: no such file")
    if not path.is_file():
        raise DataError(f"{path}: not a file")
    where: Callable[[int], str] = _row
    suffix = path.suffix.lower()
    if suffix in (".npz", ".mat"):
        if suffix == ".npz":
            header, data = _read_npz(path, columns)
        else:
            data = _read_mat(path)
            header = list(data)
        chosen, extra = _signals(path, data, columns)
    else:
        header, table, lines = _read_csv(path)
        if len(set(header)) != len(header):
            raise DataError(f"{path}: duplicate column names in header {header}")
        data = dict(zip(header, table, strict=True))
        where = lines.where
        chosen = [data.get(c) for c in columns]
        extra = {k: a for k, a in data.items() if k not in columns}
    has_output = chosen[2] is not None
    if not has_output and not output_required and chosen[0] is not None \
            and chosen[1] is not None:
        chosen[2] = np.zeros(chosen[1].shape)
    missing = [c for c, a in zip(columns, chosen, strict=True) if a is None]
    if missing:
        raise DataError(
            f"{path}: column(s) {missing} not found; available: {header} "
            "(choose names with columns=(time, input, output) or --columns)"
        )
    names = [*columns, *extra]
    checked = _validate_columns(names, [*chosen, *extra.values()], str(path), where)
    return Record(checked[0], checked[1], checked[2], dict(zip(extra, checked[3:], strict=True)),
                  source=str(path), has_output=has_output)


def save_record(record: Record, path, columns: tuple[str, str, str] = DEFAULT_COLUMNS) -> Path:
    """Write a record to CSV (full float precision), NPZ or MATLAB ``.mat``, by the file suffix.

    Parameters
    ----------
    record : Record
        The record to write; its extra columns follow ``t, v, y``.
    path : str or Path
        Target file, written under exactly this name (no suffix appended); ``.npz`` (any
        case) writes NumPy's archive, ``.mat`` a MATLAB v5 file (column vectors), anything
        else comma-separated text with a header line. Missing parent directories are created.
    columns : tuple of str, optional
        Names for the time, input and output columns (default ``("t", "v", "y")``).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ValueError
        Two columns with one name (an extra column named like one of ``columns``).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> rec = Record(np.arange(3) * 0.1, [0.0, 1.0, 0.0], [0.0, 0.5, 0.5])
    >>> f = save_record(rec, pathlib.Path(tempfile.mkdtemp()) / "r.csv")
    >>> f.read_text().splitlines()[:2]
    ['t,v,y', '0,0,0']
    >>> load_record(f).y
    array([0. , 0.5, 0.5])
    """
    path = Path(path)
    names = list(columns) + list(record.extra)
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise ValueError(f"{path}: column name(s) {dup} would appear twice; rename the extra "
                         "column(s) or choose other columns=")
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = [record.t, record.v, record.y, *record.extra.values()]
    suffix = path.suffix.lower()
    if suffix in (".npz", ".mat"):
        with path.open("wb") as fh:  # a file object: np.savez appends no ".npz" behind our back
            if suffix == ".npz":
                np.savez(fh, **dict(zip(names, arrays, strict=True)))
            else:
                from scipy.io import savemat

                savemat(fh, dict(zip(names, arrays, strict=True)), oned_as="column")
    else:
        table = np.column_stack(arrays)
        np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
    return path
