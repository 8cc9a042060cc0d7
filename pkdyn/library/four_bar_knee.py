"""Four-bar knee: a motor high on the thigh drives the knee through a crank and a coupler rod.

The knee of legged robots that keep the knee motor near the hip to lighten the leg (e.g. the
Kangaroo and Digit legs, many quadrupeds' knee linkages): a planar four-bar whose ground link
is the thigh (from the motor axis to the knee axis), the input the motor crank, the output the
shank's lever. pkdyn's own dimensions: motor 0.30 m above the knee, 0.06 m crank, 0.045 m knee
lever (a knee-to-motor speed ratio of about 1.33 near full extension), 0.35 m shank.

Thigh frame (the base): knee axis along ``y`` at the origin, ``x`` forward, ``z`` up. Tree:
``crank`` (actuated revolute about y at ``(x_motor, 0, a)``, actuator ``motor``, crank along
``+x`` at zero) -> ``coupler`` (revolute at the crank end) and ``knee`` (passive revolute about
y at the origin) -> ``shank`` (hanging along ``-z``, lever ``r3`` along ``+x``, foot mass at its
end); closure ``coupler_pin`` (hinge about y) between the coupler's end and the lever end.
At zero the crank and the lever both point forward and the coupler joins them (its length is
derived, :func:`pkdyn.closed_form.four_bar_knee.coupler_length`), the leg straight. Home: knee
at ``knee_home``. Platform frame: the shank's end, task ``ry`` (the knee angle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pkdyn.closed_form.four_bar_knee import motor_from_knee
from pkdyn.exceptions import ParameterError
from pkdyn.library._check import finite, in_range, positive
from pkdyn.library._colors import GREY
from pkdyn.library._links import PASSIVE_VELOCITY, driven_rod, passive_rod
from pkdyn.library._render import builder_text
from pkdyn.model.formats.urdf_writer import Shape, UrdfWriter

__all__ = ["NAME", "SUMMARY", "Params", "build_urdf", "home", "layout"]

NAME = "four_bar_knee"
"""Family name (``pkdyn.load`` and the CLI take it)."""
SUMMARY = "Four-bar knee: thigh motor drives the knee through a crank and a coupler rod"
"""One-line description of the family (``pkdyn info``, the family registry)."""


@dataclass(frozen=True)
class Params:
    """Four-bar knee parameters (SI units; thigh frame, knee axis at the origin).

    Attributes:
        a: Height of the motor axis above the knee axis [m].
        x_motor: Forward offset of the motor axis [m].
        r1: Crank length [m].
        r3: Knee lever length [m].
        shank_length: Knee to the end of the shank [m].
        shank_mass: Shank mass [kg] (uniform rod).
        foot_mass: Point mass at the end of the shank [kg].
        crank_mass: Crank mass [kg].
        coupler_mass: Coupler mass [kg].
        link_radius: Link radius (inertia, display, collision) [m].
        knee_home: Knee angle of the home configuration [rad] (0: straight leg).
        knee_min: Lower knee limit [rad].
        knee_max: Upper knee limit [rad] (flexion is positive).
        effort: Joint-side motor torque limit [N m].
        velocity: Joint-side motor speed limit [rad/s].
        reduction: Gear reduction between motor and crank.

    """

    a: float = 0.30
    x_motor: float = 0.0
    r1: float = 0.06
    r3: float = 0.045
    shank_length: float = 0.35
    shank_mass: float = 2.0
    foot_mass: float = 1.0
    crank_mass: float = 0.1
    coupler_mass: float = 0.1
    link_radius: float = 0.008
    knee_home: float = 0.3
    knee_min: float = -0.2
    knee_max: float = 1.6
    effort: float = 120.0
    velocity: float = 10.0
    reduction: float = 10.0

    def __post_init__(self) -> None:
        positive(
            NAME,
            a=self.a,
            r1=self.r1,
            r3=self.r3,
            shank_length=self.shank_length,
            shank_mass=self.shank_mass,
            foot_mass=self.foot_mass,
            crank_mass=self.crank_mass,
            coupler_mass=self.coupler_mass,
            link_radius=self.link_radius,
            effort=self.effort,
            velocity=self.velocity,
            reduction=self.reduction,
        )
        finite(NAME, x_motor=self.x_motor)
        in_range(NAME, "knee_min", self.knee_min, -math.pi, self.knee_max)
        in_range(NAME, "knee_max", self.knee_max, self.knee_min, math.pi)
        in_range(NAME, "knee_home", self.knee_home, self.knee_min, self.knee_max)
        _, ok = motor_from_knee(self, np.array([self.knee_home]))
        if not ok[0]:
            raise ParameterError(
                NAME, "knee_home", f"the linkage cannot reach the knee angle {self.knee_home} rad"
            )


def home(p: Params) -> list[float]:
    """Crank angle [rad] of the home knee angle."""
    phi, _ = motor_from_knee(p, np.array([p.knee_home]))
    return [float(phi[0])]


def layout(p: Params) -> UrdfWriter:
    """The elements of the pkdyn description of a four-bar knee with parameters ``p``.

    :func:`build_urdf` renders them; :mod:`pkdyn.model.candidate` reads their numbers.
    """
    w = UrdfWriter(NAME)
    r = p.link_radius
    w.link(
        "thigh",
        visuals=[Shape("cylinder", (1.5 * r, p.a), (0.0, -0.03, 0.5 * p.a), rgba=GREY)],
        collisions=[Shape("cylinder", (1.5 * r, p.a), (0.0, -0.03, 0.5 * p.a))],
    )
    y = (0.0, 1.0, 0.0)
    driven_rod(
        w,
        "crank",
        "thigh",
        ((0.0, 0.0, 0.0), (p.r1, 0.0, 0.0)),
        p.crank_mass,
        r,
        xyz=(p.x_motor, 0.0, p.a),
        axis=y,
        limit=(-math.pi, math.pi, p.effort, p.velocity),
        actuator="motor",
        reduction=p.reduction,
    )
    end = (p.r3 - p.x_motor - p.r1, 0.0, -p.a)  # lever end seen from the crank end, at zero
    passive_rod(
        w,
        "coupler",
        "crank",
        ((0.0, 0.0, 0.0), end),
        p.coupler_mass,
        r,
        xyz=(p.r1, 0.0, 0.0),
        axis=y,
    )
    L = p.shank_length
    m = p.shank_mass + p.foot_mass
    com_z = -(0.5 * p.shank_mass * L + p.foot_mass * L) / m
    i_rod = p.shank_mass * L**2 / 12.0 + p.shank_mass * (0.5 * L + com_z) ** 2
    i_xx = i_rod + p.foot_mass * (L + com_z) ** 2
    w.link(
        "shank",
        m,
        (0.0, 0.0, com_z),
        np.diag([i_xx, i_xx, 0.5 * p.shank_mass * r**2]),
        visuals=[
            Shape("cylinder", (r, L), (0.0, 0.0, -0.5 * L), rgba=GREY),
            Shape("box", (p.r3, 2 * r, 2 * r), (0.5 * p.r3, 0.0, 0.0), rgba=GREY),
            Shape("sphere", (0.03,), (0.0, 0.0, -L), rgba=GREY),
        ],
        collisions=[Shape("cylinder", (r, L), (0.0, 0.0, -0.5 * L))],
    )
    knee_limit = (p.knee_min, p.knee_max, 0.0, PASSIVE_VELOCITY)
    w.joint("knee", "revolute", "thigh", "shank", axis=y, limit=knee_limit)
    w.closure(
        "coupler_pin",
        "hinge",
        ("coupler", end, (0.0, 0.0, 0.0)),
        ("shank", (p.r3, 0.0, 0.0), (0.0, 0.0, 0.0)),
        axis=y,
    )
    w.platform("shank", ("ry",), xyz=(0.0, 0.0, -L))
    return w


def build_urdf(p: Params) -> str:
    """URDF text, with pkdyn extension elements, of a four-bar knee with parameters ``p``."""
    return builder_text(layout(p), __name__)
