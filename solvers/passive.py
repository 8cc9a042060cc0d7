r"""Passive elements: joint springs, viscous dampers, Coulomb friction and two-frame springs.

Generalized forces on the velocity coordinates of a Pinocchio model, with their potential
energy and the power they dissipate, for the forward and inverse dynamics and the statics.

Per joint, per degree of freedom (the velocity coordinates of the joint):

- a linear **spring** of stiffness ``K`` (diagonal, nv values) about a rest configuration
  ``q_r``: with the deviation ``d = difference(q_r, q)`` (nv,) (``q - q_r`` on revolute,
  prismatic and universal joints; the rotation vector ``log3(R_r^T R)`` in the child frame on a
  spherical joint, as MuJoCo's ball-joint spring),

  .. math::

      V = \tfrac12\, d^T K d, \qquad f_s = -\left(\frac{\partial d}{\partial v}\right)^T K d

  (``dDifference``: the exact gradient on any joint; ``-K d`` itself on vector-space joints
  and on an isotropic spherical spring);
- **viscous damping** ``f_d = -c v`` and smooth **Coulomb friction**
  ``f_c = -f_0 \tanh(v / v_s)`` (``v_s``: the smoothing speed), dissipating
  ``c v^2 + f_0 v \tanh(v / v_s) >= 0``.

Between two frames on two bodies (:class:`FrameSpring`): a linear spring along the line
joining the two points ``p_1``, ``p_2``, of stiffness ``k`` and free length ``L_0`` (negative for
an extension spring with initial tension): tension
``T = k (L - L_0)`` (positive: pulls the points together), potential
``\tfrac12 k (L - L_0)^2``, generalized force ``f = -T (\partial L / \partial q)^T`` with
``\dot L = u^T (\dot p_2 - \dot p_1)``, ``u = (p_2 - p_1) / L``. ``L_0 = 0`` gives the
zero-free-length spring of gravity balancing (its force ``k (p_2 - p_1)`` on body 1 stays
defined at ``L = 0``).

Units: SI; stiffness [N m/rad or N/m], damping [N m s/rad or N s/m], friction [N m or N].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

__all__ = ["FrameSpring", "PassiveForces"]


@dataclass(frozen=True)
class FrameSpring:
    """A linear spring between two points on two bodies.

    Attributes:
        joint1: Joint (body) id of the first point (0: the world).
        placement1: Frame of the first point in that joint's frame.
        joint2: Joint (body) id of the second point.
        placement2: Frame of the second point in that joint's frame.
        stiffness: ``k`` [N/m], >= 0.
        rest_length: Free length ``L_0`` [m]; negative for an extension spring with an initial
            tension ``T_i`` (free length ``L_f``): ``L_0 = L_f - T_i / k``.
        name: Name, for messages.

    """

    joint1: int
    placement1: pin.SE3
    joint2: int
    placement2: pin.SE3
    stiffness: float
    rest_length: float = 0.0
    name: str = ""


_WORLD = ([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [0.0, 0.0, 0.0])
"""Rotation rows and translation of the world frame (joint 0), as Python floats."""


def _xyz(M: pin.SE3) -> list[float]:
    return [float(v) for v in M.translation]


def _per_v(x: float | Sequence[float] | np.ndarray | None, nv: int, what: str) -> np.ndarray:
    if x is None:
        return np.zeros(nv)
    out = np.array(np.broadcast_to(np.asarray(x, dtype=float), (nv,)))
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{what} must be finite, got {out.tolist()}")
    if np.any(out < 0.0):
        k = int(np.flatnonzero(out < 0.0)[0])
        raise ValueError(f"{what} must be >= 0, got {out[k]} at velocity index {k}")
    return out


class PassiveForces:
    """Springs, dampers and Coulomb friction of a model (see the module docstring).

    Args:
        model: The kinematic tree.
        stiffness: Joint stiffness per velocity coordinate, scalar or (nv,)
            [N m/rad or N/m] (default: none).
        rest: Rest configuration of the joint springs (nq,) (default: ``pin.neutral``).
        damping: Viscous coefficients, scalar or (nv,) [N m s/rad or N s/m] (default: none).
        friction: Coulomb levels, scalar or (nv,) [N m or N] (default: none).
        smoothing: Speed ``v_s`` at which the friction reaches 76 % of its level
            [rad/s or m/s].
        springs: Springs between two frames.

    Raises:
        ValueError: Negative or non-finite coefficients, sizes that do not match, a joint id out
            of range.

    """

    _data: pin.Data | None

    @property
    def data(self) -> pin.Data:
        """The Pinocchio data of the two-frame springs' kinematics (made on first use)."""
        if self._data is None:
            self._data = self.model.createData()
        return self._data

    def __init__(
        self,
        model: pin.Model,
        stiffness: float | Sequence[float] | np.ndarray | None = None,
        rest: Sequence[float] | np.ndarray | None = None,
        damping: float | Sequence[float] | np.ndarray | None = None,
        friction: float | Sequence[float] | np.ndarray | None = None,
        smoothing: float = 1e-2,
        springs: Sequence[FrameSpring] = (),
    ) -> None:
        nv = model.nv
        self.model = model
        self._data = None  # made on first use (nv^3 in size)
        self.stiffness = _per_v(stiffness, nv, "stiffness")
        self.damping = _per_v(damping, nv, "damping")
        self.friction = _per_v(friction, nv, "friction")
        if not smoothing > 0.0:
            raise ValueError(f"friction smoothing must be > 0, got {smoothing}")
        self.smoothing = float(smoothing)
        q_rest = pin.neutral(model) if rest is None else np.asarray(rest, dtype=float)
        if q_rest.shape != (model.nq,) or not np.all(np.isfinite(q_rest)):
            raise ValueError(f"rest configuration: expected {model.nq} finite values")
        self.rest = q_rest.copy()
        for s in springs:
            for j in (s.joint1, s.joint2):
                if not 0 <= j < model.njoints:
                    raise ValueError(f"spring '{s.name}': joint id {j} out of range")
            if not (np.isfinite(s.stiffness) and s.stiffness >= 0.0):
                raise ValueError(f"spring '{s.name}': stiffness must be finite and >= 0")
            if not np.isfinite(s.rest_length):
                raise ValueError(f"spring '{s.name}': rest length must be finite")
        self.springs = tuple(springs)
        self._live = [s for s in self.springs if s.stiffness > 0.0]
        self._ends = [
            (s.joint1, _xyz(s.placement1), s.joint2, _xyz(s.placement2)) for s in self._live
        ]
        self._moving = sorted({j for s in self._live for j in (s.joint1, s.joint2) if j})
        self._force_zero = pin.Force.Zero()
        self._zero = np.zeros(nv)
        self._fext = pin.StdVec_Force()
        for _ in range(model.njoints):
            self._fext.append(pin.Force.Zero())
        self._free: tuple[pin.Model, pin.Data] | None = None  # gravity-free copy, on first use
        # joint springs: vector-space coordinates (nq == nv: q - q_r) vectorised, the others
        # (spherical, free-flyer, planar, unbounded revolute) through pin.difference and
        # pin.dDifference of the whole model, restricted to their velocity coordinates
        lin_q: list[int] = []
        lin_v: list[int] = []
        curved_v: list[int] = []
        for j in range(1, model.njoints):
            jm = model.joints[j]
            iv = range(jm.idx_v, jm.idx_v + jm.nv)
            if not np.any(self.stiffness[jm.idx_v : jm.idx_v + jm.nv]):
                continue
            if jm.nq == jm.nv:
                lin_q.extend(range(jm.idx_q, jm.idx_q + jm.nq))
                lin_v.extend(iv)
            else:
                curved_v.extend(iv)
        self._curved = np.array(curved_v, dtype=int)
        self._curved_K = self.stiffness[self._curved]
        self._curved_block = np.ix_(self._curved, self._curved)
        self._lin_q = np.array(lin_q, dtype=int)
        self._lin_v = np.array(lin_v, dtype=int)
        self._lin_K = self.stiffness[self._lin_v]
        self._lin_rest = q_rest[self._lin_q]
        self._dissipative = bool(np.any(self.damping) or np.any(self.friction))

    # ------------------------------------------------------------------ properties

    @property
    def nv(self) -> int:
        """Size of the velocity vector."""
        return int(self.model.nv)

    @property
    def conservative(self) -> bool:
        """No damping and no friction: springs only."""
        return not self._dissipative

    @property
    def empty(self) -> bool:
        """No passive element at all."""
        return not (self._dissipative or self._lin_v.size or self._curved.size or self._live)

    # ------------------------------------------------------------------ joint springs

    def deviation(self, q: np.ndarray) -> np.ndarray:
        """Spring deviation ``d = difference(q_r, q)`` (nv,) (zero where no joint spring)."""
        d = np.zeros(self.model.nv)
        d[self._lin_v] = q[self._lin_q] - self._lin_rest
        if self._curved.size:
            d[self._curved] = pin.difference(self.model, self.rest, q)[self._curved]
        return d

    def _joint_spring(self, q: np.ndarray, f: np.ndarray) -> float:
        """Add the joint springs' force to ``f`` (nv,); return their potential energy [J]."""
        energy = 0.0
        if self._lin_v.size:
            d = q[self._lin_q] - self._lin_rest
            Kd = self._lin_K * d
            f[self._lin_v] -= Kd
            energy += 0.5 * float(d @ Kd)
        if self._curved.size:
            energy += self._curved_spring(q, f)
        return energy

    def _curved_spring(self, q: np.ndarray, f: np.ndarray) -> float:
        c = self._curved
        d = pin.difference(self.model, self.rest, q)[c]
        Kd = self._curved_K * d
        D = pin.dDifference(self.model, self.rest, q, pin.ArgumentPosition.ARG1)[self._curved_block]
        f[c] -= D.T.dot(Kd)
        return 0.5 * float(d @ Kd)

    # ------------------------------------------------------------------ two-frame springs

    def spring_state(self, q: np.ndarray) -> list[tuple[float, float]]:
        """Length [m] and tension [N] of each two-frame spring at ``q``."""
        model, data = self.model, self.data
        pin.forwardKinematics(model, data, q)
        out = []
        for s in self.springs:
            p1 = data.oMi[s.joint1].act(s.placement1.translation)
            p2 = data.oMi[s.joint2].act(s.placement2.translation)
            L = float(np.linalg.norm(p2 - p1))
            out.append((L, s.stiffness * (L - s.rest_length)))
        return out

    def _frame_springs(self, q: np.ndarray, f: np.ndarray) -> float:
        """Add the two-frame springs' force to ``f``; return their potential energy [J].

        The generalized force of the end forces ``sum J_i^T F_i`` is ``-rnea(q, 0, 0, fext)``
        on a copy of the model without gravity (``fext``: the wrenches in the joints' frames).
        The few 3-vectors of each spring are handled as Python floats, unrolled: for a handful
        of springs that is several times faster than numpy's small-array calls.
        """
        if not self._live:
            return 0.0
        pin.forwardKinematics(self.model, self.data, q)
        oMi = self.data.oMi
        frames = {}  # joint -> (rotation rows, translation) as Python floats
        for j in self._moving:
            M = oMi[j]
            frames[j] = (M.rotation.tolist(), M.translation.tolist())
        world = _WORLD
        wrenches: dict[int, list[float]] = {}
        energy = 0.0
        for s, (j1, r1, j2, r2) in zip(self._live, self._ends, strict=True):
            (a, t1), (b, t2) = frames.get(j1, world), frames.get(j2, world)
            x1, y1, z1 = r1
            x2, y2, z2 = r2
            p1x = a[0][0] * x1 + a[0][1] * y1 + a[0][2] * z1 + t1[0]
            p1y = a[1][0] * x1 + a[1][1] * y1 + a[1][2] * z1 + t1[1]
            p1z = a[2][0] * x1 + a[2][1] * y1 + a[2][2] * z1 + t1[2]
            dx = b[0][0] * x2 + b[0][1] * y2 + b[0][2] * z2 + t2[0] - p1x
            dy = b[1][0] * x2 + b[1][1] * y2 + b[1][2] * z2 + t2[1] - p1y
            dz = b[2][0] * x2 + b[2][1] * y2 + b[2][2] * z2 + t2[2] - p1z
            L = math.sqrt(dx * dx + dy * dy + dz * dz)
            stretch = L - s.rest_length
            energy += 0.5 * s.stiffness * stretch * stretch
            if L == 0.0:
                if s.rest_length == 0.0:
                    continue
                raise ValueError(f"spring '{s.name}': both ends coincide, its direction is lost")
            c = s.stiffness * stretch / L
            Fx, Fy, Fz = c * dx, c * dy, c * dz  # on body 1, towards the second end
            for j, R, (rx, ry, rz), sign in ((j1, a, r1, 1.0), (j2, b, r2, -1.0)):
                if not j:
                    continue
                fx = sign * (R[0][0] * Fx + R[1][0] * Fy + R[2][0] * Fz)  # R^T F
                fy = sign * (R[0][1] * Fx + R[1][1] * Fy + R[2][1] * Fz)
                fz = sign * (R[0][2] * Fx + R[1][2] * Fy + R[2][2] * Fz)
                w = wrenches.get(j)
                if w is None:
                    w = wrenches[j] = [0.0] * 6
                w[0] += fx
                w[1] += fy
                w[2] += fz
                w[3] += ry * fz - rz * fy
                w[4] += rz * fx - rx * fz
                w[5] += rx * fy - ry * fx
        fext = self._fext
        for j, w in wrenches.items():
            fext[j] = pin.Force(np.array(w))
        if self._free is None:  # gravity-free copy: rnea gives -J^T F
            free = pin.Model(self.model)
            free.gravity = pin.Motion.Zero()
            self._free = (free, free.createData())
        f -= pin.rnea(self._free[0], self._free[1], q, self._zero, self._zero, fext)
        for j in wrenches:
            fext[j] = self._force_zero
        return energy

    # ------------------------------------------------------------------ totals

    def conservative_force(self, q: np.ndarray) -> np.ndarray:
        """Generalized force (nv,) of all springs at ``q`` [N m or N]."""
        f = np.zeros(self.model.nv)
        self._joint_spring(q, f)
        self._frame_springs(q, f)
        return f

    def dissipative_force(self, v: np.ndarray) -> np.ndarray:
        """Generalized force (nv,) of the dampers and the friction at ``v`` [N m or N]."""
        return -(self.damping * v + self.friction * np.tanh(v / self.smoothing))

    def force(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Generalized force (nv,) of every passive element at ``(q, v)`` [N m or N]."""
        f = self.conservative_force(q)
        if self._dissipative:
            f += self.dissipative_force(v)
        return f

    def evaluate(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, float]:
        """Generalized force (nv,) and dissipated power [W] at ``(q, v)`` (one pass)."""
        f = self.conservative_force(q)
        if not self._dissipative:
            return f, 0.0
        fd = self.dissipative_force(v)
        return f + fd, -float(fd @ v)

    def potential(self, q: np.ndarray) -> float:
        """Potential energy of every spring at ``q`` [J] (zero at the rest positions)."""
        f = np.zeros(self.model.nv)
        return self._joint_spring(q, f) + self._frame_springs(q, f)

    def dissipation(self, v: np.ndarray) -> float:
        """Power dissipated by the dampers and the friction at ``v`` [W] (>= 0)."""
        if not self._dissipative:
            return 0.0
        return -float(self.dissipative_force(v) @ v)

    def forces(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Generalized forces (N, nv) along a series of states ``q`` (N, nq), ``v`` (N, nv)."""
        q, v = np.atleast_2d(q), np.atleast_2d(v)
        out = np.zeros((q.shape[0], self.model.nv))
        if self._lin_v.size:
            out[:, self._lin_v] = -self._lin_K * (q[:, self._lin_q] - self._lin_rest)
        if self._curved.size or self._live:
            for k in range(q.shape[0]):
                f = out[k]
                if self._curved.size:
                    self._curved_spring(q[k], f)
                self._frame_springs(q[k], f)
        if self._dissipative:
            out += self.dissipative_force(v)
        return out

    def potentials(self, q: np.ndarray) -> np.ndarray:
        """Potential energy of the springs (N,) [J] along configurations ``q`` (N, nq)."""
        q = np.atleast_2d(q)
        return np.array([self.potential(qk) for qk in q])

    def dissipations(self, v: np.ndarray) -> np.ndarray:
        """Dissipated power (N,) [W] along velocities ``v`` (N, nv)."""
        v = np.atleast_2d(v)
        if not self._dissipative:
            return np.zeros(v.shape[0])
        return np.sum(self.damping * v**2 + self.friction * v * np.tanh(v / self.smoothing), 1)
