"""Measured motions: the CSV columns of ``pkdyn identify`` and their checks.

Columns (one header line, then one row per sample, comma-separated):

- ``t``: time [s], increasing;
- ``qa_<actuator>``: actuator positions [rad or m], one per actuator (required);
- ``qa_dot_<actuator>``, ``qa_ddot_<actuator>``: rates and accelerations (optional, both or
  neither; without them they come from the positions by zero-phase filtering,
  :mod:`pkdyn.identification.filtering`);
- ``tau_<actuator>``: measured efforts, joint side [N m or N] (reduction x motor torque; required
  to identify, optional in a motion to predict).

Any other column, a missing one, a value that is not a finite number, or times that do not
increase is refused with one line naming the column (and the row).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public

__all__ = ["Measurements", "read_measurements"]


@dataclass(frozen=True, eq=False)  # numpy fields
class Measurements:
    """A measured motion.

    Attributes:
        t: Times (N,) [s].
        qa: Actuator positions (N, n_a) [rad or m].
        qa_dot: Rates (N, n_a), or ``None`` (to be filtered).
        qa_ddot: Accelerations (N, n_a), or ``None``.
        tau: Efforts (N, n_a) [N m or N], or ``None``.
        source: File name, for messages.

    """

    t: np.ndarray
    qa: np.ndarray
    qa_dot: np.ndarray | None = None
    qa_ddot: np.ndarray | None = None
    tau: np.ndarray | None = None
    source: str = "data"

    def __post_init__(self) -> None:
        from pkdyn.inputs import instance, matrix, vector

        instance("source", self.source, str, "a name for messages (str)")
        t = vector("t", self.t, unit="s", bound=MAX_VALUE)
        if t.size < 2:
            raise InvalidInputError("t", f"{t.size} samples: at least 2")
        object.__setattr__(self, "t", t)  # (frozen: the checked copies replace what was given)
        qa = matrix("qa", self.qa, t.size, None, "rad or m", bound=MAX_VALUE)
        object.__setattr__(self, "qa", qa)
        for name in ("qa_dot", "qa_ddot", "tau"):
            value = getattr(self, name)
            if value is not None:
                arr = matrix(name, value, t.size, qa.shape[1], bound=MAX_VALUE)
                object.__setattr__(self, name, arr)


MAX_BYTES = 512_000_000
"""Largest motion file read [bytes] (several million samples)."""
MAX_VALUE = 1e9
"""Largest magnitude of a time, position, rate or effort in a motion file [SI units]."""
MIN_STEP = 1e-9
"""Smallest time step between samples [s]."""


def _check_file(p: Path, src: str) -> None:
    """Refuse a missing file, a directory, a FIFO or a device, or a file too large, unopened."""
    import stat

    try:
        st = p.stat()
    except OSError as err:
        raise InvalidInputError(src, f"cannot be read ({err.strerror or err})") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else "a FIFO, device or socket"
        raise InvalidInputError(src, f"cannot be read: {kind}, not a regular file")
    if st.st_size > MAX_BYTES:
        raise InvalidInputError(
            src, f"is {st.st_size / 1e6:.3g} MB, more than the {MAX_BYTES / 1e6:.3g} MB accepted"
        )


def _read_table(path: Path) -> tuple[list[str], np.ndarray]:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise InvalidInputError(str(path), f"cannot read the file ({err.strerror})") from None
    except UnicodeDecodeError:
        raise InvalidInputError(str(path), "not a text CSV file") from None
    lines = text.lstrip("\ufeff").splitlines()  # (a spreadsheet's byte-order mark)
    if not lines or not lines[0].strip():
        raise InvalidInputError(str(path), "empty file: expected a header line t,qa_...,tau_...")
    header = [h.strip() for h in lines[0].split(",")]
    body = [ln for ln in lines[1:] if ln.strip()]
    if not body:
        raise InvalidInputError(str(path), "no data rows after the header")
    import pyarrow as pa
    from pyarrow import csv as pacsv

    try:
        table = pacsv.read_csv(
            pa.py_buffer(("\n".join([",".join(header), *body]) + "\n").encode()),
            convert_options=pacsv.ConvertOptions(
                column_types={h: pa.float64() for h in header}, strings_can_be_null=True
            ),
        )
    except (pa.ArrowInvalid, pa.ArrowTypeError) as err:
        msg = str(err).splitlines()[0]
        raise InvalidInputError(str(path), f"malformed CSV ({msg})") from None
    cols = [table.column(i).to_numpy(zero_copy_only=False) for i in range(table.num_columns)]
    return header, np.column_stack([np.asarray(c, dtype=float) for c in cols])


@public
def read_measurements(
    path: str | os.PathLike[str], actuators: list[str], need_tau: bool = True
) -> Measurements:
    """Read and check a measured motion (module doc).

    Args:
        path: CSV file.
        actuators: Actuator names of the robot, in order.
        need_tau: The ``tau_*`` columns are required.

    Returns:
        The measurements.

    Raises:
        InvalidInputError: Missing, unknown or duplicated columns, values that are not finite,
            times that do not increase, fewer than 2 rows.

    """
    from pkdyn.inputs import instance, names

    instance("path", path, str | os.PathLike, "a CSV file name")
    actuators = list(names("actuators", actuators, what="actuator"))
    p = Path(path)
    src = str(path)
    _check_file(p, src)
    header, X = _read_table(p)
    seen: set[str] = set()
    for h in header:
        if h in seen:
            raise InvalidInputError(src, f"column '{h}' is given twice")
        seen.add(h)
    groups = {
        "qa": [f"qa_{a}" for a in actuators],
        "qa_dot": [f"qa_dot_{a}" for a in actuators],
        "qa_ddot": [f"qa_ddot_{a}" for a in actuators],
        "tau": [f"tau_{a}" for a in actuators],
    }
    known = {"t", *(c for cols in groups.values() for c in cols)}
    extra = [h for h in header if h not in known]
    if extra:
        raise InvalidInputError(
            src,
            f"unknown column '{extra[0]}' (the columns are t, qa_<actuator>, qa_dot_<actuator>, "
            f"qa_ddot_<actuator>, tau_<actuator> with the actuators {', '.join(actuators)})",
        )
    required = ["t", *groups["qa"], *(groups["tau"] if need_tau else [])]
    missing = [c for c in required if c not in seen]
    if missing:
        raise InvalidInputError(
            src, f"missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)}"
        )
    for g in ("qa_dot", "qa_ddot", "tau"):
        have = [c for c in groups[g] if c in seen]
        if have and len(have) != len(actuators):
            absent = [c for c in groups[g] if c not in seen]
            raise InvalidInputError(src, f"missing column {absent[0]} (give all {g}_* or none)")
    if ("qa_dot_" + actuators[0] in seen) != ("qa_ddot_" + actuators[0] in seen):
        raise InvalidInputError(src, "give both the qa_dot_* and qa_ddot_* columns, or neither")
    bad = ~np.isfinite(X)
    if bad.any():
        row, col = (int(i) for i in np.argwhere(bad)[0])
        raise InvalidInputError(
            src, f"row {row + 2}, column '{header[col]}': not a finite number (NaN or empty)"
        )
    if X.shape[0] < 2:
        raise InvalidInputError(src, "fewer than 2 samples")
    big = np.abs(X) > MAX_VALUE
    if big.any():
        row, col = (int(i) for i in np.argwhere(big)[0])
        raise InvalidInputError(
            src,
            f"row {row + 2}, column '{header[col]}': {X[row, col]:g} is beyond any plausible "
            f"value (at most {MAX_VALUE:g} in SI units)",
        )
    idx = {h: i for i, h in enumerate(header)}
    t = X[:, idx["t"]]
    dt = np.diff(t)
    if np.any(dt <= 0.0):
        k = int(np.flatnonzero(dt <= 0.0)[0])
        raise InvalidInputError(src, f"row {k + 3}, column 't': times must increase")
    if np.any(dt < MIN_STEP):
        k = int(np.flatnonzero(dt < MIN_STEP)[0])
        raise InvalidInputError(
            src, f"row {k + 3}, column 't': a time step of {dt[k]:g} s (at least {MIN_STEP:g} s)"
        )

    def cols(g: str) -> np.ndarray | None:
        names = groups[g]
        return X[:, [idx[c] for c in names]] if names[0] in idx else None

    qa = cols("qa")
    assert qa is not None
    return Measurements(t, qa, cols("qa_dot"), cols("qa_ddot"), cols("tau"), src)
