"""Payloads rigidly attached to the platform."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.inputs import non_negative
from pkdyn.model.arguments import public
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import PLATFORM_HINT, Robot

__all__ = ["with_payload"]


@public
def with_payload(
    robot: Robot,
    mass: float,
    offset: Sequence[float] = (0.0, 0.0, 0.0),
    inertia: Sequence[float] | np.ndarray | None = None,
) -> Robot:
    """A copy of ``robot`` carrying a payload rigidly attached to the platform.

    Args:
        robot: The robot (unchanged).
        mass: Payload mass [kg] (>= 0).
        offset: Payload centre of mass in the platform frame [m].
        inertia: Rotational inertia about its centre of mass, platform axes (3, 3) [kg m^2]
            (default: a point mass).

    Returns:
        A robot whose platform body includes the payload (same joints, closures and home).

    Raises:
        InvalidInputError: Negative, non-finite or absurd (beyond 1e9 kg) mass, or a robot
            without platform.

    """
    mass = non_negative("payload", mass, "kg")
    if robot.platform_frame is None:
        raise InvalidInputError(
            "robot", f"{robot.name} declares no platform to carry a payload; {PLATFORM_HINT}"
        )
    c = as_finite("offset", offset, 3)
    if inertia is None:
        I3 = np.zeros((3, 3))
    else:
        from pkdyn.inputs import vector

        I3 = vector("inertia", inertia, 9, "kg m^2").reshape(3, 3)
    model = pin.Model(robot.model)
    frame = model.frames[robot.platform_frame]
    joint = frame.parentJoint
    # payload inertia expressed in the joint frame
    body = pin.Inertia(float(mass), c, I3)
    model.inertias[joint] = model.inertias[joint] + frame.placement.act(body)
    return dataclasses.replace(robot, model=model, data=model.createData())
