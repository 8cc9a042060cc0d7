"""The fastest cycle over payloads and motors' rotor inertias: what the payload and the rotor cost.

:func:`fastest_grid` runs :func:`pkdyn.dynamics.fastest.fastest_trajectory` along one path (mapped
once) for every payload, with the robot's drives and with each rotor inertia of a list (the arms
see it multiplied by the reduction squared: :func:`pkdyn.dynamics.actuation.with_drives`).
:class:`FastestGrid` prints, per payload, each cycle time, how much slower the rotor makes it,
the RMS torque of the most loaded actuator, the peak torque that accelerates the rotor, and the
share of the path on a limit; every cell is checked by the independent inverse-dynamics pass of
the fastest motion (its worst use of the torque limit is printed).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.dynamics.actuation import with_drives
from pkdyn.dynamics.fastest import FastestResult, fastest_trajectory, joint_path
from pkdyn.dynamics.sizing import SizingResult, sizing_from_efforts
from pkdyn.dynamics.trajectory import TaskTrajectory
from pkdyn.exceptions import InvalidInputError
from pkdyn.inputs import instance, non_negative, vector
from pkdyn.model.robot import Robot
from pkdyn.progress import progress_steps
from pkdyn.results import Result, jsonable
from pkdyn.units import columns

__all__ = ["MAX_CELLS", "FastestGrid", "fastest_grid"]

MAX_CELLS = 60
"""Most cells (payloads x rotor inertias) of one grid (each a toppra solve or more)."""


@dataclass(frozen=True)
class FastestGrid(Result):
    """Fastest cycles of one path over payloads and rotor inertias.

    Attributes:
        robot: Robot name.
        path: The path's name.
        payloads: Payloads [kg], rows.
        rotor_inertias: Motor-side rotor inertias [kg m^2], columns (``None``: the robot's own
            drives).
        results: The fastest motion of each cell, by ``(payload, rotor_inertia)``.
        sizings: The sizing figures along each of them (:func:`~.sizing.sizing_from_efforts`).

    """

    robot: str
    path: str
    payloads: tuple[float, ...]
    rotor_inertias: tuple[float | None, ...]
    results: dict[tuple[float, float | None], FastestResult]
    sizings: dict[tuple[float, float | None], SizingResult]

    @property
    def cycle_time(self) -> np.ndarray:
        """Cycle time of each cell (payloads, rotor inertias) [s]."""
        return self._cells(lambda r, s: r.cycle_time)

    @property
    def rms(self) -> np.ndarray:
        """Time RMS joint-side effort of the most loaded actuator [N m or N]."""
        return self._cells(lambda r, s: max((a.rms for a in s.actuators), default=0.0))

    @property
    def rotor_peak(self) -> np.ndarray:
        """Peak joint-side effort that accelerates the rotors, ``N^2 J |qa_ddot|`` [N m or N]."""
        return self._cells(lambda r, s: max((a.rotor_peak for a in s.actuators), default=0.0))

    @property
    def active_fraction(self) -> np.ndarray:
        """Share of the path's samples on which a torque or speed limit is active."""
        return self._cells(lambda r, s: r.active_fraction)

    @property
    def torque_utilisation(self) -> float:
        """Largest use of the torque limit by the independent check of every cell."""
        return max(float(np.max(r.torque_utilisation)) for r in self.results.values())

    def _cells(self, fn: Any) -> np.ndarray:
        return np.array(
            [
                [float(fn(self.results[(m, J)], self.sizings[(m, J)])) for J in self.rotor_inertias]
                for m in self.payloads
            ]
        )

    @property
    def effort_unit(self) -> str:
        """``N m`` (revolute actuators), ``N`` (prismatic) or ``N m or N`` (both)."""
        units = {a.units[0] for s in self.sizings.values() for a in s.actuators}
        return units.pop() if len(units) == 1 else "N m or N"

    def to_json(self) -> dict[str, Any]:
        """The grid as JSON values.

        ``cells`` with ``payload`` [kg], ``rotor_inertia`` [kg m^2] (``None``: the robot's
        drives), ``cycle_time`` [s], ``rms``, ``rotor_peak`` [N m or N], ``active_fraction``;
        ``max_torque_utilisation`` of the checks.
        """
        T, rms, rp, act = self.cycle_time, self.rms, self.rotor_peak, self.active_fraction
        return jsonable(
            {
                "robot": self.robot,
                "path": self.path,
                "payloads": list(self.payloads),
                "rotor_inertias": list(self.rotor_inertias),
                "effort_unit": self.effort_unit,
                "max_torque_utilisation": self.torque_utilisation,
                "cells": [
                    {
                        "payload": m,
                        "rotor_inertia": J,
                        "cycle_time": T[i, k],
                        "rms": rms[i, k],
                        "rotor_peak": rp[i, k],
                        "active_fraction": act[i, k],
                    }
                    for i, m in enumerate(self.payloads)
                    for k, J in enumerate(self.rotor_inertias)
                ],
            }
        )

    def table(self) -> str:
        """Per payload and rotor inertia: cycle time, slow-down, RMS, rotor peak, limits active."""
        T, rms, rp, act = self.cycle_time, self.rms, self.rotor_peak, self.active_fraction
        e = self.effort_unit
        rows = [
            [
                "payload [kg]",
                "rotor [kg m^2]",
                "cycle [s]",
                "slower",
                f"rms [{e}]",
                f"rotor pk [{e}]",
                "active",
            ]
        ]
        for i, m in enumerate(self.payloads):
            for k, J in enumerate(self.rotor_inertias):
                slower = f"{100 * (T[i, k] / T[i, 0] - 1):.1f}%" if k else "-"
                rows.append(
                    [
                        f"{m:g}",
                        "drives" if J is None else f"{J:g}",
                        f"{T[i, k]:.4f}",
                        slower,
                        f"{rms[i, k]:.2f}",
                        f"{rp[i, k]:.2f}",
                        f"{100 * act[i, k]:.0f}%",
                    ]
                )
        return (
            f"{self.robot}: fastest {self.path} per payload and rotor inertia\n"
            + columns(rows)
            + "\ncheck: inverse dynamics along each fastest cycle within the torque limit "
            f"({100 * self.torque_utilisation:.4f} % of it at most); "
            + ("'drives': the robot's own; " if None in self.rotor_inertias else "")
            + "'slower': than the first rotor of the payload; rms: time RMS effort of the most "
            "loaded actuator; 'rotor pk': the peak effort that accelerates the rotor, joint "
            "side; 'active': samples on a torque or speed limit"
        )


