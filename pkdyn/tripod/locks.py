"""Lockable passive joints as rigid constraint models (robot-agnostic).

A lock holds some coordinates of a tree joint at fixed values. It is written as one more
Pinocchio rigid constraint model between the joint's child body and its parent body, so every
tool built on constraint models (:class:`solvers.ConstraintSet`, :func:`solvers.solve_lm`,
:class:`solvers.InverseDynamics`, :class:`solvers.ForwardDynamics`, the kinematic models and
singularity analysis of :mod:`pkdyn.analysis.kinematics`) handles locked joints without change; the
lock's multiplier is the force or torque the locking device carries.

- every coordinate of the joint: a ``CONTACT_6D`` weld of the child frame on its placement at the
  locked values (6 equations, of rank ``nv`` of the joint);
- the only coordinate of a revolute joint: a ``CONTACT_3D`` point of the child at
  :data:`LOCK_ARM` from the axis, held on its parent-side position at the locked angle
  (3 equations of rank 1: the point leaves its place iff the angle changes);
- the only coordinate of a prismatic joint: the child origin held on its locked position;
- the second coordinate of a universal joint (the first stays free): a point at
  :data:`LOCK_ARM` on the first axis (which the first rotation leaves in place), held on the
  first axis (it leaves the axis iff the second angle changes).

Redundant equations (rank below the number of rows) are handled as for hinge closures:
minimum-norm Levenberg-Marquardt steps, rank-revealing inverse dynamics, proximal forward
dynamics. Residuals are lengths [m] (``LOCK_ARM`` times the chord of the angle error) or, for
welds, ``log6`` [m, rad].
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError

__all__ = ["LOCK_ARM", "Lock", "lock_constraint", "lock_values"]

LOCK_ARM = 0.1
"""Lever arm [m] of point locks: the locked point's distance from the rotation axis."""

_REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
_PRISMATIC = ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")


@dataclass(frozen=True)
class Lock:
    """Some coordinates of a tree joint held at fixed values.

    Attributes:
        joint: Joint name in the Pinocchio model.
        coordinates: Indices of the locked coordinates within the joint (``(0,)`` for a
            revolute joint; ``(1,)`` or ``(0, 1)`` for a universal joint).
        values: Locked values [rad or m], one per coordinate.
        name: Label reported to the user (e.g. the paper's ``branch1_q3``).

    """

    joint: str
    coordinates: tuple[int, ...]
    values: tuple[float, ...]
    name: str = ""

    def __post_init__(self) -> None:
        if len(self.coordinates) != len(self.values) or not self.coordinates:
            raise InvalidInputError(
                f"lock of '{self.joint}'",
                f"{len(self.coordinates)} coordinates for {len(self.values)} values",
            )
        if not all(np.isfinite(self.values)):
            raise InvalidInputError(f"lock of '{self.joint}'", f"values {self.values} not finite")


def _joint(model: pin.Model, name: str) -> tuple[int, pin.JointModel]:
    if not isinstance(model, pin.Model):
        raise InvalidInputError("model", f"expected a pin.Model (robot.model), got {model!r:.40}")
    if not isinstance(name, str) or not model.existJointName(name):
        raise InvalidInputError("lock", f"no joint named '{name}' in the model")
    j = model.getJointId(name)
    return j, model.joints[j]


def _axis(jm: pin.JointModel) -> np.ndarray:
    """Unit axis (3,) of a revolute or prismatic joint, in its own frame."""
    kind = jm.shortname()
    if kind.endswith(("X", "Y", "Z")) and "Unaligned" not in kind:
        return np.eye(3)["XYZ".index(kind[-1])]
    return np.asarray(jm.extract().axis, dtype=float)


def _relative(jm: pin.JointModel, q: np.ndarray) -> pin.SE3:
    """Joint transform (child frame in the joint frame) of a revolute, prismatic or universal."""
    kind = jm.shortname()
    if kind in _REVOLUTE:
        return pin.SE3(pin.exp3(_axis(jm) * q[0]), np.zeros(3))
    if kind in _PRISMATIC:
        return pin.SE3(np.eye(3), _axis(jm) * q[0])
    u = jm.extract()
    return pin.SE3(pin.exp3(u.axis1 * q[0]) @ pin.exp3(u.axis2 * q[1]), np.zeros(3))


