"""The closed-loop regressor: actuator efforts linear in the dynamic parameters.

On the spanning tree, Pinocchio's joint-torque regressor gives the inverse dynamics as
``M a + h = Y_tree(q, v, a) pi`` (``pi``: 10 parameters per body, gravity ``model.gravity``
included). The closures add ``J^T lambda``; the actuators ``S^T tau``. Eliminating ``lambda``
as pkdyn's inverse dynamics does (:mod:`solvers.inverse_dynamics`, its fast path): ``lambda``
solves the passive rows ``J_p^T lambda = b_p`` (least squares, least norm), then
``tau = b_a - J_a^T lambda``, so that, for any generalized force ``b`` (nv,),

    ``tau = T b,   T = [I  on the actuated columns;  -J_a^T (J_p^T)^+  on the passive ones]``

(unit gains: joint-side efforts). ``T`` depends on ``q`` only, so the actuator efforts are
linear in the parameters:

    ``tau_meas = T (Y_tree pi + armature a - f_passive) + drive terms``

with, per actuator ``i`` of reduction ``N`` and joint rate ``qd``, the drive model of
:class:`solvers.Drives` at unit efficiency referred to the joint (``tau_meas = N tau_motor``):
rotor inertia ``N^2 qdd`` x ``J_rotor``, viscous friction ``N^2 qd`` x ``b``, Coulomb friction
``N tanh(N qd / omega_s)`` x ``c`` (``omega_s``: :data:`pkdyn.dynamics.actuation.DRIVE_SMOOTHING`).
A payload's 10 parameters, in the platform frame, enter through the platform body's columns
mapped by :func:`~pkdyn.identification.parameters.placement_map`. The robot's passive elements
(springs, dampers, joint friction: ``robot.passive``) and the armature of non-actuated
coordinates are known terms.

Where the actuators do not determine every joint (internal mobilities: a Delta's bar spin),
the least-squares elimination drops the part of the dynamics no actuator can balance, as the
inverse dynamics' fast path does.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pkdyn.dynamics.actuation import DRIVE_SMOOTHING
from pkdyn.identification.motion import MotionBatch, passive_solve
from pkdyn.identification.parameters import ParameterSet, placement_map
from pkdyn.model.robot import Robot

__all__ = ["ClosedLoopRegressor"]


class ClosedLoopRegressor:
    """Rows of the actuator-space regressor for batches of joint motions (module doc).

    Args:
        robot: The robot.
        parameters: Its parameter set (:func:`~pkdyn.identification.parameters.parameter_set`).

    """

    def __init__(self, robot: Robot, parameters: ParameterSet) -> None:
        self.robot = robot
        self.parameters = parameters
        model = robot.model
        self.model = model
        self.data = model.createData()
        self.va = np.asarray(robot.actuated_v, dtype=int)
        self.vp = np.setdiff1d(np.arange(model.nv), self.va)
        self.reduction = np.array([a.reduction for a in robot.actuators], dtype=float)
        ps = parameters
        self._cols = np.concatenate(
            [np.arange(10 * (j - 1), 10 * j) for j in ps.bodies] or [np.zeros(0, dtype=int)]
        ).astype(int)
        self._all_cols = bool(np.array_equal(self._cols, np.arange(10 * (model.njoints - 1))))
        self._payload_cols = None
        if ps.payload_joint is not None:
            j = ps.payload_joint
            self._payload_cols = np.arange(10 * (j - 1), 10 * j)
            self._payload_L = placement_map(ps.payload_placement)
        arm = np.array(model.armature, dtype=float)
        rotor = np.array([a.rotor_inertia for a in robot.actuators], dtype=float)
        arm[self.va] -= self.reduction**2 * rotor
        self._armature_known = arm  # armature that no rotor parameter carries
        self._has_known_armature = bool(np.any(np.abs(arm) > 1e-15))
        self._sel = ps.identified
        self._known_theta = np.where(ps.identified, 0.0, ps.nominal)

    def elimination(self, J: np.ndarray, passive_map: np.ndarray | None = None) -> np.ndarray:
        """The maps ``T`` (n, n_a, nv) from generalized forces to actuator efforts.

        Args:
            J: Closure Jacobians (n, nc, nv).
            passive_map: ``J_p^+ J_a`` (n, n_p, n_a) if known (:class:`MotionBatch`).

        Returns:
            ``T`` per sample.

        """
        n = J.shape[0]
        n_a, nv = self.va.size, self.model.nv
        T = np.zeros((n, n_a, nv))
        T[:, np.arange(n_a), self.va] = 1.0
        if J.shape[1] and self.vp.size:
            # lambda = (J_p^T)^+ b_p  ->  T_p = -J_a^T (J_p^T)^+ = -((J_p)^+ J_a)^T
            if passive_map is None:
                passive_map = passive_solve(J[:, :, self.vp], J[:, :, self.va])
            T[:, :, self.vp] = -np.swapaxes(passive_map, 1, 2)
        return T

    def full(self, batch: MotionBatch) -> tuple[np.ndarray, np.ndarray]:
        """Regressor of every standard parameter and the efforts of the known terms.

        Args:
            batch: Joint motion (``q, v, a`` and closure Jacobians) of ``n`` samples.

        Returns:
            ``W`` (n, n_a, p): efforts per unit parameter, and ``k`` (n, n_a): the efforts of
            the known passive forces and non-actuated armature [N m or N].

        """
        model, data = self.model, self.data
        q, v, a = batch.q, batch.v, batch.a
        n = q.shape[0]
        ps = self.parameters
        nb = 10 * (model.njoints - 1)
        Yt = np.empty((n, model.nv, nb))
        reg = pin.computeJointTorqueRegressor
        for i in range(n):
            Yt[i] = reg(model, data, q[i], v[i], a[i])
        T = self.elimination(batch.J, batch.passive_map)
        n_a = self.va.size
        W = np.zeros((n, n_a, ps.p))
        nbody = 10 * len(ps.bodies)
        TY = T @ Yt  # (gathering the columns of the small product, not of Yt)
        W[:, :, :nbody] = TY if self._all_cols else TY[:, :, self._cols]
        if self._payload_cols is not None:
            W[:, :, ps.payload_slice] = TY[:, :, self._payload_cols] @ self._payload_L
        qd, qdd = v[:, self.va], a[:, self.va]
        N = self.reduction
        for i in range(n_a):
            W[:, i, ps.drive_column(i, "viscous")] = N[i] ** 2 * qd[:, i]
            W[:, i, ps.drive_column(i, "coulomb")] = N[i] * np.tanh(
                N[i] * qd[:, i] / DRIVE_SMOOTHING
            )
            W[:, i, ps.drive_column(i, "rotor_inertia")] = N[i] ** 2 * qdd[:, i]
        passive = self.robot.passive
        if not self._has_known_armature and passive is None:
            return W, np.zeros((n, n_a))
        b = np.zeros((n, model.nv))
        if self._has_known_armature:
            b += self._armature_known * a
        if passive is not None:
            b -= passive.forces(q, v)
        return W, (T @ b[..., None])[..., 0]

    def rows(self, batch: MotionBatch) -> tuple[np.ndarray, np.ndarray]:
        """Regressor of the identified parameters and the efforts of everything held.

        Args:
            batch: Joint motion of ``n`` samples.

        Returns:
            ``Y`` (n, n_a, p_id) and ``known`` (n, n_a) [N m or N]: the measured efforts are
            ``Y theta_id + known`` (plus noise).

        """
        W, known = self.full(batch)
        known = known + W @ self._known_theta
        return W[:, :, self._sel], known

    def efforts(self, batch: MotionBatch, theta: np.ndarray) -> np.ndarray:
        """Efforts (n, n_a) [N m or N] of a batch for standard parameters ``theta`` (p,)."""
        W, known = self.full(batch)
        return W @ theta + known
