"""The platform Jacobian: how the platform moves per joint velocity, built in this one place.

``J_p`` (6, nv) maps the joint velocities ``v`` (increments applied by ``pin.integrate``) to the
platform's motion: the linear velocity of a **reference point** fixed on the platform (its frame
origin unless one is given, in platform-frame coordinates) in world axes [m/s], then the angular
velocity of the platform [rad/s], expressed in one of two axes:

- ``angular="world"``: world axes, the convention of the precision layer (stiffness, compliance,
  modes: ``w = -K d`` with ``d`` a rotation vector in world axes, DESIGN's precision
  conventions);
- ``angular="platform"``: the platform frame, the **task convention** of the kinematic models,
  the pose sensitivities and the error budgets (``log3(R0^T R)``, the rows of
  :class:`solvers.FramePoseTask` at zero error); ``omega_world = R omega_platform``.

The kinematic models (:mod:`pkdyn.analysis.kinematics`), the sensitivities of accuracy and
calibration (:mod:`pkdyn.precision.sensitivity`) and the condensation of the elastic model
(:mod:`pkdyn.precision.condensation`) all take it from here; the passive joints are eliminated
from it by :func:`solvers.numerics.passive_elimination`.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError

__all__ = ["ANGULAR_AXES", "PLATFORM_HINT", "PlatformRobot", "platform_jacobian"]

PLATFORM_HINT = (
    'declare one: <pkdyn:platform link="LINK" task="x y z"/> in the URDF (urdf/README.md), '
    "or 'platform: {frame: LINK}' in its YAML sidecar"
)
"""How to declare a platform, for the messages of the commands that need one."""

ANGULAR_AXES = ("world", "platform")
"""Axes of the angular rows: world (precision) or the platform frame (task convention)."""

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class PlatformRobot(Protocol):
    """What the platform Jacobian reads of a robot (a :class:`~pkdyn.model.robot.Robot`)."""

    @property
    def name(self) -> str:
        """The robot's name (for messages)."""

    @property
    def model(self) -> pin.Model:
        """Pinocchio model of the spanning tree."""

    @property
    def data(self) -> pin.Data:
        """Pinocchio data of ``model`` (the joint Jacobians are computed in it)."""

    @property
    def platform_frame(self) -> int | None:
        """Frame id of the platform, or ``None``."""


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def platform_jacobian(
    robot: PlatformRobot,
    q: np.ndarray | None = None,
    *,
    point: np.ndarray | None = None,
    angular: str = "world",
) -> np.ndarray:
    """The platform Jacobian (6, nv) (module docstring).

    Args:
        robot: The robot (a :class:`~pkdyn.model.robot.Robot`; it must declare a platform
            frame).
        q: Configuration (nq,): the joint Jacobians are computed at it (in ``robot.data``);
            ``None``: ``robot.data`` already holds them (``pin.computeJointJacobians``, e.g.
            after the closure Jacobian at the same configuration).
        point: Reference point in the platform frame [m] (default: the frame's origin).
        angular: ``world`` or ``platform``: the axes of the angular rows.

    Returns:
        ``J_p`` (6, nv): reference point velocity [m/s] (world axes), angular velocity [rad/s].

    Raises:
        InvalidInputError: No platform frame, or unknown ``angular``.

    """
    fid = robot.platform_frame
    if fid is None:
        raise InvalidInputError(
            "robot", f"{robot.name} declares no platform frame; {PLATFORM_HINT}"
        )
    if angular not in ANGULAR_AXES:
        raise InvalidInputError("angular", f"'{angular}': use {' or '.join(ANGULAR_AXES)}")
    model, data = robot.model, robot.data
    if q is not None:
        pin.computeJointJacobians(model, data, q)
    R = pin.updateFramePlacement(model, data, fid).rotation
    J = np.array(pin.getFrameJacobian(model, data, fid, _LWA)).reshape(6, model.nv)  # (nv = 1)
    if point is not None and np.any(point):
        J[:3] -= _skew(R @ np.asarray(point, dtype=float)) @ J[3:]
    if angular == "platform":
        J[3:] = R.T @ J[3:]
    return J
