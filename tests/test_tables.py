"""The one table reader (pkdyn.tables), input class by input class, and its three users.

Every bad table gives one line naming the file, the line (CSV) or row (Parquet) and the column;
trajectories, calibration measurements and identification motions read CSV and Parquet alike.
"""

from __future__ import annotations

import os

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import pkdyn
from pkdyn.exceptions import InvalidInputError, OutputError
from pkdyn.tables import MAX_CELL, read_table, write_table


def _write(tmp_path, name, content, mode="w"):
    path = tmp_path / name
    if mode == "wb":
        path.write_bytes(content)
    else:
        with open(path, "w", newline="", encoding="utf-8") as fh:
            fh.write(content)
    return path


@pytest.mark.parametrize(
    ("content", "columns", "values", "lines"),
    [
        ("a,b\n1,2\n3,4\n", ("a", "b"), [[1, 2], [3, 4]], [2, 3]),
        ("\ufeffa,b\r\n1,2\r\n3,4\r\n", ("a", "b"), [[1, 2], [3, 4]], [2, 3]),  # BOM, CRLF
        ('"a","b,c"\n"1"," 2 "\n', ("a", "b,c"), [[1, 2]], [2]),  # RFC 4180 quoting
        ('a,"b\nc"\n\n1,2\n\n3,4\n', ("a", "b\nc"), [[1, 2], [3, 4]], [4, 6]),  # blank lines
        (" a , b \n-1e-3,+2.5E2\n", ("a", "b"), [[-1e-3, 250.0]], [2]),
    ],
    ids=["plain", "bom-crlf", "quoted", "multiline-blank", "spaces-exponents"],
)
def test_csv_variants_read_the_same_numbers(tmp_path, content, columns, values, lines):
    t = read_table(_write(tmp_path, "t.csv", content))
    assert t.columns == columns and t.kind == "csv"
    np.testing.assert_array_equal(t.data, values)
    np.testing.assert_array_equal(t.lines, lines)


@pytest.mark.parametrize(
    ("content", "needle"),
    [
        ("", "is empty"),
        ("a,b\n", "has a header but no data rows"),
        ("a,b\n1,2\n3\n", "line 3 has 1 cell, the header 2"),
        ("a,b\n1,2\n3,x\n", "line 3, column b: 'x' is not a number"),
        ("a,b\n1,2\n3,\n", "line 3, column b: empty cell"),
        ("a,b\n1,nan\n", "line 2, column b: nan is not a finite number"),
        ("a,b\n1,-inf\n", "line 2, column b: -inf is not a finite number"),
        ("a,a\n1,2\n", "column a is given twice"),
        ("a,,b\n1,2,3\n", "line 1, column 2 has no name"),
        ("1,2\n3,4\n", "line 1 holds numbers, not column names"),
        ('a,b\n1,"2"x\n', "line 2: malformed CSV"),
        ("a,b\n1,2\x003\n", "line 2: a NUL byte: a binary file"),
    ],
    ids=[
        "empty",
        "header only",
        "ragged",
        "text",
        "empty cell",
        "nan",
        "inf",
        "repeated name",
        "no name",
        "no header",
        "bad quote",
        "binary",
    ],
)
def test_bad_csv_named_in_one_line(tmp_path, content, needle):
    path = _write(tmp_path, "bad.csv", content)
    with pytest.raises(InvalidInputError) as err:
        read_table(path)
    text = str(err.value)
    assert "\n" not in text and str(path) in text and needle in text, text


def test_encoding_cell_row_and_size_limits(tmp_path):
    with pytest.raises(InvalidInputError, match="line 3: not UTF-8 text"):
        read_table(_write(tmp_path, "latin.csv", b"a,b\n1,2\n\xe9,3\n", "wb"))
    big = "a,b\n1," + "1" * (MAX_CELL + 1) + "\n"  # past the csv module's 131,072 too
    with pytest.raises(InvalidInputError, match="longer than 1,048,576 characters"):
        read_table(_write(tmp_path, "cell.csv", big))
    long = "a,b\n" + "".join(f"{i},{i}\n" for i in range(200_000))  # past csv's default limit
    assert len(read_table(_write(tmp_path, "long.csv", long))) == 200_000
    rows = _write(tmp_path, "rows.csv", "a\n1\n2\n3\n")
    with pytest.raises(InvalidInputError, match="more than 2 sample rows: at most 2; resample"):
        read_table(rows, "sample", max_rows=2, hint="resample")
    with pytest.raises(InvalidInputError, match="has 3 sample rows: at least 4 are needed"):
        read_table(rows, "sample", min_rows=4)
    with pytest.raises(InvalidInputError, match="more than the 4e-06 MB accepted"):
        read_table(rows, max_bytes=4)


