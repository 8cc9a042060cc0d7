"""A simulation's time series as a CSV file: actuators, energies, closures, conditioning."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pkdyn.model.robot import Robot
from pkdyn.tables import write_table
from solvers import ForwardResult

__all__ = ["simulation_columns", "write_simulation_csv"]


def simulation_columns(
    robot: Robot, result: ForwardResult, readings: bool = True
) -> dict[str, np.ndarray]:
    """The recorded series by column name.

    ``t`` [s]; per actuator ``<a>`` (``robot.actuator_names``): ``qa_<a>`` and ``qa_dot_<a>``,
    its reading and the reading's rate (:meth:`pkdyn.Robot.readings`: the joint coordinate
    [rad or m] and rate [rad/s or m/s] unless the description has encoder gains or offsets;
    a file read back as a trajectory gives the same motion), ``tau_<a>`` (joint-side effort)
    [N m or N]; ``kinetic``,
    ``potential``, ``work`` (of the efforts), ``dissipated`` (dampers and friction) [J];
    ``energy_balance`` (``kinetic + potential - work + dissipated`` minus its start value: 0
    for an exact integration) [J]; ``closure_residual`` [m or rad]; with couplings,
    ``coupling_residual`` [rad or m]; ``conditioning`` (of the closure forces,
    :mod:`solvers.conditioning`: below 1e-4 near a singularity, below 1e-5 through one).

    Args:
        robot: The simulated robot.
        result: Its :func:`pkdyn.dynamics.simulate` result.
        readings: ``qa_`` columns of readings (``False``: of joint coordinates, as plotted).

    Returns:
        ``{name: (N,) array}`` in column order.

    """
    out: dict[str, np.ndarray] = {"t": result.t}
    names = robot.actuator_names
    qa = result.q[:, robot.actuated_q]
    qd = result.v[:, robot.actuated_v]
    if readings and isinstance(robot, Robot):  # (a result's layout has no encoders)
        qa, qd = robot.readings(qa), robot.readings(qd, rates=True)
    for prefix, data in (("qa", qa), ("qa_dot", qd), ("tau", result.tau)):
        for k, name in enumerate(names):
            out[f"{prefix}_{name}"] = data[:, k]
    out["kinetic"] = result.kinetic
    out["potential"] = result.potential
    out["work"] = result.work
    out["dissipated"] = result.dissipated
    balance = result.energy - result.work + result.dissipated
    out["energy_balance"] = balance - balance[0]
    out["closure_residual"] = result.closure_residual
    constraints = getattr(robot, "constraints", None)  # (a result's layout has none)
    coupled = bool(getattr(result, "couplings", ())) or bool(getattr(constraints, "nk", 0))
    if coupled and result.coupling_residual is not None:
        out["coupling_residual"] = result.coupling_residual
    out["conditioning"] = (
        result.conditioning if result.conditioning is not None else np.ones_like(result.t)
    )
    return out


def write_simulation_csv(robot: Robot, result: ForwardResult, path: str | Path) -> None:
    """Write :func:`simulation_columns` as a CSV file (written whole or not at all).

    Args:
        robot: The simulated robot.
        result: Its simulation result.
        path: Output file.

    Raises:
        OutputError: The file cannot be written (an existing file is left intact).

    """
    cols = simulation_columns(robot, result)
    rows = np.column_stack(list(cols.values()))
    write_table(path, list(cols), rows, digits=10)
