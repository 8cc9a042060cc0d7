"""The pkdyn description format: a URDF spanning tree plus namespaced extension elements.

The extension elements live in the XML namespace :data:`NAMESPACE` (conventionally bound to the
prefix ``pkdyn``); URDF parsers ignore them. See ``urdf/README.md`` for the full reference.

- ``<pkdyn:closure name type="point|hinge|weld" [axis]>`` with two ``<pkdyn:frame link xyz rpy>``
  children: a loop closure between two frames on two links.
- ``<pkdyn:joint name type="spherical|universal" [axis2]>``: upgrades the URDF placeholder joint
  of that name (a ``continuous`` or ``revolute`` joint) to Pinocchio's spherical or universal
  joint; optional ``<pkdyn:cone>`` or ``<pkdyn:pyramid>`` passive-joint limit.
- ``<pkdyn:platform link xyz rpy task="x y z rx ry rz">``: the platform / end-effector frame and
  which pose components the mechanism controls.
- Actuation is the standard ``<transmission>`` element (SimpleTransmission,
  ``mechanicalReduction``); effort and velocity limits come from the joint's ``<limit>``. Its
  ``<actuator>`` may hold ``<pkdyn:rotor_inertia value>`` [kg m^2, motor side],
  ``<pkdyn:efficiency value [backdrive]>`` and ``<pkdyn:motor_friction viscous coulomb>``.
- Passive elements: the joint's standard ``<dynamics damping friction>``;
  ``<pkdyn:passive joint stiffness rest damping friction>`` (per degree of freedom: a joint
  spring about a rest position, and damping / friction overriding ``<dynamics>``);
  ``<pkdyn:spring name stiffness rest_length>`` with two ``<pkdyn:frame>`` children: a linear
  spring between two frames.
- ``<pkdyn:coupling name joint [source] [multiplier offset | polycoef] [joint_ref
  source_ref]>``: a scalar relation between two 1-DoF joint coordinates (a gear pair, a rack,
  a cam law): ``joint - joint_ref = offset + multiplier (source - source_ref)``, or the polynomial
  ``sum_k polycoef[k] (source - source_ref)^k`` (1 to 5 coefficients); without ``source`` the
  joint is locked at ``joint_ref + offset``. ``<pkdyn:coupling name [offset]>`` with
  ``<pkdyn:term joint coefficient>`` children: a linear relation over any number of 1-DoF
  joints, ``sum_i coefficient_i joint_i = offset`` (a rotor geared to the sum of a knee and an
  ankle angle). The standard URDF ``<mimic joint multiplier
  offset>`` of a joint is read as the coupling ``<joint name>_mimic`` (the joint stays a tree
  joint).
- Compliance (:mod:`pkdyn.precision`): ``<pkdyn:stiffness value>`` in a ``<transmission>`` (or
  its ``<actuator>``): the actuator's joint-side stiffness [N m/rad or N/m];
  ``<pkdyn:material name [E G density]>``: the material of the links modelled as beams;
  ``<pkdyn:compliance link [material E G density inner_radius] [compliance xyz rpy]
  [rigid]>``: one link's beam material and tube bore, or its compliance given directly.
- ``<pkdyn:family name>`` with ``<pkdyn:param name value>`` children: the library family and
  parameters the file was written from (``pkdyn urdf FAMILY``); the file then loads exactly as
  the family does (its parameters, home configuration and closed forms), after a check that its
  model is the builder's.
- ``<pkdyn:home q>``: the home configuration to assemble (actuator coordinates, or a full
  configuration in Pinocchio's order), as ``pkdyn.load(..., home=)`` takes it: written by
  ``pkdyn calibrate`` so that a calibrated robot loads in the assembly mode it was measured in.
- ``<pkdyn:encoder gain offset>`` in a transmission's ``<actuator>``: the actuated joint's
  coordinate is ``gain`` times the actuator's reading plus ``offset`` (a calibrated scale error of
  the encoder or screw; the joint coordinate at a zero reading).

The URDF part is validated by :mod:`pkdyn.model.validate` (numbers, physics, tree), the pkdyn
elements here (unknown elements, mistyped namespaces, duplicates).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError
from pkdyn.model.validate import check_urdf, unit_vector

__all__ = [
    "NAMESPACE",
    "TASK_COMPONENTS",
    "FrameRef",
    "ClosureSpec",
    "ConeLimit",
    "PyramidLimit",
    "JointSpec",
    "ActuatorSpec",
    "PlatformSpec",
    "PassiveSpec",
    "SpringSpec",
    "FamilySpec",
    "CouplingSpec",
    "LinearCouplingSpec",
    "MaterialSpec",
    "ComplianceSpec",
    "Description",
    "parse_description",
]

NAMESPACE = "urn:pkdyn:urdf:1"
"""XML namespace of pkdyn's extension elements."""

TASK_COMPONENTS = ("x", "y", "z", "rx", "ry", "rz")
"""Names of the platform pose components, in the order of :func:`pkdyn.model.pose.pose_error`."""

CLOSURE_KINDS = {"point": 3, "hinge": 5, "weld": 6}
JOINT_KINDS = ("spherical", "universal")
_NS = "{" + NAMESPACE + "}"


@dataclass(frozen=True, eq=False)  # numpy / SE3 fields: no boolean ==
class FrameRef:
    """A frame rigidly attached to a link (or to any named Pinocchio frame).

    Attributes:
        link: Link or frame name.
        placement: Placement of the frame in the link frame.

    """

    link: str
    placement: pin.SE3 = field(default_factory=pin.SE3.Identity)


