"""Checks of recorded actuator motions before a fit: limits, motion, closures.

Identification (and calibration, for its readings) refuses data that cannot be what it claims,
before fitting anything to it, each with one line naming the line of the file and the column:

- :func:`check_limits`: the actuated joint coordinates of the readings lie within their joints'
  limits (a reading of 147 rad on a joint limited to +-pi is degrees given as radians);
- :func:`check_moves`: the actuators move (a still motion excites nothing but gravity);
- :func:`readings_hint`: what out-of-reach readings look like (degrees for revolute actuators,
  millimetres for prismatic ones), when converting them explains them.

The closures are checked on a coarse pass along the motion (:func:`pkdyn.identification.
identify.identify`), each sample assembled to :data:`~pkdyn.identification.motion.ASSEMBLY_RTOL`
of the robot's size (:meth:`pkdyn.Robot.closure_tolerance`): readings the robot cannot be
assembled at are named with their residual and the robot's size.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.assembly import forward_geometry
from pkdyn.model.robot import Robot

__all__ = ["LIMIT_RTOL", "check_limits", "check_moves", "readings_hint"]

LIMIT_RTOL = 1e-2
"""Tolerance of the limits check, relative to the joint's range (or its actuator's scale): a
recording at a hard stop a little beyond the described limit passes; degrees given as radians
(a hundred times beyond) do not."""


def _factor(robot: Robot) -> np.ndarray:
    """What a reading is multiplied by if it is in degrees (revolute) or millimetres (prismatic)."""
    return np.where(robot.actuator_prismatic, 1e-3, np.pi / 180.0)


def readings_hint(robot: Robot, qa: np.ndarray, columns: np.ndarray | None = None) -> str:
    """``; the readings of motor1 look like degrees (give rad)`` when that explains them, else "".

    Args:
        robot: The robot.
        qa: Actuated joint coordinates (N, n_a) that are out of the robot's reach or limits
            [rad or m].
        columns: The actuators at fault (default: those out of their limits, else all).

    Returns:
        A phrase to append to a message, or ``""``: converted (degrees to radians, millimetres
        to metres), the values must lie within the limits and a few of them assemble.

    """
    qa = np.atleast_2d(np.asarray(qa, dtype=float))
    lo = robot.model.lowerPositionLimit[robot.actuated_q]
    hi = robot.model.upperPositionLimit[robot.actuated_q]
    scaled = qa * _factor(robot)
    if columns is None:
        tol = LIMIT_RTOL * np.where(np.isfinite(hi - lo), hi - lo, robot.actuator_scale)
        outside = ((qa < lo - tol) | (qa > hi + tol)).any(axis=0)
        columns = np.flatnonzero(outside) if outside.any() else np.arange(qa.shape[1])
    cols = np.asarray(columns, dtype=int)
    inside = (scaled[:, cols] >= lo[cols]) & (scaled[:, cols] <= hi[cols])
    if not cols.size or not np.all(inside):
        return ""
    if not np.all(np.isfinite(lo[cols]) | np.isfinite(hi[cols])):
        return ""
    trial = qa.copy()
    trial[:, cols] = scaled[:, cols]
    step = max(1, len(trial) // 5)
    for row in trial[::step][:5]:  # a few of them assemble once converted
        try:
            forward_geometry(robot, row, check_limits=False)
        except PkdynError:
            return ""
    names = ", ".join(robot.actuator_names[int(c)] for c in cols)
    prismatic = robot.actuator_prismatic[cols]
    unit, si = ("millimetres", "m") if np.all(prismatic) else ("degrees", "rad")
    return f"; the readings of {names} look like {unit} (give {si})"


def check_limits(robot: Robot, qa: np.ndarray, source: str, where: Callable[[int], str]) -> None:
    """Refuse actuated joint coordinates beyond their joints' limits.

    Args:
        robot: The robot.
        qa: Joint coordinates of the readings (N, n_a) [rad or m].
        source: The file, for the message.
        where: Where sample ``k`` stands (``line L``), for the message.

    Raises:
        InvalidInputError: The first sample and column beyond the limits (by more than
            :data:`LIMIT_RTOL` of the range), and what the readings look like when that explains
            them (degrees, millimetres).

    """
    lo = robot.model.lowerPositionLimit[robot.actuated_q]
    hi = robot.model.upperPositionLimit[robot.actuated_q]
    tol = LIMIT_RTOL * np.where(np.isfinite(hi - lo), hi - lo, robot.actuator_scale)
    bad = (qa < lo - tol) | (qa > hi + tol)
    if not bad.any():
        return
    i, j = (int(k) for k in np.argwhere(bad)[0])
    unit = "m" if robot.actuator_prismatic[j] else "rad"
    a = robot.actuators[j]
    raise InvalidInputError(
        source,
        f"{where(i)}, column qa_{a.name}: {qa[i, j]:.6g} {unit} lies beyond the limits "
        f"[{lo[j]:.6g}, {hi[j]:.6g}] {unit} of joint {a.joint}"
        + (
            readings_hint(robot, qa, np.flatnonzero(bad.any(axis=0)))
            or readings_hint(robot, qa, np.arange(qa.shape[1]))
        ),
    )


def check_moves(robot: Robot, qa: np.ndarray, source: str) -> None:
    """Refuse a motion in which no actuator moves (beyond 1e-9 of its scale).

    Raises:
        InvalidInputError: Every actuator still.

    """
    travel = np.ptp(qa, axis=0) / robot.actuator_scale
    if np.all(travel <= 1e-9):
        raise InvalidInputError(
            source,
            "the motion does not excite every base parameter: no actuator moves; record a "
            "motion that moves them (pkdyn.identification.excitation)",
        )
