"""Tables in: the one reader of the numeric tables pkdyn reads (CSV and Parquet).

Trajectories (``size --trajectory``), calibration measurements (``calibrate --measurements``)
and identification motions (``identify --measurements``) are tables of numbers with named columns.
:func:`read_table` reads them all, with the same rules and the same one-line messages, each
naming the file, the line (CSV) or row (Parquet) and the column at fault:

- **the file**: a regular file (a FIFO, a device or a directory is refused before it is
  opened: :func:`pkdyn.files.read_bytes`) of at most the caller's size limit; Parquet when it
  starts with Parquet's magic bytes ``PAR1``, else CSV;
- **CSV** (RFC 4180, Python's :mod:`csv`): a header line naming the columns, then one row per
  line; fields may be quoted (``"1.5"``, a comma or a line break inside quotes); UTF-8 text with
  or without a byte-order mark, lines ending in LF or CRLF; blank lines are skipped; a NUL byte
  (a binary file), text that is not UTF-8, a cell longer than :data:`MAX_CELL` characters, a
  malformed quote, a row whose number of cells differs from the header's (*ragged*), a cell that
  is empty, not a number or not finite (``nan``, ``inf``) are refused;
- **Parquet** (pyarrow): numeric columns (integers or floats); a null, a non-finite value or a
  column of another type is refused;
- **both**: column names stripped of surrounding white space, none empty or repeated, at most
  :data:`MAX_COLUMNS` of them; at least one row (a header alone is refused) and at most the
  caller's row limit.

The values come back as one float array (:class:`Table`); what the columns must be is the
caller's check (:meth:`Table.error` words its messages the same way). :func:`write_table`
writes a table :func:`read_table` reads back exactly (CSV, or Parquet by the file's suffix).
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError, OutputError
from pkdyn.files import read_bytes, shown

__all__ = ["MAX_CELL", "MAX_COLUMNS", "Table", "read_table", "write_table"]

MAX_CELL = 1_048_576
"""Longest CSV cell accepted [characters] (Python's :mod:`csv` stops at 131,072)."""

MAX_COLUMNS = 10_000
"""Most columns of a table."""

_CHUNK = 65_536  # rows converted to numbers at once
_PARQUET_MAGIC = b"PAR1"


@dataclass(frozen=True, eq=False)  # numpy fields: no boolean ==
class Table:
    """A table of numbers read by :func:`read_table`.

    Attributes:
        source: The file, as messages show it.
        columns: Column names, in file order.
        data: The values (N, len(columns)), finite floats.
        lines: Where each row stands (N,): its line in a CSV file (the header is line 1), its
            row number in a Parquet file (the first is 1).
        kind: ``csv`` or ``parquet``.

    """

    source: str
    columns: tuple[str, ...]
    data: np.ndarray
    lines: np.ndarray
    kind: str = "csv"

    def __len__(self) -> int:
        return int(self.data.shape[0])

    def __contains__(self, name: object) -> bool:
        return name in self.columns

    def column(self, name: str) -> np.ndarray:
        """The values (N,) of a column (a view)."""
        return self.data[:, self.columns.index(name)]

    def select(self, names: Sequence[str]) -> np.ndarray:
        """The values (N, len(names)) of some columns, in the order given (a copy)."""
        return self.data[:, [self.columns.index(n) for n in names]]

    def where(self, row: int | None = None, column: str | None = None) -> str:
        """``line 5, column x`` (CSV) or ``row 4, column x`` (Parquet) of a row index."""
        parts = []
        if row is not None:
            parts.append(f"{'line' if self.kind == 'csv' else 'row'} {int(self.lines[row])}")
        if column is not None:
            parts.append(f"column {column}")
        return ", ".join(parts)

    def error(
        self, message: str, row: int | None = None, column: str | None = None
    ) -> InvalidInputError:
        """The exception naming this file, the row's line and the column (not raised here)."""
        at = self.where(row, column)
        return InvalidInputError(self.source, f"{at}: {message}" if at else message)


def read_table(
    path: str | os.PathLike[str],
    what: str = "data",
    max_bytes: int = 512_000_000,
    max_rows: int = 10_000_000,
    min_rows: int = 1,
    hint: str = "",
) -> Table:
    """Read a table of numbers (module docstring).

    Args:
        path: A CSV or Parquet file.
        what: What a row is, for messages (``measurement``, ``sample``...).
        max_bytes: Largest file accepted [bytes].
        max_rows: Most rows accepted.
        min_rows: Fewest rows accepted (at least 1).
        hint: Appended to the message of a file over ``max_rows`` (why the limit, what to do).

    Returns:
        The table.

    Raises:
        InvalidInputError: One line naming the file, and the line and column at fault.

    """
    src = shown(path)

    def fail(message: str) -> InvalidInputError:
        return InvalidInputError(src, message)

    data = read_bytes(path, max_bytes, fail)
    if data.startswith(_PARQUET_MAGIC):
        table = _parquet(data, src, what, max_rows, hint)
    else:
        table = _csv(data, src, what, max_rows, hint)
    n = len(table)
    if n < max(min_rows, 1):
        if n == 0:
            raise fail(f"has a header but no {what} rows")
        raise fail(f"has {n} {what} rows: at least {min_rows} are needed")
    return table


def _too_many(src: str, what: str, max_rows: int, hint: str) -> InvalidInputError:
    return InvalidInputError(
        src,
        f"more than {max_rows:,} {what} rows: at most {max_rows:,}{'; ' + hint if hint else ''}",
    )


def _header(src: str, names: list[str], kind: str) -> tuple[str, ...]:
    where = "line 1, " if kind == "csv" else ""
    out = [n.strip() for n in names]
    if len(out) > MAX_COLUMNS:
        raise InvalidInputError(src, f"{len(out)} columns: at most {MAX_COLUMNS:,}")
    for k, name in enumerate(out):
        if not name:
            raise InvalidInputError(src, f"{where}column {k + 1} has no name")
    seen: set[str] = set()
    for name in out:
        if name in seen:
            raise InvalidInputError(src, f"column {name} is given twice")
        seen.add(name)
    if kind == "csv" and all(_is_number(n) for n in out):
        raise InvalidInputError(
            src, "line 1 holds numbers, not column names: the first line names the columns"
        )
    return tuple(out)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _csv(data: bytes, src: str, what: str, max_rows: int, hint: str) -> Table:
    nul = data.find(b"\x00")
    if nul >= 0:
        line = data.count(b"\n", 0, nul) + 1
        raise InvalidInputError(src, f"line {line}: a NUL byte: a binary file, not a CSV table")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = data.count(b"\n", 0, err.start) + 1
        raise InvalidInputError(
            src, f"line {line}: not UTF-8 text (byte {err.start}); save the table as UTF-8 CSV"
        ) from None
    if not text.strip():
        raise InvalidInputError(
            src, f"is empty: expected a header line naming the columns and one row per {what}"
        )
    old = csv.field_size_limit(MAX_CELL)
    try:
        return _csv_rows(text, src, what, max_rows, hint)
    finally:
        csv.field_size_limit(old)


def _csv_rows(text: str, src: str, what: str, max_rows: int, hint: str) -> Table:
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    header: tuple[str, ...] | None = None
    chunks: list[np.ndarray] = []
    pending: list[list[str]] = []
    pending_lines: list[int] = []
    lines: list[int] = []
    start = 1
    count = 0
    while True:
        try:
            row = next(reader)
        except StopIteration:
            break
        except csv.Error as err:
            msg = str(err)
            if "field larger" in msg:
                msg = f"a cell longer than {MAX_CELL:,} characters"
            raise InvalidInputError(src, f"line {start}: malformed CSV ({msg})") from None
        line, start = start, reader.line_num + 1
        if not row or (not row[0].strip() and not any(c.strip() for c in row)):
            continue  # a blank line
        if header is None:
            header = _header(src, row, "csv")
            continue
        if len(row) != len(header):
            raise InvalidInputError(
                src,
                f"line {line} has {len(row)} cell{'s' if len(row) != 1 else ''}, the header "
                f"{len(header)}",
            )
        count += 1
        if count > max_rows:
            raise _too_many(src, what, max_rows, hint)
        pending.append(row)
        pending_lines.append(line)
        if len(pending) >= _CHUNK:
            chunks.append(_numbers(pending, pending_lines, header, src))
            lines += pending_lines
            pending, pending_lines = [], []
    if header is None:
        raise InvalidInputError(src, f"is empty: expected a header line and one row per {what}")
    if pending:
        chunks.append(_numbers(pending, pending_lines, header, src))
        lines += pending_lines
    values = np.concatenate(chunks) if chunks else np.zeros((0, len(header)))
    return Table(src, header, values, np.asarray(lines, dtype=int), "csv")


def _numbers(
    rows: list[list[str]], lines: list[int], header: tuple[str, ...], src: str
) -> np.ndarray:
    """The cells of some rows as finite floats; the first bad cell named otherwise."""
    try:
        out = np.array(rows, dtype=float)
    except ValueError:
        for row, line in zip(rows, lines, strict=True):
            for cell, name in zip(row, header, strict=True):
                text = cell.strip()
                if not text:
                    raise InvalidInputError(
                        src, f"line {line}, column {name}: empty cell (give a number)"
                    ) from None
                if not _is_number(text):
                    raise InvalidInputError(
                        src, f"line {line}, column {name}: '{text[:40]}' is not a number"
                    ) from None
        raise  # pragma: no cover - numpy and float() agree
    bad = ~np.isfinite(out)
    if bad.any():
        i, j = (int(k) for k in np.argwhere(bad)[0])
        raise InvalidInputError(
            src,
            f"line {lines[i]}, column {header[j]}: {rows[i][j].strip()} is not a finite number",
        )
    return out


def _parquet(data: bytes, src: str, what: str, max_rows: int, hint: str) -> Table:
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        pf = pq.ParquetFile(pa.BufferReader(data))
        meta = pf.metadata
        names = list(pf.schema_arrow.names)
    except (pa.ArrowException, OSError, ValueError) as err:
        first = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise InvalidInputError(src, f"malformed Parquet file ({first})") from None
    header = _header(src, names, "parquet")
    if meta.num_rows > max_rows:
        raise _too_many(src, what, max_rows, hint)
    try:
        table = pf.read()
    except (pa.ArrowException, OSError, ValueError) as err:
        first = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise InvalidInputError(src, f"malformed Parquet file ({first})") from None
    n = table.num_rows
    out = np.empty((n, len(header)))
    for j, name in enumerate(header):
        col = table.column(j)
        kind = col.type
        if not (pa.types.is_integer(kind) or pa.types.is_floating(kind)):
            raise InvalidInputError(src, f"column {name} holds {kind} values: numbers only")
        if col.null_count:
            i = int(np.flatnonzero(np.asarray(col.is_null().to_numpy(zero_copy_only=False)))[0])
            raise InvalidInputError(src, f"row {i + 1}, column {name}: empty (null)")
        out[:, j] = np.asarray(col.to_numpy(zero_copy_only=False), dtype=float)
    bad = ~np.isfinite(out)
    if bad.any():
        i, j = (int(k) for k in np.argwhere(bad)[0])
        raise InvalidInputError(
            src, f"row {i + 1}, column {header[j]}: {out[i, j]} is not a finite number"
        )
    return Table(src, header, out, np.arange(1, n + 1), "parquet")


def write_table(
    path: str | os.PathLike[str],
    columns: Sequence[str],
    data: np.ndarray | Any,
    *,
    digits: int = 17,
) -> None:
    """Write a table :func:`read_table` reads, atomically (a file is left intact on error).

    CSV (values with ``digits`` significant digits; 17, the default, reads back the same floats)
    unless the file's suffix is ``.parquet`` or ``.pq``.

    Args:
        path: The file.
        columns: Column names.
        data: Values (N, len(columns)).
        digits: Significant digits of the CSV values (1 to 17).

    Raises:
        InvalidInputError: ``data`` does not have one value per column in each row.
        OutputError: The file cannot be written.

    """
    from pkdyn.files import atomic_path, atomic_write, output_target

    output_target(path, "path")  # refused before any work: not a file name, a directory, ...
    values = np.asarray(data, dtype=float)
    if values.ndim != 2 or values.shape[1] != len(columns):
        raise InvalidInputError(
            "data", f"expected rows of {len(columns)} values ({', '.join(columns)})"
        )
    try:
        if Path(path).suffix.lower() in (".parquet", ".pq"):
            import pyarrow as pa
            import pyarrow.parquet as pq

            table = pa.table({c: values[:, k] for k, c in enumerate(columns)})
            with atomic_path(path) as tmp:
                pq.write_table(table, tmp)
            return
        with atomic_write(path, newline="") as fh:
            csv.writer(fh, lineterminator="\n").writerow(columns)
            np.savetxt(fh, values, delimiter=",", fmt=f"%.{digits}g")
    except OSError as err:
        raise OutputError(os.fspath(path), err.strerror or str(err)) from None
