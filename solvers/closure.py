"""Residual and Jacobian of a set of rigid loop-closure constraints.

Conventions (exact derivatives, checked against finite differences in the tests):

- 3D point constraint: ``r = p1 - p2`` [m], the world positions of the two contact points;
  ``J = J_lin(p1) - J_lin(p2)`` with world-aligned linear point Jacobians.
- 6D weld constraint: ``r = log6(oMc1^-1 oMc2)`` [m, rad]; ``J = Jlog6(c1Mc2) (J2 - Ad(c2Mc1) J1)``
  with ``J1, J2`` the local Jacobians of the contact frames.

Both are derivatives with respect to a velocity-space increment ``dq`` applied as
``pin.integrate(model, q, dq)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

__all__ = ["ClosureSet"]

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_LOCAL = pin.ReferenceFrame.LOCAL


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


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

    def residual(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Closure residual at ``q`` (runs the forward kinematics).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Residual (nc,) [m, rad].
        """
        pin.forwardKinematics(self.model, data, q)
        return self._residual(data)

    def _residual(self, data: pin.Data) -> np.ndarray:
        r = np.empty(self.nc)
        for k, (is_point, j1, M1, j2, M2) in enumerate(self._items):
            o = self.offsets[k]
            oMc1 = data.oMi[j1] * M1
            oMc2 = data.oMi[j2] * M2
            if is_point:
                r[o : o + 3] = oMc1.translation - oMc2.translation
            else:
                r[o : o + 6] = pin.log6(oMc1.actInv(oMc2)).vector
        return r

    def residual_and_jacobian(
        self, data: pin.Data, q: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Closure residual and its Jacobian at ``q`` (runs kinematics and joint Jacobians).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Residual (nc,) [m, rad] and Jacobian (nc, nv).
        """
        model = self.model
        pin.computeJointJacobians(model, data, q)
        return self._residual(data), self._jacobian(data)

    def _jacobian(self, data: pin.Data) -> np.ndarray:
        model = self.model
        J = np.zeros((self.nc, model.nv))
        for k, (is_point, j1, M1, j2, M2) in enumerate(self._items):
            o = self.offsets[k]
            if is_point:
                for sign, j, M in ((1.0, j1, M1), (-1.0, j2, M2)):
                    if j == 0:
                        continue
                    oMi = data.oMi[j]
                    Jj = pin.getJointJacobian(model, data, j, _LWA)
                    lever = oMi.rotation @ M.translation
                    J[o : o + 3] += sign * (Jj[:3] - _skew(lever) @ Jj[3:])
            else:
                oMc1 = data.oMi[j1] * M1
                oMc2 = data.oMi[j2] * M2
                c1Mc2 = oMc1.actInv(oMc2)
                nu = np.zeros((6, model.nv))
                if j2 != 0:
                    nu += M2.toActionMatrixInverse() @ pin.getJointJacobian(model, data, j2, _LOCAL)
                if j1 != 0:
                    J1 = M1.toActionMatrixInverse() @ pin.getJointJacobian(model, data, j1, _LOCAL)
                    nu -= c1Mc2.toActionMatrixInverse() @ J1
                J[o : o + 6] = pin.Jlog6(c1Mc2) @ nu
        return J

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
