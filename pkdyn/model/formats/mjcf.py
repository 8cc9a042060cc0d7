"""MJCF export: a MuJoCo model of any loaded robot (its joints and states: ``mjcf_state``).

The exported model has one MuJoCo body per Pinocchio joint, whose frame *is* that joint's frame
(body ``pos``/``quat`` = the joint placement in its parent joint's frame), so body poses agree
with ``data.oMi`` at the same configuration. Joints map as follows (MuJoCo names in brackets):

- revolute (bounded or not, aligned or not) -> ``hinge`` [name]; prismatic -> ``slide`` [name];
- spherical -> ``ball`` [name]; free-flyer -> ``free`` [name] (on a body of the world only);
- universal(axis1, axis2) -> two hinges in one body [name_1, name_2] (MuJoCo applies the joints
  of a body in order, each axis in the frame moved by the previous ones, as Pinocchio does);
- planar -> slide x, slide y, hinge z [name_x, name_y, name_rz]; translation -> three slides;
  spherical ZYX -> three hinges z, y, x.

Inertias are written explicitly (``fullinertia`` at the centre of mass, no inference from
geoms). Visual geoms are in group 2 without contacts, collision geoms in group 3; contacts
between bodies linked by a joint or a closure are excluded. Closures become equality constraints
between two sites placed at the Pinocchio contact frames (``<name>_1`` on ``joint1``'s body,
``<name>_2`` on ``joint2``'s): a ``point`` closure a ``connect``, a ``weld`` a ``weld``, a
``hinge`` the same two ``connect`` as its two Pinocchio point constraints. Polynomial joint
couplings become ``joint`` equalities named after the coupling (``joint1`` the driven joint,
``joint2`` the source, ``polycoef`` the polynomial re-expanded about ``qpos0 = 0``: MuJoCo's
``qpos - qpos0`` convention with the exported joints' zero ``ref``); a linear coupling of one
joint to one (a URDF+ rotor transmission) a joint equality too (its last term driven); a linear
coupling ``sum a_i q_i = b`` of more joints a fixed tendon ``<name>/sum`` of length
``sum a_i q_i`` and a ``tendon`` equality named after the coupling holding it at ``b``. Each
actuator is a ``motor`` on its joint with ``gear`` = the transmission reduction, so its control
is the motor-side effort; ``ctrlrange`` and ``forcerange`` are the URDF (joint-side) effort limit
divided by the reduction. A keyframe ``home`` holds the assembled home configuration.

Inertias MuJoCo refuses (:mod:`~pkdyn.model.formats.mjcf_inertia`): a massless rotor borrows a
tiny mass from the body it turns in, at a point of its axis (the dynamics unchanged); a tensor
breaking the triangle inequality is refused with the remedy (``repair_inertias=True``).

Passive elements: joint damping, friction (``frictionloss``: MuJoCo's dry friction is a
constraint, pkdyn's a smooth ``tanh`` law) and armature; joint springs as ``stiffness`` and
``springref`` (the rest position) on hinges and slides, ``stiffness`` on a ball joint whose spring
is isotropic about the zero rotation (MuJoCo's ball spring: ``-k log(q_ref^-1 q)``, as pkdyn's);
two-frame springs as spatial tendons between two sites (``<name>/1``, ``<name>/2``) with
``stiffness`` and ``springlength`` (the free length).

Not exported: ball-joint springs with a rest rotation or different stiffnesses per axis, and
springs on free joints (a warning says so); the cone / pyramid limits of passive ball and
universal joints (MuJoCo's ball ``range`` bounds the rotation angle, not the tilt of an axis),
velocity limits, meshes in formats MuJoCo cannot read (skipped with a warning). MuJoCo's
equality constraints are soft (``solref``, ``solimp``); the defaults below make them stiff for
the chosen time step.

The export's joints and state vectors are mapped by :class:`~pkdyn.model.formats.mjcf_state.
StateMap` (:mod:`~pkdyn.model.formats.mjcf_state`); the actuator efforts of MuJoCo's inverse
dynamics are in :mod:`~pkdyn.model.formats.mjcf_mujoco`. Their public names are importable from
here too (``from pkdyn.model.formats.mjcf import StateMap``); :func:`mujoco_model` compiles the
export.
"""

from __future__ import annotations

import math
import os
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import OutputError
from pkdyn.files import atomic_write
from pkdyn.inputs import positive
from pkdyn.model.formats.mjcf_inertia import mujoco_inertias
from pkdyn.model.formats.mjcf_mujoco import actuator_efforts
from pkdyn.model.formats.mjcf_state import JointMap, StateMap
from pkdyn.model.formats.mjcf_state import quat_wxyz as _quat_wxyz
from pkdyn.model.robot import Robot
from solvers.coupling import MAX_COEFFICIENTS, JointCoupling, LinearCoupling

