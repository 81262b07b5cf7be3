"""Measured records: load and save ``t, v, y`` data as CSV or NPZ, validated on load.

A record holds time ``t`` [s], actuator input ``v`` (e.g. V) and measured output ``y``
(e.g. um), sampled at the same instants; extra columns are kept in ``Record.extra``.
Validation: at least two samples, equal lengths, finite numbers, strictly increasing time.
Errors name the file, the row (1-based data row, header excluded) and the column.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

DEFAULT_COLUMNS = ("t", "v", "y")


class DataError(ValueError):
    """A record file or array that does not meet the record rules."""


@dataclass
class Record:
    """A sampled input/output record: ``v[k]`` applied and ``y[k]`` measured at ``t[k]``."""

    t: np.ndarray
    v: np.ndarray
    y: np.ndarray
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    source: str = "<array>"

    def __post_init__(self):
        cols = {"t": self.t, "v": self.v, "y": self.y, **self.extra}
        arrays = _validate_columns(cols, self.source)
        self.t, self.v, self.y = arrays["t"], arrays["v"], arrays["y"]
        self.extra = {k: arrays[k] for k in self.extra}

    def __len__(self) -> int:
        return self.t.size

    @property
    def dt(self) -> float:
        """Median sample interval [s]."""
        return float(np.median(np.diff(self.t)))

    def slice(self, start: int | None = None, stop: int | None = None) -> Record:
        """Samples ``start:stop`` as a new record (extras included)."""
        s = slice(start, stop)
        return Record(
            self.t[s], self.v[s], self.y[s], {k: a[s] for k, a in self.extra.items()},
            source=f"{self.source}[{start}:{stop}]",
        )


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
    return out


def _read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    with path.open(newline="") as fh:
        reader = csv.reader(fh)
        try:
            header = [h.strip() for h in next(reader)]
        except StopIteration:
            raise DataError(f"{path}: empty file, expected a header line") from None
        rows = []
        for lineno, row in enumerate(reader, start=1):
            if not row or all(not c.strip() for c in row):
                continue
            if len(row) != len(header):
                raise DataError(
                    f"{path}: row {lineno} has {len(row)} fields, expected {len(header)} "
                    f"(header: {','.join(header)})"
                )
            try:
                rows.append([float(c) for c in row])
            except ValueError:
                for c, name in zip(row, header, strict=True):
                    try:
                        float(c)
                    except ValueError:
                        raise DataError(
                            f"{path}: row {lineno}, column '{name}': {c!r} is not a number"
                        ) from None
    return header, np.array(rows, dtype=float).reshape(-1, len(header))


def load_record(path, columns: tuple[str, str, str] = DEFAULT_COLUMNS) -> Record:
    """Load a record from CSV (header line) or NPZ; ``columns`` names time, input, output.

    Columns other than the three named are kept in ``Record.extra``. Raises
    :class:`DataError` naming the file, row and column on any violation.
    """
    path = Path(path)
    if len(columns) != 3:
        raise DataError(f"columns: expected three names (time, input, output), got {columns!r}")
    if not path.exists():
        raise DataError(f"{path}: no such file")
    if path.suffix.lower() == ".npz":
        with np.load(path, allow_pickle=False) as npz:
            data = {k: npz[k] for k in npz.files}
        header = list(data)
    else:
        header, table = _read_csv(path)
        if len(set(header)) != len(header):
            raise DataError(f"{path}: duplicate column names in header {header}")
        data = {name: table[:, i] for i, name in enumerate(header)}
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
                  {k: checked[k] for k in extra}, source=str(path))


def save_record(record: Record, path, columns: tuple[str, str, str] = DEFAULT_COLUMNS) -> Path:
    """Write a record to CSV (full float precision) or NPZ, by the file suffix."""
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
