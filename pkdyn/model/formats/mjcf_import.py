"""MJCF import: a MuJoCo model with its equality constraints as a closed-loop robot.

What is read (attributes with their default classes, see :mod:`~pkdyn.model.formats.mjcf_spec`):

- the body tree under ``<worldbody>`` (every top-level body: several grounded branches and
  free bodies), ``<frame>`` elements, ``<include>`` files; joints ``hinge``, ``slide``,
  ``ball``, ``free`` (several joints in one body are chained as MuJoCo applies them), their
  ``ref`` (``qpos0``): pkdyn's coordinates are MuJoCo's ``qpos`` (quaternions reordered to
  Pinocchio's ``x y z w``), so ranges, keyframes and actuator positions carry over;
- the joints' passive elements, on every joint type: ``damping``, ``frictionloss`` (pkdyn's
  smooth Coulomb friction), ``armature`` (``model.armature``), ``stiffness`` about ``springref``
  (hinge, slide: in ``qpos`` units, so ``ref`` needs no correction; ball and free joints: their
  spring rests at ``qpos0``, as in MuJoCo) -> ``robot.passive`` (Pinocchio's own MJCF parser
  keeps the armature only); a free joint's spring follows Pinocchio's SE(3) difference, not
  MuJoCo's separate translation and rotation;
- inertias from ``<inertial>``, or from the geoms when it is absent (``inertiafromgeom``),
  with MuJoCo's formulas for primitive shapes (mesh volumes from the mesh file, exact);
- geoms: primitives and meshes (``contype = conaffinity = 0`` ones are visual, the others
  collision); a mesh file that cannot be found is left out with one warning naming the files;
- ``<equality>``: ``connect`` -> ``point`` closure (a pair ``N``, ``N/axis`` on the same two
  bodies, as pkdyn exports a hinge, -> the ``hinge`` closure ``N``), ``weld`` -> ``weld``
  closure, by bodies (the second anchor / relative pose taken at ``qpos0``, as MuJoCo does)
  or by sites; named after the equality (unnamed ones ``connect1``, ``weld2``...).
  ``joint`` -> a joint coupling (:class:`~pkdyn.model.description.CouplingSpec`:
  ``joint1 - qpos0 = polycoef(joint2 - qpos0)``, up to 5 coefficients, on hinge and slide
  joints; ``joint1`` alone is locked at ``qpos0 + polycoef[0]``). ``tendon``, ``distance``
  and ``flex`` equalities are refused with a message naming them;
- ``<actuator>`` on joints: ``gear`` -> reduction, joint-side effort limit from ``forcerange``
  x gear (motors and proportional ``general`` actuators also from ``ctrlrange`` x gain x gear);
  actuators on tendons, sites or bodies are left out with a warning;
- ``<keyframe>``: the key named ``home`` gives the home configuration (else ``qpos0``);
  ``<option gravity>``.

Elements that change the mechanism and that pkdyn cannot represent (``composite``,
``flexcomp``, ``replicate``, ``attach``, body plugins) are refused naming the element and its
line.
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
from pkdyn.model.description import (
    ActuatorSpec,
    ClosureSpec,
    CouplingSpec,
    FrameRef,
    LinearCouplingSpec,
)
from pkdyn.model.formats import mjcf_spec as spec
from pkdyn.model.formats import unread
from pkdyn.model.formats.graph import WORLD, Body, Geometry, Joint, Mechanism
from pkdyn.model.formats.xmldoc import XmlDoc, parse_xml, read_text
from pkdyn.model.inertia import report
from pkdyn.model.validate import unit_vector
from pkdyn.model.warn import warn, warn_missing_meshes

__all__ = ["MAX_BODIES", "MAX_DEPTH", "MAX_INCLUDES", "MAX_INCLUDE_DEPTH", "read_mjcf"]

_REFUSED_IN_BODY = ("composite", "flexcomp", "replicate", "attach", "plugin")
_IGNORED_IN_BODY = ("camera", "light")
MAX_INCLUDE_DEPTH = 8
"""Deepest nesting of ``<include>`` files."""

MAX_INCLUDES = 100
"""Most ``<include>`` elements one model may expand, in all."""

MAX_DEPTH = 200
"""Deepest nesting of ``<body>`` and ``<frame>`` elements (real robots: about 20)."""

MAX_BODIES = 10_000
"""Most bodies in one model (a humanoid has about 30; MuJoCo scenes of many robots, hundreds)."""


@dataclass
class _Reader:
    doc: XmlDoc
    comp: spec.Compiler
    defs: spec.Defaults
    mech: Mechanism
    meshes: dict[str, tuple[str, np.ndarray]] = field(default_factory=dict)
    materials: dict[str, np.ndarray] = field(default_factory=dict)
    missing: list[str] = field(default_factory=list)
    lost_inertia: list[str] = field(default_factory=list)  # bodies whose mesh mass is missing
    mj_joints: list[tuple[str, str]] = field(default_factory=list)  # (name, type), qpos order
    joint_types: dict[str, str] = field(default_factory=dict)
    joint_refs: dict[str, float] = field(default_factory=dict)
    sites: dict[str, tuple[str, pin.SE3]] = field(default_factory=dict)
    geometry: bool = True
    repair: bool = False  # repair_inertias
    repaired: list[tuple[str, np.ndarray, np.ndarray]] = field(default_factory=list)
    rotors: list[str] = field(default_factory=list)  # bodies with inertia and no mass
    mass_from_geoms: dict[str, bool] = field(default_factory=dict)  # inertiafromgeom, by body
    tendons: dict[str, list[tuple[str, float]]] = field(default_factory=dict)  # fixed tendons


def _includes(doc: XmlDoc, root: ET.Element, base: Path | None) -> None:
    """Replace ``<include file>`` elements by the children of the included documents.

    Iterative (any nesting of elements), with the nesting of includes capped at
    :data:`MAX_INCLUDE_DEPTH` levels and their number at :data:`MAX_INCLUDES` (a tree of files
    each including the next ten times would otherwise multiply), and the included text at
    :data:`~pkdyn.model.formats.xmldoc.MAX_FILE_BYTES` in all.
    """
    from pkdyn.model.formats.xmldoc import MAX_FILE_BYTES

    origin: dict[int, tuple[Path | None, int]] = {}  # included elements: their file, depth
    count, size = 0, 0
    stack: list[tuple[ET.Element, Path | None, int]] = [(root, base, 0)]
    while stack:
        el, b, depth = stack.pop()
        i = 0
        while i < len(el):
            child = el[i]
            cb, cd = origin.get(id(child), (b, depth))
            if child.tag != "include":
                stack.append((child, cb, cd))
                i += 1
                continue
            if cd >= MAX_INCLUDE_DEPTH:
                raise doc.error(child, f"includes nested deeper than {MAX_INCLUDE_DEPTH} levels")
            count += 1
            if count > MAX_INCLUDES:
                raise doc.error(
                    child, f"more than {MAX_INCLUDES} <include> elements in one model (in all)"
                )
            name = child.get("file")
            if not name:
                raise doc.error(child, "missing attribute 'file'")
            path = (cb / name) if cb is not None and not os.path.isabs(name) else Path(name)
            if not path.is_file():
                raise doc.error(child, f"included file '{path}' does not exist")
            text = read_text(path, "included file")
            size += len(text)
            if size > MAX_FILE_BYTES:
                raise doc.error(
                    child, f"the included files exceed {MAX_FILE_BYTES // 2**20} MiB in all"
                )
            sub = parse_xml(text, str(path), path)
            if sub.root.tag != "mujoco":
                raise doc.error(child, f"included file '{path}' is not an MJCF document")
            doc.merge(sub)
            el.remove(child)
            for k, grandchild in enumerate(list(sub.root)):
                el.insert(i + k, grandchild)
                origin[id(grandchild)] = (path.parent, cd + 1)


def _check_size(doc: XmlDoc, root: ET.Element) -> None:
    """Bounded work: the number of bodies, the nesting depth and Pinocchio's data, up front."""
    from pkdyn.model.validate import check_data_size

    bodies = nv = 0
    dofs = {"hinge": 1, "slide": 1, "ball": 3, "free": 6}
    stack: list[tuple[ET.Element, int]] = [(w, 0) for w in root if w.tag == "worldbody"]
    while stack:
        el, depth = stack.pop()
        for child in el:
            if child.tag in ("body", "frame"):
                if depth + 1 > MAX_DEPTH:
                    raise doc.error(
                        child,
                        f"bodies and frames nested deeper than {MAX_DEPTH} levels (real robots "
                        "nest about 20)",
                    )
                bodies += child.tag == "body"
                if bodies > MAX_BODIES:
                    raise doc.error(
                        child,
                        f"more than {MAX_BODIES} bodies: pkdyn reads models of at most "
                        f"{MAX_BODIES} bodies",
                    )
                stack.append((child, depth + 1))
            elif child.tag == "freejoint":
                nv += 6
            elif child.tag == "joint":
                nv += dofs.get(child.get("type", "hinge"), 1)
    check_data_size(doc.source, nv, bodies)