__all__ = [
    "JointMap",
    "MjcfOptions",
    "StateMap",
    "actuator_efforts",
    "mujoco_model",
    "to_mjcf",
    "write_mjcf",
]

_MESH_FORMATS = (".stl", ".obj", ".msh")
_TAG_ORDER = {"inertial": 0, "joint": 1, "geom": 2, "site": 3, "body": 4}


@dataclass(frozen=True)
class MjcfOptions:
    """Simulation options written into the model.

    Attributes:
        timestep: Integration step [s].
        integrator: MuJoCo integrator (``Euler``, ``implicitfast``, ``implicit``, ``RK4``).
        eq_solref: ``solref`` of the closure constraints (time constant [s], damping ratio);
            default: twice the time step, critically damped (the stiffest MuJoCo accepts).
        eq_solimp: ``solimp`` of the closure constraints (``dmin dmax width``); close to 1:
            nearly hard constraints.
        contacts: Give the collision geoms contacts (else they are written without any).
        visual: Write the visual geoms.
        collision: Write the collision geoms.

    """

    timestep: float = 1e-3
    integrator: str = "implicitfast"
    eq_solref: tuple[float, float] | None = None
    eq_solimp: tuple[float, float, float] = (0.99, 0.9999, 0.001)
    contacts: bool = True
    visual: bool = True
    collision: bool = True


def _num(x: float) -> str:
    """Shortest text that reads back as the same double."""
    text = repr(float(x))
    return text[:-2] if text.endswith(".0") else text


def _fmt(x: np.ndarray | list[float] | tuple[float, ...]) -> str:
    return " ".join(_num(v) for v in np.ravel(x))


# ---------------------------------------------------------------------------------- writing


def _sub(parent: ET.Element, tag: str, **attrs: str) -> ET.Element:
    return ET.SubElement(parent, tag, {k.rstrip("_"): v for k, v in attrs.items()})


def _pose_attrs(M: pin.SE3) -> dict[str, str]:
    out = {}
    if np.any(M.translation != 0.0):
        out["pos"] = _fmt(M.translation)
    if not np.allclose(M.rotation, np.eye(3), rtol=0.0, atol=1e-15):
        out["quat"] = _fmt(_quat_wxyz(M.rotation))
    return out


def _inertial(body: ET.Element, inertia: pin.Inertia) -> None:
    if inertia.mass <= 0.0:
        return
    I = np.asarray(inertia.inertia)
    _sub(
        body,
        "inertial",
        pos=_fmt(inertia.lever),
        mass=_num(inertia.mass),
        fullinertia=_fmt([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]),
    )


def _joint_attrs(model: pin.Model, jid: int, nv_index: int, k: int) -> dict[str, str]:
    """Damping, friction loss and armature of one velocity coordinate, when non-zero."""
    out = {}
    for attr, vec in (
        ("damping", model.damping),
        ("frictionloss", model.friction),
        ("armature", model.armature),
    ):
        value = float(vec[nv_index + k])
        if value != 0.0:
            out[attr] = _num(value)
    return out


def _spring_attrs(robot: Robot, jid: int, kind: str, k: int) -> dict[str, str]:
    """``stiffness`` and ``springref`` of MuJoCo joint ``k`` of Pinocchio joint ``jid``."""
    passive = robot.passive
    if passive is None:
        return {}
    jm = robot.model.joints[jid]
    K = passive.stiffness[jm.idx_v : jm.idx_v + jm.nv]
    rest = passive.rest[jm.idx_q : jm.idx_q + jm.nq]
    if not np.any(K):
        return {}
    name = robot.model.names[jid]
    if kind == "ball":
        if np.all(K == K[0]) and np.allclose(rest, [0.0, 0.0, 0.0, 1.0], rtol=0.0, atol=1e-15):
            return {"stiffness": _num(K[0])}
    elif kind in ("hinge", "slide") and K.size == jm.nq:  # one MuJoCo joint per coordinate
        return {"stiffness": _num(K[k]), "springref": _num(rest[k])}
    elif kind == "hinge" and jm.nq == 2 and K.size == 1:  # unbounded revolute (cos, sin)
        return {"stiffness": _num(K[0]), "springref": _num(math.atan2(rest[1], rest[0]))}
    warnings.warn(
        f"{robot.source}: the spring of joint '{name}' has no MuJoCo equivalent; not exported",
        stacklevel=3,
    )
    return {}


