"""Humanoid-style parallel ankle: two motors in the shank drive a 2-DOF ankle through two rods.

The layout of many humanoid ankles (two motors high in the shank, cranks, rods down to the
heel; e.g. Unitree H1-2 / G1, Fourier GR-1, Agility Digit's toe actuation): a 2R-2RSU parallel
mechanism. The dimensions are pkdyn's own choice, of the size of an adult humanoid's ankle
(no vendor drawing was used): motors 0.25 m above the ankle, 0.04 m either side of the shank's
mid-plane, 0.05 m cranks, rods to points 0.08 m behind the ankle axis.

Shank frame (the base): ankle centre at the origin, ``x`` forward, ``z`` up. Tree:

- ``ankle_pitch`` (revolute about y) -> ``ankle_cross`` -> ``ankle_roll`` (revolute about x) ->
  ``foot`` (passive: the joint space of the serial-equivalent ankle);
- for each side ``l`` (``y > 0``) and ``r``: ``crank_<s>`` (actuated revolute about y at
  ``(x_motor, +-d, h)``, actuator ``motor_<s>``, the crank along ``-x`` at zero) ->
  ``rod_<s>`` (universal joint at the crank end, axes across the rod) -> rod of length ``rod``;
- closures ``heel_<s>`` (point: a spherical rod end) between the rod's lower end and the foot
  point ``(x_foot, +-e, z_foot)``.

Mobility 2 (8 coordinates, 6 independent closure equations; the universal upper rod ends leave
no spin). Home: ankle at zero pitch and roll; the motor angles come from the closed form
(:mod:`pkdyn.closed_form.parallel_ankle`). Platform frame: the foot, task ``rx ry``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.closed_form.parallel_ankle import crank_points, foot_points, inverse
from pkdyn.exceptions import ParameterError
from pkdyn.library._check import finite, positive
from pkdyn.library._colors import GREY, ORANGE
from pkdyn.library._links import PASSIVE_VELOCITY, driven_rod
from pkdyn.library._render import builder_text
from pkdyn.model.formats.urdf_writer import Shape, UrdfWriter, rod_inertia

__all__ = ["NAME", "SUMMARY", "Params", "build_urdf", "home", "layout"]

NAME = "parallel_ankle"
"""Family name (``pkdyn.load`` and the CLI take it)."""
SUMMARY = "Humanoid parallel ankle: two shank motors drive ankle pitch and roll through two rods"
"""One-line description of the family (``pkdyn info``, the family registry)."""


@dataclass(frozen=True)
class Params:
    """Parallel ankle parameters (SI units; shank frame, ankle centre at the origin).

    Attributes:
        h: Height of the motor axes above the ankle centre [m].
        d: Lateral offset of each motor from the shank's mid-plane [m].
        x_motor: Forward position of the motor axes [m] (negative: behind the ankle).
        crank: Crank length [m].
        rod: Rod length [m].
        x_foot: Forward position of the rod attachment points on the foot [m].
        e: Lateral offset of the rod attachment points [m].
        z_foot: Height of the rod attachment points in the foot frame [m].
        foot_mass: Foot mass [kg] (centre of mass 0.03 m ahead, 0.05 m below the ankle).
        crank_mass: Mass of a crank [kg].
        rod_mass: Mass of a rod [kg].
        rod_radius: Rod and crank radius (inertia, display, collision) [m].
        pitch_limit: Ankle pitch range +- [rad].
        roll_limit: Ankle roll range +- [rad].
        motor_limit: Motor angle range +- about the home angles [rad].
        effort: Joint-side motor torque limit [N m].
        velocity: Joint-side motor speed limit [rad/s].
        reduction: Gear reduction between motor and crank.

    """

    h: float = 0.25
    d: float = 0.04
    x_motor: float = -0.03
    crank: float = 0.05
    rod: float = 0.25
    x_foot: float = -0.08
    e: float = 0.04
    z_foot: float = 0.0
    foot_mass: float = 1.0
    crank_mass: float = 0.05
    rod_mass: float = 0.03
    rod_radius: float = 0.005
    pitch_limit: float = 0.6
    roll_limit: float = 0.4
    motor_limit: float = 1.5
    effort: float = 40.0
    velocity: float = 10.0
    reduction: float = 10.0

    def __post_init__(self) -> None:
        positive(
            NAME,
            h=self.h,
            d=self.d,
            crank=self.crank,
            rod=self.rod,
            e=self.e,
            foot_mass=self.foot_mass,
            crank_mass=self.crank_mass,
            rod_mass=self.rod_mass,
            rod_radius=self.rod_radius,
            pitch_limit=self.pitch_limit,
            roll_limit=self.roll_limit,
            motor_limit=self.motor_limit,
            effort=self.effort,
            velocity=self.velocity,
            reduction=self.reduction,
        )
        finite(NAME, x_motor=self.x_motor, x_foot=self.x_foot, z_foot=self.z_foot)
        _, ok = inverse(self, np.zeros(2))
        if not ok[0]:
            raise ParameterError(
                NAME,
                "rod",
                f"rods of {self.rod} m cannot join the cranks to the foot at zero pitch and "
                "roll: change rod, crank or the attachment points",
            )


def _rpy_z_to(d: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw of the smallest rotation taking z onto ``d`` (zero when ``d`` is z)."""
    z = np.asarray(d, dtype=float) / float(np.linalg.norm(d))
    axis = np.cross([0.0, 0.0, 1.0], z)
    s = float(np.linalg.norm(axis))
    if s < 1e-15:
        return (0.0, 0.0, 0.0)
    R = pin.AngleAxis(math.atan2(s, float(z[2])), axis / s).matrix()
    rpy = pin.rpy.matrixToRpy(R)
    return (float(rpy[0]), float(rpy[1]), float(rpy[2]))


