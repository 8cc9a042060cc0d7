"""Forward kinematics and world Jacobians of many configurations at once, with numpy.

Pinocchio computes one configuration per call; from Python, reading its results (one
``SE3`` object per joint) costs more than the computation. :class:`BatchKinematics` runs the
same recursion over a batch of configurations with numpy, joint after joint:

    ``oMi_j = oMi_parent(j) jointPlacement_j X_J(q_j)``,
    ``J_w[:, v_j] = X(oMi_j) S_j(q_j)``

(``X``: the action of a placement on spatial motions, world axes at the world origin, as
Pinocchio's ``computeJointJacobians`` leaves ``data.J``; ``S_j``: the joint's motion subspace in
its own frame). Joint models: revolute (about x, y, z or any axis, bounded or unbounded),
prismatic (x, y, z or any axis), spherical (quaternion), free-flyer, planar, translation and
universal. On any other joint, or when a check against Pinocchio at a random configuration fails
at construction, :attr:`BatchKinematics.supported` is false and the caller uses Pinocchio.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

__all__ = ["BatchKinematics"]

_AXES = {"X": 0, "Y": 1, "Z": 2}
_CHECK_TOL = 1e-11


def _rotation(axis: np.ndarray, c: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Rotations (n, 3, 3) about a unit ``axis`` (3,) of cosines ``c`` and sines ``s`` (n,)."""
    K = np.array(
        [[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]]
    )
    K2 = K @ K
    return np.eye(3) + s[:, None, None] * K + (1.0 - c)[:, None, None] * K2


def _quaternion(x: np.ndarray) -> np.ndarray:
    """Rotations (n, 3, 3) of quaternions (n, 4) stored ``x, y, z, w`` (Eigen's formula)."""
    qx, qy, qz, qw = x[:, 0], x[:, 1], x[:, 2], x[:, 3]
    R = np.empty((x.shape[0], 3, 3))
    R[:, 0, 0] = 1.0 - 2.0 * (qy * qy + qz * qz)
    R[:, 0, 1] = 2.0 * (qx * qy - qz * qw)
    R[:, 0, 2] = 2.0 * (qx * qz + qy * qw)
    R[:, 1, 0] = 2.0 * (qx * qy + qz * qw)
    R[:, 1, 1] = 1.0 - 2.0 * (qx * qx + qz * qz)
    R[:, 1, 2] = 2.0 * (qy * qz - qx * qw)
    R[:, 2, 0] = 2.0 * (qx * qz - qy * qw)
    R[:, 2, 1] = 2.0 * (qy * qz + qx * qw)
    R[:, 2, 2] = 1.0 - 2.0 * (qx * qx + qy * qy)
    return R


# A joint: q (n, nq_j) -> (R (n, 3, 3) or None, p (n, 3) or None, S (n or 1, 6, nv_j))
JointFn = Callable[[np.ndarray], tuple[np.ndarray | None, np.ndarray | None, np.ndarray]]


def _constant(S: np.ndarray) -> np.ndarray:
    return S[None]


