"""Task-space trajectories and their mapping to joint space, consistent with the closures.

A :class:`TaskTrajectory` samples the platform pose ``[x, y, z, roll, pitch, yaw]`` [m, rad] and
its first two time derivatives. :func:`map_task_trajectory` turns it into a
:class:`JointTrajectory` ``(q, v, a)`` of the whole mechanism such that at every sample

- ``q`` is assembled and puts the platform at the pose (inverse geometric model, warm-started
  from a second-order prediction from the previous sample, so the assembly mode is followed
  continuously and the internal mobilities follow their velocities);
- ``v`` satisfies the closures (``Jc v = 0``) and gives the pose rates (``Jx v = x_dot``);
- ``a`` satisfies the closures to second order (``Jc a = -gamma_c``, see
  :meth:`solvers.ConstraintSet.drift`) and gives the pose accelerations
  (``Jx a = x_ddot - gamma_x``);
- the unactuated internal mobilities (e.g. the spin of a ball-ended Delta bar about its axis)
  move as the dynamics dictate: their accelerations solve ``N^T (M a + h) = 0`` with ``N`` the
  internal motions (no actuator and no closure can act on them), so the inverse dynamics has an
  exact solution; their velocities have zero momentum (``N^T M v = 0``). For a ball-ended bar,
  symmetric about its axis, this is the exact motion from rest: no force of the ball joints has
  a moment about the bar axis, so the bar's spin momentum stays zero.

Task rates use the platform-frame angular velocity of :mod:`pkdyn.analysis.kinematics`:
``omega = E(rpy) rpy_dot`` with ``E`` from ``pin.rpy.computeRpyJacobian`` (LOCAL), and
``omega_dot = E rpy_ddot + E_dot rpy_dot``.

Built-in trajectories (:func:`named_trajectory`): ``adept`` (the pick-and-place "Adept cycle":
25 mm up, 305 mm across, 25 mm down and back), ``sine`` (sinusoidal motion of each task
component about the home pose) and ``p2p`` (one straight point-to-point move).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.analysis.kinematics import SINGULAR_TOL, kinematic_models
from pkdyn.dynamics.profiles import MotionLaw, motion_law
from pkdyn.dynamics.series import series_table
from pkdyn.exceptions import (
    InvalidInputError,
    JointLimitError,
    SingularConfigurationError,
    TrajectoryError,
    UnreachablePoseError,
)
from pkdyn.model.assembly import inverse_geometry
from pkdyn.model.pose import pose_from_vector, pose_to_vector
from pkdyn.model.robot import PLATFORM_HINT, Robot
from pkdyn.progress import progress as progress_bar
from pkdyn.results import Result, jsonable
from solvers import numerics

__all__ = [
    "TRAJECTORIES",
    "JointTrajectory",
    "TaskTrajectory",
    "adept_cycle",
    "concatenate",
    "map_task_trajectory",
    "named_task",
    "named_trajectory",
    "point_to_point",
    "sinusoid",
    "task_at_home",
]

TRAJECTORIES = ("adept", "sine", "p2p")
"""Names of the task trajectories :func:`named_task` and :func:`named_trajectory` know."""

_LOCAL = pin.ReferenceFrame.LOCAL
_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class TaskTrajectory(Result):
    """Sampled platform poses and their derivatives.

    Attributes:
        t: Sample times (N,) [s], increasing.
        pose: Poses (N, 6): ``x, y, z`` [m], ``roll, pitch, yaw`` [rad].
        pose_d: First derivatives (N, 6) [m/s, rad/s].
        pose_dd: Second derivatives (N, 6) [m/s^2, rad/s^2].
        name: What the trajectory is (for reports).

    """

    t: np.ndarray
    pose: np.ndarray
    pose_d: np.ndarray
    pose_dd: np.ndarray
    name: str = "task trajectory"

    def __post_init__(self) -> None:
        n = self.t.shape[0]
        for what in ("pose", "pose_d", "pose_dd"):
            arr = getattr(self, what)
            if arr.shape != (n, 6):
                raise InvalidInputError(what, f"expected shape ({n}, 6), got {arr.shape}")
        for what in ("t", "pose", "pose_d", "pose_dd"):
            arr = getattr(self, what)
            bad = np.flatnonzero(~np.isfinite(arr.reshape(n, -1)).all(axis=1))
            if bad.size:
                k = int(bad[0])
                raise TrajectoryError(f"{what} is not finite", sample=k)
        if n < 2 or np.any(np.diff(self.t) <= 0.0):
            raise InvalidInputError("t", "sample times must be increasing (at least 2 samples)")

    @property
    def duration(self) -> float:
        """Duration [s]."""
        return float(self.t[-1] - self.t[0])

    def to_json(self) -> dict[str, Any]:
        """``name``, ``t`` [s], ``pose`` (N, 6) [m, rad] and its derivatives."""
        return jsonable(
            {
                "name": self.name,
                "t": self.t,
                "pose": self.pose,
                "pose_d": self.pose_d,
                "pose_dd": self.pose_dd,
            }
        )

    def table(self) -> str:
        """Per pose component: its range and its speed's."""
        names = ["x", "y", "z", "roll", "pitch", "yaw"]
        return series_table(
            self.name,
            self.t,
            [
                ("pose", self.pose, names, ["m"] * 3 + ["rad"] * 3),
                ("speed", self.pose_d, names, ["m/s"] * 3 + ["rad/s"] * 3),
            ],
        )