@dataclass(frozen=True, eq=False)  # numpy / SE3 fields: no boolean ==
class ClosureSpec:
    """A loop closure between two frames.

    Attributes:
        name: Closure name.
        kind: ``point`` (spherical joint, 3 equations), ``hinge`` (revolute joint about ``axis``,
            5 equations) or ``weld`` (rigid, 6 equations).
        frame1: First frame.
        frame2: Second frame; at assembly its origin coincides with frame1's (and, for a weld,
            its orientation too).
        axis: Hinge axis, unit vector in the coordinates of each of the two frames.

    """

    name: str
    kind: str
    frame1: FrameRef
    frame2: FrameRef
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))

    @property
    def equations(self) -> int:
        """Number of independent scalar equations of this closure (3, 5 or 6)."""
        return CLOSURE_KINDS[self.kind]


@dataclass(frozen=True, eq=False)  # numpy / SE3 fields: no boolean ==
class ConeLimit:
    """Passive-joint limit: ``axis`` of the child may tilt at most ``half_angle`` [rad].

    The tilt is the angle between the axis carried by the child body and the same axis in the
    joint's parent frame.
    """

    axis: np.ndarray
    half_angle: float

    def margin(self, R: np.ndarray) -> float:
        """Signed margin [rad] of a joint rotation ``R`` (3x3): positive inside the cone."""
        c = float(np.clip(self.axis @ R @ self.axis, -1.0, 1.0))
        return self.half_angle - math.acos(c)


@dataclass(frozen=True, eq=False)  # numpy / SE3 fields: no boolean ==
class PyramidLimit:
    """Passive-joint limit of Merlet's pyramid (a square hole): four plane faces.

    The direction ``d = R @ axis`` must satisfy ``|atan2(d.ref, d.axis)| <= half_angles[0]`` and
    ``|atan2(d.(axis x ref), d.axis)| <= half_angles[1]``.
    """

    axis: np.ndarray
    ref: np.ndarray
    half_angles: tuple[float, float]

    def margin(self, R: np.ndarray) -> float:
        """Signed margin [rad] of a joint rotation ``R`` (3x3): positive inside the pyramid."""
        d = R @ self.axis
        a1 = math.atan2(float(d @ self.ref), float(d @ self.axis))
        a2 = math.atan2(float(d @ np.cross(self.axis, self.ref)), float(d @ self.axis))
        return min(self.half_angles[0] - abs(a1), self.half_angles[1] - abs(a2))


@dataclass(frozen=True, eq=False)  # numpy / SE3 fields: no boolean ==
class JointSpec:
    """A tree joint URDF cannot express, mapped to a Pinocchio joint model.

    Attributes:
        name: Name of the URDF placeholder joint.
        kind: ``spherical`` or ``universal``.
        axis2: Second axis of a universal joint (in the frame after the first rotation).
        limit: Optional passive-joint limit.

    """

    name: str
    kind: str
    axis2: np.ndarray | None = None
    limit: ConeLimit | PyramidLimit | None = None


@dataclass(frozen=True)
class ActuatorSpec:
    """One actuator, from a URDF ``<transmission>``.

    Attributes:
        name: Actuator name.
        joint: Actuated joint name.
        reduction: Mechanical reduction (joint speed x reduction = motor speed).
        effort: Joint-side effort limit [N m or N] (``inf`` when absent).
        velocity: Joint-side velocity limit [rad/s or m/s] (``inf`` when absent).
        rotor_inertia: Rotor (and gearbox input) inertia, motor side [kg m^2]; reflected on
            the joint as ``reduction^2 rotor_inertia`` (``pkdyn:rotor_inertia``).
        efficiency: Gearbox efficiency when the motor drives (``pkdyn:efficiency value``).
        backdrive_efficiency: Efficiency when the joint drives the motor
            (``pkdyn:efficiency backdrive``; default ``efficiency``).
        viscous: Motor viscous friction [N m s/rad] (``pkdyn:motor_friction viscous``).
        coulomb: Motor Coulomb friction [N m] (``pkdyn:motor_friction coulomb``).
        stiffness: Joint-side stiffness of the actuator and its transmission [N m/rad or N/m]
            (``pkdyn:stiffness value``), ``None`` when not described.
        encoder_gain: Joint coordinate per unit of the actuator's reading (``pkdyn:encoder
            gain``, > 0; default 1), from a geometric calibration.
        encoder_offset: Joint coordinate at a zero reading [rad or m] (``pkdyn:encoder
            offset``; default 0): ``q = encoder_gain * reading + encoder_offset``
            (:meth:`pkdyn.Robot.joint_coordinates`).

    """

    name: str
    joint: str
    reduction: float = 1.0
    effort: float = math.inf
    velocity: float = math.inf
    rotor_inertia: float = 0.0
    efficiency: float = 1.0
    backdrive_efficiency: float | None = None
    viscous: float = 0.0
    coulomb: float = 0.0
    stiffness: float | None = None
    encoder_gain: float = 1.0
    encoder_offset: float = 0.0


@dataclass(frozen=True, eq=False)  # numpy / SE3 fields: no boolean ==
class PlatformSpec:
    """The platform / end-effector frame and the pose components the mechanism controls."""

    frame: FrameRef
    task: tuple[str, ...] = TASK_COMPONENTS


@dataclass(frozen=True)
class PassiveSpec:
    """Passive elements of one joint, per degree of freedom (its velocity coordinates).

    Each field holds no value (absent), one value (every degree of freedom) or one value per
    degree of freedom.

    Attributes:
        joint: Joint name.
        stiffness: Spring stiffness [N m/rad or N/m], >= 0.
        rest: Rest position of the spring, as the joint's displacement from its zero
            configuration [rad or m]: the angle or position of a revolute or prismatic joint,
            the two angles of a universal joint, the rotation vector of a spherical joint
            (default: zero).
        damping: Viscous damping [N m s/rad or N s/m], >= 0.
        friction: Coulomb friction [N m or N], >= 0.

    """

    joint: str
    stiffness: tuple[float, ...] = ()
    rest: tuple[float, ...] = ()
    damping: tuple[float, ...] = ()
    friction: tuple[float, ...] = ()

    @property
    def empty(self) -> bool:
        """No non-zero stiffness, damping or friction."""
        return not any(any(getattr(self, f)) for f in ("stiffness", "damping", "friction"))


