"""Calibration measurements: actuator readings and what was measured of the platform.

Kinds (:data:`KINDS`):

- ``pose``: the platform frame's position [m] and orientation (roll, pitch, yaw [rad], fixed
  axes x, y, z) in the measurement frame, which is the robot's world frame;
- ``position``: its position only;
- ``point`` (implicit, self-calibration): the platform origin was held on one fixed but unknown
  point per ``group`` (a ball socket on the table) while the actuators moved; nothing is
  measured but the readings;
- ``plane`` (implicit): the platform origin touched one unknown plane per ``group`` (a probe on
  a surface plate);
- ``joints`` (implicit, extra sensors): redundant encoders on passive joints read their
  coordinates [rad or m] (``q_<joint>`` columns, any subset of the robot's passive 1-DoF
  joints); the platform is not measured at all. A joint encoder's zero is the rotation (or
  translation) of the joint's placement along its axis, which the placement model holds.

Implicit kinds add unknowns (the point's 3 coordinates, the plane's normal and offset) that the
calibration identifies with the robot's parameters.

Table file (:func:`read_csv`: CSV or Parquet, read by :func:`pkdyn.tables.read_table` with its
rules and limits): one row per measurement, columns ``qa_<actuator>`` (actuator **readings**
[rad or m], every actuator, by name: the robot turns them into joint coordinates,
:meth:`pkdyn.Robot.joint_coordinates`) and ``x y z`` (position), ``x y z rx ry rz`` (pose),
``group`` (``point`` and ``plane``, which the caller names), or ``q_<joint>`` (``joints``: read
whenever such columns are present). Missing or extra columns are refused with one line naming
them.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.pose import pose_to_vector
from pkdyn.model.robot import Robot

__all__ = ["KINDS", "Measurements", "measurable_joints", "read_csv", "write_csv"]

KINDS = ("pose", "position", "point", "plane", "joints")
"""Measurement kinds (module docstring)."""

MAX_BYTES = 16_000_000
"""Largest measurements file read [bytes] (about 150,000 rows of six numbers)."""
MAX_ROWS = 20_000
"""Most measurements accepted: each calibration iteration solves the forward geometry at every
pose (about a millisecond each), and a few hundred well chosen poses identify any model."""
MAX_GROUP = 2**31 - 1
"""Largest group number of implicit measurements."""

ROWS = {"pose": 6, "position": 3, "point": 3, "plane": 1}
"""Residual rows per measurement of each kind (``joints``: one per measured joint)."""


@dataclass(eq=False)  # numpy fields: no boolean ==
class Measurements:
    """Actuator readings and platform measurements.

    Attributes:
        kind: One of :data:`KINDS`.
        qa: Actuator readings (N, n_a) [rad or m], in actuator order.
        position: Measured platform positions (N, 3) [m] (``pose`` and ``position``).
        rpy: Measured roll, pitch, yaw (N, 3) [rad] (``pose``).
        group: Group of each measurement (N,) int (``point`` and ``plane``: one unknown point
            or plane per group).
        joints: Names of the measured passive joints (``joints``).
        q: Their measured coordinates (N, len(joints)) [rad or m] (``joints``).
        lines: Line (CSV) or row (Parquet) of each measurement in its file (N,), for
            messages; ``None`` for measurements made in memory.
        source: The file they were read from (``""``: made in memory).
        line_word: ``line`` (CSV) or ``row`` (Parquet), for messages.

    """

    kind: str
    qa: np.ndarray
    position: np.ndarray | None = None
    rpy: np.ndarray | None = None
    group: np.ndarray | None = None
    joints: tuple[str, ...] = ()
    q: np.ndarray | None = None
    _rotations: np.ndarray | None = field(default=None, repr=False)
    lines: np.ndarray | None = field(default=None, repr=False)
    source: str = ""
    _rows: np.ndarray | None = field(default=None, repr=False)
    line_word: str = field(default="line", repr=False)

    def where(self, i: int) -> str:
        """``line L`` of its file (``row R`` of a Parquet file, or of the measurements given)."""
        from pkdyn.inputs import count

        i = count("i", i, 0, len(self.qa) - 1)
        if self.lines is not None:
            return f"{self.line_word} {int(self.lines[int(i)])}"
        if self._rows is not None:
            return f"row {int(self._rows[int(i)])}"
        return f"row {int(i) + 1}"

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InvalidInputError("kind", f"'{self.kind}': use one of {', '.join(KINDS)}")
        from pkdyn.inputs import MAX_MAGNITUDE

        self.qa = _finite("qa", _array("qa", self.qa, 2))
        if len(self.qa) > MAX_ROWS:
            raise InvalidInputError(
                "qa",
                f"{len(self.qa)} measurements: at most {MAX_ROWS} (each calibration iteration "
                "solves the forward geometry at every pose)",
            )
        n = len(self.qa)
        needs = {
            "pose": ("position", "rpy"),
            "position": ("position",),
            "point": ("group",),
            "plane": ("group",),
            "joints": (),
        }[self.kind]
        from pkdyn.inputs import names

        self.joints = names("joints", self.joints, what="joint", empty=True)
        if self.kind == "joints":
            if not self.joints or self.q is None:
                raise InvalidInputError(
                    "joints", "joints measurements need the joint names and their coordinates q"
                )
            q = _finite("q", _array("q", self.q, 2))
            if q.shape != (n, len(self.joints)):
                raise InvalidInputError(
                    "q", f"expected {n} rows of {len(self.joints)} values, got {q.shape}"
                )
            if np.any(np.abs(q) > MAX_MAGNITUDE):
                raise InvalidInputError("q", "a joint coordinate beyond any plausible value")
            if len(set(self.joints)) != len(self.joints):
                raise InvalidInputError("joints", f"a joint is named twice: {self.joints}")
            self.q = q
        for name in ("position", "rpy", "group"):
            value = getattr(self, name)
            if name in needs and value is None:
                raise InvalidInputError(name, f"{self.kind} measurements need {name}")
            if value is None:
                continue
            arr = _array(name, value, 1 if name == "group" else 2)
            want = n if name == "group" else 3 * n
            if arr.size != want:
                shape = f"{n} values" if name == "group" else f"{n} rows of 3 values"
                raise InvalidInputError(name, f"expected {shape}, got {arr.shape}")
            arr = arr.reshape(-1) if name == "group" else arr.reshape(n, 3)
            arr = _finite(name, arr)
            if np.any(np.abs(arr) > MAX_MAGNITUDE):
                row = int(np.argwhere(np.abs(arr) > MAX_MAGNITUDE)[0][0])
                raise InvalidInputError(
                    name,
                    f"{self.where(row)} holds a value beyond any plausible one (at most 1e9)",
                )
            if name == "group":
                if np.any(arr != np.round(arr)):
                    raise InvalidInputError("group", "groups are whole numbers")
                arr = arr.astype(int)
            setattr(self, name, arr)

    def __len__(self) -> int:
        return len(self.qa)

    def check_groups(self) -> None:
        """Refuse implicit groups too small to fix their unknowns (a point: 2, a plane: 4).

        Raises:
            InvalidInputError: The first group that is too small.

        """
        if self.group is None:
            return
        need = 2 if self.kind == "point" else 4
        for g in np.unique(self.group):
            n = int(np.sum(self.group == g))
            if n < need:
                raise InvalidInputError(
                    "group",
                    f"group {g} has {n} calibration measurements; a {self.kind} group needs at "
                    f"least {need}",
                )

    @property
    def rows(self) -> int:
        """Residual rows per measurement."""
        return len(self.joints) if self.kind == "joints" else ROWS[self.kind]

    @property
    def rotations(self) -> np.ndarray:
        """Measured rotation matrices (N, 3, 3) (``pose``)."""
        if self._rotations is None:
            assert self.rpy is not None
            self._rotations = np.array([pin.rpy.rpyToMatrix(*r) for r in self.rpy])
        return self._rotations

    def subset(self, idx: np.ndarray | Sequence[int]) -> Measurements:
        """The measurements of some rows (their indices, each in ``0 .. len - 1``)."""
        from pkdyn.inputs import count

        flat = _array("idx", idx, 1).reshape(-1)  # (none: an empty subset)
        i = np.array([count("idx", v, 0, len(self.qa) - 1) for v in flat], dtype=int)
        return Measurements(
            self.kind,
            self.qa[i],
            None if self.position is None else self.position[i],
            None if self.rpy is None else self.rpy[i],
            None if self.group is None else self.group[i],
            self.joints,
            None if self.q is None else self.q[i],
            lines=None if self.lines is None else self.lines[i],
            source=self.source,
            _rows=(np.arange(1, len(self) + 1) if self._rows is None else self._rows)[i],
            line_word=self.line_word,
        )

    def with_readings(self, qa: np.ndarray) -> Measurements:
        """The same measurements with other actuator values (N, n_a) (e.g. joint coordinates)."""
        from pkdyn.inputs import matrix

        rows, cols = self.qa.shape
        qa = matrix("qa", qa, rows, cols, "rad or m", bound=np.inf)  # (the reach: the caller's)
        return Measurements(
            self.kind,
            qa,
            self.position,
            self.rpy,
            self.group,
            self.joints,
            self.q,
            lines=self.lines,
            source=self.source,
            _rows=self._rows,
            line_word=self.line_word,
        )

    @classmethod
    def from_placements(
        cls, qa: np.ndarray, placements: Sequence[pin.SE3], kind: str = "pose"
    ) -> Measurements:
        """Measurements of platform placements (``pose`` or ``position``).

        Args:
            qa: Actuator readings (N, n_a).
            placements: Platform placements (N).
            kind: ``pose`` or ``position``.

        Returns:
            The measurements.

        """
        if (
            isinstance(placements, pin.SE3)
            or not isinstance(placements, Sequence)
            or not all(isinstance(M, pin.SE3) for M in placements)
        ):
            raise InvalidInputError("placements", "expected a sequence of pin.SE3 placements")
        vec = [pose_to_vector(M) for M in placements]
        P = np.array([v[0] for v in vec]).reshape(-1, 3)
        rpy = np.array([v[1] for v in vec]).reshape(-1, 3) if kind == "pose" else None
        return cls(kind, qa, P, rpy)


def _array(name: str, value: Any, ndim: int) -> np.ndarray:
    """``value`` as a float array of at most ``ndim`` dimensions (2: rows of values)."""
    if isinstance(value, str | bytes | dict):
        raise InvalidInputError(name, f"expected an array of numbers, got {value!r:.60}")
    try:
        arr = np.asarray(value)
        if np.iscomplexobj(arr):
            raise TypeError
        arr = np.asarray(arr, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(
            name, f"expected an array of numbers (rows as long), got {value!r:.60}"
        ) from None
    arr = np.atleast_2d(arr) if ndim == 2 else arr
    if arr.ndim > ndim:
        raise InvalidInputError(name, f"expected {ndim} dimensions at most, got shape {arr.shape}")
    if ndim == 2 and arr.shape[1] == 0:
        raise InvalidInputError(name, "no value: give one row of values per measurement")
    return arr


def _finite(name: str, arr: np.ndarray) -> np.ndarray:
    bad = ~np.isfinite(arr)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        raise InvalidInputError(name, f"row {row + 1} holds NaN or an infinite value")
    return arr


def measurable_joints(robot: Robot) -> list[str]:
    """Names of the passive 1-DoF joints (revolute or prismatic) an encoder could read."""
    act = {int(j) for j in robot.actuated_joints}
    out = []
    for jid in range(1, robot.model.njoints):
        j = robot.model.joints[jid]
        if jid not in act and j.nq == 1 and j.nv == 1:
            out.append(str(robot.model.names[jid]))
    return out


def _columns(robot: Robot, kind: str, joints: Sequence[str] = ()) -> list[str]:
    qa = [f"qa_{a}" for a in robot.actuator_names]
    if kind == "joints":
        return qa + [f"q_{j}" for j in joints]
    tail = {
        "pose": ["x", "y", "z", "rx", "ry", "rz"],
        "position": ["x", "y", "z"],
        "point": ["group"],
        "plane": ["group"],
    }[kind]
    return qa + tail


@public
def read_csv(path: str | os.PathLike[str], robot: Robot, kind: str | None = None) -> Measurements:
    """Measurements from a table file (module docstring): CSV or Parquet.

    The file is read by :func:`pkdyn.tables.read_table` (its rules: quoting, encodings, empty,
    non-numeric and non-finite cells, ragged rows, limits), then its columns are checked.

    Args:
        path: The file.
        robot: The robot (its actuator names give the ``qa_<actuator>`` columns).
        kind: ``point`` or ``plane`` for implicit measurements (a ``group`` column); default:
            ``joints`` when ``q_<joint>`` columns are present, ``pose`` when ``rx ry rz`` are,
            else ``position``.

    Returns:
        The measurements (readings as recorded: :func:`~pkdyn.calibration.calibrate` applies the
        robot's readings rule).

    Raises:
        InvalidInputError: Missing, extra or repeated columns, non-numeric or NaN cells, no
            rows, or an unreadable file (one line naming what is wrong).

    """
    from pkdyn.tables import read_table

    table = read_table(
        path,
        "measurement",
        MAX_BYTES,
        MAX_ROWS,
        hint="each calibration iteration solves the forward geometry at every pose; a few "
        "hundred well chosen poses suffice (pkdyn.calibration.selection)",
    )
    src = table.source
    header = list(table.columns)
    sensors = [c[2:] for c in header if c.startswith("q_")]
    if kind is None:
        if sensors:
            kind = "joints"
        else:
            kind = "pose" if {"rx", "ry", "rz"} & set(header) else "position"
    if kind not in KINDS:
        raise InvalidInputError("kind", f"'{kind}': use one of {', '.join(KINDS)}")
    if kind == "joints":
        known = measurable_joints(robot)
        for name in sensors:
            if name not in known:
                from pkdyn.exceptions import close_match

                raise InvalidInputError(
                    src,
                    f"column q_{name}: '{name}' is not a passive 1-DoF joint of {robot.name}"
                    f"{close_match(name, known)} (measurable: {', '.join(known) or 'none'})",
                )
        if not sensors:
            raise InvalidInputError(
                src, "joints measurements need q_<joint> columns (passive joint encoders)"
            )
    want = _columns(robot, kind, sensors)
    missing = [c for c in want if c not in header]
    extra = [c for c in header if c not in want]
    if missing or extra:
        parts = []
        if missing:
            parts.append(f"missing column(s) {', '.join(missing)}")
        if extra:
            parts.append(f"unexpected column(s) {', '.join(extra)}")
        raise InvalidInputError(
            src, f"{'; '.join(parts)} (a {kind} table has exactly: {' '.join(want)})"
        )
    data = table.select(want)
    n_a = len(robot.actuators)
    qa = data[:, :n_a]
    at = {"lines": table.lines, "source": src, "line_word": table.where(0).split()[0]}
    if kind == "pose":
        P, rpy = data[:, n_a : n_a + 3], data[:, n_a + 3 : n_a + 6]
        return Measurements(kind, qa, P, rpy, **at)  # type: ignore[arg-type]
    if kind == "position":
        return Measurements(kind, qa, data[:, n_a : n_a + 3], **at)  # type: ignore[arg-type]
    if kind == "joints":
        joints = tuple(c[2:] for c in want[n_a:])
        return Measurements(kind, qa, joints=joints, q=data[:, n_a:], **at)  # type: ignore[arg-type]
    return Measurements(kind, qa, group=data[:, n_a], **at)  # type: ignore[arg-type]


@public
def write_csv(path: str | os.PathLike[str], robot: Robot, m: Measurements) -> None:
    """Write measurements as a table :func:`read_csv` reads back exactly (atomically).

    CSV, or Parquet when the file name ends in ``.parquet``.

    Args:
        path: The file.
        robot: The robot (actuator names).
        m: The measurements.

    """
    from pkdyn.inputs import instance
    from pkdyn.tables import write_table

    instance("m", m, Measurements, "Measurements (pkdyn.calibration.read_csv)")

    cols = _columns(robot, m.kind, m.joints)
    if m.kind == "joints":
        assert m.q is not None
        data = np.hstack([m.qa, m.q])
    elif m.kind == "pose":
        assert m.position is not None and m.rpy is not None
        data = np.hstack([m.qa, m.position, m.rpy])
    elif m.kind == "position":
        assert m.position is not None
        data = np.hstack([m.qa, m.position])
    else:
        assert m.group is not None
        data = np.hstack([m.qa, m.group[:, None]])
    write_table(path, cols, data)
