"""Which links deform, and how: beams read from the links' geometry, or described compliances.

A link is modelled as a **beam** when its collision (else visual) geometry holds a slender
cylinder or capsule (length at least twice its diameter) and a material is known for it: the
link's own ``<pkdyn:compliance material>`` (with an optional ``inner_radius``: a tube), else
the robot's ``<pkdyn:material>``, else the ``material`` argument (``--material``), which thus
applies only to the links the description leaves undescribed (:attr:`LinkCompliance.origin`
says where each link's material came from). The longest such shape is the beam. Its **root**
is the end at the link's parent joint (the end nearer that
joint's origin; for a link hung on a prismatic, planar or floating joint, which has no location,
the end farther from what the link carries); its **tip** the other end. Everything the link
carries (child joints, closure frames, the platform frame, spring ends) is taken as attached at
the tip: the beam's compliance is that of a cantilever clamped at the root, expressed at its
elastic centre (the mid-point), where it is diagonal (:func:`pkdyn.precision.beam.
centre_compliance`). A link weighs what the URDF's ``<inertial>`` says, unless the description
asks ``mass="from-material"`` (on ``<pkdyn:material>`` or the link's ``<pkdyn:compliance>``):
then its mass and inertia are those of its beam (section, length, density), replacing the URDF's
in the precision models (:attr:`LinkCompliance.inertia`).

A ``<pkdyn:compliance link compliance="c1 .. c6" xyz rpy>`` gives the diagonal compliance
directly, in a frame of the link; ``rigid="true"`` keeps a link rigid.
"""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.description import ComplianceSpec
from pkdyn.model.robot import Robot
from pkdyn.precision.beam import Section, _centre, _check_length
from pkdyn.precision.material import Material, as_material
from solvers.vec3 import cross_one

__all__ = ["SLENDERNESS", "LinkCompliance", "link_compliances"]

SLENDERNESS = 2.0
"""Smallest length / diameter of a cylinder or capsule read as a beam."""

_LOCATED = ("JointModelR", "JointModelSpherical", "JointModelUniversal", "JointModelRevolute")
"""Joint models with a location (their frame origin is where they act)."""


@dataclass(frozen=True, eq=False)  # numpy / SE3 fields
class LinkCompliance:
    """The compliance of one link: a 6-DOF virtual spring between its root and its tip.

    Attributes:
        link: Link name.
        joint: Joint id of the link's body (in the robot's model).
        placement: Frame of the virtual spring in that joint's frame (for a beam: its mid-point,
            ``z`` from root to tip).
        compliance: Diagonal compliance (6,) in that frame [m/N x3, rad/(N m) x3].
        source: ``beam`` or ``description``.
        length: Beam length [m] (``None`` for a described compliance).
        section: Beam cross-section (``None`` for a described compliance).
        material: Beam material (``None`` for a described compliance).
        origin: Where the material (or compliance) came from: ``description`` (the link's
            element or the robot's ``<pkdyn:material>``) or ``argument`` (``material=``).
        mass_from_material: The link weighs what its beam's section and density say.
        segment: Index of this piece of the beam, from its root (a beam is cut where springs
            attach to it: one virtual spring per piece, in series).
        beam: The whole beam, ``(root, tip)`` in the joint frame [m] (``None`` for a described
            compliance).
        end: Distance from the beam's root to this piece's far end [m].
        sliding: The beam is a rod sliding out of its parent's beam (a prismatic leg): its
            length is that outside the parent, at the configuration the model was built for.

    """

    link: str
    joint: int
    placement: pin.SE3
    compliance: np.ndarray
    source: str
    length: float | None = None
    section: Section | None = None
    material: Material | None = None
    origin: str = "description"
    mass_from_material: bool = False
    segment: int = 0
    beam: tuple[np.ndarray, np.ndarray] | None = None
    end: float = 0.0
    sliding: bool = False

    @property
    def beam_length(self) -> float | None:
        """Length of the whole beam [m] (``None`` for a described compliance)."""
        return None if self.beam is None else float(np.linalg.norm(self.beam[1] - self.beam[0]))

    @property
    def beam_placement(self) -> pin.SE3:
        """Mid-point frame of the whole beam in the joint frame, ``z`` from root to tip."""
        return self.placement if self.beam is None else _beam_frame(*self.beam)

    @property
    def inertia(self) -> pin.Inertia | None:
        """The whole beam's inertia in the joint frame (``mass_from_material``), else ``None``."""
        L = self.beam_length
        if not (self.mass_from_material and self.section is not None and L):
            return None
        assert self.material is not None
        return self.beam_placement.act(self.section.inertia(L, self.material))

    @property
    def stiffness(self) -> np.ndarray:
        """Diagonal stiffness (6,) of the virtual spring [N/m x3, N m/rad x3]."""
        return 1.0 / self.compliance


