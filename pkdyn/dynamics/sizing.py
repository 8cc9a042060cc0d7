"""Motor sizing: per-actuator efforts, speeds and powers along a trajectory, against the limits.

For each actuator: peak and RMS effort (joint side, and motor side through the drive model of
:mod:`pkdyn.dynamics.actuation`: ``omega_motor = N qd``, ``tau_motor = f(omega) + tau / (N
kappa)``, i.e. ``tau / N`` for a lossless transmission of reduction ``N``), peak speed, peak
power ``|tau qd|``, the share of the reflected rotor inertia, and the margins against the URDF
limits (``margin = 1 - peak / limit``: the fraction of the limit left; negative when exceeded).
The effort limit is read as the motor's peak torque seen through the reduction: the torque
margin compares ``|N| x motor peak`` with it (the joint-side peak for a lossless drive).
The RMS effort is the time RMS over the trajectory (trapezoidal rule), the figure that sizes a
motor's continuous torque. Joint-side efforts include the reflected rotor inertia (armature).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.dynamics.actuation import drives
from pkdyn.dynamics.inverse import EffortTrajectory, inverse_dynamics
from pkdyn.dynamics.payload import with_payload
from pkdyn.dynamics.trajectory import JointTrajectory
from pkdyn.model.robot import Robot
from pkdyn.results import Result, deprecated_alias, jsonable
from pkdyn.tables import write_table
from pkdyn.units import quantity

__all__ = [
    "FEASIBLE_TOL",
    "ActuatorSizing",
    "SizingResult",
    "percent",
    "size",
    "sizing_from_efforts",
]


FEASIBLE_TOL = 1e-6
"""Relative excess of a limit still reported as feasible (rounding of a motion that uses its
limits exactly, such as the fastest cycle)."""


@dataclass(frozen=True)
class ActuatorSizing(Result):
    """Sizing figures of one actuator.

    Attributes:
        name: Actuator name (the transmission, e.g. ``motor1``).
        peak: Peak ``|effort|``, joint side [N m or N].
        rms: RMS effort over time, joint side [N m or N].
        peak_speed: Peak ``|speed|``, joint side [rad/s or m/s].
        peak_power: Peak ``|effort x speed|`` [W].
        limit: Effort limit, joint side (URDF ``effort``; ``inf`` when absent).
        margin: ``1 - peak / limit`` (negative: limit exceeded; NaN without a limit).
        speed_limit: Speed limit, joint side (URDF ``velocity``; ``inf`` when absent).
        speed_margin: ``1 - peak_speed / speed_limit`` (NaN without a limit).
        reduction: Transmission reduction (motor speed = reduction x joint speed).
        motor_peak: Peak ``|effort|`` on the motor side [N m or N].
        motor_rms: RMS effort on the motor side [N m or N].
        motor_peak_speed: Peak motor speed [rad/s or m/s].
        reflected_inertia: Rotor inertia seen by the joint, ``N^2 J`` [kg m^2 or kg].
        rotor_peak: Peak ``|effort|`` that accelerates the rotor, ``N^2 J |qa_ddot|``, joint side
            [N m or N].
        efficiency: Gearbox efficiency when driving.
        motor_mean_speed: Time mean of the motor's ``|speed|`` [rad/s] (with ``motor_rms``: the
            RMS operating point).
        loss: Mean power lost in the drive, motor friction and gearbox [W].
        prismatic: The actuator drives a prismatic joint: joint-side efforts in N and speeds in
            m/s (else N m and rad/s). Its motor side is rotary (N m, rad/s) through a reduction
            in rad/m (a screw: ``2 pi / lead``), linear (N, m/s) when the reduction is 1.

    """

    name: str
    peak: float
    rms: float
    peak_speed: float
    peak_power: float
    limit: float
    margin: float
    speed_limit: float
    speed_margin: float
    reduction: float
    motor_peak: float
    motor_rms: float
    motor_peak_speed: float
    reflected_inertia: float = 0.0
    rotor_peak: float = 0.0
    efficiency: float = 1.0
    motor_mean_speed: float = 0.0
    loss: float = 0.0
    prismatic: bool = False

    @property
    def units(self) -> tuple[str, str, str, str]:
        """Units of (joint effort, joint speed, motor effort, motor speed)."""
        if not self.prismatic:
            return ("N m", "rad/s", "N m", "rad/s")
        if self.reduction == 1.0:
            return ("N", "m/s", "N", "m/s")
        return ("N", "m/s", "N m", "rad/s")

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict (infinite limits as ``None``)."""
        return jsonable(dict(self.__dict__))

    as_json = deprecated_alias("as_json", "to_json")

    def table(self) -> str:
        """Peak and RMS effort against the limit, peak speed, power, in the actuator's units."""
        e, v, _, _ = self.units
        limit = quantity(self.limit, e) if math.isfinite(self.limit) else "none"
        return (
            f"{self.name}: peak {quantity(self.peak, e)}, RMS {quantity(self.rms, e)}, limit "
            f"{limit} (margin {percent(self.margin).strip()}); peak speed "
            f"{quantity(self.peak_speed, v)} (margin {percent(self.speed_margin).strip()}); "
            f"peak power {quantity(self.peak_power, 'W')}"
        )