COUPLING_TENDON = "/sum"
"""Name suffix of the fixed tendon a linear coupling is exported as (``ankle_rotor/sum``)."""


def _coupling_tendons(root: ET.Element, model: pin.Model, sums: list[LinearCoupling]) -> None:
    """Linear couplings ``sum a_i q_i = b`` as fixed tendons ``L = sum a_i q_i``.

    MuJoCo's tendon equality without ``tendon2`` holds ``L - L0 = polycoef[0]``, ``L0`` the
    length at ``qpos0`` (zero here: no joint has a ``ref``), so ``polycoef[0] = b``.
    """
    if not sums:
        return
    tendon = root.find("tendon")
    if tendon is None:
        tendon = _sub(root, "tendon")
    for c in sums:
        el = _sub(tendon, "fixed", name=f"{c.name}{COUPLING_TENDON}")
        for j, a in c.terms:
            _sub(el, "joint", joint=model.names[j], coef=_num(a))


def _tendons(root: ET.Element, robot: Robot, elements: dict[int, ET.Element]) -> None:
    """Two-frame springs as spatial tendons between two sites."""
    springs = [] if robot.passive is None else list(robot.passive.springs)
    if not springs:
        return
    tendon = _sub(root, "tendon")
    for k, sp in enumerate(springs):
        name = sp.name or f"spring{k}"
        sites = []
        for j, M, end in ((sp.joint1, sp.placement1, 1), (sp.joint2, sp.placement2, 2)):
            sites.append(f"{name}/{end}")
            _sub(elements[j], "site", name=sites[-1], **_pose_attrs(M))
        el = _sub(
            tendon,
            "spatial",
            name=name,
            stiffness=_num(sp.stiffness),
            springlength=_num(sp.rest_length),
        )
        for site in sites:
            _sub(el, "site", site=site)


def _geom(
    parent: ET.Element,
    assets: ET.Element,
    go: pin.GeometryObject,
    cls: str,
    source: str,
    mesh_names: dict[tuple[str, str], str],
) -> None:
    g = go.geometry
    kind = type(g).__name__
    attrs: dict[str, str] = {"name": f"{cls}/{go.name}", "class_": cls, **_pose_attrs(go.placement)}
    if kind == "Cylinder":
        attrs.update(type="cylinder", size=_fmt([g.radius, g.halfLength]))
    elif kind == "Capsule":
        attrs.update(type="capsule", size=_fmt([g.radius, g.halfLength]))
    elif kind == "Box":
        attrs.update(type="box", size=_fmt(g.halfSide))
    elif kind == "Sphere":
        attrs.update(type="sphere", size=_fmt([g.radius]))
    elif kind == "Ellipsoid":
        attrs.update(type="ellipsoid", size=_fmt(g.radii))
    elif Path(go.meshPath).suffix.lower() in _MESH_FORMATS and os.path.isfile(go.meshPath):
        key = (go.meshPath, _fmt(go.meshScale))
        if key not in mesh_names:
            mesh_names[key] = f"mesh{len(mesh_names)}_{Path(go.meshPath).stem}"
            _sub(
                assets,
                "mesh",
                name=mesh_names[key],
                file=os.path.abspath(go.meshPath),
                scale=key[1],
            )
        attrs.update(type="mesh", mesh=mesh_names[key])
    else:
        warnings.warn(
            f"{source}: geometry '{go.name}' ({kind} {go.meshPath}) has no MuJoCo equivalent; "
            "not exported",
            stacklevel=3,
        )
        return
    if cls == "visual":
        attrs["rgba"] = _fmt(np.round(np.asarray(go.meshColor, dtype=float), 4))
    _sub(parent, "geom", **attrs)