@dataclass(frozen=True)
class JointTrajectory(Result):
    """A trajectory of the whole mechanism, consistent with the closures.

    Attributes:
        t: Sample times (N,) [s].
        q: Configurations (N, nq).
        v: Velocities (N, nv).
        a: Accelerations (N, nv).
        actuated_v: Velocity (and configuration of one-dimensional joints) index per actuator.
        actuated_q: Configuration index per actuator.
        task: The task-space trajectory it was mapped from (``None`` if built in joint space).
        name: What the trajectory is.

    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    actuated_q: np.ndarray
    actuated_v: np.ndarray
    task: TaskTrajectory | None = None
    name: str = "joint trajectory"

    @property
    def qa(self) -> np.ndarray:
        """Actuator positions (N, n_a) [rad or m]."""
        return self.q[:, self.actuated_q]

    @property
    def qa_dot(self) -> np.ndarray:
        """Actuator rates (N, n_a) [rad/s or m/s]."""
        return self.v[:, self.actuated_v]

    @property
    def qa_ddot(self) -> np.ndarray:
        """Actuator accelerations (N, n_a) [rad/s^2 or m/s^2]."""
        return self.a[:, self.actuated_v]

    def to_json(self) -> dict[str, Any]:
        """``name``, ``t`` [s], the actuators' ``qa``, ``qa_dot``, ``qa_ddot``, and ``q``, ``v``."""
        return jsonable(
            {
                "name": self.name,
                "t": self.t,
                "qa": self.qa,
                "qa_dot": self.qa_dot,
                "qa_ddot": self.qa_ddot,
                "q": self.q,
                "v": self.v,
            }
        )

    def table(self) -> str:
        """Per actuator: the range of its coordinate and rate (rad or m)."""
        k = self.qa.shape[1]
        names = [f"#{i + 1}" for i in range(k)]
        return series_table(
            self.name,
            self.t,
            [
                ("qa", self.qa, names, ["rad or m"] * k),
                ("qa_dot", self.qa_dot, names, ["rad/s or m/s"] * k),
            ],
        )


# ---------------------------------------------------------------------- task-space builders


def _pose6(pose: Sequence[float] | np.ndarray, what: str) -> np.ndarray:
    p = np.asarray(pose, dtype=float).reshape(-1)
    if p.size == 3:
        p = np.concatenate([p, np.zeros(3)])
    if p.size != 6 or not np.all(np.isfinite(p)):
        raise InvalidInputError(what, f"expected 3 or 6 finite numbers, got {pose!r}")
    return p


MIN_SAMPLES_PER_MOVE = 2
"""Fewest samples of the shortest move (or half period) a trajectory accepts: coarser, the
motion is not seen at all (``size --dt 10`` used to report a 0.5 s cycle feasible with
0.05 N m)."""

_WARNED: list[bool] = []

WARN_SAMPLES_PER_MOVE = 10
"""Below this many samples of the shortest move a warning says that peaks may be missed (a
quintic move's acceleration peaks at 21 % and 79 % of its duration)."""

MAX_SAMPLES = 2_000_000
"""Most samples of one trajectory (mapping to the joints takes ~1 ms each: about half an hour)."""


