"""Constrained forward dynamics of a loaded robot: ``simulate`` and ``ForwardDynamics``.

Built on :class:`solvers.ForwardDynamics`.
Actuator efforts ``tau(t, q, v)`` are joint-side [N m or N], or motor torques
``motor_torque(t, q, v)`` [N m] mapped through the robot's drives (reduction, gearbox efficiency,
motor friction: :mod:`pkdyn.dynamics.actuation`); the rotor inertia is in the model's armature
either way; gravity is ``model.gravity``; the robot's passive elements (``robot.passive``:
springs, dampers, friction) act unless ``passive=False``; the solvers' failures
(``solvers.IntegrationError``, numpy's ``LinAlgError``) become
:class:`pkdyn.exceptions.SimulationError`, bad arguments
:class:`pkdyn.exceptions.InvalidInputError` naming them.

**Singular passages.** Where the motion passes near or through a singularity of the closures
(the conditioning of the closure forces below 1e-4, :mod:`solvers.conditioning`), the result
records an event (time, conditioning, whether it went through) and one warning is issued; past
a passage *through* one (``result.valid_until``) the motion is not the exact rigid one, and the
energy and closure figures are claimed up to there.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from pkdyn.dynamics.actuation import actuation, drives
from pkdyn.dynamics.callbacks import user_efforts
from pkdyn.dynamics.simulation_result import SimulationResult
from pkdyn.exceptions import InvalidInputError, SimulationError
from pkdyn.inputs import callable_input, count, flag, instance, positive, real
from pkdyn.model.arguments import public
from pkdyn.model.passive import FRICTION_SMOOTHING
from pkdyn.model.pose import as_configuration, as_finite
from pkdyn.model.reuse import kept_data
from pkdyn.model.robot import Robot
from pkdyn.model.warn import warn
from pkdyn.threads import one_blas_thread
from solvers import ForwardDynamics as _SolverDynamics
from solvers import IntegrationError, PassiveForces
from solvers.conditioning import SingularityEvent

__all__ = ["ForwardDynamics", "TorqueFn", "simulate", "singularity_warning"]


TorqueFn = Callable[[float, np.ndarray, np.ndarray], np.ndarray]
"""Actuator efforts ``tau(t, q, v)`` (n_a,) [N m or N] from the time [s], ``q`` and ``v``."""


@public
@one_blas_thread
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

    Warns:
        UserWarning: Once, when the motion passes near or through a singularity of the
            closures (:func:`singularity_warning`; the passages are ``result.events``).

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
    if torque is not None and motor_torque is not None:
        raise InvalidInputError("motor_torque", "give either torque or motor_torque, not both")
    fd = ForwardDynamics(
        robot,
        integrator,
        passive=passive,
        viscous=viscous,
        coulomb=coulomb,
        # (a run's datas kept by the robot: nv^3 in size, made once, pkdyn.model.reuse)
        datas=(kept_data(robot, "forward"), kept_data(robot, "forward kinematics")),
    )
    drv = drives(robot)
    tau_fn = None
    if torque is not None:
        tau_fn = user_efforts("torque", torque, len(robot.actuators))
    elif motor_torque is not None or not drv.lossless:
        tau_fn = _through_drives(robot, motor_torque)
    return fd._simulate(q, v, duration, dt, tau_fn, record_every, 0.0, step)


def singularity_warning(
    name: str, events: Sequence[SingularityEvent], valid_until: float | None
) -> str:
    """The one warning of a motion with singular passages (one line).

    Args:
        name: The robot's name.
        events: The passages, in time order (at least one).
        valid_until: The start of the first passage through a singularity [s] (a simulation's
            ``valid_until``), or ``None`` for a control loop (:meth:`ForwardDynamics.step`,
            whose later passages are recorded without a warning).

    Returns:
        The message: the first passage (time, conditioning, near or through), how many more,
        and from when the motion is no longer the exact rigid one.

    """
    first = events[0]
    more = f" ({len(events) - 1} more passage(s) in result.events)" if len(events) > 1 else ""
    if valid_until is None:
        more = " (this and later passages: ForwardDynamics.events)"
    head = f"{name}: the motion passed {first.describe()}{more}: its closures lose rank there"
    if any(e.through for e in events):
        at = "" if valid_until is None else f" (t = {valid_until:.6g} s: result.valid_until)"
        return (
            f"{head}; past a passage through one{at} the motion is the model's minimum-norm "
            "continuation, not the exact rigid one: its energy and closure figures hold up to it"
        )
    return f"{head}, and their forces peak"


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


def _configuration(model: Any, name: str, q: Any) -> np.ndarray:
    """``q`` itself when it is a float array of the right size, else checked and normalised.

    (The control step recognises the state it returned by its bytes: no copy on the fast path.)
    """
    if type(q) is np.ndarray and q.dtype == np.float64 and q.shape == (model.nq,):
        return q
    return as_configuration(model, name, q)


def _finite_state(q: np.ndarray, v: np.ndarray) -> None:
    """Name a non-finite ``q`` or ``v`` (checked once a step failed: the fast path does not)."""
    for name, x in (("q", q), ("v", v)):
        as_finite(name, x)


def _velocity(nv: int, name: str, v: Any) -> np.ndarray:
    if type(v) is np.ndarray and v.dtype == np.float64 and v.shape == (nv,):
        return v
    return as_finite(name, v, nv)


class ForwardDynamics(_SolverDynamics):
    """The forward dynamics of a loaded robot, stepped by a control loop or simulated.

    :class:`solvers.ForwardDynamics` built from the robot (its closures and couplings, joint-side
    actuator efforts, passive elements, length scale, and the rank of its closures at home as
    the reference of the conditioning), with the public boundary's contract: every argument is
    checked and named when wrong (:class:`~pkdyn.exceptions.InvalidInputError`), the solvers'
    failures become :class:`~pkdyn.exceptions.SimulationError` with the time, a torque function
    that raises or returns something else than ``n_a`` finite numbers is named, and the first
    passage near or through a singularity of the closures issues one warning (the passages
    are in :attr:`events`).

    Args:
        robot: The robot.
        integrator: ``dopri5``, ``rk4`` or ``euler`` (see :class:`solvers.ForwardDynamics`;
            ``euler`` with the default ``project=True`` is the control-loop step).
        passive: Include the robot's own passive elements (``robot.passive``).
        viscous: Extra viscous damping per velocity coordinate, scalar or (nv,)
            [N m s/rad or N s/m].
        coulomb: Extra Coulomb friction per velocity coordinate, scalar or (nv,) [N m or N].
        warn_events: Warn at the first singular passage of :meth:`step` and after a
            :meth:`simulate` that had any.
        **options: Keyword arguments of :class:`solvers.ForwardDynamics` (``baumgarte``,
            ``project``, ``project_tol``, ``rtol``, ``atol``, ...).

    Raises:
        InvalidInputError: Not a robot, an unknown integrator or option, a bad value.

    Example:
        A 1 kHz loop holding the Delta's arms with a PD law (joint-side torques [N m])::

            fd = ForwardDynamics(delta, integrator="euler")
            q, v = fd.project_state(delta.q_home, np.zeros(delta.nv))
            for k in range(500):
                q, v = fd.step(k * 1e-3, q, v, 1e-3, pd)

    """

    def __init__(
        self,
        robot: Robot,
        integrator: str = "dopri5",
        *,
        passive: bool = True,
        viscous: float | Sequence[float] = 0.0,
        coulomb: float | Sequence[float] = 0.0,
        warn_events: bool = True,
        **options: Any,
    ) -> None:
        instance("robot", robot, Robot, "a Robot (pkdyn.load)")
        if not isinstance(integrator, str) or integrator not in ("dopri5", "rk4", "euler"):
            raise InvalidInputError("integrator", f"unknown {integrator!r} (dopri5, rk4 or euler)")
        forces = _passive(robot, flag("passive", passive), viscous, coulomb)
        try:
            super().__init__(
                robot.model,
                robot.constraints,
                actuation(robot),
                passive=forces,
                integrator=integrator,
                length_scale=robot.length_scale,
                **options,
            )
        except TypeError as err:  # an unknown keyword
            raise InvalidInputError("options", str(err)) from None
        except ValueError as err:
            raise InvalidInputError("options", str(err)) from None
        self.robot = robot
        self.warn_events = flag("warn_events", warn_events)
        self._warned = False
        self._user_tau: Any = None
        self._checked_tau: TorqueFn | None = None
        self._n_a = len(robot.actuators)
        g = max(float(np.linalg.norm(robot.model.gravity.linear)), 1.0)
        mass = sum(robot.model.inertias[j].mass for j in range(robot.model.njoints))
        self._energy_scale = float(mass * g * robot.length_scale)
        try:
            self.reference_rank(robot.q_home)
        except np.linalg.LinAlgError as err:  # pragma: no cover - a home that is not a state
            raise InvalidInputError("robot", f"its home is not a valid state: {err}") from None

    def _torque(self, tau: Any) -> TorqueFn | None:
        """The user's torque function, checked (its failures named), cached by identity."""
        if tau is None:
            return None
        if tau is not self._user_tau:
            callable_input("tau", tau)
            self._checked_tau = user_efforts("tau", tau, self._n_a)
            self._user_tau = tau
        return self._checked_tau

    def step(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        dt: float,
        tau: TorqueFn | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Advance a state by one step ``dt`` (:meth:`solvers.ForwardDynamics.step`).

        Args:
            t: Time [s] (a finite real number).
            q: Configuration (nq,).
            v: Velocity (nv,).
            dt: Step [s] (a finite real number > 0).
            tau: Joint-side actuator efforts ``tau(t, q, v) -> (n_a,)`` [N m or N]
                (default: none).

        Returns:
            The state ``(q, v)`` at ``t + dt``.

        Raises:
            InvalidInputError: ``t``, ``q``, ``v``, ``dt`` or ``tau`` malformed (named).
            SimulationError: The torque function failed, the state became non-finite, or the
                closures could not be restored.

        """
        if type(dt) is not float or not 0.0 < dt < math.inf:
            dt = positive("dt", dt, "s")
        if type(t) is not float or not math.isfinite(t):
            t = real("t", t, "s")
        q = _configuration(self.model, "q", q)
        v = _velocity(self.model.nv, "v", v)
        fn = self._torque(tau)
        try:
            q1, v1 = super().step(t, q, v, dt, fn)
        except IntegrationError as err:
            _finite_state(q, v)
            time = err.time if math.isfinite(err.time) else t + dt
            raise SimulationError(_untimed(str(err), time), time) from err
        except np.linalg.LinAlgError as err:
            _finite_state(q, v)
            raise SimulationError(f"the dynamics could not be solved ({err})", t) from err
        if not (np.isfinite(q1).all() and np.isfinite(v1).all()):
            _finite_state(q, v)
            raise SimulationError(
                "the state became non-finite (the step is too long for the motion, or the "
                "efforts are too large): use a shorter dt",
                t + dt,
            )
        if self.warn_events and not self._warned and self.passages.events:
            self._warned = True
            warn(singularity_warning(self.robot.name, self.passages.events, None))
        return q1, v1

    def simulate(
        self,
        q0: np.ndarray,
        v0: np.ndarray,
        duration: float,
        dt: float,
        tau: TorqueFn | None = None,
        record_every: int = 1,
        t0: float = 0.0,
        step: float | None = None,
    ) -> SimulationResult:
        """Integrate from ``(q0, v0)`` (:meth:`solvers.ForwardDynamics.simulate`).

        Args:
            q0: Initial configuration (nq,).
            v0: Initial velocity (nv,).
            duration: Simulated time [s].
            dt: Output step [s].
            tau: Joint-side actuator efforts ``tau(t, q, v) -> (n_a,)`` (default: none).
            record_every: Record one sample every that many output steps.
            t0: Initial time [s].
            step: Integration step [s] (default ``dt``).

        Returns:
            The recorded time series with the robot's names
            (:class:`~pkdyn.dynamics.simulation_result.SimulationResult`), its singular
            passages in ``events``.

        Raises:
            InvalidInputError: A malformed or out-of-range argument (named).
            SimulationError: The run could not go on (the time and the reason).

        """
        duration = positive("duration", duration, "s")
        dt = positive("dt", dt, "s")
        t0 = real("t0", t0, "s")
        record_every = count("record_every", record_every)
        if step is not None:
            step = positive("step", step, "s")
        if dt > duration:
            raise InvalidInputError(
                "dt", f"{dt:g} s is longer than the duration {duration:g} s: no step would be taken"
            )
        _check_work(self.robot, duration, dt if step is None else min(dt, step), record_every)
        q = as_configuration(self.model, "q0", q0)
        v = as_finite("v0", v0, self.model.nv)
        return self._simulate(q, v, duration, dt, self._torque(tau), record_every, t0, step)

    def _simulate(
        self,
        q: np.ndarray,
        v: np.ndarray,
        duration: float,
        dt: float,
        tau: TorqueFn | None,
        record_every: int,
        t0: float,
        step: float | None,
    ) -> SimulationResult:
        """:meth:`simulate` on checked arguments (``tau`` already wrapped)."""
        try:
            out = super().simulate(q, v, duration, dt, tau, record_every, t0, step)
        except IntegrationError as err:
            raise SimulationError(_untimed(str(err), err.time), err.time) from None
        except np.linalg.LinAlgError as err:
            raise SimulationError(f"the dynamics could not be solved ({err})", t0) from err
        out.energy_scale = self._energy_scale
        if self.warn_events and out.events:
            warn(singularity_warning(self.robot.name, out.events, out.valid_until))
        return SimulationResult.of(self.robot, out, self.integrator, dt)

    def project_state(
        self, q: np.ndarray, v: np.ndarray, tol: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Project a state onto the closures (:meth:`solvers.ForwardDynamics.project_state`).

        Raises:
            InvalidInputError: ``q``, ``v`` or ``tol`` malformed, or ``q`` too far from the
                closures to be brought onto them.

        """
        qq = as_configuration(self.model, "q", q)
        vv = as_finite("v", v, self.model.nv)
        if tol is not None:
            tol = positive("tol", tol, "m or rad")
        try:
            return super().project_state(qq, vv, tol)
        except IntegrationError as err:
            raise InvalidInputError("q", f"cannot be brought onto the closures: {err}") from None