@dataclass(frozen=True)
class _Rod:
    joint: int
    link: str
    ends: tuple[np.ndarray, np.ndarray]  # in the joint frame [m]
    radius: float

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.ends[1] - self.ends[0]))


def _rods(robot: Robot) -> dict[int, _Rod]:
    """The longest slender cylinder or capsule of each body (collision geometry first).

    Read once per robot (:mod:`pkdyn.model.reuse`): a sliding leg's elastic model is rebuilt at
    every pose from the same shapes.
    """
    from pkdyn.model.reuse import kept

    return dict(kept(robot, "slender rods", lambda: _read_rods(robot)))


def _read_rods(robot: Robot) -> dict[int, _Rod]:
    model = robot.model
    out: dict[int, _Rod] = {}
    for gm in (robot.collision_model, robot.visual_model):
        found: dict[int, _Rod] = {}
        for g in gm.geometryObjects:
            shape = g.geometry
            if not isinstance(shape, coal.Cylinder | coal.Capsule) or g.parentJoint == 0:
                continue
            r, h = float(shape.radius), float(shape.halfLength)
            if 2.0 * h < SLENDERNESS * 2.0 * r:
                continue
            M = g.placement
            ends = (M.act(np.array([0.0, 0.0, -h])), M.act(np.array([0.0, 0.0, h])))
            link = str(model.frames[g.parentFrame].name) if g.parentFrame < model.nframes else ""
            rod = _Rod(int(g.parentJoint), link, ends, r)
            best = found.get(rod.joint)
            if best is None or rod.length > best.length:
                found[rod.joint] = rod
        for j, rod in found.items():
            out.setdefault(j, rod)
    return out


def _attachments(robot: Robot, joint: int) -> list[np.ndarray]:
    """Points (joint frame) where a body carries something: children, closures, platform."""
    model = robot.model
    pts = [
        np.array(model.jointPlacements[c].translation)
        for c in range(1, model.njoints)
        if model.parents[c] == joint
    ]
    for cm in robot.constraint_models:  # (a hinge's two points, as built)
        pts += [
            np.array(M.translation)
            for j, M in ((cm.joint1_id, cm.joint1_placement), (cm.joint2_id, cm.joint2_placement))
            if j == joint
        ]
    if robot.platform_frame is not None:
        f = model.frames[robot.platform_frame]
        if f.parentJoint == joint:
            pts.append(np.array(f.placement.translation))
    if robot.passive is not None:
        for s in robot.passive.springs:
            for j, M in ((s.joint1, s.placement1), (s.joint2, s.placement2)):
                if j == joint:
                    pts.append(np.array(M.translation))
    return pts


def _rod_ends(robot: Robot) -> dict[int, tuple[np.ndarray, np.ndarray] | None]:
    """:func:`_root_tip` of each body's rod, read once per robot (as :func:`_rods`)."""
    from pkdyn.model.reuse import kept

    def make() -> dict[int, tuple[np.ndarray, np.ndarray] | None]:
        return {j: _root_tip(robot, rod) for j, rod in _rods(robot).items()}

    return kept(robot, "rod ends", make)


def _root_tip(robot: Robot, rod: _Rod) -> tuple[np.ndarray, np.ndarray] | None:
    """(root, tip) of a rod, ``None`` when the link carries nothing."""
    a, b = rod.ends
    jm = robot.model.joints[rod.joint]
    if str(jm.shortname()).startswith(_LOCATED):
        root_first = np.linalg.norm(a) <= np.linalg.norm(b)
    else:
        pts = _attachments(robot, rod.joint)
        if not pts:
            return None
        c = np.mean(pts, axis=0)
        root_first = np.linalg.norm(a - c) >= np.linalg.norm(b - c)
    return (a, b) if root_first else (b, a)


def _beam_frame(root: np.ndarray, tip: np.ndarray) -> pin.SE3:
    """Mid-point frame with ``z`` from root to tip."""
    d = tip - root
    z = d / np.sqrt(d.dot(d))  # (np.linalg.norm's arithmetic, np.cross's: vec3)
    helper = _X if abs(z[0]) < 0.9 else _Y
    x = cross_one(helper, z)
    x /= np.sqrt(x.dot(x))
    R = np.empty((3, 3))
    R[:, 0], R[:, 1], R[:, 2] = x, cross_one(z, x), z
    return pin.SE3(R, 0.5 * (root + tip))