@dataclass(frozen=True, eq=False)  # numpy / SE3 fields: no boolean ==
class SpringSpec:
    """A linear spring between two frames on two bodies, along the line joining their origins.

    Attributes:
        name: Spring name.
        frame1: First end.
        frame2: Second end.
        stiffness: Stiffness [N/m], >= 0.
        rest_length: Free length [m] (0: a zero-free-length spring; negative: an extension
            spring with initial tension ``T_i`` and free length ``L_f`` has
            ``L_f - T_i / stiffness``); the tension is ``stiffness * (length - rest_length)``.

    """

    name: str
    frame1: FrameRef
    frame2: FrameRef
    stiffness: float
    rest_length: float = 0.0


@dataclass(frozen=True)
class FamilySpec:
    """``<pkdyn:family>``: the library family and parameters a file was written from.

    Attributes:
        name: Family name (``delta``...).
        params: Parameter values as written (text), by name.

    """

    name: str
    params: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class CouplingSpec:
    """Scalar holonomic relation between two 1-DoF joint coordinates.

    ``(q[joint] - joint_ref) = sum_k coefficients[k] * (q[source] - source_ref)**k``
    (MuJoCo joint equality: ``polycoef``, refs = ``qpos0``; URDF ``<mimic>``:
    ``(offset, multiplier)``, refs 0); with ``source`` ``None`` the joint is held at
    ``joint_ref + coefficients[0]``. A continuous joint's coordinate is its angle [rad].

    Attributes:
        name: Coupling name (the equality, mimic or ``pkdyn:coupling`` it came from).
        joint: Driven (dependent) joint name.
        source: Driving joint name, or ``None`` for a locked joint.
        coefficients: Polynomial coefficients, constant term first (1 to 5 of them)
            [rad or m per (rad or m)^k].
        joint_ref: Reference coordinate of ``joint`` [rad or m].
        source_ref: Reference coordinate of ``source`` [rad or m].

    """

    name: str
    joint: str
    source: str | None
    coefficients: tuple[float, ...]
    joint_ref: float = 0.0
    source_ref: float = 0.0


@dataclass(frozen=True)
class LinearCouplingSpec:
    """Linear holonomic relation between any number of 1-DoF joint coordinates.

    ``sum_i coefficient_i * q[joint_i] = offset`` [rad or m]: sums and differences of joint
    coordinates along paths, with ratios (URDF+ ``<coupling>``: ``ratio * (sum of the
    predecessor path) - (sum of the successor path) = 0``; a rotor geared to the sum of a knee
    and an ankle angle). A continuous joint's coordinate is its angle [rad].

    Attributes:
        name: Coupling name.
        terms: ``(joint name, coefficient)`` pairs, each joint once, at least two of them (or
            one, which then holds that joint at ``offset / coefficient``).
        offset: Right-hand side [rad or m].

    """

    name: str
    terms: tuple[tuple[str, float], ...]
    offset: float = 0.0


@dataclass(frozen=True)
class MaterialSpec:
    """``<pkdyn:material>``: a material by preset name, or with its own constants.

    Attributes:
        name: Preset name (``steel``, ``aluminium``, ``carbon``: :mod:`pkdyn.precision.material`)
            or the name of a material given by its constants.
        E: Young's modulus [Pa] (``None``: the preset's).
        G: Shear modulus [Pa] (``None``: the preset's).
        density: Density [kg/m^3] (``None``: the preset's).
        mass_from_material: ``mass="from-material"``: the links read as beams of this material
            weigh what their section and density say (mass and inertia replace the URDF's
            ``<inertial>`` in the precision models), instead of what the URDF says.

    """

    name: str
    E: float | None = None
    G: float | None = None
    density: float | None = None
    mass_from_material: bool = False


@dataclass(frozen=True, eq=False)  # SE3 field: no boolean ==
class ComplianceSpec:
    """``<pkdyn:compliance link>``: how one link deforms (:mod:`pkdyn.precision`).

    Attributes:
        link: Link name.
        material: The link's material when it is modelled as a beam (``None``: the robot's
            ``<pkdyn:material>``, or the one given by argument).
        inner_radius: Bore of a hollow tube [m] (0: solid).
        compliance: Diagonal compliance (6,) [m/N x3, rad/(N m) x3] of the link's tip part with
            respect to its root, in the frame ``frame`` (given instead of a beam), or ``None``.
        frame: Placement of that frame in the link frame.
        rigid: The link does not deform (no beam even with a material).
        mass_from_material: ``mass="from-material"``: the link's beam weighs what its section
            and material's density say (``None``: as the robot's ``<pkdyn:material>`` says).

    """

    link: str
    material: MaterialSpec | None = None
    inner_radius: float = 0.0
    compliance: tuple[float, ...] | None = None
    frame: pin.SE3 = field(default_factory=pin.SE3.Identity)
    rigid: bool = False
    mass_from_material: bool | None = None


@dataclass(frozen=True, eq=False)  # numpy / SE3 fields: no boolean ==
class Description:
    """Everything a pkdyn description says beyond the URDF tree."""

    name: str
    closures: tuple[ClosureSpec, ...] = ()
    joints: tuple[JointSpec, ...] = ()
    actuators: tuple[ActuatorSpec, ...] = ()
    platform: PlatformSpec | None = None
    links: tuple[str, ...] = ()
    joint_names: tuple[str, ...] = ()
    passive: tuple[PassiveSpec, ...] = ()
    springs: tuple[SpringSpec, ...] = ()
    family: FamilySpec | None = None
    couplings: tuple[CouplingSpec | LinearCouplingSpec, ...] = ()
    home: tuple[float, ...] | None = None
    material: MaterialSpec | None = None
    compliance: tuple[ComplianceSpec, ...] = ()


