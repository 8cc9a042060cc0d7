"""Rods on revolute joints: the driven and passive links the library builders share.

A *driven rod* is a crank, an arm or a proximal link: a solid rod on an actuated revolute joint
with its transmission (the Delta's arms, the planar robots' proximal links, the knee's and the
ankle's cranks). A *passive rod* is a coupler, a distal link or a beam: a solid rod on a passive
revolute joint (effort 0). Each link is named after its joint.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from pkdyn.library._colors import BLUE, ORANGE
from pkdyn.model.formats.urdf_writer import Shape, UrdfWriter, Vec

__all__ = ["PASSIVE_VELOCITY", "driven_rod", "passive_rod"]

PASSIVE_VELOCITY = 1e3
"""Velocity limit written on passive revolute joints [rad/s] (effort 0: they are not driven)."""

_ORIGIN = (0.0, 0.0, 0.0)


def driven_rod(
    w: UrdfWriter,
    name: str,
    parent: str,
    rod: tuple[Vec, Vec],
    mass: float,
    radius: float,
    *,
    xyz: Vec,
    axis: Vec,
    limit: tuple[float, float, float, float],
    actuator: str,
    reduction: float,
    rpy: Vec = _ORIGIN,
    rotor_inertia: float = 0.0,
    efficiency: float = 1.0,
    extra_visuals: Sequence[Shape] = (),
) -> None:
    """Write a rod on an actuated revolute joint ``name``, and its transmission.

    Args:
        w: The description being written.
        name: Link, joint and transmission name.
        parent: Parent link.
        rod: Rod start and end in the link frame [m].
        mass: Rod mass [kg].
        radius: Rod radius [m].
        xyz: Joint origin in the parent frame [m].
        axis: Joint axis.
        limit: ``(lower, upper, effort, velocity)`` [rad, N m, rad/s], joint side.
        actuator: Actuator (motor) name.
        reduction: Motor-to-joint reduction.
        rpy: Joint orientation in the parent frame [rad].
        rotor_inertia: Motor-side rotor inertia [kg m^2] (written when non-zero).
        efficiency: Gearbox efficiency (written when below 1).
        extra_visuals: More visual shapes of the link (an elbow).

    """
    w.rod(name, mass, radius, rod[0], rod[1], BLUE, extra_visuals)
    w.joint(name, "revolute", parent, name, xyz=xyz, rpy=rpy, axis=axis, limit=limit)
    w.transmission(name, actuator, reduction, rotor_inertia, efficiency)


def passive_rod(
    w: UrdfWriter,
    name: str,
    parent: str,
    rod: tuple[Vec, Vec],
    mass: float,
    radius: float,
    *,
    xyz: Vec,
    axis: Vec,
    rpy: Vec = _ORIGIN,
    lower: float = -math.pi,
    upper: float = math.pi,
) -> None:
    """Write a rod on a passive revolute joint ``name`` (range ``[lower, upper]`` [rad]).

    Args:
        w: The description being written.
        name: Link and joint name.
        parent: Parent link.
        rod: Rod start and end in the link frame [m].
        mass: Rod mass [kg].
        radius: Rod radius [m].
        xyz: Joint origin in the parent frame [m].
        axis: Joint axis.
        rpy: Joint orientation in the parent frame [rad].
        lower: Lower joint limit [rad].
        upper: Upper joint limit [rad].

    """
    w.rod(name, mass, radius, rod[0], rod[1], ORANGE)
    limit = (lower, upper, 0.0, PASSIVE_VELOCITY)
    w.joint(name, "revolute", parent, name, xyz=xyz, rpy=rpy, axis=axis, limit=limit)
