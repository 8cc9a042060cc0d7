"""MJCF export: a MuJoCo model of any loaded robot, and the map between the two state spaces.

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
``hinge`` the same two ``connect`` as its two Pinocchio point constraints. Joint couplings
become ``joint`` equalities named after the coupling (``joint1`` the driven joint, ``joint2``
the source, ``polycoef`` the polynomial re-expanded about ``qpos0 = 0``: MuJoCo's
``qpos - qpos0`` convention with the exported joints' zero ``ref``). Each actuator is a
``motor`` on its joint with ``gear`` = the transmission reduction, so its control is the
motor-side effort; ``ctrlrange`` and ``forcerange`` are the URDF (joint-side) effort limit
divided by the reduction. A keyframe ``home`` holds the assembled home configuration.

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

:class:`StateMap` converts states: Pinocchio stores quaternions ``(x, y, z, w)``, MuJoCo
``(w, x, y, z)``; a free-flyer's Pinocchio velocity is the body's spatial velocity in its own
frame, MuJoCo's has the linear part in world axes (``qvel_lin = R v_lin``, and
``qacc_lin = R (a_lin + w x v_lin)``); a planar joint likewise in the plane; ball velocities
are local angular velocities in both. Generalized forces map by power: ``f = T^T f_mj`` with
``qvel = T v``.
"""

from __future__ import annotations

import math
import os
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError, OutputError, PkdynError
from pkdyn.files import atomic_write
from pkdyn.model.robot import Robot
from solvers.coupling import MAX_COEFFICIENTS, JointCoupling
from solvers.numerics import lstsq, machine_rtol

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


@dataclass(frozen=True)
class JointMap:
    """Where one Pinocchio joint lives in both state vectors.

    Attributes:
        name: Pinocchio joint name.
        kind: ``hinge``, ``hinge_unbounded`` (Pinocchio stores cos, sin), ``slide``, ``ball``,
            ``free``, ``planar``, or ``multi`` (several 1-dof MuJoCo joints: universal,
            translation, spherical ZYX; coordinates shared one to one).
        idx_q: First Pinocchio configuration index.
        nq: Number of Pinocchio configuration coordinates.
        idx_v: First Pinocchio velocity index.
        nv: Number of velocity coordinates (equal in both).
        qpos: First MuJoCo ``qpos`` index.
        dof: First MuJoCo ``qvel`` index.
        mj_joints: Names of the MuJoCo joints, in order.

    """

    name: str
    kind: str
    idx_q: int
    nq: int
    idx_v: int
    nv: int
    qpos: int
    dof: int
    mj_joints: tuple[str, ...]


@dataclass
class _MjJoint:
    """One MuJoCo joint element to write."""

    name: str
    type: str
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    range: tuple[float, float] | None = None


def _num(x: float) -> str:
    """Shortest text that reads back as the same double."""
    text = repr(float(x))
    return text[:-2] if text.endswith(".0") else text


def _fmt(x: np.ndarray | list[float] | tuple[float, ...]) -> str:
    return " ".join(_num(v) for v in np.ravel(x))


def _quat_wxyz(R: np.ndarray) -> np.ndarray:
    c = pin.Quaternion(np.asarray(R, dtype=float)).coeffs()  # x y z w
    return np.array([c[3], c[0], c[1], c[2]])


def _placement(jm: pin.JointModel, v: np.ndarray) -> pin.SE3:
    """Joint placement ``M(q)`` at ``q = neutral (+) v`` (a copy).

    Axes are read from placements, not from the motion subspace ``jd.S``: Pinocchio 4.1 leaves
    some entries of a universal joint's ``S`` uninitialised.
    """
    m = pin.Model()
    m.addJoint(0, jm, pin.SE3.Identity(), "j")
    d = m.createData()
    pin.forwardKinematics(m, d, pin.integrate(m, pin.neutral(m), np.asarray(v, dtype=float)))
    return pin.SE3(d.oMi[1])


def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.linalg.norm(x)


