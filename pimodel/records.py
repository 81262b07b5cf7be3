"""Measured records: load and save ``t, v, y`` data as CSV or NPZ, validated on load.

A record holds time ``t`` [s], actuator input ``v`` (e.g. V) and measured output ``y``
(e.g. um), sampled at the same instants; extra columns are kept in ``Record.extra``.
Validation: at least two samples, equal lengths, finite numbers, strictly increasing time,
uniform sampling (every interval within 1 % of the median).
Errors name the file, the row (1-based data row, header excluded) and the column.
"""

from __future__ import annotations

import csv
import warnings
import zipfile
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
        Further columns of the same length, by name.
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
        cols = {"t": self.t, "v": self.v, "y": self.y, **self.extra}
        arrays = _validate_columns(cols, self.source)
        self.t, self.v, self.y = arrays["t"], arrays["v"], arrays["y"]
        self.extra = {k: arrays[k] for k in self.extra}

    def __len__(self) -> int:
        return self.t.size

    @property
    def dt(self) -> float:
        """Sample time [s]: exact where the clock is regular (:func:`sample_time`)."""
        return sample_time(self.t)

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
            source=f"{self.source}[{start}:{stop}]",
        )


def _resolution(t: np.ndarray) -> float:
    """The time column's resolution [s]: the coarsest decimal step all its values sit on (to a
    few ulps), else a few ulps of its largest value."""
    ulps = 8.0 * np.spacing(float(np.max(np.abs(t))) or 1.0)
    for digits in range(16):
        if np.all(np.abs(t - np.round(t, digits)) <= ulps):
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
    if t.ndim != 1 or t.size < 2 or not np.all(np.diff(t) > 0):
        raise ValueError(f"t: expected at least 2 strictly increasing times, got {t.size}")
    k = np.arange(t.size)
    mean = (t[-1] - t[0]) / (t.size - 1)
    # the column's resolution plus the rounding a clock accumulates as t[k] = t[k-1] + Ts
    # (at most one ulp of max |t| per sample), and never more than 1e-3 samples
    ulp = np.spacing(float(np.max(np.abs(t))) or 1.0)
    tol = min(_resolution(t) + t.size * ulp, 1e-3 * mean)
    for digits in range(1, 16):
        for ts in (float(f"{mean:.{digits}g}"), 1.0 / float(f"{1.0 / mean:.{digits}g}")):
            if np.max(np.abs(t - (t[0] + k * ts))) <= tol:
                return ts
    return float(np.median(np.diff(t)))


def _validate_columns(cols: dict[str, np.ndarray], source: str) -> dict[str, np.ndarray]:
    out = {}
    length = None
    for name, values in cols.items():
        arr = np.asarray(values, dtype=float)
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
                f"{source}: row {bad[0] + 1}, column '{name}': "
                f"value {float(arr[bad[0]])!r} is not a finite number"
            )
        out[name] = np.ascontiguousarray(arr)
    if length is None or length < 2:
        raise DataError(f"{source}: at least two samples are needed, got {length or 0}")
    dt = np.diff(out["t"])
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = bad[0] + 1
        raise DataError(
            f"{source}: row {k + 1}, column 't': time {float(out['t'][k])!r} does not increase "
            f"strictly (previous {float(out['t'][k - 1])!r})"
        )
    med = float(np.median(dt))
    off = np.flatnonzero(np.abs(dt - med) > SAMPLING_TOLERANCE * med)
    if off.size:
        change = np.flatnonzero(np.abs(dt - dt[0]) > SAMPLING_TOLERANCE * med)
        k = int(change[0]) if change.size else int(off[0])
        raise DataError(
            f"{source}: row {k + 2}, column 't': the sample interval changes there from "
            f"{float(dt[max(k - 1, 0)]):.6g} s to {float(dt[k]):.6g} s (median {med:.6g} s; "
            f"{off.size} interval(s) more than {100 * SAMPLING_TOLERANCE:g} % off the median); "
            "the methods need uniform sampling: resample the record or split it where the "
            "rate changes"
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
                          f"{name}-separated", UserWarning, stacklevel=4)
            return sep
    return ","


def _read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:  # a UTF-8 BOM is accepted
            first = fh.readline()
            fh.seek(0)
            sep = _delimiter(path, first)
            return _parse_csv(path, csv.reader(fh, delimiter=sep), sep)
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: not a UTF-8 text file (byte {exc.start}); expected a CSV "
                        "with a header line, or an .npz") from None


