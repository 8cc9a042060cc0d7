"""SDFormat import: a model graph with kinematic loops (the Pinocchio wheel has no SDFormat).

One ``<model>`` per file (directly under ``<sdf>`` or in a ``<world>``). What is read:

- links with their ``<pose>`` (``relative_to`` any frame; SDFormat 1.6's ``frame`` attribute;
  ``degrees`` and ``rotation_format="quat_xyzw"`` of 1.9), inertials, visual and collision
  geometry (box, sphere, cylinder, capsule, ellipsoid, mesh; ``model://`` and ``package://``
  URIs are looked up in the file's directory and its ancestors, missing meshes are left out with
  one warning), ``<frame>`` elements (``attached_to``);
- joints ``revolute``, ``continuous``, ``prismatic``, ``ball``, ``universal``, ``fixed`` between
  links or frames, their pose (relative to the child by default), axes (``expressed_in``,
  ``use_parent_model_frame``), limits and dynamics (damping, friction, ``spring_stiffness``
  about ``spring_reference``: ``robot.passive``; a universal joint takes its first axis's);
- ``revolute2`` joints (Gazebo's two-axis hinge: ``<axis>`` fixed in the parent, ``<axis2>``
  carried by the first rotation, not necessarily orthogonal, but not parallel: that is a
  revolute joint, refused naming it) as two revolute joints
  ``<name>_1``, ``<name>_2`` through a massless intermediate body, each axis with its own limits
  and dynamics; as a loop's cut joint, the second axis becomes a hinge closure;
- the model's ``<pose>`` and ``<static>``;
- Drake's ``drake:ball_constraint`` and ``drake:weld_constraint``
  (:mod:`~pkdyn.model.formats.drake`).

The joints form a graph: :func:`pkdyn.model.formats.graph.build` takes a spanning tree and
turns the joints that close loops into closures (ball -> point, revolute -> hinge, fixed ->
weld; a prismatic joint closing a loop trades places with the revolute beside it). A link that
is no joint's child floats: it gets a free-flyer joint (``root_joint`` when there is one such
link, else ``<link>_root_joint``), unless the model is static.

SDFormat has no actuators: name them in a sidecar (``name_mot``). Joint types SDFormat has and
pkdyn does not (``screw``, ``gearbox``), nested models, ``<include>`` and
``drake:joint`` are refused, naming the element and its line.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError
from pkdyn.model.description import FrameRef
from pkdyn.model.formats import drake, unread
from pkdyn.model.formats.graph import WORLD, Body, Geometry, Joint, Mechanism
from pkdyn.model.formats.xmldoc import XmlDoc, parse_xml
from pkdyn.model.inertia import massless_rotor, nearest_valid_inertia, report
from pkdyn.model.validate import inertia_problem, unit_vector
from pkdyn.model.warn import warn, warn_missing_meshes

__all__ = ["read_sdf"]

_REFUSED_JOINTS = {
    "screw": "screw joints",
    "gearbox": "gearbox joints",
}
_INFINITE = 1e15  # SDFormat's "no limit" defaults are +-1e16


@dataclass
class _Frame:
    relative_to: str
    pose: pin.SE3
    attached_to: str  # link, "world", or another frame
    el: ET.Element | None = None


@dataclass
class _Reader:
    doc: XmlDoc
    version: float
    frames: dict[str, _Frame] = field(default_factory=dict)
    world: dict[str, pin.SE3] = field(default_factory=dict)
    links: list[str] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)
    search: list[Path] = field(default_factory=list)
    geometry: bool = True
    repair: bool = False  # repair_inertias
    repaired: list[tuple[str, np.ndarray, np.ndarray]] = field(default_factory=list)
    rotors: list[str] = field(default_factory=list)  # links with inertia and no mass
    dropped: list[str] = field(default_factory=list)  # malformed collision shapes left out


def _text(el: ET.Element | None, default: str = "") -> str:
    return (el.text or "").strip() if el is not None else default


def _numbers(r: _Reader, el: ET.Element, n: int | None = None) -> np.ndarray:
    text = _text(el)
    try:
        v = np.array([float(t) for t in text.split()], dtype=float)
    except ValueError:
        raise r.doc.error(el, f"'{text}': expected numbers") from None
    if (n is not None and v.size != n) or not np.all(np.isfinite(v)):
        raise r.doc.error(el, f"'{text}': expected {n or 'finite'} finite numbers")
    return v


def _number(r: _Reader, parent: ET.Element, tag: str, default: float) -> float:
    el = parent.find(tag)
    return float(_numbers(r, el, 1)[0]) if el is not None and _text(el) else default


def _pose(r: _Reader, el: ET.Element | None, default: str) -> tuple[pin.SE3, str]:
    """Pose element -> (placement, frame it is relative to)."""
    if el is None:
        return pin.SE3.Identity(), default
    rel = el.get("relative_to") or el.get("frame") or default
    v = _numbers(r, el) if _text(el) else np.zeros(6)
    fmt = el.get("rotation_format", "euler_rpy")
    if fmt == "quat_xyzw":
        if v.size != 7:
            raise r.doc.error(el, "a quat_xyzw pose needs 7 numbers")
        u = unit_vector(v[3:])
        if u is None:
            raise r.doc.error(el, "a quat_xyzw pose needs a non-zero quaternion")
        x, y, z, w = u
        R = pin.Quaternion(w, x, y, z).matrix()
    else:
        if v.size != 6:
            raise r.doc.error(el, "a pose needs 6 numbers: x y z roll pitch yaw")
        rpy = np.radians(v[3:]) if el.get("degrees") == "true" else v[3:]
        R = pin.rpy.rpyToMatrix(rpy)
    return pin.SE3(R, v[:3]), rel


def _resolve(r: _Reader, name: str) -> pin.SE3:
    """World pose of a named frame in the reference configuration (iterative, any depth)."""
    chain: list[str] = []
    seen: set[str] = set()
    cur = name
    while cur not in r.world:
        if cur not in r.frames:
            raise DescriptionError(
                r.doc.source, f"frame '{cur}'", "is not a link, joint or frame of this model"
            )
        if cur in seen:
            loop = chain[chain.index(cur) :] + [cur]
            raise DescriptionError(
                r.doc.source,
                f"frame '{cur}'",
                "poses refer to each other in a cycle: "
                + " -> ".join(loop[:8])
                + (" ..." if len(loop) > 8 else ""),
            )
        seen.add(cur)
        chain.append(cur)
        cur = r.frames[cur].relative_to
    out = r.world[cur]
    for f in reversed(chain):
        out = out * r.frames[f].pose
        r.world[f] = out
    return r.world[name]


def _link_of(r: _Reader, name: str) -> str:
    """Link (or ``world``) a frame is attached to (iterative, any depth)."""
    seen: set[str] = set()
    cur = name
    while True:
        if cur == WORLD or cur in r.links:
            return cur
        if cur == "__model__":  # the model frame is attached to the canonical (first) link
            return r.links[0] if r.links else WORLD
        if cur not in r.frames or cur in seen:
            raise DescriptionError(
                r.doc.source, f"frame '{name}'", "is attached to no link of this model"
            )
        seen.add(cur)
        cur = r.frames[cur].attached_to


def _frame_ref(r: _Reader, name: str) -> FrameRef:
    """A named frame as a frame on its link (placement in the link frame)."""
    link = _link_of(r, name)
    M = _resolve(r, link).actInv(_resolve(r, name)) if link != WORLD else _resolve(r, name)
    return FrameRef(link if link != WORLD else "universe", M)


def read_sdf(
    text: str,
    source: str,
    path: Path | None = None,
    geometry: bool = True,
    ignore: frozenset[str] = frozenset(),
    repair_inertias: bool = False,
) -> Mechanism:
    """Read an SDFormat document into a mechanism (see the module docstring).

    Args:
        text: The document.
        source: File or name, for messages.
        path: The file (mesh look-up).
        geometry: Read the visual and collision geometry (mesh files).
        ignore: Element names to leave out (:mod:`~pkdyn.model.formats.unread`).
        repair_inertias: Replace invalid inertia tensors by the nearest valid ones.

    Returns:
        The mechanism; its ``home`` holds the pose the file describes.

    Raises:
        DescriptionError: Malformed or unsupported content, naming the element and its line.

    """
    doc = parse_xml(text, source, path)
    root = doc.root
    if root.tag != "sdf":
        raise doc.error(root, "the root element of an SDFormat file must be <sdf>")
    unread.check(doc, "sdf", ignore)
    unread.prune(doc, ignore)
    try:
        version = float(root.get("version", "1.6"))
    except ValueError:
        raise doc.error(root, f"version='{root.get('version')}' is not a number") from None
    models = [m for m in root if m.tag == "model"]
    for w in (w for w in root if w.tag == "world"):
        models += [m for m in w if m.tag == "model"]
        for inc in (i for i in w if i.tag == "include"):
            raise doc.error(inc, "<include> is not supported: give the model itself")
    for inc in (i for i in root if i.tag == "include"):
        raise doc.error(inc, "<include> is not supported: give the model itself")
    if len(models) != 1:
        raise DescriptionError(
            source, "<model>", f"found {len(models)} models; pkdyn loads one model per file"
        )
    model_el = models[0]
    r = _Reader(doc, version, geometry=geometry, repair=repair_inertias)
    if path is not None:
        p = path.resolve().parent
        for _ in range(7):
            r.search.append(p)
            p = p.parent
    return _model(r, model_el)


def _model(r: _Reader, m: ET.Element) -> Mechanism:
    doc = r.doc
    name = m.get("name", "sdf_model")
    mech = Mechanism(name, doc.source)
    oMm, rel = _pose(r, m.find("pose"), WORLD)
    if rel != WORLD:
        raise doc.error(m.find("pose") or m, "a model pose can only be relative to the world")
    r.world = {WORLD: pin.SE3.Identity(), "__model__": oMm}
    static = _text(m.find("static")).lower() in ("1", "true")
    for child in m:
        if child.tag in ("model", "include"):
            raise doc.error(child, f"nested <{child.tag}> is not supported: flatten the model")
        if child.tag == "drake:joint":
            raise doc.error(child, "drake:joint is not supported; use SDFormat joints")
        if child.tag == "drake:linear_bushing_rpy":
            warn(
                f"{doc.source}: {doc.where(child)}: force elements are not modelled (a bushing "
                "does not close a loop in pkdyn; use drake:ball_constraint)"
            )
    links = [e for e in m if e.tag == "link"]
    joints = [e for e in m if e.tag == "joint"]
    r.links = [e.get("name", "") for e in links]
    seen: set[str] = set()
    for el in links + joints + [e for e in m if e.tag == "frame"]:
        n = el.get("name", "")
        if not n:
            raise doc.error(el, "missing attribute 'name'")
        if n in seen or n in (WORLD, "__model__"):
            raise doc.error(el, f"duplicate frame name '{n}'")
        seen.add(n)
    default_rel = "__model__"
    for el in links:
        M, rel = _pose(r, el.find("pose"), default_rel)
        r.frames[el.get("name", "")] = _Frame(rel, M, el.get("name", ""), el)
        for fel in (e for e in el if e.tag == "frame"):  # SDFormat 1.5 link frames
            FM, frel = _pose(r, fel.find("pose"), el.get("name", ""))
            r.frames[fel.get("name", "")] = _Frame(frel, FM, el.get("name", ""), fel)
    for el in joints:
        child_name = _text(el.find("child"))
        M, rel = _pose(r, el.find("pose"), child_name)
        r.frames[el.get("name", "")] = _Frame(rel, M, child_name, el)
    for el in (e for e in m if e.tag == "frame"):
        att = el.get("attached_to", "__model__")
        M, rel = _pose(r, el.find("pose"), att)
        r.frames[el.get("name", "")] = _Frame(rel, M, att, el)
    for el in links:
        mech.add_body(_link(r, el), doc.where(el))
    children = set()
    for el in joints:
        for j in _joint(r, el, mech):
            mech.joints.append(j)
            children.add(j.child)
    roots = [b for b in mech.bodies if b not in children]
    for b in roots:
        if static:
            mech.joints.append(Joint(f"{b}_static", "fixed", WORLD, b, mech.bodies[b].pose))
            continue
        jname = "root_joint" if len(roots) == 1 else f"{b}_root_joint"
        pose = mech.bodies[b].pose
        mech.joints.append(Joint(jname, "free", WORLD, b, pose, q_ref=pin.SE3ToXYZQUAT(pose)))
    counts = {"ball_constraint": 0, "weld_constraint": 0}
    for el in m:
        if el.tag in ("drake:ball_constraint", "drake:weld_constraint"):
            kind = el.tag.split(":")[1]
            counts[kind] += 1

            def frames(fname: str, fel: ET.Element) -> FrameRef:
                try:
                    return _frame_ref(r, fname)
                except DescriptionError:
                    raise doc.error(fel, f"'{fname}' is not a frame of this model") from None

            c = drake.closure(el, counts[kind], doc.source, doc.where(el), _text, frames)
            for ref in (c.frame1, c.frame2):
                if ref.link not in mech.bodies and ref.link != "universe":
                    raise doc.error(el, f"names body '{ref.link}', which is not a link")
            mech.closures.append(c)
    if r.missing:
        mech.missing_meshes = sorted(set(r.missing))
        warn_missing_meshes(doc.source, mech.missing_meshes)
    report(doc.source, [], r.repaired, r.rotors)
    mech.dropped_collisions = list(r.dropped)
    return mech


def _link(r: _Reader, el: ET.Element) -> Body:
    name = el.get("name", "")
    oMl = _resolve(r, name)
    body = Body(name, oMl)
    inertial = el.find("inertial")
    if inertial is not None:
        body.inertia = _inertia(r, inertial, name)
    if r.geometry:
        for tag, out in (("visual", body.visuals), ("collision", body.collisions)):
            for k, g in enumerate(e for e in el if e.tag == tag):
                try:
                    geom = _geometry(r, g, name, oMl, f"{name}_{tag}_{k}")
                except DescriptionError as err:  # a typo costs the shape, not the robot
                    what = f"link '{name}' {r.doc.where(g)}"
                    warn(f"{err}; this {tag} shape is left out")
                    if tag == "collision":
                        r.dropped.append(what)
                    continue
                if geom is not None:
                    out.append(geom)
    return body


def _inertia(r: _Reader, el: ET.Element, link: str) -> pin.Inertia:
    mass = _number(r, el, "mass", 1.0)
    M, rel = _pose(r, el.find("pose"), link)
    if rel != link:
        M = _resolve(r, link).actInv(_resolve(r, rel) * M)
    I = np.zeros((3, 3))
    ie = el.find("inertia")
    if ie is not None:
        xx, yy, zz = (_number(r, ie, k, 0.0) for k in ("ixx", "iyy", "izz"))
        xy, xz, yz = (_number(r, ie, k, 0.0) for k in ("ixy", "ixz", "iyz"))
        I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    problem = inertia_problem(mass, I)  # the rule of every importer (point masses kept)
    if problem is not None:
        if not r.repair or mass < 0.0 or not np.all(np.isfinite(I)):
            hint = "" if r.repair else " (or load with repair_inertias=True)"
            raise r.doc.error(el, f"link '{link}': {problem}{hint}")
        fixed = nearest_valid_inertia(I)
        r.repaired.append((link, I, fixed))
        I = fixed
    elif massless_rotor(mass, I):
        r.rotors.append(link)
    R = M.rotation
    return pin.Inertia(mass, M.translation, R @ I @ R.T)


def _uri(r: _Reader, uri: str) -> str:
    for prefix in ("model://", "package://", "file://"):
        if uri.startswith(prefix):
            rest = uri[len(prefix) :]
            if prefix == "file://" and os.path.isabs(rest):
                return rest
            for d in r.search:
                if (d / rest).is_file():
                    return str(d / rest)
            return rest
    if os.path.isabs(uri):
        return uri
    return str(r.search[0] / uri) if r.search else uri


def _geometry(r: _Reader, el: ET.Element, link: str, oMl: pin.SE3, default: str) -> Geometry | None:
    import coal

    doc = r.doc
    M, rel = _pose(r, el.find("pose"), link)
    if rel != link:
        M = oMl.actInv(_resolve(r, rel) * M)
    g = el.find("geometry")
    if g is None or len(g) == 0:
        raise doc.error(el, "missing <geometry>")
    shape_el = g[0]
    kind = shape_el.tag
    rgba = np.array([0.7, 0.7, 0.7, 1.0])
    mat = el.find("material")
    if mat is not None:
        for key in ("diffuse", "ambient"):
            c = mat.find(key)
            if c is not None and _text(c):
                v = _numbers(r, c)
                if v.size not in (3, 4):
                    raise doc.error(c, f"'{_text(c)}': a colour is 3 or 4 numbers (r g b [a])")
                rgba = np.concatenate([v[:3], v[3:4] if v.size > 3 else [1.0]])
                break
    name = el.get("name") or default

    def positive(tag: str, default_value: str) -> np.ndarray:
        sub = shape_el.find(tag)
        n = len(default_value.split())
        v = (
            _numbers(r, sub, n)
            if sub is not None
            else np.array([float(x) for x in default_value.split()])
        )
        if np.any(v <= 0.0):
            raise doc.error(sub if sub is not None else shape_el, f"{kind} {tag} must be positive")
        return v

    shape: Any
    mesh_path, scale = "", np.ones(3)
    if kind == "box":
        s = positive("size", "1 1 1")
        shape = coal.Box(*s)
    elif kind == "sphere":
        shape = coal.Sphere(float(positive("radius", "1")[0]))
    elif kind == "cylinder":
        shape = coal.Cylinder(float(positive("radius", "1")[0]), float(positive("length", "1")[0]))
    elif kind == "capsule":
        shape = coal.Capsule(float(positive("radius", "0.5")[0]), float(positive("length", "1")[0]))
    elif kind == "ellipsoid":
        shape = coal.Ellipsoid(*positive("radii", "1 1 1"))
    elif kind == "mesh":
        uri = _text(shape_el.find("uri"))
        sc = shape_el.find("scale")
        scale = _numbers(r, sc, 3) if sc is not None else np.ones(3)
        mesh_path = _uri(r, uri)
        if not os.path.isfile(mesh_path):
            r.missing.append(uri)
            return None
        try:
            shape = coal.MeshLoader().load(mesh_path, scale)
        except (RuntimeError, ValueError) as err:
            raise doc.error(el, f"mesh '{mesh_path}' cannot be read ({err})") from None
    elif kind in ("plane", "heightmap", "empty", "polyline"):
        return None
    else:
        raise doc.error(shape_el, f"geometry <{kind}> is not supported")
    return Geometry(name, shape, M, mesh_path, scale, rgba)


def _axis(r: _Reader, el: ET.Element | None, oMj: pin.SE3) -> np.ndarray | None:
    """Unit axis in the joint frame."""
    if el is None:
        return None
    xyz = el.find("xyz")
    v = _numbers(r, xyz, 3) if xyz is not None else np.array([0.0, 0.0, 1.0])
    u = unit_vector(v)
    if u is None or float(np.abs(v).max()) < 1e-12:
        raise r.doc.error(xyz if xyz is not None else el, "zero joint axis")
    v = u
    expressed = xyz.get("expressed_in") if xyz is not None else None
    if expressed is None and (
        _text(el.find("use_parent_model_frame")).lower() in ("1", "true") or r.version < 1.5
    ):
        expressed = "__model__"
    if expressed:
        R = _resolve(r, expressed).rotation
        v = oMj.rotation.T @ (R @ v)
    return v


def _joint(r: _Reader, el: ET.Element, mech: Mechanism) -> list[Joint]:
    doc = r.doc
    name = el.get("name", "")
    jtype = el.get("type", "")
    where = doc.where(el)
    if jtype in _REFUSED_JOINTS:
        raise doc.error(el, f"{_REFUSED_JOINTS[jtype]} are not supported by pkdyn")
    kinds = {
        "revolute2": "revolute2",
        "revolute": "revolute",
        "continuous": "revolute",
        "prismatic": "prismatic",
        "ball": "ball",
        "universal": "universal",
        "fixed": "fixed",
    }
    if jtype not in kinds:
        raise doc.error(el, f"unknown joint type '{jtype}'")
    parent_name, child_name = _text(el.find("parent")), _text(el.find("child"))
    if not parent_name or not child_name:
        raise doc.error(el, "needs <parent> and <child>")
    for n in (parent_name, child_name):
        if n not in (WORLD, "__model__") and n not in r.frames:
            raise doc.error(el, f"names '{n}', which is not a link or frame of this model")
    try:
        parent = _link_of(r, parent_name) if parent_name != "__model__" else r.links[0]
        child = _link_of(r, child_name)
    except DescriptionError as err:
        raise doc.error(el, str(err).split(": ", 1)[-1]) from None
    if child == WORLD:
        raise doc.error(el, "the world cannot be a joint's child")
    oMj = _resolve(r, name)
    kind = kinds[jtype]
    if kind == "revolute2":
        return _revolute2(r, el, mech, parent, child, oMj)
    axis_el = el.find("axis")
    axis = _axis(r, axis_el, oMj)
    if kind in ("revolute", "prismatic", "universal") and axis is None:
        axis = np.array([0.0, 0.0, 1.0])
    axis2 = _axis(r, el.find("axis2"), oMj) if kind == "universal" else None
    if kind == "universal" and axis2 is None:
        raise doc.error(el, "a universal joint needs <axis2>")
    props = _axis_props(r, axis_el, jtype == "continuous")
    if kind not in ("revolute", "prismatic"):
        props["spring_ref"] = None
    return [
        Joint(
            name,
            kind,
            parent,
            child,
            oMj,
            axis=axis if axis is not None else np.array([0.0, 0.0, 1.0]),
            axis2=axis2,
            where=where,
            **props,
        )
    ]


def _axis_props(r: _Reader, axis_el: ET.Element | None, continuous: bool) -> dict[str, Any]:
    """Limits and dynamics of one ``<axis>`` (or ``<axis2>``) as :class:`Joint` fields."""
    lo, hi, effort, velocity, damping, friction = -math.inf, math.inf, math.inf, math.inf, 0.0, 0.0
    stiffness, spring_ref = 0.0, 0.0
    if axis_el is not None:
        lim = axis_el.find("limit")
        if lim is not None and not continuous:
            lo = _number(r, lim, "lower", -math.inf)
            hi = _number(r, lim, "upper", math.inf)
            lo = -math.inf if lo <= -_INFINITE else lo
            hi = math.inf if hi >= _INFINITE else hi
            if lo > hi:
                raise r.doc.error(lim, f"lower limit {lo} above upper limit {hi}")
        if lim is not None:
            effort = _number(r, lim, "effort", -1.0)
            velocity = _number(r, lim, "velocity", -1.0)
            effort = math.inf if effort < 0 else effort
            velocity = math.inf if velocity < 0 else velocity
        dyn = axis_el.find("dynamics")
        if dyn is not None:
            damping = _number(r, dyn, "damping", 0.0)
            friction = _number(r, dyn, "friction", 0.0)
            stiffness = _number(r, dyn, "spring_stiffness", 0.0)
            spring_ref = _number(r, dyn, "spring_reference", 0.0)
    return {
        "lower": lo,
        "upper": hi,
        "effort": effort,
        "velocity": velocity,
        "damping": damping,
        "friction": friction,
        "stiffness": stiffness,
        "spring_ref": np.array([spring_ref]),
    }


def _revolute2(
    r: _Reader, el: ET.Element, mech: Mechanism, parent: str, child: str, oMj: pin.SE3
) -> list[Joint]:
    """A ``revolute2`` joint as two revolute joints through a massless intermediate body.

    The first turns about ``<axis>`` (fixed in the parent), the second about ``<axis2>``, carried
    by the first rotation (as Gazebo's two-axis hinge: the axes need not be orthogonal); each
    has its own limits and dynamics. Named ``<name>_1`` and ``<name>_2``; when the joint closes
    a loop, the second becomes a hinge closure.
    """
    name = el.get("name", "")
    where = r.doc.where(el)
    z = np.array([0.0, 0.0, 1.0])
    a1 = _axis(r, el.find("axis"), oMj)
    a2 = _axis(r, el.find("axis2"), oMj)
    if a2 is None:
        raise r.doc.error(el, "a revolute2 joint needs <axis2>")
    if float(np.linalg.norm(np.cross(a1 if a1 is not None else z, a2))) < 1e-9:
        raise r.doc.error(
            el,
            "the two axes of this revolute2 joint are parallel: it turns about one axis (one "
            "degree of freedom, not two); make it a revolute joint, or give axis2 another "
            "direction",
        )
    mid = f"{name}#1"
    mech.add_body(Body(mid, oMj, virtual=True), where)
    out = []
    for k, (axis, a_el, p, c) in enumerate(
        (
            (a1 if a1 is not None else z, el.find("axis"), parent, mid),
            (a2, el.find("axis2"), mid, child),
        )
    ):
        out.append(
            Joint(
                f"{name}_{k + 1}",
                "revolute",
                p,
                c,
                oMj,
                axis=axis,
                where=where,
                **_axis_props(r, a_el, False),
            )
        )
    return out