@dataclass(frozen=True)
class SizingResult(Result):
    """Sizing of every actuator along a trajectory.

    Attributes:
        robot: Robot name.
        trajectory: Trajectory name.
        payload: Payload mass [kg].
        duration: Trajectory duration [s].
        actuators: Per-actuator figures.
        efforts: The underlying efforts, energies and trajectory.
        motor_tau: Motor torques (N, n_a) [N m] (drive model; ``None``: not computed).
        readings: The actuators' readings along the trajectory (N, n_a)
            (:meth:`pkdyn.Robot.readings`; ``None``: the joint coordinates, a robot without
            encoder gains or offsets).
        reading_rates: Their rates (N, n_a) (``None``: the joint rates).

    """

    robot: str
    trajectory: str
    payload: float
    duration: float
    actuators: list[ActuatorSizing]
    efforts: EffortTrajectory
    motor_tau: np.ndarray | None = None
    readings: np.ndarray | None = None
    reading_rates: np.ndarray | None = None

    @property
    def feasible(self) -> bool:
        """All peaks within the effort and speed limits (to :data:`FEASIBLE_TOL`)."""
        tol = -FEASIBLE_TOL
        return all(
            not (m < tol) for a in self.actuators for m in (a.margin, a.speed_margin)
        )  # (NaN: no limit)

    @property
    def exceeded(self) -> list[str]:
        """The limits exceeded, one phrase each (``motor1 torque by 16 %``); empty if feasible."""
        out = []
        for a in self.actuators:
            for what, m in (
                ("torque" if not a.prismatic else "force", a.margin),
                ("speed", a.speed_margin),
            ):
                if m < -FEASIBLE_TOL:
                    out.append(f"{a.name} {what} by {-100 * m:.3g} %")
        return out

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary (``actuators``: list of per-actuator dicts)."""
        return jsonable(
            {
                "robot": self.robot,
                "trajectory": self.trajectory,
                "payload": self.payload,
                "duration": self.duration,
                "feasible": self.feasible,
                "actuators": [a.to_json() for a in self.actuators],
            }
        )

    as_json = deprecated_alias("as_json", "to_json")

    def table(self) -> str:
        """What was sized, then the figures (units per actuator kind: N m, rad/s or N, m/s)."""
        head = (
            f"{self.robot}: {self.trajectory}, {quantity(self.duration, 's')}, payload "
            f"{quantity(self.payload, 'kg')}" + ("" if self.feasible else "  -- LIMITS EXCEEDED")
        )
        return head + "\n" + self.figures()

    def figures(self) -> str:
        """A readable table of the figures (units per actuator kind: N m, rad/s or N, m/s)."""
        head = (
            f"{'actuator':<10} {'peak':>9} {'rms':>9} {'limit':>8} {'margin':>7} "
            f"{'speed':>8} {'v-margin':>8} {'power':>8} {'motor pk':>9} {'motor rms':>9}"
        )
        kinds = {a.units for a in self.actuators}
        mixed = len(kinds) > 1
        rows = [head + ("  units" if mixed else "")]
        if not mixed and kinds:
            e, v, me, _ = next(iter(kinds))
            rows.append(
                f"{'':<10} {f'[{e}]':>9} {f'[{e}]':>9} {f'[{e}]':>8} {'':>7} {f'[{v}]':>8} "
                f"{'':>8} {'[W]':>8} {f'[{me}]':>9} {f'[{me}]':>9}"
            )
        for a in self.actuators:
            limit = f"{a.limit:8.3g}" if math.isfinite(a.limit) else f"{'-':>8}"
            rows.append(
                f"{a.name:<10} {a.peak:9.3f} {a.rms:9.3f} {limit} {percent(a.margin)} "
                f"{a.peak_speed:8.3f} {percent(a.speed_margin, 7)} {a.peak_power:8.1f} "
                f"{a.motor_peak:9.4f} {a.motor_rms:9.4f}"
                + (f"  {a.units[0]}, {a.units[1]}, motor {a.units[2]}" if mixed else "")
            )
        return "\n".join(rows)

    def write_csv(self, path: str | Path) -> None:
        """Time series: ``t``, ``qa_<a>``, ``qa_dot_<a>``, ``tau_<a>`` per actuator, ``energy``.

        ``<a>`` is the actuator's name (``robot.actuator_names``). ``qa_<a>`` and ``qa_dot_<a>``
        are the actuators' **readings** and their rates (the readings rule of
        :meth:`pkdyn.Robot.readings`: what ``--trajectory FILE`` reads back as the same
        motion), ``tau_<a>`` the joint-side efforts [N m or N], ``energy`` [J].

        Args:
            path: Output file.

        Raises:
            OutputError: The file cannot be written (an existing file is left intact).

        """
        ef = self.efforts
        traj = ef.trajectory
        names = ef.actuators
        header = (
            ["t"]
            + [f"qa_{n}" for n in names]
            + [f"qa_dot_{n}" for n in names]
            + [f"tau_{n}" for n in names]
            + ["energy"]
        )
        readings = traj.qa if self.readings is None else self.readings
        rates = traj.qa_dot if self.reading_rates is None else self.reading_rates
        table = np.column_stack([traj.t, readings, rates, ef.tau, ef.energy])
        write_table(path, header, table, digits=10)


def _rms(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Time RMS of the columns of ``x`` (trapezoidal rule)."""
    T = float(t[-1] - t[0])
    sq = x**2
    return np.sqrt(np.sum(0.5 * (sq[1:] + sq[:-1]) * np.diff(t)[:, None], axis=0) / T)