def to_mjcf(robot: Robot, options: MjcfOptions | None = None) -> str:
    """MJCF text of a robot (see the module docstring for the mapping).

    Args:
        robot: A loaded robot (``geometry=True`` for geoms).
        options: Simulation options (default: :class:`MjcfOptions`).

    Returns:
        The MJCF document.

    Raises:
        DescriptionError: A joint has no MuJoCo equivalent.
        InvalidInputError: A timestep that is not a positive finite number of seconds.

    """
    opt = options or MjcfOptions()
    positive("timestep", opt.timestep, "s")
    model = robot.model
    inertias = mujoco_inertias(robot)
    smap = StateMap(robot)
    names = smap.body_names
    root = ET.Element("mujoco", model=robot.name)
    _sub(root, "compiler", angle="radian", autolimits="true", inertiafromgeom="false")
    _sub(
        root,
        "option",
        timestep=_num(opt.timestep),
        gravity=_fmt(model.gravity.linear),
        integrator=opt.integrator,
    )
    default = _sub(root, "default")
    solref = opt.eq_solref or (2.0 * opt.timestep, 1.0)
    _sub(default, "equality", solref=_fmt(solref), solimp=_fmt(opt.eq_solimp))
    vis = _sub(_sub(default, "default", class_="visual"), "geom")
    vis.attrib.update(contype="0", conaffinity="0", group="2")
    col = _sub(_sub(default, "default", class_="collision"), "geom", group="3")
    if not opt.contacts:
        col.attrib.update(contype="0", conaffinity="0")
    assets = _sub(root, "asset")
    world = _sub(root, "worldbody")
    elements: dict[int, ET.Element] = {0: world}
    for j in smap.order:
        body = _sub(elements[model.parents[j]], "body", name=names[j])
        body.attrib.update(_pose_attrs(model.jointPlacements[j]))
        elements[j] = body
        _inertial(body, inertias[j])
        jm = model.joints[j]
        for k, e in enumerate(smap.elements[j]):
            attrs = {"name": e.name, "type": e.type}
            if e.type in ("hinge", "slide"):
                attrs["axis"] = _fmt(e.axis)
                if e.range is not None:
                    attrs["range"] = _fmt(e.range)
            if e.type in ("hinge", "slide") or k == 0:
                attrs.update(_joint_attrs(model, j, jm.idx_v, k if e.type != "free" else 0))
                attrs.update(_spring_attrs(robot, j, e.type, k))
            _sub(body, "joint", **attrs)
    mesh_names: dict[tuple[str, str], str] = {}
    for cls, gm, wanted in (
        ("visual", robot.visual_model, opt.visual),
        ("collision", robot.collision_model, opt.collision),
    ):
        if wanted:
            for go in gm.geometryObjects:
                _geom(elements[go.parentJoint], assets, go, cls, robot.source, mesh_names)
    for f in model.frames:
        if f.type == pin.FrameType.OP_FRAME:
            _sub(elements[f.parentJoint], "site", name=f.name, **_pose_attrs(f.placement))
    equality = _sub(root, "equality")
    for cm in robot.constraint_models:
        s1, s2 = f"{cm.name}_1", f"{cm.name}_2"
        _sub(elements[cm.joint1_id], "site", name=s1, **_pose_attrs(cm.joint1_placement))
        _sub(elements[cm.joint2_id], "site", name=s2, **_pose_attrs(cm.joint2_placement))
        tag = "connect" if cm.type == pin.ContactType.CONTACT_3D else "weld"
        _sub(equality, tag, name=cm.name, site1=s1, site2=s2)
    sums: list[LinearCoupling] = []
    for c in robot.constraints.coupling_specs:
        if isinstance(c, LinearCoupling) and len(c.terms) <= 2:  # one joint to one: a joint
            _linear_joint_equality(equality, model, c)  # equality, as MuJoCo writes a gear
            continue
        if isinstance(c, LinearCoupling):  # a fixed tendon held at its length
            sums.append(c)
            _sub(equality, "tendon", name=c.name, tendon1=f"{c.name}{COUPLING_TENDON}",
                 polycoef=_fmt([c.offset, 0.0, 0.0, 0.0, 0.0]))  # fmt: skip
            continue
        attrs = {"name": c.name, "joint1": model.names[c.joint]}
        if c.source is not None:
            attrs["joint2"] = model.names[c.source]
        _sub(equality, "joint", polycoef=_fmt(_polycoef(c)), **attrs)
    if len(equality) == 0:
        root.remove(equality)
    _tendons(root, robot, elements)
    _coupling_tendons(root, model, sums)
    if opt.contacts and opt.collision and len(robot.collision_model.geometryObjects):
        contact = _sub(root, "contact")
        for a, b in _excluded_pairs(robot):
            _sub(contact, "exclude", body1=names[a], body2=names[b])
    if len(assets) == 0:
        root.remove(assets)
    _actuators(root, robot)
    for el in elements.values():  # readable order: inertial, joints, geoms, sites, children
        el[:] = sorted(el, key=lambda c: _TAG_ORDER.get(c.tag, 5))
    keyframe = _sub(root, "keyframe")
    _sub(keyframe, "key", name="home", qpos=_fmt(smap.qpos(robot.q_home)))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"