def home(p: Params) -> list[float]:
    """Motor angles [rad] with the ankle at zero pitch and roll."""
    theta, _ = inverse(p, np.zeros(2))
    return [float(v) for v in theta[0]]


def layout(p: Params) -> UrdfWriter:
    """The elements of the pkdyn description of a parallel ankle with parameters ``p``.

    :func:`build_urdf` renders them; :mod:`pkdyn.model.candidate` reads their numbers.
    """
    w = UrdfWriter(NAME)
    r = p.rod_radius
    w.link(
        "shank",
        visuals=[
            Shape("cylinder", (0.03, p.h + 0.05), (0.0, 0.0, 0.5 * (p.h + 0.05)), rgba=GREY),
            Shape("box", (0.03, 2 * p.d + 0.04, 0.04), (p.x_motor, 0.0, p.h), rgba=GREY),
        ],
        collisions=[Shape("cylinder", (0.03, p.h), (0.0, 0.0, 0.5 * p.h + 0.05))],
    )
    w.link("ankle_cross", 0.02, (0.0, 0.0, 0.0), np.eye(3) * 1e-6)
    I_foot = p.foot_mass / 12.0 * np.diag([0.1**2 + 0.04**2, 0.24**2 + 0.04**2, 0.24**2 + 0.1**2])
    foot_box = Shape("box", (0.24, 0.10, 0.03), (0.03, 0.0, -0.06), rgba=GREY)
    w.link(
        "foot",
        p.foot_mass,
        (0.03, 0.0, -0.05),
        I_foot,
        visuals=[foot_box],
        collisions=[Shape("box", (0.24, 0.10, 0.03), (0.03, 0.0, -0.06))],
    )
    passive = (0.0, PASSIVE_VELOCITY)
    w.joint(
        "ankle_pitch",
        "revolute",
        "shank",
        "ankle_cross",
        axis=(0.0, 1.0, 0.0),
        limit=(-p.pitch_limit, p.pitch_limit, *passive),
    )
    w.joint(
        "ankle_roll",
        "revolute",
        "ankle_cross",
        "foot",
        axis=(1.0, 0.0, 0.0),
        limit=(-p.roll_limit, p.roll_limit, *passive),
    )
    theta0 = np.array(home(p))
    C = crank_points(p, theta0)[0]
    P = foot_points(p, np.zeros(2))[0]
    for k, side in enumerate(("l", "r")):
        sign = 1.0 if side == "l" else -1.0
        crank = f"crank_{side}"
        t0 = float(theta0[k])
        driven_rod(
            w,
            crank,
            "shank",
            ((0.0, 0.0, 0.0), (-p.crank, 0.0, 0.0)),
            p.crank_mass,
            r,
            xyz=(p.x_motor, sign * p.d, p.h),
            axis=(0.0, 1.0, 0.0),
            limit=(t0 - p.motor_limit, t0 + p.motor_limit, p.effort, p.velocity),
            actuator=f"motor_{side}",
            reduction=p.reduction,
        )
        rod = f"rod_{side}"
        # rod frame: z along the rod from its lower end up, at the home configuration, given
        # in the crank frame (turned by theta0 about y)
        up = C[k] - P[k]
        c, s = math.cos(t0), math.sin(t0)
        Ry_T = np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])  # R_y(-t0)
        rpy = _rpy_z_to(Ry_T @ up)
        com, inertia = rod_inertia(p.rod_mass, r, (0.0, 0.0, 0.0), (0.0, 0.0, -p.rod))
        w.link(
            rod,
            p.rod_mass,
            com,
            inertia,
            visuals=[Shape("cylinder", (r, p.rod), (0.0, 0.0, -0.5 * p.rod), rgba=ORANGE)],
            collisions=[Shape("cylinder", (r, p.rod), (0.0, 0.0, -0.5 * p.rod))],
        )
        w.universal(rod, crank, rod, (-p.crank, 0.0, 0.0), rpy, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
        w.closure(
            f"heel_{side}",
            "point",
            (rod, (0.0, 0.0, -p.rod), (0.0, 0.0, 0.0)),
            ("foot", (p.x_foot, sign * p.e, p.z_foot), (0.0, 0.0, 0.0)),
        )
    w.platform("foot", ("rx", "ry"))
    return w


def build_urdf(p: Params) -> str:
    """URDF text, with pkdyn extension elements, of a parallel ankle with parameters ``p``."""
    return builder_text(layout(p), __name__)
