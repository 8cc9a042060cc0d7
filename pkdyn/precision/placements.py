"""The placements of a description that manufacturing errors move.

A **placement** is a rigid transform of the description that a manufacturing error changes:

- the placement of every tree joint in its parent body (the URDF joint ``<origin>``), except the
  free-flyer and planar joints that only place a platform or a floating base (modelling devices,
  :data:`pkdyn.model.robot.MODELLING_JOINTS`: their placement is absorbed by their motion);
- the placement of each closure frame in its body (the two ``<pkdyn:frame>`` of a closure);
- the platform frame in its body (``<pkdyn:platform xyz rpy>``: the tool, the measured frame).

An error of a placement ``M`` is a twist ``xi = (v, w)`` (6,) [m, rad] in the frame it places:
``M -> M exp(xi)`` (right perturbation). For a joint it is the error of its URDF ``<origin>``
(``origin exp(xi)``); its component along a 1-DOF joint's motion axis shifts that joint's zero:
for an actuated joint, the actuator's **offset** [rad or m]. The parameter models
(:mod:`pkdyn.precision.parameters`) map parameters to these twists.
"""

from __future__ import annotations

from dataclasses import dataclass

import pinocchio as pin

from pkdyn.model.robot import MODELLING_JOINTS, Robot

__all__ = ["COMPONENTS", "Placement", "local_placement", "placement_frames", "placements"]

COMPONENTS = ("tx", "ty", "tz", "rx", "ry", "rz")
"""Names of a placement twist's components (translation [m], rotation [rad], placed frame)."""


@dataclass(frozen=True)
class Placement:
    """A placement of the description that a manufacturing error moves.

    Attributes:
        kind: ``joint`` (a tree joint's origin), ``closure`` (a closure frame) or ``platform``.
        name: Joint name, ``<closure>/1`` or ``<closure>/2``, or ``platform``.
        joint: Pinocchio id of the joint the placed frame moves with (for a joint placement,
            that joint; 0 for a frame on the ground).
        closure: Closure name (closure frames), else ``""``.
        side: 1 or 2 for a closure frame (its first or second ``<pkdyn:frame>``), else 0.

    """

    kind: str
    name: str
    joint: int
    closure: str = ""
    side: int = 0


def placements(robot: Robot) -> tuple[Placement, ...]:
    """The placements of a robot a manufacturing error moves, in a fixed order.

    Joints (model order, modelling joints excluded), then the closure frames (closure order,
    frame 1 then frame 2), then the platform frame.

    Args:
        robot: The robot.

    Returns:
        The placements.

    """
    model = robot.model
    out = [
        Placement("joint", str(model.names[j]), j)
        for j in range(1, model.njoints)
        if model.joints[j].shortname() not in MODELLING_JOINTS
    ]
    first = _first_constraint(robot)
    for c in robot.closures:
        cm = robot.constraint_models[first[c.name]]
        out.append(Placement("closure", f"{c.name}/1", int(cm.joint1_id), c.name, 1))
        out.append(Placement("closure", f"{c.name}/2", int(cm.joint2_id), c.name, 2))
    if robot.platform_frame is not None:
        out.append(
            Placement("platform", "platform", int(model.frames[robot.platform_frame].parentJoint))
        )
    return tuple(out)


def _first_constraint(robot: Robot) -> dict[str, int]:
    """Index of the first constraint model of each closure (its frames, before hinge arms)."""
    first: dict[str, int] = {}
    for k, owner in enumerate(robot.constraint_owner):
        first.setdefault(owner, k)
    return first


def placement_frames(robot: Robot, data: pin.Data, where: tuple[Placement, ...]) -> list[pin.SE3]:
    """World placement of each placed frame, from the joint placements in ``data``.

    For a joint, the frame just after its origin (before its motion); for a closure frame, the
    frame of its ``<pkdyn:frame>``; for the platform, the platform frame.

    Args:
        robot: The robot.
        data: Pinocchio data after ``forwardKinematics`` at the configuration.
        where: The placements (:func:`placements`).

    Returns:
        One world placement per placement.

    """
    model = robot.model
    first = _first_constraint(robot)
    out = []
    for pl in where:
        if pl.kind == "joint":
            out.append(data.oMi[model.parents[pl.joint]] * model.jointPlacements[pl.joint])
        elif pl.kind == "closure":
            cm = robot.constraint_models[first[pl.closure]]
            M = cm.joint1_placement if pl.side == 1 else cm.joint2_placement
            out.append(data.oMi[pl.joint] * M)
        else:
            assert robot.platform_frame is not None
            f = model.frames[robot.platform_frame]
            out.append(data.oMi[f.parentJoint] * f.placement)
    return out


def local_placement(robot: Robot, pl: Placement) -> pin.SE3:
    """The placement itself: in the parent joint frame (joints) or in the frame's joint frame.

    Args:
        robot: The robot.
        pl: One of its placements.

    Returns:
        ``M`` such that an error ``xi`` makes it ``M exp(xi)``.

    """
    model = robot.model
    if pl.kind == "joint":
        return pin.SE3(model.jointPlacements[pl.joint])
    if pl.kind == "closure":
        cm = robot.constraint_models[_first_constraint(robot)[pl.closure]]
        return pin.SE3(cm.joint1_placement if pl.side == 1 else cm.joint2_placement)
    assert robot.platform_frame is not None
    return pin.SE3(model.frames[robot.platform_frame].placement)