_X = np.array([1.0, 0.0, 0.0])
_Y = np.array([0.0, 1.0, 0.0])


def _body_joint(robot: Robot, link: str) -> int:
    model = robot.model
    if model.existFrame(link, pin.FrameType.BODY):
        return int(model.frames[model.getFrameId(link, pin.FrameType.BODY)].parentJoint)
    if model.existFrame(link):
        return int(model.frames[model.getFrameId(link)].parentJoint)
    raise InvalidInputError("link", f"{robot.name} has no link '{link}'")


def _no_beam(robot: Robot, what: str) -> InvalidInputError:
    """The error when a material is given but no link has a cylinder to read a beam from."""
    if not robot.collision_model.ngeoms + robot.visual_model.ngeoms:
        missing = (
            "has no collision or visual geometry (loaded without it: pkdyn.load(..., "
            "geometry=True) reads it, as the command line does)"
        )
    else:
        missing = (
            "has no link whose collision or visual geometry holds a slender cylinder or "
            f"capsule (length at least {SLENDERNESS:g} diameters) to read a beam from"
        )
    return InvalidInputError(
        what,
        f"{robot.name} {missing}: give the links cylinders in the URDF, or describe their "
        "compliance (<pkdyn:compliance link=... compliance=...>), or leave the material out "
        "(no --material / material=, or --rigid-links: rigid links)",
    )


@public
def link_compliances(
    robot: Robot,
    material: str | Material | None = None,
    shear: bool = True,
    q: np.ndarray | None = None,
) -> list[LinkCompliance]:
    """The compliant links of a robot (see the module docstring).

    Args:
        robot: The robot, loaded with its geometry (``pkdyn.load(..., geometry=True)``, the
            default) for beams.
        material: Material of the slender links the description leaves undescribed (a preset
            name or a :class:`~pkdyn.precision.material.Material`); ``None``: the description's
            materials only.
        shear: Include Timoshenko's shear deflection in the beams.
        q: Configuration (nq,) of the sliding rods' lengths (default: home).

    Returns:
        One entry per compliant link (per piece of a beam cut by springs), in joint order.

    Raises:
        InvalidInputError: A material is given but the robot has no slender cylinder to read a
            beam from (the message says what is missing and how to fix it), a described link
            is the base, or a bad material.

    """
    desc = robot.description
    specs: dict[int, ComplianceSpec] = {}
    for given in desc.compliance:
        j = _body_joint(robot, given.link)
        if j == 0:
            raise InvalidInputError(
                f"pkdyn:compliance link '{given.link}'", "the base does not move: it cannot deform"
            )
        specs[j] = given
    argument = as_material(material) if material is not None else None
    described = as_material(desc.material) if desc.material is not None else None
    robot_mass = bool(desc.material is not None and desc.material.mass_from_material)
    beams_wanted = (
        argument is not None
        or described is not None
        or any(s.material is not None or s.inner_radius > 0.0 for s in specs.values())
    )
    rods = _rods(robot) if beams_wanted else {}
    if beams_wanted and not rods:
        raise _no_beam(robot, "material" if argument is not None else "pkdyn:material")
    rod_ends = _rod_ends(robot) if rods else {}
    names = _link_names(robot)
    out: list[LinkCompliance] = []
    for j in range(1, robot.model.njoints):
        spec = specs.get(j)
        if spec is not None and spec.rigid:
            continue
        name = spec.link if spec is not None else names.get(j, str(robot.model.names[j]))
        if spec is not None and spec.compliance is not None:
            out.append(
                LinkCompliance(name, j, spec.frame, np.array(spec.compliance, float), "description")
            )
            continue
        mat, origin = (
            (described, "description") if described is not None else (argument, "argument")
        )
        if spec is not None and spec.material is not None:
            mat, origin = as_material(spec.material), "description"
        elif spec is not None and spec.inner_radius > 0.0 and described is not None:
            origin = "description"
        if mat is None:
            if spec is not None:
                raise InvalidInputError(
                    f"pkdyn:compliance link '{spec.link}'",
                    "no material for its beam: give the element a material, the robot a "
                    "<pkdyn:material>, or --material (material=)",
                )
            continue
        rod = rods.get(j)
        if rod is None:
            if spec is not None:
                raise InvalidInputError(
                    f"pkdyn:compliance link '{spec.link}'",
                    "has no slender cylinder or capsule to read a beam from; give its "
                    "compliance instead",
                )
            continue
        ends = rod_ends[j]
        if ends is None:
            continue
        sliding = False
        mouth = _mouth(robot, rod, rods, robot.q_home if q is None else q, rod_ends)
        if mouth is not None:  # a rod sliding out of its parent: the part outside deflects
            ends, sliding = _outside(ends, mouth), True
            if ends is None:
                continue
        bore = spec.inner_radius if spec is not None else 0.0
        if bore >= rod.radius:
            raise InvalidInputError(
                f"pkdyn:compliance link '{name}' inner_radius",
                f"{bore:g} m is not smaller than the link's radius {rod.radius:g} m",
            )
        section = Section(rod.radius, bore)
        own_mass = spec.mass_from_material if spec is not None else None
        mass = robot_mass if own_mass is None else bool(own_mass)
        root, tip = ends
        L = float(np.linalg.norm(tip - root))
        z = (tip - root) / L
        cuts = [0.0, *_cuts(robot, j, root, z, L), L]
        for k in range(len(cuts) - 1):
            a, b = cuts[k], cuts[k + 1]
            out.append(
                LinkCompliance(
                    name,
                    j,
                    _beam_frame(root + a * z, root + b * z),
                    _centre_checked(b - a, section, mat, shear),
                    "beam",
                    b - a,
                    section,
                    mat,
                    origin,
                    mass,
                    k,
                    (root, tip),
                    b,
                    sliding,
                )
            )
    return out