def test_only_regular_files_are_read(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for path, needle in (
        (fifo, "a FIFO"),
        (tmp_path, "a directory"),
        ("/dev/zero", "a character device"),
        (tmp_path / "nope.csv", "cannot be read"),
    ):
        with pytest.raises(InvalidInputError, match=needle):
            read_table(path)


def test_write_table_digits_and_unwritable_paths(tmp_path):
    X = np.array([[1.0 / 3.0, -2.0e-7], [123456.789012345, 0.0]])
    write_table(tmp_path / "d.csv", ["t", "x"], X, digits=10)
    text = (tmp_path / "d.csv").read_text()
    assert text.splitlines()[1] == f"{X[0, 0]:.10g},{X[0, 1]:.10g}"
    back = read_table(tmp_path / "d.csv").data
    assert np.all(np.abs(back - X) <= 1e-9 * np.abs(X))  # 10 significant digits
    with pytest.raises(OutputError, match="no_such_dir"):
        write_table(tmp_path / "no_such_dir" / "d.csv", ["t", "x"], X)


def test_parquet_reads_like_csv_and_names_rows(tmp_path):
    X = np.array([[0.1, 1.0 / 3.0], [1e-300, -2.5]])
    write_table(tmp_path / "w.csv", ["x", "y"], X)
    write_table(tmp_path / "w.parquet", ["x", "y"], X)
    a, b = read_table(tmp_path / "w.csv"), read_table(tmp_path / "w.parquet")
    np.testing.assert_array_equal(a.data, X)  # 17 digits: the same floats
    np.testing.assert_array_equal(b.data, X)
    assert b.kind == "parquet" and b.where(1, "y") == "row 2, column y"
    pq.write_table(pa.table({"a": pa.array([1, 2], pa.int32())}), tmp_path / "i.parquet")
    np.testing.assert_array_equal(read_table(tmp_path / "i.parquet").data, [[1.0], [2.0]])
    for table, needle in (
        (pa.table({"a": [1.0, None]}), "row 2, column a: empty (null)"),
        (pa.table({"a": [1.0, 2.0], "b": ["x", "y"]}), "column b holds string values"),
        (pa.table({"a": [1.0, np.inf]}), "row 2, column a: inf is not a finite number"),
        (pa.table({"a": [1.0], "a ": [2.0]}), "column a is given twice"),
    ):
        pq.write_table(table, tmp_path / "bad.parquet")
        with pytest.raises(InvalidInputError, match=needle.replace("(", r"\(").replace(")", r"\)")):
            read_table(tmp_path / "bad.parquet")
    (tmp_path / "cut.parquet").write_bytes(b"PAR1 and then nothing")
    with pytest.raises(InvalidInputError, match="malformed Parquet file"):
        read_table(tmp_path / "cut.parquet")


def test_the_three_readers_take_parquet(tmp_path):
    from pkdyn.calibration import read_csv
    from pkdyn.dynamics.trajectory_file import read_task_csv
    from pkdyn.identification import read_measurements

    delta = pkdyn.load("delta", geometry=False)
    home = delta.q_home[delta.actuated_q]
    qa = home + 0.1 * np.sin(np.arange(12)[:, None] + np.arange(3))
    pos = np.array([pkdyn.forward_geometry(delta, r).placement.translation for r in qa])
    cols = [f"qa_{n}" for n in delta.actuator_names]
    write_table(tmp_path / "m.parquet", [*cols, "x", "y", "z"], np.hstack([qa, pos]))
    m = read_csv(tmp_path / "m.parquet", delta)
    assert m.kind == "position" and m.where(3) == "row 4"  # (Parquet rows, 1-based)
    np.testing.assert_array_equal(m.position, pos)
    t = 0.01 * np.arange(12)
    write_table(tmp_path / "q.parquet", ["t", *cols], np.column_stack([t, qa]))
    traj = read_task_csv(delta, tmp_path / "q.parquet")
    np.testing.assert_allclose(traj.pose[:, :3], pos, atol=1e-12)
    tau = np.zeros_like(qa)
    write_table(
        tmp_path / "d.parquet",
        ["t", *cols, *(f"tau_{n}" for n in delta.actuator_names)],
        np.column_stack([t, qa, tau]),
    )
    data = read_measurements(tmp_path / "d.parquet", delta.actuator_names)
    np.testing.assert_array_equal(data.qa, qa)


def test_too_many_columns(tmp_path):
    from pkdyn.tables import MAX_COLUMNS

    names = ",".join(f"c{i}" for i in range(MAX_COLUMNS + 1))
    path = _write(tmp_path, "wide.csv", names + "\n" + ",".join(["1"] * (MAX_COLUMNS + 1)) + "\n")
    with pytest.raises(InvalidInputError, match="10001 columns: at most 10,000"):
        read_table(path)
