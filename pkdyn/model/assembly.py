"""Assembly and geometric models of any loaded robot, by the general numeric path.

- :func:`project`: the assembled configuration nearest (minimum-norm steps) to a guess;
- :func:`forward_geometry` (direct geometric model): actuated coordinates -> full configuration
  and platform pose, in the assembly mode reached from the initial guess;
- :func:`assembly_modes`: the assembly modes found from many initial guesses;
- :func:`inverse_geometry` (inverse geometric model): platform pose -> actuated coordinates.

The closure equations and the platform pose equations are solved together by
:func:`solvers.solve_lm`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import AssemblyError, JointLimitError, UnreachablePoseError
from pkdyn.model.pose import as_finite, pose_from_vector, pose_to_vector
from pkdyn.model.robot import Robot
from solvers import FramePoseTask, SolveResult, solve_lm

__all__ = [
    "DEFAULT_TOL",
    "GeometryResult",
    "project",
    "forward_geometry",
    "assembly_modes",
    "inverse_geometry",
    "closure_residual",
    "solve_pose",
]

DEFAULT_TOL = 1e-12
"""Convergence threshold on the largest closure / pose residual component [m or rad]."""

_LOCAL_TOL = 1.0
"""The solvers work on the contact-frame closure residual (:meth:`solvers.ClosureSet.
local_residual`, the world one rotated: same norm per closure); ``tol`` applies to its
components."""


@dataclass
class GeometryResult:
    """A solved geometric model.

    Attributes:
        q: Full assembled configuration (nq,).
        qa: Actuated coordinates in actuator order [rad or m].
        placement: Platform placement (``None`` if the robot has no platform).
        residual: Largest closure residual component after the solve [m or rad] (in the
            contact frames the solver works in: the world residual rotated).
        iterations: Solver iterations.

    """

    q: np.ndarray
    qa: np.ndarray
    placement: pin.SE3 | None
    residual: float
    iterations: int

    @property
    def position(self) -> np.ndarray:
        """Platform position [m]."""
        assert self.placement is not None
        return pose_to_vector(self.placement)[0]

    @property
    def rpy(self) -> np.ndarray:
        """Platform roll, pitch, yaw [rad]."""
        assert self.placement is not None
        return pose_to_vector(self.placement)[1]


def closure_residual(robot: Robot, q: np.ndarray) -> float:
    """Largest absolute closure residual component at ``q`` [m or rad] (0 without loops)."""
    if robot.closure_set.nc == 0:
        return 0.0
    return float(np.max(np.abs(robot.closure_set.residual(robot.data, q))))


def _solve_closures(
    robot: Robot, q0: np.ndarray, free: np.ndarray | None, tol: float
) -> SolveResult:
    cs, data = robot.closure_set, robot.data
    return solve_lm(
        robot.model,
        q0,
        partial(cs.local_residual, data),  # contact-frame residual: one copy per closure
        partial(cs.local_jacobian_after_residual, data),  # at the last residual's q
        free=free,
        tol=tol * _LOCAL_TOL,
    )


def _worst(robot: Robot, q: np.ndarray) -> tuple[str, float]:
    if robot.closure_set.nc == 0:
        return "-", 0.0
    per = robot.closure_set.split(robot.closure_set.residual(robot.data, q))
    owners = dict(zip(robot.closure_set.names, robot.constraint_owner, strict=True))
    name = max(per, key=lambda k: per[k])
    return owners[name], per[name]


def _result(robot: Robot, sol: SolveResult, closure_error: float) -> GeometryResult:
    """The result of a converged solve.

    The robot data holds the kinematics of ``sol.q``: the solver's last evaluation was there.
    """
    placement = None
    if robot.platform_frame is not None:
        placement = pin.SE3(pin.updateFramePlacement(robot.model, robot.data, robot.platform_frame))
    return GeometryResult(sol.q, sol.q[robot.actuated_q], placement, closure_error, sol.iterations)


def project(robot: Robot, q: np.ndarray, tol: float = DEFAULT_TOL) -> np.ndarray:
    """Assembled configuration near ``q``: minimum-norm Gauss-Newton steps onto the closures.

    Args:
        robot: The robot.
        q: Guess (nq,), need not satisfy the closures.
        tol: Residual threshold [m or rad].

    Returns:
        An assembled configuration (nq,).

    Raises:
        InvalidInputError: ``q`` has the wrong size or non-finite values.
        AssemblyError: The closures cannot be satisfied from this guess.

    """
    q = as_finite("q", q, robot.nq)
    if robot.closure_set.nc == 0:
        return q
    sol = _solve_closures(robot, q, None, tol)
    if not sol.converged:
        name, res = _worst(robot, sol.q)
        raise AssemblyError(
            name,
            res,
            f"{robot.name}: cannot assemble: closure '{name}' keeps a residual of {res:.3g} "
            "(check the geometry: link lengths, closure frames)",
        )
    return sol.q


def forward_geometry(
    robot: Robot,
    qa: Sequence[float] | np.ndarray,
    q_init: np.ndarray | None = None,
    tol: float = DEFAULT_TOL,
    check_limits: bool = True,
) -> GeometryResult:
    """Direct geometric model: full configuration and platform pose from actuated coordinates.

    The passive coordinates are solved from ``q_init`` (default ``robot.q_home``); the assembly
    mode is the one this guess leads to (see :func:`assembly_modes` to enumerate them).

    Args:
        robot: The robot.
        qa: Actuated coordinates in actuator order [rad or m].
        q_init: Initial configuration (nq,), e.g. the previous solution (warm start).
        tol: Residual threshold [m or rad].
        check_limits: Raise if an actuated coordinate is outside its limits.

    Returns:
        The solved configuration and platform placement.

    Raises:
        InvalidInputError: Wrong number of values or non-finite values.
        JointLimitError: An actuated coordinate is outside its limits.
        AssemblyError: The mechanism cannot be assembled with these actuator values.

    """
    qa = as_finite("actuated coordinates", qa, len(robot.actuators))
    q0 = robot.q_home.copy() if q_init is None else as_finite("q_init", q_init, robot.nq)
    q0[robot.actuated_q] = qa
    if check_limits:
        iq = robot.actuated_q
        lo, hi = robot.model.lowerPositionLimit[iq], robot.model.upperPositionLimit[iq]
        if not ((qa >= lo - 1e-12) & (qa <= hi + 1e-12)).all():
            check_actuator_limits(robot, q0)  # raises, naming the actuator
    sol = _solve_closures(robot, q0, robot.passive_v, tol)
    if not sol.converged:
        name, res = _worst(robot, sol.q)
        raise AssemblyError(
            name,
            res,
            f"{robot.name}: actuator values {np.array2string(qa, precision=6)} cannot be "
            f"assembled: closure '{name}' keeps a residual of {res:.3g}",
        )
    return _result(robot, sol, sol.error)


def assembly_modes(
    robot: Robot,
    qa: Sequence[float] | np.ndarray,
    starts: int = 64,
    seed: int = 0,
    spread: float = 1.5,
) -> list[GeometryResult]:
    """Enumerate assembly modes (direct geometric model solutions) from random guesses.

    Args:
        robot: The robot.
        qa: Actuated coordinates [rad or m].
        starts: Number of random initial guesses.
        seed: Random seed.
        spread: Amplitude of the random passive perturbation [rad or m].

    Returns:
        Distinct solutions, sorted by platform height then position (first: the home-like one).

    """
    qa = as_finite("actuated coordinates", qa, len(robot.actuators))
    rng = np.random.default_rng(seed)
    found: list[GeometryResult] = []
    for k in range(starts):
        dv = np.zeros(robot.nv)
        if k:
            dv[robot.passive_v] = rng.uniform(-spread, spread, robot.passive_v.size)
        q0 = pin.integrate(robot.model, robot.q_home, dv)
        try:
            res = forward_geometry(robot, qa, q0, check_limits=False)
        except AssemblyError:
            continue
        key = res.placement.translation if res.placement is not None else res.q
        if not any(
            np.linalg.norm((f.placement.translation if f.placement is not None else f.q) - key)
            < 1e-6
            for f in found
        ):
            found.append(res)
    return found


def inverse_geometry(
    robot: Robot,
    pose: Sequence[float] | np.ndarray | pin.SE3,
    q_init: np.ndarray | None = None,
    tol: float = DEFAULT_TOL,
    check_limits: bool = True,
) -> GeometryResult:
    """Inverse geometric model: actuated coordinates that put the platform at ``pose``.

    Only the pose components the robot controls (its ``task``) are imposed.

    Args:
        robot: The robot.
        pose: ``[x, y, z]`` or ``[x, y, z, roll, pitch, yaw]`` [m, rad], or a placement.
        q_init: Initial configuration (nq,) (default ``robot.q_home``).
        tol: Residual threshold [m or rad].
        check_limits: Raise if an actuator ends outside its limits.

    Returns:
        The solved configuration; ``qa`` holds the actuated coordinates.

    Raises:
        InvalidInputError: Malformed pose.
        UnreachablePoseError: No assembled configuration reaches the pose.
        JointLimitError: The pose needs an actuator outside its limits.

    """
    target = pose_from_vector(pose)
    if robot.platform_frame is None:
        raise UnreachablePoseError("-", 0.0, f"{robot.name} declares no platform frame")
    task = FramePoseTask(robot.model, robot.platform_frame, robot.task_rows)
    task.target = target
    q0 = robot.q_home if q_init is None else as_finite("q_init", q_init, robot.nq)
    cs = robot.closure_set
    sol = solve_pose(robot, task, q0, tol)
    if not sol.converged:
        pos, rpy = pose_to_vector(target)
        name, res = _worst(robot, sol.q)
        pose_err = float(np.max(np.abs(sol.residual[cs.nc :])))
        raise UnreachablePoseError(
            name,
            res,
            f"{robot.name}: pose {np.array2string(pos, precision=4)} m, rpy "
            f"{np.array2string(rpy, precision=4)} rad is out of reach (closest configuration "
            f"misses it by {pose_err:.3g}; closure '{name}' residual {res:.3g})",
        )
    if check_limits:
        check_actuator_limits(robot, sol.q)
    return _result(robot, sol, float(np.max(np.abs(sol.residual[: cs.nc]), initial=0.0)))


def solve_pose(
    robot: Robot,
    task: FramePoseTask,
    q0: np.ndarray,
    tol: float = DEFAULT_TOL,
    max_iter: int = 100,
    stall: float = 0.0,
) -> SolveResult:
    """Closures and platform pose solved together (the inverse geometric model, unchecked).

    The hot path of :func:`inverse_geometry` (no validation, no message): for callers that
    solve many poses, e.g. the numeric workspace.

    Args:
        robot: The robot.
        task: The platform pose task (its ``target`` set).
        q0: Initial configuration (nq,).
        tol: Residual threshold [m or rad].
        max_iter: Iteration cap.
        stall: Early stop of :func:`solvers.solve_lm` on a stalling residual (0: never).

    Returns:
        The solver's outcome: closure rows first, then the task rows.

    """
    cs, data = robot.closure_set, robot.data
    nc = cs.nc

    def residual(q: np.ndarray) -> np.ndarray:
        r_c = cs.local_residual(data, q)  # runs the kinematics
        r_t = task.residual(data)
        return np.concatenate((r_c, r_t)) if nc else r_t

    def jacobian(q: np.ndarray) -> np.ndarray:  # at the last residual's configuration
        J_c = cs.local_jacobian_after_residual(data)  # also the joint Jacobians of the task
        J_t = task.jacobian(data)
        return np.concatenate((J_c, J_t)) if nc else J_t

    return solve_lm(
        robot.model, q0, residual, jacobian, tol=tol * _LOCAL_TOL, max_iter=max_iter, stall=stall
    )


def check_actuator_limits(robot: Robot, q: np.ndarray) -> None:
    """Raise :class:`JointLimitError` if an actuated coordinate is outside its limits.

    Args:
        robot: The robot.
        q: Configuration (nq,).

    """
    iq = robot.actuated_q
    lo = robot.model.lowerPositionLimit[iq]
    hi = robot.model.upperPositionLimit[iq]
    qa = q[iq]
    out = (qa < lo - 1e-12) | (qa > hi + 1e-12)
    if out.any():
        bad = np.flatnonzero(out)
        k = int(bad[0])
        raise JointLimitError(robot.actuators[k].joint, float(q[iq[k]]), float(lo[k]), float(hi[k]))
