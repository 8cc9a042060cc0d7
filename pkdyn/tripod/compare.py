"""The paper's question: does a fourth branch remove the interference? (seed 003).

:func:`compare_walkers` runs the same walking plans with the tripod (``branches=3``) and with the
four-branch walker (``branches=4``, its swings optimised by :mod:`pkdyn.tripod.redundancy`) and
tabulates what each phase check of :mod:`pkdyn.tripod.analysis` found: the smallest leg-to-leg and
leg-to-nacelle distances (coal), the smallest stroke margin, the smallest ``1 / cond``, the largest
actuator force, the number of phases with a violation, and what the fourth branch costs: the
robot's mass, the mass moved by a swing, the actuators' work. A plan a robot cannot do at all
(:class:`pkdyn.exceptions.TrajectoryError`: a foothold out of reach, an unavoidable collision)
gives a row with the error.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from pkdyn.exceptions import TrajectoryError
from pkdyn.model.robot import Robot
from pkdyn.results import Result, deprecated_alias, jsonable
from pkdyn.tripod.analysis import ScenarioReport, run_scenario
from pkdyn.tripod.modes import branch_numbers
from pkdyn.tripod.scenario import WalkPlan

__all__ = ["Comparison", "ComparisonRow", "compare_walkers", "default_cases"]


def default_cases(plan: WalkPlan | None = None) -> list[tuple[str, WalkPlan]]:
    """The plan on the plane and on the 3 m cylinder.

    Args:
        plan: The walking plan (default :class:`pkdyn.tripod.scenario.WalkPlan`); its
            ``surface_radius`` is replaced.

    Returns:
        ``[("plane", plan on the plane), ("cylinder R = 3 m", plan on the cylinder)]``.

    """
    plan = WalkPlan() if plan is None else plan
    return [
        ("plane", replace(plan, surface_radius=math.inf)),
        ("cylinder R = 3 m", replace(plan, surface_radius=3.0)),
    ]


@dataclass
class ComparisonRow:
    """One robot on one case.

    Attributes:
        robot: ``tripod`` or ``walker``.
        case: The case's label.
        branches: Number of branches.
        mass: Mass of the robot [kg].
        swing_mass: Mass of one branch, carried by a swing [kg].
        report: The scenario's report, or ``None`` when the plan could not be done.
        error: Why the plan could not be done, or ``None``.

    """

    robot: str
    case: str
    branches: int
    mass: float
    swing_mass: float
    report: ScenarioReport | None = None
    error: str | None = None

    def _min(self, key: str) -> float:
        assert self.report is not None
        return float(min(getattr(r, key) for r in self.report.reports))

    def values(self) -> dict[str, Any]:
        """The row's figures (SI units; ``None`` where the plan could not be done)."""
        out: dict[str, Any] = {
            "robot": self.robot,
            "case": self.case,
            "branches": self.branches,
            "mass": self.mass,
            "swing_mass": self.swing_mass,
            "error": self.error,
        }
        rep = self.report
        if rep is None:
            return out
        out.update(
            {
                "min_leg_to_leg": self._min("min_leg_to_leg"),
                "min_leg_to_nacelle": self._min("min_leg_to_nacelle"),
                "min_stroke_margin": self._min("min_stroke_margin"),
                "min_singularity_distance": self._min("min_singularity_distance"),
                "max_actuator_force": float(max(r.max_actuator_force for r in rep.reports)),
                "max_actuator_speed": float(max(r.max_actuator_speed for r in rep.reports)),
                "phases": len(rep.reports),
                "phases_with_violation": _violating_phases(rep),
                "violations": rep.violations(),
                "actuator_work": _work(rep),
                "duration": float(rep.t[-1]),
            }
        )
        return out


def _violating_phases(rep: ScenarioReport) -> int:
    return sum(
        1
        for r in rep.reports
        if r.min_stroke_margin < 0.0
        or r.min_leg_distance < 0.0
        or r.max_actuator_force > rep.effort_limit
    )


