"""Which links deform, and how: beams read from the links' geometry, or described compliances.

A link is modelled as a **beam** when its collision (else visual) geometry holds a slender
cylinder or capsule (length at least twice its diameter) and a material is known for it: the
robot's ``<pkdyn:material>``, the ``material`` argument, or the link's own
``<pkdyn:compliance material>`` (with an optional ``inner_radius``: a tube). The longest such
shape is the beam. Its **root** is the end at the link's parent joint (the end nearer that
joint's origin; for a link hung on a prismatic, planar or floating joint, which has no location,
the end farther from what the link carries); its **tip** the other end. Everything the link
carries (child joints, closure frames, the platform frame, spring ends) is taken as attached at
the tip: the beam's compliance is that of a cantilever clamped at the root, expressed at its
elastic centre (the mid-point), where it is diagonal (:func:`pkdyn.precision.beam.
centre_compliance`). A link's mass stays with its root (the lumped-mass convention of the
virtual-joint method).

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
from pkdyn.precision.beam import Section, centre_compliance
from pkdyn.precision.material import Material, as_material

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

    """

    link: str
    joint: int
    placement: pin.SE3
    compliance: np.ndarray
    source: str
    length: float | None = None
    section: Section | None = None
    material: Material | None = None

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
    """The longest slender cylinder or capsule of each body (collision geometry first)."""
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
    for _, j1, M1, j2, M2 in robot.closure_set.items:
        pts += [np.array(M.translation) for j, M in ((j1, M1), (j2, M2)) if j == joint]
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
    z = (tip - root) / np.linalg.norm(tip - root)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])
    return pin.SE3(R, 0.5 * (root + tip))


def _body_joint(robot: Robot, link: str) -> int:
    model = robot.model
    if model.existFrame(link, pin.FrameType.BODY):
        return int(model.frames[model.getFrameId(link, pin.FrameType.BODY)].parentJoint)
    if model.existFrame(link):
        return int(model.frames[model.getFrameId(link)].parentJoint)
    raise InvalidInputError("link", f"{robot.name} has no link '{link}'")


@public
def link_compliances(
    robot: Robot,
    material: str | Material | None = None,
    shear: bool = True,
) -> list[LinkCompliance]:
    """The compliant links of a robot (see the module docstring).

    Args:
        robot: The robot, loaded with its geometry (``pkdyn.load(..., geometry=True)``, the
            default) for beams.
        material: Material of every slender link not described otherwise (a preset name or a
            :class:`~pkdyn.precision.material.Material`); ``None``: the description's
            ``<pkdyn:material>``, if any.
        shear: Include Timoshenko's shear deflection in the beams.

    Returns:
        One entry per compliant link, in joint order.

    Raises:
        InvalidInputError: A material is named but the robot has no geometry to read beams
            from, a described link is the base, or a bad material.

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
    default = as_material(material) if material is not None else None
    if default is None and desc.material is not None:
        default = as_material(desc.material)
    beams_wanted = default is not None or any(
        s.material is not None or s.inner_radius > 0.0 for s in specs.values()
    )
    rods = _rods(robot) if beams_wanted else {}
    if beams_wanted and not rods and not robot.collision_model.ngeoms + robot.visual_model.ngeoms:
        raise InvalidInputError(
            "material",
            f"{robot.name} was loaded without its geometry: beams are read from the links' "
            "cylinders (load it with geometry=True)",
        )
    out: list[LinkCompliance] = []
    for j in range(1, robot.model.njoints):
        spec = specs.get(j)
        if spec is not None and spec.rigid:
            continue
        name = spec.link if spec is not None else _link_name(robot, j)
        if spec is not None and spec.compliance is not None:
            out.append(
                LinkCompliance(name, j, spec.frame, np.array(spec.compliance, float), "description")
            )
            continue
        mat = default
        if spec is not None and spec.material is not None:
            mat = as_material(spec.material)
        if mat is None:
            if spec is not None:
                raise InvalidInputError(
                    f"pkdyn:compliance link '{spec.link}'",
                    "no material for its beam: give material=, a <pkdyn:material> or the "
                    "element's material attribute",
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
        ends = _root_tip(robot, rod)
        if ends is None:
            continue
        bore = spec.inner_radius if spec is not None else 0.0
        if bore >= rod.radius:
            raise InvalidInputError(
                f"pkdyn:compliance link '{name}' inner_radius",
                f"{bore:g} m is not smaller than the link's radius {rod.radius:g} m",
            )
        section = Section(rod.radius, bore)
        c = centre_compliance(rod.length, section, mat, shear)
        out.append(LinkCompliance(name, j, _beam_frame(*ends), c, "beam", rod.length, section, mat))
    return out


def _link_name(robot: Robot, joint: int) -> str:
    for f in robot.model.frames:
        if f.parentJoint == joint and f.type == pin.FrameType.BODY:
            return str(f.name)
    return str(robot.model.names[joint])
