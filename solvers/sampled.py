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
:class:`~solvers.closure.ClosureSet`):

- 3D point: residual ``p1 - p2``, velocity error ``v_p1 - v_p2 = J v`` and acceleration error
  ``a_p1 - a_p2 = J a + gamma``, world axes [m, m/s, m/s^2];
- 6D weld: residual ``log6(c1Mc2)``; velocity and acceleration errors: the relative twist
  ``X(oMc2)^-1 (V_2 - V_1)`` and its rate ``X(oMc2)^-1 (A_2 - A_1)`` in the contact frame of
  ``joint2`` (equal to ``J v`` and ``J a + gamma`` up to the factor ``Jlog6(c1Mc2) = I + O(|r|)``;
  the rate is exact when the relative twist vanishes, as the drift of ``ClosureSet`` is);
- joint coupling (:mod:`solvers.coupling`): residual, ``J v`` and ``J a + gamma`` from the
  configurations, velocities and accelerations themselves [rad or m, per s, per s^2].
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from solvers.closure import ClosureSet

__all__ = ["SampledKinematics"]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (..., 3) arrays (cheaper than ``np.cross`` on small rows)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


class SampledKinematics:
    """Buffers of per-sample kinematics and their vectorised evaluation (see the module doc).

    Args:
        model: The kinematic tree.
        closure_set: The closures.
        frames: Frame ids whose placement is also captured (for :meth:`frame_force`).
        size: Number of samples the buffers hold.

    """

    def __init__(
        self,
        model: pin.Model,
        closure_set: ClosureSet,
        frames: Sequence[int] = (),
        size: int = 256,
    ) -> None:
        self.model = model
        self.closure_set = closure_set
        self.size = int(size)
        items = closure_set.items
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
                self.masks[s] = ClosureSet._support_mask(model, j)
        self.H = np.empty((self.size, nj, 4, 4))
        self.H[:, 0] = np.eye(4)
        self.Jw = np.empty((self.size, 6, nv))
        self.acc = np.empty((self.size, nj, 6))
        self.acc[:, 0] = -model.gravity.vector  # the world's, as rnea sets it
        pts = [k for k, it in enumerate(items) if it[0]]
        self._pt_offsets = np.array([closure_set.offsets[k] for k in pts], dtype=int)
        self._pt_slot = np.array(
            [[slot[int(items[k][1])] for k in pts], [slot[int(items[k][3])] for k in pts]],
            dtype=int,
        ).reshape(2, len(pts))
        self._pt_local = np.array(
            [[items[k][2].translation for k in pts], [items[k][4].translation for k in pts]]
        ).reshape(2, len(pts), 3)
        self._pt_rows = (self._pt_offsets[:, None] + np.arange(3)).reshape(-1)
        self._welds = [
            (
                int(closure_set.offsets[k]),
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

    def _velocities(self, n: int, v: np.ndarray) -> np.ndarray:
        """World spatial velocities (n, nj, 6) of the captured bodies at the origin."""
        return np.swapaxes((self.Jw[:n] * v[:, None, :]) @ self.masks.T, 1, 2)

    def _accelerations(self, n: int) -> np.ndarray:
        """World spatial accelerations (n, nj, 6) of the captured bodies at the origin."""
        H, acc = self.H[:n], self.acc[:n]
        R, p = H[..., :3, :3], H[..., :3, 3]
        ang = np.einsum("nkij,nkj->nki", R, acc[..., 3:])
        lin = np.einsum("nkij,nkj->nki", R, acc[..., :3]) + _cross(p, ang)
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
        nc = self.closure_set.nc
        r = np.empty((n, nc))
        ev = np.empty((n, nc))
        ea = np.empty((n, nc))
        if not nc:
            return r, ev, ea
        coupled = self.closure_set.coupling_rows
        if coupled is not None:
            if q is None or a is None:
                raise ValueError("coupling rows need the configurations and accelerations")
            o = self.closure_set.n_rigid
            qq, vv, aa = q[:n], v[:n], a[:n]
            r[:, o:] = coupled.residual(qq)
            ev[:, o:] = coupled.velocity_error(qq, vv)
            ea[:, o:] = coupled.acceleration_error(qq, vv, aa)
            if o == 0:
                return r, ev, ea
        V = self._velocities(n, v)
        A = self._accelerations(n)
        H = self.H[:n]
        if self._pt_offsets.size:
            side = []
            for s in (0, 1):
                slot = self._pt_slot[s]
                Hs = H[:, slot]  # (n, K, 4, 4)
                p = np.einsum("nkij,kj->nki", Hs[..., :3, :3], self._pt_local[s]) + Hs[..., :3, 3]
                Vs, As = V[:, slot], A[:, slot]
                w = Vs[..., 3:]
                vp = Vs[..., :3] + _cross(w, p)
                ap = As[..., :3] + _cross(As[..., 3:], p) + _cross(w, vp)
                side.append((p, vp, ap))
            rows = self._pt_rows
            r[:, rows] = (side[0][0] - side[1][0]).reshape(n, -1)
            ev[:, rows] = (side[0][1] - side[1][1]).reshape(n, -1)
            ea[:, rows] = (side[0][2] - side[1][2]).reshape(n, -1)
        for o, s1, M1, s2, M2 in self._welds:
            oMc1 = H[:, s1] @ M1
            oMc2 = H[:, s2] @ M2
            R2, p2 = oMc2[:, :3, :3], oMc2[:, :3, 3]
            for err, X in ((ev, V), (ea, A)):
                d = X[:, s2] - X[:, s1]  # relative motion, world axes at the origin
                lin = d[:, :3] + _cross(d[:, 3:], p2)  # ... at the contact point of joint2
                err[:, o : o + 3] = np.einsum("nji,nj->ni", R2, lin)
                err[:, o + 3 : o + 6] = np.einsum("nji,nj->ni", R2, d[:, 3:])
            c1Mc2 = np.linalg.solve(oMc1, oMc2)
            for k in range(n):
                r[k, o : o + 6] = pin.log6(c1Mc2[k]).vector
        return r, ev, ea

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
        moment = _cross(p, F) + np.einsum("nij,nj->ni", R, W[:, 3:])  # about the world origin
        Jw = self.Jw[:n]
        g = np.einsum("nrv,nr->nv", Jw[:, :3], F) + np.einsum("nrv,nr->nv", Jw[:, 3:], moment)
        return g * self.masks[s]
