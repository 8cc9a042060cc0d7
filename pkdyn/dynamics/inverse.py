"""Inverse dynamics along joint trajectories, on :class:`solvers.InverseDynamics`.

Conventions: efforts ``tau`` are joint-side [N m or N] (motor side: divide by the reduction);
the platform wrench ``F`` is the one of :mod:`pkdyn.analysis.statics` (applied by the
environment on the platform, force in world axes [N], moment in platform axes [N m]); gravity
is ``model.gravity``; the robot's passive elements (``robot.passive``: springs, dampers,
friction) enter as a generalized force ``f_passive(q, v)`` beside the platform wrench's, unless
``passive=False``. The solver's failures become typed pkdyn exceptions naming the sample and
the actuator.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.dynamics.actuation import actuation
from pkdyn.dynamics.series import series_table
from pkdyn.dynamics.trajectory import JointTrajectory
from pkdyn.exceptions import InfeasibleEffortError, InvalidInputError, TrajectoryError
from pkdyn.model.arguments import public
from pkdyn.model.reuse import kept
from pkdyn.model.robot import PLATFORM_HINT, Robot
from pkdyn.progress import progress as progress_bar
from pkdyn.results import Result, jsonable
from solvers import InconsistentMotionError, InverseDynamics
from solvers import InfeasibleError as _SolverInfeasible
from solvers.minmax_effort import MinMaxInverseDynamics

__all__ = ["ALLOCATIONS", "CONSISTENCY_TOL", "EffortTrajectory", "inverse_dynamics"]

ALLOCATIONS = ("norm", "max")
"""Effort distributions under redundant actuation: least weighted norm, least largest effort."""


@dataclass(frozen=True)
class EffortTrajectory(Result):
    """Actuator efforts along a joint trajectory.

    Attributes:
        trajectory: The joint trajectory.
        actuators: Actuator (joint) names.
        tau: Joint-side efforts (N, n_a) [N m or N].
        constraint_forces: Closure forces (N, nc) [N, N m] (convention of
            :mod:`solvers.inverse_dynamics`).
        residual: Residual of the dynamics equation per sample (N,) [N m or N].
        kinetic: Kinetic energy (N,) [J].
        potential: Gravitational potential energy (N,) [J].
        elastic: Potential energy of the springs (N,) [J] (zeros without springs).
        dissipation: Power dissipated by the dampers and the friction (N,) [W] (>= 0).

    With passive elements the actuators' power balances ``d(energy)/dt + dissipation``.

    """

    trajectory: JointTrajectory
    actuators: list[str]
    tau: np.ndarray
    constraint_forces: np.ndarray
    residual: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    elastic: np.ndarray | None = None
    dissipation: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("elastic", "dissipation"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.zeros_like(self.kinetic))

    @property
    def t(self) -> np.ndarray:
        """Sample times (N,) [s]."""
        return self.trajectory.t

    @property
    def energy(self) -> np.ndarray:
        """Mechanical energy, kinetic + potential + elastic (N,) [J]."""
        assert self.elastic is not None
        return self.kinetic + self.potential + self.elastic

    def to_json(self) -> dict[str, Any]:
        """``t`` [s], ``actuators``, ``tau`` [N m or N], energies [J], ``residual``."""
        return jsonable(
            {
                "t": self.t,
                "actuators": list(self.actuators),
                "tau": self.tau,
                "kinetic": self.kinetic,
                "potential": self.potential,
                "elastic": self.elastic,
                "dissipation": self.dissipation,
                "residual": self.residual,
            }
        )

    def table(self) -> str:
        """Per actuator: its effort's range; the kinetic energy; the dynamics' residual."""
        n = list(self.actuators)
        return (
            series_table(
                f"efforts along {self.trajectory.name}",
                self.t,
                [
                    ("tau", self.tau, n, ["N m or N"] * len(n)),
                    ("energy", self.kinetic[:, None], ["kinetic"], ["J"]),
                ],
            )
            + f"\nlargest residual of the dynamics: {float(np.max(self.residual)):.2g} N m or N"
        )

    @property
    def power(self) -> np.ndarray:
        """Actuator powers ``tau * qd`` (N, n_a) [W]."""
        return self.tau * self.trajectory.qa_dot


def _wrench_series(robot: Robot, wrench: Any, n: int) -> np.ndarray | None:
    if wrench is None:
        return None
    from pkdyn.inputs import matrix, vector

    W = vector("wrench", wrench, 6) if np.ndim(_probe(wrench)) <= 1 else matrix("wrench", wrench)
    if W.shape == (6,):
        W = np.broadcast_to(W, (n, 6))
    if W.shape != (n, 6) or not np.all(np.isfinite(W)):
        raise InvalidInputError("wrench", f"expected 6 finite values or ({n}, 6), got {W.shape}")
    if robot.platform_frame is None:
        raise InvalidInputError(
            "wrench", f"{robot.name} declares no platform to apply it to; {PLATFORM_HINT}"
        )
    return W


def _probe(x: Any) -> Any:
    """``x`` as an array for its number of dimensions (a scalar when it cannot be one)."""
    try:
        return np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        return 0.0


CONSISTENCY_TOL = 1e-7
"""Largest closure error of a trajectory sample accepted by the inverse dynamics, relative to
``max(1, |v|)`` for velocities and ``max(1, |a|)`` for accelerations [m, m/s, m/s^2]."""

_CHUNK = 2048
"""Samples per call of the solver (one step of the progress bar)."""


def _solver(
    robot: Robot,
    allocation: str,
    lower: np.ndarray | None,
    upper: np.ndarray | None,
    weights: Sequence[float] | np.ndarray | None,
) -> InverseDynamics:
    """The robot's inverse-dynamics solver for these options, made once (:mod:`pkdyn.model.reuse`).

    Its Pinocchio datas and kinematic buffers (nv^3 in size) are made on the first call on the
    robot only; :meth:`solvers.InverseDynamics.reset` makes each call start as a new solver's.
    """
    cls = MinMaxInverseDynamics if allocation == "max" else InverseDynamics

    def key(x: Any) -> bytes | None:
        return None if x is None else np.asarray(x, dtype=float).tobytes()

    model, constraints, act = robot.model, robot.constraints, actuation(robot)

    def make() -> InverseDynamics:
        return cls(model, constraints, act, lower=lower, upper=upper, weights=weights)

    solver = kept(
        robot, ("inverse_dynamics", cls.__name__, key(lower), key(upper), key(weights)), make
    )
    solver.reset()
    return solver


@public
def inverse_dynamics(
    robot: Robot,
    trajectory: JointTrajectory,
    wrench: Sequence[float] | np.ndarray | None = None,
    limits: bool = False,
    weights: Sequence[float] | np.ndarray | None = None,
    progress: bool | None = None,
    passive: bool = True,
    allocation: str = "norm",
) -> EffortTrajectory:
    """Actuator efforts (and closure forces) realising a trajectory, with gravity.

    Non-redundant actuation gives the unique efforts; redundant actuation the efforts of least
    weighted norm (proxsuite QP, warm-started along the trajectory), or with ``allocation="max"``
    those of least largest scaled effort ``max |tau_i| sqrt(w_i)``
    (:class:`solvers.minmax_effort.MinMaxInverseDynamics`), within the effort limits when
    ``limits`` is set.

    Args:
        robot: The robot (add a payload with :func:`with_payload`).
        trajectory: Joint trajectory consistent with the closures
            (:func:`pkdyn.dynamics.trajectory.map_task_trajectory`).
        wrench: Wrench on the platform, (6,) constant or (N, 6) per sample [N, N m]
            (convention of :mod:`pkdyn.analysis.statics`); e.g. a machining force.
        limits: Bound the efforts by the actuators' effort limits (URDF ``effort``).
        weights: Effort weights for redundant actuation (default ``1 / effort_limit^2`` when
            limits are finite, else ones).
        progress: Progress bar: ``True`` / ``False`` force it on / off, ``None`` (default) shows
            it when stderr is a terminal and there are more than 2048 samples (the samples go
            to the solver by chunks of 2048).
        passive: Include the robot's springs, dampers and friction (``robot.passive``).
        allocation: Redundant actuation: ``"norm"`` (least weighted norm) or ``"max"`` (least
            largest effort relative to its limit, with the default weights).

    Returns:
        Efforts, closure forces, residuals and energies per sample.

    Raises:
        InfeasibleEffortError: No efforts within the limits realise a sample (names the sample
            and the actuator), or the motion is not dynamically consistent there.
        TrajectoryError: The trajectory does not belong to this robot, is not finite, or does
            not satisfy the closures (position, velocity or acceleration, :data:`CONSISTENCY_TOL`).

    """
    from pkdyn.inputs import instance, vector

    traj = instance("trajectory", trajectory, JointTrajectory, "a JointTrajectory")
    if weights is not None:
        weights = vector("weights", weights, len(robot.actuators))
        if np.any(weights <= 0.0):
            raise InvalidInputError("weights", f"must be > 0, got {weights.tolist()}")
    N = traj.t.size
    if traj.q.shape != (N, robot.nq) or traj.v.shape != (N, robot.nv):
        raise TrajectoryError(
            f"trajectory of shape q {traj.q.shape}, v {traj.v.shape} does not fit {robot.name} "
            f"(nq = {robot.nq}, nv = {robot.nv})"
        )
    for what, arr in (("q", traj.q), ("v", traj.v), ("a", traj.a)):
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        if bad.size:
            k = int(bad[0])
            raise TrajectoryError(f"{what} is not finite", sample=k, time=float(traj.t[k]))
    W = _wrench_series(robot, wrench, N)
    if allocation not in ALLOCATIONS:
        raise InvalidInputError(
            "allocation", f"expected one of {', '.join(ALLOCATIONS)}, got {allocation!r}"
        )
    effort = np.array([a.effort for a in robot.actuators])
    lower = -effort if limits else None
    upper = effort if limits else None
    if weights is None and np.all(np.isfinite(effort)) and np.all(effort > 0.0):
        weights = 1.0 / effort**2
    if not robot.actuators:
        raise InvalidInputError(
            "robot", f"{robot.name} has no actuators: inverse dynamics gives actuator efforts"
        )
    solver = _solver(robot, allocation, lower, upper, weights)
    elements = robot.passive if passive else None
    F_passive = None if elements is None else elements.forces(traj.q, traj.v)  # vectorised
    frame = robot.platform_frame
    parts = []
    starts = range(0, N, _CHUNK)
    try:  # (a bar from two chunks on, when stderr is a terminal unless forced)
        for s in progress_bar(starts, "inverse dynamics", "chunk", progress, min_items=2):
            e = min(N, s + _CHUNK)
            parts.append(
                solver.trajectory(
                    traj.q[s:e],
                    traj.v[s:e],
                    traj.a[s:e],
                    None if F_passive is None else F_passive[s:e],
                    wrench=None if W is None or frame is None else (frame, W[s:e]),
                    check_tol=CONSISTENCY_TOL,
                    first_sample=s,
                )
            )
    except InconsistentMotionError as err:
        raise TrajectoryError(
            f"the {err.what} does not satisfy closure '{err.closure}' (error {err.error:.3g}); "
            "map task trajectories with pkdyn.dynamics.trajectory.map_task_trajectory",
            sample=err.sample,
            time=float(traj.t[err.sample]),
        ) from None
    except _SolverInfeasible as err:
        k = int(err.sample) if err.sample is not None else 0
        raise InfeasibleEffortError(
            f"t = {traj.t[k]:.6g} s: {err}", sample=k, actuator=err.name
        ) from None
    elastic = dissipation = None
    if elements is not None:
        elastic = elements.potentials(traj.q)
        dissipation = elements.dissipations(traj.v)
    return EffortTrajectory(
        traj,
        robot.actuator_names,
        np.concatenate([p.tau for p in parts]),
        np.concatenate([p.constraint_forces for p in parts]),
        np.concatenate([p.residual for p in parts]),
        np.concatenate([p.kinetic for p in parts]),
        np.concatenate([p.potential for p in parts]),
        elastic,
        dissipation,
    )
