"""Walking tripod of Yang, Krut, Baradat and Pierrot (seed 003), in its machining (PP) mode.

Three identical branches are mounted symmetrically on the nacelle. Branch ``i`` (``i = 1, 2, 3``,
at ``phi_i = 0, 120, 240 deg`` about the nacelle axis, branch 1 along +x) is attached to the
nacelle at ``P_Li`` and ``P_Ri``, on the circle of radius ``r_p`` centred on ``P_O`` at the angles
``phi_i + theta`` and ``phi_i - theta`` (``P_Ci`` is their midpoint, ``theta`` the angle between
``P_O P_Li`` and ``P_O P_Ci``; consecutive edges ``P_L P_R`` make ``psi_p = 2 pi / 3``). Two
prismatic actuators ``q_Li = |A_i P_Li|`` and ``q_Ri = |A_i P_Ri|`` form with the edge a planar
2-DOF triangle of three parallel axes (``a`` at the foot end ``A_i``, ``b`` at ``P_Li``, ``c`` at
``P_Ri``); the triangle plane hinges about the edge (the paper's ``q6``), and ``A_i`` carries the
foot through a universal joint (``q2`` then ``q1``). With all feet fixed on the support, the robot
is a 6-DOF parallel manipulator (mode PP, "payload platform").

Frames (SI units, z up, support surface ``z = 0``):

- ``R_B`` (world, link ``support``); ``R_P`` (link ``nacelle``) at ``P_O``, x axis towards
  ``P_C1``, z axis normal to the nacelle plane; at home ``R_P`` is ``R_B`` raised by
  ``nacelle_height``. The nacelle hangs on a free-flyer (joint ``nacelle``) whose origin is the
  home pose, so the neutral configuration is the home configuration.
- ``R_Ai`` (on link ``branch{i}_foot``): origin ``A_i`` (universal-joint centre, ``foot_height``
  above the foothold), ``w_a`` normal to the support, ``u_a`` radial (outwards), see
  :func:`foothold_frames`.
- The platform (``pkdyn:platform``, task ``x y z rx ry rz``) is the spindle tip, ``tool_offset``
  below ``P_O`` along ``-w_p``.

Tree of branch ``i`` (all passive joints are zero at home; links ``branch{i}_*``):

- ``branch{i}_q6``: revolute, nacelle -> ``edge``, about ``u = P_L P_R / |P_L P_R|`` through
  ``P_L``; value ``q6 - q6_home``.
- ``branch{i}_b``: revolute at ``P_L`` about axis ``b`` (normal to the triangle), edge -> ``cylL``.
- ``branch{i}_qL``: prismatic, actuated (transmission ``L{i}``), ``cylL`` -> ``rodL``; its value
  is the length ``|A P_L|`` (the rod frame origin is ``A``).
- ``branch{i}_c``, ``branch{i}_qR``: the same for the right actuator (``cylR``, ``rodR``,
  transmission ``R{i}``); ``rodR`` closes on ``rodL`` at ``A`` by the ``hinge`` closure
  ``branch{i}_A`` about axis ``a``.
- ``branch{i}_a``: revolute at ``A`` about axis ``a``, ``rodL`` -> ``knuckle``. The knuckle frame
  has x along ``a`` (the paper's ``v3``) and z along the projection of ``w_a`` on the triangle
  plane, so ``q3 = branch{i}_a + gamma_L(home) - gamma_L`` with ``gamma_L`` the angle of the
  triangle at ``A`` between ``A P_C`` and ``A P_L`` (the virtual ``q3`` is measured from
  ``A P_C``, the real joint from the rod ``A P_L``).
- ``branch{i}_q2q1``: universal joint at ``A`` (Pinocchio's ``JointModelUniversal``),
  knuckle -> ``foot``; first axis ``-y`` of the knuckle (the paper's ``q2`` axis, in the triangle
  plane), second axis ``-w_a`` (``q1``); coordinates ``[q2 - q2_home, q1 - q1_home]`` with
  ``q1_home = 0`` and ``q2_home = -q6_home``. The foot link frame is ``R_A`` turned by ``pi``
  about ``w_a`` (x axis inwards) at every configuration.
- ``branch{i}_foothold``: ``weld`` closure of the foot sole on the support.

The virtual ``q4 = |A P_C|`` and ``q5`` (angle between ``P_L P_R`` and ``A P_C``) are carried by
no single joint: ``q4^2 = (q_L^2 + q_R^2) / 2 - e^2 / 4`` and
``sin q5 = (q_R^2 - q_L^2) / (2 e q4)`` with ``e = |P_L P_R| = 2 r_p sin theta``. See
:func:`virtual_joints` for the paper's equations (1)-(8).

**Four-branch walker** (``branches=4``, the paper's proposal in its conclusion): the same branch
design repeated four times, evenly: branch ``i`` at ``phi_i = 90 (i - 1) deg`` with its attachment
points at ``phi_i +- theta`` on the same nacelle circle ``r_p`` and its foothold on the same
circle ``foothold_radius``. Every branch then sees exactly the geometry (home lengths, home passive
angles) of a tripod branch, the nacelle and the spindle are unchanged, and the fourth branch adds
its own mass (9.7 kg by default) and two actuators (``L4``, ``R4``): eight in all, a redundantly
actuated 6-DOF machine in mode PP. Keeping the nacelle radius rather than, say, the gap between
neighbouring branches is the conservative choice for interference: neighbouring legs are 90 deg
apart instead of 120 deg (``theta`` must stay below ``pi / 4``, half the spacing, so that
neighbouring attachment points do not cross). The robot is named ``walker``.

Default dimensions: chosen for a bench-top machining tripod (the paper gives none): ``r_p = 0.3``,
``theta = 0.3 rad`` (17.2 deg), footholds on a circle of radius 0.7 m, nacelle 0.6 m above the
support, universal-joint centres 0.06 m above the footholds, actuator strokes 0.5-0.9 m (home
length 0.686 m, ``q6_home`` = 37.4 deg), spindle tip 0.15 m below ``P_O``; nacelle and spindle
14 kg, 9.7 kg per branch (feet included).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.closed_form.tripod import (
    attachments,
    foothold_frames,
    home_nacelle_placement,
    perpendicular,
    unit_vector,
    virtual_joints,
)
from pkdyn.exceptions import ParameterError
from pkdyn.library._check import in_range, param_items, positive
from pkdyn.library._colors import BLUE, GREY, ORANGE
from pkdyn.library._render import builder_text
from pkdyn.model.formats.urdf_writer import Shape, UrdfWriter, rod_inertia, segment_origin

__all__ = [
    "MOUNT_CLEARANCE",
    "NAME",
    "SUMMARY",
    "Params",
    "build_urdf",
    "home",
    "layout",
]

NAME = "tripod"
"""Family name (``pkdyn.load`` and the CLI take it)."""
SUMMARY = (
    "Walking tripod (Yang et al.), 3 branches of 2 prismatic actuators, feet welded (mode PP); "
    "branches=4: the four-branch walker"
)
"""One-line description of the family (``pkdyn info``, the family registry)."""

MOUNT_CLEARANCE = 0.08
"""Length [m] of an actuator body next to its nacelle attachment (the clevis, inside the
nacelle plate) left out of its collision cylinder, so that leg-to-nacelle distances measure
interference, not the mount."""


@dataclass(frozen=True)
class Params:
    """Tripod parameters (SI units). The paper gives no dimensions; defaults are plausible.

    Attributes:
        r_p: Radius of the circle through the attachment points ``P_L``, ``P_R`` [m].
        theta: Angle between ``P_O P_L`` and ``P_O P_C`` [rad], in ``(0, pi/3)``.
        foothold_radius: Distance of the footholds from the support origin [m] (foothold ``i``
            at angle ``phi_i``).
        foot_height: Height of the universal-joint centre ``A`` above the foot sole [m].
        nacelle_height: Height of ``P_O`` above the support at home [m].
        tool_offset: Spindle tip below ``P_O`` along ``-w_p`` [m] (platform frame).
        stroke_min: Shortest actuator length ``|A P_L|`` or ``|A P_R|`` [m].
        stroke_max: Longest actuator length [m].
        nacelle_mass: Nacelle plate mass [kg].
        spindle_mass: Machining spindle mass [kg] (rigid with the nacelle).
        edge_mass: Mass of the body hinged about the edge ``P_L P_R`` [kg].
        cylinder_mass: Actuator body (motor, screw, tube) mass [kg].
        rod_mass: Actuator rod mass [kg].
        knuckle_mass: Knuckle mass (rotation about axis ``a``), universal-joint cross
            included [kg].
        foot_mass: Foot mass (sole and clamping device) [kg].
        cylinder_radius: Actuator body radius [m].
        rod_radius: Actuator rod radius [m].
        effort: Actuator force limit [N].
        velocity: Actuator speed limit [m/s].
        screw_lead: Ball-screw lead [m/rev]; the transmission reduction is ``2 pi / lead``
            [rad/m] (motor angle per actuator length).
        passive_range: Limit of every passive revolute joint about its home value, and cone
            half-angle of the foot's universal joint about its home direction [rad].
        branches: Number of branches: 3 (the tripod) or 4 (the four-branch walker the paper
            proposes, see the module docstring).

    """

    r_p: float = 0.30
    theta: float = 0.30
    foothold_radius: float = 0.70
    foot_height: float = 0.06
    nacelle_height: float = 0.60
    tool_offset: float = 0.15
    stroke_min: float = 0.50
    stroke_max: float = 0.90
    nacelle_mass: float = 8.0
    spindle_mass: float = 6.0
    edge_mass: float = 0.8
    cylinder_mass: float = 2.5
    rod_mass: float = 1.0
    knuckle_mass: float = 0.4
    foot_mass: float = 1.5
    cylinder_radius: float = 0.030
    rod_radius: float = 0.015
    effort: float = 3000.0
    velocity: float = 0.25
    screw_lead: float = 0.005
    passive_range: float = 1.2
    branches: int = 3

    def _heights(self) -> list[float | None]:
        """Sampled nacelle heights whose home actuator lengths are within the strokes."""
        heights = np.linspace(self.foot_height, self.foot_height + 2.0 * self.stroke_max, 401)
        return [
            float(h)
            if all(
                self.stroke_min <= q <= self.stroke_max for q in home(_at_height(self, float(h)))
            )
            else None
            for h in heights[1:]
        ]

    def __post_init__(self) -> None:
        if self.branches not in (3, 4):
            raise ParameterError(
                NAME, "branches", f"must be 3 (tripod) or 4 (walker), got {self.branches!r}"
            )
        positive(NAME, **{k: v for k, v in param_items(self) if k != "tool_offset"})
        in_range(NAME, "tool_offset", self.tool_offset, 0.0, math.inf)
        if self.theta >= np.pi / self.branches:
            raise ParameterError(
                NAME,
                "theta",
                f"must be below pi/{self.branches} with {self.branches} branches (neighbouring "
                f"branches would overlap), got {self.theta!r}",
            )
        in_range(NAME, "passive_range", self.passive_range, 0.0, np.pi)
        if self.stroke_min >= self.stroke_max:
            raise ParameterError(
                NAME,
                "stroke_min",
                f"must be below stroke_max ({self.stroke_max}), got {self.stroke_min!r}",
            )
        if self.nacelle_height <= self.foot_height:
            raise ParameterError(
                NAME,
                "nacelle_height",
                f"must exceed foot_height ({self.foot_height}), got {self.nacelle_height!r}",
            )
        lengths = home(self)
        if not all(self.stroke_min <= q <= self.stroke_max for q in lengths):
            fits = [float(h) for h in self._heights() if h is not None]
            advice = (
                f"nacelle_height must lie in [{min(fits):.3g}, {max(fits):.3g}] m with these "
                "footholds and strokes"
                if fits
                else "no nacelle height fits these footholds and strokes"
            )
            raise ParameterError(
                NAME,
                "nacelle_height",
                f"{self.nacelle_height} m puts the home actuator lengths at "
                f"{min(lengths):.4g}..{max(lengths):.4g} m, outside the strokes "
                f"[{self.stroke_min}, {self.stroke_max}] m: {advice}",
            )


def _at_height(p: Params, h: float) -> Params:
    """``p`` with another nacelle height, not validated (a copy: no ``__post_init__``)."""
    out = copy.copy(p)
    object.__setattr__(out, "nacelle_height", h)
    return out


def home(p: Params) -> list[float]:
    """Actuator lengths ``[q_L1, q_R1, q_L2, q_R2, ...]`` [m] at home (two per branch).

    Args:
        p: Parameters.

    Returns:
        ``|A_i P_Li|`` and ``|A_i P_Ri|`` with the nacelle at :func:`home_nacelle_placement` and
        the feet at :func:`foothold_frames`.

    """
    M = home_nacelle_placement(p)
    out: list[float] = []
    for i, foot in enumerate(foothold_frames(p)):
        for P in attachments(p, i):
            out.append(float(np.linalg.norm(M.act(P) - foot.translation)))
    return out


# --- builder --------------------------------------------------------------------------------


def _rpy(R: np.ndarray) -> tuple[float, float, float]:
    r = pin.rpy.matrixToRpy(R)
    return (float(r[0]), float(r[1]), float(r[2]))


def _inertia(parts: Sequence[pin.Inertia]) -> tuple[float, tuple[float, ...], np.ndarray]:
    total = pin.Inertia.Zero()
    for part in parts:
        total += part
    return float(total.mass), tuple(float(x) for x in total.lever), np.array(total.inertia)


def _rod(mass: float, radius: float, p0: np.ndarray, p1: np.ndarray) -> pin.Inertia:
    com, inertia = rod_inertia(mass, radius, p0, p1)
    return pin.Inertia(mass, np.array(com), inertia)


def _cylinder_shapes(
    radius: float, p0: np.ndarray, p1: np.ndarray, rgba: tuple[float, ...]
) -> tuple[Shape, Shape]:
    xyz, rpy, length = segment_origin(p0, p1)
    return Shape("cylinder", (radius, length), xyz, rpy, rgba), Shape(
        "cylinder", (radius, length), xyz, rpy
    )


def _sphere(mass: float, radius: float) -> pin.Inertia:
    return pin.Inertia(mass, np.zeros(3), np.eye(3) * 0.4 * mass * radius**2)


def layout(p: Params) -> UrdfWriter:
    """The elements of the tripod (or walker) description with parameters ``p``, feet welded.

    :func:`build_urdf` renders them; :mod:`pkdyn.model.candidate` reads their numbers.
    """
    w = UrdfWriter("tripod" if p.branches == 3 else "walker")
    dark = (0.25, 0.25, 0.3, 1.0)
    ground = Shape("cylinder", (p.foothold_radius + 0.15, 0.01), (0, 0, -0.005), rgba=GREY)
    w.link("support", visuals=[ground], collisions=[Shape("cylinder", ground.size, ground.xyz)])

    plate_r, plate_t, spindle_r = p.r_p + 0.04, 0.04, 0.05
    spindle_end = np.array([0.0, 0.0, -max(p.tool_offset, 1e-3)])
    plate = pin.Inertia(
        p.nacelle_mass,
        np.zeros(3),
        np.diag([0.25 * plate_r**2 + plate_t**2 / 12] * 2 + [0.5 * plate_r**2]) * p.nacelle_mass,
    )
    mass, com, inertia = _inertia(
        [plate, _rod(p.spindle_mass, spindle_r, np.zeros(3), spindle_end)]
    )
    spindle_v, spindle_c = _cylinder_shapes(spindle_r, np.zeros(3), spindle_end, dark)
    w.link(
        "nacelle",
        mass,
        com,
        inertia,
        visuals=[Shape("cylinder", (plate_r, plate_t), rgba=GREY), spindle_v],
        collisions=[Shape("cylinder", (plate_r, plate_t)), spindle_c],
    )
    M0 = home_nacelle_placement(p)
    w.joint("nacelle", "floating", "support", "nacelle", xyz=M0.translation)

    s0 = virtual_joints(p, M0)
    e = 2.0 * p.r_p * math.sin(p.theta)
    lo, hi = -p.passive_range, p.passive_range
    passive = (lo, hi, 0.0, 10.0)
    reduction = 2.0 * np.pi / p.screw_lead
    for i, foot in enumerate(foothold_frames(p)):
        b = f"branch{i + 1}"
        q2h = float(s0[i, 1])
        P_L, P_R = attachments(p, i)  # nacelle frame == world axes at home
        A = foot.translation - M0.translation  # A in the home nacelle frame
        u = unit_vector(P_R - P_L)
        y_t = perpendicular(A - P_L, u)
        R_T = np.column_stack([u, y_t, np.cross(u, y_t)])  # edge frame: x = u, z = axes a, b, c
        d_l, d_r = R_T.T @ (A - P_L), R_T.T @ (A - P_R)  # in the edge frame (z = 0)
        alpha_l, alpha_r = math.atan2(d_l[1], d_l[0]), math.atan2(d_r[1], d_r[0])

        # edge body, hinged about u through P_L (the paper's q6)
        ends = (np.zeros(3), np.array([e, 0.0, 0.0]))
        vis, col = _cylinder_shapes(0.02, ends[0], ends[1], GREY)
        edge = _rod(p.edge_mass, 0.02, ends[0], ends[1])
        w.link(f"{b}_edge", p.edge_mass, tuple(edge.lever), edge.inertia, [vis], [col])
        w.joint(f"{b}_q6", "revolute", "nacelle", f"{b}_edge", P_L, _rpy(R_T), (1, 0, 0), passive)

        # actuators: body revolving about b (at P_L) or c (at P_R), rod sliding along x
        cyl_len, rod_len = p.stroke_min, p.stroke_max - p.stroke_min + 0.03
        for side, origin, alpha in (("L", ends[0], alpha_l), ("R", ends[1], alpha_r)):
            axis_joint = "b" if side == "L" else "c"
            body, rod = f"{b}_cyl{side}", f"{b}_rod{side}"
            c_end = np.array([cyl_len, 0.0, 0.0])
            vis, _ = _cylinder_shapes(p.cylinder_radius, np.zeros(3), c_end, BLUE)
            # the collision cylinder leaves out the clevis inside the nacelle plate
            _, col = _cylinder_shapes(
                p.cylinder_radius, np.array([MOUNT_CLEARANCE, 0.0, 0.0]), c_end, BLUE
            )
            cyl = _rod(p.cylinder_mass, p.cylinder_radius, np.zeros(3), c_end)
            w.link(body, p.cylinder_mass, tuple(cyl.lever), cyl.inertia, [vis], [col])
            w.joint(
                f"{b}_{axis_joint}",
                "revolute",
                f"{b}_edge",
                body,
                origin,
                (0, 0, alpha),
                (0, 0, 1),
                passive,
            )
            r_start = np.array([-rod_len, 0.0, 0.0])
            vis, col = _cylinder_shapes(p.rod_radius, r_start, np.zeros(3), ORANGE)
            rd = _rod(p.rod_mass, p.rod_radius, r_start, np.zeros(3))
            w.link(rod, p.rod_mass, tuple(rd.lever), rd.inertia, [vis], [col])
            w.joint(
                f"{b}_q{side}",
                "prismatic",
                body,
                rod,
                axis=(1, 0, 0),
                limit=(p.stroke_min, p.stroke_max, p.effort, p.velocity),
            )
            w.transmission(f"{b}_q{side}", f"{side}{i + 1}", reduction)

        # knuckle at A: x along axis a (v3), z along w' (projection of w_a on the triangle)
        R_rod_l = R_T @ pin.rpy.rpyToMatrix(0.0, 0.0, alpha_l)
        v3 = R_T[:, 2]
        w_proj = perpendicular(foot.rotation[:, 2], v3)
        R_K = np.column_stack([v3, np.cross(w_proj, v3), w_proj])
        k = _sphere(p.knuckle_mass, 0.03)
        w.link(
            f"{b}_knuckle",
            p.knuckle_mass,
            (0, 0, 0),
            k.inertia,
            [Shape("sphere", (0.03,), rgba=dark)],
            [Shape("sphere", (0.03,))],
        )
        w.joint(
            f"{b}_a",
            "revolute",
            f"{b}_rodL",
            f"{b}_knuckle",
            rpy=_rpy(R_rod_l.T @ R_K),
            axis=(1, 0, 0),
            limit=passive,
        )
        # foot on a universal joint at A, zero at home: first axis -y of the knuckle (q2), then
        # -w_a (q1). The joint frame is turned half a turn about z so that the placeholder's
        # axis is +y; the foot frame is therefore R_A turned half a turn about w_a.
        R_U = pin.rpy.rpyToMatrix(0.0, -q2h, 0.0) @ pin.rpy.rpyToMatrix(0.0, 0.0, np.pi)
        R_F = foot.rotation @ pin.rpy.rpyToMatrix(0.0, 0.0, np.pi)
        sole = np.array([0.0, 0.0, -p.foot_height])
        post_v, post_c = _cylinder_shapes(0.02, sole, np.zeros(3), dark)
        pad = Shape("cylinder", (0.07, 0.02), (0.0, 0.0, -p.foot_height + 0.01), rgba=dark)
        post = _rod(0.3 * p.foot_mass, 0.02, sole, np.zeros(3))
        pad_i = _rod(0.7 * p.foot_mass, 0.07, sole, sole + np.array([0.0, 0.0, 0.02]))
        mass, com, inertia = _inertia([post, pad_i])
        w.link(
            f"{b}_foot",
            mass,
            com,
            inertia,
            [post_v, pad],
            [post_c, Shape("cylinder", pad.size, pad.xyz)],
        )
        w.universal(
            f"{b}_q2q1",
            f"{b}_knuckle",
            f"{b}_foot",
            (0.0, 0.0, 0.0),
            _rpy(R_U),
            (0.0, 1.0, 0.0),
            (0.0, 0.0, -1.0),
            cone=((0.0, 0.0, 1.0), p.passive_range),
        )

        # closures: the two rods share axis a at A; the foot sole is clamped on the support
        w.closure(
            f"{b}_A",
            "hinge",
            (f"{b}_rodR", (0, 0, 0), (0, 0, 0)),
            (f"{b}_rodL", (0, 0, 0), (0, 0, 0)),
            axis=(0, 0, 1),
        )
        w.closure(
            f"{b}_foothold",
            "weld",
            (f"{b}_foot", sole, (0, 0, 0)),
            ("support", foot.translation + R_F @ sole, _rpy(R_F)),
        )
    w.platform("nacelle", ("x", "y", "z", "rx", "ry", "rz"), xyz=(0.0, 0.0, -p.tool_offset))
    return w


def build_urdf(p: Params) -> str:
    """URDF text of the tripod (or walker) with parameters ``p``, its feet welded to the support."""
    return builder_text(layout(p), __name__)
