"""The standard dynamic parameters of a closed-loop robot, in groups one can identify or hold.

The efforts are linear in these parameters (:mod:`pkdyn.identification.regressor`):

- ``inertia``: 10 per moving body of the spanning tree (every Pinocchio joint whose body has a
  mass), Pinocchio's dynamic parameters in the joint frame, in its order
  ``m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz`` [kg, kg m, kg m^2]: the mass, the first moment
  ``m c`` and the rotational inertia about the joint origin (``pin.Inertia.toDynamicParameters``);
- ``payload``: the same 10 for a payload rigidly attached to the platform, in the platform frame
  (nominal zero). When it is identified the platform body's own parameters are held at their
  nominal values (the two are indistinguishable from the efforts);
- ``friction``: per actuator the motor's viscous [N m s/rad] and Coulomb [N m] friction of the
  drive model (:class:`solvers.Drives`, motor side, as ``<pkdyn:motor_friction>`` writes them);
- ``rotor``: per actuator the rotor inertia [kg m^2], motor side (``<pkdyn:rotor_inertia>``).

Parameters that are not identified are held at the robot's values and their efforts are
subtracted from the measurements.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot

__all__ = [
    "BODY_FIELDS",
    "DEFAULT_GROUPS",
    "GROUPS",
    "ParameterSet",
    "body_links",
    "parameter_set",
    "placement_map",
]

BODY_FIELDS = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
"""Names of a body's 10 parameters, in Pinocchio's order (``toDynamicParameters``)."""

_BODY_UNITS = ("kg", "kg m", "kg m", "kg m", *("kg m^2",) * 6)

GROUPS = ("inertia", "payload", "friction", "rotor")
"""The parameter groups (module docstring)."""

DEFAULT_GROUPS = ("inertia", "friction", "rotor")
"""The groups identified unless told otherwise."""

DRIVE_FIELDS = ("viscous", "coulomb", "rotor_inertia")
"""Names of an actuator's drive parameters."""


@dataclass(frozen=True, eq=False)  # numpy fields: no boolean ==
class ParameterSet:
    """The standard parameters of a robot and which of them are identified.

    Attributes:
        names: Parameter names (p,): ``<link>.<field>``, ``payload.<field>``,
            ``<actuator>.viscous``, ``<actuator>.coulomb``, ``<actuator>.rotor_inertia``.
        units: Their units (p,).
        groups: Group of each parameter (p,).
        nominal: The robot's values (p,) (payload: zero).
        identified: Which parameters are identified (p,) bool.
        bodies: Joint id of each body in the ``inertia`` group, in column order.
        links: URDF link name of each of those bodies.
        payload_joint: Joint id carrying the platform (``None`` without a platform).
        payload_placement: Platform frame in that joint's frame.

    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    groups: tuple[str, ...]
    nominal: np.ndarray
    identified: np.ndarray
    bodies: tuple[int, ...]
    links: tuple[str, ...]
    payload_joint: int | None
    payload_placement: pin.SE3

    @property
    def p(self) -> int:
        """Number of standard parameters."""
        return len(self.names)

    @property
    def chosen(self) -> tuple[str, ...]:
        """The identified groups."""
        return tuple(g for g in GROUPS if any(self.identified & (np.array(self.groups) == g)))

    def index(self, name: str) -> int:
        """Column of a parameter by name."""
        return self.names.index(name)

    def body_slice(self, k: int) -> slice:
        """Columns of the ``k``-th body of :attr:`bodies`."""
        return slice(10 * k, 10 * k + 10)

    @property
    def payload_slice(self) -> slice:
        """Columns of the payload."""
        n = 10 * len(self.bodies)
        return slice(n, n + 10)

    def drive_column(self, actuator: int, field: str) -> int:
        """Column of an actuator's drive parameter (``viscous``, ``coulomb``, ``rotor_inertia``)."""
        return 10 * len(self.bodies) + 10 + 3 * actuator + DRIVE_FIELDS.index(field)


def body_links(robot: Robot) -> dict[int, list[str]]:
    """URDF links of each joint's body, the joint's own link first (Pinocchio BODY frames).

    Args:
        robot: The robot.

    Returns:
        ``{joint id: [link names]}``; links merged into a body by fixed joints follow its own.

    """
    out: dict[int, list[str]] = {}
    for f in robot.model.frames:
        if f.type == pin.FrameType.BODY:
            out.setdefault(int(f.parentJoint), []).append(f.name)
    return out