def _parse_csv(path: Path, reader, sep: str) -> tuple[list[str], np.ndarray]:
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise DataError(f"{path}: empty file, expected a header line") from None
    if not any(header):
        raise DataError(f"{path}: the first line is empty; expected a header line of column "
                        "names, e.g. t,v,y")
    rows = []
    for lineno, row in enumerate(reader, start=1):
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            hint = ""
            if len(header) == 1 and any(c in header[0] for c in ";\t"):
                hint = " (is the file separated by something other than commas?)"
            raise DataError(
                f"{path}: row {lineno} has {len(row)} fields, expected {len(header)} "
                f"(header: {','.join(header)}){hint}"
            )
        try:
            rows.append([float(c) for c in row])
        except ValueError:
            for c, name in zip(row, header, strict=True):
                try:
                    float(c)
                except ValueError:
                    hint = " (a decimal comma? write decimal points)" if \
                        sep != "," and "," in c else ""
                    raise DataError(
                        f"{path}: row {lineno}, column '{name}': {c!r} is not a number{hint}"
                    ) from None
    return header, np.array(rows, dtype=float).reshape(-1, len(header))


def _read_npz(path: Path) -> dict[str, np.ndarray]:
    with path.open("rb") as fh:
        magic = fh.read(4)
    if magic[:2] != b"PK":
        kind = "looks like a text (CSV?) file; rename it to .csv" if \
            magic and all(32 <= b < 127 or b in (9, 10, 13) for b in magic) else \
            "is not a zip archive"
        raise DataError(f"{path}: not a valid .npz file: it {kind}")
    try:
        with np.load(path, allow_pickle=False) as npz:
            data = {k: npz[k] for k in npz.files}
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, KeyError) as exc:
        raise DataError(f"{path}: corrupt .npz file ({type(exc).__name__}: {exc})") from None
    for k, a in data.items():
        if a.dtype.kind not in "biuf":
            raise DataError(f"{path}: array '{k}' has dtype {a.dtype}; expected numbers")
    return data


def load_record(path, columns: tuple[str, str, str] = DEFAULT_COLUMNS, *,
                output_required: bool = True) -> Record:
    """Load a record from CSV (header line) or NPZ; ``columns`` names time, input, output.

    Parameters
    ----------
    path : str or pathlib.Path
        A CSV file with a header line (comma-separated; a header without commas but with
        semicolons or tabs is read with that separator, with a warning; a UTF-8 BOM is
        accepted) or an ``.npz`` of 1-D arrays.
    columns : tuple of str
        Names of the time [s], input and output columns.
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
        Naming the file, row and column on any violation (also: a corrupt ``.npz``, a text
        file named ``.npz``, a sampling interval that changes mid-record).

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "r.csv"
    >>> _ = f.write_text("t,v\\n0,0\\n0.1,1\\n0.2,0\\n")
    >>> load_record(f, output_required=False).has_output
    False
    """
    path = Path(path)
    if len(columns) != 3:
        raise DataError(f"columns: expected three names (time, input, output), got {columns!r}")
    if not path.exists():
        raise DataError(f"{path}: no such file")
    if not path.is_file():
        raise DataError(f"{path}: not a file")
    if path.suffix.lower() == ".npz":
        data = _read_npz(path)
        header = list(data)
    else:
        header, table = _read_csv(path)
        if len(set(header)) != len(header):
            raise DataError(f"{path}: duplicate column names in header {header}")
        data = {name: table[:, i] for i, name in enumerate(header)}
    has_output = columns[2] in data
    if not has_output and not output_required and columns[0] in data and columns[1] in data:
        data = {**data, columns[2]: np.zeros(np.shape(data[columns[1]]))}
    missing = [c for c in columns if c not in data]
    if missing:
        raise DataError(
            f"{path}: column(s) {missing} not found; available: {header} "
            "(choose names with columns=(time, input, output) or --columns)"
        )
    tcol, vcol, ycol = columns
    extra = {k: data[k] for k in header if k not in columns}
    cols = {"t": data[tcol], "v": data[vcol], "y": data[ycol], **extra}
    try:
        checked = _validate_columns(cols, str(path))
    except DataError as exc:  # report the user's column names, not the internal ones
        msg = str(exc)
        for internal, user in (("t", tcol), ("v", vcol), ("y", ycol)):
            msg = msg.replace(f"column '{internal}'", f"column '{user}'")
        raise DataError(msg) from None
    return Record(checked["t"], checked["v"], checked["y"],
                  {k: checked[k] for k in extra}, source=str(path), has_output=has_output)


def save_record(record: Record, path, columns: tuple[str, str, str] = DEFAULT_COLUMNS) -> Path:
    """Write a record to CSV (full float precision) or NPZ, by the file suffix.

    Parameters
    ----------
    record : Record
        The record to write; its extra columns follow ``t, v, y``.
    path : str or Path
        Target file; ``.npz`` writes NumPy's archive, anything else comma-separated text with a
        header line. Missing parent directories are created.
    columns : tuple of str, optional
        Names for the time, input and output columns (default ``("t", "v", "y")``).

    Returns
    -------
    pathlib.Path
        ``path``.

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
    path.parent.mkdir(parents=True, exist_ok=True)
    names = list(columns) + list(record.extra)
    arrays = [record.t, record.v, record.y, *record.extra.values()]
    if path.suffix.lower() == ".npz":
        np.savez(path, **dict(zip(names, arrays, strict=True)))
    else:
        table = np.column_stack(arrays)
        np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
    return path