def _sections(root: ET.Element, tag: str) -> list[ET.Element]:
    return [el for el in root if el.tag == tag]


def read_mjcf(
    text: str,
    source: str,
    path: Path | None = None,
    geometry: bool = True,
    ignore: frozenset[str] = frozenset(),
    repair_inertias: bool = False,
) -> Mechanism:
    """Read an MJCF document into a mechanism (see the module docstring).

    Args:
        text: The MJCF document.
        source: File or name, for messages.
        path: The file, for includes and mesh paths relative to it.
        geometry: Read the geometry (mesh files); without it, only inertias use the geoms.
        ignore: Element names to leave out (:mod:`~pkdyn.model.formats.unread`).
        repair_inertias: Replace invalid ``<inertial>`` tensors by the nearest valid ones.

    Returns:
        The mechanism: bodies, joints, closures, actuators, ``home`` configurations
        (``qpos0`` and the ``home`` keyframe when present).

    Raises:
        DescriptionError: Malformed or unsupported content, naming the element and its line.

    """
    doc = parse_xml(text, source, path)
    root = doc.root
    if root.tag != "mujoco":
        raise doc.error(root, "the root element of an MJCF file must be <mujoco>")
    base = path.parent if path is not None else None
    _includes(doc, root, base)
    _check_size(doc, root)
    unread.check(doc, "mjcf", ignore)
    unread.prune(doc, ignore)
    comp = spec.Compiler.read(doc, _sections(root, "compiler"))
    defs = spec.Defaults(doc, _sections(root, "default"))
    mech = Mechanism(root.get("model", "mujoco"), source)
    r = _Reader(doc, comp, defs, mech, geometry=geometry, repair=repair_inertias)
    for opt in _sections(root, "option"):
        if "gravity" in opt.attrib:
            mech.gravity = spec.vector(doc, opt, "gravity", opt.attrib["gravity"], 3)
    meshdir = (base or Path(".")) / comp.meshdir
    for asset in _sections(root, "asset"):
        _assets(r, asset, meshdir)
    worlds = _sections(root, "worldbody")
    mech.add_body(Body("worldbody", pin.SE3.Identity()))  # world geoms and sites
    for wb in worlds:
        _children(r, wb, WORLD, "worldbody", pin.SE3.Identity(), pin.SE3.Identity(), "main")
    if not mech.bodies["worldbody"].visuals + mech.bodies["worldbody"].collisions and not (
        mech.bodies["worldbody"].frames
    ):
        del mech.bodies["worldbody"]
    for tendon in _sections(root, "tendon"):
        _fixed_tendons(r, tendon)
    for eq in _sections(root, "equality"):
        _equalities(r, eq)
    for act in _sections(root, "actuator"):
        _actuators(r, act)
    mech.home["qpos0"] = {}
    for keys in _sections(root, "keyframe"):
        for key in keys:
            if key.tag == "key" and key.get("name") == "home" and "qpos" in key.attrib:
                mech.home["home"] = _keyframe(r, key)
    if r.missing:
        mech.missing_meshes = sorted(set(r.missing))
        warn_missing_meshes(source, mech.missing_meshes, r.lost_inertia)
    report(source, [], r.repaired, r.rotors, "body")
    return mech