def _times(
    duration: float,
    dt: float,
    shortest: float | None = None,
    what: str = "",
    warn: bool = False,
) -> np.ndarray:
    """Sample times ``0..duration`` every ``dt``, refused when too coarse or too many.

    Args:
        duration: Duration [s].
        dt: Sample period [s].
        shortest: Duration of the shortest feature to resolve [s] (a move, a half period).
        what: What that feature is, for messages.
        warn: Warn below :data:`WARN_SAMPLES_PER_MOVE` samples of it (the built-in
            trajectories of :func:`named_task`).

    """
    if not np.isfinite(dt) or dt <= 0.0:
        raise InvalidInputError("dt", f"sample period must be > 0 s, got {dt}")
    shortest = duration if shortest is None else shortest
    if dt > shortest / MIN_SAMPLES_PER_MOVE:
        raise InvalidInputError(
            "dt",
            f"{dt:g} s samples the {shortest:.3g} s {what or 'motion'} fewer than "
            f"{MIN_SAMPLES_PER_MOVE} times: the motion would be missed; use dt <= "
            f"{shortest / WARN_SAMPLES_PER_MOVE:.3g} s",
        )
    if warn and dt > shortest / WARN_SAMPLES_PER_MOVE and not _WARNED:
        _WARNED.append(True)  # once per process: a design study samples many robots alike
        warnings.warn(
            f"dt = {dt:g} s samples the {shortest:.3g} s {what or 'motion'} only "
            f"{shortest / dt:.1f} times: peak and RMS values may be underestimated (dt <= "
            f"{shortest / WARN_SAMPLES_PER_MOVE:.3g} s resolves them)",
            UserWarning,
            stacklevel=4,
        )
    steps = duration / dt
    if steps > MAX_SAMPLES:
        raise InvalidInputError(
            "dt",
            f"{duration:g} s every {dt:g} s is {steps:.3g} samples (mapping them takes ~1 ms "
            f"each: about {steps * 1e-3 / 3600:.2g} h); at most {MAX_SAMPLES:.0e}: use a longer "
            "dt or a shorter duration",
        )
    n = max(2, int(round(steps)) + 1)
    return np.linspace(0.0, duration, n)


def point_to_point(
    start: Sequence[float] | np.ndarray,
    end: Sequence[float] | np.ndarray,
    duration: float,
    profile: str = "quintic",
    dt: float = 1e-3,
    warn_coarse: bool = False,
) -> TaskTrajectory:
    """A straight rest-to-rest move in pose coordinates.

    Args:
        start: Start pose ``[x, y, z]`` or ``[x, y, z, roll, pitch, yaw]`` [m, rad].
        end: End pose, same form.
        duration: Duration [s].
        profile: Motion law, ``quintic`` or ``jerk`` (see :mod:`pkdyn.dynamics.profiles`).
        dt: Sample period [s] (at least 2 samples of the move).
        warn_coarse: Warn when fewer than 10 samples resolve the move.

    Returns:
        The sampled move.

    """
    p0, p1 = _pose6(start, "start"), _pose6(end, "end")
    law = motion_law(profile, duration)
    t = _times(duration, dt, duration, "move", warn_coarse)
    return _segment(t, p0, p1, law, f"{profile} move")


def _segment(
    t: np.ndarray, p0: np.ndarray, p1: np.ndarray, law: MotionLaw, name: str
) -> TaskTrajectory:
    s, sd, sdd = law(t)
    d = p1 - p0
    return TaskTrajectory(t, p0 + np.outer(s, d), np.outer(sd, d), np.outer(sdd, d), name=name)


def concatenate(parts: Sequence[TaskTrajectory], name: str | None = None) -> TaskTrajectory:
    """Join trajectories end to end.

    Each part's times are shifted after the previous one; the first sample of every later part,
    a repeat of the previous end, is dropped.

    Args:
        parts: Trajectories; each must start where the previous one ends.
        name: Name of the result (default: the first part's).

    Returns:
        The joined trajectory.

    """
    if not parts:
        raise InvalidInputError("parts", "nothing to concatenate")
    t, pose, pd, pdd = [parts[0].t], [parts[0].pose], [parts[0].pose_d], [parts[0].pose_dd]
    for k, part in enumerate(parts[1:], start=1):
        gap = float(np.max(np.abs(part.pose[0] - pose[-1][-1])))
        if gap > 1e-9:
            raise InvalidInputError(
                "parts", f"part {k} starts {gap:.3g} away from where part {k - 1} ends"
            )
        t.append(part.t[1:] - part.t[0] + t[-1][-1])
        pose.append(part.pose[1:])
        pd.append(part.pose_d[1:])
        pdd.append(part.pose_dd[1:])
    return TaskTrajectory(
        np.concatenate(t),
        np.vstack(pose),
        np.vstack(pd),
        np.vstack(pdd),
        name=name or parts[0].name,
    )