def _work(rep: ScenarioReport) -> float:
    """Work done by the actuators, the integral of ``sum |tau_i qd_i|`` [J]."""
    total = 0.0
    k = 0
    for ph in rep.phases:
        jt = ph.trajectory
        n = jt.t.size
        power = np.sum(np.abs(rep.tau[k : k + n] * jt.qa_dot), axis=1)
        total += float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(jt.t)))
        k += n
    return total


@dataclass
class Comparison(Result):
    """Tripod against walker on the cases.

    Attributes:
        rows: One per robot and case (cases in order, tripod first).
        cases: The case labels and plans.

    """

    rows: list[ComparisonRow]
    cases: list[tuple[str, WalkPlan]] = field(default_factory=list)

    def row(self, robot: str, case: str) -> ComparisonRow:
        """The row of ``robot`` (``tripod`` or ``walker``) on ``case``."""
        for r in self.rows:
            if r.robot == robot and r.case == case:
                return r
        raise KeyError((robot, case))

    def table(self) -> str:
        """A markdown table of the figures."""
        head = (
            "| case | robot | legs to legs [mm] | legs to nacelle [mm] | stroke margin [mm] | "
            "1/cond | largest force [N] | phases with a violation | mass [kg] | "
            "actuator work [J] |"
        )
        lines = [head, "|" + "---|" * 10]
        for r in self.rows:
            v = r.values()
            if r.report is None:
                lines.append(
                    f"| {r.case} | {r.robot} | cannot: {r.error} | | | | | all | {r.mass:.1f} | |"
                )
                continue
            lines.append(
                f"| {r.case} | {r.robot} | {1e3 * v['min_leg_to_leg']:.0f} | "
                f"{1e3 * v['min_leg_to_nacelle']:.1f} | {1e3 * v['min_stroke_margin']:.0f} | "
                f"{v['min_singularity_distance']:.3f} | {v['max_actuator_force']:.0f} | "
                f"{v['phases_with_violation']} of {v['phases']} | {r.mass:.1f} | "
                f"{v['actuator_work']:.0f} |"
            )
        return "\n".join(lines)

    as_json = deprecated_alias("as_json", "to_json")

    def to_json(self) -> dict[str, Any]:
        """``{"rows": [...]}`` (see :meth:`ComparisonRow.values`)."""
        return jsonable({"rows": [r.values() for r in self.rows]})


def _mass(robot: Robot) -> tuple[float, float]:
    masses = [float(robot.model.inertias[j].mass) for j in range(robot.model.njoints)]
    total = sum(masses)
    branch = sum(m for j, m in enumerate(masses) if robot.model.names[j].startswith("branch1_"))
    return total, branch


def compare_walkers(
    cases: Sequence[tuple[str, WalkPlan]] | None = None,
    robots: Sequence[Robot] | None = None,
    stride: int = 1,
    allocation: str = "norm",
    progress: bool | None = None,
) -> Comparison:
    """Run each case with the tripod and the four-branch walker, and compare.

    Args:
        cases: ``(label, plan)`` pairs (default :func:`default_cases`: the default plan on the
            plane and on the 3 m cylinder).
        robots: The robots (default ``pkdyn.load("tripod")`` and
            ``pkdyn.load("tripod", branches=4)``, with their collision geometry).
        stride: Singularity-margin sampling stride (see :func:`pkdyn.tripod.analysis.analyse`).
        allocation: The walker's effort distribution in mode PP (``"norm"`` or ``"max"``).
        progress: Progress bars (``None``: when stderr is a terminal).

    Returns:
        The comparison.

    """
    if robots is None:
        from pkdyn.model.loader import load

        robots = [load("tripod"), load("tripod", branches=4)]
    cases = default_cases() if cases is None else list(cases)
    rows: list[ComparisonRow] = []
    for label, plan in cases:
        for robot in robots:
            n = len(branch_numbers(robot))
            mass, swing = _mass(robot)
            row = ComparisonRow("tripod" if n == 3 else "walker", label, n, mass, swing)
            try:
                row.report = run_scenario(robot, plan, stride, progress, allocation)
            except TrajectoryError as err:
                row.error = str(err)
            rows.append(row)
    return Comparison(rows, list(cases))
