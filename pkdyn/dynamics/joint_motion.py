"""Joint trajectories driven from actuator space, consistent with the closures.

:func:`actuator_trajectory` turns sampled actuator motions ``qa(t)``, ``qa_dot(t)``,
``qa_ddot(t)`` into a :class:`~pkdyn.dynamics.trajectory.JointTrajectory` of the whole
mechanism, for robots without a platform task (legs, linkages) or when the motion is given in
actuator space. At every sample:

- ``q`` is assembled with the actuators at ``qa`` (warm-started from the previous sample, so
  the assembly mode is followed); floating-base joints (free-flyer, planar) stay where they
  are, with zero velocity and acceleration;
- ``v`` solves ``Jc v = 0`` with the actuator rates imposed, and ``a`` solves
  ``Jc a = -gamma`` (the closures' drift, :meth:`solvers.ConstraintSet.drift`) with the actuator
  accelerations imposed;
- the internal mobilities that no actuator moves (the spin of a ball-ended rod, a leaf spring)
  have zero momentum (``N^T M v = 0``) and move as the dynamics dictate
  (``N^T (M a + h - f_passive) = 0``, with the robot's springs, dampers and friction), so that
  :func:`pkdyn.dynamics.inverse_dynamics` has an exact solution.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from pkdyn.dynamics.trajectory import JointTrajectory
from pkdyn.exceptions import InvalidInputError, TrajectoryError
from pkdyn.model.reuse import kept_data
from pkdyn.model.robot import MODELLING_JOINTS, Robot
from solvers import numerics, solve_lm

__all__ = ["ASSEMBLY_RTOL", "ASSEMBLY_TOL", "actuator_trajectory"]

ASSEMBLY_RTOL = 1e-10
"""Closure residual each sample is assembled to, relative to the robot's size
(:meth:`pkdyn.Robot.closure_tolerance`; round-off of a large model's closures is ~1e-12 of it)."""

ASSEMBLY_TOL = ASSEMBLY_RTOL
"""The former name of :data:`ASSEMBLY_RTOL` (kept for one release)."""


def _samples(
    x: Sequence[Sequence[float]] | np.ndarray, shape: tuple[int, int], what: str
) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.shape != shape or not np.all(np.isfinite(a)):
        raise InvalidInputError(what, f"expected {shape} finite values, got {a.shape}")
    return a


def actuator_trajectory(
    robot: Robot,
    t: Sequence[float] | np.ndarray,
    qa: Sequence[Sequence[float]] | np.ndarray,
    qa_dot: Sequence[Sequence[float]] | np.ndarray,
    qa_ddot: Sequence[Sequence[float]] | np.ndarray,
    q_init: np.ndarray | None = None,
    name: str = "actuator trajectory",
) -> JointTrajectory:
    """Joint trajectory of the whole mechanism from an actuator-space motion.

    Args:
        robot: The robot.
        t: Sample times (N,) [s].
        qa: Actuator positions (N, n_a) [rad or m].
        qa_dot: Actuator rates (N, n_a) [rad/s or m/s].
        qa_ddot: Actuator accelerations (N, n_a) [rad/s^2 or m/s^2].
        q_init: Configuration of the first sample's warm start (default ``robot.q_home``).
        name: Name of the trajectory.

    Returns:
        The joint trajectory.

    Raises:
        InvalidInputError: Malformed samples.
        TrajectoryError: A sample cannot be assembled, or the actuators cannot move
            independently there (a singular configuration), naming the sample.

    """
    tt = np.asarray(t, dtype=float).reshape(-1)
    N, n_a = tt.size, len(robot.actuators)
    if N == 0 or not np.all(np.isfinite(tt)):
        raise InvalidInputError("t", "expected finite sample times")
    QA = _samples(qa, (N, n_a), "qa")
    QD = _samples(qa_dot, (N, n_a), "qa_dot")
    QDD = _samples(qa_ddot, (N, n_a), "qa_ddot")
    model, data = robot.model, kept_data(robot, "joint_motion")
    cs = robot.constraints
    held = [
        i
        for j in range(1, model.njoints)
        if model.joints[j].shortname() in MODELLING_JOINTS
        for i in range(model.joints[j].idx_v, model.joints[j].idx_v + model.joints[j].nv)
    ]
    fixed = np.array(sorted(set(held) | set(robot.actuated_v.tolist())), dtype=int)
    free = np.setdiff1d(np.arange(model.nv), fixed)
    S = np.zeros((fixed.size, model.nv))
    S[np.arange(fixed.size), fixed] = 1.0
    act_rows = np.searchsorted(fixed, robot.actuated_v)
    q = np.array(robot.q_home if q_init is None else q_init, dtype=float)
    tol = robot.closure_tolerance(ASSEMBLY_RTOL)
    Q = np.empty((N, model.nq))
    V = np.empty((N, model.nv))
    A = np.empty((N, model.nv))
    for k in range(N):
        q[robot.actuated_q] = QA[k]
        if cs.n:
            sol = solve_lm(
                model,
                q,
                lambda x: cs.residual(data, x),
                lambda x: cs.jacobian(data, x),
                free,
                tol,
            )
            if not sol.converged:
                raise TrajectoryError(
                    f"cannot be assembled (closure residual {sol.error:.3g})", k, float(tt[k])
                )
            q = sol.q
            Jc = cs.jacobian(data, q)
        else:
            Jc = np.zeros((0, model.nv))
        G = np.vstack([Jc, S])
        rhs = np.zeros(G.shape[0])
        rhs[Jc.shape[0] + act_rows] = QD[k]
        v, Nm = numerics.lstsq_null(G, rhs, numerics.RTOL, 1.0)
        if np.max(np.abs(G @ v - rhs), initial=0.0) > 1e-9 * max(1.0, float(np.abs(rhs).max())):
            raise TrajectoryError(
                "the actuators cannot move independently here (singular configuration)",
                k,
                float(tt[k]),
            )
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        if Nm.shape[1]:
            K = Nm.T @ M @ Nm
            v = v - Nm @ np.linalg.solve(K, Nm.T @ M @ v)
        rhs_a = np.zeros(G.shape[0])
        if cs.n:
            rhs_a[: Jc.shape[0]] = -cs.drift(data, q, v)
        rhs_a[Jc.shape[0] + act_rows] = QDD[k]
        a = numerics.lstsq(G, rhs_a, numerics.RTOL, 1.0)
        if Nm.shape[1]:
            h = pin.rnea(model, data, q, v, np.zeros(model.nv))
            if robot.passive is not None:
                h = h - robot.passive.force(q, v)
            a = a - Nm @ np.linalg.solve(K, Nm.T @ (M @ a + h))
        Q[k], V[k], A[k] = q, v, a
    return JointTrajectory(
        tt, Q, V, A, robot.actuated_q.copy(), robot.actuated_v.copy(), None, name
    )
