"""Clavel's Delta with rotary actuators (seed 000, sections 1.3.5 and 1.4).

Three arms driven about horizontal axes on a base circle of radius ``ra`` (arm ``i`` in the
vertical plane at ``theta_i = 0, 120, 240 deg``, arm 1 along +x; base in z = 0, nacelle below);
each arm carries a parallelogram of two bars of length ``lb`` with ball joints (or, with
``bar_joint="universal"``, a universal joint at the upper end, which removes the bars' spin);
the bars close on the nacelle at radius ``rb``. Defaults: the DELTA 580 prototype
(ra=150, rb=25, la=200, lb=380 mm).

Model: the nacelle hangs on a free-flyer (its placement is part of q); upper bar ends are tree
joints (spherical / universal), lower bar ends are ``point`` closures on the nacelle.

With ``parallelogram="hinge"`` each parallelogram is made of revolute joints (Tsai's
construction): both bars of arm ``i`` hang from the elbow on universal joints whose first axes
lie on the elbow line (parallel to the arm axis) and whose second axes are the normal ``n`` to
the parallelogram plane; a lower beam ``beam{i}`` turns about ``n`` at the lower end of bar
``a`` (revolute ``beam{i}``), bar ``b`` closes on it with the ``hinge`` closure ``loop{i}b``
(about ``n``), and the beam closes on the nacelle with the ``hinge`` closure ``loop{i}`` about
an axis parallel to the arm axis. Every hinge axis is a coordinate axis of both of its frames,
so the parallel axes stay exactly parallel in the written file. Each parallelogram is a planar
four-bar closed in space and the three legs all keep the nacelle's orientation, so Grübler's
count (-6) misses redundant equations; the mobility is still 3 (see :mod:`pkdyn.analysis.mobility`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.closed_form import delta as cf
from pkdyn.exceptions import ParameterError, UnreachablePoseError
from pkdyn.library._check import in_range, middle_of_reach, param_items, positive
from pkdyn.library._colors import BLUE, GREY, ORANGE
from pkdyn.library._links import driven_rod, passive_rod
from pkdyn.library._render import builder_text
from pkdyn.model.formats.urdf_writer import Shape, UrdfWriter, rpy_z_to

__all__ = [
    "NAME",
    "SUMMARY",
    "Params",
    "build_urdf",
    "configuration",
    "forward_position",
    "home",
    "in_working_mode",
    "inverse_actuators",
    "layout",
    "resolved",
]

NAME = "delta"
"""Family name (``pkdyn.load`` and the CLI take it)."""
SUMMARY = "Clavel's Delta, rotary actuators, parallelograms of two ball-jointed bars (DELTA 580)"
"""One-line description of the family (``pkdyn info``, the family registry)."""


@dataclass(frozen=True)
class Params:
    """Delta parameters (SI units). Defaults: DELTA 580 (seed 000) with plausible masses.

    Attributes:
        ra: Base centre to arm axis [m].
        rb: Nacelle centre to parallelogram side [m].
        la: Arm length [m].
        lb: Bar length [m].
        bar_spacing: Distance between the two bars of a parallelogram [m].
        arm_mass: Arm mass, elbow included [kg].
        bar_mass: Mass of one bar [kg].
        nacelle_mass: Nacelle mass [kg].
        arm_radius: Arm tube radius (inertia, display, collision) [m].
        bar_radius: Bar tube radius [m].
        z_home: Nacelle height on the axis at the home configuration [m] (negative: below the
            base); ``None`` (default) derives it from the other parameters: the middle of the
            nacelle's vertical reach within the arm limits, rounded to two significant digits
            (-0.35 m for the DELTA 580). See :meth:`home_height`.
        alpha_min: Lower arm-angle limit [rad].
        alpha_max: Upper arm-angle limit [rad].
        effort: Joint-side actuator torque limit [N m].
        velocity: Joint-side actuator speed limit [rad/s].
        reduction: Gear reduction between motor and arm.
        rotor_inertia: Motor rotor (plus gearbox input) inertia, motor side [kg m^2] (default 0:
            not modelled); the arm sees ``reduction^2 rotor_inertia``.
        efficiency: Gearbox efficiency, driving and back-driven (default 1: lossless).
        bar_joint: ``spherical`` (12 ball joints, mobility 9 of which 6 internal) or
            ``universal`` (universal joint at the upper end of each bar, mobility 3).
            Ignored when ``parallelogram="hinge"`` (the upper joints are then universal).
        parallelogram: ``ball`` (bars closed on the nacelle by ball joints, mobility 9 or 3
            with ``bar_joint``) or ``hinge`` (revolute-jointed parallelograms with a lower beam
            hinged to the nacelle, mobility 3; each beam has the mass and radius of a bar).
        cone_half_angle: Ball-joint cone limit about the home bar direction [rad].
        arms: Number of arms, 3 (Clavel's Delta) or 4 (a redundantly actuated variant, arms
            every 90 deg: 4 actuators for 3 degrees of freedom; the inverse dynamics then
            shares the load by a weighted least-effort QP).

    """

    ra: float = 0.150
    rb: float = 0.025
    la: float = 0.200
    lb: float = 0.380
    bar_spacing: float = 0.060
    arm_mass: float = 0.250
    bar_mass: float = 0.040
    nacelle_mass: float = 0.150
    arm_radius: float = 0.012
    bar_radius: float = 0.005
    z_home: float | None = None
    alpha_min: float = -0.8
    alpha_max: float = 1.6
    effort: float = 40.0
    velocity: float = 15.0
    reduction: float = 20.0
    rotor_inertia: float = 0.0
    efficiency: float = 1.0
    bar_joint: str = "spherical"
    cone_half_angle: float = 0.8
    parallelogram: str = "ball"
    arms: int = 3

    @property
    def theta(self) -> np.ndarray:
        """Arm plane angles [rad], arm 1 along +x."""
        return 2.0 * np.pi * np.arange(self.arms) / self.arms

    def __post_init__(self) -> None:
        positive(NAME, **{k: v for k, v in param_items(self) if k not in _SIGNED})
        in_range(NAME, "rotor_inertia", self.rotor_inertia, 0.0, 1.0)
        if not 0.0 < self.efficiency <= 1.0:
            raise ParameterError(NAME, "efficiency", f"must lie in (0, 1], got {self.efficiency}")
        in_range(NAME, "alpha_min", self.alpha_min, -np.pi, self.alpha_max)
        in_range(NAME, "alpha_max", self.alpha_max, self.alpha_min, np.pi)
        if self.bar_joint not in ("spherical", "universal"):
            raise ParameterError(NAME, "bar_joint", "must be 'spherical' or 'universal'")
        if self.arms not in (3, 4):
            raise ParameterError(NAME, "arms", f"must be 3 or 4, got {self.arms}")
        if self.parallelogram not in ("ball", "hinge"):
            raise ParameterError(NAME, "parallelogram", "must be 'ball' or 'hinge'")
        if self.ra <= self.rb:
            raise ParameterError(NAME, "ra", f"must exceed rb ({self.rb}) for a Delta")
        if self.z_home is not None:
            in_range(NAME, "z_home", self.z_home, -math.inf, 0.0)
            # the home's arm angles, which the layout and the assembly read (:meth:`_home`),
            # tell whether it is reachable: one inverse model for both (the same numbers:
            # :meth:`_reachable` sees x = y = -0.0 where :meth:`_home` sees +0.0, and the
            # inverse model uses them only as x c + y s - R (-R exactly) and (-x s + y c)^2)
            alpha, ok = cf.inverse(self, np.array([0.0, 0.0, self.z_home]))
            if not (ok[0] and self._inside(alpha)[0] and self.z_home < 0.0):
                raise ParameterError(
                    NAME,
                    "z_home",
                    f"{self.z_home} m is not reachable below the base with these lengths and arm "
                    f"limits (leave z_home unset: it is then {self._derived_height():.4g} m)",
                )
            self.__dict__["_home"] = tuple(float(a) for a in alpha[0])
        else:
            self._derived_height()  # raises if nothing is reachable

    def _inside(self, alpha: np.ndarray) -> np.ndarray:
        """Which rows of arm angles (N, arms) lie within the arm limits (NaN: not)."""
        with np.errstate(invalid="ignore"):
            return np.all((alpha >= self.alpha_min) & (alpha <= self.alpha_max), axis=1)

    def _reachable(self, z: np.ndarray) -> np.ndarray:
        """Nacelle heights on the axis reached with every arm within its limits."""
        alpha, ok = cf.inverse(self, np.column_stack([0.0 * z, 0.0 * z, z]))
        return ok & self._inside(alpha) & (z < 0.0)

    def _derived_height(self) -> float:
        return self._derived

    @functools.cached_property
    def _derived(self) -> float:
        reach = self.la + self.lb + self.ra
        return middle_of_reach(NAME, "z_home", -reach, 0.0, self._reachable)

    @functools.cached_property
    def _home(self) -> tuple[float, ...]:
        """:func:`home` of these parameters (the layout and the assembly both ask for it)."""
        alpha, _ = cf.inverse(self, np.array([0.0, 0.0, self.home_height()]))
        return tuple(float(a) for a in alpha[0])

    def home_height(self) -> float:
        """Nacelle height at home [m]: ``z_home``, or the middle of the vertical reach."""
        return float(self.z_home) if self.z_home is not None else self._derived_height()


_SIGNED = {
    "z_home",
    "alpha_min",
    "alpha_max",
    "bar_joint",
    "parallelogram",
    "arms",
    "rotor_inertia",
    "efficiency",
}


def home(p: Params) -> list[float]:
    """Arm angles [rad] with the nacelle at ``(0, 0, p.home_height())``."""
    return list(p._home)


def forward_position(
    p: Params, qa: np.ndarray, reference: tuple[np.ndarray, np.ndarray] | None = None
) -> np.ndarray | None:
    """Nacelle position [m] from the arm angles: Clavel's direct model, working mode.

    The working assembly mode has the nacelle below the plane of the reduced elbows ``C'_i``
    (the lower root of eq. 4; below the base in use); ``reference`` is not needed. With four
    arms the first three give the position (the fourth must agree for the input to be
    assemblable). ``None`` if the arms cannot be assembled.
    """
    P, ok = cf.forward(p, np.asarray(qa, dtype=float)[:3])
    return P[0] if ok[0] else None


def in_working_mode(p: Params, P: np.ndarray) -> np.ndarray:
    """Which nacelle positions (N, 3) the working modes reach.

    Arms on the working branch (elbows out) and the nacelle below the plane of the reduced
    elbows (the lower root of the direct model).
    """
    P = np.atleast_2d(np.asarray(P, dtype=float))
    alpha, ok = cf.inverse(p, P)
    C = cf.elbow_points(p, np.where(np.isfinite(alpha), alpha, 0.0))[:, :3]
    n = np.cross(C[:, 1] - C[:, 0], C[:, 2] - C[:, 0])
    n *= np.where(n[:, 2:3] < 0.0, -1.0, 1.0)  # upward normal
    below = np.einsum("ij,ij->i", P - C[:, 0], n) < 0.0
    return ok & below


def inverse_actuators(p: Params, pose: pin.SE3) -> np.ndarray | None:
    """Arm angles [rad] of a nacelle position in the working modes, or ``None``.

    Elbows out and nacelle below the elbows; ``None`` when the arms cannot reach it.

    Raises:
        UnreachablePoseError: Only the other assembly mode (nacelle above the elbows) reaches
            the position.

    """
    P = np.asarray(pose.translation, dtype=float)
    alpha, ok = cf.inverse(p, P)
    if not ok[0]:
        return None
    if not in_working_mode(p, P)[0]:
        raise UnreachablePoseError(
            "-",
            0.0,
            f"delta: nacelle position {np.array2string(P, precision=4)} m lies above the plane "
            "of the elbows: only the other assembly mode (nacelle above the arms) reaches it; "
            "pkdyn keeps the Delta in its working mode",
        )
    return alpha[0]


def configuration(robot: Any, qa: np.ndarray, position: np.ndarray) -> np.ndarray | None:
    """The configuration with arm angles ``qa`` and the nacelle at ``position``, built.

    Ball-jointed bars are turned along the segment from their upper joint to their nacelle
    joint (the shortest rotation, no spin): exact even where a bar and its arm are aligned (the
    workspace boundary), where an iterative solve from far away stalls. ``None`` for the other
    bar joints (the caller solves from the home configuration).

    Args:
        robot: A Delta of this family.
        qa: Arm angles [rad].
        position: Nacelle position [m] (from :func:`forward_position`).

    """
    p = robot.params
    if p.parallelogram != "ball" or p.bar_joint != "spherical":
        return None
    m, data = robot.model, robot.data
    q = np.array(robot.q_home, dtype=float)
    q[robot.actuated_q] = qa
    j = m.getJointId("nacelle")
    jm = m.joints[j]
    M = m.jointPlacements[j].actInv(pin.SE3(np.eye(3), np.asarray(position, dtype=float)))
    q[jm.idx_q : jm.idx_q + 7] = pin.SE3ToXYZQUAT(M)
    pin.forwardKinematics(m, data, q)
    for cm in robot.constraint_models:  # bar (joint 1, tip) to nacelle (joint 2)
        jb = cm.joint1_id
        top = data.oMi[m.parents[jb]] * m.jointPlacements[jb]
        low = data.oMi[cm.joint2_id].act(cm.joint2_placement.translation)
        d = top.rotation.T @ (low - top.translation)
        tip = np.asarray(cm.joint1_placement.translation, dtype=float)
        quat = pin.Quaternion.FromTwoVectors(tip / np.linalg.norm(tip), d / np.linalg.norm(d))
        k = m.joints[jb].idx_q
        q[k : k + 4] = quat.coeffs()
    return q


def resolved(p: Params) -> Params:
    """The parameters with the derived ones (``z_home``) computed."""
    return dataclasses.replace(p, z_home=p.home_height())


@functools.lru_cache(maxsize=4)
def _arm_frames(arms: int) -> tuple[tuple[Any, np.ndarray, np.ndarray, np.ndarray], ...]:
    """Per arm: ``theta``, the radial and tangential unit vectors ``u``, ``t`` and the yaw.

    What :func:`layout` needs of the arms' plane angles alone, the same numbers once per arm
    count (read-only arrays); an arm's rotation is ``yaw @ rpyToMatrix(0, alpha, 0)``.
    """
    out = []
    for theta in 2.0 * np.pi * np.arange(arms) / arms:  # (Params.theta)
        u = np.array([np.cos(theta), np.sin(theta), 0.0])
        t = np.array([-np.sin(theta), np.cos(theta), 0.0])
        yaw = pin.rpy.rpyToMatrix(0.0, 0.0, theta)
        for a in (u, t, yaw):
            a.flags.writeable = False
        out.append((theta, u, t, yaw))
    return tuple(out)


def _hinged_bar(
    w: UrdfWriter,
    p: Params,
    i: int,
    side: str,
    u: np.ndarray,
    theta: float,
    pitch: tuple[float, float, float],
    cone: tuple[tuple[float, float, float], float],
) -> None:
    """Upper universal joint of a bar of a hinged parallelogram, and the beam or its closures.

    Bar frames: z along the bar, y along the arm axis, x along the parallelogram normal ``n``.
    """
    s = 0.5 * p.bar_spacing
    arm, bar, beam = f"arm{i}", f"bar{i}{side}", f"beam{i}"
    sign = 1.0 if side == "a" else -1.0
    x, y = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
    w.universal(f"{bar}_upper", arm, bar, (p.la, sign * s, 0.0), pitch, y, x, cone=cone)
    if side == "a":
        rod = ((0, 0, 0), (0, -2 * s, 0))
        passive_rod(w, beam, bar, rod, p.bar_mass, p.bar_radius, xyz=(0.0, 0.0, p.lb), axis=x)
        return
    zero = (0.0, 0.0, 0.0)
    w.closure(f"loop{i}b", "hinge", (bar, (0.0, 0.0, p.lb), zero), (beam, (0, -2 * s, 0), zero), x)
    # The beam frame's y and a nacelle frame turned by theta are both the arm axis.
    w.closure(
        f"loop{i}",
        "hinge",
        (beam, (0.0, -s, 0.0), zero),
        ("nacelle", p.rb * u, (0.0, 0.0, theta)),
        y,
    )


def layout(p: Params) -> UrdfWriter:
    """The elements of the pkdyn description of a Delta with parameters ``p``.

    :func:`build_urdf` renders them; :mod:`pkdyn.model.candidate` reads their numbers.
    """
    w = UrdfWriter("delta")
    s = 0.5 * p.bar_spacing
    w.link(
        "base",
        visuals=[Shape("cylinder", (p.ra + 0.04, 0.01), (0, 0, 0.02), rgba=GREY)],
        collisions=[Shape("cylinder", (p.ra + 0.04, 0.01), (0, 0, 0.02))],
    )
    alphas = home(p)
    P = np.array([0.0, 0.0, p.home_height()])
    frames = _arm_frames(p.arms)
    for i, ((theta, u, t, yaw), alpha) in enumerate(zip(frames, alphas, strict=True), start=1):
        arm = f"arm{i}"
        elbow = Shape(
            "cylinder",
            (p.arm_radius * 0.8, p.bar_spacing + 0.02),
            (p.la, 0, 0),
            (np.pi / 2, 0, 0),
            BLUE,
        )
        driven_rod(
            w,
            arm,
            "base",
            ((0, 0, 0), (p.la, 0, 0)),
            p.arm_mass,
            p.arm_radius,
            xyz=p.ra * u,
            rpy=(0.0, 0.0, theta),
            axis=(0.0, 1.0, 0.0),
            limit=(p.alpha_min, p.alpha_max, p.effort, p.velocity),
            actuator=f"motor{i}",
            reduction=p.reduction,
            rotor_inertia=p.rotor_inertia,
            efficiency=p.efficiency,
            extra_visuals=[elbow],
        )
        R_arm = yaw @ pin.rpy.rpyToMatrix(0.0, alpha, 0.0)
        O = p.ra * u
        hinged = p.parallelogram == "hinge"
        if hinged:
            # Bar direction in the arm frame: in its xz plane (the bars are normal to the arm
            # axis y at home). A pitch-only joint frame keeps y (the arm axis) exact.
            d = R_arm.T @ (P + p.rb * u - O - R_arm @ np.array([p.la, 0.0, 0.0]))
            pitch = (0.0, float(np.arctan2(d[0], d[2])), 0.0)
        ru = p.rb * u
        for side, sign in (("a", 1.0), ("b", -1.0)):
            bar = f"bar{i}{side}"
            elbow_w = O + R_arm @ np.array([p.la, sign * s, 0.0])
            st = sign * s * t
            attach = P + ru + st  # (P + rb u + sign s t)
            d_arm = R_arm.T @ (attach - elbow_w)
            jrpy = rpy_z_to(d_arm)
            w.rod(bar, p.bar_mass, p.bar_radius, (0, 0, 0), (0, 0, p.lb), ORANGE)
            cone = ((0.0, 0.0, 1.0), p.cone_half_angle)
            if hinged:
                _hinged_bar(w, p, i, side, u, theta, pitch, cone)
                continue
            if p.bar_joint == "spherical":
                w.spherical(f"{bar}_upper", arm, bar, (p.la, sign * s, 0.0), jrpy, cone=cone)
            else:
                R_j = pin.rpy.rpyToMatrix(*jrpy)
                axis1 = R_j.T @ np.array([0.0, 1.0, 0.0])
                axis2 = np.cross(np.array([0.0, 0.0, 1.0]), axis1)
                w.universal(
                    f"{bar}_upper", arm, bar, (p.la, sign * s, 0.0), jrpy, axis1, axis2, cone=cone
                )
            w.closure(
                f"loop{i}{side}",
                "point",
                (bar, (0.0, 0.0, p.lb), (0.0, 0.0, 0.0)),
                ("nacelle", ru + st, (0.0, 0.0, 0.0)),
            )
    nacelle_r = p.rb + 0.015
    I_n = np.diag([1 / 4, 1 / 4, 1 / 2]) * p.nacelle_mass * nacelle_r**2
    w.link(
        "nacelle",
        p.nacelle_mass,
        (0, 0, 0),
        I_n,
        visuals=[Shape("cylinder", (nacelle_r, 0.01), rgba=GREY)],
        collisions=[Shape("cylinder", (nacelle_r, 0.01))],
    )
    w.joint("nacelle", "floating", "base", "nacelle", xyz=P)
    w.platform("nacelle", ("x", "y", "z"))
    return w


def build_urdf(p: Params) -> str:
    """URDF text, with pkdyn extension elements, of a Delta with parameters ``p``."""
    return builder_text(layout(p), __name__)
