"""The robot's actuation and drives (motors, gearboxes) as the robot-agnostic solvers see them.

The drive model (:class:`solvers.Drives`): rotor inertia reflected on the joint as the armature
``N^2 J`` of the actuated coordinate (set in ``robot.model.armature`` by the loader, so every
dynamics algorithm includes it), gearbox efficiency (driving / back-driven) and motor friction
between the motor torque ``tau_m`` and the joint-side effort ``tau_j``. Joint-side efforts are
what :func:`pkdyn.dynamics.inverse_dynamics` returns; :func:`motor_efforts` turns them into
motor torques.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.description import ActuatorSpec
from pkdyn.model.robot import Robot
from solvers import Actuation, Drives

__all__ = ["actuation", "drives", "motor_efforts", "with_drives"]

DRIVE_SMOOTHING = 0.1
"""Motor speed [rad/s] over which the sign of the Coulomb friction and the driving / back-driven
efficiency blend smoothly (:class:`solvers.Drives`)."""


@public
def actuation(robot: Robot) -> Actuation:
    """The robot's actuation for the solvers (joint-side efforts: unit gains).

    Args:
        robot: The robot.

    Returns:
        Actuated velocity indices and names, in actuator order.

    """
    return Actuation(robot.actuated_v, names=robot.actuator_names)


def drives(robot: Robot) -> Drives:
    """The drive model of the robot's actuators, from their transmissions.

    Args:
        robot: The robot.

    Returns:
        Reductions, rotor inertias, efficiencies and motor friction, in actuator order.

    """
    acts = robot.actuators
    return Drives(
        [a.reduction for a in acts],
        rotor_inertia=[a.rotor_inertia for a in acts],
        efficiency=[a.efficiency for a in acts],
        backdrive_efficiency=[
            a.efficiency if a.backdrive_efficiency is None else a.backdrive_efficiency for a in acts
        ],
        viscous=[a.viscous for a in acts],
        coulomb=[a.coulomb for a in acts],
        smoothing=DRIVE_SMOOTHING,
    )


def motor_efforts(robot: Robot, tau: np.ndarray, qa_dot: np.ndarray) -> np.ndarray:
    """Motor torques giving joint-side efforts ``tau`` (exact inverse of the drive model).

    Args:
        robot: The robot.
        tau: Joint-side efforts (..., n_a) [N m or N], armature included (as returned by
            :func:`pkdyn.dynamics.inverse_dynamics`).
        qa_dot: Actuator rates (..., n_a) [rad/s or m/s].

    Returns:
        Motor torques (..., n_a) [N m].

    """
    return drives(robot).motor_effort(tau, qa_dot)


def _values(what: str, x: float | Sequence[float] | None, n: int) -> np.ndarray | None:
    if x is None:
        return None
    arr = np.asarray(x, dtype=float).reshape(-1)
    if arr.size == 1:
        arr = np.full(n, float(arr[0]))
    if arr.size != n or not np.all(np.isfinite(arr)):
        raise InvalidInputError(what, f"expected one or {n} finite values, got {x!r}")
    return arr


def with_drives(
    robot: Robot,
    rotor_inertia: float | Sequence[float] | None = None,
    efficiency: float | Sequence[float] | None = None,
    backdrive_efficiency: float | Sequence[float] | None = None,
    viscous: float | Sequence[float] | None = None,
    coulomb: float | Sequence[float] | None = None,
    reduction: float | Sequence[float] | None = None,
) -> Robot:
    """A copy of ``robot`` with other drive parameters (``None``: keep the robot's).

    The model's armature follows: ``reduction^2 rotor_inertia`` replaces the previous reflected
    inertia of each actuated coordinate.

    Args:
        robot: The robot (unchanged).
        rotor_inertia: Motor-side rotor inertia, one for all or per actuator [kg m^2], >= 0.
        efficiency: Driving gearbox efficiency, in (0, 1].
        backdrive_efficiency: Back-driven efficiency, in (0, 1] (default: ``efficiency``).
        viscous: Motor viscous friction [N m s/rad], >= 0.
        coulomb: Motor Coulomb friction [N m], >= 0.
        reduction: Reduction (motor speed / joint speed), non-zero.

    Returns:
        The robot with the new drives (same model otherwise, new data).

    Raises:
        InvalidInputError: Values of the wrong size, not finite, or out of range.

    """
    n = len(robot.actuators)
    new = {
        "rotor_inertia": _values("rotor_inertia", rotor_inertia, n),
        "efficiency": _values("efficiency", efficiency, n),
        "backdrive_efficiency": _values("backdrive_efficiency", backdrive_efficiency, n),
        "viscous": _values("viscous", viscous, n),
        "coulomb": _values("coulomb", coulomb, n),
        "reduction": _values("reduction", reduction, n),
    }
    if new["efficiency"] is not None and new["backdrive_efficiency"] is None:
        new["backdrive_efficiency"] = new["efficiency"]
    acts: list[ActuatorSpec] = []
    for i, a in enumerate(robot.actuators):
        changes: dict[str, Any] = {k: float(v[i]) for k, v in new.items() if v is not None}
        acts.append(dataclasses.replace(a, **changes))
    old = drives(robot)
    try:
        d = Drives(
            [a.reduction for a in acts],
            rotor_inertia=[a.rotor_inertia for a in acts],
            efficiency=[a.efficiency for a in acts],
            backdrive_efficiency=[
                a.efficiency if a.backdrive_efficiency is None else a.backdrive_efficiency
                for a in acts
            ],
            viscous=[a.viscous for a in acts],
            coulomb=[a.coulomb for a in acts],
        )
    except ValueError as err:
        raise InvalidInputError("drives", str(err)) from None
    model = pin.Model(robot.model)
    arm = np.array(model.armature)
    arm[robot.actuated_v] += d.armature - old.armature
    model.armature = np.maximum(arm, 0.0)
    desc = dataclasses.replace(robot.description, actuators=tuple(acts))
    return dataclasses.replace(
        robot, model=model, data=model.createData(), actuators=tuple(acts), description=desc
    )