def _joint_elements(model: pin.Model, jid: int, source: str) -> tuple[str, list[_MjJoint]]:
    """Kind (see :class:`JointMap`) and MuJoCo joint elements of Pinocchio joint ``jid``."""
    jm = model.joints[jid]
    name = model.names[jid]
    short = jm.shortname()
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit

    def limits(i: int) -> tuple[float, float] | None:
        a, b = float(lo[i]), float(hi[i])
        return (a, b) if math.isfinite(a) and math.isfinite(b) and a < b else None

    if short == "JointModelFreeFlyer":
        if model.parents[jid] != 0:
            raise DescriptionError(
                source,
                f"joint '{name}'",
                "a free-flyer joint must hang on the world to be exported to MuJoCo",
            )
        return "free", [_MjJoint(name, "free")]
    if short == "JointModelSpherical":
        return "ball", [_MjJoint(name, "ball")]
    if short.startswith(("JointModelRUB", "JointModelRevoluteUnbounded")):
        axis = _unit(pin.log3(_placement(jm, np.ones(1)).rotation))
        return "hinge_unbounded", [_MjJoint(name, "hinge", axis)]
    if short.startswith(("JointModelR", "JointModelRevolute")):
        axis = _unit(pin.log3(_placement(jm, np.ones(1)).rotation))
        return "hinge", [_MjJoint(name, "hinge", axis, limits(jm.idx_q))]
    if short.startswith(("JointModelP", "JointModelPrismatic")) and short != "JointModelPlanar":
        axis = _unit(_placement(jm, np.ones(1)).translation)
        return "slide", [_MjJoint(name, "slide", axis, limits(jm.idx_q))]
    if short == "JointModelUniversal":  # M(q1, 0) = exp(q1 axis1), M(0, q2) = exp(q2 axis2)
        axes = tuple(_unit(pin.log3(_placement(jm, e).rotation)) for e in np.eye(2))
        return "multi", [_MjJoint(f"{name}_{k + 1}", "hinge", a) for k, a in enumerate(axes)]
    if short == "JointModelPlanar":
        e = np.eye(3)
        return "planar", [
            _MjJoint(f"{name}_x", "slide", e[0]),
            _MjJoint(f"{name}_y", "slide", e[1]),
            _MjJoint(f"{name}_rz", "hinge", e[2]),
        ]
    if short == "JointModelTranslation":
        e = np.eye(3)
        return "multi", [
            _MjJoint(f"{name}_{c}", "slide", e[k], limits(jm.idx_q + k))
            for k, c in enumerate("xyz")
        ]
    if short == "JointModelSphericalZYX":
        e = np.eye(3)
        return "multi", [
            _MjJoint(f"{name}_{c}", "hinge", e[k], limits(jm.idx_q + i))
            for i, (k, c) in enumerate(((2, "z"), (1, "y"), (0, "x")))
        ]
    raise DescriptionError(
        source, f"joint '{name}'", f"{short} has no MuJoCo equivalent; it cannot be exported"
    )


def _body_names(model: pin.Model) -> list[str]:
    """MuJoCo body name of each joint: its child link's name (the first body frame on it)."""
    names = ["world"] + [""] * (model.njoints - 1)
    for f in model.frames:
        j = f.parentJoint
        if j > 0 and not names[j] and f.type == pin.FrameType.BODY:
            names[j] = f.name
    used: set[str] = {"world"}
    for j in range(1, model.njoints):
        base = names[j] or model.names[j]
        n, k = base, 1
        while n in used:
            n, k = f"{base}_{k}", k + 1
        names[j] = n
        used.add(n)
    return names


def _dfs(model: pin.Model) -> list[int]:
    """Joint ids in the depth-first order of the written body tree (MuJoCo's qpos order)."""
    children: dict[int, list[int]] = {j: [] for j in range(model.njoints)}
    for j in range(1, model.njoints):
        children[model.parents[j]].append(j)
    order: list[int] = []
    stack = list(reversed(children[0]))
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(reversed(children[j]))
    return order


