"""Constrained forward dynamics of a loaded robot: ``simulate``.

Built on :class:`solvers.ForwardDynamics`.
Actuator efforts ``tau(t, q, v)`` are joint-side [N m or N]; gravity is ``model.gravity``; the
solvers' failures become :class:`pkdyn.exceptions.SimulationError`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from pkdyn.dynamics.actuation import actuation
from pkdyn.exceptions import InvalidInputError, SimulationError
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from solvers import ForwardDynamics, ForwardResult, IntegrationError, JointFriction

__all__ = ["TorqueFn", "simulate"]


TorqueFn = Callable[[float, np.ndarray, np.ndarray], np.ndarray]


def simulate(
    robot: Robot,
    duration: float,
    dt: float,
    q0: np.ndarray | None = None,
    v0: np.ndarray | None = None,
    torque: TorqueFn | None = None,
    viscous: float | Sequence[float] = 0.0,
    coulomb: float | Sequence[float] = 0.0,
    integrator: str = "dopri5",
    record_every: int = 1,
) -> ForwardResult:
    """Constrained forward dynamics of the robot under gravity and actuator efforts.

    Args:
        robot: The robot.
        duration: Simulated time [s].
        dt: Output time step [s] (largest substep for ``dopri5``).
        q0: Initial configuration (default ``robot.q_home``); projected onto the closures.
        v0: Initial velocity (default zero); projected onto the closures.
        torque: Joint-side actuator efforts ``torque(t, q, v) -> (n_a,)`` [N m or N]
            (default: none, the actuators are free).
        viscous: Viscous friction coefficient(s) per velocity coordinate [N m s/rad or N s/m].
        coulomb: Coulomb friction level(s) per velocity coordinate [N m or N].
        integrator: ``dopri5`` (adaptive, default), ``rk4`` or ``euler``.
        record_every: Record one sample every that many steps.

    Returns:
        Time series: q, v, a, efforts, closure forces and residuals, energies and work.

    Raises:
        InvalidInputError: Non-positive duration or step, unknown integrator, bad sizes.
        SimulationError: The state becomes non-finite or the closures cannot be kept.

    """
    for what, val in (("duration", duration), ("dt", dt)):
        if not np.isfinite(val) or val <= 0.0:
            raise InvalidInputError(what, f"must be > 0 s, got {val}")
    if integrator not in ("dopri5", "rk4", "euler"):
        raise InvalidInputError("integrator", f"unknown {integrator!r} (dopri5, rk4 or euler)")
    if record_every < 1:
        raise InvalidInputError("record_every", f"must be >= 1, got {record_every}")
    q = robot.q_home if q0 is None else as_finite("q0", q0, robot.nq)
    v = np.zeros(robot.nv) if v0 is None else as_finite("v0", v0, robot.nv)
    friction = None
    if np.any(np.asarray(viscous) != 0.0) or np.any(np.asarray(coulomb) != 0.0):
        friction = JointFriction(
            viscous=np.asarray(viscous, dtype=float), coulomb=np.asarray(coulomb, dtype=float)
        )
    fd = ForwardDynamics(
        robot.model,
        list(robot.constraint_models),
        actuation(robot),
        friction=friction,
        integrator=integrator,
    )
    tau_fn = torque
    if torque is not None:
        n_a = len(robot.actuators)

        def tau_fn(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
            out = np.asarray(torque(t, q, v), dtype=float).reshape(-1)
            if out.size != n_a or not np.all(np.isfinite(out)):
                raise SimulationError(f"torque function returned {out!r} ({n_a} finite values)", t)
            return out

    try:
        return fd.simulate(q, v, duration, dt, tau=tau_fn, record_every=record_every)
    except IntegrationError as err:
        raise SimulationError(str(err), err.time) from None