# ---------------------------------------------------------------------------------- assets


def _assets(r: _Reader, asset: ET.Element, meshdir: Path) -> None:
    doc = r.doc
    for el in asset:
        if el.tag == "mesh":
            a = r.defs.attrs(el, "main")
            file = a.get("file", "")
            name = a.get("name") or Path(file).stem
            if not name:
                raise doc.error(el, "a mesh needs a name or a file")
            scale = spec.vector(doc, el, "scale", a.get("scale", "1 1 1"), 3)
            path = file if not file or os.path.isabs(file) else str(meshdir / file)
            r.meshes[name] = (path, scale)
        elif el.tag == "material" and el.get("name"):
            a = r.defs.attrs(el, "main")
            if "rgba" in a:
                r.materials[el.get("name", "")] = spec.vector(doc, el, "rgba", a["rgba"], 4)


# ---------------------------------------------------------------------------------- bodies


def _children(
    r: _Reader,
    el: ET.Element,
    parent: str,
    owner: str,
    oMf: pin.SE3,
    bMf: pin.SE3,
    cls: str,
) -> None:
    """Bodies, geoms, sites and frames under ``el`` (a body, the world body or a frame).

    Args:
        r: Reader state.
        el: The element.
        parent: Body that child bodies hang on (``world`` for the world body).
        owner: Body that geoms and sites attach to.
        oMf: World pose of ``el``'s frame (reference configuration).
        bMf: Pose of ``el``'s frame in ``owner``'s frame.
        cls: Default class for the children.

    """
    doc = r.doc
    for child in el:
        tag = child.tag
        if tag == "body":
            _body(r, child, parent, oMf, cls)
        elif tag == "frame":
            a = r.defs.attrs(child, cls) if "class" in child.attrib else dict(child.attrib)
            M = spec.pose(doc, child, a, r.comp)
            sub = child.get("childclass", cls)
            r.defs.check(child, sub)
            _children(r, child, parent, owner, oMf * M, bMf * M, sub)
        elif tag == "geom":
            _geom(r, child, owner, bMf, cls)
        elif tag == "site":
            a = r.defs.attrs(child, cls)
            if a.get("name"):
                M = spec.pose(doc, child, a, r.comp)
                r.mech.bodies[owner].frames.append((a["name"], bMf * M))
                r.sites[a["name"]] = (owner, bMf * M)
        elif tag in ("joint", "freejoint"):
            if el.tag == "body":
                continue  # read by _body
            if el.tag == "worldbody":
                raise doc.error(child, "the world body cannot have joints")
            raise doc.error(child, "a joint must be a direct child of its <body>")
        elif tag in _REFUSED_IN_BODY:
            raise doc.error(child, f"<{tag}> is not supported by pkdyn's MJCF import")
        elif tag in _IGNORED_IN_BODY or tag == "inertial":
            continue
        else:
            raise doc.error(child, f"unknown element <{tag}> in a body")


