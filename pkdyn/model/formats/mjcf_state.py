"""The map between a robot's Pinocchio state and MuJoCo's: joints, ``qpos``, ``qvel``, forces.

Used by the MJCF export (:mod:`~pkdyn.model.formats.mjcf`) and by every comparison with MuJoCo.
Each Pinocchio joint becomes MuJoCo joints as follows (MuJoCo names in brackets):

- revolute (bounded or not, aligned or not) -> ``hinge`` [name]; prismatic -> ``slide`` [name];
- spherical -> ``ball`` [name]; free-flyer -> ``free`` [name] (on a body of the world only);
- universal(axis1, axis2) -> two hinges in one body [name_1, name_2] (MuJoCo applies the joints
  of a body in order, each axis in the frame moved by the previous ones, as Pinocchio does);
- planar -> slide x, slide y, hinge z [name_x, name_y, name_rz]; translation -> three slides;
  spherical ZYX -> three hinges z, y, x;
- composite of revolute and prismatic joints without placements between them -> their hinges
  and slides in one body, in order [name_tx, name_ry... along a frame axis, else name_1,
  name_2...] (e.g. the six joints of a compliant link's virtual spring in the elastic model's
  export, :mod:`pkdyn.precision.vibration_mjcf`).

:class:`StateMap` converts states: Pinocchio stores quaternions ``(x, y, z, w)``, MuJoCo
``(w, x, y, z)``; a free-flyer's Pinocchio velocity is the body's spatial velocity in its own
frame, MuJoCo's has the linear part in world axes (``qvel_lin = R v_lin``, and
``qacc_lin = R (a_lin + w x v_lin)``); a planar joint likewise in the plane; ball velocities
are local angular velocities in both. Generalized forces map by power: ``f = T^T f_mj`` with
``qvel = T v``. :meth:`StateMap.by_name` maps a robot imported from an MJCF file to the MuJoCo
model of that file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError
from pkdyn.model.robot import Robot

__all__ = ["JointMap", "MjJoint", "StateMap", "quat_wxyz"]


def quat_wxyz(R: np.ndarray) -> np.ndarray:
    """MuJoCo's quaternion ``(w, x, y, z)`` of a rotation matrix (3, 3)."""
    c = pin.Quaternion(np.asarray(R, dtype=float)).coeffs()  # x y z w
    return np.array([c[3], c[0], c[1], c[2]])


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
class MjJoint:
    """One MuJoCo joint element of a Pinocchio joint (name, type, axis, range)."""

    name: str
    type: str
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    range: tuple[float, float] | None = None


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


def _joint_elements(model: pin.Model, jid: int, source: str) -> tuple[str, list[MjJoint]]:
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
        return "free", [MjJoint(name, "free")]
    if short == "JointModelSpherical":
        return "ball", [MjJoint(name, "ball")]
    if short.startswith(("JointModelRUB", "JointModelRevoluteUnbounded")):
        axis = _unit(pin.log3(_placement(jm, np.ones(1)).rotation))
        return "hinge_unbounded", [MjJoint(name, "hinge", axis)]
    if short.startswith(("JointModelR", "JointModelRevolute")):
        axis = _unit(pin.log3(_placement(jm, np.ones(1)).rotation))
        return "hinge", [MjJoint(name, "hinge", axis, limits(jm.idx_q))]
    if short.startswith(("JointModelP", "JointModelPrismatic")) and short != "JointModelPlanar":
        axis = _unit(_placement(jm, np.ones(1)).translation)
        return "slide", [MjJoint(name, "slide", axis, limits(jm.idx_q))]
    if short == "JointModelUniversal":  # M(q1, 0) = exp(q1 axis1), M(0, q2) = exp(q2 axis2)
        axes = tuple(_unit(pin.log3(_placement(jm, e).rotation)) for e in np.eye(2))
        return "multi", [MjJoint(f"{name}_{k + 1}", "hinge", a) for k, a in enumerate(axes)]
    if short == "JointModelPlanar":
        e = np.eye(3)
        return "planar", [
            MjJoint(f"{name}_x", "slide", e[0]),
            MjJoint(f"{name}_y", "slide", e[1]),
            MjJoint(f"{name}_rz", "hinge", e[2]),
        ]
    if short == "JointModelTranslation":
        e = np.eye(3)
        return "multi", [
            MjJoint(f"{name}_{c}", "slide", e[k], limits(jm.idx_q + k)) for k, c in enumerate("xyz")
        ]
    if short == "JointModelComposite":
        return "multi", _composite_elements(jm, name, source)
    if short == "JointModelSphericalZYX":
        e = np.eye(3)
        return "multi", [
            MjJoint(f"{name}_{c}", "hinge", e[k], limits(jm.idx_q + i))
            for i, (k, c) in enumerate(((2, "z"), (1, "y"), (0, "x")))
        ]
    raise DescriptionError(
        source, f"joint '{name}'", f"{short} has no MuJoCo equivalent; it cannot be exported"
    )


def _composite_elements(jm: pin.JointModel, name: str, source: str) -> list[MjJoint]:
    """Hinges and slides of a composite of 1-DoF revolute and prismatic joints."""
    out: list[MjJoint] = []
    axes = np.eye(3)
    composite = jm.extract() if hasattr(jm, "extract") else jm
    for k, (sub, M) in enumerate(zip(composite.joints, composite.jointPlacements, strict=True)):
        short = sub.shortname()
        revolute = short.startswith(("JointModelR", "JointModelRevolute")) and not short.startswith(
            ("JointModelRUB", "JointModelRevoluteUnbounded")
        )
        prismatic = short.startswith(("JointModelP", "JointModelPrismatic")) and short != (
            "JointModelPlanar"
        )
        if not (revolute or prismatic) or not M.isIdentity():
            raise DescriptionError(
                source,
                f"joint '{name}'",
                "a composite joint is exported only as revolute and prismatic joints without "
                f"placements between them ({short} at part {k + 1})",
            )
        if revolute:
            axis = _unit(pin.log3(_placement(sub, np.ones(1)).rotation))
        else:
            axis = _unit(_placement(sub, np.ones(1)).translation)
        along = [i for i in range(3) if np.allclose(axis, axes[i], rtol=0.0, atol=1e-15)]
        tag = f"{'r' if revolute else 't'}{'xyz'[along[0]]}" if along else f"{k + 1}"
        if any(e.name == f"{name}_{tag}" for e in out):
            tag = f"{k + 1}"
        out.append(MjJoint(f"{name}_{tag}", "hinge" if revolute else "slide", axis))
    return out


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
        self.elements: dict[int, list[MjJoint]] = {}
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
                out[a + 3 : a + 7] = quat_wxyz(M.rotation)
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
        return self._transposed(q, qvel)

    def _transposed(self, q: np.ndarray, x_mj: np.ndarray) -> np.ndarray:
        """``T^T x_mj`` (nv,) of a MuJoCo dof vector (nv_mj,): ``T`` of :meth:`velocity_matrix`.

        ``T`` is orthogonal on each remapped joint, so this inverts ``qvel = T v`` and maps a
        MuJoCo generalized force to the Pinocchio one of the same power.
        """
        x_mj = np.asarray(x_mj, dtype=float)
        out = x_mj[self._dof_of_v].copy()
        for jm, R in self._rotations(q):
            n = R.shape[0]
            out[jm.idx_v : jm.idx_v + n] = R.T @ x_mj[jm.dof : jm.dof + n]
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
        return self._transposed(q, f_mj)
