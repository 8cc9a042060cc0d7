"""Statics of any loaded robot: actuator efforts, transmitted wrenches, closure reactions.

Conventions (power conjugates of :mod:`pkdyn.analysis.kinematics`' velocities):

- ``F`` is the wrench the **environment applies to the platform** at the platform frame origin:
  force in world axes [N], moment in platform axes [N m], restricted to the task components
  (``m`` values) or given in full (6 values: ``fx fy fz mx my mz``).
- ``tau`` are the joint-side actuator efforts [N m or N], positive along the actuated joint
  coordinate, that **hold the platform in equilibrium** against ``F``. Virtual work on every
  motion compatible with the closures: ``tau . dq_a + F . dx = 0``, hence
  ``tau = -J^T F`` (seed 001: ``tau = J^T f`` with ``f = -F`` the wrench the robot applies).
- The wrench the actuators produce (applied by the platform on the environment) when they exert
  ``tau`` is ``w = J^-T tau`` (:func:`platform_wrench`); holding ``F`` means ``w = -F``.

Full equilibrium with closure reactions (:func:`static_equilibrium`): on the spanning tree,
``S^T tau + Jc^T lambda + J6^T F = g(q)``, with ``S`` the actuator selection, ``Jc`` the closure
Jacobian, ``J6`` the 6D platform Jacobian and ``g`` the generalised gravity (optional), plus the
springs' generalized force ``f_s(q)`` on the left when the robot has springs (``robot.passive``;
dampers and friction vanish at rest: the smooth friction model holds nothing), solved in
the least-squares sense (minimum norm in ``lambda`` when closure equations are redundant, e.g.
an over-constrained loop). ``lambda`` holds the multipliers of the constraint rows
(``robot.constraints``), with the sign of the residual conventions of :mod:`solvers.closure`:
for the point rows of a closure (residual ``p1 - p2``), the force [N] body 2 exerts on body 1 at
the contact point, world axes; for a 6D weld (residual ``log6(oMc1^-1 oMc2)``), the wrench
[N, N m] body 1 exerts on body 2, in the contact frame; then the couplings' generalized forces.
:func:`closure_reactions` turns them into one force and one moment per closure.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.analysis.kinematics import SINGULAR_TOL, NearSingularityWarning, kinematic_models
from pkdyn.exceptions import InvalidInputError, SingularConfigurationError
from pkdyn.model.arguments import public
from pkdyn.model.description import LinearCouplingSpec
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.results import Result, jsonable
from pkdyn.units import quantity, vector
from solvers import numerics

__all__ = [
    "Reaction",
    "StaticsResult",
    "closure_reactions",
    "actuator_efforts",
    "platform_wrench",
    "static_equilibrium",
    "statics_json",
]

EQUILIBRIUM_TOL = 1e-8
"""Relative residual of the equilibrium above which no static solution exists."""


def _wrench6(robot: Robot, F: Sequence[float] | np.ndarray | None) -> np.ndarray:
    out = np.zeros(6)
    if F is None:
        return out
    arr = as_finite("F", F)
    rows = np.asarray(robot.task_rows, dtype=int)
    if arr.size == 6:
        return arr
    if arr.size != rows.size:
        raise InvalidInputError(
            "F", f"expected {rows.size} task components or 6 values, got {arr.size}"
        )
    out[rows] = arr
    return out


def actuator_efforts(
    robot: Robot, q: Sequence[float] | np.ndarray, F: Sequence[float] | np.ndarray
) -> np.ndarray:
    """Actuator efforts holding the platform against an external wrench: ``tau = -J^T F``.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        F: Wrench on the platform, task components (m,) [N, N m].

    Returns:
        ``tau`` (n_a,) [N m or N], joint side.

    Raises:
        SingularConfigurationError: Parallel singularity (``J`` does not exist).

    """
    km = kinematic_models(robot, q)
    return -km.J.T @ as_finite("F", F, km.m)


def platform_wrench(
    robot: Robot, q: Sequence[float] | np.ndarray, tau: Sequence[float] | np.ndarray
) -> np.ndarray:
    """Wrench the actuators produce on the environment through the platform: ``J^-T tau``.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        tau: Actuator efforts (n_a,) [N m or N].

    Returns:
        ``w`` (m,) task components [N, N m], with ``w . x_dot = tau . qa_dot``.

    Raises:
        SingularConfigurationError: Serial singularity (``J_inv`` does not exist).

    """
    km = kinematic_models(robot, q)
    return km.J_inv.T @ as_finite("tau", tau, km.n_a)


@dataclass(frozen=True)
class Reaction(Result):
    """The reaction of one closure: one force and one moment.

    What the closure's second body (its ``frame2`` link) exerts on the first, world axes, the
    moment about the closure point (``frame1``'s origin). A ``point`` closure carries no moment;
    a ``hinge`` a moment normal to its axis; a ``weld`` both
    (:meth:`solvers.ConstraintSet.reactions`).

    Attributes:
        force: Force (3,) [N].
        moment: Moment (3,) [N m] about ``point``.
        point: The closure point (3,) [m], world frame.

    """

    force: np.ndarray
    moment: np.ndarray
    point: np.ndarray

    def to_json(self) -> dict[str, Any]:
        """``{"force", "moment", "point"}`` as lists [N, N m, m]."""
        return jsonable({"force": self.force, "moment": self.moment, "point": self.point})

    def table(self) -> str:
        """Force, moment and the point it is taken about."""
        return (
            f"force {vector(self.force, 'N', roundoff=1e-12)}, moment "
            f"{vector(self.moment, 'N m', roundoff=1e-12)} about "
            f"{vector(self.point, 'm', roundoff=1e-12)} (on its first body, world axes)"
        )


def closure_reactions(robot: Robot, q: np.ndarray, lambdas: np.ndarray) -> dict[str, Reaction]:
    """One force and one moment per closure from the constraint forces (see :class:`Reaction`).

    Args:
        robot: The robot.
        q: Configuration (nq,).
        lambdas: Constraint forces (n,) in the convention of the module docstring (the
            couplings' rows, if any, are not closures: left out).

    Returns:
        ``{closure name: Reaction}``, in the description's order.

    """
    cs = robot.constraints
    out = cs.reactions(robot.model.createData(), q, np.asarray(lambdas, dtype=float))
    return {name: Reaction(f, m, p) for name, (f, m, p) in out.items()}


@dataclass
class StaticsResult(Result):
    """Static equilibrium of the whole mechanism.

    Attributes:
        tau: Actuator efforts (n_a,) [N m or N].
        lambdas: Constraint forces (n,) [N, N m] (convention in the module docstring).
        reactions: One force and one moment per closure, by closure name (:class:`Reaction`).
        residual: Norm of the unbalanced generalised force [N m or N] (round-off when the
            equilibrium exists).
        couplings: The force of each joint coupling (:mod:`solvers.coupling`), by coupling
            name: the generalized force [N m or N] it applies to its driven joint (the source
            receives ``-p'`` times it, ``p'`` the law's derivative).
        actuators: Actuator names, in order.
        units: Unit of each actuator effort (``N m`` or ``N``).
        linear_couplings: Names of the linear couplings (their force acts on each joint times
            its coefficient; the others' on their driven joint).

    """

    tau: np.ndarray
    lambdas: np.ndarray
    reactions: dict[str, Reaction]
    residual: float
    couplings: dict[str, float] = field(default_factory=dict)
    actuators: tuple[str, ...] = ()
    units: tuple[str, ...] = ()
    linear_couplings: tuple[str, ...] = ()

    def to_json(self) -> dict[str, Any]:
        """``tau`` [N m or N], ``actuators``, ``reactions``, ``couplings``, ``residual``."""
        return jsonable(
            {
                "tau": self.tau,
                "actuators": list(self.actuators),
                "reactions": {k: v.to_json() for k, v in self.reactions.items()},
                "couplings": dict(self.couplings),
                "residual": self.residual,
            }
        )

    def table(self) -> str:
        """One line per actuator effort, per closure reaction and per coupling force."""
        names = self.actuators or tuple(f"actuator {k + 1}" for k in range(self.tau.size))
        units = self.units or ("N m or N",) * self.tau.size
        lines = [f"{n}: {quantity(t, u)}" for n, t, u in zip(names, self.tau, units, strict=True)]
        lines += [f"closure {k}: {r.table()}" for k, r in self.reactions.items()]
        for k, f in self.couplings.items():
            on = (
                "each joint times its coefficient"
                if k in self.linear_couplings
                else ("on its driven joint")
            )
            lines.append(f"coupling {k}: {quantity(f)} N m or N ({on})")
        return "\n".join(lines)


@public
def static_equilibrium(
    robot: Robot,
    q: Sequence[float] | np.ndarray,
    F: Sequence[float] | np.ndarray | None = None,
    gravity: bool = False,
    passive: bool = True,
) -> StaticsResult:
    """Actuator efforts and closure reactions balancing an external wrench (and gravity).

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        F: Wrench on the platform (task components or all 6) [N, N m]; ``None``: zero.
        gravity: Also balance the robot's weight (``model.gravity``).
        passive: Include the robot's springs (joint and two-frame springs).

    Returns:
        The efforts and reactions.

    Raises:
        SingularConfigurationError: The load cannot be balanced (parallel singularity with a
            load along the uncontrollable direction) or the efforts are not unique.

    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearSingularityWarning)
        km = kinematic_models(robot, q)
    model, data = robot.model, robot.data
    F6 = _wrench6(robot, F)
    nv, n_a = robot.nv, km.n_a
    S_T = np.zeros((nv, n_a))
    S_T[km.actuated_v, np.arange(n_a)] = 1.0
    K = np.hstack([S_T, km.Jc.T])
    with np.errstate(over="ignore", invalid="ignore"):
        rhs = -km.J6.T @ F6
        if gravity:
            rhs += pin.computeGeneralizedGravity(model, data, km.q)
        if passive and robot.passive is not None:
            rhs -= robot.passive.conservative_force(km.q)
        sol = numerics.lstsq(K, rhs, 1e-12) if np.all(np.isfinite(rhs)) else rhs
        residual = float(np.linalg.norm(K @ sol - rhs)) if sol.shape == (K.shape[1],) else 0.0
    if not (np.all(np.isfinite(sol)) and np.isfinite(residual)):
        raise InvalidInputError(
            "F",
            f"wrench {np.array2string(F6, precision=3)} [N, N m] overflows the computation "
            f"(largest component {float(np.max(np.abs(F6))):.3g}): the efforts are not finite "
            "numbers; give a physical load",
        )
    scale = max(float(np.linalg.norm(rhs)), 1e-300)
    if residual > EQUILIBRIUM_TOL * scale + 1e-12:
        raise SingularConfigurationError(
            "parallel",
            f"{robot.name}: no static equilibrium: the load has a component along an "
            f"uncontrollable platform motion (unbalanced {residual:.3g})",
        )
    if km.margin_A < SINGULAR_TOL:
        raise SingularConfigurationError(
            "parallel",
            f"{robot.name}: parallel singularity: actuator efforts are not unique here",
        )
    tau, lam = sol[:n_a], sol[n_a:]
    couplings = robot.constraints.coupling_forces(lam)
    linear = tuple(c.name for c in robot.couplings if isinstance(c, LinearCouplingSpec))
    return StaticsResult(
        tau,
        lam,
        closure_reactions(robot, km.q, lam),
        residual,
        couplings,
        actuators=tuple(robot.actuator_names),
        units=tuple("N" if p else "N m" for p in robot.actuator_prismatic),
        linear_couplings=linear,
    )


def statics_json(
    robot: Robot,
    q: Sequence[float] | np.ndarray,
    F: Sequence[float] | np.ndarray | None = None,
    gravity: bool = False,
) -> dict[str, Any]:
    """JSON-ready statics for the CLI.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        F: Wrench on the platform (task components or 6 values) [N, N m].
        gravity: Include the robot's weight.

    Returns:
        ``{"tau", "actuators", "reactions", "couplings", "residual"}``.

    """
    return static_equilibrium(robot, q, F, gravity).to_json()
