"""Reference implementations with raw Pinocchio and numpy only, to time pkdyn against.

Each is the plainest version of what pkdyn does, built on Pinocchio's own constraint machinery
(C++): closure residuals and Jacobians from ``RigidConstraintModel.calc`` and
``getConstraintsJacobian``, Gauss-Newton with minimum-norm least-squares steps for assembly and
the inverse geometric model, ``rnea`` plus one least-squares solve for the inverse dynamics.
No error handling, no limits, no drift control: only the computation.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_POINT = pin.ContactType.CONTACT_3D


class RawClosures:
    """Closure residual and Jacobian from Pinocchio's constraint models.

    Point constraints are copied with ``LOCAL_WORLD_ALIGNED`` Jacobians (``d(p1 - p2)/dt`` in
    world axes, residual ``p1 - p2``); welds keep Pinocchio's ``LOCAL`` Jacobian (relative
    velocity of the two frames in frame 1, residual ``log6(c2Mc1)``, exact at closure).
    """

    def __init__(self, model: pin.Model, constraints: pin.StdVec_RigidConstraintModel) -> None:
        self.model = model
        self.cms = pin.StdVec_RigidConstraintModel()
        self.cds = pin.StdVec_RigidConstraintData()
        for cm in constraints:
            ref = _LWA if cm.type == _POINT else pin.ReferenceFrame.LOCAL
            c = pin.RigidConstraintModel(
                cm.type, model, cm.joint1_id, cm.joint1_placement, cm.joint2_id,
                cm.joint2_placement, ref,
            )  # fmt: skip
            self.cms.append(c)
            self.cds.append(c.createData())
        self.pairs = [
            (cm.type == _POINT, cm, cd) for cm, cd in zip(self.cms, self.cds, strict=True)
        ]
        self.nc = sum(3 if p else 6 for p, _, _ in self.pairs)

    def residual_and_jacobian(self, data: pin.Data, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        model = self.model
        pin.computeJointJacobians(model, data, q)
        r = []
        for point, cm, cd in self.pairs:
            cm.calc(model, data, cd)
            if point:
                r.append(cd.oMc1.translation - cd.oMc2.translation)
            else:
                r.append(pin.log6(cd.c1Mc2.inverse()).vector)
        J = pin.getConstraintsJacobian(model, data, self.cms, self.cds)
        return np.concatenate(r), np.reshape(J, (self.nc, model.nv))

    def jacobian(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        model = self.model
        pin.computeJointJacobians(model, data, q)
        for _, cm, cd in self.pairs:
            cm.calc(model, data, cd)
        return np.reshape(
            pin.getConstraintsJacobian(model, data, self.cms, self.cds), (self.nc, model.nv)
        )


def gauss_newton(
    model: pin.Model,
    q: np.ndarray,
    residual_and_jacobian,  # (q) -> (r, J)
    free: np.ndarray,
    tol: float = 1e-12,
    max_iter: int = 50,
) -> tuple[np.ndarray, int]:
    """Minimum-norm Gauss-Newton on the free velocity coordinates until ``max|r| < tol``."""
    dq = np.zeros(model.nv)
    for it in range(max_iter):
        r, J = residual_and_jacobian(q)
        if np.abs(r).max() < tol:
            return q, it
        dq[free] = -np.linalg.lstsq(J[:, free], r, rcond=1e-12)[0]
        q = pin.integrate(model, q, dq)
    return q, max_iter


class RawPoseTask:
    """Platform position (world, m) and orientation (``log3(R_t^T R)``, rad) residual rows."""

    def __init__(self, model: pin.Model, frame: int, rows: np.ndarray, target: pin.SE3) -> None:
        self.model, self.frame, self.rows, self.target = model, frame, rows, target

    def residual_and_jacobian(self, data: pin.Data) -> tuple[np.ndarray, np.ndarray]:
        pin.updateFramePlacement(self.model, data, self.frame)
        M = data.oMf[self.frame]
        e = np.r_[
            M.translation - self.target.translation, pin.log3(self.target.rotation.T @ M.rotation)
        ]
        Jw = pin.getFrameJacobian(self.model, data, self.frame, _LWA)
        Jl = pin.getFrameJacobian(self.model, data, self.frame, pin.ReferenceFrame.LOCAL)
        J = np.vstack([Jw[:3], Jl[3:]])
        return e[self.rows], J[self.rows]


def inverse_dynamics(
    model: pin.Model,
    data: pin.Data,
    closures: RawClosures,
    S: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    a: np.ndarray,
) -> np.ndarray:
    """Actuator efforts: least-squares solve of ``[S^T J^T] [tau; lambda] = rnea(q, v, a)``."""
    b = pin.rnea(model, data, q, v, a)
    J = closures.jacobian(data, q)
    x = np.linalg.lstsq(np.hstack([S.T, J.T]), b, rcond=1e-12)[0]
    return x[: S.shape[0]]


def inverse_dynamics_floor(
    model: pin.Model,
    data: pin.Data,
    closures: RawClosures,
    va: np.ndarray,
    vp: np.ndarray,
    Q: np.ndarray,
    V: np.ndarray,
    A: np.ndarray,
) -> np.ndarray:
    """Actuator efforts along a trajectory (N, n_a), the plainest loop: per sample ``rnea``, the
    C++ constraint Jacobian and the normal equations of the passive rows
    (``J_p J_p^T lambda = J_p b_p``, ``tau = b_a - J_a^T lambda``; unit gains, no check)."""
    tau = np.empty((Q.shape[0], va.size))
    for k in range(Q.shape[0]):
        b = pin.rnea(model, data, Q[k], V[k], A[k])
        J = closures.jacobian(data, Q[k])
        Jp = J[:, vp]
        lam = np.linalg.solve(Jp @ Jp.T, Jp @ b[vp])
        tau[k] = b[va] - J[:, va].T @ lam
    return tau


class LeanNewton:
    """The leanest direct geometric model: Newton on the passive coordinates.

    Per iteration one ``computeJointJacobians`` (kinematics and joint Jacobians), the constraint
    datas, one ``getConstraintsJacobian`` (C++), the point residuals copied into a preallocated
    vector and one linear solve (square passive Jacobian: ``solve``; else the minimum-norm step
    from the normal equations). Point closures only; no damping, no checks.
    """

    def __init__(self, model: pin.Model, constraints, actuated_q, passive_v) -> None:
        self.model = model
        self.data = model.createData()
        self.closures = RawClosures(model, constraints)
        self.iq = np.asarray(actuated_q)
        self.vp = np.asarray(passive_v)
        self.r = np.empty(self.closures.nc)
        self.dq = np.zeros(model.nv)
        self.pts = [(3 * k, cd) for k, (point, _, cd) in enumerate(self.closures.pairs) if point]
        assert len(self.pts) == len(self.closures.pairs), "point closures only"

    def solve(
        self, q0: np.ndarray, qa: np.ndarray, tol: float = 1e-12, max_iter: int = 50
    ) -> tuple[np.ndarray, int]:
        model, data, cl = self.model, self.data, self.closures
        r, dq, vp = self.r, self.dq, self.vp
        q = q0.copy()
        q[self.iq] = qa
        square = cl.nc == vp.size
        for it in range(max_iter):
            pin.computeJointJacobians(model, data, q)
            for _, c, cd in cl.pairs:
                c.calc(model, data, cd)
            for o, cd in self.pts:
                r[o : o + 3] = cd.oMc1.translation
                r[o : o + 3] -= cd.oMc2.translation
            if np.abs(r).max() < tol:
                return q, it
            Jp = pin.getConstraintsJacobian(model, data, cl.cms, cl.cds)[:, vp]
            if square:
                dq[vp] = -np.linalg.solve(Jp, r)
            else:
                dq[vp] = -Jp.T @ np.linalg.solve(Jp @ Jp.T, r)
            q = pin.integrate(model, q, dq)
        return q, max_iter