def lock_constraint(
    model: pin.Model, lock: Lock, q: np.ndarray | None = None, arm: float = LOCK_ARM
) -> pin.RigidConstraintModel:
    """Rigid constraint model that holds the locked coordinates (see the module docstring).

    Args:
        model: The kinematic tree.
        lock: Joint, coordinates and values.
        q: Configuration (nq,) giving the joint's free coordinates when the whole joint is not
            locked (only for the record: the constraint does not depend on them).
        arm: Lever arm of point locks [m].

    Returns:
        The constraint model, named ``lock:<joint>[<coordinates>]``; ``joint1`` is the child.

    Raises:
        InvalidInputError: Unknown joint, coordinate out of range, or a lock this module cannot
            express (e.g. the first coordinate of a universal joint alone).

    """
    from pkdyn.inputs import instance, positive, vector

    instance("lock", lock, Lock, "a Lock")
    j, jm = _joint(model, lock.joint)
    arm = positive("arm", arm, "m")
    if q is not None:
        q = vector("q", q, model.nq, "rad or m")
    kind = jm.shortname()
    coords = tuple(int(c) for c in lock.coordinates)
    if sorted(coords) != sorted(set(coords)) or not all(0 <= c < jm.nq for c in coords):
        raise InvalidInputError(
            f"lock of '{lock.joint}'", f"coordinates {coords} not in 0..{jm.nq - 1}"
        )
    if kind not in _REVOLUTE + _PRISMATIC + ("JointModelUniversal",):
        raise InvalidInputError(
            f"lock of '{lock.joint}'",
            f"{kind} joints cannot be locked (revolute, prismatic or universal only)",
        )
    parent = int(model.parents[j])
    jP = model.jointPlacements[j]
    values = np.zeros(jm.nq)
    if q is not None:
        values[:] = np.asarray(q, dtype=float)[jm.idx_q : jm.idx_q + jm.nq]
    for c, v in zip(coords, lock.values, strict=True):
        values[c] = v
    label = ",".join(str(c) for c in coords)
    name = f"lock:{lock.joint}[{label}]"
    if len(coords) == jm.nq and jm.nq > 1:  # the whole universal joint: weld
        cm = pin.RigidConstraintModel(
            pin.ContactType.CONTACT_6D,
            model,
            j,
            pin.SE3.Identity(),
            parent,
            jP * _relative(jm, values),
            pin.ReferenceFrame.LOCAL,
        )
        cm.name = name
        return cm
    if kind in _REVOLUTE:
        axis = _axis(jm)
        helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        p_child = arm * np.cross(axis, helper) / np.linalg.norm(np.cross(axis, helper))
    elif kind in _PRISMATIC:
        p_child = np.zeros(3)
    elif coords == (1,):  # universal, second coordinate: a point on the first axis
        u = jm.extract()
        p_child = arm * (pin.exp3(u.axis2 * values[1]).T @ np.asarray(u.axis1))
    else:
        raise InvalidInputError(
            f"lock of '{lock.joint}'",
            "the first coordinate of a universal joint cannot be locked alone "
            "(lock the second, or both)",
        )
    p_parent = jP * _relative(jm, values) * pin.SE3(np.eye(3), p_child)
    cm = pin.RigidConstraintModel(
        pin.ContactType.CONTACT_3D,
        model,
        j,
        pin.SE3(np.eye(3), p_child),
        parent,
        p_parent,
        pin.ReferenceFrame.LOCAL,
    )
    cm.name = name
    return cm


def lock_values(
    model: pin.Model, q: np.ndarray, joint: str, coordinates: Sequence[int]
) -> tuple[float, ...]:
    """Current values of some coordinates of a joint (to lock it where it stands).

    Args:
        model: The kinematic tree.
        q: Configuration (nq,).
        joint: Joint name.
        coordinates: Coordinate indices within the joint.

    Returns:
        The values [rad or m].

    """
    from pkdyn.inputs import count, vector

    _, jm = _joint(model, joint)
    q = vector("q", q, model.nq, "rad or m")
    if isinstance(coordinates, str | bytes) or not hasattr(coordinates, "__iter__"):
        raise InvalidInputError("coordinates", f"expected indices, got {coordinates!r:.40}")
    idx = [count("coordinates", c, 0, jm.nq - 1) for c in coordinates]
    if not idx:
        raise InvalidInputError("coordinates", "name at least one coordinate")
    return tuple(float(q[jm.idx_q + c]) for c in idx)