def adept_cycle(
    bottom: Sequence[float] | np.ndarray,
    cycle_time: float = 0.5,
    up: float = 0.025,
    across: float = 0.305,
    direction: float = 0.0,
    profile: str = "quintic",
    overlap: float = 0.0,
    dt: float = 1e-3,
    warn_coarse: bool = False,
) -> TaskTrajectory:
    """The pick-and-place "Adept cycle": ``up`` up, ``across`` across, ``up`` down, and back.

    The cycle starts and ends at rest at the pick point ``bottom`` (the across move is centred on
    it: from ``bottom - across/2`` to ``bottom + across/2`` along ``direction``; the cycle starts
    at the first of them). Each half cycle is three rest-to-rest moves (up, across, down) whose
    durations are proportional to the square roots of their lengths (equal peak accelerations
    for one motion law); ``overlap`` in ``[0, 1)`` starts the across move before the up move
    ends (and the down move before it ends) by that fraction of the vertical move's duration,
    rounding the corners.

    Args:
        bottom: Centre of the pick-and-place line ``[x, y, z]`` [m] (the low points are
            ``across / 2`` either side of it).
        cycle_time: Duration of the whole cycle, there and back [s].
        up: Height of the vertical moves [m] (default 25 mm).
        across: Length of the horizontal move [m] (default 305 mm).
        direction: Direction of the horizontal move in the x-y plane [rad] (0: along x).
        profile: Motion law of each move, ``quintic`` or ``jerk``.
        overlap: Fraction of the vertical moves overlapped with the horizontal one.
        dt: Sample period [s] (at least 2 samples of the shortest move).
        warn_coarse: Warn when fewer than 10 samples resolve the shortest move.

    Returns:
        The sampled cycle (one period; repeat by :func:`concatenate`).

    """
    c = _pose6(bottom, "bottom")[:3]
    if not 0.0 <= overlap < 1.0:
        raise InvalidInputError("overlap", f"must be in [0, 1), got {overlap}")
    for what, val in (("cycle_time", cycle_time), ("up", up), ("across", across)):
        if not np.isfinite(val) or val <= 0.0:
            raise InvalidInputError(what, f"must be > 0, got {val}")
    u = np.array([np.cos(direction), np.sin(direction), 0.0])
    half = 0.5 * cycle_time
    # rest-to-rest durations ~ sqrt(length); overlapping shortens the sum by 2 * overlap * Tv
    rv, rh = np.sqrt(up), np.sqrt(across)
    Tv = half / (2.0 * rv * (1.0 - overlap) + rh) * rv
    Th = half - 2.0 * Tv * (1.0 - overlap)
    t = _times(cycle_time, dt, min(Tv, Th), "shortest move of the cycle", warn_coarse)
    law_v, law_h = motion_law(profile, Tv), motion_law(profile, Th)
    pose = np.zeros((t.size, 6))
    pd = np.zeros((t.size, 6))
    pdd = np.zeros((t.size, 6))
    for k, sign in enumerate((1.0, -1.0)):  # there, then back
        t0 = k * half
        tau = t - t0
        active = (tau >= 0.0) & (tau <= half) if k == 1 else (tau >= 0.0) & (tau < half)
        start_h = Tv * (1.0 - overlap)
        zs = law_v(tau)
        zd = law_v(tau - (half - Tv))
        xs = law_h(tau - start_h)
        z = up * (zs[0] - zd[0])
        zv = up * (zs[1] - zd[1])
        za = up * (zs[2] - zd[2])
        x = across * (xs[0] - 0.5) * sign
        xv = across * xs[1] * sign
        xa = across * xs[2] * sign
        pose[active, :3] = c + np.outer(x[active], u) + np.outer(z[active], [0.0, 0.0, 1.0])
        pd[active, :3] = np.outer(xv[active], u) + np.outer(zv[active], [0.0, 0.0, 1.0])
        pdd[active, :3] = np.outer(xa[active], u) + np.outer(za[active], [0.0, 0.0, 1.0])
    return TaskTrajectory(
        t, pose, pd, pdd, name=f"Adept cycle {1e3 * up:.0f}/{1e3 * across:.0f}/{1e3 * up:.0f} mm"
    )


