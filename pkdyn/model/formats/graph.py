"""A mechanism as a graph of bodies and joints, and the Pinocchio model of its spanning tree.

The MJCF and SDF importers read their files into a :class:`Mechanism`: bodies with their
reference world pose (the pose the file describes), joints with the world pose of their frame
in that reference configuration and their coordinates there (``q_ref``: MuJoCo's ``ref``, the
pose of a free body), loop closures, actuators. :func:`build` chooses the spanning tree and
returns the Pinocchio model:

- the tree is grown breadth first from the world and from every body without a parent joint,
  in file order, following each joint from its parent to its child (so loops are cut at the
  joints farthest from a root); a joint whose child is already in the tree closes a loop
  and becomes a closure (``ball`` -> ``point``, ``revolute`` -> ``hinge`` about its axis,
  ``fixed`` -> ``weld``); a prismatic (or other) joint that would close a loop swaps places with
  the closable tree joint that reached the same body; when there is none, it is refused, naming
  the joint;
- a body without a parent joint is welded to the world (an importer that wants it floating
  gives it a ``free`` joint);
- Pinocchio joints are added depth first along the tree, in file order (MuJoCo's order);
- Pinocchio joint placements are chosen so that the configuration ``q_ref`` puts every body at
  its reference pose; joint axes are expressed in the joint frames;
- frames: ``BODY`` per body (not the intermediate bodies of multi-joint MJCF bodies), ``JOINT``
  per moving joint, ``FIXED_JOINT`` per fixed joint, ``OP_FRAME`` per site or named frame.

Revolute and prismatic joints always get one coordinate (no cos/sin pair for unbounded
revolute joints), as in MuJoCo, so that any of them can carry an actuator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
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
    PassiveSpec,
)
from pkdyn.model.validate import unit_vector
from pkdyn.model.warn import warn

__all__ = ["WORLD", "Body", "Geometry", "Joint", "Mechanism", "Built", "build"]

WORLD = "world"
"""Name of the world body in a :class:`Mechanism`."""

JOINT_KINDS = ("revolute", "prismatic", "ball", "universal", "free", "fixed")


@dataclass
class Geometry:
    """A visual or collision shape attached to a body.

    Attributes:
        name: Name (unique within its body).
        shape: Coal collision geometry.
        placement: Pose of the shape in the body frame.
        mesh_path: Mesh file of a mesh shape ('' for primitives).
        scale: Mesh scale (3,).
        rgba: Colour (4,).

    """

    name: str
    shape: Any
    placement: pin.SE3
    mesh_path: str = ""
    scale: np.ndarray = field(default_factory=lambda: np.ones(3))
    rgba: np.ndarray = field(default_factory=lambda: np.array([0.7, 0.7, 0.7, 1.0]))


@dataclass
class Body:
    """A rigid body.

    Attributes:
        name: Unique name.
        pose: World pose in the reference configuration.
        inertia: Inertia in the body frame.
        visuals: Visual shapes.
        collisions: Collision shapes.
        frames: Named frames (sites) on the body, with their pose in the body frame.
        virtual: An intermediate body of a chain of joints (no ``BODY`` frame of its own).

    """

    name: str
    pose: pin.SE3
    inertia: pin.Inertia = field(default_factory=pin.Inertia.Zero)
    visuals: list[Geometry] = field(default_factory=list)
    collisions: list[Geometry] = field(default_factory=list)
    frames: list[tuple[str, pin.SE3]] = field(default_factory=list)
    virtual: bool = False


@dataclass
class Joint:
    """A joint between two bodies.

    Attributes:
        name: Unique name.
        kind: One of ``revolute``, ``prismatic``, ``ball``, ``universal``, ``free``, ``fixed``.
        parent: Parent body name (or :data:`WORLD`).
        child: Child body name.
        pose: World pose of the joint frame in the reference configuration.
        axis: Unit axis in the joint frame (revolute, prismatic, first axis of a universal).
        axis2: Second axis of a universal joint, in the joint frame (orthogonal to ``axis``).
        q_ref: Joint coordinates in the reference configuration (Pinocchio convention; default
            the neutral configuration).
        lower: Lower position limits (one per coordinate; -inf when absent).
        upper: Upper position limits.
        effort: Effort limit [N m or N].
        velocity: Velocity limit [rad/s or m/s].
        damping: Viscous damping [N m s/rad or N s/m].
        friction: Dry friction [N m or N].
        armature: Armature (reflected rotor inertia) [kg m^2 or kg].
        stiffness: Spring stiffness [N m/rad or N/m] (every degree of freedom).
        spring_ref: Configuration where the spring rests (Pinocchio convention; default the
            neutral configuration).
        where: How messages name the joint's element (tag and line).

    """

    name: str
    kind: str
    parent: str
    child: str
    pose: pin.SE3
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    axis2: np.ndarray | None = None
    q_ref: np.ndarray | None = None
    lower: float = -math.inf
    upper: float = math.inf
    effort: float = math.inf
    velocity: float = math.inf
    damping: float = 0.0
    friction: float = 0.0
    armature: float = 0.0
    stiffness: float = 0.0
    spring_ref: np.ndarray | None = None
    where: str = ""


@dataclass
class Mechanism:
    """Bodies, joints, closures and actuators read from a file.

    Attributes:
        name: Robot name.
        source: File it came from.
        bodies: Bodies by name, in file order.
        joints: Joints in file order.
        closures: Loop closures (frames name bodies, placements in the body frames).
        actuators: Actuators.
        gravity: Gravity vector [m/s^2].
        home: Named configurations (joint name -> coordinates, Pinocchio convention).
        couplings: Joint couplings (joint names, coordinates in the file's convention).
        missing_meshes: Mesh files that were not found (their shapes are left out).
        dropped_collisions: Collision shapes left out because they were malformed.

    """

    name: str
    source: str
    bodies: dict[str, Body] = field(default_factory=dict)
    joints: list[Joint] = field(default_factory=list)
    closures: list[ClosureSpec] = field(default_factory=list)
    actuators: list[ActuatorSpec] = field(default_factory=list)
    couplings: list[CouplingSpec | LinearCouplingSpec] = field(default_factory=list)
    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -9.81]))
    home: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    missing_meshes: list[str] = field(default_factory=list)
    dropped_collisions: list[str] = field(default_factory=list)

    def add_body(self, body: Body, where: str = "") -> Body:
        """Add a body; its name must be new."""
        if body.name == WORLD or body.name in self.bodies:
            raise DescriptionError(self.source, where or f"body '{body.name}'", "duplicate name")
        self.bodies[body.name] = body
        return body


@dataclass
class Built:
    """The Pinocchio side of a mechanism.

    Attributes:
        model: Pinocchio model of the spanning tree.
        visual: Visual geometry.
        collision: Collision geometry.
        closures: The mechanism's closures followed by those of the cut joints.
        q_ref: Reference configuration (nq,): every body at its reference pose.
        joint_ids: Pinocchio joint id of each moving tree joint, by name.
        cut: Names of the joints that became closures.
        passive: Springs, dampers and friction of the moving tree joints (the rest position as
            the displacement from the joint's zero configuration).
        couplings: The mechanism's joint couplings (on tree joints).

    """

    model: pin.Model
    visual: pin.GeometryModel
    collision: pin.GeometryModel
    closures: list[ClosureSpec]
    q_ref: np.ndarray
    joint_ids: dict[str, int]
    cut: list[str]
    passive: list[PassiveSpec] = field(default_factory=list)
    couplings: list[CouplingSpec | LinearCouplingSpec] = field(default_factory=list)

    def configuration(self, values: dict[str, np.ndarray], base: np.ndarray) -> np.ndarray:
        """A configuration with some joints set (joint name -> coordinates).

        Args:
            values: Coordinates per joint name (Pinocchio convention).
            base: Configuration for the other joints (nq,).

        Returns:
            The configuration (nq,).

        """
        q = np.array(base, dtype=float)
        for name, v in values.items():
            jid = self.joint_ids.get(name)
            if jid is None:
                continue
            jm = self.model.joints[jid]
            q[jm.idx_q : jm.idx_q + jm.nq] = v
        return q


def _unit(v: np.ndarray) -> np.ndarray:
    u = unit_vector(v)
    if u is None:
        raise ValueError(f"zero or non-finite axis {v}")  # importers refuse these first
    return np.asarray(u)


def _axis_model(kind: str, axis: np.ndarray) -> pin.JointModel:
    """Pinocchio revolute / prismatic joint model about ``axis`` (aligned types when exact)."""
    e = np.eye(3)
    for k, c in enumerate("XYZ"):
        if np.array_equal(axis, e[k]):
            return getattr(pin, f"JointModel{'R' if kind == 'revolute' else 'P'}{c}")()
    if kind == "revolute":
        return pin.JointModelRevoluteUnaligned(axis)
    return pin.JointModelPrismaticUnaligned(axis)


def _joint_model(j: Joint, source: str) -> pin.JointModel:
    if j.kind in ("revolute", "prismatic"):
        return _axis_model(j.kind, _unit(j.axis))
    if j.kind == "ball":
        return pin.JointModelSpherical()
    if j.kind == "free":
        return pin.JointModelFreeFlyer()
    if j.kind == "universal":
        assert j.axis2 is not None
        a1, a2 = _unit(j.axis), _unit(j.axis2)
        if abs(float(a1 @ a2)) > 1e-9:
            raise DescriptionError(
                source,
                j.where or f"joint '{j.name}'",
                "the two axes of a universal joint must be orthogonal",
            )
        return pin.JointModelUniversal(a1, a2)
    raise DescriptionError(source, j.where or f"joint '{j.name}'", f"unknown kind '{j.kind}'")


def _motion(jm: pin.JointModel, q: np.ndarray) -> pin.SE3:
    """Placement ``M(q)`` of a single joint model."""
    m = pin.Model()
    m.addJoint(0, jm, pin.SE3.Identity(), "j")
    d = m.createData()
    pin.forwardKinematics(m, d, np.asarray(q, dtype=float))
    return pin.SE3(d.oMi[1])


def _neutral(jm: pin.JointModel) -> np.ndarray:
    m = pin.Model()
    m.addJoint(0, jm, pin.SE3.Identity(), "j")
    return np.asarray(pin.neutral(m))


def spanning_tree(mech: Mechanism) -> tuple[list[Joint], list[Joint]]:
    """Tree joints in the order they are added, and the joints that close loops.

    Args:
        mech: The mechanism.

    Returns:
        ``(tree, cut)``.

    Raises:
        DescriptionError: A joint names a missing body, or joins a body to itself.

    """
    by_parent: dict[str, list[Joint]] = {WORLD: []}
    has_parent: set[str] = set()
    for name in mech.bodies:
        by_parent[name] = []
    for j in mech.joints:
        for side in (j.parent, j.child):
            if side != WORLD and side not in mech.bodies:
                raise DescriptionError(
                    mech.source,
                    j.where or f"joint '{j.name}'",
                    f"names body '{side}', which does not exist",
                )
        if j.parent == j.child:
            raise DescriptionError(
                mech.source, j.where or f"joint '{j.name}'", "joins a body to itself"
            )
        if j.child == WORLD:
            raise DescriptionError(
                mech.source, j.where or f"joint '{j.name}'", "the world cannot be a child"
            )
        by_parent[j.parent].append(j)
        has_parent.add(j.child)
    roots = [WORLD] + [b for b in mech.bodies if b not in has_parent]
    reached = set(roots)
    chosen: dict[str, list[Joint]] = {b: [] for b in by_parent}
    cut: list[Joint] = []
    frontier = list(roots)
    while frontier:  # breadth first: loops are cut at the joints farthest from a root
        nxt = []
        for b in frontier:
            for j in by_parent[b]:
                if j.child in reached:
                    cut.append(j)
                else:
                    reached.add(j.child)
                    chosen[b].append(j)
                    nxt.append(j.child)
        frontier = nxt
    _prefer_cuttable(chosen, cut, {id(j): k for k, j in enumerate(mech.joints)})
    tree: list[Joint] = []
    for root in roots:  # then depth first, in file order: MuJoCo's joint (and qpos) order
        stack = list(reversed(chosen[root]))
        while stack:
            j = stack.pop()
            tree.append(j)
            stack.extend(reversed(chosen[j.child]))
    order = {id(j): k for k, j in enumerate(mech.joints)}
    cut.sort(key=lambda j: order[id(j)])
    # bodies reachable only against joint directions are not reached: their joints are cuts
    # already, or they hang on an unreached body (a cycle without a root)
    missing = [b for b in mech.bodies if b not in reached]
    if missing:
        raise DescriptionError(
            mech.source,
            f"body '{missing[0]}'",
            "is on a cycle of joints that no root leads to (every body of the cycle is a "
            "joint's child); make one of them a root or reverse a joint",
        )
    return tree, cut


_CUT_KINDS = {"ball": "point", "revolute": "hinge", "fixed": "weld"}


def _prefer_cuttable(
    chosen: dict[str, list[Joint]], cut: list[Joint], order: dict[int, int]
) -> None:
    """Swap a cut joint that cannot close a loop (prismatic...) with the tree joint beside it.

    When a joint ``J`` that no closure can replace closes a loop at body ``c``, and the tree
    joint ``T`` that reached ``c`` can (ball, revolute, fixed), ``J`` joins the tree and ``T``
    closes the loop instead, unless ``J``'s parent hangs below ``c`` (the tree would cycle).
    """
    parent_joint = {j.child: j for joints in chosen.values() for j in joints}
    for J in [j for j in cut if j.kind not in _CUT_KINDS]:
        T = parent_joint.get(J.child)
        if T is None or T.kind not in _CUT_KINDS:
            continue
        below, stack = set(), [J.child]
        while stack:  # the subtree of c
            b = stack.pop()
            below.add(b)
            stack.extend(j.child for j in chosen.get(b, []))
        if J.parent in below:
            continue
        chosen[T.parent].remove(T)
        chosen[J.parent].append(J)
        chosen[J.parent].sort(key=lambda j: order[id(j)])
        parent_joint[J.child] = J
        cut[cut.index(J)] = T


def _cut_closure(mech: Mechanism, j: Joint) -> ClosureSpec:
    """Closure replacing a joint that closes a loop."""
    kinds = _CUT_KINDS
    if j.kind not in kinds:
        raise DescriptionError(
            mech.source,
            j.where or f"joint '{j.name}'",
            f"a {j.kind} joint closes a kinematic loop; pkdyn closes loops with ball, revolute "
            "or fixed joints only (make this joint part of the tree and cut the loop elsewhere)",
        )
    oMp = mech.bodies[j.parent].pose if j.parent != WORLD else pin.SE3.Identity()
    oMc = mech.bodies[j.child].pose
    f1 = FrameRef(j.parent if j.parent != WORLD else "universe", oMp.actInv(j.pose))
    f2 = FrameRef(j.child, oMc.actInv(j.pose))
    return ClosureSpec(j.name, kinds[j.kind], f1, f2, _unit(j.axis))


def build(mech: Mechanism) -> Built:
    """Pinocchio model, geometry and closures of a mechanism (see the module docstring).

    Args:
        mech: The mechanism.

    Returns:
        The built model.

    Raises:
        DescriptionError: Missing bodies, a loop closed by an unsupported joint kind, a cycle
            without root, non-orthogonal universal axes.

    """
    tree, cut = spanning_tree(mech)
    model = pin.Model()
    model.name = mech.name
    model.gravity = pin.Motion(np.asarray(mech.gravity, dtype=float), np.zeros(3))
    # each body's Pinocchio joint and its placement in that joint's frame
    where: dict[str, tuple[int, pin.SE3]] = {WORLD: (0, pin.SE3.Identity())}
    q_ref: list[tuple[int, np.ndarray]] = []
    joint_ids: dict[str, int] = {}
    body_frames: dict[str, int] = {}
    passive: list[PassiveSpec] = []
    for j in cut:
        if j.damping or j.friction or j.stiffness:
            warn(
                f"{mech.source}: joint '{j.name}' closes a loop (a closure): its damping, friction "
                "and spring are left out"
            )

    def pose(name: str) -> pin.SE3:
        return mech.bodies[name].pose if name != WORLD else pin.SE3.Identity()

    children = {j.child for j in mech.joints}
    for b in mech.bodies.values():  # roots without a parent joint: welded to the world
        if b.name not in children:
            where[b.name] = (0, b.pose)
    for j in tree:
        pj, pMb = where[j.parent]
        if j.kind == "fixed":
            where[j.child] = (pj, pMb * pose(j.parent).actInv(pose(j.child)))
            model.addFrame(
                pin.Frame(j.name, pj, pMb * pose(j.parent).actInv(j.pose), pin.FIXED_JOINT), False
            )
            continue
        jm = _joint_model(j, mech.source)
        qr = _neutral(jm) if j.q_ref is None else np.asarray(j.q_ref, dtype=float)
        placement = pMb * pose(j.parent).actInv(j.pose) * _motion(jm, qr).inverse()
        jMc = j.pose.actInv(pose(j.child))
        jid = model.addJoint(pj, jm, placement, j.name)
        joint_ids[j.name] = jid
        jm = model.joints[jid]
        sl_q = slice(jm.idx_q, jm.idx_q + jm.nq)
        sl_v = slice(jm.idx_v, jm.idx_v + jm.nv)
        if j.kind in ("revolute", "prismatic"):
            model.lowerPositionLimit[sl_q] = j.lower
            model.upperPositionLimit[sl_q] = j.upper
            model.effortLimit[sl_v] = j.effort
            model.velocityLimit[sl_v] = j.velocity
        for attr, value in (("damping", j.damping), ("friction", j.friction)):
            getattr(model, attr)[sl_v] = value
        model.armature[sl_v] = j.armature
        if j.damping or j.friction or j.stiffness:
            passive.append(_passive(j, jm))
        model.addFrame(pin.Frame(j.name, jid, pin.SE3.Identity(), pin.JOINT), False)
        where[j.child] = (jid, jMc)
        q_ref.append((jm.idx_q, qr))
    closures = list(mech.closures) + [_cut_closure(mech, j) for j in cut]
    referenced = {f.link for c in closures for f in (c.frame1, c.frame2)}
    for b in mech.bodies.values():
        jid, jMb = where[b.name]
        model.appendBodyToJoint(jid, b.inertia, jMb)
        if not b.virtual:
            body_frames[b.name] = model.addFrame(pin.Frame(b.name, jid, jMb, pin.BODY), False)
        elif b.name in referenced:  # an intermediate body a closure holds (a cut revolute2)
            model.addFrame(pin.Frame(b.name, jid, jMb, pin.OP_FRAME), False)
        for name, bMf in b.frames:
            model.addFrame(pin.Frame(name, jid, jMb * bMf, pin.OP_FRAME), False)
    q = pin.neutral(model)
    for i, qr in q_ref:
        q[i : i + qr.size] = qr
    visual, collision = pin.GeometryModel(), pin.GeometryModel()
    for b in mech.bodies.values():
        jid, jMb = where[b.name]
        fid = body_frames.get(b.name, 0)
        for gm, geoms in ((visual, b.visuals), (collision, b.collisions)):
            for g in geoms:
                go = pin.GeometryObject(
                    g.name, jid, fid, jMb * g.placement, g.shape, g.mesh_path, g.scale
                )
                go.meshColor = np.asarray(g.rgba, dtype=float)
                gm.addGeometryObject(go)
    cut_names = {j.name for j in cut}
    for c in mech.couplings:
        coupled = [j for j, _ in c.terms] if isinstance(c, LinearCouplingSpec) else [c.joint]
        if isinstance(c, CouplingSpec):
            coupled.append(c.source)  # type: ignore[arg-type]
        for jname in coupled:
            if jname in cut_names:
                raise DescriptionError(
                    mech.source,
                    f"coupling '{c.name}'",
                    f"joint '{jname}' closes a loop (it became a closure and has no coordinate); "
                    "a coupled joint must be a tree joint",
                )
    return Built(
        model,
        visual,
        collision,
        closures,
        q,
        joint_ids,
        [j.name for j in cut],
        passive,
        list(mech.couplings),
    )


def _passive(j: Joint, jm: pin.JointModel) -> PassiveSpec:
    """The joint's damping, friction and spring (rest: displacement from zero)."""
    rest: tuple[float, ...] = ()
    if j.stiffness:
        single = pin.Model()
        single.addJoint(0, jm, pin.SE3.Identity(), "j")
        qs = pin.neutral(single) if j.spring_ref is None else np.asarray(j.spring_ref, float)
        rest = tuple(float(x) for x in pin.difference(single, pin.neutral(single), qs))
    return PassiveSpec(
        j.name,
        stiffness=(float(j.stiffness),) if j.stiffness else (),
        rest=rest,
        damping=(float(j.damping),) if j.damping else (),
        friction=(float(j.friction),) if j.friction else (),
    )
