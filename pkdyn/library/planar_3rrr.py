"""Planar 3-RRR parallel robot (seed 001, "3R Plan", Pasqui).

Three RRR chains in the plane z = 0: chain ``i`` has its actuated revolute at the base point
``O_1^i = (a_i, b_i)`` (by default on a circle of radius ``base_radius`` at 210, 330 and 90 deg),
a proximal link ``l1``, a passive elbow, a distal link ``l2`` and a passive revolute on the
platform at ``B_i = P + h (cos(phi + gamma_i), sin(phi + gamma_i))``. All axes are along z; the
platform pose is ``(x, y, phi)``. Defaults: ``l1 = l2 = 0.3``, ``h = 0.1``, ``base_radius = 0.5``
m, radial attachments; home pose ``(0, 0, 0)`` with every elbow at ``q_2^i ~ +96 deg``.

Model: the platform (link ``effector``) rides on a ``planar`` joint whose frame sits at the home
pose (so its neutral coordinates are the home pose); each chain is the tree
``base -> proximal{i}`` (actuated revolute, coordinate ``q_1^i``: absolute angle of the
proximal link from the base x axis, as in the seed) ``-> distal{i}`` (passive revolute,
coordinate ``q_2^i - q_2^i(home)`` so that its neutral value is the home elbow angle), closed on
the platform by the ``hinge`` closure ``loop{i}`` about z. Actuators ``motor1..3`` drive
``proximal1..3`` in that order. Task: ``x y rz``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from pkdyn.closed_form import planar_3rrr as cf
from pkdyn.exceptions import ParameterError
from pkdyn.library._check import in_range, positive, within_limits
from pkdyn.library._colors import GREY
from pkdyn.library._planar import check_chain, write_rr_chain
from pkdyn.library._render import builder_text
from pkdyn.model.formats.urdf_writer import Shape, UrdfWriter

__all__ = ["NAME", "SUMMARY", "Params", "build_urdf", "home", "layout", "resolved"]

NAME = "planar_3rrr"
"""Family name (``pkdyn.load`` and the CLI take it)."""
SUMMARY = "Planar 3-RRR, three actuated base revolutes, triangular platform (Pasqui's 3R plan)"
"""One-line description of the family (``pkdyn info``, the family registry)."""

_ANGLES = (7.0 * math.pi / 6.0, 11.0 * math.pi / 6.0, math.pi / 2.0)


@dataclass(frozen=True)
class Params:
    """Planar 3-RRR parameters (SI units).

    Attributes:
        l1: Proximal (actuated) link length [m].
        l2: Distal link length [m].
        h: Platform centre to platform joint [m].
        base_radius: Radius of the circle of base points [m].
        base_angles: Polar angles of the base points on that circle [rad]
            (default 210, 330, 90 deg).
        base_points: Explicit base points ``((a_1, b_1), (a_2, b_2), (a_3, b_3))`` [m]; when
            given, they replace ``base_radius`` and ``base_angles``.
        platform_angles: Attachment angles ``gamma_i`` of the platform joints in the platform
            frame [rad] (default 210, 330, 90 deg: radial, facing the base points).
        elbow: Working mode of every chain: ``+1`` for ``sin q_2^i > 0`` (elbows
            counter-clockwise), ``-1`` for the mirror mode.
        x_home: Platform x at the home pose [m]; ``None`` (default): the centroid of the base
            points (0 for the default base).
        y_home: Platform y at the home pose [m]; ``None`` (default): the centroid's y.
        phi_home: Platform orientation at the home pose [rad].
        proximal_mass: Mass of a proximal link [kg].
        distal_mass: Mass of a distal link [kg].
        platform_mass: Platform mass [kg].
        link_radius: Link tube radius (inertia, display, collision) [m].
        q_min: Lower limit of the actuated angles ``q_1^i`` [rad].
        q_max: Upper limit of the actuated angles ``q_1^i`` [rad].
        effort: Joint-side actuator torque limit [N m].
        velocity: Joint-side actuator speed limit [rad/s].
        reduction: Gear reduction between motor and proximal link.

    """

    l1: float = 0.30
    l2: float = 0.30
    h: float = 0.10
    base_radius: float = 0.50
    base_angles: tuple[float, float, float] = _ANGLES
    base_points: tuple[tuple[float, float], ...] = ()
    platform_angles: tuple[float, float, float] = _ANGLES
    elbow: int = 1
    x_home: float | None = None
    y_home: float | None = None
    phi_home: float = 0.0
    proximal_mass: float = 0.50
    distal_mass: float = 0.30
    platform_mass: float = 0.40
    link_radius: float = 0.012
    q_min: float = -math.pi
    q_max: float = math.pi
    effort: float = 20.0
    velocity: float = 6.0
    reduction: float = 10.0

    def __post_init__(self) -> None:
        check_chain(NAME, self)
        positive(NAME, h=self.h, base_radius=self.base_radius, platform_mass=self.platform_mass)
        for name in ("base_angles", "platform_angles"):
            _angles(name, getattr(self, name))
        if self.base_points:
            pts = self.base_points
            if len(pts) != 3 or any(not isinstance(pt, tuple | list) or len(pt) != 2 for pt in pts):
                raise ParameterError(NAME, "base_points", "give three (a_i, b_i) pairs [m]")
            if not all(isinstance(v, int | float) and math.isfinite(v) for pt in pts for v in pt):
                raise ParameterError(NAME, "base_points", f"must be finite numbers, got {pts!r}")
        if self.elbow not in (-1, 1):
            raise ParameterError(NAME, "elbow", f"must be +1 or -1, got {self.elbow!r}")
        for name in ("x_home", "y_home", "phi_home"):
            if getattr(self, name) is not None:
                in_range(NAME, name, getattr(self, name), -math.inf, math.inf)
        q, ok = cf.inverse(self, self.home_pose, self.elbow)
        if not ok[0]:
            raise ParameterError(
                NAME,
                "x_home",
                f"home pose {self.home_pose.tolist()} is out of reach with these lengths "
                "(check l1, l2, h and the base points)",
            )
        within_limits(NAME, q[0], self.q_min, self.q_max)

    @property
    def base_xy(self) -> np.ndarray:
        """Base points ``(a_i, b_i)``, shape (3, 2) [m]."""
        if self.base_points:
            return np.array(self.base_points, dtype=float)
        a = np.asarray(self.base_angles, dtype=float)
        return self.base_radius * np.column_stack([np.cos(a), np.sin(a)])

    @property
    def home_pose(self) -> np.ndarray:
        """Home platform pose ``(x, y, phi)`` [m, m, rad] (unset x, y: the base centroid)."""
        base = self.base_xy
        c = base.mean(axis=0)
        c[np.abs(c) < 1e-12 * float(np.max(np.abs(base)))] = 0.0  # the symmetric default: 0
        x = c[0] if self.x_home is None else self.x_home
        y = c[1] if self.y_home is None else self.y_home
        return np.array([x, y, self.phi_home])


def _angles(name: str, values: tuple[float, ...]) -> None:
    if len(values) != 3 or not all(isinstance(v, int | float) and math.isfinite(v) for v in values):
        raise ParameterError(NAME, name, f"give three finite angles [rad], got {values!r}")


def home(p: Params) -> list[float]:
    """Actuated angles ``q_1^i`` [rad] at the home pose, in the ``elbow`` working mode."""
    q, _ = cf.inverse(p, p.home_pose, p.elbow)
    return [float(v) for v in q[0]]


def resolved(p: Params) -> Params:
    """The parameters with the derived ones (``x_home``, ``y_home``) computed."""
    x, y, _ = (float(v) for v in p.home_pose)
    return dataclasses.replace(p, x_home=x, y_home=y)


def layout(p: Params) -> UrdfWriter:
    """The elements of the pkdyn description of a planar 3-RRR with parameters ``p``.

    :func:`build_urdf` renders them; :mod:`pkdyn.model.candidate` reads their numbers.
    """
    w = UrdfWriter("planar_3rrr")
    base = p.base_xy
    r = p.link_radius
    # Display layers (kinematics is in z = 0): proximal links, distal links, platform.
    z_prox, z_dist, z_plat = 0.0, 2.5 * r, 5.0 * r
    reach = float(np.max(np.linalg.norm(base, axis=1)))
    w.link(
        "base",
        visuals=[
            Shape("cylinder", (2.0 * r, 2.0 * r), (float(a), float(b), z_prox - 2.0 * r), rgba=GREY)
            for a, b in base
        ]
        + [Shape("cylinder", (reach + 2.0 * r, 0.004), (0.0, 0.0, z_prox - 3.0 * r), rgba=GREY)],
        collisions=[
            Shape("cylinder", (2.0 * r, 2.0 * r), (float(a), float(b), z_prox - 2.0 * r))
            for a, b in base
        ],
    )
    angles, _ = cf.chain_angles(p, p.home_pose, p.elbow)
    for i in range(3):
        k = i + 1
        _, q2, _ = (float(v) for v in angles[0, i])
        # elbow frame turned by the home elbow angle: coordinate q_2^i - q_2^i(home)
        _, dist = write_rr_chain(
            w, p, k, (float(base[i, 0]), float(base[i, 1])), q2, z_prox, z_dist
        )
        gamma = p.platform_angles[i]
        w.closure(
            f"loop{k}",
            "hinge",
            (dist, (p.l2, 0.0, 0.0), (0.0, 0.0, 0.0)),
            ("effector", (p.h * math.cos(gamma), p.h * math.sin(gamma), 0.0), (0.0, 0.0, 0.0)),
            axis=(0.0, 0.0, 1.0),
        )
    thick = 2.0 * r
    I_p = p.platform_mass * np.diag(
        [(3 * p.h**2 + thick**2) / 12, (3 * p.h**2 + thick**2) / 12, p.h**2 / 2]
    )
    w.link(
        "effector",
        p.platform_mass,
        (0, 0, z_plat),
        I_p,
        visuals=[Shape("cylinder", (p.h, thick), (0.0, 0.0, z_plat), rgba=GREY)],
        collisions=[Shape("cylinder", (p.h, thick), (0.0, 0.0, z_plat))],
    )
    w.joint(
        "effector",
        "planar",
        "base",
        "effector",
        xyz=(float(p.home_pose[0]), float(p.home_pose[1]), 0.0),
        rpy=(0, 0, p.phi_home),
    )
    w.platform("effector", ("x", "y", "rz"))
    return w


def build_urdf(p: Params) -> str:
    """URDF text, with pkdyn extension elements, of a planar 3-RRR with parameters ``p``."""
    return builder_text(layout(p), __name__)
