"""The results table of a study, its files, and the partial file a running study streams to.

Columns: ``index``, the design variables, ``feasible``, ``reason``, then one column per metric.
Rows are sorted by ``index``; floats are written with ``repr`` (shortest exact form), so a
table read back is bit-identical and the same study gives the same bytes whatever the
executor.

While a study runs, each finished design is appended (and flushed) to a hidden partial file
beside the output, ``.<name>.partial``, whose first line carries the study's digest; the
output files themselves appear only at the end, written to temporary names and renamed
(:mod:`pkdyn.files`). A restart of the same study reads the partial file and skips the designs
in it; a partial file of another study is refused.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from pkdyn.design.evaluate import Row
from pkdyn.exceptions import OutputError, StudyError
from pkdyn.files import atomic_path, atomic_write, output_target, shown

__all__ = ["PartialFile", "Table", "output_paths"]

_MAGIC = "# pkdyn design study "


def _fmt(v: float) -> str:
    return repr(float(v)) if math.isfinite(v) else ("nan" if math.isnan(v) else repr(float(v)))


@dataclass
class Table:
    """Rows of a study, sorted by index.

    Attributes:
        variables: Design variable names.
        metrics: Metric names.
        units: Unit of each variable and metric column.
        rows: The rows, sorted by index.

    """

    variables: list[str]
    metrics: list[str]
    units: dict[str, str]
    rows: list[Row]

    def __post_init__(self) -> None:
        self.rows = sorted(self.rows, key=lambda r: r.index)

    @property
    def columns(self) -> list[str]:
        """Column names."""
        return ["index", *self.variables, "feasible", "reason", *self.metrics]

    def __len__(self) -> int:
        return len(self.rows)

    @property
    def index(self) -> np.ndarray:
        """Design numbers (N,)."""
        return np.array([r.index for r in self.rows], dtype=int)

    @property
    def x(self) -> np.ndarray:
        """Design variables (N, d)."""
        return np.array([r.x for r in self.rows], dtype=float).reshape(len(self.rows), -1)

    @property
    def feasible(self) -> np.ndarray:
        """(N,) feasibility."""
        return np.array([r.feasible for r in self.rows], dtype=bool)

    @property
    def values(self) -> np.ndarray:
        """Metric values (N, m)."""
        return np.array([r.values for r in self.rows], dtype=float).reshape(len(self.rows), -1)

    def column(self, name: str) -> np.ndarray:
        """A column by name (numbers as floats, ``reason`` as strings)."""
        if name in self.metrics:
            return self.values[:, self.metrics.index(name)]
        if name in self.variables:
            return self.x[:, self.variables.index(name)]
        if name == "index":
            return self.index
        if name == "feasible":
            return self.feasible
        if name == "reason":
            return np.array([r.reason for r in self.rows], dtype=object)
        raise KeyError(name)

    def record(self, i: int) -> dict[str, Any]:
        """Row ``i`` as ``{column: value}``."""
        r = self.rows[i]
        out: dict[str, Any] = {"index": r.index}
        out.update(zip(self.variables, r.x, strict=True))
        out.update({"feasible": r.feasible, "reason": r.reason})
        out.update(zip(self.metrics, r.values, strict=True))
        return out

    def header(self) -> list[str]:
        """CSV header fields."""
        return self.columns

    @staticmethod
    def csv_fields(r: Row) -> list[str]:
        """CSV fields of a row."""
        return [
            str(r.index),
            *(_fmt(v) for v in r.x),
            "True" if r.feasible else "False",
            r.reason,
            *(_fmt(v) for v in r.values),
        ]

    def to_csv(self) -> str:
        """The table as CSV text."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.header())
        for r in self.rows:
            w.writerow(self.csv_fields(r))
        return buf.getvalue()

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        """Write the CSV file (atomically)."""
        with atomic_write(path, newline="") as fh:
            fh.write(self.to_csv())

    def write_parquet(self, path: str | os.PathLike[str], metadata: dict[str, str]) -> None:
        """Write the Parquet file (atomically), with units and ``metadata`` in its schema."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        cols: dict[str, Any] = {"index": pa.array(self.index, pa.int64())}
        x, v = self.x, self.values
        for k, name in enumerate(self.variables):
            cols[name] = pa.array(x[:, k], pa.float64())
        cols["feasible"] = pa.array(self.feasible, pa.bool_())
        cols["reason"] = pa.array([r.reason for r in self.rows], pa.string())
        for k, name in enumerate(self.metrics):
            cols[name] = pa.array(v[:, k], pa.float64())
        fields = [
            pa.field(n, a.type, metadata={"unit": self.units.get(n, "")}) for n, a in cols.items()
        ]
        meta = {k.encode(): str(val).encode() for k, val in metadata.items()}
        table = pa.Table.from_arrays(list(cols.values()), schema=pa.schema(fields, metadata=meta))
        with atomic_path(path) as tmp:
            pq.write_table(table, tmp)

    @classmethod
    def read_rows(cls, lines: Iterable[str], header: Sequence[str]) -> list[Row]:
        """Rows from CSV lines (whole lines only; a torn last line is dropped).

        Raises:
            StudyError: The header does not match ``header``.

        """
        reader = csv.reader(lines)
        try:
            got = next(reader)
        except StopIteration:
            return []
        except csv.Error as err:  # a header cell beyond the csv module's field limit
            raise StudyError("results", f"the header is not a CSV row ({err})") from None
        if list(got) != list(header):
            raise StudyError("results", f"columns {got} differ from the study's {list(header)}")
        d = header.index("feasible") - 1
        rows = []
        while True:
            try:
                fields = next(reader)
            except StopIteration:
                break
            except csv.Error:  # a cell beyond the csv module's field limit: a torn row
                continue
            if len(fields) != len(header):
                continue
            try:
                rows.append(
                    Row(
                        int(fields[0]),
                        tuple(float(v) for v in fields[1 : 1 + d]),
                        fields[1 + d] == "True",
                        fields[2 + d],
                        tuple(float(v) for v in fields[3 + d :]),
                    )
                )
            except ValueError:
                continue
        return rows


def output_paths(out: str | os.PathLike[str]) -> dict[str, Path]:
    """The files of a study written to ``out`` (``.csv`` or ``.parquet``), each checked.

    Every one must be a file pkdyn may write (:func:`pkdyn.files.output_target`: a regular
    file or a new name, never a FIFO, a device or a directory, a name the file system accepts).

    Returns:
        ``csv``, ``parquet``, ``study`` (the study file, ``<stem>.study.yaml``) and ``partial``.

    Raises:
        OutputError: Another suffix, or one of the files cannot be written.

    """
    p = Path(out)
    if p.suffix not in (".csv", ".parquet"):
        raise OutputError(shown(p), "a study table is .csv or .parquet (both are written)")
    stem = p.with_suffix("")
    paths = {
        "csv": stem.with_suffix(".csv"),
        "parquet": stem.with_suffix(".parquet"),
        "study": stem.parent / f"{stem.name}.study.yaml",
        "partial": stem.parent / f".{stem.name}.partial.csv",
    }
    for key, path in paths.items():
        what = {"csv": "the CSV table", "parquet": "the Parquet table", "study": "the study file"}
        output_target(path, "" if key == p.suffix[1:] else what.get(key, "the partial file"))
    return paths


class PartialFile:
    """The file a running study appends its finished designs to.

    Args:
        path: Its path.
        digest: The study's digest.
        header: The table's CSV header.

    """

    def __init__(self, path: Path, digest: str, header: list[str]) -> None:
        self.path = path
        self.digest = digest
        self.header = header
        self._fh: IO[str] | None = None
        self._writer: Any = None

    def load(self) -> list[Row]:
        """Rows already done by an earlier run of the same study (none if no file).

        Raises:
            StudyError: The file belongs to another study.

        """
        if not self.path.exists():
            return []
        try:
            with open(self.path, newline="") as fh:
                first = fh.readline()
                if not first.startswith(_MAGIC):
                    raise StudyError(str(self.path), "not a pkdyn partial study file; remove it")
                if first[len(_MAGIC) :].strip() != self.digest:
                    raise StudyError(
                        str(self.path),
                        "partial results of a different study (another definition); remove "
                        "it or write the study elsewhere (--out)",
                    )
                text = fh.read()
        except OSError as err:
            raise OutputError(str(self.path), err.strerror or str(err)) from None
        lines = text.splitlines(keepends=True)
        if lines and not lines[-1].endswith("\n"):
            lines = lines[:-1]  # torn by an interruption
        return Table.read_rows(lines, self.header)

    def open(self, rows: list[Row]) -> None:
        """Start the file over with ``rows`` (the designs already done), ready to append.

        The restart copy is written to a temporary name and renamed, so an interruption at
        that moment keeps the previous partial file.
        """
        with atomic_write(self.path, newline="") as fh:
            fh.write(f"{_MAGIC}{self.digest}\n")
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(self.header)
            for r in rows:
                w.writerow(Table.csv_fields(r))
        try:
            self._fh = open(self.path, "a", newline="")
        except OSError as err:
            raise OutputError(str(self.path), err.strerror or str(err)) from None
        self._writer = csv.writer(self._fh, lineterminator="\n")

    def append(self, rows: Iterable[Row]) -> None:
        """Append finished designs and flush them to disk."""
        assert self._fh is not None
        for r in rows:
            self._writer.writerow(Table.csv_fields(r))
        self._fh.flush()

    def close(self, remove: bool = False) -> None:
        """Close the file; remove it (the study completed)."""
        if self._fh is not None:
            self._fh.close()
            self._fh = None
        if remove:
            self.path.unlink(missing_ok=True)
