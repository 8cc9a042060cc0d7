"""Residual and Jacobian of a set of rigid loop-closure constraints.

Conventions (exact derivatives, checked against finite differences in the tests):

- 3D point constraint: ``r = p1 - p2`` [m], the world positions of the two contact points;
  ``J = J_lin(p1) - J_lin(p2)`` with world-aligned linear point Jacobians.
- 6D weld constraint: ``r = log6(oMc1^-1 oMc2)`` [m, rad]; ``J = Jlog6(c1Mc2) (J2 - Ad(c2Mc1) J1)``
  with ``J1, J2`` the local Jacobians of the contact frames.

Both are derivatives with respect to a velocity-space increment ``dq`` applied as
``pin.integrate(model, q, dq)``.

- Scalar joint couplings (:mod:`solvers.coupling`, gears and mimic joints): one row each,
  after the rigid constraints: ``r = (x_j - x_j0) - p(x_s - x_s0)`` [rad or m]; Jacobian ``+1``
  at the driven joint, ``-p'`` at the source.

Second derivative along a motion ``(q, v, a)``: ``d^2 r / dt^2 = J a + gamma(q, v)``, with the
acceleration drift ``gamma`` of :meth:`ClosureSet.drift` (classical accelerations of the contact
points at ``a = 0`` for points; for welds the relative spatial acceleration at ``a = 0``, exact
when the weld's relative velocity vanishes, as it does on a closed mechanism; ``-p'' v_s^2`` for
couplings).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from solvers.coupling import CouplingRows, JointCoupling

__all__ = ["ClosureSet"]

_LOCAL = pin.ReferenceFrame.LOCAL


class ClosureSet:
    """Closure equations of rigid constraint models, evaluated on a Pinocchio model.

    Residuals and Jacobians are computed by Pinocchio's C++ constraint models (copies with
    ``LOCAL_WORLD_ALIGNED`` point rows, ``d(p1 - p2)/dt``, and ``LOCAL`` weld rows mapped to the
    convention of this module by ``-Jlog6(c1Mc2) Ad(c2Mc1)``): one ``getConstraintsJacobian``
    call and a few copies per evaluation.

    Rows: the rigid constraints in order (``n_rigid`` rows), then one row per coupling;
    ``names``, ``sizes`` and ``offsets`` list both (a coupling has size 1).

    The coupling rows need the configuration: :meth:`jacobian_after_residual` and
    :meth:`local_jacobian_after_residual` use the one of the last residual call when not given
    it, :meth:`jacobian_at` needs it when there are couplings.

    Args:
        model: The kinematic tree.
        constraints: CONTACT_3D / CONTACT_6D rigid constraint models (their reference frame is
            ignored: residuals use the conventions of this module).
        couplings: Scalar joint couplings (default: none).

    Raises:
        ValueError: A malformed coupling (:class:`solvers.coupling.CouplingRows`).

    """

    def __init__(
        self,
        model: pin.Model,
        constraints: Sequence[pin.RigidConstraintModel],
        couplings: Sequence[JointCoupling] = (),
    ) -> None:
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
        self.n_rigid = int(sum(self.sizes))
        self.couplings = tuple(couplings)
        self._rows = CouplingRows(model, self.couplings) if self.couplings else None
        self._q_last: np.ndarray | None = None
        for c in self.couplings:
            self.names.append(c.name)
            self.sizes.append(1)
        self.offsets = np.concatenate([[0], np.cumsum(self.sizes)]).astype(int)
        self.nc = int(self.offsets[-1])
        self._cms = pin.StdVec_RigidConstraintModel()
        self._cds = pin.StdVec_RigidConstraintData()
        for is_point, j1, M1, j2, M2 in self._items:
            kind = pin.ContactType.CONTACT_3D if is_point else pin.ContactType.CONTACT_6D
            frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED if is_point else _LOCAL
            c = pin.RigidConstraintModel(kind, model, j1, M1, j2, M2, frame)
            self._cms.append(c)
            self._cds.append(c.createData())
        self._entries = [
            (is_point, int(o), cm, cd)
            for (is_point, *_), o, cm, cd in zip(
                self._items, self.offsets[: len(self._items)], self._cms, self._cds, strict=True
            )
        ]
        self._welds = [(int(o), cd) for is_point, o, _, cd in self._entries if not is_point]
        # contact-frame (LOCAL) copies for the solvers (see local_residual)
        self._loc_cms = pin.StdVec_RigidConstraintModel()
        self._loc_cds = pin.StdVec_RigidConstraintData()
        for is_point, j1, M1, j2, M2 in self._items:
            kind = pin.ContactType.CONTACT_3D if is_point else pin.ContactType.CONTACT_6D
            c = pin.RigidConstraintModel(kind, model, j1, M1, j2, M2, _LOCAL)
            self._loc_cms.append(c)
            self._loc_cds.append(c.createData())
        self._loc_entries = [
            (is_point, int(o), cm, cd)
            for (is_point, *_), o, cm, cd in zip(
                self._items,
                self.offsets[: len(self._items)],
                self._loc_cms,
                self._loc_cds,
                strict=True,
            )
        ]

    @property
    def items(self) -> list[tuple[bool, int, pin.SE3, int, pin.SE3]]:
        """Per rigid closure: ``(is_point, joint1, placement1, joint2, placement2)``."""
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
        return self._residual(data, q)

    @property
    def coupling_rows(self) -> CouplingRows | None:
        """The coupling evaluator (``None`` without couplings)."""
        return self._rows

    def _coupling_q(self, q: np.ndarray | None) -> np.ndarray:
        if q is not None:
            return np.asarray(q)
        if self._q_last is None:
            raise ValueError("the coupling rows need the configuration q")
        return self._q_last

    def _residual(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Residual from the joint placements of ``data`` (updates the constraint datas)."""
        model = self.model
        r = np.empty(self.nc)
        if self._rows is not None:
            self._q_last = np.array(q, dtype=float)
            r[self.n_rigid :] = self._rows.residual(self._q_last)
        for is_point, o, cm, cd in self._entries:
            cm.calc(model, data, cd)
            if is_point:
                r[o : o + 3] = cd.oMc1.translation
                r[o : o + 3] -= cd.oMc2.translation
            else:
                r[o : o + 6] = pin.log6(cd.c1Mc2).vector
        return r

    def residual_and_jacobian(self, data: pin.Data, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closure residual and its Jacobian at ``q`` (runs kinematics and joint Jacobians).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Residual (nc,) [m, rad] and Jacobian (nc, nv).

        """
        pin.computeJointJacobians(self.model, data, q)
        r = self._residual(data, q)
        return r, self._constraint_jacobian(data, q)

    def local_residual(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Closure residual in the contact frame of ``joint1`` (runs the forward kinematics).

        For the solvers: a point's residual is ``R_c1^T (p1 - p2)`` (the world residual
        rotated, same norm), a weld's ``log6(c2Mc1)``; with :meth:`local_jacobian_after_residual`
        (Pinocchio's ``LOCAL`` constraint Jacobian) it is exact at closure, where
        Newton's method needs it (its error is of the order of the residual: convergence stays
        quadratic). Cheaper than :meth:`residual`: one copy per closure.

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Residual (nc,) [m, rad].

        """
        model = self.model
        pin.forwardKinematics(model, data, q)
        r = np.empty(self.nc)
        for is_point, o, cm, cd in self._loc_entries:
            cm.calc(model, data, cd)
            if is_point:
                r[o : o + 3] = cd.c1Mc2.translation
            else:
                r[o : o + 6] = pin.log6(cd.c1Mc2).vector
        nr = self.n_rigid
        np.negative(r[:nr], out=r[:nr])
        if self._rows is not None:
            self._q_last = np.array(q, dtype=float)
            r[nr:] = self._rows.residual(self._q_last)
        return r

    def local_jacobian_after_residual(
        self, data: pin.Data, q: np.ndarray | None = None
    ) -> np.ndarray:
        """Jacobian (nc, nv) of :meth:`local_residual`, exact at closure.

        At the configuration of the last :meth:`local_residual` call (``data`` untouched since;
        see :meth:`jacobian_after_residual`); ``q``, that configuration, is used by the coupling
        rows only (default: the last residual's).
        """
        model = self.model
        pin.computeJointJacobians(model, data)
        if self._rows is None:
            J = pin.getConstraintsJacobian(model, data, self._loc_cms, self._loc_cds)
            return np.reshape(J, (self.nc, model.nv))
        out = np.zeros((self.nc, model.nv))
        if self.n_rigid:
            J = pin.getConstraintsJacobian(model, data, self._loc_cms, self._loc_cds)
            out[: self.n_rigid] = np.reshape(J, (self.n_rigid, model.nv))
        self._rows.jacobian(self._coupling_q(q), out[self.n_rigid :])
        return out

    def jacobian_after_residual(self, data: pin.Data, q: np.ndarray | None = None) -> np.ndarray:
        """Closure Jacobian (nc, nv) at the configuration of the last :meth:`residual` call.

        Only the joint Jacobians (from the placements already in ``data``) and the constraint
        Jacobian are computed: for solvers that evaluate the Jacobian where they have just
        evaluated the residual (:func:`solvers.solve_lm` does).

        Args:
            data: The data the last :meth:`residual` call used, untouched since.
            q: That call's configuration (used by the coupling rows only; default: the last
                residual's).

        Returns:
            Jacobian (nc, nv).

        """
        pin.computeJointJacobians(self.model, data)
        return self._constraint_jacobian(data, q)

    def jacobian_at(self, data: pin.Data, q: np.ndarray | None = None) -> np.ndarray:
        """Closure Jacobian (nc, nv) from ``data`` after ``pin.computeJointJacobians(q)``.

        Args:
            data: Pinocchio data whose placements and joint Jacobians are those of ``q``.
            q: That configuration (nq,), needed by the coupling rows when there are couplings.

        Returns:
            Jacobian (nc, nv).

        """
        model = self.model
        for _, _, cm, cd in self._entries:
            cm.calc(model, data, cd)
        if self._rows is not None and q is None:
            raise ValueError("jacobian_at needs the configuration q when there are couplings")
        return self._constraint_jacobian(data, q)

    def _constraint_jacobian(self, data: pin.Data, q: np.ndarray | None = None) -> np.ndarray:
        """Pinocchio's constraint Jacobian (constraint datas up to date) in this convention."""
        nv = self.model.nv
        if self._rows is None:
            J = pin.getConstraintsJacobian(self.model, data, self._cms, self._cds)
            J = np.reshape(J, (self.nc, nv))
        else:
            J = np.zeros((self.nc, nv))
            if self.n_rigid:
                Jr = pin.getConstraintsJacobian(self.model, data, self._cms, self._cds)
                J[: self.n_rigid] = np.reshape(Jr, (self.n_rigid, nv))
            self._rows.jacobian(self._coupling_q(q), J[self.n_rigid :])
        for o, cd in self._welds:
            M = cd.c1Mc2
            J[o : o + 6] = -pin.Jlog6(M).dot(M.toActionMatrixInverse()).dot(J[o : o + 6])
        return J

    def jacobian(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """Closure Jacobian (nc, nv) at ``q`` (runs kinematics and joint Jacobians).

        Args:
            data: Pinocchio data of ``model``.
            q: Configuration (nq,).

        Returns:
            Jacobian (nc, nv).

        """
        pin.computeJointJacobians(self.model, data, q)
        return self.jacobian_at(data, q)

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
        g = np.zeros(self.nc)
        zero = pin.Motion.Zero()
        classic = pin.classicAcceleration
        for k, (is_point, j1, M1, j2, M2) in enumerate(self._items):
            o = self.offsets[k]
            if is_point:  # classical accelerations of the two contact points, world axes
                if j1:
                    lin = classic(data.v[j1], data.a[j1], M1)
                    g[o : o + 3] = (data.oMi[j1] * M1).rotation.dot(lin)
                if j2:
                    lin = classic(data.v[j2], data.a[j2], M2)
                    g[o : o + 3] -= (data.oMi[j2] * M2).rotation.dot(lin)
                continue
            c1Mc2 = (data.oMi[j1] * M1).actInv(data.oMi[j2] * M2)
            v1 = c1Mc2.actInv(M1.actInv(data.v[j1])) if j1 else zero
            a1 = c1Mc2.actInv(M1.actInv(data.a[j1])) if j1 else zero
            v2 = M2.actInv(data.v[j2]) if j2 else zero
            a2 = M2.actInv(data.a[j2]) if j2 else zero
            nu = v2 - v1
            g[o : o + 6] = pin.Jlog6(c1Mc2) @ (a2 - a1 + nu.cross(v1)).vector
        if self._rows is not None:
            g[self.n_rigid :] = self._rows.drift(np.asarray(q), np.asarray(v))
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
