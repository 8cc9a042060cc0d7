"""The fastest motion along a path: time-optimal path parametrisation (toppra) under the limits.

The path is a task trajectory whose time is taken as the path parameter ``s`` (its shape, e.g.
the Adept cycle, and the way it is traversed: the nominal rest points stay rest points), mapped
to joint space by :func:`~pkdyn.dynamics.trajectory.map_task_trajectory`: ``q(s)``, ``q'(s)``,
``q''(s)``, closure-consistent (the internal mobilities follow their dynamics). Along it
``v = q' sd`` and ``a = q' sdd + q'' sd^2``, and since the closed-loop inverse dynamics is linear
in ``M a + h`` (unique efforts, or the least-norm sharing of redundant actuation) and ``h`` is
quadratic in ``v``, the joint-side efforts are

    tau(s) = A(s) sdd + B(s) sd^2 + C(s),
    C = ID(q, 0, 0),  A = ID(q, 0, q') - C,  B = ID(q, q', q'') - C,

three passes of pkdyn's own inverse dynamics (gravity, payload, springs and reflected rotor
inertia included; the robot's dampers and friction, which depend on ``sd``, are updated from
the previous solution like the drive losses). The limits: ``|N tau_m| <= effort`` with
``tau_m`` the motor torque of the drive model (:mod:`pkdyn.dynamics.actuation`; for a lossless
drive ``|tau| <= effort``), i.e. bounds on ``tau`` that depend on the direction of motion
(efficiency) and on the speed (friction), and ``|q'_a sd| <= velocity``. toppra (reachability
analysis, interpolation discretisation, Seidel LPs) gives the fastest ``sd(s)`` from rest to
rest on the grid of the path's samples, with a constant ``sdd`` per segment; the rows of the
torque constraint are normalised (the path's derivatives vanish at its rest points, which
defeats the LP's absolute tolerances otherwise).
With lossy drives the speed-dependent bounds are updated from the previous solution until the
profile converges. At each sample the acceleration is the one of the adjacent segment that
loads the actuators most (both satisfy the limits there); the result is checked by a fourth,
independent inverse-dynamics pass.

Errors: a path the robot cannot follow at any speed is reported with its sample and why (out of
reach or singular: from the mapping; beyond the actuator's stroke; efforts needed to hold it at
rest above the limits).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.dynamics.actuation import drives
from pkdyn.dynamics.inverse import EffortTrajectory, inverse_dynamics
from pkdyn.dynamics.payload import with_payload
from pkdyn.dynamics.trajectory import JointTrajectory, TaskTrajectory, map_task_trajectory
from pkdyn.exceptions import InfeasibleEffortError, InvalidInputError, TrajectoryError
from pkdyn.model.robot import Robot
from pkdyn.results import Result, deprecated_alias, jsonable
from pkdyn.units import quantity

__all__ = ["MAX_PATH_SAMPLES", "FastestResult", "fastest_trajectory", "joint_path"]

ACTIVE_TOL = 1e-3
"""A limit counts as active at a sample when it is used to within this fraction."""

MAX_PATH_SAMPLES = 100_000
"""Most samples of a path :func:`fastest_trajectory` accepts (its grid: mapped, then solved by
toppra up to ``max_iter`` times)."""

_XMAX = 1e8
"""Cap on ``sd^2`` where no speed limit applies (rest points of the path) [1/s^2 in path
units]; the Seidel LP bounds its variables at 1e8."""


@dataclass(frozen=True)
class FastestResult(Result):
    """The time-optimal motion along a path.

    Attributes:
        trajectory: The motion, sampled at the path's samples (non-uniform times).
        cycle_time: Its duration [s].
        payload: Payload mass [kg].
        path: The geometric path (``t`` = path parameter ``s``; ``v``, ``a`` = ``q'``, ``q''``).
        s_dot: Path speed ``ds/dt`` at the samples (N,).
        s_ddot: Path acceleration at the samples (N,) (the adjacent segment's, see the module).
        segment_s_ddot: Constant path acceleration of each segment (N - 1,).
        A: Effort coefficient of ``sdd`` (N, n_a) [joint side].
        B: Effort coefficient of ``sd^2`` (N, n_a).
        C: Effort at rest (N, n_a) (gravity, payload, springs).
        P: Effort of the dampers and friction at the final speeds (N, n_a) (zero without).
        effort_limit: Limit of ``|N tau_m|`` per actuator (n_a,) [N m or N].
        velocity_limit: Joint-side speed limit per actuator (n_a,) [rad/s or m/s].
        efforts: Independent inverse dynamics along ``trajectory`` (the check; its sizing:
            :func:`pkdyn.dynamics.sizing.sizing_from_efforts`).
        torque_utilisation: ``|N tau_m| / effort_limit`` from ``efforts`` (N, n_a).
        speed_utilisation: ``|qa_dot| / velocity_limit`` (N, n_a).
        iterations: toppra solves (more than one with speed-dependent drive losses).

    """

    trajectory: JointTrajectory
    cycle_time: float
    payload: float
    path: JointTrajectory
    s_dot: np.ndarray
    s_ddot: np.ndarray
    segment_s_ddot: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    P: np.ndarray
    effort_limit: np.ndarray
    velocity_limit: np.ndarray
    efforts: EffortTrajectory
    torque_utilisation: np.ndarray
    speed_utilisation: np.ndarray
    iterations: int

    @property
    def utilisation(self) -> np.ndarray:
        """Largest use of any limit at each sample (N,) (1: a limit is reached)."""
        return np.maximum(self.torque_utilisation.max(axis=1), self.speed_utilisation.max(axis=1))

    @property
    def active_fraction(self) -> float:
        """Fraction of the samples where a torque or speed limit is active."""
        return float(np.mean(self.utilisation >= 1.0 - ACTIVE_TOL))

    def joint_effort_at(
        self, t: float, q: np.ndarray | None = None, v: np.ndarray | None = None
    ) -> np.ndarray:
        """Joint-side efforts (n_a,) of the time-optimal motion at time ``t`` [s].

        Between samples the path acceleration is constant; ``A``, ``B``, ``C`` are interpolated
        linearly in ``s``. A feed-forward torque function for :func:`pkdyn.dynamics.simulate`
        (``q`` and ``v`` are ignored).
        """
        T = self.trajectory.t
        s = self.path.t
        i = min(max(int(np.searchsorted(T, t, side="right")) - 1, 0), T.size - 2)
        h = min(max(t - T[i], 0.0), T[i + 1] - T[i])
        u = self.segment_s_ddot[i]
        sd = self.s_dot[i] + u * h
        si = s[i] + self.s_dot[i] * h + 0.5 * u * h * h
        lam = min(max((si - s[i]) / (s[i + 1] - s[i]), 0.0), 1.0)

        def mix(X: np.ndarray) -> np.ndarray:
            return (1.0 - lam) * X[i] + lam * X[i + 1]

        return mix(self.A) * u + mix(self.B) * sd * sd + mix(self.C) + mix(self.P)

    def scaled(self, scale: float = 1.0) -> tuple[JointTrajectory, TaskTrajectory]:
        """The motion slowed down uniformly (times ``scale t``, rates and accelerations divided).

        Rates are divided by ``scale``, accelerations by ``scale^2``.
        A slower copy stays within the limits (its efforts are ``C + (tau - C) / scale^2``, a
        convex combination of the fastest motion's and of those at rest), minus the dampers'
        and drives' speed-dependent losses, which only fall.

        Args:
            scale: Slow-down factor (>= 1 keeps the limits).

        Returns:
            ``(joint, task)``: the joint and platform trajectories (non-uniform times).

        Raises:
            InvalidInputError: A path without its task trajectory, or a scale not > 0.

        """
        from pkdyn.inputs import positive

        scale = positive("scale", scale)
        traj = self.trajectory
        joint = JointTrajectory(
            traj.t * scale,
            traj.q,
            traj.v / scale,
            traj.a / scale**2,
            traj.actuated_q,
            traj.actuated_v,
            name=traj.name,
        )
        task = self.path.task
        if task is None:
            raise InvalidInputError("path", "this motion was built in joint space: no task path")
        sd = self.s_dot[:, None] / scale
        sdd = self.s_ddot[:, None] / scale**2
        pose_d = task.pose_d * sd
        pose_dd = task.pose_d * sdd + task.pose_dd * sd * sd
        timed = TaskTrajectory(joint.t, task.pose, pose_d, pose_dd, name=traj.name)
        return joint, timed

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary: cycle time [s], payload [kg], samples, use of the limits."""
        return jsonable(
            {
                "cycle_time": self.cycle_time,
                "payload": self.payload,
                "samples": int(self.trajectory.t.size),
                "active_fraction": self.active_fraction,
                "max_torque_utilisation": float(np.max(self.torque_utilisation)),
                "max_speed_utilisation": float(np.max(self.speed_utilisation)),
                "toppra_solves": self.iterations,
            }
        )

    as_json = deprecated_alias("as_json", "to_json")

    def table(self) -> str:
        """The cycle time, how much of it runs on a limit, and the independent check."""
        return (
            f"fastest cycle: {quantity(self.cycle_time, 's')} (toppra on "
            f"{self.trajectory.t.size} samples; a torque or speed limit active on "
            f"{quantity(100 * self.active_fraction, '%', 3)} of them; inverse dynamics along "
            f"it: {quantity(100 * float(np.max(self.torque_utilisation)), '%', 6)} of the "
            f"torque limit, {quantity(100 * float(np.max(self.speed_utilisation)), '%', 6)} of "
            "the speed limit)"
        )


def joint_path(
    robot: Robot,
    task: TaskTrajectory,
    q_init: np.ndarray | None = None,
    progress: bool | None = None,
) -> JointTrajectory:
    """The joint-space path of a task path (time = path parameter), checked against the strokes.

    Args:
        robot: The robot.
        task: The task path; its time is the path parameter.
        q_init: Configuration choosing the assembly mode (default ``robot.q_home``).
        progress: Progress bar of the mapping.

    Returns:
        ``q(s)``, ``q'(s)``, ``q''(s)`` as a joint trajectory in ``s``.

    Raises:
        TrajectoryError: A sample out of reach, singular, or beyond an actuator's stroke (the
            message names the sample, and the actuator).

    """
    path = map_task_trajectory(robot, task, q_init=q_init, check_limits=False, progress=progress)
    lo = robot.model.lowerPositionLimit[robot.actuated_q]
    hi = robot.model.upperPositionLimit[robot.actuated_q]
    qa = path.qa
    bad = np.argwhere((qa < lo - 1e-9) | (qa > hi + 1e-9))
    if bad.size:
        k, i = (int(x) for x in bad[0])
        raise TrajectoryError(
            f"the path takes actuator '{robot.actuator_names[i]}' (joint "
            f"'{robot.actuated_joint_names[i]}') to {qa[k, i]:.6g}, outside its stroke "
            f"[{lo[i]:.6g}, {hi[i]:.6g}]: no speed can follow it",
            sample=k,
            time=float(path.t[k]),
        )
    return path


def _limits(robot: Robot, what: str, given: Any, default: list[float]) -> np.ndarray:
    n = len(robot.actuators)
    arr = np.asarray(default if given is None else given, dtype=float).reshape(-1)
    if arr.size == 1:
        arr = np.full(n, float(arr[0]))
    if arr.size != n or np.any(np.isnan(arr)) or np.any(arr <= 0.0):
        raise InvalidInputError(what, f"expected one or {n} values > 0, got {given!r}")
    return arr


def _coefficients(
    robot: Robot, path: JointTrajectory, progress: bool | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``A``, ``B``, ``C`` of ``tau = A sdd + B sd^2 + C`` by inverse-dynamics passes.

    ``C`` includes the springs (position only); the dampers and friction, which depend on
    ``sd`` otherwise, are left to :func:`_dissipative`.
    """
    Z = np.zeros_like(path.v)

    def run(v: np.ndarray, a: np.ndarray, passive: bool) -> np.ndarray:
        jt = JointTrajectory(path.t, path.q, v, a, path.actuated_q, path.actuated_v, name="path")
        return inverse_dynamics(robot, jt, progress=progress, passive=passive).tau

    bare = run(Z, Z, False)
    C = bare if robot.passive is None else run(Z, Z, True)
    A = run(Z, path.v, False) - bare
    B = run(path.v, path.a, False) - bare
    return A, B, C


def _has_dissipation(robot: Robot) -> bool:
    p = robot.passive
    return p is not None and bool(np.any(p.damping) or np.any(p.friction))


def _dissipative(
    robot: Robot,
    path: JointTrajectory,
    sd: np.ndarray,
    u: np.ndarray,
    A: np.ndarray,
    B: np.ndarray,
    C: np.ndarray,
) -> np.ndarray:
    """Efforts (N, n_a) of the dampers and friction at the path speeds ``sd``.

    The inverse dynamics with the passive elements, minus ``A u + B sd^2 + C`` (the rest).
    """
    x = sd**2
    v = path.v * sd[:, None]
    a = path.v * u[:, None] + path.a * x[:, None]
    jt = JointTrajectory(path.t, path.q, v, a, path.actuated_q, path.actuated_v, name="path")
    return inverse_dynamics(robot, jt).tau - (A * u[:, None] + B * x[:, None] + C)


def _bounds(
    robot: Robot,
    qa1: np.ndarray,
    x: np.ndarray | None,
    effort: np.ndarray,
    slow: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint-side effort bounds (N, n_a) from ``|N tau_m| <= effort`` along the path.

    The efficiency and the Coulomb friction depend on the direction of motion, ``sign(q'_a)``,
    the viscous friction on the speed ``q'_a sd`` with ``sd^2 = x`` (``None``: not known yet,
    taken as fast for the direction and zero for the viscous term). Where the motor speed is
    within 5 smoothing speeds of zero (and at the path's rest points) the bounds are the
    conservative ``N eta (tau_max - coulomb - viscous |omega|)`` either way: there the blend of
    the drive model (:class:`solvers.Drives`) could take any value between its two branches.
    Those samples accumulate over the iterations (``slow``, returned), so that the fixed point
    converges.
    """
    d = drives(robot)
    if d.lossless:
        lossless = np.broadcast_to(effort, qa1.shape)
        return -lossless, lossless, np.zeros(qa1.shape, dtype=bool)
    N = d.reduction
    direction = np.sign(N * qa1)
    sd = np.full(qa1.shape[0], np.inf) if x is None else np.sqrt(np.maximum(x, 0.0))
    with np.errstate(invalid="ignore"):
        omega = np.nan_to_num(N * qa1 * sd[:, None], nan=0.0)
    viscous = 0.0 if x is None else d.viscous * omega
    f = viscous + d.coulomb * direction
    tau_max = effort / np.abs(N)
    ends = []
    for sign in (-1.0, 1.0):
        tau_in = sign * tau_max - f
        kappa = d.transmission_factor(tau_in, direction * 1e3 * d.smoothing)
        ends.append(N * kappa * tau_in)
    lo, hi = np.minimum(*ends), np.maximum(*ends)
    now = (np.abs(omega) < 5.0 * d.smoothing) | (direction == 0.0)
    slow = now if slow is None else slow | now
    safe = np.abs(N) * d.efficiency * (tau_max - d.coulomb - np.abs(viscous))
    return np.where(slow, -safe, lo), np.where(slow, safe, hi), slow


def _static_check(robot: Robot, path: JointTrajectory, C: np.ndarray, effort: np.ndarray) -> None:
    lo, hi, _ = _bounds(robot, np.zeros_like(C), np.zeros(C.shape[0]), effort)
    over = np.maximum(C - hi, lo - C)
    bad = np.argwhere(over > 1e-12 * np.maximum(1.0, np.abs(C)))
    if bad.size:
        k, i = (int(x) for x in bad[0])
        raise InfeasibleEffortError(
            f"sample {k} (s = {path.t[k]:.6g}): actuator '{robot.actuator_names[i]}' needs "
            f"{C[k, i]:.6g} to hold the path at rest (gravity, payload), beyond its limits "
            f"[{lo[k, i]:.6g}, {hi[k, i]:.6g}]: the robot cannot follow this path at any speed",
            sample=k,
            actuator=robot.actuator_names[i],
        )


def _toppra(
    s: np.ndarray,
    A: np.ndarray,
    B: np.ndarray,
    C: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    xmax: np.ndarray,
) -> tuple[np.ndarray, np.ndarray] | int:
    """Fastest ``(sd, sdd)`` from rest to rest, or the first sample toppra cannot control."""
    import toppra.algorithm as algo
    from toppra.constraint import (
        DiscretizationType,
        LinearConstraint,
        canlinear_colloc_to_interpolate,
    )
    from toppra.interpolator import AbstractGeometricPath

    class _Path(AbstractGeometricPath):  # only the interval is used by the algorithm
        def __init__(self, n: int) -> None:
            self._n = n

        @property
        def path_interval(self) -> np.ndarray:
            return np.array([s[0], s[-1]])

        @property
        def dof(self) -> int:
            return self._n

        def get_duration(self) -> float:
            return float(s[-1] - s[0])

        def __call__(self, path_positions: Any, order: int = 0) -> np.ndarray:
            raise NotImplementedError

    class _Torque(LinearConstraint):
        """One-sided rows ``a u + b x + c <= 0``, each scaled to a unit largest coefficient."""

        def __init__(self) -> None:
            super().__init__()
            a = np.hstack([A, -A])
            b = np.hstack([B, -B])
            c = np.hstack([C - hi, lo - C])
            rho = 1.0 / np.maximum(np.maximum(np.abs(a), np.abs(b)), 1e-300)
            self._abc = (a * rho, b * rho, np.clip(c * rho, -1e12, 1e12))
            self.discretization_type = DiscretizationType.Interpolation
            self.identical = True
            self.dof = A.shape[1]

        def compute_constraint_params(self, path: Any, gridpoints: Any, *args: Any, **kw: Any):
            a, b, c = self._abc
            m = a.shape[1]
            return canlinear_colloc_to_interpolate(
                a, b, c, np.eye(m), np.zeros(m), None, None, gridpoints, identical=True
            )

    class _Speed(LinearConstraint):
        def __init__(self) -> None:
            super().__init__()
            self.dof = A.shape[1]

        def compute_constraint_params(self, path: Any, gridpoints: Any, *args: Any, **kw: Any):
            xb = np.column_stack([np.zeros_like(xmax), xmax])
            return None, None, None, None, None, None, xb

    log = logging.getLogger("toppra")
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        inst = algo.TOPPRA([_Torque(), _Speed()], _Path(A.shape[1]), gridpoints=s,
                           solver_wrapper="seidel")  # fmt: skip
        sdd, sd, _ = inst.compute_parameterization(0.0, 0.0)
        if sd is None or sdd is None or np.any(~np.isfinite(sd)):
            K = inst.compute_controllable_sets(0.0, 0.0)
            bad = np.flatnonzero(~np.isfinite(K).all(axis=1))
            return int(bad[-1]) if bad.size else 0
    finally:
        log.setLevel(level)
    return np.asarray(sd, dtype=float), np.asarray(sdd, dtype=float)


def fastest_trajectory(
    robot: Robot,
    path: TaskTrajectory | JointTrajectory,
    payload: float = 0.0,
    effort: float | np.ndarray | None = None,
    velocity: float | np.ndarray | None = None,
    q_init: np.ndarray | None = None,
    max_iter: int = 10,
    progress: bool | None = None,
) -> FastestResult:
    """The fastest motion along a path under the actuators' torque and speed limits.

    Args:
        robot: The robot (its drives: reductions, rotor inertia, efficiency, motor friction).
        path: A task path (its time is the path parameter; e.g.
            :func:`~pkdyn.dynamics.trajectory.named_task` ``(robot, "adept")``), or its joint
            path from :func:`joint_path` (to reuse the mapping, e.g. across payloads).
        payload: Payload mass at the platform [kg].
        effort: Limit of ``|N tau_m|`` per actuator [N m or N] (default: the URDF effort
            limits; for a catalog motor, its peak torque times the reduction).
        velocity: Joint-side speed limit per actuator [rad/s or m/s] (default: URDF).
        q_init: Configuration choosing the assembly mode when mapping a task path.
        max_iter: toppra solves allowed for speed-dependent losses to converge.
        progress: Progress bars of the mapping and of the inverse dynamics.

    Returns:
        The time-optimal motion, its cycle time, the check of its efforts and their use of the
        limits.

    Raises:
        TrajectoryError: The path leaves the workspace, meets a singularity or an actuator's
            stroke (sample named).
        InfeasibleEffortError: The efforts needed to hold the path at rest exceed the limits
            (sample and actuator named), or toppra finds no feasible speed.
        InvalidInputError: Bad limits or payload, or more than :data:`MAX_PATH_SAMPLES` samples.

    """
    if path.t.size > MAX_PATH_SAMPLES:
        raise InvalidInputError(
            "path",
            f"{path.t.size:,} samples, more than {MAX_PATH_SAMPLES:,} (each is mapped, then "
            f"solved up to {max_iter} times by toppra: about {path.t.size * 3e-3 / 60:.0f} min "
            "or more); sample the path more coarsely (a longer dt)",
        )
    if isinstance(path, TaskTrajectory):
        path = joint_path(robot, path, q_init=q_init, progress=progress)
    if path.q.shape[1] != robot.nq:
        raise InvalidInputError("path", f"a path of nq = {path.q.shape[1]}, not {robot.name}'s")
    E = _limits(robot, "effort", effort, [a.effort for a in robot.actuators])
    V = _limits(robot, "velocity", velocity, [a.velocity for a in robot.actuators])
    loaded = with_payload(robot, payload) if payload else robot
    s = path.t
    qa1 = path.qa_dot
    A, B, C = _coefficients(loaded, path, progress)
    _static_check(robot, path, C, E)
    with np.errstate(divide="ignore"):
        xmax = np.min(np.where(np.abs(qa1) > 0.0, (V / np.abs(qa1)) ** 2, _XMAX), axis=1)
    xmax = np.minimum(xmax, _XMAX)
    d = drives(robot)
    damped = _has_dissipation(loaded)
    P = np.zeros_like(C)  # dampers and friction at the current speed estimate
    x_est: np.ndarray | None = None
    slow: np.ndarray | None = None
    T_est = math.inf
    scale = 1.0
    solves = 0
    while True:
        lo, hi, slow = _bounds(robot, qa1, x_est, E * scale, slow)
        out = _toppra(s, A, B, C + P, lo, hi, xmax)
        solves += 1
        if isinstance(out, int):
            raise InfeasibleEffortError(
                f"sample {out} (s = {s[out]:.6g}): no feasible path speed from there on "
                "(toppra's controllable set is empty); the limits are too tight for this path",
                sample=out,
            )
        sd, sdd = out
        x = sd**2
        T_new = _duration(s, sd)
        converged = (d.lossless and not damped) or abs(T_new - T_est) <= 1e-7 * T_new
        T_est = T_new
        if not converged and solves < max_iter:
            x_est = x
            if damped:
                P = _dissipative(loaded, path, sd, np.append(sdd, sdd[-1]), A, B, C)
            continue
        traj, u, efforts, tu, su = _motion(loaded, robot, path, sd, sdd, A, B, C + P, E, V)
        excess = float(np.max(tu))
        if excess <= 1.0 + 1e-7 or solves >= max_iter + 3:
            break
        scale *= (1.0 - 1e-7) / excess  # a lossy drive's iteration left a small excess
        x_est = x
    T = float(traj.t[-1])
    return FastestResult(
        trajectory=traj,
        cycle_time=T,
        payload=float(payload),
        path=path,
        s_dot=sd,
        s_ddot=u,
        segment_s_ddot=sdd,
        A=A,
        B=B,
        C=C,
        P=P,
        effort_limit=E,
        velocity_limit=V,
        efforts=efforts,
        torque_utilisation=tu,
        speed_utilisation=su,
        iterations=solves,
    )


def _duration(s: np.ndarray, sd: np.ndarray) -> float:
    with np.errstate(divide="ignore"):
        return float(np.sum(2.0 * np.diff(s) / (sd[1:] + sd[:-1])))


def _motion(
    loaded: Robot,
    robot: Robot,
    path: JointTrajectory,
    sd: np.ndarray,
    sdd: np.ndarray,
    A: np.ndarray,
    B: np.ndarray,
    C: np.ndarray,
    E: np.ndarray,
    V: np.ndarray,
) -> tuple[JointTrajectory, np.ndarray, EffortTrajectory, np.ndarray, np.ndarray]:
    """The sampled motion, its per-sample path acceleration, checked efforts and utilisations."""
    s = path.t
    x = sd**2
    with np.errstate(divide="ignore", invalid="ignore"):
        dt = 2.0 * np.diff(s) / (sd[1:] + sd[:-1])
    if not np.all(np.isfinite(dt)):
        k = int(np.flatnonzero(~np.isfinite(dt))[0])
        raise InfeasibleEffortError(
            f"sample {k} (s = {s[k]:.6g}): the path speed stays zero (no motion is possible)",
            sample=k,
        )
    t = np.concatenate([[0.0], np.cumsum(dt)])
    d = drives(robot)
    qa1 = path.qa_dot
    qd = qa1 * sd[:, None]
    right = np.append(sdd, sdd[-1])
    left = np.insert(sdd, 0, sdd[0])

    def use(u: np.ndarray) -> np.ndarray:
        tau = A * u[:, None] + B * x[:, None] + C
        return np.max(np.abs(d.reduction * d.motor_effort(tau, qd)) / E, axis=1)

    u = np.where(use(right) >= use(left), right, left)
    v = path.v * sd[:, None]
    a = path.v * u[:, None] + path.a * x[:, None]
    task = path.task
    name = f"fastest {task.name if task is not None else path.name}"
    traj = JointTrajectory(t, path.q, v, a, path.actuated_q, path.actuated_v, name=name)
    efforts = inverse_dynamics(loaded, traj)
    tu = np.abs(d.reduction * d.motor_effort(efforts.tau, qd)) / E
    su = np.abs(qd) / V
    return traj, u, efforts, tu, su
