"""Motor sizing over a grid of cycle times and payloads: which cells the motors can drive.

:func:`sizing_grid` sizes the actuators (:func:`pkdyn.dynamics.sizing.size`) along one built-in
motion (``adept`` by default) run in each cycle time of a list, with each payload of another:
one :class:`~pkdyn.dynamics.sizing.SizingResult` per cell, each cell's motion mapped once and
sized for every payload. :class:`SizingGrid` prints the peak effort of the most loaded actuator
with the smallest effort and speed margins of the cell, and draws them (``plot()``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.dynamics.sizing import SizingResult, percent, size
from pkdyn.dynamics.trajectory import map_task_trajectory, named_task
from pkdyn.exceptions import InvalidInputError
from pkdyn.inputs import non_negative, positive, vector
from pkdyn.model.robot import Robot
from pkdyn.progress import progress_steps
from pkdyn.results import Result, jsonable
from pkdyn.units import columns

__all__ = ["MAX_CELLS", "SizingGrid", "sizing_grid"]

MAX_CELLS = 400
"""Most cells (cycle times x payloads) of one grid."""


@dataclass(frozen=True)
class SizingGrid(Result):
    """Sizings of one motion over cycle times and payloads.

    Attributes:
        robot: Robot name.
        trajectory: The built-in motion (``adept``, ``sine`` or ``p2p``).
        cycle_times: Cycle times [s], rows of the grid.
        payloads: Payloads [kg], columns of the grid.
        results: The sizing of each cell, by ``(cycle_time, payload)``.

    """

    robot: str
    trajectory: str
    cycle_times: tuple[float, ...]
    payloads: tuple[float, ...]
    results: dict[tuple[float, float], SizingResult]

    def _cells(self, what: str) -> np.ndarray:
        """(cycle times, payloads) of ``peak``, ``margin``, ``speed_margin`` (worst actuator)."""
        out = np.full((len(self.cycle_times), len(self.payloads)), math.nan)
        for i, T in enumerate(self.cycle_times):
            for j, m in enumerate(self.payloads):
                values = [getattr(a, what) for a in self.results[(T, m)].actuators]
                if what == "peak":
                    out[i, j] = max(values, default=math.nan)
                else:  # (NaN: no limit; the smallest margin of the limited ones)
                    finite = [v for v in values if not math.isnan(v)]
                    out[i, j] = min(finite, default=math.nan)
        return out

    @property
    def peak(self) -> np.ndarray:
        """Peak joint-side effort of the most loaded actuator (cycle times, payloads) [N m or N]."""
        return self._cells("peak")

    @property
    def margin(self) -> np.ndarray:
        """Smallest effort margin of each cell (``1 - peak / limit``; NaN: no limit)."""
        return self._cells("margin")

    @property
    def speed_margin(self) -> np.ndarray:
        """Smallest speed margin of each cell (NaN: no limit)."""
        return self._cells("speed_margin")

    @property
    def feasible(self) -> np.ndarray:
        """Whether each cell is within every limit (cycle times, payloads)."""
        return np.array(
            [[self.results[(T, m)].feasible for m in self.payloads] for T in self.cycle_times]
        )

    @property
    def effort_unit(self) -> str:
        """``N m`` (revolute actuators), ``N`` (prismatic) or ``N m or N`` (both)."""
        units = {a.units[0] for r in self.results.values() for a in r.actuators}
        return units.pop() if len(units) == 1 else "N m or N"

    def to_json(self) -> dict[str, Any]:
        """The grid as JSON values.

        ``cells`` with ``cycle_time`` [s], ``payload`` [kg], ``peak`` [N m or N], ``margin``,
        ``speed_margin`` (``None``: no limit) and ``feasible``.
        """
        peak, margin, speed = self.peak, self.margin, self.speed_margin
        feasible = self.feasible
        cells = [
            {
                "cycle_time": T,
                "payload": m,
                "peak": peak[i, j],
                "margin": margin[i, j],
                "speed_margin": speed[i, j],
                "feasible": bool(feasible[i, j]),
            }
            for i, T in enumerate(self.cycle_times)
            for j, m in enumerate(self.payloads)
        ]
        return jsonable(
            {
                "robot": self.robot,
                "trajectory": self.trajectory,
                "cycle_times": list(self.cycle_times),
                "payloads": list(self.payloads),
                "effort_unit": self.effort_unit,
                "cells": cells,
            }
        )

    def table(self) -> str:
        """Peak effort (effort margin, speed margin) per cycle time (rows) and payload."""
        peak, margin, speed = self.peak, self.margin, self.speed_margin
        feasible = self.feasible
        unit = self.effort_unit
        rows = [["cycle [s]", *(f"{m:g} kg" for m in self.payloads)]]
        for i, T in enumerate(self.cycle_times):
            cells = [
                f"{peak[i, j]:.2f} ({_pct(margin[i, j])}, {_pct(speed[i, j])})"
                + (" " if feasible[i, j] else "!")
                for j in range(len(self.payloads))
            ]
            rows.append([f"{T:g}", *cells])
        return (
            f"{self.robot}: {self.trajectory}, peak effort [{unit}] of the most loaded actuator "
            "(effort margin, speed margin) by cycle time and payload:\n"
            + columns(rows)
            + "\n! = a limit is exceeded (negative margin); - = no limit."
        )


def _pct(margin: float) -> str:
    """A margin in whole percent (``-`` without a limit), never ``-0%``."""
    return percent(margin, 1, 0).strip()


def sizing_grid(
    robot: Robot,
    cycle_times: Sequence[float],
    payloads: Sequence[float],
    trajectory: str = "adept",
    progress: bool | None = None,
    **options: Any,
) -> SizingGrid:
    """Size the actuators along a built-in motion for every cycle time and payload.

    Args:
        robot: The robot.
        cycle_times: Cycle times [s] (each > 0).
        payloads: Payload masses at the platform [kg] (each >= 0).
        trajectory: The built-in motion (:func:`pkdyn.dynamics.trajectory.named_task`).
        progress: Progress bar over the cells (``None``: when the grid takes long).
        **options: Other options of the motion (``depth``, ``dt``...).

    Returns:
        The grid of sizings (limits exceeded are reported by margins, not refused).

    Raises:
        InvalidInputError: A cycle time not > 0 or a payload < 0, an empty list, more than
            :data:`MAX_CELLS` cells, or an unknown motion.
        TrajectoryError: The motion leaves the workspace.

    """
    times = tuple(positive("cycle_times", T, "s") for T in vector("cycle_times", cycle_times))
    masses = tuple(non_negative("payloads", m, "kg") for m in vector("payloads", payloads))
    for name, values in (("cycle_times", times), ("payloads", masses)):
        if not values:
            raise InvalidInputError(name, "give at least one value")
    if len(times) * len(masses) > MAX_CELLS:
        raise InvalidInputError(
            "cycle_times",
            f"{len(times)} x {len(masses)} cells: more than {MAX_CELLS}; give fewer values",
        )
    results: dict[tuple[float, float], SizingResult] = {}
    with progress_steps(len(times) * len(masses), "sizing grid", "cell", progress) as advance:
        for T in times:
            task = named_task(robot, trajectory, cycle_time=T, **options)
            joint = map_task_trajectory(robot, task, check_limits=False)
            for m in masses:
                results[(T, m)] = size(robot, joint, payload=m, progress=False)
                advance()
    return SizingGrid(robot.name, trajectory, times, masses, results)
