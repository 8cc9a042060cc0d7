"""Trajectories read from CSV files: in actuator space or in task space.

A table (CSV or Parquet, read by :func:`pkdyn.tables.read_table`: its rules and limits) with one
row per sample; a column ``t`` [s], strictly increasing, and either

- **actuator space**: ``qa_<actuator>`` for every actuator (``robot.actuator_names``), the
  actuators' **readings** [rad or m] (turned into joint coordinates by
  :meth:`pkdyn.Robot.joint_coordinates`: a calibrated description's encoder gains applied), the
  motion given to the actuators (the platform follows by the direct geometric model, sample
  after sample in one assembly mode); or
- **task space**: the platform pose components the robot controls, among ``x y z`` [m] and
  ``roll pitch yaw`` [rad] (the others may be given; they are not imposed).

Rates and accelerations are second-order finite differences of the positions (on uneven times
too, ``numpy.gradient``); angles are unwrapped first. The result is the task trajectory of the
platform (for :func:`pkdyn.dynamics.trajectory.map_task_trajectory`, or the fastest cycle's
path): in actuator space, the platform poses the direct model gives.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pkdyn.dynamics.trajectory import MAX_SAMPLES, TaskTrajectory
from pkdyn.exceptions import InvalidInputError, TrajectoryError
from pkdyn.model.assembly import forward_geometry
from pkdyn.model.pose import pose_to_vector
from pkdyn.model.robot import PLATFORM_HINT, Robot
from pkdyn.tables import read_table

__all__ = ["TASK_COLUMNS", "read_task_csv"]

TASK_COLUMNS = ("x", "y", "z", "roll", "pitch", "yaw")
"""The task-space columns, in pose order."""

MAX_BYTES = 256_000_000
"""Largest trajectory file read [bytes] (a FIFO or a device is refused before it is opened)."""


def _rates(t: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Second-order finite-difference first and second derivatives of ``x`` (N, k)."""
    d = np.gradient(x, t, axis=0, edge_order=2)
    return d, np.gradient(d, t, axis=0, edge_order=2)


def read_task_csv(robot: Robot, path: str | Path) -> TaskTrajectory:
    """The platform trajectory of a CSV file (see the module docstring).

    Args:
        robot: The robot (with a platform).
        path: The file.

    Returns:
        The task trajectory (poses and their finite-difference rates).

    Raises:
        InvalidInputError: No platform, unreadable file, missing ``t`` or columns, times not
            increasing, bad numbers, too many samples.
        TrajectoryError: Actuator values that cannot be assembled (the sample is named).

    """
    if robot.platform_frame is None:
        raise InvalidInputError(
            "robot", f"{robot.name} declares no platform frame; {PLATFORM_HINT}"
        )
    p = Path(path)
    table = read_table(
        p, "sample", max_rows=MAX_SAMPLES, min_rows=3, hint="resample the trajectory coarser"
    )
    head = list(table.columns)
    if "t" not in table:
        raise table.error(f"no column 't' (time [s]) among {', '.join(head)}")
    t = table.column("t")
    steps = np.diff(t)
    if not np.all(steps > 0.0):
        k = int(np.argmax(steps <= 0.0))
        raise table.error(f"t = {t[k + 1]:g} s does not increase", k + 1, "t")
    names = robot.actuator_names
    qa_cols = [f"qa_{n}" for n in names]
    home = np.concatenate(pose_to_vector(robot.platform_placement(robot.q_home)))
    if any(c in head for c in qa_cols):
        missing = [c for c in qa_cols if c not in head]
        if missing:
            raise table.error(
                f"actuator column(s) {', '.join(missing)} missing (needs {', '.join(qa_cols)})"
            )
        qa = robot.joint_coordinates(table.select(qa_cols))
        pose = np.empty((t.size, 6))
        q = robot.q_home
        for k in range(t.size):
            try:
                q = forward_geometry(robot, qa[k], q_init=q).q
            except Exception as err:  # noqa: BLE001 (a pkdyn error: named by sample)
                raise TrajectoryError(str(err), sample=k, time=float(t[k])) from None
            pose[k] = np.concatenate(pose_to_vector(robot.platform_placement(q)))
        what = "actuator"
    else:
        rows = [int(r) for r in robot.task_rows]
        need = [TASK_COLUMNS[r] for r in rows]
        missing = [c for c in need if c not in head]
        if missing:
            raise table.error(
                f"give the actuators ({', '.join(qa_cols)}) or the controlled pose "
                f"components ({', '.join(need)}); missing {', '.join(missing)}"
            )
        pose = np.tile(home, (t.size, 1))
        for r, c in enumerate(TASK_COLUMNS):
            if c in head:
                pose[:, r] = table.column(c)
        what = "task"
    pose[:, 3:] = np.unwrap(pose[:, 3:], axis=0)
    pd, pdd = _rates(t, pose)
    return TaskTrajectory(t - t[0], pose, pd, pdd, name=f"{p.name} ({what} space)")