class StateMap:
    """Conversion of states and forces between a robot's Pinocchio model and its MJCF export.

    Args:
        robot: The robot (its model decides the layout; no MuJoCo needed).

    Raises:
        DescriptionError: A joint has no MuJoCo equivalent.

    """

    def __init__(self, robot: Robot) -> None:
        model = robot.model
        self.model = model
        self.body_names = _body_names(model)
        self.order = _dfs(model)
        self.elements: dict[int, list[_MjJoint]] = {}
        joints: list[JointMap] = []
        qpos = dof = 0
        for j in self.order:
            kind, els = _joint_elements(model, j, robot.source)
            self.elements[j] = els
            jm = model.joints[j]
            names = tuple(e.name for e in els)
            joints.append(
                JointMap(model.names[j], kind, jm.idx_q, jm.nq, jm.idx_v, jm.nv, qpos, dof, names)
            )
            qpos += {"free": 7, "ball": 4}.get(kind, len(els))
            dof += jm.nv
        self._index(joints, qpos, dof)

    def _index(self, joints: list[JointMap], nq: int, nv: int) -> None:
        self.joints = tuple(joints)
        self.nq = nq
        self.nv = nv
        self._dof_of_v = np.empty(self.model.nv, dtype=int)
        for jm_ in joints:
            self._dof_of_v[jm_.idx_v : jm_.idx_v + jm_.nv] = np.arange(jm_.dof, jm_.dof + jm_.nv)
        self._nonlinear = [jm for jm in joints if jm.kind in ("free", "planar")]

    @classmethod
    def by_name(cls, robot: Robot, mj_model: Any) -> StateMap:
        """The map between a robot and a MuJoCo model of it pkdyn did not write.

        For a robot loaded from an MJCF file and the ``mujoco.MjModel`` of that file: joints
        are matched by name (each MuJoCo joint is a Pinocchio joint of the same name; the two
        joint orders may differ), ``qpos`` / ``qvel`` addresses are MuJoCo's. Coordinates
        then agree as pkdyn's MJCF importer writes them: a hinge or slide coordinate is
        MuJoCo's ``qpos`` itself (``ref`` included: the importer places the joint so that
        ``q = ref`` is the file's pose), a ball quaternion is reordered (MuJoCo ``w x y z``,
        Pinocchio ``x y z w``), a free joint's linear velocity is turned from world axes
        (MuJoCo) to the body's axes (Pinocchio).

        Args:
            robot: The robot.
            mj_model: The ``mujoco.MjModel``.

        Returns:
            The map (``qpos``, ``qvel``, ``qacc``, ``force`` and their inverses).

        Raises:
            DescriptionError: A MuJoCo joint has no Pinocchio joint of that name and kind, or
                a Pinocchio joint no MuJoCo one.

        """
        self = cls.__new__(cls)
        model = robot.model
        self.model = model
        self.body_names, self.order, self.elements = [], [], {}
        kinds = {0: ("free", 7, 6), 1: ("ball", 4, 3), 2: ("slide", 1, 1), 3: ("hinge", 1, 1)}
        joints: list[JointMap] = []
        for j in range(int(mj_model.njnt)):
            name = str(mj_model.joint(j).name)
            kind, nq, nv = kinds[int(mj_model.jnt_type[j])]
            jid = model.getJointId(name) if model.existJointName(name) else model.njoints
            jm = model.joints[jid] if jid < model.njoints else None
            if jm is None or jm.nq != nq or jm.nv != nv:
                raise DescriptionError(
                    robot.source,
                    f"MuJoCo joint '{name}'",
                    f"no Pinocchio {kind} joint of that name",
                )
            qpos, dof = int(mj_model.jnt_qposadr[j]), int(mj_model.jnt_dofadr[j])
            joints.append(JointMap(name, kind, jm.idx_q, nq, jm.idx_v, nv, qpos, dof, (name,)))
        if sum(jm.nv for jm in joints) != model.nv:
            raise DescriptionError(
                robot.source, "MuJoCo model", "its joints do not cover the robot's coordinates"
            )
        self._index(joints, int(mj_model.nq), int(mj_model.nv))
        return self

    def qpos(self, q: np.ndarray) -> np.ndarray:
        """MuJoCo ``qpos`` of a Pinocchio configuration ``q`` (nq,)."""
        out = np.empty(self.nq)
        for jm in self.joints:
            a, i = jm.qpos, jm.idx_q
            if jm.kind == "ball":
                out[a : a + 4] = q[i + 3], q[i], q[i + 1], q[i + 2]
            elif jm.kind == "free":
                M = self._free_placement(jm, q)
                out[a : a + 3] = M.translation
                out[a + 3 : a + 7] = _quat_wxyz(M.rotation)
            elif jm.kind == "hinge_unbounded":
                out[a] = math.atan2(q[i + 1], q[i])
            elif jm.kind == "planar":
                out[a : a + 3] = q[i], q[i + 1], math.atan2(q[i + 3], q[i + 2])
            else:
                out[a : a + jm.nq] = q[i : i + jm.nq]
        return out

    def q(self, qpos: np.ndarray) -> np.ndarray:
        """Pinocchio configuration of a MuJoCo ``qpos``."""
        model = self.model
        out = np.empty(model.nq)
        for jm in self.joints:
            a, i = jm.qpos, jm.idx_q
            if jm.kind == "ball":
                out[i : i + 4] = qpos[a + 1], qpos[a + 2], qpos[a + 3], qpos[a]
            elif jm.kind == "free":
                w, x, y, z = qpos[a + 3 : a + 7]
                oM = pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), qpos[a : a + 3])
                jid = model.getJointId(jm.name)
                M = model.jointPlacements[jid].actInv(oM)
                out[i : i + 7] = pin.SE3ToXYZQUAT(M)
            elif jm.kind == "hinge_unbounded":
                out[i : i + 2] = math.cos(qpos[a]), math.sin(qpos[a])
            elif jm.kind == "planar":
                th = qpos[a + 2]
                out[i : i + 4] = qpos[a], qpos[a + 1], math.cos(th), math.sin(th)
            else:
                out[i : i + jm.nq] = qpos[a : a + jm.nq]
        return out

    def _free_placement(self, jm: JointMap, q: np.ndarray) -> pin.SE3:
        jid = self.model.getJointId(jm.name)
        return self.model.jointPlacements[jid] * pin.XYZQUATToSE3(q[jm.idx_q : jm.idx_q + 7])

    def _rotations(self, q: np.ndarray) -> list[tuple[JointMap, np.ndarray]]:
        """World (free) or in-plane (planar) rotation of each joint whose velocity is remapped."""
        out = []
        for jm in self._nonlinear:
            if jm.kind == "free":
                out.append((jm, self._free_placement(jm, q).rotation))
            else:
                c, s = q[jm.idx_q + 2], q[jm.idx_q + 3]
                out.append((jm, np.array([[c, -s], [s, c]])))
        return out

    def velocity_matrix(self, q: np.ndarray) -> np.ndarray:
        """``T`` (nv_mj, nv) with ``qvel = T v`` at configuration ``q``."""
        T = np.zeros((self.nv, self.model.nv))
        T[self._dof_of_v, np.arange(self.model.nv)] = 1.0
        for jm, R in self._rotations(q):
            n = R.shape[0]
            T[jm.dof : jm.dof + n, jm.idx_v : jm.idx_v + n] = R
        return T

    def qvel(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """MuJoCo ``qvel`` of a Pinocchio velocity ``v`` (nv,) at ``q``."""
        out = np.empty(self.nv)
        out[self._dof_of_v] = v
        for jm, R in self._rotations(q):
            n = R.shape[0]
            out[jm.dof : jm.dof + n] = R @ v[jm.idx_v : jm.idx_v + n]
        return out

    def v(self, q: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """Pinocchio velocity of a MuJoCo ``qvel`` at the Pinocchio configuration ``q``."""
        out = np.asarray(qvel, dtype=float)[self._dof_of_v].copy()
        for jm, R in self._rotations(q):
            n = R.shape[0]
            out[jm.idx_v : jm.idx_v + n] = R.T @ qvel[jm.dof : jm.dof + n]
        return out

    def _coriolis(self, jm: JointMap, v: np.ndarray) -> np.ndarray:
        """``w x v_lin`` of a free-flyer or planar joint (local frame)."""
        i = jm.idx_v
        if jm.kind == "free":
            return np.cross(v[i + 3 : i + 6], v[i : i + 3])
        return v[i + 2] * np.array([-v[i + 1], v[i]])

    def qacc(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """MuJoCo ``qacc`` of a Pinocchio acceleration ``a`` at ``(q, v)``."""
        out = np.empty(self.nv)
        out[self._dof_of_v] = a
        for jm, R in self._rotations(q):
            n = R.shape[0]
            out[jm.dof : jm.dof + n] = R @ (a[jm.idx_v : jm.idx_v + n] + self._coriolis(jm, v))
        return out

    def a(self, q: np.ndarray, v: np.ndarray, qacc: np.ndarray) -> np.ndarray:
        """Pinocchio acceleration of a MuJoCo ``qacc`` at the Pinocchio state ``(q, v)``."""
        out = np.asarray(qacc, dtype=float)[self._dof_of_v].copy()
        for jm, R in self._rotations(q):
            n = R.shape[0]
            i = jm.idx_v
            out[i : i + n] = R.T @ qacc[jm.dof : jm.dof + n] - self._coriolis(jm, v)
        return out

    def force(self, q: np.ndarray, f_mj: np.ndarray) -> np.ndarray:
        """Pinocchio generalized force of a MuJoCo one (``qfrc_*``): ``T^T f_mj`` (same power)."""
        out = np.asarray(f_mj, dtype=float)[self._dof_of_v].copy()
        for jm, R in self._rotations(q):
            n = R.shape[0]
            out[jm.idx_v : jm.idx_v + n] = R.T @ f_mj[jm.dof : jm.dof + n]
        return out


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
        PkdynError: Invalid options.

    """
    opt = options or MjcfOptions()
    if not opt.timestep > 0.0:
        raise PkdynError(f"MJCF timestep must be > 0, got {opt.timestep}")
    model = robot.model
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
        _inertial(body, model.inertias[j])
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
    for c in robot.closure_set.couplings:
        attrs = {"name": c.name, "joint1": model.names[c.joint]}
        if c.source is not None:
            attrs["joint2"] = model.names[c.source]
        _sub(equality, "joint", polycoef=_fmt(_polycoef(c)), **attrs)
    if len(equality) == 0:
        root.remove(equality)
    _tendons(root, robot, elements)
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


# ---------------------------------------------------------------------------------- MuJoCo side


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


def actuator_efforts(model: Any, data: Any) -> np.ndarray:
    """Actuator forces that explain MuJoCo's inverse dynamics through the closures.

    The least-squares solution of ``[moment^T  J_eq^T] [tau; lambda] = qfrc_inverse`` after
    ``mujoco.mj_inverse``, with ``J_eq`` the rows of MuJoCo's constraint Jacobian that belong to
    equality constraints (the closures) and ``moment`` the actuator moment arm (the gears).
    Unique when the actuation is not redundant, whatever the redundancy of the closure rows.

    Args:
        model: The ``mujoco.MjModel``.
        data: Its ``mujoco.MjData`` after ``mj_inverse``.

    Returns:
        Actuator forces (nu,) in actuation space (motor-side efforts for geared motors).

    """
    import mujoco

    nv, nefc = model.nv, data.nefc
    if mujoco.mj_isSparse(model):
        J = np.zeros((nefc, nv))
        mujoco.mju_sparse2dense(
            J, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind
        )
    else:
        J = np.asarray(data.efc_J).reshape(-1)[: nefc * nv].reshape(nefc, nv)
    eq = np.asarray(data.efc_type[:nefc]) == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    moment = np.zeros((model.nu, nv))
    mujoco.mju_sparse2dense(
        moment, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind
    )
    A = np.hstack([moment.T, J[eq].T])
    x = lstsq(A, np.asarray(data.qfrc_inverse), machine_rtol(A))
    return np.asarray(x[: model.nu])