def _vec(source: str, el: ET.Element, attr: str, default: str, n: int = 3) -> np.ndarray:
    text = el.get(attr, default)
    try:
        values = np.array([float(t) for t in text.split()], dtype=float)
    except ValueError:
        raise DescriptionError(
            source, f"<{_tag(el)}> attribute {attr}='{text}'", "expected numbers"
        ) from None
    if values.shape != (n,) or not np.all(np.isfinite(values)):
        raise DescriptionError(
            source, f"<{_tag(el)}> attribute {attr}='{text}'", f"expected {n} finite numbers"
        )
    return values


def _float(source: str, el: ET.Element, attr: str, default: float | None = None) -> float:
    text = el.get(attr)
    if text is None:
        if default is None:
            raise DescriptionError(source, f"<{_tag(el)}>", f"missing attribute '{attr}'")
        return default
    try:
        value = float(text)
    except ValueError:
        raise DescriptionError(
            source, f"<{_tag(el)}> attribute {attr}='{text}'", "expected a number"
        ) from None
    if math.isnan(value):
        raise DescriptionError(source, f"<{_tag(el)}> attribute {attr}", "NaN is not allowed")
    return value


def _tag(el: ET.Element) -> str:
    return el.tag.replace(_NS, "pkdyn:")


def _unit(source: str, what: str, v: np.ndarray) -> np.ndarray:
    u = unit_vector(v)  # no overflow for huge components
    if u is None or float(np.abs(v).max()) < 1e-12:
        raise DescriptionError(source, what, "axis must be a non-zero vector")
    return np.asarray(u)


def _frame(source: str, el: ET.Element, links: set[str]) -> FrameRef:
    link = el.get("link")
    if not link:
        raise DescriptionError(source, f"<{_tag(el)}>", "missing attribute 'link'")
    xyz = _vec(source, el, "xyz", "0 0 0")
    rpy = _vec(source, el, "rpy", "0 0 0")
    return FrameRef(link, pin.SE3(pin.rpy.rpyToMatrix(rpy), xyz))


def _closure(source: str, el: ET.Element, links: set[str]) -> ClosureSpec:
    name = el.get("name")
    if not name:
        raise DescriptionError(source, "<pkdyn:closure>", "missing attribute 'name'")
    kind = el.get("type", "")
    if kind not in CLOSURE_KINDS:
        raise DescriptionError(
            source,
            f"closure '{name}'",
            f"unknown type '{kind}'; use one of {', '.join(CLOSURE_KINDS)}",
        )
    frames = el.findall(_NS + "frame")
    if len(frames) != 2:
        raise DescriptionError(
            source, f"closure '{name}'", f"needs exactly two <pkdyn:frame>, found {len(frames)}"
        )
    f1, f2 = (_frame(source, f, links) for f in frames)
    axis = _unit(source, f"closure '{name}' axis", _vec(source, el, "axis", "0 0 1"))
    return ClosureSpec(name, kind, f1, f2, axis)


def _joint(source: str, el: ET.Element) -> JointSpec:
    name = el.get("name")
    if not name:
        raise DescriptionError(source, "<pkdyn:joint>", "missing attribute 'name'")
    kind = el.get("type", "")
    if kind not in JOINT_KINDS:
        raise DescriptionError(
            source,
            f"pkdyn:joint '{name}'",
            f"unknown type '{kind}'; use one of {', '.join(JOINT_KINDS)}",
        )
    axis2 = None
    if kind == "universal":
        if el.get("axis2") is None:
            raise DescriptionError(source, f"pkdyn:joint '{name}'", "universal needs axis2")
        axis2 = _unit(source, f"joint '{name}' axis2", _vec(source, el, "axis2", ""))
    limit: ConeLimit | PyramidLimit | None = None
    cone = el.find(_NS + "cone")
    pyramid = el.find(_NS + "pyramid")
    if cone is not None:
        axis = _unit(source, f"joint '{name}' cone axis", _vec(source, cone, "axis", "0 0 1"))
        half = _float(source, cone, "half_angle")
        if not 0.0 < half <= math.pi:
            raise DescriptionError(
                source, f"pkdyn:joint '{name}' cone half_angle={half}", "must lie in (0, pi] rad"
            )
        limit = ConeLimit(axis, half)
    elif pyramid is not None:
        axis = _unit(source, f"joint '{name}' pyramid", _vec(source, pyramid, "axis", "0 0 1"))
        ref = _vec(source, pyramid, "ref", "1 0 0")
        ref = _unit(source, f"joint '{name}' pyramid ref", ref - (ref @ axis) * axis)
        ha = _vec(source, pyramid, "half_angles", "", 2)
        if not all(0.0 < h <= math.pi / 2 for h in ha):
            raise DescriptionError(
                source, f"pkdyn:joint '{name}' pyramid half_angles", "must lie in (0, pi/2] rad"
            )
        limit = PyramidLimit(axis, ref, (float(ha[0]), float(ha[1])))
    return JointSpec(name, kind, axis2, limit)