def sinusoid(
    center: Sequence[float] | np.ndarray,
    amplitude: Sequence[float] | np.ndarray,
    frequency: Sequence[float] | np.ndarray | float,
    duration: float,
    phase: Sequence[float] | np.ndarray | float = 0.0,
    dt: float = 1e-3,
    warn_coarse: bool = False,
) -> TaskTrajectory:
    """Sinusoidal motion of each pose component: ``center + amplitude sin(2 pi f t + phase)``.

    Args:
        center: Centre pose (3 or 6 values) [m, rad].
        amplitude: Amplitudes (6,) [m, rad].
        frequency: Frequencies (6,) or one for all [Hz].
        duration: Duration [s].
        phase: Phases (6,) or one for all [rad].
        dt: Sample period [s] (at least 2 samples per half period).
        warn_coarse: Warn when fewer than 10 samples resolve a half period.

    Returns:
        The sampled motion (it starts in motion unless every phase is a multiple of pi and
        starts at rest only if all amplitudes vanish).

    """
    c = _pose6(center, "center")
    A = np.broadcast_to(np.asarray(amplitude, dtype=float), (6,))
    f = np.broadcast_to(np.asarray(frequency, dtype=float), (6,))
    ph = np.broadcast_to(np.asarray(phase, dtype=float), (6,))
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(f)) and np.all(np.isfinite(ph))):
        raise InvalidInputError("sinusoid", "amplitudes, frequencies and phases must be finite")
    if not np.isfinite(duration) or duration <= 0.0:
        raise InvalidInputError("duration", f"must be > 0 s, got {duration}")
    moving = f[(A != 0.0) & (f > 0.0)]
    half = 0.5 / float(np.max(moving)) if moving.size else duration
    t = _times(duration, dt, min(half, duration), "half period", warn_coarse)
    w = 2.0 * np.pi * f
    arg = np.outer(t, w) + ph
    return TaskTrajectory(
        t,
        c + A * np.sin(arg),
        A * w * np.cos(arg),
        -A * w**2 * np.sin(arg),
        name="sinusoid",
    )


# ---------------------------------------------------------------------- mapping to joint space