def _centre_checked(length: float, section: Section, material: Material, shear: bool) -> np.ndarray:
    """:func:`pkdyn.precision.beam.centre_compliance` of a section and material made here."""
    _check_length(length)
    return _centre(float(length), section, material, shear)


_CUT_TOL = 1e-6
"""Springs attached within this fraction of a beam's length of its ends act at the end."""


def _cuts(robot: Robot, joint: int, root: np.ndarray, z: np.ndarray, L: float) -> list[float]:
    """Distances from the root where springs attach along a beam (strictly inside it)."""
    if robot.passive is None:
        return []
    found: list[float] = []
    for sp in robot.passive.springs:
        for j, M in ((sp.joint1, sp.placement1), (sp.joint2, sp.placement2)):
            if j != joint:
                continue
            s = float((np.asarray(M.translation) - root) @ z)
            if _CUT_TOL * L < s < (1.0 - _CUT_TOL) * L:
                found.append(s)
    out: list[float] = []
    for s in sorted(found):
        if not out or s - out[-1] > _CUT_TOL * L:
            out.append(s)
    return out


def _mouth(
    robot: Robot,
    rod: _Rod,
    rods: dict[int, _Rod],
    q: np.ndarray,
    rod_ends: dict[int, tuple[np.ndarray, np.ndarray] | None],
) -> np.ndarray | None:
    """Where a rod leaves its parent's beam (rod joint frame) at ``q``, for a prismatic leg.

    A link hung on a prismatic joint, whose beam lies along the joint's axis and whose parent
    has a beam along the same axis (a cylinder), slides out of it: the point is the parent
    beam's tip (its mouth); ``None`` for any other link.
    """
    model = robot.model
    jm = model.joints[rod.joint]
    if not str(jm.shortname()).startswith("JointModelP"):
        return None
    parent = rods.get(int(model.parents[rod.joint]))
    if parent is None:
        return None
    ends = rod_ends[int(model.parents[rod.joint])]
    if ends is None:
        return None
    jd = jm.createData()
    jm.calc(jd, np.asarray(q, dtype=float))
    M = model.jointPlacements[rod.joint] * jd.M  # the rod's frame in the parent's
    axis = np.asarray(jd.S, dtype=float).reshape(6)[:3]
    d = (rod.ends[1] - rod.ends[0]) / rod.length
    p = (parent.ends[1] - parent.ends[0]) / parent.length
    if abs(abs(float(d @ axis)) - 1.0) > 1e-6 or abs(abs(float(p @ M.rotation @ d)) - 1.0) > 1e-6:
        return None
    return np.asarray(M.actInv(ends[1]))


def _outside(
    ends: tuple[np.ndarray, np.ndarray], mouth: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """The part of a rod ``(root, tip)`` beyond ``mouth`` (projected on its axis), or ``None``."""
    root, tip = ends
    L = float(np.linalg.norm(tip - root))
    z = (tip - root) / L
    s = float((mouth - root) @ z)
    if s >= (1.0 - _CUT_TOL) * L:
        return None  # the rod is inside its parent: it does not bend or stretch alone
    return (root + max(s, 0.0) * z, tip)


def _link_names(robot: Robot) -> dict[int, str]:
    """The first body frame's name of each joint that has one."""
    out: dict[int, str] = {}
    for f in robot.model.frames:
        if f.type == pin.FrameType.BODY:
            out.setdefault(int(f.parentJoint), str(f.name))
    return out
