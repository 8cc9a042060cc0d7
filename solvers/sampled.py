"""Kinematics of many sampled states at once: closure errors and frame wrenches, vectorised.

Along a trajectory ``(q_k, v_k, a_k)``, Pinocchio computes in C++, per sample, the joint
accelerations (``pin.rnea(model, data, q, v, a)`` leaves them in ``data.a_gf``, local frames,
with the gravity offset ``-g``), the joint placements ``data.oMi`` and the world Jacobian
``data.J`` (``pin.computeJointJacobians(model, data, q)``). :class:`SampledKinematics` copies
the few placements and accelerations the closures (and given frames) need, with ``J``, into
preallocated arrays (:meth:`~SampledKinematics.capture`, the only per-sample Python work) and
evaluates the closure equations of all the samples with numpy
(:meth:`~SampledKinematics.closure_errors`).

World-frame quantities at the world origin: the spatial velocity of joint ``j``'s body is
``V_j = J_w S_j v`` (``S_j``: the velocity coordinates supporting ``j``), its spatial
acceleration ``A_j = X(oMi_j) a_j`` (the local ``a_j`` includes the joint bias accelerations,
which the time variation of ``J_w`` leaves out for joints such as the universal joint); a point
``p`` of that body moves at ``v_p = V_lin + w x p`` and accelerates (classical acceleration) at
``a_p = A_lin + alpha x p + w x v_p``. The gravity offset, a uniform translation acceleration of
every body, cancels in the differences below. Per closure (conventions of
:class:`~solvers.constraints.ConstraintSet`):

- 3D point: residual ``p1 - p2``, velocity error ``v_p1 - v_p2 = J v`` and acceleration error
  ``a_p1 - a_p2 = J a + gamma``, world axes [m, m/s, m/s^2];
- 6D weld: residual ``log6(c1Mc2)``; velocity and acceleration errors: the relative twist
  ``X(oMc2)^-1 (V_2 - V_1)`` and its rate ``X(oMc2)^-1 (A_2 - A_1)`` in the contact frame of
  ``joint2`` (equal to ``J v`` and ``J a + gamma`` up to the factor ``Jlog6(c1Mc2) = I + O(|r|)``;
  the rate is exact when the relative twist vanishes, as the drift of ``ConstraintSet`` is);
- joint coupling (:mod:`solvers.coupling`): residual, ``J v`` and ``J a + gamma`` from the
  configurations, velocities and accelerations themselves [rad or m, per s, per s^2].
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from solvers.closure import support_mask
from solvers.constraints import ConstraintSet
from solvers.vec3 import cross

__all__ = ["SampledKinematics"]


def _turn(R: np.ndarray, R1: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Angle (n,) of rotations ``R = c1Rc2`` (n, 3, 3) about ``R1^T n`` (``R1 = R_c1``).

    ``atan2(s, c)`` with ``s = (R1^T n) . vee(R - R^T) / 2`` and ``c = (tr R - 1) / 2``: the
    angle of a rotation about that axis, as :class:`~solvers.closure.ClosureRows` computes it.
    """
    m = np.einsum("nji,j->ni", R1, n)
    vee = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], -1)
    return np.arctan2(0.5 * np.sum(m * vee, axis=-1), 0.5 * (np.trace(R, axis1=1, axis2=2) - 1.0))


def _relative_motion(d: np.ndarray, oMc2: np.ndarray) -> np.ndarray:
    """Spatial motions (n, 6), world axes at the origin, in contact frames ``oMc2`` (n, 4, 4)."""
    R2, p2 = oMc2[:, :3, :3], oMc2[:, :3, 3]
    lin = d[:, :3] + cross(d[:, 3:], p2)  # at the contact point
    return np.concatenate(
        [np.einsum("nji,nj->ni", R2, lin), np.einsum("nji,nj->ni", R2, d[:, 3:])], axis=1
    )