def placement_map(M: pin.SE3) -> np.ndarray:
    """Linear map (10, 10) of dynamic parameters from a frame to its parent frame.

    For a body whose parameters ``pi`` are given in a frame placed at ``M = (R, p)`` in the
    parent frame: ``m' = m``, ``h' = R h + m p`` and the inertia about the parent origin
    ``I' = R I R^T + m (|p|^2 1 - p p^T) + 2 (p . R h) 1 - (R h) p^T - p (R h)^T``.

    Args:
        M: Placement of the frame in the parent frame.

    Returns:
        ``L`` with ``pi_parent = L pi``.

    """
    R, p = M.rotation, M.translation
    L = np.zeros((10, 10))
    for i in range(10):
        e = np.zeros(10)
        e[i] = 1.0
        m, h = e[0], e[1:4]
        Iv = e[4:]
        I = np.array([[Iv[0], Iv[1], Iv[3]], [Iv[1], Iv[2], Iv[4]], [Iv[3], Iv[4], Iv[5]]])
        Rh = R @ h
        I2 = (
            R @ I @ R.T
            + m * (p @ p * np.eye(3) - np.outer(p, p))
            + 2.0 * (p @ Rh) * np.eye(3)
            - np.outer(Rh, p)
            - np.outer(p, Rh)
        )
        L[0, i] = m
        L[1:4, i] = Rh + m * p
        L[4:, i] = [I2[0, 0], I2[0, 1], I2[1, 1], I2[0, 2], I2[1, 2], I2[2, 2]]
    return L


def _groups(groups: Sequence[str] | str | None) -> tuple[str, ...]:
    if groups is None:
        return DEFAULT_GROUPS
    from pkdyn.inputs import names

    items = (
        groups.replace(",", " ").split()
        if isinstance(groups, str)
        else list(names("parameters", groups, what="group", empty=True))
    )
    bad = [g for g in items if g not in GROUPS]
    if bad or not items:
        raise InvalidInputError(
            "parameters",
            f"unknown group {bad[0]!r}"
            if bad
            else f"no group given; choose among {', '.join(GROUPS)}",
        )
    return tuple(g for g in GROUPS if g in items)


@public
def parameter_set(robot: Robot, groups: Sequence[str] | str | None = None) -> ParameterSet:
    """The standard parameters of a robot, with the chosen groups marked identified.

    Args:
        robot: The robot (its values are the nominal ones).
        groups: Groups to identify (:data:`GROUPS`, a sequence or a comma- or space-separated
            string; default :data:`DEFAULT_GROUPS`).

    Returns:
        The parameter set.

    Raises:
        InvalidInputError: An unknown group, or ``payload`` for a robot without a platform.

    """
    chosen = _groups(groups)
    model = robot.model
    if "payload" in chosen and robot.platform_frame is None:
        raise InvalidInputError("parameters", f"{robot.name} declares no platform for a payload")
    links = body_links(robot)
    bodies = [j for j in range(1, model.njoints) if model.inertias[j].mass > 0.0]
    payload_joint = None
    payload_M = pin.SE3.Identity()
    if robot.platform_frame is not None:
        frame = model.frames[robot.platform_frame]
        payload_joint = int(frame.parentJoint)
        payload_M = pin.SE3(frame.placement)
    names: list[str] = []
    units: list[str] = []
    grp: list[str] = []
    nominal: list[float] = []
    ident: list[bool] = []
    link_names = []
    for j in bodies:
        link = links.get(j, [str(model.names[j])])[0]
        link_names.append(link)
        names += [f"{link}.{f}" for f in BODY_FIELDS]
        units += _BODY_UNITS
        grp += ["inertia"] * 10
        nominal += list(model.inertias[j].toDynamicParameters())
        held = "payload" in chosen and j == payload_joint
        ident += [("inertia" in chosen) and not held] * 10
    names += [f"payload.{f}" for f in BODY_FIELDS]
    units += _BODY_UNITS
    grp += ["payload"] * 10
    nominal += [0.0] * 10
    ident += ["payload" in chosen] * 10
    for a in robot.actuators:
        names += [f"{a.name}.{f}" for f in DRIVE_FIELDS]
        units += ["N m s/rad", "N m", "kg m^2"]
        grp += ["friction", "friction", "rotor"]
        nominal += [a.viscous, a.coulomb, a.rotor_inertia]
        ident += ["friction" in chosen, "friction" in chosen, "rotor" in chosen]
    return ParameterSet(
        tuple(names),
        tuple(units),
        tuple(grp),
        np.array(nominal, dtype=float),
        np.array(ident, dtype=bool),
        tuple(bodies),
        tuple(link_names),
        payload_joint,
        payload_M,
    )