def _body(r: _Reader, el: ET.Element, parent: str, oMp: pin.SE3, cls: str) -> None:
    doc, mech = r.doc, r.mech
    a = r.defs.attrs(el, cls) if "class" in el.attrib else dict(el.attrib)
    name = el.get("name") or f"body{len(mech.bodies) + 1}"
    oMb = oMp * spec.pose(doc, el, a, r.comp)
    sub = el.get("childclass", cls)
    r.defs.check(el, sub)
    joints = [c for c in el if c.tag in ("joint", "freejoint")]
    props = [spec.joint_props(doc, j, sub, r.defs, r.comp) for j in joints]
    if any(p.type == "free" for p in props) and (len(props) > 1 or parent != WORLD):
        bad = joints[[p.type for p in props].index("free")]
        raise doc.error(bad, "a free joint must be the only joint of a top-level body")
    prev = parent
    for k, (jel, p) in enumerate(zip(joints, props, strict=True)):
        last = k == len(props) - 1
        child = name if last else f"{name}#{k + 1}"
        jname = p.name or (f"{name}_joint" if len(props) == 1 else f"{name}_joint{k + 1}")
        if jname in r.joint_types:
            raise doc.error(jel, f"duplicate joint name '{jname}'")
        if not last:
            mech.add_body(Body(child, oMb, virtual=True), doc.where(el, name))
        r.mj_joints.append((jname, p.type))
        r.joint_types[jname] = p.type
        r.joint_refs[jname] = float(p.ref) if p.type in ("hinge", "slide") else 0.0
        mech.joints.append(_joint(r, jel, p, jname, prev, child, oMb))
        prev = child
    if not props:  # a body without joints is welded to its parent
        mech.joints.append(
            Joint(f"{name}_fixed", "fixed", parent, name, oMb, where=doc.where(el, name))
        )
    body = mech.add_body(Body(name, oMb), doc.where(el, name))
    inertial = [c for c in el if c.tag == "inertial"]
    if len(inertial) > 1:
        raise doc.error(inertial[1], "a body has at most one <inertial>")
    use_geoms = r.comp.inertiafromgeom == "true" or (
        r.comp.inertiafromgeom == "auto" and not inertial
    )
    r.mass_from_geoms[name] = use_geoms
    _children(r, el, name, name, oMb, pin.SE3.Identity(), sub)
    if use_geoms:
        body.inertia = _geom_inertia(r, el, sub)
        I = body.inertia
        if not (math.isfinite(I.mass) and np.all(np.isfinite(I.inertia))):
            raise doc.error(el, "the inertia inferred from the geoms is not finite", name)
    elif inertial:
        iprops = spec.inertial_props(doc, inertial[0], r.comp, r.repair)
        body.inertia = iprops.inertia
        if iprops.repaired is not None:
            r.repaired.append((name, *iprops.repaired))
        elif iprops.mass == 0.0 and np.any(iprops.inertia.inertia):
            r.rotors.append(name)


def _joint(
    r: _Reader,
    el: ET.Element,
    p: spec.JointProps,
    name: str,
    parent: str,
    child: str,
    oMb: pin.SE3,
) -> Joint:
    where = r.doc.where(el, name)
    if p.type == "free":
        q0 = pin.SE3ToXYZQUAT(oMb)
        if el.tag == "freejoint":  # takes no defaults and no passive attributes in MuJoCo
            return Joint(name, "free", parent, child, oMb, q_ref=q0, where=where)
        return Joint(
            name,
            "free",
            parent,
            child,
            oMb,
            q_ref=q0,
            damping=p.damping,
            friction=p.frictionloss,
            armature=p.armature,
            stiffness=p.stiffness,
            spring_ref=q0,  # MuJoCo: a free joint's spring rests at qpos0
            where=where,
        )
    oMj = oMb * pin.SE3(np.eye(3), p.pos)
    kind = {"hinge": "revolute", "slide": "prismatic", "ball": "ball"}[p.type]
    lo, hi = (-math.inf, math.inf) if p.range is None or p.type == "ball" else p.range
    return Joint(
        name,
        kind,
        parent,
        child,
        oMj,
        axis=p.axis,
        q_ref=np.array([p.ref]) if kind != "ball" else None,
        lower=lo,
        upper=hi,
        damping=p.damping,
        friction=p.frictionloss,
        armature=p.armature,
        stiffness=p.stiffness,
        # hinge / slide: springref (qpos units, as pkdyn's q); ball: the identity (qpos0)
        spring_ref=np.array([p.springref]) if kind != "ball" else None,
        where=where,
    )


def _shape(r: _Reader, el: ET.Element, g: spec.GeomProps) -> tuple[Any, str, np.ndarray] | None:
    """Coal shape, mesh path and scale of a geom (``None``: nothing to draw or collide)."""
    import coal

    s = g.size
    if g.type in ("plane", "hfield", "sdf"):
        return None
    if g.type == "mesh":
        if g.mesh not in r.meshes:
            raise r.doc.error(el, f"mesh '{g.mesh}' is not an asset of this model")
        path, scale = r.meshes[g.mesh]
        if not path or not os.path.isfile(path):
            r.missing.append(path or g.mesh)
            return None
        try:
            return coal.MeshLoader().load(path, scale), path, scale
        except (RuntimeError, ValueError) as err:
            raise r.doc.error(el, f"mesh file '{path}' cannot be read ({err})") from None
    need = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3}
    if g.type not in need:
        raise r.doc.error(el, f"geom type '{g.type}' is not an MJCF geom type")
    if np.any(s[: need[g.type]] <= 0.0):
        raise r.doc.error(el, f"{g.type} size {s[: need[g.type]].tolist()} must be positive")
    ones = np.ones(3)
    if g.type == "sphere":
        return coal.Sphere(s[0]), "", ones
    if g.type == "capsule":
        return coal.Capsule(s[0], 2.0 * s[1]), "", ones
    if g.type == "cylinder":
        return coal.Cylinder(s[0], 2.0 * s[1]), "", ones
    if g.type == "box":
        return coal.Box(2.0 * s[0], 2.0 * s[1], 2.0 * s[2]), "", ones
    return coal.Ellipsoid(s[0], s[1], s[2]), "", ones


