"""Mechanical energy of the whole mechanism: kinetic, gravitational and elastic (springs)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from solvers.energy import KineticEnergy

__all__ = ["elastic_energy", "mechanical_energy"]


@public
def mechanical_energy(robot: Robot, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """Kinetic and gravitational potential energy of the whole mechanism.

    Args:
        robot: The robot.
        q: Configuration (nq,).
        v: Velocity (nv,).

    Returns:
        ``(kinetic, potential)`` [J] (potential relative to the world origin).

    """
    model, data = robot.model, robot.data
    kinetic = KineticEnergy(model)(model, data, q, v)  # with every joint's armature
    potential = float(pin.computePotentialEnergy(model, data, q))
    return kinetic, potential


@public
def elastic_energy(robot: Robot, q: np.ndarray) -> float:
    """Potential energy of the robot's springs (joint and two-frame springs) at ``q``.

    Args:
        robot: The robot.
        q: Configuration (nq,).

    Returns:
        The energy [J] (zero at the springs' rest positions; zero without springs).

    """
    return 0.0 if robot.passive is None else robot.passive.potential(q)