def _actuators(source: str, root: ET.Element, strict: bool = True) -> list[ActuatorSpec]:
    """Actuators of the ``SimpleTransmission`` elements (other types are left out, one warning).

    With ``strict=False`` (a plain URDF, without pkdyn elements), ros_control transmissions
    pkdyn cannot use (no joint, a joint absent from the URDF or not revolute / prismatic) are
    skipped instead of raising.
    """
    limits: dict[str, tuple[float, float]] = {}
    kinds: dict[str, str] = {}
    for j in root.findall("joint"):
        kinds[j.get("name", "")] = j.get("type", "")
        lim = j.find("limit")
        if lim is not None:
            limits[j.get("name", "")] = (
                _float(source, lim, "effort", math.inf),
                _float(source, lim, "velocity", math.inf),
            )
    out = []
    other: list[str] = []
    for t in root.findall("transmission"):
        tname = t.get("name", "?")
        ttype = t.findtext("type") or t.get("type") or "SimpleTransmission"
        if not ttype.strip().endswith("SimpleTransmission"):
            other.append(f"'{tname}' ({ttype.strip().rsplit('/', 1)[-1]})")
            continue
        joint = t.find("joint")
        if not strict and (
            joint is None
            or kinds.get(joint.get("name", "")) not in ("revolute", "prismatic", "continuous")
        ):
            continue
        if joint is None or not joint.get("name"):
            raise DescriptionError(source, f"transmission '{tname}'", "needs a <joint name=...>")
        act = t.find("actuator")
        reduction = 1.0
        aname = tname
        red = t.find("mechanicalReduction")  # ROS 1 style: directly in the transmission
        if act is not None:
            aname = act.get("name", tname)
            if act.find("mechanicalReduction") is not None:
                red = act.find("mechanicalReduction")
        if red is not None and red.text:
            try:
                reduction = float(red.text)
            except ValueError:
                reduction = math.nan
            if not math.isfinite(reduction) or reduction == 0.0:
                raise DescriptionError(
                    source,
                    f"transmission '{tname}' mechanicalReduction '{red.text.strip()}'",
                    "expected a finite non-zero number",
                )
        jname = joint.get("name", "")
        effort, velocity = limits.get(jname, (math.inf, math.inf))
        drive = _drive(source, f"transmission '{tname}'", t if act is None else act)
        stiffness = _actuator_stiffness(source, f"transmission '{tname}'", t, act)
        out.append(
            ActuatorSpec(aname, jname, reduction, effort, velocity, **drive, stiffness=stiffness)
        )
    if other:
        from pkdyn.model.warn import warn

        warn(
            f"{source}: transmission(s) {', '.join(other[:3])}{' ...' if len(other) > 3 else ''} "
            "not read: pkdyn reads SimpleTransmission (one actuator on one joint)"
        )
    return out


def _drive(source: str, where: str, el: ET.Element) -> dict[str, float]:
    """Rotor inertia, efficiency and motor friction of an ``<actuator>`` (pkdyn elements)."""
    out: dict[str, float] = {}
    fields = (
        ("rotor_inertia", "value", "rotor_inertia", 0.0, math.inf),
        ("efficiency", "value", "efficiency", 0.0, 1.0),
        ("efficiency", "backdrive", "backdrive_efficiency", 0.0, 1.0),
        ("motor_friction", "viscous", "viscous", 0.0, math.inf),
        ("motor_friction", "coulomb", "coulomb", 0.0, math.inf),
        ("encoder", "gain", "encoder_gain", 0.0, math.inf),
        ("encoder", "offset", "encoder_offset", -math.inf, math.inf),
    )
    for tag, attr, key, lo, hi in fields:
        child = el.find(_NS + tag)
        if child is None or (child.get(attr) is None and attr != "value"):
            continue
        try:
            value = _float(source, child, attr)
        except DescriptionError as err:
            msg = str(err).split(": ")[-1]
            raise DescriptionError(source, f"{where} {err.culprit}", msg) from None
        positive = key.endswith("efficiency") or key == "encoder_gain"
        ok = lo < value <= hi if positive else lo <= value < hi
        ok = ok and math.isfinite(value) if key == "encoder_offset" else ok
        if not ok:
            interval = "(0, 1]" if key.endswith("efficiency") else "[0, inf)"
            interval = "(0, inf)" if key == "encoder_gain" else interval
            interval = "(-inf, inf)" if key == "encoder_offset" else interval
            raise DescriptionError(
                source,
                f"{where} <pkdyn:{tag}> {attr}='{child.get(attr)}'",
                f"must lie in {interval}",
            )
        out[key] = value
    return out


def _actuator_stiffness(
    source: str, where: str, transmission: ET.Element, actuator: ET.Element | None
) -> float | None:
    """``<pkdyn:stiffness value>`` of a transmission or of its actuator [N m/rad or N/m]."""
    found = [el.find(_NS + "stiffness") for el in (transmission, actuator) if el is not None]
    given = [el for el in found if el is not None]
    if not given:
        return None
    if len(given) > 1:
        raise DescriptionError(
            source, f"{where} <pkdyn:stiffness>", "given twice (transmission and actuator)"
        )
    value = _float(source, given[0], "value")
    if not (math.isfinite(value) and value > 0.0):
        raise DescriptionError(
            source,
            f"{where} <pkdyn:stiffness> value='{given[0].get('value')}'",
            "must be a finite stiffness > 0 [N m/rad or N/m]",
        )
    return value


def _positive(source: str, el: ET.Element, attr: str, zero: bool = False) -> float | None:
    """An optional finite attribute > 0 (>= 0 with ``zero``)."""
    if el.get(attr) is None:
        return None
    value = _float(source, el, attr)
    if not math.isfinite(value) or value < 0.0 or (value == 0.0 and not zero):
        bound = ">= 0" if zero else "> 0"
        raise DescriptionError(
            source, f"<{_tag(el)}> {attr}='{el.get(attr)}'", f"must be a finite number {bound}"
        )
    return value


_MASS_MODES = ("from-material", "as-described")
"""Values of the ``mass`` attribute of ``<pkdyn:material>`` and ``<pkdyn:compliance>``."""


def _mass_mode(source: str, el: ET.Element) -> bool | None:
    """``mass="from-material"`` (True), ``"as-described"`` (False) or absent (None)."""
    text = el.get("mass")
    if text is None:
        return None
    if text.strip() not in _MASS_MODES:
        raise DescriptionError(
            source, f"<{_tag(el)}> mass='{text}'", f"expected one of {', '.join(_MASS_MODES)}"
        )
    return text.strip() == "from-material"


