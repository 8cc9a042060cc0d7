"""Kinematically redundant robots: a platform trajectory plus prescribed joint coordinates.

When a mechanism has more degrees of freedom than its platform task has components (e.g. the
four-branch walker of seed 003 carrying a foot: 8 DOF, a 6-component task), the task leaves some
motions free. :func:`map_redundant_trajectory` fixes them by prescribing as many joint
coordinates ``r(t)`` (one-dimensional joints, e.g. some actuators) with their rates and
accelerations, and maps the whole to a :class:`~pkdyn.dynamics.trajectory.JointTrajectory`
consistent with the closures, as :func:`~pkdyn.dynamics.trajectory.map_task_trajectory` does for a
non-redundant task: at every sample ``q`` solves the closures, the task and ``q[r] = r(t)``
together (Levenberg-Marquardt, warm-started from a second-order prediction), ``v`` and ``a``
solve ``[Jc; Jx; S_r] v = [0; x_dot; r_dot]`` and
``[Jc; Jx; S_r] a = [-gamma_c; x_ddot - gamma_x; r_ddot]`` exactly. Whoever chooses ``r(t)``
(an optimisation, :mod:`pkdyn.tripod.redundancy`) decides the redundant motion. The actuator
limits are not checked here (the caller's analysis reports them).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from pkdyn.dynamics.trajectory import (
    JointTrajectory,
    TaskTrajectory,
    _lstsq,
    _platform_drift,
    _task_rates,
)
from pkdyn.exceptions import InvalidInputError, TrajectoryError
from pkdyn.model.assembly import DEFAULT_TOL
from pkdyn.model.pose import pose_from_vector
from pkdyn.model.robot import PLATFORM_HINT, Robot
from solvers import FramePoseTask, solve_lm

__all__ = ["map_redundant_trajectory"]


def _indices(robot: Robot, joints: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    iq, iv = [], []
    for name in joints:
        if not robot.model.existJointName(name):
            raise InvalidInputError("joints", f"{robot.name} has no joint named {name!r}")
        jm = robot.model.joints[robot.model.getJointId(name)]
        if jm.nq != 1 or jm.nv != 1:
            raise InvalidInputError("joints", f"{name!r} is not a one-dimensional joint")
        iq.append(jm.idx_q)
        iv.append(jm.idx_v)
    return np.array(iq, dtype=int), np.array(iv, dtype=int)


def map_redundant_trajectory(
    robot: Robot,
    task: TaskTrajectory,
    joints: Sequence[str],
    values: np.ndarray,
    rates: np.ndarray,
    accelerations: np.ndarray,
    q_init: np.ndarray | None = None,
    tol: float = DEFAULT_TOL,
) -> JointTrajectory:
    """Joint trajectory following a platform trajectory and prescribed joint coordinates.

    Args:
        robot: The robot (must declare a platform).
        task: The platform trajectory (N samples).
        joints: Names of the prescribed one-dimensional joints (m of them).
        values: Their coordinates (N, m) [rad or m].
        rates: Their rates (N, m) [rad/s or m/s].
        accelerations: Their accelerations (N, m) [rad/s^2 or m/s^2].
        q_init: Configuration near the first sample (default ``robot.q_home``).
        tol: Largest residual of the closures, the task and the prescribed coordinates at each
            sample [m or rad].

    Returns:
        The joint trajectory.

    Raises:
        InvalidInputError: Unknown joints or arrays of the wrong shape.
        TrajectoryError: A sample cannot be reached, or the task and the prescribed coordinates
            leave some motion undetermined or over-determined (the message names the sample).

    """
    if robot.platform_frame is None:
        raise InvalidInputError(
            "robot", f"{robot.name} declares no platform frame; {PLATFORM_HINT}"
        )
    iq, iv = _indices(robot, joints)
    N, m = task.t.size, iq.size
    arrays = [np.asarray(x, dtype=float) for x in (values, rates, accelerations)]
    for what, arr in zip(("values", "rates", "accelerations"), arrays, strict=True):
        if arr.shape != (N, m) or not np.all(np.isfinite(arr)):
            raise InvalidInputError(what, f"expected ({N}, {m}) finite numbers, got {arr.shape}")
    r, rd, rdd = arrays
    model, data = robot.model, robot.data
    rows = robot.task_rows
    cs = robot.constraints
    pose_task = FramePoseTask(model, robot.platform_frame, rows)
    S = np.zeros((m, robot.nv))
    S[np.arange(m), iv] = 1.0

    def residual(q: np.ndarray, k: int) -> np.ndarray:
        pin.framesForwardKinematics(model, data, q)
        return np.concatenate([cs.residual(data, q), pose_task.residual(data), q[iq] - r[k]])

    def jacobian(q: np.ndarray) -> np.ndarray:
        _, Jc = cs.residual_and_jacobian(data, q)
        return np.vstack([Jc, pose_task.residual_and_jacobian(data)[1], S])

    Q = np.empty((N, robot.nq))
    V = np.empty((N, robot.nv))
    A = np.empty((N, robot.nv))
    q = np.array(robot.q_home if q_init is None else q_init, dtype=float)
    for k in range(N):
        tk = float(task.t[k])
        if k:
            h = tk - float(task.t[k - 1])
            q = pin.integrate(model, q, h * V[k - 1] + 0.5 * h * h * A[k - 1])
        pose_task.target = pose_from_vector(task.pose[k])
        sol = solve_lm(model, q, functools.partial(residual, k=k), jacobian, tol=tol)
        if not sol.converged:
            raise TrajectoryError(
                f"the platform pose and the prescribed {', '.join(joints)} cannot be reached "
                f"together (residual {sol.error:.3g})",
                sample=k,
                time=tk,
            )
        q = sol.q
        pin.computeJointJacobians(model, data, q)
        K = jacobian(q)
        nc = cs.n
        xd, xdd = _task_rates(task.pose[k], task.pose_d[k], task.pose_dd[k])
        rhs_v = np.concatenate([np.zeros(nc), xd[rows], rd[k]])
        v, res_v, null = _lstsq(K, rhs_v, 1e-10)
        if null.shape[1] or res_v > 1e-8 * max(1.0, float(np.max(np.abs(rhs_v)))):
            what = "leave a motion free" if null.shape[1] else "are not compatible"
            raise TrajectoryError(
                f"the platform rates and the prescribed rates {what} here (residual {res_v:.3g}, "
                f"{null.shape[1]} free motions): prescribe the robot's redundant coordinates",
                sample=k,
                time=tk,
            )
        gamma_c = cs.drift(data, q, v)
        gamma_x = _platform_drift(robot, q, v)[rows]
        rhs_a = np.concatenate([-gamma_c, xdd[rows] - gamma_x, rdd[k]])
        a, res_a, _ = _lstsq(K, rhs_a, 1e-10)
        if res_a > 1e-8 * max(1.0, float(np.max(np.abs(rhs_a)))):
            raise TrajectoryError(
                f"the accelerations are not feasible here (residual {res_a:.3g})",
                sample=k,
                time=tk,
            )
        Q[k], V[k], A[k] = q, v, a
    return JointTrajectory(
        task.t.copy(), Q, V, A, robot.actuated_q, robot.actuated_v, task=task, name=task.name
    )
