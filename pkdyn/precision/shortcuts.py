"""The family shortcuts: the dimensions people calibrate on a library family, as twists.

Per-chain Clavel parameters of a Delta (``ra, rb, la, lb``, the arm plane angle, the arm height
and the arm offset of each chain), the base and platform joint centres ``A_i``, ``B_i`` and the
leg offsets of a Gough-Stewart platform (:func:`family_shortcuts`).
"""

from __future__ import annotations

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.robot import Robot
from pkdyn.precision.parameter_model import ParameterModel, with_gains
from pkdyn.precision.placement_parameters import motion_axis
from pkdyn.precision.placements import local_placement, placements

__all__ = ["SHORTCUTS", "family_shortcuts"]


class _Columns:
    """Builder of a shortcut model: named columns of placement twists."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.where = placements(robot)
        self.index = {pl.name: k for k, pl in enumerate(self.where)}
        self.cols: list[np.ndarray] = []
        self.names: list[str] = []
        self.units: list[str] = []

    def add(self, name: str, unit: str, terms: list[tuple[str, np.ndarray]]) -> None:
        col = np.zeros(6 * len(self.where))
        for pl_name, xi in terms:
            k = self.index[pl_name]
            col[6 * k : 6 * k + 6] += xi
        self.cols.append(col)
        self.names.append(name)
        self.units.append(unit)

    def translation(self, pl_name: str, d: np.ndarray) -> np.ndarray:
        """Twist translating a placement along ``d`` given in its parent (joint/link) frame."""
        M = local_placement(self.robot, self.where[self.index[pl_name]])
        return np.concatenate([M.rotation.T @ np.asarray(d, dtype=float), np.zeros(3)])

    def offset(self, joint: str) -> np.ndarray:
        return motion_axis(self.robot, self.robot.model.getJointId(joint))

    def model(self, kind: str, gains: bool) -> ParameterModel:
        E = np.column_stack(self.cols)
        G = np.zeros((len(self.robot.actuators), E.shape[1]))
        if gains:
            E, G = with_gains(self.robot, E, G, self.names, self.units)
        return ParameterModel(
            kind,
            tuple(self.names),
            tuple(self.units),
            self.where,
            E,
            G,
            np.zeros(len(self.names)),
        )


def _delta_shortcuts(robot: Robot, c: _Columns) -> None:
    p = robot.params
    if p.parallelogram != "ball":
        raise InvalidInputError(
            "parameters",
            "the Delta shortcuts describe ball-jointed parallelograms; this Delta has "
            "parallelogram='hinge': use the placement parameters",
        )
    ez = np.array([0.0, 0.0, 1.0])
    for i, theta in enumerate(p.theta, start=1):
        u = np.array([np.cos(theta), np.sin(theta), 0.0])
        arm, motor = f"arm{i}", robot.actuators[i - 1].name
        M = local_placement(robot, c.where[c.index[arm]])
        spin = M.inverse().toActionMatrix() @ np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
        bars = [f"bar{i}{s}_upper" for s in "ab"]
        tips = [f"loop{i}{s}/1" for s in "ab"]
        seats = [f"loop{i}{s}/2" for s in "ab"]
        c.add(f"ra{i}", "m", [(arm, c.translation(arm, u))])
        c.add(f"rb{i}", "m", [(s, c.translation(s, u)) for s in seats])
        c.add(f"la{i}", "m", [(b, c.translation(b, np.array([1.0, 0.0, 0.0]))) for b in bars])
        c.add(f"lb{i}", "m", [(s, c.translation(s, ez)) for s in tips])
        c.add(f"theta{i}", "rad", [(arm, spin)])
        c.add(f"z{i}", "m", [(arm, c.translation(arm, ez))])
        c.add(f"{motor}.offset", "rad", [(arm, c.offset(arm))])


def _gough_stewart_shortcuts(robot: Robot, c: _Columns) -> None:
    joint = "U" if robot.params.base_joint == "universal" else "S"
    for i in range(1, 7):
        for k, axis in enumerate("xyz"):
            d = np.eye(3)[k]
            c.add(f"A{i}{axis}", "m", [(f"leg{i}_{joint}", c.translation(f"leg{i}_{joint}", d))])
        for k, axis in enumerate("xyz"):
            d = np.eye(3)[k]
            c.add(f"B{i}{axis}", "m", [(f"S{i}/2", c.translation(f"S{i}/2", d))])
        motor = robot.actuators[i - 1].name
        c.add(f"{motor}.offset", "m", [(f"leg{i}", c.offset(f"leg{i}"))])


SHORTCUTS = {"delta": _delta_shortcuts, "gough_stewart": _gough_stewart_shortcuts}
"""Families with calibration shortcuts (:func:`family_shortcuts`)."""


def family_shortcuts(robot: Robot, gains: bool = False) -> ParameterModel:
    """The dimensions people calibrate on a library family, as placement twists.

    - Delta (chain ``i``): ``ra<i>`` (arm axis from the base centre, along the arm's radial
      direction), ``rb<i>`` (the chain's two nacelle ball joints, radially), ``la<i>`` (arm
      length: both upper ball joints along the arm), ``lb<i>`` (both bars' length),
      ``theta<i>`` (arm plane angle about the base z axis), ``z<i>`` (arm axis height) [m, rad]
      and the arm's ``<motor>.offset`` [rad];
    - Gough-Stewart (leg ``i``): ``A<i>x A<i>y A<i>z`` (base joint centre, base axes),
      ``B<i>x B<i>y B<i>z`` (platform joint centre, platform axes) [m] and the leg's
      ``<motor>.offset`` [m].

    Args:
        robot: A robot of a family of :data:`SHORTCUTS`.
        gains: Add one relative gain per actuator.

    Returns:
        The parameter model.

    Raises:
        InvalidInputError: The robot is of no family with shortcuts.

    """
    fam = robot.family
    if fam not in SHORTCUTS:
        raise InvalidInputError(
            "parameters",
            f"{robot.name} is {'of family ' + fam if fam else 'of no library family'}; "
            f"family shortcuts exist for {', '.join(SHORTCUTS)}: use the placement parameters",
        )
    c = _Columns(robot)
    SHORTCUTS[fam](robot, c)
    return c.model("family shortcuts", gains)
