"""Constrained forward dynamics of a loaded robot: ``simulate``.

Built on :class:`solvers.ForwardDynamics`.
Actuator efforts ``tau(t, q, v)`` are joint-side [N m or N], or motor torques
``motor_torque(t, q, v)`` [N m] mapped through the robot's drives (reduction, gearbox efficiency,
motor friction: :mod:`pkdyn.dynamics.actuation`); the rotor inertia is in the model's armature
either way; gravity is ``model.gravity``; the robot's passive elements (``robot.passive``:
springs, dampers, friction) act unless ``passive=False``; the solvers' failures become
:class:`pkdyn.exceptions.SimulationError`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from pkdyn.dynamics.actuation import actuation, drives
from pkdyn.dynamics.callbacks import user_efforts
from pkdyn.dynamics.simulation_result import SimulationResult
from pkdyn.exceptions import InvalidInputError, SimulationError
from pkdyn.inputs import callable_input, count, positive
from pkdyn.model.arguments import public
from pkdyn.model.passive import FRICTION_SMOOTHING
from pkdyn.model.pose import as_configuration, as_finite
from pkdyn.model.robot import Robot
from solvers import ForwardDynamics, IntegrationError, PassiveForces

__all__ = ["TorqueFn", "simulate"]


TorqueFn = Callable[[float, np.ndarray, np.ndarray], np.ndarray]
"""Actuator efforts ``tau(t, q, v)`` (n_a,) [N m or N] from the time [s], ``q`` and ``v``."""


@public
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
    passive: bool = True,
    step: float | None = None,
    motor_torque: TorqueFn | None = None,
) -> SimulationResult:
    """Constrained forward dynamics of the robot under gravity and actuator efforts.

    Args:
        robot: The robot.
        duration: Simulated time [s].
        dt: Output time step [s]: the closures are checked (and the state projected back on
            them when their residual exceeds 1e-9) and a sample recorded once per output step.
        q0: Initial configuration (default ``robot.q_home``); projected onto the closures.
        v0: Initial velocity (default zero); projected onto the closures.
        torque: Joint-side actuator efforts ``torque(t, q, v) -> (n_a,)`` [N m or N]
            (default: none, the actuators are free).
        viscous: Extra viscous damping per velocity coordinate, scalar or (nv,)
            [N m s/rad or N s/m], added to the joints' own damping.
        coulomb: Extra Coulomb friction per velocity coordinate, scalar or (nv,) [N m or N],
            added to the joints' own friction.
        integrator: ``dopri5`` (adaptive, default), ``rk4`` or ``euler``.
        record_every: Record one sample every that many output steps.
        passive: Include the robot's own passive elements (``robot.passive``).
        step: Integration step [s] of ``euler`` and ``rk4`` (``dt`` is divided into a whole
            number of steps), largest substep of ``dopri5`` (default: ``dt``). ``euler`` keeps
            the energy of a passive Delta to 0.1 % over 10 s at ``step=1e-5``.
        motor_torque: Motor torques ``motor_torque(t, q, v) -> (n_a,)`` [N m] instead of
            ``torque``: the joint-side efforts are ``Drives.joint_effort(tau_m, qa_dot)``
            (efficiency and motor friction included). Without either, the motors are free: zero
            motor torque, so the motor friction and the back-driven gearbox still act.

    Returns:
        Time series (:class:`~pkdyn.dynamics.simulation_result.SimulationResult`, a
        :class:`solvers.ForwardResult` with the actuators' names): q, v, a, efforts (joint
        side), closure forces and residuals, energies (the springs' in ``elastic``), the work
        of the joint-side efforts and the energy dissipated by dampers and friction (the
        losses in the drives are outside the mechanism: ``Drives.losses``).

    Raises:
        InvalidInputError: Non-positive duration or step, a step longer than the duration,
            more than :data:`MAX_STEPS` steps or :data:`MAX_RECORD_BYTES` of recording,
            negative damping or friction, unknown integrator, bad sizes.
        SimulationError: The state becomes non-finite or blows up (joint speed beyond
            10^4 rad/s or m/s), the adaptive step count within an output step exceeds its
            limit, or the closures cannot be kept.

    """
    duration = positive("duration", duration, "s")
    dt = positive("dt", dt, "s")
    record_every = count("record_every", record_every)
    if step is not None:
        step = positive("step", step, "s")
    if not isinstance(integrator, str) or integrator not in ("dopri5", "rk4", "euler"):
        raise InvalidInputError("integrator", f"unknown {integrator!r} (dopri5, rk4 or euler)")
    if dt > duration:
        raise InvalidInputError(
            "dt", f"{dt:g} s is longer than the duration {duration:g} s: no step would be taken"
        )
    _check_work(robot, duration, dt, record_every)
    if step is not None and duration / min(step, dt) > MAX_STEPS:
        raise InvalidInputError(
            "step",
            f"{duration:g} s in integration steps of {min(step, dt):g} s is "
            f"{duration / min(step, dt):.3g} steps; at most {MAX_STEPS:.0e}: use a longer step",
        )
    for what, fn in (("torque", torque), ("motor_torque", motor_torque)):
        if fn is not None:
            callable_input(what, fn)
    q = robot.q_home if q0 is None else as_configuration(robot.model, "q0", q0)
    v = np.zeros(robot.nv) if v0 is None else as_finite("v0", v0, robot.nv)
    fd = ForwardDynamics(
        robot.model,
        robot.constraints,
        actuation(robot),
        passive=_passive(robot, passive, viscous, coulomb),
        integrator=integrator,
    )
    if torque is not None and motor_torque is not None:
        raise InvalidInputError("motor_torque", "give either torque or motor_torque, not both")
    drv = drives(robot)
    tau_fn = None
    if torque is not None:
        tau_fn = user_efforts("torque", torque, len(robot.actuators))
    elif motor_torque is not None or not drv.lossless:
        tau_fn = _through_drives(robot, motor_torque)
    try:
        out = fd.simulate(q, v, duration, dt, tau=tau_fn, record_every=record_every, step=step)
    except IntegrationError as err:
        raise SimulationError(_untimed(str(err), err.time), err.time) from None
    g = max(float(np.linalg.norm(robot.model.gravity.linear)), 1.0)
    mass = sum(robot.model.inertias[j].mass for j in range(robot.model.njoints))
    out.energy_scale = float(mass * g * robot.length_scale)
    return SimulationResult.of(robot, out, integrator, dt)


MAX_STEPS = 10_000_000
"""Largest number of output steps of one :func:`simulate` call (about an hour of computing)."""

MAX_RECORD_BYTES = 2 * 1024**3
"""Largest memory of the recorded time series of one :func:`simulate` call."""


def _check_work(robot: Robot, duration: float, dt: float, record_every: int) -> None:
    """Refuse up front a run that would take hours or exhaust memory (with the estimate)."""
    steps = duration / dt
    if steps > MAX_STEPS:
        raise InvalidInputError(
            "dt",
            f"{duration:g} s in steps of {dt:g} s is {steps:.3g} steps (hours of computing at "
            f"~50 us each); at most {MAX_STEPS:.0e}: use a longer dt or a shorter duration",
        )
    nc = robot.constraints.n
    per_sample = 8 * (robot.nq + 3 * robot.nv + len(robot.actuators) + nc + 8)
    need = (steps / record_every + 2) * per_sample
    if need > MAX_RECORD_BYTES:
        every = int(np.ceil(need / MAX_RECORD_BYTES * record_every))
        raise InvalidInputError(
            "record_every",
            f"recording {steps / record_every:.3g} samples of {robot.name} would take "
            f"{need / 1e9:.3g} GB (at most {MAX_RECORD_BYTES / 1e9:.3g} GB); record every "
            f"{every} steps or fewer",
        )


def _untimed(message: str, time: float) -> str:
    """A solver's message without its leading ``t = ... s:`` (the error adds its own)."""
    prefix = f"t = {time:.6g} s: "
    return message[len(prefix) :] if message.startswith(prefix) else message


def _extra(name: str, x: float | Sequence[float], nv: int) -> np.ndarray:
    from pkdyn.inputs import vector

    arr = vector(name, x, (1, nv))
    if arr.ndim > 1 or arr.size not in (1, nv) or not np.all(np.isfinite(arr)):
        raise InvalidInputError(name, f"expected one or {nv} finite values, got {arr.tolist()}")
    if np.any(arr < 0.0):
        raise InvalidInputError(name, f"must be >= 0, got {arr.tolist()}")
    return np.array(np.broadcast_to(arr, (nv,)))


def _passive(
    robot: Robot, own: bool, viscous: float | Sequence[float], coulomb: float | Sequence[float]
) -> PassiveForces | None:
    """The robot's passive forces (if ``own``) with extra damping and friction."""
    base = robot.passive if own else None
    c = _extra("viscous", viscous, robot.nv)
    f = _extra("coulomb", coulomb, robot.nv)
    if not (np.any(c) or np.any(f)):
        return base
    if base is None:
        return PassiveForces(robot.model, damping=c, friction=f, smoothing=FRICTION_SMOOTHING)
    return PassiveForces(
        robot.model,
        stiffness=base.stiffness,
        rest=base.rest,
        damping=base.damping + c,
        friction=base.friction + f,
        smoothing=base.smoothing,
        springs=base.springs,
    )


def _through_drives(robot: Robot, motor_torque: TorqueFn | None) -> TorqueFn:
    """Joint-side efforts of motor torques (zero when ``motor_torque`` is ``None``)."""
    drv = drives(robot)
    va = robot.actuated_v
    n_a = len(robot.actuators)
    zero = np.zeros(n_a)

    motor = None if motor_torque is None else user_efforts("motor_torque", motor_torque, n_a)

    def joint_side(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        tau_m = zero if motor is None else motor(t, q, v)
        return drv.joint_effort(tau_m, v[va])

    return joint_side