def fastest_grid(
    robot: Robot,
    path: TaskTrajectory,
    payloads: Sequence[float],
    rotor_inertias: Sequence[float | None] = (None,),
    progress: bool | None = None,
) -> FastestGrid:
    """The fastest cycle along ``path`` for every payload and rotor inertia.

    Args:
        robot: The robot.
        path: The task path (its time is the path parameter, e.g.
            :func:`~pkdyn.dynamics.trajectory.named_task` ``(robot, "adept", dt=...)``); mapped
            to joint space once.
        payloads: Payload masses at the platform [kg] (each >= 0).
        rotor_inertias: Motor-side rotor inertias [kg m^2] (each >= 0; ``None``: the robot's
            own drives).
        progress: Progress bar over the cells (``None``: on a terminal).

    Returns:
        The grid of fastest cycles.

    Raises:
        InvalidInputError: Not a task path, a payload or a rotor inertia < 0, an empty list,
            more than :data:`MAX_CELLS` cells.
        TrajectoryError: The path leaves the workspace or an actuator's stroke.
        InfeasibleEffortError: The path cannot be held at rest with a payload.

    """
    instance("path", path, TaskTrajectory, "a task path (pkdyn.dynamics.trajectory.named_task)")
    masses = tuple(non_negative("payloads", m, "kg") for m in vector("payloads", payloads))
    if isinstance(rotor_inertias, str | bytes) or not isinstance(rotor_inertias, Sequence):
        raise InvalidInputError("rotor_inertias", "give a list of inertias [kg m^2] or None")
    inertias = tuple(
        None if J is None else non_negative("rotor_inertias", J, "kg m^2") for J in rotor_inertias
    )
    for name, values in (("payloads", masses), ("rotor_inertias", inertias)):
        if not values:
            raise InvalidInputError(name, "give at least one value")
    if len(masses) * len(inertias) > MAX_CELLS:
        raise InvalidInputError(
            "payloads",
            f"{len(masses)} x {len(inertias)} cells: more than {MAX_CELLS}; give fewer values",
        )
    joint = joint_path(robot, path, progress=False)
    robots = {J: robot if J is None else with_drives(robot, rotor_inertia=J) for J in inertias}
    results: dict[tuple[float, float | None], FastestResult] = {}
    sizings: dict[tuple[float, float | None], SizingResult] = {}
    with progress_steps(len(masses) * len(inertias), "fastest cycles", "cycle", progress) as step:
        for m in masses:
            for J in inertias:
                res = fastest_trajectory(robots[J], joint, payload=m, progress=False)
                results[(m, J)] = res
                sizings[(m, J)] = sizing_from_efforts(robots[J], res.efforts, m)
                step()
    name = path.name or "path"
    return FastestGrid(robot.name, name, masses, inertias, results, sizings)