def _material(source: str, el: ET.Element, name: str | None) -> MaterialSpec | None:
    """The material an element names (``name`` attribute) and its optional constants."""
    E, G, rho = (_positive(source, el, a) for a in ("E", "G", "density"))
    if name is None and E is None and G is None and rho is None:
        return None
    return MaterialSpec(name or "custom", E, G, rho, bool(_mass_mode(source, el)))


def _material_element(source: str, root: ET.Element) -> MaterialSpec | None:
    found = root.findall(_NS + "material")
    if not found:
        return None
    if len(found) > 1:
        raise DescriptionError(
            source, "<pkdyn:material>", f"given {len(found)} times; give the robot's one material"
        )
    name = found[0].get("name")
    if not name:
        raise DescriptionError(source, "<pkdyn:material>", "missing attribute 'name'")
    return _material(source, found[0], name)


def _compliance(source: str, el: ET.Element, links: set[str]) -> ComplianceSpec:
    link = el.get("link")
    if not link:
        raise DescriptionError(source, "<pkdyn:compliance>", "missing attribute 'link'")
    where = f"pkdyn:compliance link '{link}'"
    if link not in links:
        raise DescriptionError(source, where, "no link of that name in the URDF")
    rigid_text = el.get("rigid", "false").strip().lower()
    if rigid_text not in ("true", "false", "1", "0"):
        raise DescriptionError(source, f"{where} rigid='{rigid_text}'", "expected true or false")
    rigid = rigid_text in ("true", "1")
    compliance = None
    if el.get("compliance") is not None:
        values = _values(source, f"{where} compliance", el.get("compliance", ""), False)
        if len(values) != 6 or min(values) <= 0.0:
            raise DescriptionError(
                source,
                f"{where} compliance",
                "expected 6 values > 0: m/N along x y z, rad/(N m) about x y z of the frame",
            )
        compliance = values
    bore = _positive(source, el, "inner_radius", zero=True) or 0.0
    material = _material(source, el, el.get("material"))
    if sum((rigid, compliance is not None, material is not None or bore > 0.0)) > 1:
        raise DescriptionError(
            source,
            where,
            "give one of: rigid, compliance (with xyz / rpy), or a beam's material / inner_radius",
        )
    frame = _frame(source, el, links) if el.get("link") else pin.SE3.Identity()
    mass = _mass_mode(source, el)
    if mass and (rigid or compliance is not None):
        raise DescriptionError(
            source, f"{where} mass", "from-material needs a beam (a material or inner_radius)"
        )
    return ComplianceSpec(link, material, bore, compliance, frame.placement, rigid, mass)


_PASSIVE_FIELDS = ("stiffness", "rest", "damping", "friction")


def _values(source: str, culprit: str, text: str, signed: bool) -> tuple[float, ...]:
    """Finite numbers of a passive-element attribute (>= 0 unless ``signed``)."""
    try:
        values = tuple(float(t) for t in text.split())
    except ValueError:
        raise DescriptionError(source, culprit, f"'{text}' is not a list of numbers") from None
    if not values:
        raise DescriptionError(source, culprit, "is empty; give one value or one per DOF")
    for x in values:
        if not math.isfinite(x):
            raise DescriptionError(source, culprit, f"{x} is not finite")
        if not signed and x < 0.0:
            raise DescriptionError(source, culprit, f"{x:g} is negative; it must be >= 0")
    return values


def _passive(source: str, root: ET.Element) -> tuple[PassiveSpec, ...]:
    """Passive elements per joint: ``<dynamics>`` overridden field by field by pkdyn:passive.

    The ``<dynamics damping>`` of a fixed joint is dropped (URDF files reduced from moving
    joints keep it; a locked joint damps nothing); its friction is kept, and refused later.
    """
    fields: dict[str, dict[str, tuple[float, ...]]] = {}
    for j in root.findall("joint"):
        dyn = j.find("dynamics")
        name = j.get("name", "?")
        if dyn is None:
            continue
        kept = ("friction",) if j.get("type") == "fixed" else ("damping", "friction")
        for attr in kept:
            text = dyn.get(attr)
            if text is not None:
                culprit = f"joint '{name}' <dynamics> {attr}"
                fields.setdefault(name, {})[attr] = _values(source, culprit, text, False)
    seen: set[str] = set()
    for el in root.findall(_NS + "passive"):
        name = el.get("joint", "")
        if not name:
            raise DescriptionError(source, "<pkdyn:passive>", "missing attribute 'joint'")
        if name in seen:
            raise DescriptionError(
                source, f"pkdyn:passive joint '{name}'", "one <pkdyn:passive> per joint"
            )
        seen.add(name)
        for attr in _PASSIVE_FIELDS:
            text = el.get(attr)
            if text is not None:
                culprit = f"joint '{name}' {attr}"
                fields.setdefault(name, {})[attr] = _values(source, culprit, text, attr == "rest")
    return tuple(PassiveSpec(name, **f) for name, f in fields.items())


def _number(source: str, culprit: str, text: str) -> float:
    """One finite number of a coupling attribute."""
    try:
        value = float(text)
    except ValueError:
        raise DescriptionError(source, culprit, f"'{text}' is not a number") from None
    if not math.isfinite(value):
        raise DescriptionError(source, culprit, f"{text} is not a finite number")
    return value


