"""Accuracy: the error budget of the platform pose, in one report (and every name of its parts).

The parts, one module each:

- :mod:`pkdyn.precision.budgets`: worst case and RMS of actuator errors
  (:func:`actuator_errors`) and geometric tolerances (:func:`geometric_errors`) at a
  configuration, the ranking of the tolerances, the ``error_max`` design metric;
- :mod:`pkdyn.precision.monte_carlo`: :func:`monte_carlo`, robots drawn with random errors and
  solved exactly (the check of the first order);
- :mod:`pkdyn.precision.accuracy_maps`: :func:`accuracy_map`, the position errors over a plane
  (the map convention of :mod:`pkdyn.precision.grid`).

:func:`accuracy_budget` runs the budgets (and optionally the Monte Carlo) at one configuration and
returns them in one result (:class:`Accuracy`) that names the values it assumed when none was
given (the ``accuracy`` command prints it). Every name of the three modules is importable from
here.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.precision.accuracy_maps import AccuracyMap, accuracy_map, slice_grid
from pkdyn.precision.budgets import (
    DEFAULT_RESOLUTION,
    DEFAULT_TOLERANCE,
    DISTRIBUTIONS,
    MAX_ERROR,
    ActuatorAccuracy,
    Budget,
    GeometricAccuracy,
    ToleranceRanking,
    actuator_errors,
    default_resolution,
    geometric_errors,
    largest_position_error,
    pose_error,
    worst_norm,
)
from pkdyn.precision.monte_carlo import MonteCarlo, monte_carlo
from pkdyn.precision.parameters import ParameterModel
from pkdyn.precision.validity import PrecisionWarning
from pkdyn.results import Result, renamed_keyword

__all__ = [
    "DEFAULT_RESOLUTION",
    "DEFAULT_TOLERANCE",
    "DISTRIBUTIONS",
    "MAX_ERROR",
    "Accuracy",
    "AccuracyMap",
    "ActuatorAccuracy",
    "Budget",
    "GeometricAccuracy",
    "MonteCarlo",
    "ToleranceRanking",
    "accuracy_budget",
    "accuracy_map",
    "actuator_errors",
    "default_resolution",
    "geometric_errors",
    "largest_position_error",
    "monte_carlo",
    "pose_error",
    "slice_grid",
    "worst_norm",
]


@dataclass
class Accuracy(Result):
    """The error budget at one configuration: actuators, tolerances, a Monte Carlo check.

    Attributes:
        actuators: The actuator budget.
        geometric: The geometric budget (with the ranking of the tolerances).
        monte_carlo: The Monte Carlo check, or ``None``.
        assumed: The values used because none was given, one line each (named in the table).

    """

    actuators: ActuatorAccuracy
    geometric: GeometricAccuracy
    monte_carlo: MonteCarlo | None = None
    assumed: tuple[str, ...] = ()

    @property
    def valid(self) -> bool:
        """Both budgets hold at this pose."""
        return self.actuators.valid and self.geometric.valid

    @property
    def warnings(self) -> tuple[str, ...]:
        """What to know (the budgets share their pose: their warnings are the same)."""
        return tuple(dict.fromkeys(self.actuators.warnings + self.geometric.warnings))

    def to_json(self) -> dict[str, Any]:
        """``actuators``, ``geometric`` (with ``ranking``), ``monte_carlo``, ``assumed``..."""
        out: dict[str, Any] = {
            "pose_components": ["x", "y", "z", "rx", "ry", "rz"],
            "actuators": self.actuators.to_json(),
            "geometric": self.geometric.to_json(),
            "assumed": list(self.assumed),
            "valid": self.valid,
            "warnings": list(self.warnings),
        }
        if self.monte_carlo is not None:
            out["monte_carlo"] = self.monte_carlo.to_json()
        return out

    def table(self) -> str:
        """The assumptions, the two budgets, the ranking, the Monte Carlo line, the flags."""
        lines = [f"assumed (not given): {a}" for a in self.assumed]
        geo = self.geometric
        lines += [self.actuators.headline(), geo.headline()]
        if geo.top != 0:
            lines.append(geo.ranked(geo.top).table())
        lines += geo._left_out()
        if self.monte_carlo is not None:
            lines.append(self.monte_carlo.table())
        if not self.valid:
            lines.append("NOT VALID here (see the warnings)")
        return "\n".join(lines + [f"warning: {w}" for w in self.warnings])


@renamed_keyword("progress_bar", "progress")
@public
def accuracy_budget(
    robot: Robot,
    q: Sequence[float] | np.ndarray,
    model: ParameterModel,
    resolution: float | Sequence[float] | np.ndarray | None = None,
    backlash: float | Sequence[float] | np.ndarray | None = None,
    tolerance: float | Sequence[float] | np.ndarray | None = None,
    distribution: str = "uniform",
    samples: int = 0,
    seed: int = 0,
    top: int | None = 10,
    progress: bool | None = None,
    *,
    workers: int | None = 1,
    scheduler: str | None = None,
    timeout: float = 10.0,
) -> Accuracy:
    """Actuator and geometric budgets at ``q`` (and a Monte Carlo check), in one result.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        model: The parameter model of the tolerances.
        resolution: Actuator resolution, one or per actuator [rad or m] (``None``: 0, named).
        backlash: Actuator backlash [rad or m] (``None``: 0, named).
        tolerance: One per parameter or one for all [m, rad, -] (``None``:
            :data:`DEFAULT_TOLERANCE` by unit, named).
        distribution: ``uniform`` or ``normal``.
        samples: Monte Carlo robots (0: none).
        seed: Random seed of the Monte Carlo.
        top: Tolerances ranked in the table and JSON (``None``: all).
        progress: Progress bar of the Monte Carlo (``progress_bar``: its former name, kept
            for one release).
        workers: Worker processes of the Monte Carlo (:func:`pkdyn.precision.monte_carlo`).
        scheduler: A Dask scheduler address for the Monte Carlo.
        timeout: How long to wait for the scheduler or for a worker [s].

    Returns:
        The report.

    Raises:
        InvalidInputError: Bad errors, tolerances, distribution or counts.
        SingularConfigurationError: A parallel singularity (unbounded errors).

    """
    if top is not None:
        from pkdyn.inputs import count

        top = count("top", top, 1)
    assumed = []
    if resolution is None:
        resolution = 0.0
        assumed.append("actuator resolution 0 (give one: --resolution)")
    if backlash is None:
        backlash = 0.0
        assumed.append("actuator backlash 0 (give one: --backlash)")
    if tolerance is None:
        length, angle = DEFAULT_TOLERANCE
        tolerance = model.tolerances(length, angle)
        assumed.append(
            f"geometric tolerances +-{length * 1e6:g} um on lengths, +-{angle * 1e3:g} mrad on "
            "angles, 0 on gains (give them: --tolerance LENGTH [ANGLE [GAIN]])"
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PrecisionWarning)  # (issued once, below)
        act = actuator_errors(robot, q, resolution, backlash)
        geo = geometric_errors(robot, q, model, tolerance, distribution)
    act.validity.warn()
    geo.top = top
    mc = None
    if samples:
        mc = monte_carlo(
            robot,
            q,
            model,
            tolerance,
            samples,
            distribution,
            seed,
            progress,
            workers=workers,
            scheduler=scheduler,
            timeout=timeout,
        )
        mc.first_order_rms = geo.position_rms
    return Accuracy(act, geo, mc, tuple(assumed))