def _margin(peak: float, limit: float) -> float:
    """``1 - peak / limit``; NaN where there is no limit (no margin to report)."""
    if not math.isfinite(limit):
        return math.nan
    if limit <= 0.0:
        return -math.inf
    return 1.0 - peak / limit


def percent(margin: float, width: int = 6, digits: int = 1) -> str:
    """A margin as a percentage for tables: ``-`` without a limit, never ``-0.0%``."""
    if math.isnan(margin):
        return f"{'-':>{width}} "
    v = round(100.0 * margin, digits)
    return f"{v + 0.0:{width}.{digits}f}%"  # (+ 0.0 turns -0.0 into 0.0)


def size(
    robot: Robot,
    trajectory: JointTrajectory,
    payload: float = 0.0,
    wrench: Any = None,
    progress: bool | None = None,
    passive: bool = True,
) -> SizingResult:
    """Size the actuators of ``robot`` for a trajectory (inverse dynamics with gravity).

    Args:
        robot: The robot.
        trajectory: Joint trajectory (:mod:`pkdyn.dynamics.trajectory`), consistent with the
            closures.
        payload: Point-mass payload at the platform frame origin [kg].
        wrench: Platform wrench, see :func:`pkdyn.dynamics.inverse_dynamics`.
        progress: Progress bar: ``True`` / ``False`` force it on / off, ``None`` (default) as
            :func:`pkdyn.dynamics.inverse_dynamics` decides.
        passive: Include the robot's springs, dampers and friction (``robot.passive``);
            ``False`` gives the efforts without them.

    Returns:
        The figures per actuator and the time series behind them.

    Raises:
        InfeasibleEffortError: The motion is not dynamically consistent at some sample.
        InvalidInputError: Bad payload or wrench.

    """
    loaded = with_payload(robot, payload) if payload else robot
    ef = inverse_dynamics(loaded, trajectory, wrench=wrench, progress=progress, passive=passive)
    return sizing_from_efforts(robot, ef, payload)


