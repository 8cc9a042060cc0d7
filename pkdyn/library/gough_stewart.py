"""6-UPS Gough-Stewart platform; defaults: the MEL prototype of Merlet's report (seed 002).

Joint centres from Table 3.1 (base joints ``A_i`` 25 mm below the base plate, platform joints
``B_i`` 20 mm below the platform frame), leg strokes from Table 3.2 (legs 1-3: 528-757 mm,
legs 4-6: 491-733 mm). Each leg: universal joint at ``A_i``, actuated prismatic joint whose
coordinate is the leg length ``rho_i``, spherical joint at ``B_i`` (a ``point`` closure on the
platform). The base joints sit under the base plate and the legs pass through square holes,
modelled as 4-face pyramids about the home leg direction with two faces facing the base centre
(Merlet, chapter 3; the report gives no hole size: ``pyramid_half_angle`` is an assumption).
The base plate carries collision geometry, so legs are checked against it.

With ``base_joint="spherical"`` the base joints are ball joints ``leg{i}_S`` (S-P-S legs): each
leg may then spin about its own axis, Pasqui's mobility 12 = 6 + 6 internal (seed 001).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.closed_form.gough_stewart import leg_lengths
from pkdyn.exceptions import ParameterError
from pkdyn.library._check import in_range, positive
from pkdyn.library._colors import BLUE, GREY, ORANGE
from pkdyn.library._render import builder_text
from pkdyn.model.formats.urdf_writer import Shape, UrdfWriter, rpy_z_to

__all__ = [
    "MEL_A",
    "MEL_B",
    "MEL_RHO_MAX",
    "MEL_RHO_MIN",
    "NAME",
    "SUMMARY",
    "Params",
    "build_urdf",
    "home",
    "layout",
    "resolved",
]

NAME = "gough_stewart"
"""Family name (``pkdyn.load`` and the CLI take it)."""
SUMMARY = "6-UPS Gough-Stewart hexapod; defaults: Merlet's MEL prototype (Tables 3.1, 3.2)"
"""One-line description of the family (``pkdyn info``, the family registry)."""

_XA = (112.5, -225.0, -112.5, 67.5, -135.0, 67.5)
_YA = (-194.856, 0.0, 194.856, -116.913, 0.0, 116.913)
_XB = (95.263, 0.0, -95.263, -69.282, 0.0, 69.282)
_YB = (55.0, -110.0, 55.0, -40.0, 80.0, -40.0)

MEL_A = tuple((x / 1000, y / 1000, -0.025) for x, y in zip(_XA, _YA, strict=True))
"""Base joint centres A_i [m] (Table 3.1)."""
MEL_B = tuple((x / 1000, y / 1000, -0.020) for x, y in zip(_XB, _YB, strict=True))
"""Platform joint centres B_i in the platform frame [m] (Table 3.1)."""
MEL_RHO_MIN = (0.528, 0.528, 0.528, 0.491, 0.491, 0.491)
"""Minimum leg lengths [m] (Table 3.2)."""
MEL_RHO_MAX = (0.757, 0.757, 0.757, 0.733, 0.733, 0.733)
"""Maximum leg lengths [m] (Table 3.2)."""


@dataclass(frozen=True)
class Params:
    """Gough-Stewart parameters (SI units). Defaults: MEL prototype (seed 002).

    Attributes:
        A: Base joint centres (6 x 3) [m], base frame.
        B: Platform joint centres (6 x 3) [m], platform frame.
        rho_min: Minimum leg lengths (6) [m].
        rho_max: Maximum leg lengths (6) [m].
        z_home: Platform height at home [m]; 0 picks the height that puts the legs closest to
            mid-stroke.
        leg_radius: Leg radius for collision geometry [m] (Merlet: 8 mm).
        cylinder_length: Length of the fixed (cylinder) part of a leg [m].
        cylinder_mass: Mass of a leg's cylinder [kg].
        rod_mass: Mass of a leg's rod [kg].
        platform_mass: Platform mass [kg].
        platform_radius: Platform disc radius (display, inertia) [m].
        pyramid_half_angle: Half-angle of the square-hole pyramid at the base joints [rad].
            The report gives no hole size; 0.3 rad is the tilt a 16 mm leg has in a 33 mm
            square hole 25 mm above the joint centre, with which the base joints cut the
            orientation workspace at the home point, as Merlet reports (chapter 3).
        effort: Actuator force limit [N].
        velocity: Actuator speed limit [m/s].
        reduction: Transmission ratio motor [rad] per leg length [m] (2 pi / screw lead).
        base_joint: ``universal`` (6-UPS, joints ``leg{i}_U``, mobility 6) or ``spherical``
            (6-SPS, joints ``leg{i}_S``: each leg spins about its axis, mobility 12 of which 6
            internal).

    """

    A: tuple[tuple[float, float, float], ...] = MEL_A
    B: tuple[tuple[float, float, float], ...] = MEL_B
    rho_min: tuple[float, ...] = MEL_RHO_MIN
    rho_max: tuple[float, ...] = MEL_RHO_MAX
    z_home: float = 0.0
    leg_radius: float = 0.008
    cylinder_length: float = 0.40
    cylinder_mass: float = 0.8
    rod_mass: float = 0.4
    platform_mass: float = 3.0
    platform_radius: float = 0.13
    pyramid_half_angle: float = 0.3
    effort: float = 800.0
    velocity: float = 0.25
    reduction: float = 2 * np.pi / 0.005
    base_joint: str = "universal"

    def __post_init__(self) -> None:
        if self.base_joint not in ("universal", "spherical"):
            raise ParameterError(NAME, "base_joint", "must be 'universal' or 'spherical'")
        for name in ("A", "B"):
            arr = np.asarray(getattr(self, name), dtype=float)
            if arr.shape != (6, 3) or not np.all(np.isfinite(arr)):
                raise ParameterError(NAME, name, "must be 6 rows of 3 finite numbers [m]")
        lo = np.asarray(self.rho_min, dtype=float)
        hi = np.asarray(self.rho_max, dtype=float)
        if lo.shape != (6,) or hi.shape != (6,) or not np.all((0 < lo) & (lo < hi)):
            raise ParameterError(NAME, "rho_min", "need 6 strokes with 0 < rho_min < rho_max")
        positive(
            NAME,
            leg_radius=self.leg_radius,
            cylinder_length=self.cylinder_length,
            cylinder_mass=self.cylinder_mass,
            rod_mass=self.rod_mass,
            platform_mass=self.platform_mass,
            platform_radius=self.platform_radius,
            effort=self.effort,
            velocity=self.velocity,
            reduction=self.reduction,
        )
        in_range(NAME, "pyramid_half_angle", self.pyramid_half_angle, 0.0, np.pi / 2)
        rho = leg_lengths(self.a, self.b, np.array([0, 0, self.home_height()]), np.eye(3))[0]
        bad = np.flatnonzero((rho < lo) | (rho > hi))
        if bad.size:
            raise ParameterError(
                NAME,
                "z_home",
                f"home pose puts leg {bad[0] + 1} at {rho[bad[0]]:.4f} m, off stroke",
            )

    @property
    def a(self) -> np.ndarray:
        """Base joint centres as a (6, 3) array [m]."""
        return np.asarray(self.A, dtype=float)

    @property
    def b(self) -> np.ndarray:
        """Platform joint centres as a (6, 3) array [m]."""
        return np.asarray(self.B, dtype=float)

    def home_height(self) -> float:
        """Home platform height [m]: ``z_home``, or the one closest to mid-stroke if 0."""
        if self.z_home != 0.0:
            return float(self.z_home)
        mid = 0.5 * (np.asarray(self.rho_min) + np.asarray(self.rho_max))
        top = 2.0 * float(np.max(self.rho_max))
        # from 5 cm (a tenth of the range for robots under 25 cm: any size works)
        z = np.linspace(0.05 if top > 0.5 else 0.1 * top, top, 4001)
        p = np.column_stack([np.zeros_like(z), np.zeros_like(z), z])
        err = ((leg_lengths(self.a, self.b, p, np.eye(3)) - mid) ** 2).sum(axis=1)
        return float(z[int(np.argmin(err))])


def home(p: Params) -> list[float]:
    """Leg lengths [m] at the home pose (platform level, centred, at ``home_height``)."""
    rho = leg_lengths(p.a, p.b, np.array([0.0, 0.0, p.home_height()]), np.eye(3))[0]
    return [float(r) for r in rho]


def resolved(p: Params) -> Params:
    """The parameters with the derived ones (``z_home = 0``: the mid-stroke height) computed."""
    return dataclasses.replace(p, z_home=p.home_height())


def _hole_ref(a: np.ndarray, rpy: tuple[float, float, float]) -> tuple[float, float, float]:
    """Pyramid ``ref`` (joint frame) facing the base centre: the square hole's sides face it.

    The horizontal direction from ``A_i`` to the base axis, made normal to the pyramid axis
    (the joint frame's z, the home leg direction), in joint-frame coordinates.
    """
    R = pin.rpy.rpyToMatrix(*rpy)
    inward = -np.array([a[0], a[1], 0.0])
    ref = R.T @ inward
    ref[2] = 0.0
    ref /= np.linalg.norm(ref)
    return (float(ref[0]), float(ref[1]), 0.0)


def layout(p: Params) -> UrdfWriter:
    """The elements of the pkdyn description of a 6-UPS Gough-Stewart with parameters ``p``.

    :func:`build_urdf` renders them; :mod:`pkdyn.model.candidate` reads their numbers.
    """
    w = UrdfWriter("gough_stewart")
    base_r = float(np.max(np.linalg.norm(p.a[:, :2], axis=1))) + 0.04
    plate = Shape("cylinder", (base_r, 0.01), (0, 0, -0.005), rgba=GREY)
    w.link("base", visuals=[plate], collisions=[plate])
    zh = p.home_height()
    C = np.array([0.0, 0.0, zh])
    L, r = p.cylinder_length, p.leg_radius
    for i in range(6):
        d = C + p.b[i] - p.a[i]
        rpy = rpy_z_to(d)
        cyl, rod = f"leg{i + 1}_cylinder", f"leg{i + 1}_rod"
        Ic = np.diag([1 / 12 * L**2 + 0.25 * r**2] * 2 + [0.5 * r**2]) * p.cylinder_mass
        w.link(
            cyl,
            p.cylinder_mass,
            (0, 0, 0.5 * L),
            Ic,
            visuals=[Shape("cylinder", (1.6 * r, L), (0, 0, 0.5 * L), rgba=BLUE)],
            collisions=[Shape("cylinder", (r, L), (0, 0, 0.5 * L))],
        )
        Lr = float(min(p.rho_min[i], L))
        Ir = np.diag([1 / 12 * Lr**2 + 0.25 * r**2] * 2 + [0.5 * r**2]) * p.rod_mass
        w.link(
            rod,
            p.rod_mass,
            (0, 0, -0.5 * Lr),
            Ir,
            visuals=[Shape("cylinder", (r, Lr), (0, 0, -0.5 * Lr), rgba=ORANGE)],
            collisions=[Shape("cylinder", (r, Lr), (0, 0, -0.5 * Lr))],
        )
        pyramid = ((0.0, 0.0, 1.0), _hole_ref(p.a[i], rpy), (p.pyramid_half_angle,) * 2)
        if p.base_joint == "spherical":
            w.spherical(f"leg{i + 1}_S", "base", cyl, p.a[i], rpy, pyramid=pyramid)
        else:
            w.universal(
                f"leg{i + 1}_U",
                "base",
                cyl,
                p.a[i],
                rpy,
                (1.0, 0.0, 0.0),
                (0.0, 1.0, 0.0),
                pyramid=pyramid,
            )
        w.joint(
            f"leg{i + 1}",
            "prismatic",
            cyl,
            rod,
            axis=(0.0, 0.0, 1.0),
            limit=(p.rho_min[i], p.rho_max[i], p.effort, p.velocity),
        )
        w.transmission(f"leg{i + 1}", f"motor{i + 1}", p.reduction)
        w.closure(
            f"S{i + 1}", "point", (rod, (0, 0, 0), (0, 0, 0)), ("platform", p.b[i], (0, 0, 0))
        )
    R = p.platform_radius
    Ip = np.diag([0.25 * R**2, 0.25 * R**2, 0.5 * R**2]) * p.platform_mass
    w.link(
        "platform",
        p.platform_mass,
        (0, 0, 0),
        Ip,
        visuals=[Shape("cylinder", (R, 0.012), (0, 0, -0.014), rgba=GREY)],
        collisions=[Shape("cylinder", (R, 0.012), (0, 0, -0.014))],
    )
    w.joint("platform", "floating", "base", "platform", xyz=C)
    w.platform("platform", ("x", "y", "z", "rx", "ry", "rz"))
    return w


def build_urdf(p: Params) -> str:
    """URDF text, with pkdyn extension elements, of a 6-UPS Gough-Stewart with parameters ``p``."""
    return builder_text(layout(p), __name__)
