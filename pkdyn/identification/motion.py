"""Joint motions of the whole mechanism from measured actuator motions, sample after sample.

Identification reads actuator positions ``qa`` (and rates, accelerations) only; the regressor
needs the configuration, velocity and acceleration ``(q, v, a)`` of every joint. Per sample:

- ``q``: the actuators at ``qa``, the other coordinates solved onto the closures by Newton's
  method (minimum-norm steps) from a quadratic extrapolation of the three previous samples (at
  a millisecond sampling one step converges; a few more when the sampling is coarse,
  Levenberg-Marquardt from the previous sample when Newton stalls). The assembly mode of the
  start configuration (default ``robot.q_home``) is followed;
- ``v``: ``J v = 0`` with the actuator rates imposed, ``a``: ``J a = -gamma`` with the actuator
  accelerations imposed (``gamma``: the closures' acceleration drift, computed for a batch of
  samples at once by :class:`solvers.SampledKinematics`). The passive coordinates get the
  least-squares solution ``v_p = -J_p^+ J_a qa_dot``: unique when the actuators determine the
  mechanism; where internal mobilities remain (the spin of a Delta's ball-jointed bars, which no
  sensor measures) the solution of least norm, i.e. no spin relative to the neighbouring bodies.

Per sample only Pinocchio's C++ runs (closure residual and Jacobian, ``rnea``, the joint
Jacobians); the velocity and acceleration solves are batched with numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import TrajectoryError
from pkdyn.model.robot import Robot
from solvers import SampledKinematics, solve_lm

__all__ = ["ASSEMBLY_TOL", "BATCH", "MotionBatch", "MotionSampler", "passive_solve"]

ASSEMBLY_TOL = 1e-10
"""Closure residual [m or rad] each sample is assembled to."""

BATCH = 256
"""Samples per batch."""

_NEWTON_STEPS = 12
_REG = 1e-15  # relative regularisation of the Gram matrices (rank-deficient closure rows)


@dataclass(eq=False)  # numpy fields
class MotionBatch:
    """Joint motion of a batch of consecutive samples.

    Attributes:
        q: Configurations (n, nq).
        v: Velocities (n, nv).
        a: Accelerations (n, nv).
        J: Closure Jacobians (n, nc, nv) (:class:`solvers.ClosureSet` convention).
        first: Index of the first sample in the whole series.

    """

    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    J: np.ndarray
    first: int = 0


def passive_solve(Jp: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Least-squares, least-norm solutions ``J_p^+ x`` of a batch, by regularised normal equations.

    Args:
        Jp: Passive columns of the closure Jacobians (n, nc, n_p).
        x: Right-hand sides (n, nc) or (n, nc, k).

    Returns:
        ``J_p^+ x``: (n, n_p) or (n, n_p, k).

    """
    vec = x.ndim == 2
    X = x[..., None] if vec else x
    n, nc, n_p = Jp.shape
    JpT = np.swapaxes(Jp, 1, 2)
    if nc <= n_p:
        G = Jp @ JpT
        G += _REG * np.trace(G, axis1=1, axis2=2)[:, None, None] * np.eye(nc)
        out = JpT @ np.linalg.solve(G, X)
    else:
        G = JpT @ Jp
        G += _REG * np.trace(G, axis1=1, axis2=2)[:, None, None] * np.eye(n_p)
        out = np.linalg.solve(G, JpT @ X)
    return out[..., 0] if vec else out


def _step(Jp: np.ndarray, r: np.ndarray) -> np.ndarray:
    """One sample's least-squares, least-norm ``J_p^+ r`` (as :func:`passive_solve`)."""
    nc, n_p = Jp.shape
    if nc <= n_p:
        G = Jp @ Jp.T
        G.flat[:: nc + 1] += _REG * G.trace()
        return Jp.T @ np.linalg.solve(G, r)
    G = Jp.T @ Jp
    G.flat[:: n_p + 1] += _REG * G.trace()
    return np.linalg.solve(G, Jp.T @ r)