def _geom(r: _Reader, el: ET.Element, owner: str, bMf: pin.SE3, cls: str) -> None:
    """A geom of body ``owner``.

    A malformed one is left out with a warning when its body's inertia does not come from its
    geoms (else it is an error, as in MuJoCo).
    """
    try:
        g = spec.geom_props(r.doc, el, cls, r.defs, r.comp)
        if not r.geometry:
            return
        shape = _shape(r, el, g)
    except DescriptionError as err:
        if r.mass_from_geoms.get(owner, False):
            raise
        attrs = {**r.defs.classes.get(cls, {}).get("geom", {}), **el.attrib}
        visual = attrs.get("contype", "1").strip() == attrs.get("conaffinity", "1").strip() == "0"
        kind = "visual" if visual else "collision"
        warn(f"{err}; this {kind} geom is left out (its body's inertia does not come from it)")
        if not visual:
            r.mech.dropped_collisions.append(f"body '{owner}' {r.doc.where(el)}")
        return
    if shape is None:
        return
    body = r.mech.bodies[owner]
    k = len(body.visuals) + len(body.collisions)
    name = g.name or f"{owner}_{k}"
    rgba = g.rgba if "rgba" in r.defs.attrs(el, cls) else r.materials.get(g.material, g.rgba)
    geom = Geometry(name, shape[0], bMf * g.placement, shape[1], shape[2], rgba)
    (body.visuals if g.visual else body.collisions).append(geom)


def _geom_inertia(r: _Reader, el: ET.Element, cls: str) -> pin.Inertia:
    """Body inertia from its geoms (MuJoCo's volume formulas; meshes from their file)."""
    total = pin.Inertia.Zero()
    lo, hi = r.comp.inertiagrouprange
    for child in el:
        if child.tag != "geom":
            continue
        g = spec.geom_props(r.doc, child, el.get("childclass", cls), r.defs, r.comp)
        if not lo <= g.group <= hi or g.type in ("plane", "hfield", "sdf"):
            continue
        n = len(r.missing)
        I = _primitive_inertia(r, child, g)
        if I is not None:
            total += g.placement.act(I)
        elif g.type == "mesh" and len(r.missing) > n and (g.mass is None or g.mass > 0.0):
            r.lost_inertia.append(f"{el.get('name') or '?'} ({r.missing[-1]})")
    return total


def _primitive_inertia(r: _Reader, el: ET.Element, g: spec.GeomProps) -> pin.Inertia | None:
    s = g.size
    if g.type == "mesh":
        shape = _shape(r, el, g)
        if shape is None:
            return None
        bvh = shape[0]
        vol = float(bvh.computeVolume())
        if vol <= 0.0:
            return None
        m = g.mass if g.mass is not None else g.density * vol
        I = np.asarray(bvh.computeMomentofInertiaRelatedToCOM()) * (m / vol)
        return pin.Inertia(m, np.asarray(bvh.computeCOM()), I)
    if g.type == "sphere":
        vol = 4.0 * math.pi * s[0] ** 3 / 3.0
    elif g.type == "capsule":
        vol = math.pi * (s[0] ** 2 * 2.0 * s[1] + 4.0 * s[0] ** 3 / 3.0)
    elif g.type == "cylinder":
        vol = math.pi * s[0] ** 2 * 2.0 * s[1]
    elif g.type == "ellipsoid":
        vol = 4.0 * math.pi * s[0] * s[1] * s[2] / 3.0
    elif g.type == "box":
        vol = 8.0 * s[0] * s[1] * s[2]
    else:
        return None
    m = g.mass if g.mass is not None else g.density * vol
    if g.type == "sphere":
        d = np.full(3, 2.0 * m * s[0] ** 2 / 5.0)
    elif g.type == "capsule":
        rad, h = s[0], 2.0 * s[1]
        ms = m * 4.0 * rad / (4.0 * rad + 3.0 * h)
        mc = m - ms
        ixx = mc * (3 * rad**2 + h**2) / 12 + 2 * ms * rad**2 / 5 + ms * h * (3 * rad + 2 * h) / 8
        d = np.array([ixx, ixx, mc * rad**2 / 2 + 2 * ms * rad**2 / 5])
    elif g.type == "cylinder":
        rad, h = s[0], 2.0 * s[1]
        ixx = m * (3 * rad**2 + h**2) / 12
        d = np.array([ixx, ixx, m * rad**2 / 2])
    elif g.type == "ellipsoid":
        a2, b2, c2 = s**2
        d = m * np.array([b2 + c2, a2 + c2, a2 + b2]) / 5.0
    else:
        a2, b2, c2 = (2.0 * s) ** 2
        d = m * np.array([b2 + c2, a2 + c2, a2 + b2]) / 12.0
    return pin.Inertia(m, np.zeros(3), np.diag(d))


# ---------------------------------------------------------------------------------- equality


def _unique(mech: Mechanism, name: str) -> str:
    used = {c.name for c in mech.closures} | {c.name for c in mech.couplings}
    out, k = name, 1
    while out in used:
        out, k = f"{name}_{k}", k + 1
    return out


def _frame_of(r: _Reader, el: ET.Element, attr: str) -> FrameRef:
    """Frame of a site (``site1``/``site2``) at the site."""
    name = el.get(attr, "")
    if name not in r.sites:
        raise r.doc.error(el, f"{attr}='{name}' is not a site of this model")
    body, M = r.sites[name]
    return FrameRef(body if body != "worldbody" else "worldbody", M)


