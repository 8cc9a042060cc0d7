"""The placement parameters: every placement's six twist components, optional gains.

An actuated joint's component along its motion axis is named ``<actuator>.offset`` (its other
five keep the names ``tx ... rz`` when the axis is a coordinate axis of the joint frame).
"""

from __future__ import annotations

import numpy as np

from pkdyn.model.robot import Robot
from pkdyn.precision.parameter_model import ParameterModel, with_gains
from pkdyn.precision.placements import COMPONENTS, placements

__all__ = ["motion_axis", "placement_parameters"]


def motion_axis(robot: Robot, joint: int) -> np.ndarray:
    """Motion subspace (6,) of a 1-DOF joint in its frame (translation, rotation)."""
    jm = robot.model.joints[joint]
    jd = jm.createData()
    jm.calc(jd, robot.q_home)
    return np.asarray(jd.S, dtype=float).reshape(6)


def _basis(axis: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """An orthonormal basis of twists whose first vector is ``axis``, with component names.

    The other five are the coordinate directions, minus the one ``axis`` is closest to, made
    orthogonal to it: exactly the five other coordinate twists when ``axis`` is one.
    """
    axis = axis / np.linalg.norm(axis)
    drop = int(np.argmax(np.abs(axis)))
    vecs, names = [axis], ["offset"]
    for k in range(6):
        if k == drop:
            continue
        v = np.eye(6)[k] - axis[k] * axis
        for w in vecs[1:]:
            v -= (w @ v) * w
        n = float(np.linalg.norm(v))
        vecs.append(v / n)
        aligned = abs(n - 1.0) < 1e-12
        names.append(COMPONENTS[k] if aligned else f"d{len(vecs) - 1}")
    return np.column_stack(vecs), names


def placement_parameters(robot: Robot, gains: bool = False) -> ParameterModel:
    """Every placement's 6 twist components, plus actuator gains if asked.

    An actuated joint's component along its motion axis is named ``<actuator>.offset`` (its other
    five keep the names ``tx ... rz`` when the axis is a coordinate axis of the joint frame).

    Args:
        robot: The robot.
        gains: Add one relative gain per actuator (``<actuator>.gain``).

    Returns:
        The parameter model (6 per placement, plus ``n_a`` gains).

    """
    where = placements(robot)
    actuated = {int(j): a for j, a in zip(robot.actuated_joints, robot.actuators, strict=True)}
    cols: list[np.ndarray] = []
    names: list[str] = []
    units: list[str] = []
    n_pl = len(where)
    for k, pl in enumerate(where):
        if pl.kind == "joint" and pl.joint in actuated:
            S = motion_axis(robot, pl.joint)
            basis, comp = _basis(S)
            prismatic = bool(np.linalg.norm(S[:3]) > 0.5)
            act = actuated[pl.joint].name
            for b, c in zip(basis.T, comp, strict=True):
                col = np.zeros(6 * n_pl)
                col[6 * k : 6 * k + 6] = b
                cols.append(col)
                if c == "offset":
                    names.append(f"{act}.offset")
                    units.append("m" if prismatic else "rad")
                else:
                    names.append(f"{pl.name}.{c}")
                    units.append("m" if np.linalg.norm(b[:3]) > 0.5 else "rad")
            continue
        for i in range(6):
            col = np.zeros(6 * n_pl)
            col[6 * k + i] = 1.0
            cols.append(col)
            names.append(f"{pl.name}.{COMPONENTS[i]}")
            units.append("m" if i < 3 else "rad")
    E = np.column_stack(cols)
    n_a = len(robot.actuators)
    G = np.zeros((n_a, E.shape[1]))
    if gains:
        E, G = with_gains(robot, E, G, names, units)
    return ParameterModel(
        "placements", tuple(names), tuple(units), where, E, G, np.zeros(len(names))
    )
