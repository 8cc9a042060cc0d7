"""The commanded motion of a vibration analysis, and what it asks of the elastic model.

A task trajectory (the platform pose and its first two derivatives at samples) is the command.
It is put on a uniform time grid (resampled by quintic Hermite interpolation when its samples
are not evenly spaced: exact for the quintic and polynomial motion laws within a move), mapped
to the joints (:func:`pkdyn.dynamics.trajectory.map_task_trajectory`: closure-consistent ``q``,
``v``, ``a``) and embedded in the elastic model (links undeformed, actuators at their commanded
positions). On the library Delta the actuators' motion and the rigid efforts are closed forms
(:mod:`pkdyn.precision.vibration_closed_form`) and the joints are mapped only when an analysis
asks for them (:attr:`Command.joint`). The command must start and end at rest: the residual
vibration and the settling are defined after a stop.

The actuators' feedforward ``tau_ff`` (the servo law's last term, see
:mod:`pkdyn.precision.vibration`) is computed here: ``none`` (zero), ``gravity`` (the rigid
robot's static efforts at the commanded pose, payload included) or ``rigid`` (its full inverse
dynamics along the command).

Between samples the command is interpolated by quintic Hermite polynomials matching the
position, rate and acceleration at both ends (:class:`Hermite5`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pkdyn.dynamics.delta import DeltaDynamics
from pkdyn.dynamics.inverse import inverse_dynamics
from pkdyn.dynamics.payload import with_payload
from pkdyn.dynamics.trajectory import JointTrajectory, TaskTrajectory, map_task_trajectory
from pkdyn.exceptions import InvalidInputError
from pkdyn.model.robot import Robot
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.vibration_closed_form import (
    ActuatorMotion,
    arm_motion,
    closed_form,
    delta_joint_trajectory,
    gravity_efforts,
)

__all__ = [
    "FEEDFORWARDS",
    "REST_TOL",
    "Command",
    "Hermite5",
    "command",
    "extended_motion",
    "uniform",
]

FEEDFORWARDS = ("none", "gravity", "rigid")
"""The servo feedforward terms (see :mod:`pkdyn.precision.vibration`)."""

REST_TOL = 1e-2
"""A command starts (ends) at rest when its speed there is below this fraction of its peak
speed (files give finite-difference rates: a sampled rest has a small non-zero rate)."""

_UNIFORM_TOL = 1e-9
"""Sample steps equal to within this fraction of the mean step are uniform."""


_HERMITE5 = np.array(
    [
        [1.0, 0.0, 0.0, -10.0, 15.0, -6.0],
        [0.0, 1.0, 0.0, -6.0, 8.0, -3.0],
        [0.0, 0.0, 0.5, -1.5, 1.5, -0.5],
        [0.0, 0.0, 0.0, 10.0, -15.0, 6.0],
        [0.0, 0.0, 0.0, -4.0, 7.0, -3.0],
        [0.0, 0.0, 0.0, 0.5, -1.0, 0.5],
    ]
)
"""Power-basis coefficients (columns: ``s^0 .. s^5``) of the six quintic Hermite functions
(rows: ``x0, h x0', h^2 x0'', x1, h x1', h^2 x1''``)."""


class Hermite5:
    """Quintic Hermite interpolation of sampled positions, rates and accelerations.

    On each interval ``[t_k, t_k+1]`` the polynomial of degree 5 matching ``x``, ``x'`` and
    ``x''`` at both ends (exact for polynomials of degree 5 or less). Outside the samples the
    motion is held at rest at the first (last) value.

    Args:
        t: Sample times (N,) [s], increasing.
        x: Values (N, n).
        xd: First derivatives (N, n).
        xdd: Second derivatives (N, n).

    """

    def __init__(self, t: np.ndarray, x: np.ndarray, xd: np.ndarray, xdd: np.ndarray) -> None:
        self.t = np.asarray(t, dtype=float)
        n = self.t.size
        x = np.asarray(x, dtype=float).reshape(n, -1)
        xd = np.asarray(xd, dtype=float).reshape(n, -1)
        xdd = np.asarray(xdd, dtype=float).reshape(n, -1)
        h = np.diff(self.t)[:, None]
        terms = np.stack(
            [x[:-1], h * xd[:-1], h * h * xdd[:-1], x[1:], h * xd[1:], h * h * xdd[1:]], axis=1
        )  # (K, 6, n)
        self.c = np.einsum("bi,kbn->kin", _HERMITE5, terms)  # (K, 6, n): x = sum c_i s^i
        self.h = h[:, 0]
        self.first = x[0].copy()
        self.last = x[-1].copy()
        steps = np.diff(self.t)
        self._uniform = bool(np.ptp(steps) <= _UNIFORM_TOL * float(np.mean(steps)))
        self._h0 = float(steps[0])
        self._zero = np.zeros(x.shape[1])

    def __call__(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Values, first and second derivatives at ``t``.

        Args:
            t: Times (M,) or one time [s].

        Returns:
            ``(x, x', x'')``, each (M, n) (or (n,) for one time).

        """
        if np.ndim(t) == 0:
            return self.scalar(float(t))  # type: ignore[arg-type]
        tt = np.asarray(t, dtype=float)
        T = self.t
        k = np.clip(np.searchsorted(T, tt, side="right") - 1, 0, T.size - 2)
        h = self.h[k][:, None]
        s = np.clip((tt - T[k]) / self.h[k], 0.0, 1.0)[:, None]
        c = self.c[k]
        x = c[:, 5]
        for i in (4, 3, 2, 1, 0):
            x = x * s + c[:, i]
        xd = 5 * c[:, 5]
        for i in (4, 3, 2, 1):
            xd = xd * s + i * c[:, i]
        xdd = 20 * c[:, 5]
        for i in (4, 3, 2):
            xdd = xdd * s + i * (i - 1) * c[:, i]
        xd = xd / h
        xdd = xdd / (h * h)
        out = (tt < T[0]) | (tt > T[-1])
        if out.any():
            xd[out] = 0.0
            xdd[out] = 0.0
        return x, xd, xdd

    def scalar(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`__call__` at one time, quickly (a servo law calls it at every stage)."""
        T = self.t
        if t <= T[0]:
            return self.first, self._zero, self._zero
        if t >= T[-1]:
            return self.last, self._zero, self._zero
        if self._uniform:
            k = min(int((t - T[0]) / self._h0), T.size - 2)
            if t < T[k]:
                k -= 1
            elif t > T[k + 1]:
                k += 1
        else:
            k = min(int(np.searchsorted(T, t, side="right")) - 1, T.size - 2)
        h = self.h[k]
        s = (t - T[k]) / h
        s2 = s * s
        s3 = s2 * s
        basis = np.array(
            [
                [1.0, s, s2, s3, s2 * s2, s3 * s2],
                [0.0, 1.0 / h, 2.0 * s / h, 3.0 * s2 / h, 4.0 * s3 / h, 5.0 * s2 * s2 / h],
                [
                    0.0,
                    0.0,
                    2.0 / (h * h),
                    6.0 * s / (h * h),
                    12.0 * s2 / (h * h),
                    20.0 * s3 / (h * h),
                ],
            ]
        )
        out = basis @ self.c[k]  # (3, n): value, rate, acceleration
        return out[0], out[1], out[2]


def uniform(task: TaskTrajectory) -> TaskTrajectory:
    """``task`` on evenly spaced samples (itself when they already are).

    Resampled at its mean step by :class:`Hermite5` (same number of samples).
    """
    t = task.t - task.t[0]
    steps = np.diff(t)
    if float(np.ptp(steps)) <= _UNIFORM_TOL * float(np.mean(steps)):
        if task.t[0] == 0.0:
            return task
        return dataclasses.replace(task, t=t)
    grid = np.linspace(0.0, float(t[-1]), t.size)
    x, xd, xdd = Hermite5(t, task.pose, task.pose_d, task.pose_dd)(grid)
    return TaskTrajectory(grid, x, xd, xdd, name=task.name)


def _check_rest(task: TaskTrajectory) -> None:
    speed = np.linalg.norm(task.pose_d[:, :3], axis=1) + np.linalg.norm(task.pose_d[:, 3:], axis=1)
    peak = float(np.max(speed))
    if peak <= 0.0:
        raise InvalidInputError("trajectory", f"{task.name}: the platform does not move")
    for where, k in (("starts", 0), ("ends", -1)):
        if speed[k] > REST_TOL * peak:
            raise InvalidInputError(
                "trajectory",
                f"{task.name} {where} in motion (speed {speed[k]:.3g}, {100 * speed[k] / peak:.1f} "
                f"% of its peak): a vibration analysis runs from rest to rest (the residual "
                "vibration and the settling follow a stop); give a motion that starts and ends at "
                "rest (adept, p2p, or a file that does)",
            )


@dataclass(eq=False)  # numpy fields
class Command:
    """The commanded motion on a uniform grid and its feedforward (see the module docstring).

    The joint trajectory of the whole mechanism is mapped when first asked for
    (:attr:`joint`): a closed-form analysis (:mod:`pkdyn.precision.vibration_closed_form`)
    needs the actuators' motion only.

    Attributes:
        task: The commanded platform trajectory (uniform samples, ``t[0] = 0``).
        tau_ff: Actuator feedforward (N, n_a) [N m or N], joint side.
        feedforward: ``none``, ``gravity`` or ``rigid``.
        loaded: The robot as loaded, with the payload (the rigid model of the feedforward).
        em: The elastic model the command is embedded in (its ``base`` is the robot as loaded).
        arms: The actuators' motion and rigid efforts in closed form, when the robot has one.
        progress: Progress bar of the mapping.
        payload: The payload ``loaded`` carries [kg].
        point: Where, platform frame [m].
        delta: The closed forms of the Delta read from ``loaded``
            (:class:`pkdyn.dynamics.delta.DeltaDynamics`), when they apply.
        mapped: The joint trajectory, once mapped.

    """

    task: TaskTrajectory
    tau_ff: np.ndarray
    feedforward: str
    loaded: Robot
    em: ElasticModel
    arms: ActuatorMotion | None = None
    progress: bool | None = None
    payload: float = 0.0
    point: np.ndarray | None = None
    delta: DeltaDynamics | None = field(default=None, repr=False)
    mapped: JointTrajectory | None = field(default=None, repr=False)
    _extended: tuple[np.ndarray, np.ndarray, np.ndarray] | None = field(default=None, repr=False)

    @property
    def joint(self) -> JointTrajectory:
        """Its joint trajectory on the robot as loaded, mapped on first use.

        In closed form on the library Delta
        (:func:`~pkdyn.precision.vibration_closed_form.delta_joint_trajectory`), else by
        :func:`~pkdyn.dynamics.trajectory.map_task_trajectory`.

        Raises:
            TrajectoryError: The motion leaves the workspace or meets a singularity.

        """
        if self.mapped is None and self.delta is not None and self.arms is not None:
            self.mapped = delta_joint_trajectory(self.em.base, self.delta, self.task, self.arms)
        if self.mapped is None:
            self.mapped = map_task_trajectory(
                self.em.base, self.task, check_speeds=False, progress=self.progress
            )
        return self.mapped

    def _ext(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self._extended is None:
            self._extended = extended_motion(self.em, self.joint)
        return self._extended

    @property
    def q(self) -> np.ndarray:
        """Commanded configurations of the elastic model (N, nq_ext), links undeformed."""
        return self._ext()[0]

    @property
    def v(self) -> np.ndarray:
        """Commanded velocities (N, nv_ext)."""
        return self._ext()[1]

    @property
    def a(self) -> np.ndarray:
        """Commanded accelerations (N, nv_ext)."""
        return self._ext()[2]

    @property
    def t(self) -> np.ndarray:
        """Sample times (N,) [s]."""
        return self.task.t

    @property
    def duration(self) -> float:
        """Duration of the motion ``T`` [s]."""
        return float(self.task.t[-1])

    @property
    def step(self) -> float:
        """Sample period [s]."""
        return float(self.task.t[1] - self.task.t[0])

    def actuators(self) -> Hermite5:
        """Interpolation of the actuators' commanded positions, rates and accelerations."""
        if self.arms is not None:
            m = self.arms
            return Hermite5(self.t, m.qa, m.qa_dot, m.qa_ddot)
        jt = self.joint
        return Hermite5(jt.t, jt.qa, jt.qa_dot, jt.qa_ddot)


def extended_motion(
    em: ElasticModel, joint: JointTrajectory
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A joint trajectory of the robot as loaded, embedded in the elastic model (N, nq/nv ext)."""
    n = joint.t.size
    if em.robot is em.base:
        return joint.q.copy(), joint.v.copy(), joint.a.copy()
    q0 = pin.neutral(em.robot.model)
    Q = np.tile(q0, (n, 1))
    Q[:, em.q_index] = joint.q
    V = np.zeros((n, em.nv))
    A = np.zeros((n, em.nv))
    V[:, em.v_index] = joint.v
    A[:, em.v_index] = joint.a
    return Q, V, A


def command(
    em: ElasticModel,
    task: TaskTrajectory,
    payload: float,
    point: np.ndarray,
    feedforward: str = "none",
    progress: bool | None = None,
) -> Command:
    """The command of a vibration analysis (see the module docstring).

    Args:
        em: The elastic model (its ``base`` is the robot as loaded).
        task: The platform trajectory (rest to rest).
        payload: Point mass at the reference point [kg].
        point: Reference point, platform frame [m].
        feedforward: ``none``, ``gravity`` or ``rigid``.
        progress: Progress bar of the mapping.

    Returns:
        The command.

    Raises:
        InvalidInputError: A motion that does not start or end at rest, an unknown feedforward.
        TrajectoryError: The motion leaves the workspace or meets a singularity.

    """
    if not isinstance(feedforward, str) or feedforward not in FEEDFORWARDS:
        raise InvalidInputError(
            "feedforward", f"unknown {feedforward!r} (one of {', '.join(FEEDFORWARDS)})"
        )
    task = uniform(task)
    _check_rest(task)
    robot = em.base
    loaded = with_payload(robot, payload, offset=tuple(point)) if payload > 0.0 else robot
    n_a = len(robot.actuators)
    cmd = Command(
        task, np.zeros((task.t.size, n_a)), feedforward, loaded, em, None, progress, payload,
        np.array(point, dtype=float),
    )  # fmt: skip
    if closed_form(robot):
        cmd.delta = DeltaDynamics(loaded)
        arms = arm_motion(cmd.delta, task)
        cmd.arms = arms
        if feedforward == "gravity":
            cmd.tau_ff = gravity_efforts(cmd.delta, task)
        elif feedforward == "rigid":
            cmd.tau_ff = arms.tau.copy()
    else:
        joint = cmd.joint  # (mapped here: its errors before any other work)
        if feedforward != "none":
            jt = joint
            if feedforward == "gravity":
                zero = np.zeros_like(joint.v)
                jt = dataclasses.replace(joint, v=zero, a=zero)
            cmd.tau_ff = np.asarray(inverse_dynamics(loaded, jt).tau, dtype=float)
    return cmd