class MotionSampler:
    """Turns actuator motions into joint motions batch after batch (see the module doc).

    Args:
        robot: The robot.
        q_init: Start configuration (default ``robot.q_home``): the assembly mode followed.

    """

    def __init__(self, robot: Robot, q_init: np.ndarray | None = None) -> None:
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.cs = robot.closure_set
        self.kin = SampledKinematics(robot.model, robot.closure_set, (), BATCH)
        self.va = np.asarray(robot.actuated_v, dtype=int)
        self.aq = np.asarray(robot.actuated_q, dtype=int)
        self.vp = np.setdiff1d(np.arange(robot.nv), self.va)
        q0 = robot.q_home if q_init is None else q_init
        self._history: list[np.ndarray] = [np.array(q0, dtype=float)]
        self._fresh = True

    def restart(self, q: np.ndarray) -> None:
        """Forget the previous samples: the next one starts from ``q`` (nq,)."""
        self._history = [np.array(q, dtype=float)]
        self._fresh = True

    def _guess(self) -> np.ndarray:
        h = self._history
        if self._fresh or len(h) == 1:
            return h[-1].copy()
        dif = pin.difference
        d1 = dif(self.model, h[-2], h[-1])
        if len(h) == 2:
            return pin.integrate(self.model, h[-1], d1)
        d2 = dif(self.model, h[-3], h[-2])
        return pin.integrate(self.model, h[-1], 2.0 * d1 - d2)

    def _newton(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, float]:
        """Newton steps on the passive coordinates: ``(q, J at q or None, residual)``."""
        model, data, cs, vp = self.model, self.data, self.cs, self.vp
        dq = np.zeros(model.nv)
        err = np.inf
        for _ in range(_NEWTON_STEPS):
            r, J = cs.residual_and_jacobian(data, q)
            err_new = float(np.abs(r).max(initial=0.0))
            if err_new <= ASSEMBLY_TOL:
                return q, J, err_new
            if err_new > 0.9 * err:  # not converging: let Levenberg-Marquardt take over
                return q, None, err_new
            err = err_new
            dq[vp] = -_step(J[:, vp], r)
            q = pin.integrate(model, q, dq)
        return q, None, err

    def configurations(self, qa: np.ndarray, t: np.ndarray, first: int = 0) -> tuple:
        """Assembled configurations and closure Jacobians of consecutive samples.

        Args:
            qa: Actuator positions (n, n_a) [rad or m].
            t: Their times (n,) [s] (for error messages).
            first: Index of the first sample in the whole series.

        Returns:
            ``(Q (n, nq), J (n, nc, nv))``.

        Raises:
            TrajectoryError: A sample cannot be assembled.

        """
        model, cs = self.model, self.cs
        n = qa.shape[0]
        Q = np.empty((n, model.nq))
        J = np.empty((n, cs.nc, model.nv))
        for k in range(n):
            q = self._guess()
            q[self.aq] = qa[k]
            if cs.nc:
                q, Jk, err = self._newton(q)
                if Jk is None:
                    start = self._history[-1].copy()
                    start[self.aq] = qa[k]
                    sol = solve_lm(
                        model,
                        start,
                        residual_and_jacobian=lambda x: cs.residual_and_jacobian(self.data, x),
                        free=self.vp,
                        tol=ASSEMBLY_TOL,
                    )
                    if not sol.converged:
                        raise TrajectoryError(
                            f"the actuator positions cannot be assembled (closure residual "
                            f"{sol.error:.3g}): out of reach, or a jump between samples",
                            first + k,
                            float(t[k]),
                        )
                    q = sol.q
                    _, Jk = cs.residual_and_jacobian(self.data, q)
                J[k] = Jk
            Q[k] = q
            self._history = [*self._history[-2:], q]
            self._fresh = False
        return Q, J

    def batch(
        self, t: np.ndarray, qa: np.ndarray, qd: np.ndarray, qdd: np.ndarray, first: int = 0
    ) -> MotionBatch:
        """Joint motion of consecutive samples (at most :data:`BATCH`).

        Args:
            t: Times (n,) [s].
            qa: Actuator positions (n, n_a) [rad or m].
            qd: Actuator rates (n, n_a) [rad/s or m/s].
            qdd: Actuator accelerations (n, n_a) [rad/s^2 or m/s^2].
            first: Index of the first sample in the whole series.

        Returns:
            The batch's ``(q, v, a)`` and closure Jacobians.

        Raises:
            TrajectoryError: A sample cannot be assembled, or the actuators cannot move
                independently there (a singular configuration).

        """
        model, data, cs = self.model, self.data, self.cs
        n = qa.shape[0]
        Q, J = self.configurations(qa, t, first)
        V = np.zeros((n, model.nv))
        A = np.zeros((n, model.nv))
        V[:, self.va] = qd
        A[:, self.va] = qdd
        if cs.nc and self.vp.size:
            Jp, Ja = J[:, :, self.vp], J[:, :, self.va]
            rhs = -np.einsum("nij,nj->ni", Ja, qd)
            V[:, self.vp] = passive_solve(Jp, rhs)
            err = np.abs(np.einsum("nij,nj->ni", J, V)).max(axis=1)
            bad = np.flatnonzero(err > 1e-8 * np.maximum(1.0, np.abs(V).max(axis=1)))
            if bad.size:
                k = int(bad[0])
                raise TrajectoryError(
                    "the actuators cannot move independently here (singular configuration): "
                    f"the closures keep a velocity error of {err[k]:.3g}",
                    first + k,
                    float(t[k]),
                )
            zero = np.zeros(model.nv)
            kin = self.kin
            for i in range(n):
                pin.rnea(model, data, Q[i], V[i], zero)
                pin.computeJointJacobians(model, data, Q[i])
                kin.capture(i, data)
            gamma = kin.closure_errors(n, V)[2]
            rhs = -(np.einsum("nij,nj->ni", Ja, qdd) + gamma)
            A[:, self.vp] = passive_solve(Jp, rhs)
        return MotionBatch(Q, V, A, J, first)