def _coupling(source: str, el: ET.Element) -> CouplingSpec | LinearCouplingSpec:
    """A ``<pkdyn:coupling>`` element: polynomial (``joint``, ``source``...) or linear (terms)."""
    name = el.get("name")
    if not name:
        raise DescriptionError(source, "<pkdyn:coupling>", "missing attribute 'name'")
    what = f"coupling '{name}'"
    terms = el.findall(_NS + "term")
    other = [c.tag for c in el if c.tag != _NS + "term"]
    if other:
        tag = str(other[0]).replace(_NS, "pkdyn:")
        raise DescriptionError(
            source, what, f"unknown child <{tag}>; a coupling holds <pkdyn:term> children only"
        )
    if terms:
        return _linear_coupling(source, el, name, terms)
    joint = el.get("joint")
    if not joint:
        raise DescriptionError(
            source,
            what,
            "missing attribute 'joint' (the driven joint), or <pkdyn:term joint coefficient> "
            "children (a linear coupling)",
        )
    src = el.get("source") or None
    poly = el.get("polycoef")
    if poly is not None and (el.get("multiplier") is not None or el.get("offset") is not None):
        raise DescriptionError(source, what, "give polycoef or multiplier/offset, not both")
    if poly is not None:
        coef = tuple(_number(source, f"{what} polycoef", t) for t in poly.split())
        if not 1 <= len(coef) <= 5:
            raise DescriptionError(
                source, f"{what} polycoef='{poly}'", f"{len(coef)} coefficients; give 1 to 5"
            )
    else:
        offset = _number(source, f"{what} offset", el.get("offset", "0"))
        multiplier = _number(source, f"{what} multiplier", el.get("multiplier", "1"))
        coef = (offset, multiplier)
    if src is None:
        if (poly is not None and any(coef[1:])) or el.get("multiplier") is not None:
            raise DescriptionError(
                source, what, "a coupling without source locks its joint: give offset only"
            )
        coef = coef[:1]
    refs = [_number(source, f"{what} {a}", el.get(a, "0")) for a in ("joint_ref", "source_ref")]
    return CouplingSpec(name, joint, src, coef, refs[0], refs[1])


def _linear_coupling(
    source: str, el: ET.Element, name: str, terms: list[ET.Element]
) -> LinearCouplingSpec:
    """``<pkdyn:coupling name offset>`` with ``<pkdyn:term joint coefficient>`` children."""
    what = f"coupling '{name}'"
    extra = [a for a in ("joint", "source", "polycoef", "multiplier") if el.get(a) is not None]
    if extra:
        raise DescriptionError(
            source,
            what,
            f"attribute '{extra[0]}' with <pkdyn:term> children: a linear coupling is its "
            "terms and its offset only",
        )
    out: list[tuple[str, float]] = []
    for t in terms:
        joint = t.get("joint")
        if not joint:
            raise DescriptionError(source, f"{what} <pkdyn:term>", "missing attribute 'joint'")
        if any(j == joint for j, _ in out):
            raise DescriptionError(
                source, what, f"joint '{joint}' appears in two terms; give each joint once"
            )
        text = t.get("coefficient")
        if text is None:
            raise DescriptionError(
                source, f"{what} term of '{joint}'", "missing attribute 'coefficient'"
            )
        coef = _number(source, f"{what} coefficient of '{joint}'", text)
        if coef == 0.0:
            raise DescriptionError(
                source, f"{what} coefficient of '{joint}'", "is zero: leave the term out"
            )
        out.append((joint, coef))
    offset = _number(source, f"{what} offset", el.get("offset", "0"))
    return LinearCouplingSpec(name, tuple(out), offset)


_ONE_DOF = ("revolute", "continuous", "prismatic")


def _mimics(source: str, root: ET.Element) -> list[CouplingSpec]:
    """Couplings of the URDF ``<mimic joint multiplier offset>`` elements.

    A mimic between joints that are not both moving 1-DoF joints of the file (a joint that does
    not exist, a fixed joint...) is an error (``ignore_elements=("mimic",)`` leaves the file's
    mimics out): the joint would otherwise move freely, a coupling silently lost.
    """
    kinds = {j.get("name", ""): j.get("type", "") for j in root.findall("joint")}
    out = []
    for j in root.findall("joint"):
        m = j.find("mimic")
        if m is None:
            continue
        jname = j.get("name", "?")
        what = f"joint '{jname}' <mimic>"
        src = m.get("joint")
        if not src:
            raise DescriptionError(source, what, "missing attribute 'joint'")
        multiplier = _number(source, f"{what} multiplier", m.get("multiplier", "1"))
        offset = _number(source, f"{what} offset", m.get("offset", "0"))
        bad = next((n for n in (jname, src) if kinds.get(n) not in _ONE_DOF), None)
        if bad is not None:
            why = (
                f"names joint '{bad}', which does not exist"
                if bad not in kinds
                else f"joint '{bad}' is {kinds[bad] or 'untyped'}, not a revolute, continuous "
                "or prismatic joint"
            )
            raise DescriptionError(
                source, what, f"{why} (ignore_elements=('mimic',) leaves the mimics out)"
            )
        out.append(CouplingSpec(f"{jname}_mimic", jname, src, (offset, multiplier)))
    return out


def _spring(source: str, el: ET.Element, links: set[str]) -> SpringSpec:
    name = el.get("name")
    if not name:
        raise DescriptionError(source, "<pkdyn:spring>", "missing attribute 'name'")
    frames = el.findall(_NS + "frame")
    if len(frames) != 2:
        raise DescriptionError(
            source, f"spring '{name}'", f"needs exactly two <pkdyn:frame>, found {len(frames)}"
        )
    f1, f2 = (_frame(source, f, links) for f in frames)
    if el.get("stiffness") is None:
        raise DescriptionError(source, f"spring '{name}'", "missing attribute 'stiffness'")
    k = _values(source, f"spring '{name}' stiffness", el.get("stiffness", ""), False)
    L0 = _values(source, f"spring '{name}' rest_length", el.get("rest_length", "0"), True)
    if len(k) != 1 or len(L0) != 1:
        raise DescriptionError(source, f"spring '{name}'", "stiffness and rest_length: 1 value")
    return SpringSpec(name, f1, f2, k[0], L0[0])


ELEMENTS = (
    "closure",
    "joint",
    "platform",
    "passive",
    "spring",
    "family",
    "material",
    "compliance",
    "home",
    "coupling",
)
"""The top-level pkdyn elements (children of ``<robot>``)."""