def sizing_from_efforts(robot: Robot, ef: EffortTrajectory, payload: float = 0.0) -> SizingResult:
    """The sizing figures of efforts already computed (see :func:`size`).

    Args:
        robot: The robot (its drives and limits).
        ef: Efforts along a trajectory (:func:`pkdyn.dynamics.inverse_dynamics`).
        payload: Payload mass the efforts were computed with [kg] (reported only).

    Returns:
        The figures per actuator.

    """
    trajectory = ef.trajectory
    t = trajectory.t
    tau, qd, qdd = ef.tau, trajectory.qa_dot, trajectory.qa_ddot
    drv = drives(robot)
    tau_m = drv.motor_effort(tau, qd)
    omega = drv.motor_speed(qd)
    p_fric, p_gear = drv.losses(tau_m, qd)
    loss = p_fric + p_gear
    peak = np.max(np.abs(tau), axis=0)
    rms = _rms(t, tau)
    speed = np.max(np.abs(qd), axis=0)
    power = np.max(np.abs(tau * qd), axis=0)
    m_peak = np.max(np.abs(tau_m), axis=0)
    m_rms = _rms(t, tau_m)
    T = float(t[-1] - t[0])
    m_mean = _mean(t, np.abs(omega))
    mean_loss = _mean(t, loss)
    rotor = np.max(np.abs(drv.armature * qdd), axis=0)
    out = []
    prismatic = robot.actuator_prismatic
    for i, act in enumerate(robot.actuators):
        r = act.reduction
        out.append(
            ActuatorSizing(
                name=act.name,
                peak=float(peak[i]),
                rms=float(rms[i]),
                peak_speed=float(speed[i]),
                peak_power=float(power[i]),
                limit=float(act.effort),
                margin=_margin(float(abs(r) * m_peak[i]), act.effort),
                speed_limit=float(act.velocity),
                speed_margin=_margin(float(speed[i]), act.velocity),
                reduction=float(r),
                motor_peak=float(m_peak[i]),
                motor_rms=float(m_rms[i]),
                motor_peak_speed=float(speed[i] * abs(r)),
                reflected_inertia=float(drv.armature[i]),
                rotor_peak=float(rotor[i]),
                efficiency=float(act.efficiency),
                motor_mean_speed=float(m_mean[i]),
                loss=float(mean_loss[i]),
                prismatic=bool(prismatic[i]),
            )
        )
    return SizingResult(
        robot=robot.name,
        trajectory=trajectory.name,
        payload=float(payload),
        duration=T,
        actuators=out,
        efforts=ef,
        motor_tau=tau_m,
        readings=robot.readings(trajectory.qa),
        reading_rates=robot.readings(trajectory.qa_dot, rates=True),
    )


def _mean(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Time mean of the columns of ``x`` (trapezoidal rule)."""
    T = float(t[-1] - t[0])
    return np.sum(0.5 * (x[1:] + x[:-1]) * np.diff(t)[:, None], axis=0) / T
