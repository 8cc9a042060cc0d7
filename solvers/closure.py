"""Residual and Jacobian of a set of rigid loop-closure constraints.

Conventions (exact derivatives, checked against finite differences in the tests):

- 3D point constraint: ``r = p1 - p2`` [m], the world positions of the two contact points;
  ``J = J_lin(p1) - J_lin(p2)`` with world-aligned linear point Jacobians.
- 6D weld constraint: ``r = log6(oMc1^-1 oMc2)`` [m, rad]; ``J = Jlog6(c1Mc2) (J2 - Ad(c2Mc1) J1)``
  with ``J1, J2`` the local Jacobians of the contact frames.

Both are derivatives with respect to a velocity-space increment ``dq`` applied as
``pin.integrate(model, q, dq)``.

Second derivative along a motion ``(q, v, a)``: ``d^2 r / dt^2 = J a + gamma(q, v)``, with the
acceleration drift ``gamma`` of :meth:`ClosureSet.drift` (classical accelerations of the contact
points at ``a = 0`` for points; for welds the relative spatial acceleration at ``a = 0``, exact
when the weld's relative velocity vanishes, as it does on a closed mechanism).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

__all__ = ["ClosureSet"]

_LOCAL = pin.ReferenceFrame.LOCAL


def _joint_jacobian(model: pin.Model, data: pin.Data, j: int) -> np.ndarray:
    """Local joint Jacobian (6, nv), also when nv == 1 (eigenpy would return a vector)."""
    return np.reshape(pin.getJointJacobian(model, data, j, _LOCAL), (6, model.nv))


class ClosureSet:
    """Closure equations of rigid constraint models, evaluated on a Pinocchio model.

    Args:
        model: The kinematic tree.
        constraints: CONTACT_3D / CONTACT_6D rigid constraint models (their reference frame is
            ignored: residuals use the conventions of this module).

    """

    def __init__(self, model: pin.Model, constraints: Sequence[pin.RigidConstraintModel]) -> None:
        self.model = model
        self._items: list[tuple[bool, int, pin.SE3, int, pin.SE3]] = []
        self.names: list[str] = []
        self.sizes: list[int] = []
        for cm in constraints:
            is_point = cm.type == pin.ContactType.CONTACT_3D
            self._items.append(
                (is_point, cm.joint1_id, cm.joint1_placement, cm.joint2_id, cm.joint2_placement)
            )
            self.names.append(cm.name)
            self.sizes.append(3 if is_point else 6)
        self.offsets = np.concatenate([[0], np.cumsum(self.sizes)]).astype(int)
        self.nc = int(self.offsets[-1])
        # Point constraints are evaluated together: each distinct joint placement is fetched
        # once, contact points are mapped in one batch, and point Jacobians come from the world
        # Jacobian data.J restricted (masked) to each joint's support.
        pts = [k for k, it in enumerate(self._items) if it[0]]
        self._pt_rows = (
            np.concatenate([np.arange(self.offsets[k], self.offsets[k] + 3) for k in pts])
            if pts
            else np.zeros(0, dtype=int)
        )
        joints = sorted({it[j] for k in pts for j in (1, 3) for it in (self._items[k],)})
        self._pt_joints = joints
        slot = {j: n for n, j in enumerate(joints)}
        self._pt_slot = np.array(
            [[slot[self._items[k][1]] for k in pts], [slot[self._items[k][3]] for k in pts]],
            dtype=int,
        ).reshape(2, len(pts))
        self._pt_local = np.array(
            [
                [self._items[k][2].translation for k in pts],
                [self._items[k][4].translation for k in pts],
            ]
        ).reshape(2, len(pts), 3)
        self._pt_mask = np.zeros((2, len(pts), 1, model.nv))
        for n, k in enumerate(pts):
            for side, j in enumerate((self._items[k][1], self._items[k][3])):
                self._pt_mask[side, n, 0] = self._support_mask(model, j)
        self._welds = [k for k, it in enumerate(self._items) if not it[0]]
        self._n_pts = len(pts)
        self._cache: tuple[np.ndarray | None, pin.Data | None, np.ndarray | None] = (
            None,
            None,
            None,
        )

    @property
    def items(self) -> list[tuple[bool, int, pin.SE3, int, pin.SE3]]:
        """Per closure: ``(is_point, joint1, placement1, joint2, placement2)``."""
        return self._items

    @staticmethod
    def _support_mask(model: pin.Model, j: int) -> np.ndarray:
        mask = np.zeros(model.nv)
        while j > 0:
            jm = model.joints[j]
            mask[jm.idx_v : jm.idx_v + jm.nv] = 1.0
            j = model.parents[j]
        return mask

    def residual(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Closure residual at ``q`` (runs the forward kinematics).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Residual (nc,) [m, rad].

        """
        pin.forwardKinematics(self.model, data, q)
        P = self._points(data) if self._n_pts else None
        self._cache = (q.copy(), data, P)
        return self._residual(data, P)

    def _points(self, data: pin.Data) -> np.ndarray:
        """World positions (2, n, 3) of the two contact points of each point constraint."""
        oMi = data.oMi
        H = np.array([oMi[j].homogeneous for j in self._pt_joints])[self._pt_slot]
        return np.einsum("snij,snj->sni", H[..., :3, :3], self._pt_local) + H[..., :3, 3]

    def _residual(self, data: pin.Data, P: np.ndarray | None = None) -> np.ndarray:
        r = np.empty(self.nc)
        if self._n_pts:
            P = self._points(data) if P is None else P
            r[self._pt_rows] = (P[0] - P[1]).reshape(-1)
        for k in self._welds:
            _, j1, M1, j2, M2 = self._items[k]
            o = self.offsets[k]
            r[o : o + 6] = pin.log6((data.oMi[j1] * M1).actInv(data.oMi[j2] * M2)).vector
        return r

    def residual_and_jacobian(self, data: pin.Data, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closure residual and its Jacobian at ``q`` (runs kinematics and joint Jacobians).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Residual (nc,) [m, rad] and Jacobian (nc, nv).

        """
        model = self.model
        pin.computeJointJacobians(model, data, q)
        P = self._points(data) if self._n_pts else None
        return self._residual(data, P), self._jacobian(data, P)

    def _jacobian(self, data: pin.Data, P: np.ndarray | None) -> np.ndarray:
        model = self.model
        J = np.zeros((self.nc, model.nv))
        if P is not None:
            Jw = data.J.reshape(6, model.nv)  # eigenpy returns (6,) when nv == 1
            # velocity of a point p on a joint's support: v_O + w x p = v_O - [p]x w
            S = np.zeros(P.shape + (3,))
            S[..., 0, 1], S[..., 0, 2] = -P[..., 2], P[..., 1]
            S[..., 1, 0], S[..., 1, 2] = P[..., 2], -P[..., 0]
            S[..., 2, 0], S[..., 2, 1] = -P[..., 1], P[..., 0]
            Jp = (Jw[:3] - S @ Jw[3:]) * self._pt_mask  # (2, n, 3, nv)
            J[self._pt_rows] = (Jp[0] - Jp[1]).reshape(3 * self._n_pts, model.nv)
        for k in self._welds:
            _, j1, M1, j2, M2 = self._items[k]
            o = self.offsets[k]
            oMc1 = data.oMi[j1] * M1
            oMc2 = data.oMi[j2] * M2
            c1Mc2 = oMc1.actInv(oMc2)
            nu = np.zeros((6, model.nv))
            if j2 != 0:
                nu += M2.toActionMatrixInverse() @ _joint_jacobian(model, data, j2)
            if j1 != 0:
                J1 = M1.toActionMatrixInverse() @ _joint_jacobian(model, data, j1)
                nu -= c1Mc2.toActionMatrixInverse() @ J1
            J[o : o + 6] = pin.Jlog6(c1Mc2) @ nu
        return J

    def jacobian(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Closure Jacobian (nc, nv) at ``q`` (runs kinematics and joint Jacobians).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Jacobian (nc, nv).

        """
        q_last, data_last, P = self._cache
        if q_last is not None and data_last is data and np.array_equal(q_last, q):
            # kinematics at q already known: only the joint Jacobians are missing
            pin.computeJointJacobians(self.model, data, q)
            return self._jacobian(data, P)
        return self.residual_and_jacobian(data, q)[1]

    def drift(self, data: pin.Data, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Acceleration drift ``gamma`` (nc,): ``d^2 r/dt^2 = J a + gamma`` (runs the kinematics).

        A motion keeps the closures to second order when ``J a = -gamma``. Exact for point
        constraints at any state; for welds when their relative velocity is zero (``J v = 0``).

        Args:
            data: Pinocchio data of ``model`` (its kinematics are overwritten).
            q: Configuration (nq,).
            v: Velocity (nv,).

        Returns:
            Drift (nc,) [m/s^2, rad/s^2].

        """
        model = self.model
        pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
        self._cache = (None, None, None)
        g = np.zeros(self.nc)
        zero = pin.Motion.Zero()
        for k, (is_point, j1, M1, j2, M2) in enumerate(self._items):
            o = self.offsets[k]
            if is_point:
                acc = []
                for j, M in ((j1, M1), (j2, M2)):
                    if j == 0:
                        acc.append(np.zeros(3))
                        continue
                    vp = M.actInv(data.v[j])
                    ap = M.actInv(data.a[j])
                    lin = ap.linear + np.cross(vp.angular, vp.linear)
                    acc.append((data.oMi[j] * M).rotation @ lin)
                g[o : o + 3] = acc[0] - acc[1]
                continue
            c1Mc2 = (data.oMi[j1] * M1).actInv(data.oMi[j2] * M2)
            v1 = c1Mc2.actInv(M1.actInv(data.v[j1])) if j1 else zero
            a1 = c1Mc2.actInv(M1.actInv(data.a[j1])) if j1 else zero
            v2 = M2.actInv(data.v[j2]) if j2 else zero
            a2 = M2.actInv(data.a[j2]) if j2 else zero
            nu = v2 - v1
            g[o : o + 6] = pin.Jlog6(c1Mc2) @ (a2 - a1 + nu.cross(v1)).vector
        return g

    def split(self, r: np.ndarray) -> dict[str, float]:
        """Norm of the residual of each constraint, by name.

        Args:
            r: Residual (nc,).

        Returns:
            ``{constraint name: residual norm}``.

        """
        return {
            n: float(np.linalg.norm(r[self.offsets[k] : self.offsets[k + 1]]))
            for k, n in enumerate(self.names)
        }