def _task_rates(pose: np.ndarray, pd: np.ndarray, pdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Platform twist and its derivative in the task convention from pose-vector derivatives."""
    rpy, rpy_d, rpy_dd = pose[3:], pd[3:], pdd[3:]
    E = pin.rpy.computeRpyJacobian(rpy, _LOCAL)
    Ed = pin.rpy.computeRpyJacobianTimeDerivative(rpy, rpy_d, _LOCAL)
    xd = np.concatenate([pd[:3], E @ rpy_d])
    xdd = np.concatenate([pdd[:3], E @ rpy_dd + Ed @ rpy_d])
    return xd, xdd


def _platform_drift(robot: Robot, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Task-convention platform acceleration at ``a = 0`` (6,): world linear, local angular."""
    assert robot.platform_frame is not None
    model, data = robot.model, robot.data
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    acc = pin.getFrameClassicalAcceleration(model, data, robot.platform_frame, _LWA)
    R = pin.updateFramePlacement(model, data, robot.platform_frame).rotation
    return np.concatenate([acc.linear, R.T @ acc.angular])


def _lstsq(K: np.ndarray, b: np.ndarray, tol: float) -> tuple[np.ndarray, float, np.ndarray]:
    """Minimum-norm solution, its residual and the null space of ``K``."""
    x, N = numerics.lstsq_null(K, b, tol)
    return x, float(np.max(np.abs(K @ x - b), initial=0.0)), N


def map_task_trajectory(
    robot: Robot,
    task: TaskTrajectory,
    q_init: np.ndarray | None = None,
    check_limits: bool = True,
    progress: bool | None = None,
    check_speeds: bool = True,
) -> JointTrajectory:
    """Joint-space trajectory ``(q, v, a)`` of the mechanism following a platform trajectory.

    See the module docstring for what "consistent" means. Only the controlled pose components of
    the robot (its task) are imposed.

    Args:
        robot: The robot (must declare a platform).
        task: The platform trajectory.
        q_init: Configuration near the first sample, choosing the assembly mode (default:
            ``robot.q_home``).
        check_limits: Raise if an actuator leaves its position or velocity limits.
        progress: Progress bar: ``True`` / ``False`` force it on / off, ``None`` (default) shows
            it when stderr is a terminal and there are more than 2000 samples.
        check_speeds: With ``check_limits``, also raise beyond a velocity limit (``False``: a
            sizing reports the speed margin instead).

    Returns:
        The joint trajectory.

    Raises:
        TrajectoryError: A sample is out of reach, at a parallel singularity, or outside the
            actuator limits, or the trajectory crosses a singularity between two samples (the
            message names the sample and the actuator).

    """
    if robot.platform_frame is None:
        raise InvalidInputError(
            "robot", f"{robot.name} declares no platform frame; {PLATFORM_HINT}"
        )
    model, data = robot.model, robot.data
    rows = robot.task_rows
    N = task.t.size
    Q = np.empty((N, robot.nq))
    V = np.empty((N, robot.nv))
    A = np.empty((N, robot.nv))
    q = robot.q_home if q_init is None else np.asarray(q_init, dtype=float)
    iterator = progress_bar(range(N), f"mapping {task.name}", "sample", progress, min_items=2000)
    names = robot.actuator_names
    last_sign, last_sigma = 0.0, (0.0, 0.0)
    vel_limit = np.array([act.velocity for act in robot.actuators])
    for k in iterator:
        tk = float(task.t[k])
        if k:  # second-order prediction: internal mobilities follow their velocities
            h = tk - float(task.t[k - 1])
            q = pin.integrate(model, q, h * V[k - 1] + 0.5 * h * h * A[k - 1])
        try:
            # a placement: the task rows are imposed, the others are placeholders
            target = pose_from_vector(task.pose[k])
            q = inverse_geometry(robot, target, q_init=q, check_limits=check_limits).q
        except UnreachablePoseError as err:
            raise TrajectoryError(f"pose out of reach: {err}", sample=k, time=tk) from None
        except JointLimitError as err:
            raise TrajectoryError(f"actuator {err}", sample=k, time=tk) from None
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                km = kinematic_models(robot, q)
        except SingularConfigurationError as err:
            raise TrajectoryError(f"singular configuration: {err}", sample=k, time=tk) from None
        if km.margin_A < SINGULAR_TOL:
            raise TrajectoryError(
                f"parallel singularity (cond(A) = {km.cond_A:.3g}): the actuators cannot "
                "control the platform here",
                sample=k,
                time=tk,
            )
        if km.A.shape[0] == km.A.shape[1] == km.B.shape[1]:  # square: not redundant
            # det(J_inv) = det(A) / det(B) does not depend on the basis of A and B: a change of
            # sign between samples means a singularity was crossed between them
            J_inv = numerics.lstsq(km.B, km.A, numerics.machine_rtol(km.B))
            sign = float(np.sign(np.linalg.det(J_inv)))
            if k and sign * last_sign < 0.0:
                kind = (
                    "parallel"
                    if km.sigma_A[-1] + last_sigma[0] < km.sigma_B[-1] + last_sigma[1]
                    else "serial"
                )
                raise TrajectoryError(
                    f"the trajectory crosses a {kind} singularity after t = "
                    f"{task.t[k - 1]:.6g} s (det J_inv changes sign)",
                    sample=k,
                    time=tk,
                )
            last_sign = sign
            last_sigma = (float(km.sigma_A[-1]), float(km.sigma_B[-1]))
        xd, xdd = _task_rates(task.pose[k], task.pose_d[k], task.pose_dd[k])
        K = np.vstack([km.Jc, km.Jx])
        nc = km.Jc.shape[0]
        scale = max(1.0, float(np.max(np.abs(xd))))
        v, res_v, Nint = _lstsq(K, np.concatenate([np.zeros(nc), xd[rows]]), 1e-10)
        if res_v > 1e-8 * scale:
            raise TrajectoryError(
                f"the platform rates are not feasible here (residual {res_v:.3g})",
                sample=k,
                time=tk,
            )
        gamma_c = robot.constraints.drift(data, q, v)
        gamma_x = _platform_drift(robot, q, v)[rows]
        rhs = np.concatenate([-gamma_c, xdd[rows] - gamma_x])
        a, res_a, _ = _lstsq(K, rhs, 1e-10)
        if res_a > 1e-8 * max(1.0, float(np.max(np.abs(rhs)))):
            raise TrajectoryError(
                f"the platform accelerations are not feasible here (residual {res_a:.3g})",
                sample=k,
                time=tk,
            )
        if Nint.shape[1]:
            # internal mobilities: zero momentum (N^T M v = 0) and the accelerations their
            # dynamics dictate (N^T (M a + h) = 0)
            M = pin.crba(model, data, q)
            M = np.triu(M) + np.triu(M, 1).T
            MN = M @ Nint
            NMN = Nint.T @ MN
            v = v - Nint @ np.linalg.solve(NMN, MN.T @ v)
            gamma_c = robot.constraints.drift(data, q, v)
            gamma_x = _platform_drift(robot, q, v)[rows]
            rhs = np.concatenate([-gamma_c, xdd[rows] - gamma_x])
            a, _, _ = _lstsq(K, rhs, 1e-10)
            bias = pin.rnea(model, data, q, v, a)
            a = a - Nint @ np.linalg.solve(NMN, Nint.T @ bias)
        if check_limits and check_speeds:
            fast = np.flatnonzero(np.abs(v[robot.actuated_v]) > vel_limit * (1.0 + 1e-9))
            if fast.size:
                i = int(fast[0])
                raise TrajectoryError(
                    f"actuator '{names[i]}' would move at {v[robot.actuated_v][i]:.4g}, beyond its "
                    f"velocity limit {vel_limit[i]:.4g} (slow the trajectory down)",
                    sample=k,
                    time=tk,
                )
        Q[k], V[k], A[k] = q, v, a
    return JointTrajectory(
        task.t.copy(), Q, V, A, robot.actuated_q, robot.actuated_v, task=task, name=task.name
    )


# ---------------------------------------------------------------------- named trajectories


def _home_pose(robot: Robot) -> np.ndarray:
    if robot.platform_frame is None:
        raise InvalidInputError(
            "robot", f"{robot.name} declares no platform frame; {PLATFORM_HINT}"
        )
    pin.framesForwardKinematics(robot.model, robot.data, robot.q_home)
    M = robot.data.oMf[robot.platform_frame]
    pos, rpy = pose_to_vector(M)
    return np.concatenate([pos, rpy])


def named_trajectory(
    robot: Robot,
    name: str,
    check_limits: bool = True,
    check_speeds: bool = True,
    **options: Any,
) -> JointTrajectory:
    """A built-in trajectory of ``robot`` (see :func:`named_task`), mapped to joint space.

    Args:
        robot: The robot.
        name: ``adept``, ``sine`` or ``p2p``.
        check_limits: Raise if an actuator leaves its position or velocity limits.
        check_speeds: With ``check_limits``, also raise beyond a velocity limit.
        **options: See :func:`named_task`.

    Returns:
        The joint trajectory.

    Raises:
        InvalidInputError: Unknown name or option.
        TrajectoryError: The trajectory leaves the workspace or meets a singularity.

    """
    task = named_task(robot, name, **options)
    return map_task_trajectory(robot, task, check_limits=check_limits, check_speeds=check_speeds)


def named_task(robot: Robot, name: str, **options: Any) -> TaskTrajectory:
    """A built-in platform trajectory of ``robot``.

    ``adept``: :func:`adept_cycle` centred below the home pose (options: ``cycle_time`` [s],
    default 0.5; ``depth`` [m] below home of the pick-and-place line, default 0.05; ``up``,
    ``across``, ``direction``, ``profile``, ``overlap``, ``dt``, ``cycles``, default 1).
    ``sine``: :func:`sinusoid` about the home pose on every task component (options:
    ``amplitude`` [m] for translations, default 0.01; ``angle`` [rad] for rotations, default
    0.02; ``frequency`` [Hz], default 1; ``duration`` [s], default one period; ``dt``).
    ``p2p``: one :func:`point_to_point` move from home by ``offset`` (default 5 cm along x and
    0.1 rad on the task rotations) in ``duration`` (default 0.5 s) with ``profile``.

    Args:
        robot: The robot.
        name: ``adept``, ``sine`` or ``p2p``.
        **options: See above.

    Returns:
        The platform trajectory.

    Raises:
        InvalidInputError: Unknown name or option.

    """
    _check_named(name, options)
    return task_at_home(_home_pose(robot), robot.task_rows, name, **options)


def _check_named(name: Any, options: Mapping[str, Any]) -> None:
    if not isinstance(name, str) or name not in TRAJECTORIES:
        raise InvalidInputError(
            "trajectory", f"unknown trajectory {name!r} (one of {', '.join(TRAJECTORIES)})"
        )
    unknown = sorted(set(options) - set(_OPTIONS[name]) - {"dt"}, key=str)
    if unknown:
        raise InvalidInputError(
            "trajectory",
            f"{name}: unexpected option {unknown[0]!r} (valid: {', '.join(_OPTIONS[name])}, dt)",
        )


def task_at_home(
    home: Sequence[float] | np.ndarray,
    task_rows: Sequence[int] | np.ndarray,
    name: str,
    **options: Any,
) -> TaskTrajectory:
    """:func:`named_task` about a given home pose, for the given task components (no robot).

    A design study checks its duty cycle's options with it before any design is built.

    Args:
        home: Home pose ``[x, y, z, roll, pitch, yaw]`` [m, rad].
        task_rows: The controlled components (0..5: x, y, z, rx, ry, rz).
        name: ``adept``, ``sine`` or ``p2p``.
        **options: See :func:`named_task`.

    Returns:
        The platform trajectory.

    Raises:
        InvalidInputError: Unknown name or option, a bad value, too many samples.

    """
    _check_named(name, options)
    home = _pose6(home, "home")
    task_mask = np.zeros(6, dtype=bool)
    task_mask[np.asarray(task_rows, dtype=int)] = True
    opts = dict(options)
    dt = _number(name, opts, "dt", 1e-3)
    if name == "adept":
        cycles = _number(name, opts, "cycles", 1)
        if cycles != int(cycles) or cycles < 1:
            raise InvalidInputError(
                "cycles", f"{name}: expected a whole number >= 1, got {cycles:g}"
            )
        depth = _number(name, opts, "depth", 0.05)
        if depth < 0.0:
            raise InvalidInputError("depth", f"{name}: the pick line lies below home: >= 0 m")
        bottom = home[:3] - np.array([0.0, 0.0, depth])
        one = adept_cycle(
            bottom,
            cycle_time=_number(name, opts, "cycle_time", 0.5),
            up=_number(name, opts, "up", 0.025),
            across=_number(name, opts, "across", 0.305),
            direction=_number(name, opts, "direction", 0.0),
            profile=str(opts.pop("profile", "quintic")),
            overlap=_number(name, opts, "overlap", 0.0),
            dt=dt,
            warn_coarse=True,
        )
        if int(cycles) * one.t.size > MAX_SAMPLES:
            raise InvalidInputError(
                "cycles",
                f"{name}: {int(cycles)} cycles of {one.t.size} samples exceed {MAX_SAMPLES:.0e} "
                "samples (about half an hour of mapping): fewer cycles or a longer dt",
            )
        return concatenate([one] * int(cycles), name=one.name)
    if name == "sine":
        amp = _number(name, opts, "amplitude", 0.01)
        ang = _number(name, opts, "angle", 0.02)
        f = _number(name, opts, "frequency", 1.0)
        if not f > 0.0:
            raise InvalidInputError("frequency", f"{name}: must be > 0 Hz, got {f}")
        duration = _number(name, opts, "duration", 1.0 / f)
        A = np.where(task_mask, np.r_[[amp] * 3, [ang] * 3], 0.0)
        # distinct frequencies per component so that the motion explores all directions
        freqs = f * np.array([1.0, 1.0, 2.0, 1.0, 1.0, 2.0])
        phases = np.array([0.0, 0.5 * np.pi, 0.0, 0.5 * np.pi, 0.0, 0.0])
        return sinusoid(home.copy(), A, freqs, duration, phases, dt=dt, warn_coarse=True)
    default = np.where(task_mask, np.r_[0.05, 0.0, 0.0, 0.1, 0.1, 0.1], 0.0)
    offset = _pose6(opts.pop("offset", default), "offset")
    duration = _number(name, opts, "duration", 0.5)
    profile = str(opts.pop("profile", "quintic"))
    return point_to_point(home, home + offset, duration, profile, dt=dt, warn_coarse=True)


_OPTIONS = {
    "adept": ("cycle_time", "depth", "up", "across", "direction", "profile", "overlap", "cycles"),
    "sine": ("amplitude", "angle", "frequency", "duration"),
    "p2p": ("offset", "duration", "profile"),
}
"""Options of each built-in trajectory besides ``dt``."""


def _number(name: str, opts: dict[str, Any], key: str, default: float) -> float:
    """Option ``key`` as a finite float (removed from ``opts``)."""
    value = opts.pop(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float | np.number | str):
        raise InvalidInputError(key, f"{name}: expected a number, got {value!r}")
    try:
        x = float(value)
    except ValueError:  # a string that is not a number
        raise InvalidInputError(key, f"{name}: expected a number, got {value!r}") from None
    if not math.isfinite(x):
        raise InvalidInputError(key, f"{name}: expected a finite number, got {value!r}")
    return x
