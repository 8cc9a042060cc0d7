"""Measured motions: the columns of ``pkdyn identify`` and their checks.

A table (CSV or Parquet, read by :func:`pkdyn.tables.read_table`: its rules and limits) with the
columns

- ``t``: time [s], increasing;
- ``qa_<actuator>``: actuator **readings** [rad or m], one per actuator (required); the robot
  turns them into joint coordinates (:meth:`pkdyn.Robot.joint_coordinates`: a calibrated
  description's encoder gains and offsets applied);
- ``qa_dot_<actuator>``, ``qa_ddot_<actuator>``: their rates and accelerations (optional, both
  or neither; without them they come from the positions by zero-phase filtering,
  :mod:`pkdyn.identification.filtering`);
- ``tau_<actuator>``: measured efforts, joint side [N m or N] (reduction x motor torque; required
  to identify, optional in a motion to predict).

Any other column, a missing one, a value beyond :data:`MAX_VALUE`, or times that do not increase
is refused with one line naming the column and the line.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.tables import Table, read_table

__all__ = ["MAX_BYTES", "MAX_SAMPLES", "Measurements", "read_measurements"]


@dataclass(frozen=True, eq=False)  # numpy fields
class Measurements:
    """A measured motion.

    Attributes:
        t: Times (N,) [s].
        qa: Actuator readings (N, n_a) [rad or m] (joint coordinates where the robot has no
            encoder gain or offset).
        qa_dot: Their rates (N, n_a), or ``None`` (to be filtered).
        qa_ddot: Accelerations (N, n_a), or ``None``.
        tau: Efforts (N, n_a) [N m or N], or ``None``.
        source: File name, for messages.
        lines: Line (CSV) or row (Parquet) of each sample in the file (N,), for messages, or
            ``None`` (samples given in memory: counted from 0).
        line_word: ``line`` (CSV) or ``row`` (Parquet), for messages.

    """

    t: np.ndarray
    qa: np.ndarray
    qa_dot: np.ndarray | None = None
    qa_ddot: np.ndarray | None = None
    tau: np.ndarray | None = None
    source: str = "data"
    lines: np.ndarray | None = None
    line_word: str = "line"

    def where(self, k: int) -> str:
        """``line L`` of sample ``k`` in its file (``row R``: Parquet), or ``sample k`` (from 0)."""
        from pkdyn.inputs import count

        k = count("k", k, 0, self.t.size - 1)
        if self.lines is None:
            return f"sample {k}"
        return f"{self.line_word} {int(self.lines[k])}"

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
MAX_SAMPLES = 2_000_000
"""Largest number of samples accepted (about 3 minutes for a Delta on one core)."""
MAX_VALUE = 1e9
"""Largest magnitude of a time, position, rate or effort in a motion file [SI units]."""
MIN_STEP = 1e-9
"""Smallest time step between samples [s]."""


@public
def read_measurements(
    path: str | os.PathLike[str], actuators: list[str], need_tau: bool = True
) -> Measurements:
    """Read and check a measured motion (module doc).

    Args:
        path: CSV or Parquet file.
        actuators: Actuator names of the robot, in order.
        need_tau: The ``tau_*`` columns are required.

    Returns:
        The measurements (readings as recorded: :func:`pkdyn.identification.identify` applies
        the robot's readings rule).

    Raises:
        InvalidInputError: An unreadable file or table (:func:`pkdyn.tables.read_table`);
            missing, unknown or partial column groups; values beyond :data:`MAX_VALUE`; times
            that do not increase.

    """
    from pkdyn.inputs import instance, names

    instance("path", path, str | os.PathLike, "a CSV file name")
    actuators = list(names("actuators", actuators, what="actuator"))
    table = read_table(
        path,
        "data",
        MAX_BYTES,
        MAX_SAMPLES,
        hint="decimate the recording (a few thousand samples of a rich motion identify any robot)",
    )
    src = table.source
    groups = {
        "qa": [f"qa_{a}" for a in actuators],
        "qa_dot": [f"qa_dot_{a}" for a in actuators],
        "qa_ddot": [f"qa_ddot_{a}" for a in actuators],
        "tau": [f"tau_{a}" for a in actuators],
    }
    known = {"t", *(c for cols in groups.values() for c in cols)}
    extra = [h for h in table.columns if h not in known]
    if extra:
        raise InvalidInputError(
            src,
            f"unknown column {extra[0]} (the columns are t, qa_<actuator>, qa_dot_<actuator>, "
            f"qa_ddot_<actuator>, tau_<actuator> with the actuators {', '.join(actuators)})",
        )
    required = ["t", *groups["qa"], *(groups["tau"] if need_tau else [])]
    missing = [c for c in required if c not in table]
    if missing:
        raise InvalidInputError(
            src, f"missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)}"
        )
    for g in ("qa_dot", "qa_ddot", "tau"):
        have = [c for c in groups[g] if c in table]
        if have and len(have) != len(actuators):
            absent = [c for c in groups[g] if c not in table]
            raise InvalidInputError(src, f"missing column {absent[0]} (give all {g}_* or none)")
    if (groups["qa_dot"][0] in table) != (groups["qa_ddot"][0] in table):
        raise InvalidInputError(src, "give both the qa_dot_* and qa_ddot_* columns, or neither")
    _check_values(table)

    def cols(g: str) -> np.ndarray | None:
        return table.select(groups[g]) if groups[g][0] in table else None

    qa = cols("qa")
    assert qa is not None
    return Measurements(
        table.column("t").copy(),
        qa,
        cols("qa_dot"),
        cols("qa_ddot"),
        cols("tau"),
        src,
        table.lines,
        "line" if table.kind == "csv" else "row",
    )


def _check_values(table: Table) -> None:
    """Refuse absurd magnitudes and times that do not increase (the line and column named)."""
    X = table.data
    big = np.abs(X) > MAX_VALUE
    if big.any():
        row, col = (int(i) for i in np.argwhere(big)[0])
        raise table.error(
            f"{X[row, col]:g} is beyond any plausible value (at most {MAX_VALUE:g} in SI units)",
            row,
            table.columns[col],
        )
    t = table.column("t")
    dt = np.diff(t)
    if np.any(dt <= 0.0):
        k = int(np.flatnonzero(dt <= 0.0)[0])
        raise table.error("times must increase", k + 1, "t")
    if np.any(dt < MIN_STEP):
        k = int(np.flatnonzero(dt < MIN_STEP)[0])
        raise table.error(f"a time step of {dt[k]:g} s (at least {MIN_STEP:g} s)", k + 1, "t")