def _linear_joint_equality(equality: ET.Element, model: pin.Model, c: LinearCoupling) -> None:
    """``a_1 q_1 + a_2 q_2 = b`` as the joint equality ``q_2 = b / a_2 - (a_1 / a_2) q_1``.

    The last term is the driven joint (``joint1``; a URDF+ coupling's successor, the rotor),
    the first its source; one term alone locks its joint at ``b / a``. The exported joints
    have no ``ref``: ``qpos0 = 0``, so the polynomial is MuJoCo's as written.
    """
    (driven, a_d) = c.terms[-1]
    attrs = {"name": c.name, "joint1": model.names[driven]}
    coef = [c.offset / a_d + 0.0, 0.0, 0.0, 0.0, 0.0]  # + 0.0: no "-0"
    if len(c.terms) == 2:
        source, a_s = c.terms[0]
        attrs["joint2"] = model.names[source]
        coef[1] = -a_s / a_d + 0.0
    _sub(equality, "joint", polycoef=_fmt(coef), **attrs)


def _polycoef(c: JointCoupling) -> np.ndarray:
    """MuJoCo ``polycoef`` (5,) of a coupling, about ``qpos0 = 0`` of both joints.

    ``x_j = x_j0 + p(x_s - x_s0)`` expanded in powers of ``x_s`` (binomial theorem); a locked
    joint keeps the constant term only.
    """
    out = np.zeros(MAX_COEFFICIENTS)
    if c.source is None:
        out[0] = c.joint_ref + c.coefficients[0]
        return out
    for k, ck in enumerate(c.coefficients):
        for i in range(k + 1):
            out[i] += ck * math.comb(k, i) * (-c.source_ref) ** (k - i)
    out[0] += c.joint_ref
    return out


def _excluded_pairs(robot: Robot) -> list[tuple[int, int]]:
    """Joint (body) pairs whose contacts are excluded: they touch by construction.

    Bodies joined by a physical tree joint or a closure, and bodies whose collision geometries
    already touch or overlap at the home configuration (coal distance <= 0), e.g. a cylinder
    housing that encloses the pivot of the next body.
    """
    pairs = {(min(a, b), max(a, b)) for a, b in robot._physical_edges()}
    gm = robot.collision_model.copy()
    objs = gm.geometryObjects
    for i in range(len(objs)):
        for k in range(i + 1, len(objs)):
            a, b = int(objs[i].parentJoint), int(objs[k].parentJoint)
            if a != b and (min(a, b), max(a, b)) not in pairs:
                gm.addCollisionPair(pin.CollisionPair(i, k))
    if len(gm.collisionPairs):
        gd = pin.GeometryData(gm)
        pin.computeDistances(robot.model, robot.model.createData(), gm, gd, robot.q_home)
        for cp, res in zip(gm.collisionPairs, gd.distanceResults, strict=True):
            if res.min_distance <= 0.0:
                a, b = (int(objs[i].parentJoint) for i in (cp.first, cp.second))
                pairs.add((min(a, b), max(a, b)))
    return sorted(pairs)


def _actuators(root: ET.Element, robot: Robot) -> None:
    if not robot.actuators:
        return
    act = _sub(root, "actuator")
    for a in robot.actuators:
        attrs = {"name": a.name, "joint": a.joint, "gear": _num(a.reduction)}
        if math.isfinite(a.effort):
            lim = abs(a.effort / a.reduction)
            attrs.update(ctrlrange=_fmt([-lim, lim]), forcerange=_fmt([-lim, lim]))
        _sub(act, "motor", **attrs)


def mujoco_model(robot: Robot, options: MjcfOptions | None = None) -> Any:
    """The export of ``robot`` compiled by MuJoCo.

    Args:
        robot: A loaded robot.
        options: Simulation options.

    Returns:
        The ``mujoco.MjModel``.

    Raises:
        ImportError: MuJoCo is not installed (``pip install mujoco``).

    """
    try:
        import mujoco
    except ImportError as err:  # an optional dependency of the core
        raise ImportError("MuJoCo is not installed: pip install mujoco") from err
    return mujoco.MjModel.from_xml_string(to_mjcf(robot, options))


def write_mjcf(
    robot: Robot, path: str | os.PathLike[str], options: MjcfOptions | None = None
) -> None:
    """Write :func:`to_mjcf` to a file.

    Args:
        robot: A loaded robot.
        path: Output file.
        options: Simulation options.

    Raises:
        OutputError: The file cannot be written (an existing file is left intact).

    """
    text = to_mjcf(robot, options)
    try:
        with atomic_write(path) as fh:
            fh.write(text)
    except OSError as err:
        raise OutputError(str(path), err.strerror or str(err)) from None