def _check_namespace(source: str, root: ET.Element) -> None:
    """Refuse pkdyn-like elements in another namespace and unknown pkdyn elements.

    A mistyped namespace URI (``urn:pkdyn:urdf:2``, ``urn:pkydn:urdf:1``) would make every
    pkdyn element invisible: the closures would be silently dropped.
    """
    for el in root.iter():
        tag = el.tag if isinstance(el.tag, str) else ""
        if not tag.startswith("{"):
            continue
        uri, _, local = tag[1:].partition("}")
        if uri == NAMESPACE:
            if el in list(root) and local not in ELEMENTS:
                raise DescriptionError(
                    source,
                    f"<pkdyn:{local}>",
                    f"unknown pkdyn element; the elements are {', '.join(ELEMENTS)}",
                )
            continue
        if "pkdyn" in uri.lower() or local in ELEMENTS + ("frame", "cone", "pyramid", "term"):
            raise DescriptionError(
                source,
                f"namespace '{uri}' of <{local}>",
                f"pkdyn's namespace is '{NAMESPACE}' (xmlns:pkdyn=\"{NAMESPACE}\"); with any "
                "other the pkdyn elements would be ignored",
            )


def _unique(source: str, what: str, names: list[str]) -> None:
    seen: set[str] = set()
    for n in names:
        if n in seen:
            raise DescriptionError(source, f"{what} '{n}'", f"{what} is given twice")
        seen.add(n)


def parse_description(xml_text: str, source: str) -> Description:
    """Parse the pkdyn extension elements of a URDF document.

    Args:
        xml_text: The URDF document.
        source: Where it came from (file name or robot name), for error messages.

    Returns:
        The parsed description (closures, joints, actuators, platform).

    Raises:
        DescriptionError: Malformed XML or a malformed extension element.

    """
    try:
        root = ET.fromstring(xml_text)
    except ET.ParseError as err:
        raise DescriptionError(source, "XML", f"malformed document ({err})") from None
    if root.tag != "robot":
        raise DescriptionError(source, f"<{root.tag}>", "the root element must be <robot>")
    _check_namespace(source, root)
    extended = any(isinstance(el.tag, str) and el.tag.startswith(_NS) for el in root)
    check_urdf(source, root, strict=extended)
    links = {el.get("name", "") for el in root.findall("link")}
    joint_names = tuple(el.get("name", "") for el in root.findall("joint"))
    closures = tuple(_closure(source, el, links) for el in root.findall(_NS + "closure"))
    joints = tuple(_joint(source, el) for el in root.findall(_NS + "joint"))
    _unique(source, "closure", [c.name for c in closures])
    _unique(source, "pkdyn:joint", [j.name for j in joints])
    platform = None
    platforms = root.findall(_NS + "platform")
    if len(platforms) > 1:
        raise DescriptionError(
            source,
            "<pkdyn:platform>",
            f"given {len(platforms)} times; a robot has one platform frame",
        )
    pel = platforms[0] if platforms else None
    if pel is not None:
        task = tuple(pel.get("task", " ".join(TASK_COMPONENTS)).split())
        bad = [t for t in task if t not in TASK_COMPONENTS]
        if bad or not task:
            raise DescriptionError(
                source,
                f"pkdyn:platform task '{' '.join(task)}'",
                f"components must be among {' '.join(TASK_COMPONENTS)}",
            )
        platform = PlatformSpec(_frame(source, pel, links), task)
    springs = tuple(_spring(source, el, links) for el in root.findall(_NS + "spring"))
    spring_names = [sp.name for sp in springs]
    for n in spring_names:
        if spring_names.count(n) > 1:
            raise DescriptionError(source, f"spring '{n}'", "spring names must be unique")
    couplings = tuple(_mimics(source, root)) + tuple(
        _coupling(source, el) for el in root.findall(_NS + "coupling")
    )
    _unique(source, "coupling", [c.name for c in couplings])
    return Description(
        name=root.get("name", source),
        closures=closures,
        joints=joints,
        actuators=tuple(_actuators(source, root, strict=extended)),
        platform=platform,
        links=tuple(sorted(links)),
        joint_names=joint_names,
        passive=_passive(source, root),
        springs=springs,
        family=_family(source, root),
        couplings=couplings,
        home=_home(source, root),
        material=_material_element(source, root),
        compliance=_compliances(source, root, links),
    )


def _home(source: str, root: ET.Element) -> tuple[float, ...] | None:
    found = root.findall(_NS + "home")
    if not found:
        return None
    if len(found) > 1:
        raise DescriptionError(source, "<pkdyn:home>", f"given {len(found)} times")
    text = found[0].get("q")
    if text is None:
        raise DescriptionError(source, "<pkdyn:home>", "missing attribute 'q'")
    return _values(source, "<pkdyn:home> q", text, True)


def _compliances(source: str, root: ET.Element, links: set[str]) -> tuple[ComplianceSpec, ...]:
    out = tuple(_compliance(source, el, links) for el in root.findall(_NS + "compliance"))
    _unique(source, "pkdyn:compliance link", [c.link for c in out])
    return out


def _family(source: str, root: ET.Element) -> FamilySpec | None:
    found = root.findall(_NS + "family")
    if not found:
        return None
    if len(found) > 1:
        raise DescriptionError(source, "<pkdyn:family>", f"given {len(found)} times")
    el = found[0]
    name = el.get("name")
    if not name:
        raise DescriptionError(source, "<pkdyn:family>", "missing attribute 'name'")
    values: list[tuple[str, str]] = []
    for par in el.findall(_NS + "param"):
        key, value = par.get("name"), par.get("value")
        if not key or value is None:
            raise DescriptionError(
                source, f"<pkdyn:family name='{name}'> <pkdyn:param>", "needs name and value"
            )
        if key in dict(values):
            raise DescriptionError(
                source, f"<pkdyn:family name='{name}'> parameter '{key}'", "given twice"
            )
        values.append((key, value))
    return FamilySpec(name, tuple(values))