def _pose_of(r: _Reader, body: str) -> pin.SE3:
    return r.mech.bodies[body].pose if body != WORLD else pin.SE3.Identity()


def _body_ref(r: _Reader, el: ET.Element, attr: str) -> str:
    name = el.get(attr, WORLD)
    if name != WORLD and (name not in r.mech.bodies or r.mech.bodies[name].virtual):
        raise r.doc.error(el, f"{attr}='{name}' is not a body of this model")
    return name


def _link(body: str) -> str:
    return "universe" if body == WORLD else body


def _equalities(r: _Reader, eq: ET.Element) -> None:
    doc, mech = r.doc, r.mech
    counts: dict[str, int] = {}
    for el in eq:
        tag = el.tag
        counts[tag] = counts.get(tag, 0) + 1
        if tag in ("distance", "flex"):
            what = {"distance": "distance constraints", "flex": "flex constraints"}[tag]
            raise doc.error(el, f"{what} are not supported; remove this equality to load the model")
        if tag not in ("connect", "weld", "joint", "tendon"):
            raise doc.error(el, f"unknown equality <{tag}>")
        a = r.defs.attrs(el, "main")
        if a.get("active", "true") == "false":
            warn(f"{mech.source}: {doc.where(el)} is inactive (active='false'); not used")
            continue
        name = _unique(mech, a.get("name") or f"{tag}{counts[tag]}")
        if tag == "joint":
            mech.couplings.append(_coupling(r, el, a, name))
            continue
        if tag == "tendon":
            mech.couplings.append(_tendon_coupling(r, el, a, name))
            continue
        torquescale = 1.0
        if tag == "weld" and "torquescale" in a:
            torquescale = float(spec.vector(doc, el, "torquescale", a["torquescale"], 1)[0])
        f1, f2 = _equality_frames(r, el, a, tag)
        if tag == "weld" and torquescale == 0.0:  # MuJoCo: a weld that ignores rotations
            f1 = FrameRef(f1.link, pin.SE3(np.eye(3), f1.placement.translation))
            f2 = FrameRef(f2.link, pin.SE3(np.eye(3), f2.placement.translation))
        if f1.link == f2.link:
            raise doc.error(el, "both sides are on the same body; nothing to close")
        kind = "point" if tag == "connect" or torquescale == 0.0 else "weld"
        mech.closures.append(ClosureSpec(name, kind, f1, f2))
    mech.closures[:] = _hinges(mech.closures)


def _hinges(closures: list[ClosureSpec]) -> list[ClosureSpec]:
    """Pairs of connects ``N`` and ``N/axis`` (pkdyn's MJCF export of a hinge) as one hinge.

    The pair holds two points of the axis together, which is a hinge about that axis: it
    becomes the ``hinge`` closure ``N`` when both connects join the same two bodies and the
    second points lie at one distance from the first ones on both bodies.
    """
    by_name = {c.name: c for c in closures}
    merged: dict[str, ClosureSpec] = {}
    for c in closures:
        a = by_name.get(c.name + "/axis")
        if c.kind != "point" or a is None or a.kind != "point":
            continue
        if (a.frame1.link, a.frame2.link) != (c.frame1.link, c.frame2.link):
            continue
        d1 = a.frame1.placement.translation - c.frame1.placement.translation
        d2 = a.frame2.placement.translation - c.frame2.placement.translation
        n1, n2 = float(np.linalg.norm(d1)), float(np.linalg.norm(d2))
        if not (n1 > 0.0 and abs(n1 - n2) <= 1e-12 * max(1.0, n1)):
            continue
        u, w = d1 / n1, d2 / n2
        R2 = _rotation_between(u, w)  # frame 2's axes: the axis u maps onto w in body 2
        f1 = FrameRef(c.frame1.link, pin.SE3(np.eye(3), c.frame1.placement.translation))
        f2 = FrameRef(c.frame2.link, pin.SE3(R2, c.frame2.placement.translation))
        merged[c.name] = ClosureSpec(c.name, "hinge", f1, f2, u)
    drop = {n + "/axis" for n in merged}
    return [merged.get(c.name, c) for c in closures if c.name not in drop]


