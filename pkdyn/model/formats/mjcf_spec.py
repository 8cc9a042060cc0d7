"""MJCF attributes as MuJoCo reads them: compiler settings, default classes, orientations.

Each kind of element is read in one place, with its default class resolved, into a small
dataclass: :func:`joint_props` (``<joint>``, ``<freejoint>``), :func:`actuator_props` (every
actuator shortcut), :func:`geom_props` (``<geom>``), :func:`inertial_props` (``<inertial>``).
Angles follow ``<compiler angle>`` (degrees by default, as in MuJoCo) and are returned in
radians; orientations (``quat``, ``axisangle``, ``euler`` with ``eulerseq``, ``xyaxes``,
``zaxis``) become rotation matrices.

Default classes: the top-level ``<default>`` is class ``main``; nested ``<default class>``
elements inherit from their parent. An element uses its ``class`` attribute, else the nearest
enclosing ``childclass``, else ``main``. All actuator shortcuts (``motor``, ``position``,
``general``...) share one set of defaults per class, as in MuJoCo. An attribute MuJoCo reads
with fewer values than its full form (:data:`PARTIAL`: a geom's ``size``, an actuator's
``gear``...; an equality's ``polycoef``, :data:`POLYCOEF`) keeps the default class's (or
MuJoCo's built-in) values for the ones not given, as MuJoCo does.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pkdyn.model.formats.xmldoc import XmlDoc
from pkdyn.model.validate import unit_vector

__all__ = [
    "ACTUATOR_TAGS",
    "MAX_DEFAULT_DEPTH",
    "PARTIAL",
    "POLYCOEF",
    "ActuatorProps",
    "Compiler",
    "Defaults",
    "GeomProps",
    "InertialProps",
    "JointProps",
    "actuator_props",
    "complete",
    "geom_props",
    "inertial_props",
    "joint_props",
    "orientation",
    "vector",
]

ACTUATOR_TAGS = (
    "general",
    "motor",
    "position",
    "velocity",
    "intvelocity",
    "damper",
    "cylinder",
    "muscle",
    "adhesion",
    "plugin",
)
"""Actuator elements of MJCF (``plugin`` actuators included)."""

MAX_DEFAULT_DEPTH = 100
"""Deepest nesting of ``<default>`` classes."""

PARTIAL = {
    ("geom", "size"): "0 0 0",
    ("site", "size"): "0.005 0.005 0.005",
    ("joint", "stiffness"): "0 0 0",
    ("joint", "damping"): "0 0 0",
    ("actuator", "gear"): "1 0 0 0 0 0",
    ("actuator", "gainprm"): "1 0 0 0 0 0 0 0 0 0",
    ("actuator", "biasprm"): "0 0 0 0 0 0 0 0 0 0",
    ("actuator", "dynprm"): "1 0 0 0 0 0 0 0 0 0",
}
"""MJCF attributes MuJoCo reads with fewer values than their full form (its reader's
``exact = false``), and MuJoCo's built-in values: given ``k`` values, the others keep those of
the default class (or these built-in ones), as :func:`complete` fills them. Every other
attribute needs its full count (``axis="0 1"`` is refused, as MuJoCo refuses it)."""

POLYCOEF = "0 1 0 0 0"
"""MuJoCo's default ``polycoef`` of a joint or tendon equality (``polycoef="0.3"`` reads
``0.3 1 0 0 0``: an offset, not a lock)."""


def complete(given: str, base: str) -> str:
    """An attribute value with fewer numbers than ``base``, completed from ``base``.

    Args:
        given: The value as written (``"0.05"``).
        base: The full value it overrides (the default class's, or MuJoCo's built-in one).

    Returns:
        ``given``'s numbers followed by ``base``'s remaining ones (``"0.05 0.2 0.3"``);
        ``given`` unchanged when it has as many numbers as ``base`` or more.

    """
    tokens, full = given.split(), base.split()
    if len(tokens) >= len(full):
        return given
    return " ".join(tokens + full[len(tokens) :])


def vector(doc: XmlDoc, el: ET.Element, attr: str, text: str, n: int | None) -> np.ndarray:
    """Numbers of an attribute value.

    Args:
        doc: The document (for messages).
        el: The element.
        attr: Attribute name.
        text: Attribute value.
        n: Expected count (``None``: any).

    Returns:
        The numbers (finite).

    Raises:
        DescriptionError: Not numbers, not finite, or the wrong count.

    """
    try:
        values = np.array([float(t) for t in text.split()], dtype=float)
    except ValueError:
        raise doc.error(el, f"attribute {attr}='{text}': expected numbers") from None
    if n is not None and values.size != n:
        raise doc.error(el, f"attribute {attr}='{text}': expected {n} numbers")
    if not np.all(np.isfinite(values)):
        raise doc.error(el, f"attribute {attr}='{text}': NaN and infinite values are not allowed")
    return values


def integer(doc: XmlDoc, el: ET.Element, attr: str, text: str, n: int = 1) -> list[int]:
    """Integers of an attribute value (``contype``, ``group``, ``inertiagrouprange``...).

    Raises:
        DescriptionError: Not integers (``1.5``, ``abc``, ``nan``), or the wrong count.

    """
    out = []
    for t in text.split():
        try:
            out.append(int(t))
        except ValueError:
            raise doc.error(el, f"attribute {attr}='{text}': expected integers") from None
    if len(out) != n:
        raise doc.error(el, f"attribute {attr}='{text}': expected {n} integer(s)")
    return out


@dataclass(frozen=True)
class Compiler:
    """``<compiler>`` settings that change how the model reads.

    Attributes:
        degrees: Angles in degrees (``angle="degree"``, MuJoCo's default).
        eulerseq: Euler sequence (lowercase: axes that move with the frame).
        autolimits: A ``range`` alone makes a joint or actuator limited.
        meshdir: Directory of mesh files (relative to the model file).
        inertiafromgeom: ``auto``, ``true`` or ``false``.
        inertiagrouprange: Geom groups that contribute to inferred inertias.

    """

    degrees: bool = True
    eulerseq: str = "xyz"
    autolimits: bool = True
    meshdir: str = ""
    inertiafromgeom: str = "auto"
    inertiagrouprange: tuple[int, int] = (0, 5)

    @staticmethod
    def read(doc: XmlDoc, elements: list[ET.Element]) -> Compiler:
        """Settings of the ``<compiler>`` elements (later ones override)."""
        attrs: dict[str, str] = {}
        for el in elements:
            attrs.update(el.attrib)
            if el.get("coordinate", "local") != "local":
                raise doc.error(
                    el, "coordinate='global' was removed from MuJoCo; use local coordinates"
                )
        angle = attrs.get("angle", "degree")
        if angle not in ("degree", "radian"):
            raise doc.error(elements[-1], f"angle='{angle}': use degree or radian")
        seq = attrs.get("eulerseq", "xyz")
        if len(seq) != 3 or any(c not in "xyzXYZ" for c in seq):
            raise doc.error(elements[-1], f"eulerseq='{seq}': three of x y z X Y Z")
        ifg = attrs.get("inertiafromgeom", "auto")
        if ifg not in ("auto", "true", "false"):
            raise doc.error(elements[-1], f"inertiafromgeom='{ifg}': use auto, true or false")
        last = elements[-1] if elements else None
        grp = (0, 5)
        if "inertiagrouprange" in attrs and last is not None:
            lo, hi = integer(doc, last, "inertiagrouprange", attrs["inertiagrouprange"], 2)
            grp = (lo, hi)
        return Compiler(
            degrees=angle == "degree",
            eulerseq=seq,
            autolimits=attrs.get("autolimits", "true") == "true",
            meshdir=attrs.get("meshdir", attrs.get("assetdir", "")),
            inertiafromgeom=ifg,
            inertiagrouprange=grp,
        )

    def angle(self, value: float) -> float:
        """An angle of the file in radians."""
        return math.radians(value) if self.degrees else value


class Defaults:
    """The default classes of a model (see the module docstring)."""

    def __init__(self, doc: XmlDoc, elements: list[ET.Element]) -> None:
        self.doc = doc
        self.classes: dict[str, dict[str, dict[str, str]]] = {"main": {}}
        stack: list[tuple[ET.Element, str, str | None, int]] = [
            (el, "main", None, 0) for el in reversed(elements)
        ]
        while stack:  # iterative: any nesting depth up to MAX_DEFAULT_DEPTH
            el, name, parent, depth = stack.pop()
            if parent is not None and name in self.classes:
                raise self.doc.error(el, f"default class '{name}' defined twice")
            for child in reversed(self._read(el, name, parent)):
                if depth + 1 > MAX_DEFAULT_DEPTH:
                    raise self.doc.error(
                        child, f"default classes nested deeper than {MAX_DEFAULT_DEPTH} levels"
                    )
                stack.append((child, str(child.get("class")), name, depth + 1))

    def _read(self, el: ET.Element, name: str, parent: str | None) -> list[ET.Element]:
        """Read one class's own defaults; return its nested ``<default>`` elements."""
        if name not in self.classes or parent is not None:
            base = self.classes.get(parent, {}) if parent is not None else {}
            self.classes[name] = {tag: dict(a) for tag, a in base.items()}
        own = self.classes[name]
        nested: list[ET.Element] = []
        for child in el:
            if child.tag == "default":
                cname = child.get("class")
                if not cname:
                    raise self.doc.error(child, "a nested <default> needs a class name")
                if cname in self.classes or cname in [c.get("class") for c in nested]:  # early
                    raise self.doc.error(child, f"default class '{cname}' defined twice")
                nested.append(child)
            else:
                tag = "actuator" if child.tag in ACTUATOR_TAGS else child.tag
                values = own.setdefault(tag, {})
                for key, value in child.attrib.items():
                    if (tag, key) in PARTIAL:  # the parent class's values complete it
                        value = complete(value, values.get(key, PARTIAL[tag, key]))
                    values[key] = value
                if child.tag in ACTUATOR_TAGS:
                    own["actuator"]["_shortcut"] = child.tag
        return nested

    def check(self, el: ET.Element, cls: str) -> None:
        """Refuse a class name that was never defined."""
        if cls not in self.classes:
            raise self.doc.error(el, f"class '{cls}' is not a default class of this model")

    def attrs(self, el: ET.Element, cls: str) -> dict[str, str]:
        """Attributes of an element with those of its default class underneath."""
        name = el.get("class", cls)
        self.check(el, name)
        tag = "actuator" if el.tag in ACTUATOR_TAGS else el.tag
        if el.tag == "freejoint":
            tag = "joint"
        out = {k: v for k, v in self.classes[name].get(tag, {}).items() if k != "_shortcut"}
        if tag == "actuator" and self.classes[name].get(tag, {}).get("_shortcut") != el.tag:
            # shortcut-specific gains do not carry over from another shortcut's defaults
            for k in ("kp", "kv", "gainprm", "biasprm", "gaintype", "biastype", "dyntype"):
                out.pop(k, None)
        for key, value in el.attrib.items():
            if (tag, key) in PARTIAL:  # fewer values: the class's (or MuJoCo's) complete them
                value = complete(value, out.get(key, PARTIAL[tag, key]))
            out[key] = value
        return out


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    u = unit_vector(axis)
    assert u is not None  # callers refuse zero axes
    return np.asarray(pin.AngleAxis(angle, u).matrix())


def _direction(
    doc: XmlDoc, el: ET.Element, v: np.ndarray, what: str, noun: str = "axis"
) -> np.ndarray:
    """Unit vector of ``v`` (huge components allowed), refusing a zero vector."""
    u = unit_vector(v)
    if u is None or float(np.abs(v).max()) < 1e-12:
        raise doc.error(el, f"{what}: zero {noun}")
    return np.asarray(u)


def orientation(doc: XmlDoc, el: ET.Element, attrs: dict[str, str], comp: Compiler) -> np.ndarray:
    """Rotation matrix of an element's orientation attributes (identity when absent).

    Args:
        doc: The document (for messages).
        el: The element.
        attrs: Its attributes (defaults resolved).
        comp: Compiler settings.

    Returns:
        Rotation (3, 3).

    Raises:
        DescriptionError: Several orientation attributes, or malformed values.

    """
    given = [k for k in ("quat", "axisangle", "euler", "xyaxes", "zaxis") if k in el.attrib]
    if len(given) > 1:
        raise doc.error(el, f"orientation given twice ({', '.join(given)}); keep one")
    key = (
        given[0]
        if given
        else next(
            (k for k in ("quat", "axisangle", "euler", "xyaxes", "zaxis") if k in attrs), None
        )
    )
    if key is None:
        return np.eye(3)
    text = attrs[key]
    if key == "quat":
        w, x, y, z = _direction(
            doc, el, vector(doc, el, key, text, 4), f"quat='{text}'", "quaternion"
        )
        return np.asarray(pin.Quaternion(w, x, y, z).matrix())
    if key == "axisangle":
        v = vector(doc, el, key, text, 4)
        _direction(doc, el, v[:3], f"axisangle='{text}'")
        return _axis_angle(v[:3], comp.angle(v[3]))
    if key == "euler":
        v = vector(doc, el, key, text, 3)
        R = np.eye(3)
        for c, a in zip(comp.eulerseq, v, strict=True):
            Ri = _axis_angle(np.eye(3)["xyz".index(c.lower())], comp.angle(a))
            R = R @ Ri if c.islower() else Ri @ R  # moving axes: post-multiply
        return R
    if key == "xyaxes":
        v = vector(doc, el, key, text, 6)
        x = _direction(doc, el, v[:3], f"xyaxes='{text}' x axis")
        y = _direction(doc, el, v[3:], f"xyaxes='{text}' y axis")
        y = y - (y @ x) * x
        if np.linalg.norm(y) < 1e-9:
            raise doc.error(el, f"xyaxes='{text}': y axis parallel to x")
        y = y / np.linalg.norm(y)
        return np.column_stack([x, y, np.cross(x, y)])
    z = vector(doc, el, key, text, 3)
    return _zaxis(doc, el, z)


def _zaxis(doc: XmlDoc, el: ET.Element, z: np.ndarray) -> np.ndarray:
    """Minimal rotation taking (0, 0, 1) to ``z``."""
    z = _direction(doc, el, z, "z axis")
    e = np.array([0.0, 0.0, 1.0])
    axis = np.cross(e, z)
    s = float(np.linalg.norm(axis))
    if s < 1e-12:
        return np.eye(3) if z[2] > 0 else np.diag([1.0, -1.0, -1.0])
    return _axis_angle(axis, math.atan2(s, float(e @ z)))


def pose(doc: XmlDoc, el: ET.Element, attrs: dict[str, str], comp: Compiler) -> pin.SE3:
    """``pos`` and orientation of an element as a placement in its parent frame."""
    pos = vector(doc, el, "pos", attrs["pos"], 3) if "pos" in attrs else np.zeros(3)
    return pin.SE3(orientation(doc, el, attrs, comp), pos)


def _limited(attrs: dict[str, str], key: str, range_key: str, comp: Compiler) -> bool:
    flag = attrs.get(key, "auto")
    if flag == "auto":
        return comp.autolimits and range_key in attrs
    return flag == "true"


@dataclass(frozen=True)
class JointProps:
    """A ``<joint>`` (or ``<freejoint>``) with its defaults; angles in radians.

    Attributes:
        name: Name ('' when unnamed).
        type: ``hinge``, ``slide``, ``ball`` or ``free``.
        pos: Position in the body frame [m].
        axis: Unit axis in the body frame.
        ref: Reference position (``qpos0``) [rad or m].
        range: Position range when limited [rad or m] (a ball's: maximum angle), else ``None``.
        damping: Viscous damping.
        frictionloss: Dry friction.
        armature: Armature (rotor inertia reflected to the joint).
        stiffness: Spring stiffness.
        springref: Spring rest position [rad or m].

    """

    name: str
    type: str
    pos: np.ndarray
    axis: np.ndarray
    ref: float = 0.0
    range: tuple[float, float] | None = None
    damping: float = 0.0
    frictionloss: float = 0.0
    armature: float = 0.0
    stiffness: float = 0.0
    springref: float = 0.0


def _number(doc: XmlDoc, el: ET.Element, attrs: dict[str, str], key: str, default: float) -> float:
    return float(vector(doc, el, key, attrs[key], 1)[0]) if key in attrs else default


def _linear(doc: XmlDoc, el: ET.Element, attrs: dict[str, str], key: str) -> float:
    """A joint's ``stiffness`` or ``damping``, which must be linear (the law pkdyn models).

    MuJoCo reads a polynomial of up to 3 coefficients, completed from the default class.
    """
    if key not in attrs:
        return 0.0
    v = vector(doc, el, key, attrs[key], None)
    if v.size == 0 or v.size > 3:
        raise doc.error(el, f"{key}='{attrs[key]}': expected 1 to 3 numbers")
    if np.any(v[1:]):
        raise doc.error(
            el,
            f"{key}='{attrs[key]}' (with its default class): a polynomial {key} (MuJoCo's "
            "higher coefficients) is not modelled by pkdyn; give a linear one (one value)",
        )
    return float(v[0])


def joint_props(
    doc: XmlDoc, el: ET.Element, cls: str, defs: Defaults, comp: Compiler
) -> JointProps:
    """Read a ``<joint>`` or ``<freejoint>`` element.

    Raises:
        DescriptionError: Unknown joint type, zero axis, malformed numbers.

    """
    a = defs.attrs(el, cls)
    jtype = "free" if el.tag == "freejoint" else a.get("type", "hinge")
    if jtype not in ("hinge", "slide", "ball", "free"):
        raise doc.error(el, f"joint type '{jtype}' is not an MJCF joint type")
    axis = vector(doc, el, "axis", a.get("axis", "0 0 1"), 3)
    if jtype in ("hinge", "slide"):
        axis = _direction(doc, el, axis, f"axis='{a.get('axis')}'")
    angular = jtype == "hinge"

    def ang(v: float) -> float:
        return comp.angle(v) if angular else v

    rng = None
    if _limited(a, "limited", "range", comp) and jtype != "free":
        lo, hi = vector(doc, el, "range", a.get("range", "0 0"), 2)
        if jtype == "ball":
            rng = (0.0, comp.angle(hi))
        else:
            rng = (ang(lo), ang(hi))
        if rng[0] > rng[1]:
            raise doc.error(el, f"range='{a.get('range')}': lower bound above the upper bound")
    for key in ("armature", "damping", "frictionloss", "stiffness"):
        first = _linear(doc, el, a, key) if key in ("damping", "stiffness") else None
        if key in a and (first if first is not None else _number(doc, el, a, key, 0.0)) < 0.0:
            text = el.get(key, a[key])  # as written (the class's completion not shown)
            raise doc.error(el, f"{key}='{text}' is negative (a negative {key} is not physical)")
    return JointProps(
        name=a.get("name", ""),
        type=jtype,
        pos=vector(doc, el, "pos", a.get("pos", "0 0 0"), 3),
        axis=unit_vector(axis) if np.any(axis) else np.array([0.0, 0.0, 1.0]),
        ref=ang(_number(doc, el, a, "ref", 0.0)),
        range=rng,
        damping=_linear(doc, el, a, "damping"),
        frictionloss=_number(doc, el, a, "frictionloss", 0.0),
        armature=_number(doc, el, a, "armature", 0.0),
        stiffness=_linear(doc, el, a, "stiffness"),
        springref=ang(_number(doc, el, a, "springref", 0.0)),
    )


@dataclass(frozen=True)
class ActuatorProps:
    """An actuator element with its defaults.

    Attributes:
        name: Name ('' when unnamed).
        kind: Element tag (``motor``, ``position``, ``general``...).
        target: Transmission target name.
        transmission: ``joint``, ``jointinparent``, ``tendon``, ``site``, ``body``, ``slidercrank``.
        gear: First gear component (joint side = gear x actuator side).
        ctrlrange: Control range when limited, else ``None``.
        forcerange: Force range (actuation space) when limited, else ``None``.
        gain: Control-to-force gain when the force is proportional to the control (motors,
            ``general`` without bias), else ``None``.

    """

    name: str
    kind: str
    target: str
    transmission: str
    gear: float = 1.0
    ctrlrange: tuple[float, float] | None = None
    forcerange: tuple[float, float] | None = None
    gain: float | None = None


def actuator_props(doc: XmlDoc, el: ET.Element, defs: Defaults, comp: Compiler) -> ActuatorProps:
    """Read an actuator element (any shortcut).

    Raises:
        DescriptionError: No transmission target, malformed numbers.

    """
    a = defs.attrs(el, "main")
    trans = [k for k in ("joint", "jointinparent", "tendon", "site", "body", "cranksite") if k in a]
    if not trans:
        raise doc.error(el, "names no joint, tendon, site or body to act on")
    kind = trans[0]
    gear = vector(doc, el, "gear", a.get("gear", "1"), None)
    if gear.size == 0:
        raise doc.error(el, "gear is empty")

    def rng(key: str, flag: str) -> tuple[float, float] | None:
        if not _limited(a, flag, key, comp):
            return None
        lo, hi = vector(doc, el, key, a.get(key, "0 0"), 2)
        if lo > hi:
            raise doc.error(el, f"{key}='{a.get(key)}': lower bound above the upper bound")
        return (float(lo), float(hi))

    gain: float | None = None
    if el.tag == "motor":
        gain = 1.0
    elif el.tag == "general" and a.get("biastype", "none") == "none":
        if a.get("gaintype", "fixed") == "fixed" and a.get("dyntype", "none") == "none":
            gain = float(vector(doc, el, "gainprm", a.get("gainprm", "1"), None)[0])
    return ActuatorProps(
        name=a.get("name", ""),
        kind=el.tag,
        target=a[kind],
        transmission="slidercrank" if kind == "cranksite" else kind,
        gear=float(gear[0]),
        ctrlrange=rng("ctrlrange", "ctrllimited"),
        forcerange=rng("forcerange", "forcelimited"),
        gain=gain,
    )


@dataclass(frozen=True)
class GeomProps:
    """A ``<geom>`` with its defaults.

    Attributes:
        name: Name ('' when unnamed).
        type: Geom type.
        size: Size numbers (as given; ``fromto`` fills the half length).
        placement: Pose in the body frame.
        mesh: Mesh asset name (mesh geoms).
        rgba: Colour.
        visual: Contact-free geom (``contype`` and ``conaffinity`` both 0).
        group: Group.
        mass: Mass attribute, if given [kg].
        density: Density [kg/m^3].

    """

    name: str
    type: str
    size: np.ndarray
    placement: pin.SE3
    mesh: str = ""
    material: str = ""
    rgba: np.ndarray = field(default_factory=lambda: np.array([0.5, 0.5, 0.5, 1.0]))
    visual: bool = False
    group: int = 0
    mass: float | None = None
    density: float = 1000.0


def geom_props(doc: XmlDoc, el: ET.Element, cls: str, defs: Defaults, comp: Compiler) -> GeomProps:
    """Read a ``<geom>`` element.

    Raises:
        DescriptionError: Malformed numbers or ``fromto``.

    """
    a = defs.attrs(el, cls)
    gtype = a.get("type", "sphere")
    size = vector(doc, el, "size", a.get("size", "0 0 0"), None)
    size = np.concatenate([size, np.zeros(max(0, 3 - size.size))])[:3]
    if "fromto" in a:
        ft = vector(doc, el, "fromto", a["fromto"], 6)
        d = ft[3:] - ft[:3]
        half = float(np.linalg.norm(d)) / 2.0
        if half < 1e-12:
            raise doc.error(el, f"fromto='{a['fromto']}': both ends coincide")
        placement = pin.SE3(_zaxis(doc, el, d), 0.5 * (ft[:3] + ft[3:]))
        if gtype in ("capsule", "cylinder"):
            size = np.array([size[0], half, 0.0])
        elif gtype in ("box", "ellipsoid"):  # MuJoCo: size[0] for both other half-sizes
            size = np.array([size[0], size[0], half])
    else:
        placement = pose(doc, el, a, comp)
    contype = integer(doc, el, "contype", a.get("contype", "1"))[0]
    conaffinity = integer(doc, el, "conaffinity", a.get("conaffinity", "1"))[0]
    mass = _number(doc, el, a, "mass", 0.0) if "mass" in a else None
    density = _number(doc, el, a, "density", 1000.0)
    if (mass is not None and mass < 0.0) or density < 0.0:
        what = f"mass={mass:g}" if mass is not None and mass < 0.0 else f"density={density:g}"
        raise doc.error(el, f"{what} is negative")
    return GeomProps(
        name=a.get("name", ""),
        type=gtype,
        size=size,
        placement=placement,
        mesh=a.get("mesh", ""),
        material=a.get("material", ""),
        rgba=vector(doc, el, "rgba", a["rgba"], 4) if "rgba" in a else np.array([0.5] * 3 + [1.0]),
        visual=contype == 0 and conaffinity == 0,
        group=integer(doc, el, "group", a.get("group", "0"))[0],
        mass=mass,
        density=density,
    )


@dataclass(frozen=True, eq=False)  # numpy fields: no boolean ==
class InertialProps:
    """An ``<inertial>``: mass and rotational inertia at the centre of mass, in the body frame.

    Attributes:
        mass: Mass [kg].
        inertia: Spatial inertia in the body frame.
        repaired: ``(before, after)`` principal-frame tensors (3, 3) when the file's tensor was
            replaced by the nearest valid one (``repair=True``), else ``None``.

    """

    mass: float
    inertia: pin.Inertia
    repaired: tuple[np.ndarray, np.ndarray] | None = None


def inertial_props(
    doc: XmlDoc, el: ET.Element, comp: Compiler, repair: bool = False
) -> InertialProps:
    """Read an ``<inertial>`` element.

    Args:
        doc: The document.
        el: The element.
        comp: Compiler settings.
        repair: Replace a tensor no rigid body has by the nearest valid one
            (:mod:`pkdyn.model.inertia`) instead of refusing it.

    Raises:
        DescriptionError: Missing or negative mass, missing inertia, malformed numbers, an
            invalid tensor (without ``repair``).

    """
    a = dict(el.attrib)
    if "mass" not in a:
        raise doc.error(el, "missing attribute 'mass'")
    mass = float(vector(doc, el, "mass", a["mass"], 1)[0])
    M = pose(doc, el, a, comp)
    if "fullinertia" in a:
        xx, yy, zz, xy, xz, yz = vector(doc, el, "fullinertia", a["fullinertia"], 6)
        I_local = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    elif "diaginertia" in a:
        I_local = np.diag(vector(doc, el, "diaginertia", a["diaginertia"], 3))
    else:
        raise doc.error(el, "needs diaginertia or fullinertia")
    from pkdyn.model.inertia import nearest_valid_inertia
    from pkdyn.model.validate import inertia_problem

    problem = inertia_problem(mass, I_local, point_mass=False)
    repaired = None
    if problem is not None:
        if not repair or mass < 0.0 or not np.all(np.isfinite(I_local)) or not np.any(I_local):
            hint = "" if repair else " (or load with repair_inertias=True)"
            raise doc.error(el, problem + hint)
        fixed = nearest_valid_inertia(I_local)
        repaired, I_local = (I_local, fixed), fixed
    R = M.rotation
    return InertialProps(mass, pin.Inertia(mass, M.translation, R @ I_local @ R.T), repaired)
