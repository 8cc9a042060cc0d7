"""The robot's actuation as the robot-agnostic solvers see it."""

from __future__ import annotations

from pkdyn.model.robot import Robot
from solvers import Actuation

__all__ = ["actuation"]


def actuation(robot: Robot) -> Actuation:
    """The robot's actuation for the solvers (joint-side efforts: unit gains).

    Args:
        robot: The robot.

    Returns:
        Actuated velocity indices and names, in actuator order.

    """
    return Actuation(robot.actuated_v, names=robot.actuator_names)