_CONSTANT_SUBSPACE = {
    "JointModelRX",
    "JointModelRY",
    "JointModelRZ",
    "JointModelRevoluteUnaligned",
    "JointModelRUBX",
    "JointModelRUBY",
    "JointModelRUBZ",
    "JointModelRevoluteUnboundedUnaligned",
    "JointModelPX",
    "JointModelPY",
    "JointModelPZ",
    "JointModelPrismaticUnaligned",
    "JointModelSpherical",
    "JointModelFreeFlyer",
    "JointModelTranslation",
    "JointModelPlanar",
}
"""Joints whose motion subspace is constant in their own frame: the time variation of their
world Jacobian columns is ``V x column`` (``V``: their body's spatial velocity), as Pinocchio's
``computeJointJacobiansTimeVariation`` computes it."""

_DRIFT_CHECK_TOL = 1e-10


def _drift_model(model: pin.Model) -> pin.Model | None:
    """The tree with every universal joint split into two revolute joints, or ``None``.

    An intermediate massless body between the two revolute joints makes every joint's motion
    subspace constant in its frame: same coordinates, same placements and world Jacobian, and
    the time variation of the world Jacobian gives the bodies' accelerations exactly (Pinocchio
    leaves out the universal joint's bias acceleration there). ``None`` when another joint type
    is present or the check against Pinocchio's forward kinematics at a random state fails.
    """
    out = pin.Model()
    out.gravity = model.gravity
    ids = {0: 0}
    for j in range(1, model.njoints):
        jm = model.joints[j]
        kind = jm.shortname()
        parent, placement, name = (
            ids[int(model.parents[j])],
            model.jointPlacements[j],
            model.names[j],
        )
        if kind == "JointModelUniversal":
            u = jm.extract()
            mid = out.addJoint(
                parent, pin.JointModelRevoluteUnaligned(u.axis1), placement, f"{name}_axis1"
            )
            ids[j] = out.addJoint(
                mid, pin.JointModelRevoluteUnaligned(u.axis2), pin.SE3.Identity(), name
            )
        elif kind in _CONSTANT_SUBSPACE:
            ids[j] = out.addJoint(parent, jm, placement, name)
        else:
            return None
    if out.nq != model.nq or out.nv != model.nv:
        return None
    rng = np.random.default_rng(0)
    q = pin.integrate(model, pin.neutral(model), rng.standard_normal(model.nv))
    v = rng.standard_normal(model.nv)
    data, data2 = model.createData(), out.createData()
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.computeJointJacobiansTimeVariation(out, data2, q, v)
    for j in range(1, model.njoints):
        A = data2.dJ @ (support_mask(model, j) * v)
        ref = data.oMi[j].act(data.a[j]).vector
        if np.abs(A - ref).max() > _DRIFT_CHECK_TOL * max(1.0, np.abs(ref).max()):
            return None
    return out