def _rotation_between(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The smallest rotation taking the unit vector ``u`` to the unit vector ``w``."""
    axis = np.cross(u, w)
    s, c = float(np.linalg.norm(axis)), float(np.clip(u @ w, -1.0, 1.0))
    if s < 1e-15:
        if c > 0.0:
            return np.eye(3)
        t = np.eye(3)[int(np.argmin(np.abs(u)))]  # half a turn about any normal of u
        n = np.cross(u, t)
        n /= np.linalg.norm(n)
        return 2.0 * np.outer(n, n) - np.eye(3)
    return np.asarray(pin.exp3(axis / s * np.arctan2(s, c)))


def _coupling(r: _Reader, el: ET.Element, a: dict[str, str], name: str) -> CouplingSpec:
    """A ``<joint>`` equality: ``joint1 - qpos0 = polycoef(joint2 - qpos0)``."""
    doc = r.doc
    joints: list[str | None] = []
    for attr in ("joint1", "joint2"):
        jname = a.get(attr)
        if jname is None:
            joints.append(None)
            continue
        if jname not in r.joint_types:
            raise doc.error(el, f"{attr}='{jname}' is not a joint of this model", name)
        if r.joint_types[jname] not in ("hinge", "slide"):
            raise doc.error(
                el,
                f"{attr}='{jname}' is a {r.joint_types[jname]} joint; joint equalities relate "
                "hinge and slide joints",
                name,
            )
        joints.append(jname)
    j1, j2 = joints
    if j1 is None:
        raise doc.error(el, "missing attribute 'joint1'", name)
    text = spec.complete(a.get("polycoef", spec.POLYCOEF), spec.POLYCOEF)  # as MuJoCo pads it
    try:
        coef = tuple(float(t) for t in text.split())
    except ValueError:
        raise doc.error(el, f"polycoef='{text}': expected numbers", name) from None
    if not 1 <= len(coef) <= 5:
        raise doc.error(el, f"polycoef='{text}': {len(coef)} coefficients; give 1 to 5", name)
    if not all(math.isfinite(c) for c in coef):
        raise doc.error(el, f"polycoef='{text}': NaN and infinite values are not allowed", name)
    if j2 == j1:
        raise doc.error(el, f"joint1 and joint2 are both '{j1}'", name)
    if j2 is None:
        coef = coef[:1]
    given = len(a.get("polycoef", spec.POLYCOEF).split())
    coef = coef[: max(given, 2)]  # beyond the linear term MuJoCo's completion adds zeros only
    ref2 = r.joint_refs[j2] if j2 is not None else 0.0
    return CouplingSpec(name, j1, j2, coef, r.joint_refs[j1], ref2)


def _fixed_tendons(r: _Reader, section: ET.Element) -> None:
    """The ``<fixed>`` tendons: lengths ``L = sum coef_i qpos_i`` (couplings read them).

    Spatial tendons are not read (:mod:`~pkdyn.model.formats.unread` names them); a fixed
    tendon's stiffness, damping, friction and limits are not modelled (one warning).
    """
    doc = r.doc
    unmodelled = []
    for k, t in enumerate(e for e in section if e.tag == "fixed"):
        name = t.get("name") or f"tendon{k + 1}"
        terms: list[tuple[str, float]] = []
        for j in t:
            if j.tag != "joint":
                raise doc.error(j, f"<{j.tag}> in a fixed tendon: a fixed tendon holds joints")
            jname = j.get("joint", "")
            if r.joint_types.get(jname) not in ("hinge", "slide"):
                why = (
                    "is not a joint of this model"
                    if jname not in r.joint_types
                    else f"is a {r.joint_types[jname]} joint; fixed tendons sum hinge and slide "
                    "joints"
                )
                raise doc.error(j, f"joint='{jname}' {why}")
            if "coef" not in j.attrib:
                raise doc.error(j, "missing attribute 'coef'")
            coef = float(spec.vector(doc, j, "coef", j.attrib["coef"], 1)[0])
            terms.append((jname, coef))
        if not terms:
            raise doc.error(t, "a fixed tendon needs at least one <joint>")
        r.tendons[name] = terms
        a = dict(t.attrib)
        if any(
            float(a.get(key, "0") or 0) != 0.0 for key in ("stiffness", "damping", "frictionloss")
        ):
            unmodelled.append(t)
        elif "range" in a or a.get("limited") == "true":
            unmodelled.append(t)
    if unmodelled:
        warn(
            f"{doc.source}: the stiffness, damping, friction and limits of fixed tendons are not "
            f"modelled ({doc.where(unmodelled[0])}"
            + (f" and {len(unmodelled) - 1} more" if len(unmodelled) > 1 else "")
            + ")"
        )


def _tendon_coupling(
    r: _Reader, el: ET.Element, a: dict[str, str], name: str
) -> LinearCouplingSpec:
    """A ``<tendon>`` equality of fixed tendons: a linear coupling of their joints.

    MuJoCo holds ``L1 - L1_0 = p(L2 - L2_0)`` (``L_0`` the length at ``qpos0``; without
    ``tendon2``, ``L1 - L1_0 = polycoef[0]``): with a linear ``p`` this is ``sum_i a_i q_i -
    p1 sum_k b_k q_k = L1_0 + p0 - p1 L2_0``, one linear relation of the joints (a joint in both
    tendons adds its coefficients). A polynomial of a tendon length is refused.
    """
    doc = r.doc
    names = [a.get("tendon1"), a.get("tendon2")]
    if not names[0]:
        raise doc.error(el, "missing attribute 'tendon1'", name)
    for n in names:
        if n is not None and n not in r.tendons:
            raise doc.error(el, f"tendon '{n}' is not a fixed tendon of this model", name)
    text = spec.complete(a.get("polycoef", spec.POLYCOEF), spec.POLYCOEF)
    p = spec.vector(doc, el, "polycoef", text, 5)
    if names[1] is not None and np.any(p[2:]):
        raise doc.error(
            el,
            f"polycoef='{a.get('polycoef')}': a polynomial of a tendon's length is not modelled "
            "(a linear one is: polycoef='p0 p1')",
            name,
        )

    def length0(tendon: str) -> float:
        return sum(c * r.joint_refs[j] for j, c in r.tendons[tendon])

    coefs: dict[str, float] = {}
    for j, c in r.tendons[str(names[0])]:
        coefs[j] = coefs.get(j, 0.0) + c
    offset = length0(str(names[0])) + float(p[0])
    if names[1] is not None:
        for j, c in r.tendons[names[1]]:
            coefs[j] = coefs.get(j, 0.0) - float(p[1]) * c
        offset -= float(p[1]) * length0(names[1])
    terms = tuple((j, c) for j, c in coefs.items() if c != 0.0)
    if not terms:
        raise doc.error(el, "the tendons' terms cancel: no relation left", name)
    return LinearCouplingSpec(name, terms, offset)


def _equality_frames(
    r: _Reader, el: ET.Element, a: dict[str, str], tag: str
) -> tuple[FrameRef, FrameRef]:
    """The two frames a ``connect`` or ``weld`` holds together (MuJoCo's ``eq_data``).

    A weld by bodies holds the point ``anchor`` of body2 (its frame) on body1's point and
    orientation at ``qpos0`` or, with ``relpose``, at ``relpose`` in body1's frame.
    """
    doc = r.doc
    if "site1" in a or "site2" in a:
        f1, f2 = _frame_of(r, el, "site1"), _frame_of(r, el, "site2")
        if tag == "connect":  # only the origins meet: keep the frames' positions
            f1 = FrameRef(f1.link, pin.SE3(np.eye(3), f1.placement.translation))
            f2 = FrameRef(f2.link, pin.SE3(np.eye(3), f2.placement.translation))
        return f1, f2
    b1, b2 = _body_ref(r, el, "body1"), _body_ref(r, el, "body2")
    o1, o2 = _pose_of(r, b1), _pose_of(r, b2)
    anchor = spec.vector(doc, el, "anchor", a.get("anchor", "0 0 0"), 3)
    if tag == "connect":  # anchor in body1, body2's point taken at qpos0
        p1 = pin.SE3(np.eye(3), anchor)
        return FrameRef(_link(b1), p1), FrameRef(
            _link(b2), pin.SE3(np.eye(3), o2.actInv(o1 * p1).translation)
        )
    p2 = pin.SE3(np.eye(3), anchor)  # weld: anchor in body2
    rel = spec.vector(doc, el, "relpose", a.get("relpose", "0 1 0 0 0 0 0"), 7)
    if np.allclose(rel[3:], 0.0):  # relative pose of qpos0
        return FrameRef(_link(b1), o1.actInv(o2 * p2)), FrameRef(_link(b2), p2)
    w, x, y, z = rel[3:] / np.linalg.norm(rel[3:])
    return FrameRef(_link(b1), pin.SE3(pin.Quaternion(w, x, y, z).matrix(), rel[:3])), FrameRef(
        _link(b2), p2
    )


# ---------------------------------------------------------------------------------- actuators


def _actuators(r: _Reader, act: ET.Element) -> None:
    doc, mech = r.doc, r.mech
    skipped: list[str] = []
    used: dict[str, str] = {}
    for k, el in enumerate(act):
        if el.tag not in spec.ACTUATOR_TAGS:
            raise doc.error(el, f"unknown actuator <{el.tag}>")
        p = spec.actuator_props(doc, el, r.defs, r.comp)
        name = p.name or f"actuator{k + 1}"
        if p.transmission not in ("joint", "jointinparent"):
            skipped.append(f"{name} ({p.transmission})")
            continue
        if p.target not in r.joint_types:
            raise doc.error(el, f"joint='{p.target}' is not a joint of this model", name)
        if r.joint_types[p.target] not in ("hinge", "slide"):
            skipped.append(f"{name} (on a {r.joint_types[p.target]} joint)")
            continue
        if p.target in used:
            raise doc.error(
                el,
                f"joint '{p.target}' already carries actuator '{used[p.target]}'; pkdyn "
                "takes one actuator per joint",
                name,
            )
        if p.gear == 0.0:
            raise doc.error(el, "gear 0 transmits nothing", name)
        used[p.target] = name
        effort = math.inf
        if p.forcerange is not None:
            effort = max(abs(p.forcerange[0]), abs(p.forcerange[1])) * abs(p.gear)
        if p.gain is not None and p.ctrlrange is not None:
            ctrl = max(abs(p.ctrlrange[0]), abs(p.ctrlrange[1])) * abs(p.gain * p.gear)
            effort = min(effort, ctrl)
        mech.actuators.append(ActuatorSpec(name, p.target, p.gear, effort, math.inf))
    if skipped:
        warn(
            f"{mech.source}: {len(skipped)} actuator(s) not on a hinge or slide joint are left "
            f"out: {', '.join(skipped[:5])}" + (" ..." if len(skipped) > 5 else "")
        )


# ---------------------------------------------------------------------------------- keyframes


def _keyframe(r: _Reader, key: ET.Element) -> dict[str, np.ndarray]:
    """Joint coordinates (Pinocchio convention) of a keyframe's ``qpos``."""
    sizes = {"free": 7, "ball": 4, "hinge": 1, "slide": 1}
    nq = sum(sizes[t] for _, t in r.mj_joints)
    qpos = spec.vector(r.doc, key, "qpos", key.get("qpos", ""), None)
    if qpos.size != nq:
        raise r.doc.error(key, f"qpos has {qpos.size} values; the model has nq = {nq}")
    out: dict[str, np.ndarray] = {}
    i = 0
    for name, t in r.mj_joints:
        v = qpos[i : i + sizes[t]]
        i += sizes[t]
        if t in ("free", "ball"):
            w = unit_vector(v[-4:])
            if w is None:
                raise r.doc.error(
                    key, f"qpos of joint '{name}': the quaternion {v[-4:].tolist()} is zero"
                )
            out[name] = np.concatenate([v[:-4], w[1:], w[:1]])
        else:
            out[name] = v.copy()
    return out
