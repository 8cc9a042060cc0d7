"""Actuator figures of a design on a duty cycle (a named trajectory with a payload).

The trajectory is :func:`pkdyn.dynamics.trajectory.named_task` with the study's options, the
same one ``pkdyn size ROBOT --trajectory NAME`` runs, so a chosen design can be checked with
that command. The library Delta (three arms, ball-jointed bars) goes through the vectorised
closed form (:mod:`pkdyn.dynamics.delta`), any other robot through the general mapping and
inverse dynamics (:func:`pkdyn.dynamics.sizing.size`). The figures are those of
:mod:`pkdyn.dynamics.sizing`: peak and RMS (trapezoidal, over time) joint-side effort, peak
speed, peak power, per actuator.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.dynamics.delta import delta_inverse_dynamics, has_delta_dynamics
from pkdyn.dynamics.sizing import size
from pkdyn.dynamics.trajectory import TaskTrajectory, map_task_trajectory, named_task
from pkdyn.model.robot import Robot

__all__ = ["DutyFigures", "duty_figures"]


@dataclass(frozen=True)
class DutyFigures:
    """Per-actuator figures on a duty cycle (joint side).

    Attributes:
        actuators: Actuator (joint) names.
        peak: Peak ``|effort|`` (n_a,) [N m or N].
        rms: RMS effort over time (n_a,) [N m or N].
        peak_speed: Peak ``|speed|`` (n_a,) [rad/s or m/s].
        peak_power: Peak ``|effort x speed|`` (n_a,) [W].
        effort_limit: Effort limits (n_a,) [N m or N] (``inf`` when absent).
        speed_limit: Speed limits (n_a,) [rad/s or m/s].
        duration: Trajectory duration [s].
        method: ``closed form`` or ``general``.

    """

    actuators: list[str]
    peak: np.ndarray
    rms: np.ndarray
    peak_speed: np.ndarray
    peak_power: np.ndarray
    effort_limit: np.ndarray
    speed_limit: np.ndarray
    duration: float
    method: str


def _rms(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Time RMS of the columns of ``x`` (trapezoidal rule), as :mod:`pkdyn.dynamics.sizing`."""
    sq = x**2
    return np.sqrt(np.sum(0.5 * (sq[1:] + sq[:-1]) * np.diff(t)[:, None], axis=0) / (t[-1] - t[0]))


def duty_figures(
    robot: Robot,
    trajectory: str = "adept",
    options: Mapping[str, Any] | None = None,
    payload: float = 0.0,
    tasks: dict[Any, TaskTrajectory] | None = None,
) -> DutyFigures:
    """Actuator figures of ``robot`` on a named trajectory with a payload.

    Args:
        robot: The robot.
        trajectory: ``adept``, ``sine`` or ``p2p`` (:func:`pkdyn.dynamics.trajectory.named_task`).
        options: Options of the trajectory (``cycle_time`` [s], ``depth`` [m], ``dt`` [s]...).
        payload: Point-mass payload at the platform frame [kg].
        tasks: A cache of platform trajectories shared between designs: the trajectory only
            depends on the home pose and the controlled components (a study's designs often
            share them).

    Returns:
        The figures.

    Raises:
        TrajectoryError: The trajectory leaves the reach or the actuator limits, or meets a
            singularity.
        InfeasibleEffortError: The motion is not dynamically consistent.

    """
    opts = dict(options or {})
    home = robot.platform_placement(robot.q_home)
    key = (
        trajectory,
        repr(sorted(opts.items())),
        home.translation.tobytes(),
        home.rotation.tobytes(),
        robot.task_rows.tobytes(),
    )
    task = None if tasks is None else tasks.get(key)
    if task is None:
        task = named_task(robot, trajectory, **opts)
        if tasks is not None:
            if len(tasks) > 64:
                tasks.clear()
            tasks[key] = task
    effort = np.array([a.effort for a in robot.actuators], dtype=float)
    speed = np.array([a.velocity for a in robot.actuators], dtype=float)
    if has_delta_dynamics(robot):
        at = delta_inverse_dynamics(robot, task, payload=payload)
        tau, qd, method = at.tau, at.qa_dot, "closed form"
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            traj = map_task_trajectory(robot, task)
            tau = size(robot, traj, payload=payload).efforts.tau
        qd, method = traj.qa_dot, "general"
    t = task.t
    return DutyFigures(
        actuators=robot.actuator_names,
        peak=np.max(np.abs(tau), axis=0),
        rms=_rms(t, tau),
        peak_speed=np.max(np.abs(qd), axis=0),
        peak_power=np.max(np.abs(tau * qd), axis=0),
        effort_limit=effort,
        speed_limit=speed,
        duration=float(t[-1] - t[0]),
        method=method,
    )