class SampledKinematics:
    """Buffers of per-sample kinematics and their vectorised evaluation (see the module doc).

    Args:
        model: The kinematic tree.
        closure_set: The constraint set (closures and couplings).
        frames: Frame ids whose placement is also captured (for :meth:`frame_force`).
        size: Number of samples the buffers hold.

    """

    def __init__(
        self,
        model: pin.Model,
        closure_set: ConstraintSet,
        frames: Sequence[int] = (),
        size: int = 256,
    ) -> None:
        self.model = model
        self.closure_set = closure_set
        self.size = int(size)
        cr = closure_set.closure_rows
        items = cr.base_items if cr is not None else []
        base_offsets = cr.base_offsets if cr is not None else np.zeros(1, dtype=int)
        self.nb = int(base_offsets[-1])  # rows of the base constraint models
        self._identity = cr is None or cr.identity
        used = {int(j) for it in items for j in (it[1], it[3])}
        used |= {int(model.frames[f].parentJoint) for f in frames}
        used.discard(0)
        self.joints = [0, *sorted(used)]  # slot 0: the world (identity, never moves)
        self._captured = self.joints[1:]
        slot = {j: s for s, j in enumerate(self.joints)}
        nv, nj = model.nv, len(self.joints)
        self.masks = np.zeros((nj, nv))
        for s, j in enumerate(self.joints):
            if j:
                self.masks[s] = support_mask(model, j)
        self.H = np.empty((self.size, nj, 4, 4))
        self.H[:, 0] = np.eye(4)
        self.Jw = np.empty((self.size, 6, nv))
        self.acc = np.empty((self.size, nj, 6))
        self.acc[:, 0] = -model.gravity.vector  # the world's, as rnea sets it
        pts = [k for k, it in enumerate(items) if it[0]]
        self._pt_offsets = np.array([base_offsets[k] for k in pts], dtype=int)
        self._pt_slot = np.array(
            [[slot[int(items[k][1])] for k in pts], [slot[int(items[k][3])] for k in pts]],
            dtype=int,
        ).reshape(2, len(pts))
        self._pt_local = np.array(
            [[items[k][2].translation for k in pts], [items[k][4].translation for k in pts]]
        ).reshape(2, len(pts), 3)
        self._pt_rows = (self._pt_offsets[:, None] + np.arange(3)).reshape(-1)
        self._point_columns(nv)
        self._welds = [
            (
                int(base_offsets[k]),
                slot[int(items[k][1])],
                items[k][2].homogeneous,
                slot[int(items[k][3])],
                items[k][4].homogeneous,
            )
            for k, it in enumerate(items)
            if not it[0]
        ]
        self._frame_slot = {
            int(f): (slot.get(int(model.frames[f].parentJoint), 0), model.frames[f].placement)
            for f in frames
        }
        self.Q = np.empty((self.size, model.nq))  # for the coupling rows
        self._pending = np.zeros(self.size, dtype=bool)  # captured, placements not decoded
        self._aux: tuple[pin.Model, pin.Data, np.ndarray] | None = None  # built on first use
        self.Jaux = np.empty((self.size, 6, 3 * len(self._captured)))
        self._drift: tuple[pin.Model, pin.Data] | None = None
        self._drift_checked = False
        self._data = model.createData()
        self._drift_from_dJ = False

    def _point_columns(self, nv: int) -> None:
        """Index tables of the point closures' Jacobian rows.

        Per point closure: the coordinates supporting either side (padded with coordinate 0,
        weight 0), each side's weights on them (1: supports that side) and where each entry of
        the closure's 3 rows lands in a flattened ``(nc, nv + 1)`` Jacobian (padding: column
        ``nv``, dropped).
        """
        K = self._pt_offsets.size
        sides = [self.masks[self._pt_slot[s]] for s in (0, 1)]  # (K, nv) each
        union = [np.flatnonzero(sides[0][k] + sides[1][k]) for k in range(K)]
        cu = max((u.size for u in union), default=0) or 1
        self._pt_cols = np.zeros((K, cu), dtype=int)
        self._pt_w = np.zeros((2, K, cu))
        target = np.full((K, 3, cu), nv, dtype=int)
        for k, u in enumerate(union):
            self._pt_cols[k, : u.size] = u
            for s in (0, 1):
                self._pt_w[s, k, : u.size] = sides[s][k, u]
            target[k, :, : u.size] = u
        rows = self._pt_offsets[:, None, None] + np.arange(3)[None, :, None]
        self._pt_flat = (rows * (nv + 1) + target).reshape(-1)

    def capture(self, k: int, data: pin.Data) -> None:
        """Copy sample ``k``'s kinematics from ``data``.

        Args:
            k: Buffer row.
            data: Data after ``pin.rnea(model, data, q, v, a)`` then
                ``pin.computeJointJacobians(model, data, q)`` at the sample.

        """
        captured = self._captured
        if captured:
            oMi = data.oMi.tolist()
            acc = data.a_gf.tolist()
            self.H[k, 1:] = [oMi[j].homogeneous for j in captured]
            self.acc[k, 1:] = [acc[j].vector for j in captured]
        self.Jw[k] = data.J
        self._pending[k] = False
        self._drift_from_dJ = False

    def _velocities(self, n: int, v: np.ndarray) -> np.ndarray:
        """World spatial velocities (n, nj, 6) of the captured bodies at the origin."""
        return np.swapaxes((self.Jw[:n] * v[:, None, :]) @ self.masks.T, 1, 2)

    def _accelerations(self, n: int) -> np.ndarray:
        """World spatial accelerations (n, nj, 6) of the captured bodies at the origin."""
        H, acc = self.H[:n], self.acc[:n]
        R, p = H[..., :3, :3], H[..., :3, 3]
        ang = np.einsum("nkij,nkj->nki", R, acc[..., 3:])
        lin = np.einsum("nkij,nkj->nki", R, acc[..., :3]) + cross(p, ang)
        return np.concatenate([lin, ang], axis=-1)

    def closure_errors(
        self,
        n: int,
        v: np.ndarray,
        q: np.ndarray | None = None,
        a: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Closure residual, velocity and acceleration errors of the first ``n`` samples.

        Args:
            n: Number of captured samples.
            v: Their velocities (n, nv) (the accelerations are those captured).
            q: Their configurations (n, nq); needed by coupling rows only.
            a: Their accelerations (n, nv); needed by coupling rows only.

        Returns:
            Residual, velocity error and acceleration error, each (n, nc) (module doc).

        Raises:
            ValueError: The closures have couplings and ``q`` or ``a`` is missing.

        """
        cs = self.closure_set
        o = cs.nc
        out = [np.empty((n, cs.n)) for _ in range(3)]
        coupled = cs.coupling_rows
        if coupled is not None:
            if q is None or a is None:
                raise ValueError("coupling rows need the configurations and accelerations")
            qq, vv, aa = q[:n], v[:n], a[:n]
            out[0][:, o:] = coupled.residual(qq)
            out[1][:, o:] = coupled.velocity_error(qq, vv)
            out[2][:, o:] = coupled.acceleration_error(qq, vv, aa)
        if o == 0:
            return out[0], out[1], out[2]
        direct = cs.nk == 0 and self._identity  # the base rows are the rows: no copy
        r, ev, ea = out if direct else [np.empty((n, self.nb)) for _ in range(3)]
        V = self._velocities(n, v)
        A = self._accelerations(n)
        H = self.H[:n]
        if self._pt_offsets.size:
            side = self._point_sides(H, V, A)
            rows = self._pt_rows
            r[:, rows] = (side[0][0] - side[1][0]).reshape(n, -1)
            ev[:, rows] = (side[0][1] - side[1][1]).reshape(n, -1)
            ea[:, rows] = (side[0][2] - side[1][2]).reshape(n, -1)
        for o, s1, M1, s2, M2 in self._welds:
            oMc2 = H[:, s2] @ M2
            for err, X in ((ev, V), (ea, A)):
                err[:, o : o + 6] = _relative_motion(X[:, s2] - X[:, s1], oMc2)
            c1Mc2 = np.linalg.solve(H[:, s1] @ M1, oMc2)
            for k in range(n):
                r[k, o : o + 6] = pin.log6(c1Mc2[k]).vector
        if not direct:
            self._reduce(H, out[0], r, out[1], ev, out[2], ea, V, A)
        return out[0], out[1], out[2]

    def _reduce(
        self,
        H: np.ndarray,
        r_out: np.ndarray | None = None,
        r: np.ndarray | None = None,
        ev_out: np.ndarray | None = None,
        ev: np.ndarray | None = None,
        ea_out: np.ndarray | None = None,
        ea: np.ndarray | None = None,
        V: np.ndarray | None = None,
        A: np.ndarray | None = None,
        J_out: np.ndarray | None = None,
        J: np.ndarray | None = None,
        Jw: np.ndarray | None = None,
    ) -> None:
        """The closure rows of the base rows: residuals, ``J v``, ``J a + gamma``, Jacobians.

        Each ``*_out`` (n, n_all[, nv]) receives in its first ``nc`` columns the rows of the
        base ones (n, nb[, nv]) (:mod:`solvers.closure`): copies, planar projections ``E`` of
        point rows, and a hinge's axis rows and planar rotation rows from the placements ``H``,
        the world velocities ``V`` and accelerations ``A`` of the captured bodies (n, nj, 6) and
        the world Jacobian ``Jw`` (n, 6, nv).
        """
        cr = self.closure_set.closure_rows
        assert cr is not None
        nc = cr.n
        pairs = [
            (x, b)
            for x, b in ((r_out, r), (ev_out, ev), (ea_out, ea), (J_out, J))
            if x is not None and b is not None
        ]
        if cr.identity:
            for x, b in pairs:
                x[:, :nc] = b
            return
        for x, b in pairs:
            x[:, cr._dst] = b[:, cr._src]
            if cr._planes:
                sub = "mij,nmj->nmi" if b.ndim == 2 else "mij,nmjv->nmiv"
                x[:, cr._pl_dst] = np.einsum(sub, cr._pl_E, b[:, cr._pl_src])
        slot = {j: k for k, j in enumerate(self.joints)}
        base = cr.base_items
        for o, bi, F, a, j1, j2 in cr._axes:
            _, _, M1, _, M2 = base[bi]
            s1, s2 = slot[j1], slot[j2]
            R1 = H[:, s1, :3, :3] @ M1.rotation
            a2 = (H[:, s2, :3, :3] @ M2.rotation) @ a
            for k in range(2):
                f = R1 @ F[:, k]
                w = cross(a2, f)
                if r_out is not None:
                    r_out[:, o + k] = np.sum(f * a2, axis=-1)
                if J_out is not None:
                    assert Jw is not None
                    J_out[:, o + k] = np.einsum("ni,niv->nv", w, Jw[:, 3:]) * cr._dmask[(j1, j2)]
                if V is None:
                    continue
                w1, w2 = V[:, s1, 3:], V[:, s2, 3:]
                if ev_out is not None:
                    ev_out[:, o + k] = np.sum(w * (w2 - w1), axis=-1)
                if ea_out is not None:
                    assert A is not None
                    dw = cross(cross(w2, a2), f) + cross(a2, cross(w1, f))
                    ea_out[:, o + k] = np.sum(dw * (w2 - w1), axis=-1) + np.sum(
                        w * (A[:, s2, 3:] - A[:, s1, 3:]), axis=-1
                    )
        for o, bi, nrm, j1, j2 in cr._turns:
            _, _, M1, _, M2 = base[bi]
            s1, s2 = slot[j1], slot[j2]
            if r_out is not None:
                R1 = H[:, s1, :3, :3] @ M1.rotation
                R = np.swapaxes(R1, 1, 2) @ (H[:, s2, :3, :3] @ M2.rotation)
                r_out[:, o] = _turn(R, R1, nrm)
            if J_out is not None:
                assert Jw is not None
                J_out[:, o] = np.einsum("i,niv->nv", nrm, Jw[:, 3:]) * cr._dmask[(j1, j2)]
            if ev_out is not None:
                assert V is not None
                ev_out[:, o] = (V[:, s2, 3:] - V[:, s1, 3:]) @ nrm
            if ea_out is not None:
                assert A is not None
                ea_out[:, o] = (A[:, s2, 3:] - A[:, s1, 3:]) @ nrm

    def _point_sides(
        self, H: np.ndarray, V: np.ndarray, A: np.ndarray
    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Per side of the point closures: contact points, velocities, classical accelerations.

        Each (n, K, 3), world axes.
        """
        side = []
        for s in (0, 1):
            slot = self._pt_slot[s]
            Hs = H[:, slot]  # (n, K, 4, 4)
            p = np.einsum("nkij,kj->nki", Hs[..., :3, :3], self._pt_local[s]) + Hs[..., :3, 3]
            Vs, As = V[:, slot], A[:, slot]
            w = Vs[..., 3:]
            vp = Vs[..., :3] + cross(w, p)
            ap = As[..., :3] + cross(As[..., 3:], p) + cross(w, vp)
            side.append((p, vp, ap))
        return side

    def acceleration_errors(self, n: int, v: np.ndarray) -> np.ndarray:
        """The closures' acceleration drift ``gamma`` of samples captured at zero acceleration.

        Args:
            n: Number of samples captured by :meth:`capture_configuration` (placements decoded
                by :meth:`update_placements`) and :meth:`capture_drift`, rows ``0..n-1``.
            v: Their velocities (n, nv).

        Returns:
            ``gamma`` (n, nc): the acceleration errors of :meth:`closure_errors` at ``a = 0``
            (no residual: no ``log6``); coupling rows ``-p'' v_s^2``.

        """
        cs = self.closure_set
        out = np.empty((n, cs.n))
        coupled = cs.coupling_rows
        if coupled is not None:
            out[:, cs.nc :] = coupled.drift(self.Q[:n], v[:n])
        if cs.nc == 0:
            return out
        direct = cs.nk == 0 and self._identity
        ea = out if direct else np.empty((n, self.nb))
        V = self._velocities(n, v)
        if self._drift_from_dJ:  # world accelerations d/dt(J_w) S_j v (no gravity offset)
            A = np.swapaxes((self.dJw[:n] * v[:, None, :]) @ self.masks.T, 1, 2)
        else:
            A = self._accelerations(n)
        H = self.H[:n]
        if self._pt_offsets.size:
            side = self._point_sides(H, V, A)
            ea[:, self._pt_rows] = (side[0][2] - side[1][2]).reshape(n, -1)
        for o, s1, _, s2, M2 in self._welds:
            ea[:, o : o + 6] = _relative_motion(A[:, s2] - A[:, s1], H[:, s2] @ M2)
        if not direct:
            self._reduce(H, ea_out=out, ea=ea, V=V, A=A)
        return out

    def capture_configuration(self, k: int, q: np.ndarray) -> None:
        """Joint Jacobians and placements of sample ``k`` (one Pinocchio call, one array read).

        The placements of the captured joints are decoded, for many samples at once, by
        :meth:`update_placements` (:meth:`residuals_and_jacobians` does it).

        Args:
            k: Buffer row.
            q: Configuration (nq,).

        """
        self.Q[k] = q
        if not self._captured:
            return
        self._pending[k] = True
        if self._aux is None:
            # placements read from one array: a spherical leaf joint at the origin of each
            # captured joint, whose world Jacobian columns are [[o]x R; R]
            aux = pin.Model(self.model)
            for j in self._captured:
                aux.addJoint(j, pin.JointModelSpherical(), pin.SE3.Identity(), f"_pkdyn_aux_{j}")
            self._aux = (aux, aux.createData(), pin.neutral(aux))
        aux, aux_data, qx = self._aux
        qx[: self.model.nq] = q
        pin.computeJointJacobians(aux, aux_data, qx)
        Jx = aux_data.J
        nv = self.model.nv
        self.Jw[k] = Jx[:, :nv]
        self.Jaux[k] = Jx[:, nv:]

    def update_placements(self, rows: np.ndarray) -> None:
        """Placements of rows captured by :meth:`capture_configuration`, from their Jacobians.

        Args:
            rows: Buffer rows (m,).

        """
        nj = len(self._captured)
        rows = rows[self._pending[rows]]  # decoded already: left as they are
        if not nj or not rows.size:
            return
        self._pending[rows] = False
        X = self.Jaux[rows].reshape(rows.size, 6, nj, 3).transpose(0, 2, 1, 3)  # (m, nj, 6, 3)
        R, L = X[:, :, 3:], X[:, :, :3]  # columns r_i and o x r_i
        # sum_i r_i x (o x r_i) = 3 o - sum_i r_i (r_i . o) = 2 o
        H = np.empty((rows.size, nj, 4, 4))
        H[:, :, :3, :3] = R
        H[:, :, 0, 3] = 0.5 * (R[:, :, 1] * L[:, :, 2] - R[:, :, 2] * L[:, :, 1]).sum(axis=-1)
        H[:, :, 1, 3] = 0.5 * (R[:, :, 2] * L[:, :, 0] - R[:, :, 0] * L[:, :, 2]).sum(axis=-1)
        H[:, :, 2, 3] = 0.5 * (R[:, :, 0] * L[:, :, 1] - R[:, :, 1] * L[:, :, 0]).sum(axis=-1)
        H[:, :, 3] = (0.0, 0.0, 0.0, 1.0)
        self.H[rows, 1:] = H

    def capture_drift(self, k: int, q: np.ndarray, v: np.ndarray) -> None:
        """Sample ``k``'s body accelerations at zero joint acceleration.

        For :meth:`acceleration_errors` (placements captured already by
        :meth:`capture_configuration` and decoded by :meth:`update_placements`): one Pinocchio
        call and one array read.

        Args:
            k: Buffer row.
            q: Configuration (nq,).
            v: Velocity (nv,).

        """
        if not self._drift_checked:
            # accelerations at zero joint acceleration from the time variation of the world
            # Jacobian where that is exact, else from rnea
            model = _drift_model(self.model) if self._captured else None
            self._drift = None if model is None else (model, model.createData())
            self.dJw = np.empty((self.size, 6, self.model.nv))
            self._drift_checked = True
        if self._drift is not None:
            pin.computeJointJacobiansTimeVariation(self._drift[0], self._drift[1], q, v)
            self.dJw[k] = self._drift[1].dJ
            self._drift_from_dJ = True
        elif self._captured:
            pin.rnea(self.model, self._data, q, v, np.zeros(self.model.nv))
            acc = self._data.a_gf.tolist()
            self.acc[k, 1:] = [acc[j].vector for j in self._captured]
            self._drift_from_dJ = False

    def _point_positions(self, H: np.ndarray, side: int) -> np.ndarray:
        """World positions (m, K, 3) of one side's contact points, from placements (m, nj, 4, 4)."""
        Hs = H[:, self._pt_slot[side]]
        loc = self._pt_local[side]
        R = Hs[..., :3, :3]
        return (
            R[..., 0] * loc[:, 0, None] + R[..., 1] * loc[:, 1, None] + R[..., 2] * loc[:, 2, None]
        ) + Hs[..., :3, 3]

    def residuals_and_jacobians(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closure residuals and Jacobians of captured samples (:class:`ConstraintSet` conventions).

        Point rows: ``J = J_lin(p1) - J_lin(p2)``, the linear velocity of a point ``p`` of body
        ``j`` being ``(J_w,lin - [p]x J_w,ang) S_j v``. Weld rows:
        ``J = Jlog6(c1Mc2) X(oMc2)^-1 J_w (S_2 - S_1)`` (the relative twist in the contact frame
        of ``joint2``; ``log6`` and ``Jlog6`` by Pinocchio, sample by sample).

        Args:
            rows: Buffer rows (m,) of the samples (captured by :meth:`capture_configuration`).

        Returns:
            Residuals (m, nc) [m, rad] and Jacobians (m, nc, nv).

        """
        cs = self.closure_set
        m, nv, o = rows.size, self.model.nv, cs.nc
        r_out = np.empty((m, cs.n))
        J_out = np.empty((m, cs.n, nv))
        coupled = cs.coupling_rows
        if coupled is not None:
            Q = self.Q[rows]
            r_out[:, o:] = coupled.residual(Q)
            Jc = J_out[:, o:]
            Jc[:] = 0.0
            coupled.jacobian(Q, Jc)
        if o == 0:
            return r_out, J_out
        nc = self.nb
        direct = cs.nk == 0 and self._identity  # the base rows are the rows: no copy
        r = r_out if direct else np.empty((m, nc))
        J = J_out if direct else np.empty((m, nc, nv))
        self.update_placements(rows)
        H, Jw = self.H[rows], self.Jw[rows]
        if self._pt_offsets.size:
            # linear velocity of a point p of a body per coordinate: J_lin - [p]x J_ang on the
            # coordinates supporting the body; J = that of side 1 - that of side 2, on the
            # coordinates supporting either side (cross product linear in p)
            p = [self._point_positions(H, s) for s in (0, 1)]  # (m, K, 3) each
            r[:, self._pt_rows] = (p[0] - p[1]).reshape(m, -1)
            w0, w1 = self._pt_w
            G = Jw[:, :, self._pt_cols]  # (m, 6, K, c)
            P = w0[..., None] * p[0][:, :, None] - w1[..., None] * p[1][:, :, None]
            px, py, pz = P[..., 0], P[..., 1], P[..., 2]  # (m, K, c)
            ax, ay, az = G[:, 3], G[:, 4], G[:, 5]
            wd = w0 - w1
            Jp = np.empty((m, self._pt_offsets.size, 3, G.shape[3]))
            Jp[:, :, 0] = wd * G[:, 0] - (py * az - pz * ay)
            Jp[:, :, 1] = wd * G[:, 1] - (pz * ax - px * az)
            Jp[:, :, 2] = wd * G[:, 2] - (px * ay - py * ax)
            Jx = np.zeros((m, nc * (nv + 1)))
            Jx[:, self._pt_flat] = Jp.reshape(m, -1)
            J[:, self._pt_rows] = Jx.reshape(m, nc, nv + 1)[:, self._pt_rows, :nv]
        for o, s1, M1, s2, M2 in self._welds:
            oMc1 = H[:, s1] @ M1
            oMc2 = H[:, s2] @ M2
            R2, p2 = oMc2[:, :3, :3], oMc2[:, :3, 3]
            D = Jw * (self.masks[s2] - self.masks[s1])  # relative motion, world axes at origin
            D_lin = D[:, :3] - np.cross(p2[:, :, None], D[:, 3:], axis=1)  # ... at c2's origin
            twist = np.concatenate(
                [np.swapaxes(R2, 1, 2) @ D_lin, np.swapaxes(R2, 1, 2) @ D[:, 3:]], axis=1
            )
            c1Mc2 = np.linalg.solve(oMc1, oMc2)
            for k in range(m):
                M = pin.SE3(c1Mc2[k])
                r[k, o : o + 6] = pin.log6(M).vector
                J[k, o : o + 6] = pin.Jlog6(M) @ twist[k]
        if not direct:
            self._reduce(H, r_out=r_out, r=r, J_out=J_out, J=J, Jw=Jw)
        return r_out, J_out

    def frame_force(self, n: int, frame: int, W: np.ndarray) -> np.ndarray:
        """Generalized forces (n, nv) of wrenches applied at a frame's origin.

        Args:
            n: Number of captured samples.
            frame: Frame id (given at construction).
            W: Wrenches (n, 6): force in world axes [N], then moment in the frame's axes [N m].

        Returns:
            ``J_frame^T W`` per sample [N m or N] (``J_frame``: linear velocity of the frame
            origin in world axes, angular velocity in frame axes).

        """
        s, M = self._frame_slot[frame]
        oMf = self.H[:n, s] @ M.homogeneous
        p, R = oMf[:, :3, 3], oMf[:, :3, :3]
        F = W[:, :3]
        moment = cross(p, F) + np.einsum("nij,nj->ni", R, W[:, 3:])  # about the world origin
        Jw = self.Jw[:n]
        g = np.einsum("nrv,nr->nv", Jw[:, :3], F) + np.einsum("nrv,nr->nv", Jw[:, 3:], moment)
        return g * self.masks[s]