def _joint(jm: pin.JointModel) -> JointFn | None:
    """The local transform and motion subspace of a Pinocchio joint model (``None``: unknown)."""
    name = jm.shortname()
    e = np.eye(3)
    if name in ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned"):
        axis = e[_AXES[name[-1]]] if name[-1] in _AXES else np.array(jm.axis, dtype=float)
        S = _constant(np.concatenate([np.zeros(3), axis])[:, None])
        return lambda q: (_rotation(axis, np.cos(q[:, 0]), np.sin(q[:, 0])), None, S)
    if name in (
        "JointModelRUBX",
        "JointModelRUBY",
        "JointModelRUBZ",
        "JointModelRevoluteUnboundedUnaligned",
    ):
        axis = e[_AXES[name[-1]]] if name[-1] in _AXES else np.array(jm.axis, dtype=float)
        S = _constant(np.concatenate([np.zeros(3), axis])[:, None])
        return lambda q: (_rotation(axis, q[:, 0], q[:, 1]), None, S)
    if name in ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned"):
        axis = e[_AXES[name[-1]]] if name[-1] in _AXES else np.array(jm.axis, dtype=float)
        S = _constant(np.concatenate([axis, np.zeros(3)])[:, None])
        return lambda q: (None, q[:, :1] * axis, S)
    if name == "JointModelSpherical":
        S = _constant(np.vstack([np.zeros((3, 3)), e]))
        return lambda q: (_quaternion(q), None, S)
    if name == "JointModelFreeFlyer":
        S = _constant(np.eye(6))
        return lambda q: (_quaternion(q[:, 3:]), q[:, :3], S)
    if name == "JointModelTranslation":
        S = _constant(np.vstack([e, np.zeros((3, 3))]))
        return lambda q: (None, q, S)
    if name == "JointModelPlanar":
        S = _constant(np.array([[1.0, 0, 0], [0, 1, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 1]]))

        def planar(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            p = np.zeros((q.shape[0], 3))
            p[:, :2] = q[:, :2]
            return _rotation(e[2], q[:, 2], q[:, 3]), p, S

        return planar
    if name == "JointModelUniversal":
        a1, a2 = np.array(jm.axis1, dtype=float), np.array(jm.axis2, dtype=float)

        def universal(q: np.ndarray) -> tuple[np.ndarray, None, np.ndarray]:
            R1 = _rotation(a1, np.cos(q[:, 0]), np.sin(q[:, 0]))
            R2 = _rotation(a2, np.cos(q[:, 1]), np.sin(q[:, 1]))
            S = np.zeros((q.shape[0], 6, 2))
            S[:, 3:, 0] = np.einsum("nji,j->ni", R2, a1)  # R2^T a1
            S[:, 3:, 1] = a2
            return R1 @ R2, None, S

        return universal
    return None


class BatchKinematics:
    """Placements and world Jacobians of a batch of configurations (module doc).

    Args:
        model: The kinematic tree.

    Attributes:
        supported: Every joint is handled and the check against Pinocchio passed.

    """

    def __init__(self, model: pin.Model) -> None:
        self.model = model
        self._joints: list[tuple[int, int, int, int, int, np.ndarray, JointFn]] = []
        self.supported = True
        for j in range(1, model.njoints):
            jm = model.joints[j]
            fn = _joint(jm)
            if fn is None:
                self.supported = False
                return
            self._joints.append(
                (
                    j,
                    int(model.parents[j]),
                    jm.idx_q,
                    jm.idx_q + jm.nq,
                    jm.idx_v,
                    model.jointPlacements[j].homogeneous,
                    fn,
                )
            )
        self.supported = self._check()

    def _check(self) -> bool:
        model = self.model
        rng = np.random.default_rng(0)
        q = pin.integrate(model, pin.neutral(model), rng.standard_normal(model.nv))
        data = model.createData()
        pin.computeJointJacobians(model, data, q)
        H, Jw = self.placements_and_jacobians(q[None])
        ref = np.array([data.oMi[j].homogeneous for j in range(model.njoints)])
        return bool(
            np.abs(H[0] - ref).max() <= _CHECK_TOL and np.abs(Jw[0] - data.J).max() <= _CHECK_TOL
        )

    def placements_and_jacobians(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Joint placements and the world Jacobian of configurations.

        Args:
            Q: Configurations (n, nq).

        Returns:
            ``oMi`` (n, njoints, 4, 4) (joint 0: the world, identity) and ``J_w`` (n, 6, nv):
            the spatial velocity of each joint's body, world axes at the world origin, per
            unit velocity of each coordinate of its support (Pinocchio's ``data.J``).

        """
        model = self.model
        n = Q.shape[0]
        H = np.empty((n, model.njoints, 4, 4))
        H[:, 0] = np.eye(4)
        Jw = np.zeros((n, 6, model.nv))
        for j, parent, q0, q1, v0, P, fn in self._joints:
            R, p, S = fn(Q[:, q0:q1])
            M = H[:, parent] @ P
            if p is not None:
                M[:, :3, 3] += np.einsum("nij,nj->ni", M[:, :3, :3], p)
            if R is not None:
                M[:, :3, :3] = M[:, :3, :3] @ R
            H[:, j] = M
            Rw, pw = M[:, :3, :3], M[:, :3, 3]
            k = S.shape[2]
            lin = Rw @ S[:, :3] if S.shape[0] == n else np.einsum("nij,jk->nik", Rw, S[0, :3])
            ang = Rw @ S[:, 3:] if S.shape[0] == n else np.einsum("nij,jk->nik", Rw, S[0, 3:])
            px, py, pz = pw[:, 0, None], pw[:, 1, None], pw[:, 2, None]
            cols = slice(v0, v0 + k)
            Jw[:, 0, cols] = lin[:, 0] + py * ang[:, 2] - pz * ang[:, 1]
            Jw[:, 1, cols] = lin[:, 1] + pz * ang[:, 0] - px * ang[:, 2]
            Jw[:, 2, cols] = lin[:, 2] + px * ang[:, 1] - py * ang[:, 0]
            Jw[:, 3:, cols] = ang
        return H, Jw
