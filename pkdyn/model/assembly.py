"""Assembly and geometric models of any loaded robot, by the general numeric path.

- :func:`project`: the assembled configuration nearest (minimum-norm steps) to a guess;
- :func:`forward_geometry` (direct geometric model): actuated coordinates -> full configuration
  and platform pose, in the assembly mode reached from the initial guess;
- :func:`assembly_modes`: the assembly modes found from many initial guesses;
- :func:`inverse_geometry` (inverse geometric model): platform pose -> actuated coordinates.

The closure equations and the platform pose equations are solved together by
:func:`solvers.solve_lm`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import (
    AssemblyError,
    InvalidInputError,
    JointLimitError,
    UnreachablePoseError,
)
from pkdyn.model.arguments import public
from pkdyn.model.families import FAMILIES, Family
from pkdyn.model.pose import as_finite, pose_from_vector, pose_to_vector
from pkdyn.model.robot import PLATFORM_HINT, Robot
from pkdyn.results import Result, jsonable
from pkdyn.units import quantity, vector
from solvers import FramePoseTask, SolveResult, solve_lm

__all__ = [
    "DEFAULT_TOL",
    "GeometryResult",
    "project",
    "forward_geometry",
    "assembly_modes",
    "inverse_geometry",
    "closure_residual",
    "coupling_residual",
    "solve_pose",
]

DEFAULT_TOL = 1e-12
"""Convergence threshold on the largest closure / pose residual component [m or rad]."""

_LOCAL_TOL = 1.0
"""The solvers work on the contact-frame closure residual (:meth:`solvers.ConstraintSet.
local_residual`, the world one rotated: same norm per closure); ``tol`` applies to its
components."""


@dataclass
class GeometryResult(Result):
    """A solved geometric model.

    Attributes:
        q: Full assembled configuration (nq,).
        qa: Actuated coordinates in actuator order [rad or m].
        placement: Platform placement (``None`` if the robot has no platform).
        residual: Largest closure residual component after the solve [m or rad] (in the
            contact frames the solver works in: the world residual rotated).
        iterations: Solver iterations.
        actuators: Actuator names, in order (for the table).
        units: Unit of each actuator coordinate (``rad`` or ``m``).
        readings: What the actuators' encoders read (``qa / <pkdyn:encoder gain>``), when a
            gain is not 1 (a calibrated robot), else ``None``.

    """

    q: np.ndarray
    qa: np.ndarray
    placement: pin.SE3 | None
    residual: float
    iterations: int
    actuators: tuple[str, ...] = ()
    units: tuple[str, ...] = ()
    readings: np.ndarray | None = None

    def to_json(self) -> dict[str, Any]:
        """The result as JSON values.

        Returns:
            ``position`` [m], ``rpy`` [rad] (``None`` without a platform), ``qa``, ``q``,
            ``actuators``, ``residual`` [m or rad], and ``readings`` on a calibrated robot.

        """
        out: dict[str, Any] = {
            "position": None if self.placement is None else self.position,
            "rpy": None if self.placement is None else self.rpy,
            "q": self.q,
            "qa": self.qa,
            "actuators": list(self.actuators),
            "residual": self.residual,
        }
        if self.readings is not None:
            out["readings"] = self.readings
        return jsonable(out)

    def table(self) -> str:
        """The platform pose (when there is a platform) and each actuator coordinate."""
        lines = []
        if self.placement is not None:
            lines.append(f"position: {vector(self.position, 'm', roundoff=1e-12)}")
            lines.append(f"rpy:      {vector(self.rpy, 'rad', roundoff=1e-12)}")
        names = self.actuators or tuple(f"actuator {k + 1}" for k in range(self.qa.size))
        units = self.units or ("",) * self.qa.size
        width = max((len(n) for n in names), default=0)
        lines += [
            f"{n + ':':<{width + 1}} {quantity(v, u, 9)}"
            for n, v, u in zip(names, self.qa, units, strict=True)
        ]
        if self.readings is not None:
            lines.append("encoder readings (joint coordinate / <pkdyn:encoder gain>):")
            lines += [
                f"  {n + ':':<{width + 1}} {quantity(v, u, 9)}"
                for n, v, u in zip(names, self.readings, units, strict=True)
            ]
        lines.append(f"closure residual: {self.residual:.2g} (m or rad)")
        return "\n".join(lines)

    @property
    def position(self) -> np.ndarray:
        """Platform position [m]."""
        assert self.placement is not None
        return pose_to_vector(self.placement)[0]

    @property
    def rpy(self) -> np.ndarray:
        """Platform roll, pitch, yaw [rad]."""
        assert self.placement is not None
        return pose_to_vector(self.placement)[1]


@public
def closure_residual(robot: Robot, q: np.ndarray) -> float:
    """Largest absolute closure residual component at ``q`` [m or rad] (0 without loops).

    The closures only: :func:`coupling_residual` gives the couplings'.
    """
    cs = robot.constraints.closures
    if cs.n == 0:
        return 0.0
    return float(np.max(np.abs(cs.residual(robot.data, q))))


def coupling_residual(robot: Robot, q: np.ndarray) -> float:
    """Largest absolute joint-coupling residual at ``q`` [rad or m] (0 without couplings)."""
    cs = robot.constraints.couplings
    if cs.n == 0:
        return 0.0
    return float(np.max(np.abs(cs.residual(robot.data, q))))


def _solve_closures(
    robot: Robot, q0: np.ndarray, free: np.ndarray | None, tol: float
) -> SolveResult:
    cs, data = robot.constraints, robot.data
    return solve_lm(
        robot.model,
        q0,
        partial(cs.local_residual, data),  # contact-frame residual: one copy per closure
        partial(cs.local_jacobian_after_residual, data),  # where the residual just was
        free=free,
        tol=tol * _LOCAL_TOL,
    )


def _worst(robot: Robot, q: np.ndarray) -> tuple[str, float]:
    cs = robot.constraints
    if cs.n == 0:
        return "-", 0.0
    per = cs.split(cs.residual(robot.data, q))
    name = max(per, key=lambda k: per[k])
    return name, per[name]


def _result(robot: Robot, sol: SolveResult, closure_error: float) -> GeometryResult:
    """The result of a converged solve.

    The robot data holds the kinematics of ``sol.q``: the solver's last evaluation was there.
    """
    placement = None
    if robot.platform_frame is not None:
        placement = pin.SE3(pin.updateFramePlacement(robot.model, robot.data, robot.platform_frame))
    qa = sol.q[robot.actuated_q]
    calibrated = bool(
        np.any(robot.encoder_gains != 1.0) or np.any(robot.encoder_offsets != 0.0)
    )  # readings differ from joint coordinates (Robot.readings: gains and offsets)
    return GeometryResult(
        sol.q,
        qa,
        placement,
        closure_error,
        sol.iterations,
        actuators=tuple(robot.actuator_names),
        units=tuple("m" if p else "rad" for p in robot.actuator_prismatic),
        readings=robot.readings(qa) if calibrated else None,
    )


def _miss(robot: Robot, q: np.ndarray, target: pin.SE3) -> str:
    """How far the platform at ``q`` is from ``target``: distance, and angle if controlled."""
    pin.framesForwardKinematics(robot.model, robot.data, q)
    assert robot.platform_frame is not None
    at = robot.data.oMf[robot.platform_frame]
    text = quantity(float(np.linalg.norm(at.translation - target.translation)), "m")
    if np.any(np.asarray(robot.task_rows) >= 3):
        angle = float(np.linalg.norm(pin.log3(target.rotation.T @ at.rotation)))
        text += f" and {quantity(angle, 'rad')}"
    return text


def _family_of(robot: Robot) -> Family | None:
    """The library family of a robot (:attr:`Robot.family`), or ``None``."""
    name = robot.family
    return None if name is None else FAMILIES[name]


def _seeded(
    robot: Robot, q0: np.ndarray, position: np.ndarray, tol: float, fam: Family | None = None
) -> np.ndarray | None:
    """``q0`` moved onto the closures with the platform at ``position``, actuators fixed.

    The closed forms of a family give the platform position of the assembly (or working) mode
    of its home; imposing it while the passive joints settle keeps the solution in that mode,
    where a plain solve from ``q_home`` may land in another one (the Delta's nacelle above the
    base).
    """
    if robot.platform_frame is None or not np.all(np.isfinite(position)):
        return None
    rows = np.array([r for r in robot.task_rows if r < 3] or [0, 1, 2], dtype=int)
    task = FramePoseTask(robot.model, robot.platform_frame, rows)
    task.target = pin.SE3(np.eye(3), np.asarray(position, dtype=float))
    cs, data = robot.constraints, robot.data

    def residual(q: np.ndarray) -> np.ndarray:
        return np.concatenate([cs.residual(data, q), task.residual(data)])

    def jacobian(q: np.ndarray) -> np.ndarray:
        _, J = cs.residual_and_jacobian(data, q)
        return np.vstack([J, task.residual_and_jacobian(data)[1]])

    if fam is not None:  # a configuration the family builds (exact at folds), if it can
        built = fam.configuration(robot, q0[robot.actuated_q], position)
        q0 = q0 if built is None else built
    sol = solve_lm(robot.model, q0, residual, jacobian, free=robot.passive_v, tol=tol)
    return sol.q if sol.converged else None


@public
def project(robot: Robot, q: np.ndarray, tol: float = DEFAULT_TOL) -> np.ndarray:
    """Assembled configuration near ``q``: minimum-norm Gauss-Newton steps onto the closures.

    Args:
        robot: The robot.
        q: Guess (nq,), need not satisfy the closures.
        tol: Residual threshold [m or rad].

    Returns:
        An assembled configuration (nq,).

    Raises:
        InvalidInputError: ``q`` has the wrong size or non-finite values.
        AssemblyError: The closures cannot be satisfied from this guess.

    """
    q = as_finite("q", q, robot.nq)
    if robot.constraints.n == 0:
        return q
    sol = _solve_closures(robot, q, None, tol)
    if not sol.converged:
        name, res = _worst(robot, sol.q)
        raise AssemblyError(
            name,
            res,
            f"{robot.name}: cannot assemble: closure '{name}' keeps a residual of {res:.3g} "
            "(check the geometry: link lengths, closure frames)",
        )
    return sol.q


@public
def forward_geometry(
    robot: Robot,
    qa: Sequence[float] | np.ndarray,
    q_init: np.ndarray | None = None,
    tol: float = DEFAULT_TOL,
    check_limits: bool = True,
    keep_mode: bool = True,
) -> GeometryResult:
    """Direct geometric model: full configuration and platform pose from actuated coordinates.

    The result is in the assembly mode of ``q_init`` (default ``robot.q_home``): for a library
    family with a closed-form direct model (Delta: always the nacelle below the base;
    five-bar) the closed form of that mode seeds the solve; otherwise the actuators move from
    ``q_init``'s values to ``qa`` in steps (:data:`CONTINUATION_STEP`), each solved from the
    previous one. See :func:`assembly_modes` to enumerate the modes.

    Args:
        robot: The robot.
        qa: Actuated coordinates in actuator order [rad or m].
        q_init: Initial configuration (nq,), e.g. the previous solution (warm start).
        tol: Residual threshold [m or rad].
        check_limits: Raise if an actuated coordinate is outside its limits.
        keep_mode: Stay in the assembly mode of ``q_init`` (``False``: a plain solve from
            ``q_init``, wherever it leads; :func:`assembly_modes` explores that way).

    Returns:
        The solved configuration and platform placement.

    Raises:
        InvalidInputError: Wrong number of values or non-finite values.
        JointLimitError: An actuated coordinate is outside its limits.
        AssemblyError: The mechanism cannot be assembled with these actuator values.

    """
    qa = as_finite("actuated coordinates", qa, len(robot.actuators))
    start = robot.q_home if q_init is None else as_finite("q_init", q_init, robot.nq)
    _refuse_far_actuators(robot, start, qa)
    q0 = start.copy()
    q0[robot.actuated_q] = qa
    if check_limits:
        iq = robot.actuated_q
        lo, hi = robot.model.lowerPositionLimit[iq], robot.model.upperPositionLimit[iq]
        if not ((qa >= lo - 1e-12) & (qa <= hi + 1e-12)).all():
            check_actuator_limits(robot, q0)  # raises, naming the actuator
    fam = _family_of(robot) if keep_mode else None
    seeded = None
    if fam is not None and fam.has_forward_position:  # the start's mode, from the closed form
        reference = None
        if q_init is not None and robot.platform_frame is not None:
            reference = (start[robot.actuated_q], robot.platform_placement(start).translation)
        x = fam.forward_position(robot.params, qa, reference)
        seeded = None if x is None else _seeded(robot, q0, x, tol, fam)
    if (  # the assembly mode of the start, by continuation when the actuators move far
        seeded is None and keep_mode and _moves_far(robot, start[robot.actuated_q], qa)
    ):
        seeded = _fk_continuation(robot, start, qa, tol)
    q0 = q0 if seeded is None else seeded
    sol = _solve_closures(robot, q0, robot.passive_v, tol)
    if not sol.converged:
        name, res = _worst(robot, sol.q)
        raise AssemblyError(
            name,
            res,
            f"{robot.name}: actuator values {np.array2string(qa, precision=6)} cannot be "
            f"assembled: closure '{name}' keeps a residual of {res:.3g}",
        )
    return _result(robot, sol, sol.error)


MAX_STARTS = 10_000
"""Most random starts of :func:`assembly_modes` (each a direct geometric model, ~1 ms)."""


@public
def assembly_modes(
    robot: Robot,
    qa: Sequence[float] | np.ndarray,
    starts: int = 64,
    seed: int = 0,
    spread: float = 1.5,
) -> list[GeometryResult]:
    """Enumerate assembly modes (direct geometric model solutions) from random guesses.

    Args:
        robot: The robot.
        qa: Actuated coordinates [rad or m].
        starts: Number of random initial guesses (at most :data:`MAX_STARTS`).
        seed: Random seed.
        spread: Amplitude of the random passive perturbation [rad or m].

    Returns:
        Distinct solutions, sorted by platform height then position (first: the home-like one).

    """
    from pkdyn.inputs import count, positive
    from pkdyn.inputs import seed as seed_

    qa = as_finite("actuated coordinates", qa, len(robot.actuators))
    starts = count("starts", starts, 1, MAX_STARTS)
    rng = np.random.default_rng(seed_("seed", seed))
    spread = positive("spread", spread, "rad or m")
    found: list[GeometryResult] = []
    for k in range(starts):
        dv = np.zeros(robot.nv)
        if k:
            dv[robot.passive_v] = rng.uniform(-spread, spread, robot.passive_v.size)
        q0 = pin.integrate(robot.model, robot.q_home, dv)
        try:
            res = forward_geometry(robot, qa, q0, check_limits=False, keep_mode=False)
        except AssemblyError:
            continue
        key = res.placement.translation if res.placement is not None else res.q
        if not any(
            np.linalg.norm((f.placement.translation if f.placement is not None else f.q) - key)
            < 1e-6
            for f in found
        ):
            found.append(res)
    return found


@public
def inverse_geometry(
    robot: Robot,
    pose: Sequence[float] | np.ndarray | pin.SE3,
    q_init: np.ndarray | None = None,
    tol: float = DEFAULT_TOL,
    check_limits: bool = True,
) -> GeometryResult:
    """Inverse geometric model: actuated coordinates that put the platform at ``pose``.

    Only the pose components the robot controls (its ``task``) are imposed; uncontrolled
    components given as numbers must be those the robot reaches (a Delta cannot yaw), else
    :class:`UnreachablePoseError` names them. Without ``q_init``,
    a library robot with a closed-form inverse model is solved in the working mode of its
    home (the Delta's elbows out), other robots start from ``q_home``.

    Args:
        robot: The robot.
        pose: ``[x, y, z]`` or ``[x, y, z, roll, pitch, yaw]`` [m, rad], a placement, or
            only the controlled components in that order when they are neither 3 nor 6 (a
            five-bar: ``[x, y]``).
        q_init: Initial configuration (nq,) (default ``robot.q_home``).
        tol: Residual threshold [m or rad].
        check_limits: Raise if an actuator ends outside its limits.

    Returns:
        The solved configuration; ``qa`` holds the actuated coordinates.

    Raises:
        InvalidInputError: Malformed pose.
        UnreachablePoseError: No assembled configuration reaches the pose.
        JointLimitError: The pose needs an actuator outside its limits.

    """
    if robot.platform_frame is None:
        raise UnreachablePoseError(
            "-", 0.0, f"{robot.name} declares no platform frame; {PLATFORM_HINT}"
        )
    partial = _partial_pose(robot, pose)
    target = pose_from_vector(pose if partial is None else partial)
    task = FramePoseTask(robot.model, robot.platform_frame, robot.task_rows)
    task.target = target
    q0 = robot.q_home if q_init is None else as_finite("q_init", q_init, robot.nq)
    _refuse_far_pose(robot, q0, target)
    fam = _family_of(robot) if q_init is None else None
    seeded = None
    if fam is not None:  # the family's working mode, from its closed form
        qa = fam.inverse_actuators(robot.params, target)
        if qa is not None:
            guess = np.array(q0)
            guess[robot.actuated_q] = qa
            seeded = _seeded(robot, guess, target.translation, tol, fam)
    if seeded is None:  # the working mode of the start, followed by continuation
        seeded = _ik_continuation(robot, q0, target, tol)
    q0 = q0 if seeded is None else seeded
    cs = robot.constraints
    sol = solve_pose(robot, task, q0, tol)
    if not sol.converged:
        pos, rpy = pose_to_vector(target)
        name, res = _worst(robot, sol.q)
        raise UnreachablePoseError(
            name,
            res,
            f"{robot.name}: pose {vector(pos, 'm')}, rpy {vector(rpy, 'rad')} is out of reach "
            f"(the closest configuration misses it by {_miss(robot, sol.q, target)}; closure "
            f"'{name}' residual {res:.3g} m or rad)",
        )
    if partial is None:  # (a partial pose gives no uncontrolled component)
        _check_uncontrolled(robot, pose, target, sol.q)
    if check_limits:
        check_actuator_limits(robot, sol.q)
    return _result(robot, sol, float(np.max(np.abs(sol.residual[: cs.n_local]), initial=0.0)))


FAR = 100.0
"""Farthest a requested pose may lie from the platform's start (in robot sizes), or actuator
values from the start's (in actuator scales: rad, or robot sizes for prismatic actuators),
before they are refused as out of reach: the continuation towards them takes one solve per
tenth of a size (1,000 at this distance), and absurd values (1e308) would overflow."""


def _refuse_far_pose(robot: Robot, start: np.ndarray, target: pin.SE3) -> None:
    """Refuse a target more than :data:`FAR` robot sizes from the platform's start position."""
    size = _size(robot)
    d = float(np.max(np.abs(target.translation - robot.platform_placement(start).translation)))
    if d > FAR * size:  # (the largest component: no overflow)
        pos = np.array2string(target.translation, precision=4)
        raise UnreachablePoseError(
            "-",
            0.0,
            f"{robot.name}: pose {pos} m lies {d:.3g} m from the platform's position along an "
            f"axis, more than {FAR:g} times the robot's size ({size:.3g} m): out of reach",
        )


def _refuse_far_actuators(robot: Robot, start: np.ndarray, qa: np.ndarray) -> None:
    """Refuse actuator values more than :data:`FAR` actuator scales from the start's."""
    a0 = start[robot.actuated_q]
    d = np.abs(qa - a0) / robot.actuator_scale
    if d.size and float(np.max(d)) > FAR:
        k = int(np.argmax(d))
        unit = "m" if robot.actuator_prismatic[k] else "rad"
        raise InvalidInputError(
            "actuated coordinates",
            f"{robot.actuators[k].name} = {qa[k]:.6g} {unit} is {d[k]:.3g} times its scale "
            f"({robot.actuator_scale[k]:.3g} {unit}) from its start {a0[k]:.6g} {unit}: beyond "
            "any reachable value",
        )


_NAMES = ("x", "y", "z", "roll", "pitch", "yaw")


def _partial_pose(robot: Robot, pose: Sequence[float] | np.ndarray | pin.SE3) -> np.ndarray | None:
    """A full pose vector from the controlled components only, or ``None`` for a full pose.

    A pose of ``n`` values that is neither ``x y z`` nor ``x y z roll pitch yaw`` gives the
    robot's ``n`` controlled components, in the order ``x y z roll pitch yaw`` (a five-bar:
    ``x y``; a four-bar knee: its one); the others are those of the home pose (placeholders:
    the robot does not control them).
    """
    if isinstance(pose, pin.SE3):
        return None
    values = as_finite("pose", pose)
    rows = np.asarray(robot.task_rows, dtype=int)
    if values.size in (3, 6):
        return None
    if values.size != rows.size:
        names = " ".join(_NAMES[int(r)] for r in rows)
        raise InvalidInputError(
            "pose",
            f"expected x y z [roll pitch yaw] (3 or 6 values) or the {rows.size} components "
            f"{robot.name} controls ({names}), got {values.size}",
        )
    home = np.concatenate(pose_to_vector(robot.platform_placement(robot.q_home)))
    home[rows] = values
    return home


UNCONTROLLED_TOL = 1e-9
"""Largest difference [m or rad] between a requested and the reached value of a pose component
the robot does not control, before :func:`inverse_geometry` refuses the request."""


def _check_uncontrolled(
    robot: Robot, pose: Sequence[float] | np.ndarray | pin.SE3, target: pin.SE3, q: np.ndarray
) -> None:
    """Refuse a pose whose uncontrolled components differ from what the robot reaches.

    A Delta keeps its nacelle level: a requested roll or yaw cannot be imposed and must not be
    dropped silently. Components count as requested when given as numbers: all six of a
    6-vector, the position of a 3-vector. A ``pin.SE3`` placement is a target frame whose
    uncontrolled components are free (a trajectory's rows, a moved current placement).
    """
    if isinstance(pose, pin.SE3):
        return
    given = int(np.size(pose))
    rows = [k for k in range(given) if k not in set(int(r) for r in robot.task_rows)]
    if not rows:
        return
    reached = robot.platform_placement(q)
    err = np.concatenate(
        [reached.translation - target.translation, pin.log3(target.rotation.T @ reached.rotation)]
    )
    bad = [k for k in rows if abs(err[k]) > UNCONTROLLED_TOL]
    if bad:
        names = ("x", "y", "z", "roll", "pitch", "yaw")
        pos, rpy = pose_to_vector(reached)
        now = np.concatenate([pos, rpy])
        want = np.concatenate(pose_to_vector(target))
        what = ", ".join(f"{names[k]} = {want[k]:.6g} (it stays at {now[k]:.6g})" for k in bad)
        task = " ".join(("x", "y", "z", "rx", "ry", "rz")[int(r)] for r in robot.task_rows)
        raise UnreachablePoseError(
            "-",
            0.0,
            f"{robot.name} controls only {task} of its platform: {what} cannot be imposed; "
            "give those components as the robot reaches them"
            + (
                f", or only the {len(robot.task_rows)} controlled ones"
                if len(robot.task_rows) not in (3, 6)
                else ""
            ),
        )


CONTINUATION_STEP = 0.1
"""Largest actuator step [rad; m for prismatic actuators, times the robot's size] and platform
step [rad; times the size for translations] of one solve in a continuation."""

MAX_CONTINUATION_STEPS = 1000
"""Most steps of one continuation: a target farther than that many steps (100 robot sizes or
rad) gets longer steps (and is out of reach of any mechanism of bounded links), so the work
stays bounded whatever the target."""


def _size(robot: Robot) -> float:
    """Characteristic length [m] (:attr:`Robot.length_scale`)."""
    return robot.length_scale


def _moves_far(robot: Robot, a0: np.ndarray, qa: np.ndarray) -> bool:
    """Whether an actuator moves by more than one continuation step (a cheap test first)."""
    d = (qa - a0) / robot.actuator_scale
    if d.dot(d) <= CONTINUATION_STEP**2:  # the 2-norm bounds every component
        return False
    return bool(np.max(np.abs(d)) > CONTINUATION_STEP)


def _fk_continuation(
    robot: Robot, start: np.ndarray, qa: np.ndarray, tol: float
) -> np.ndarray | None:
    """Configuration for ``qa`` reached from ``start`` by moving the actuators in steps.

    Each step is solved from the previous one, so the result keeps the assembly mode of
    ``start`` (unless the path crosses a singularity). ``None``: one step suffices, or a step
    failed (the caller then solves directly).
    """
    a0 = np.array(start[robot.actuated_q], dtype=float)
    scale = CONTINUATION_STEP * robot.actuator_scale
    n = int(np.ceil(min(np.max(np.abs(qa - a0) / scale, initial=0.0), MAX_CONTINUATION_STEPS)))
    if n <= 1 or robot.constraints.n == 0:
        return None
    q = np.array(start, dtype=float)
    for t in np.linspace(0.0, 1.0, n + 1)[1:]:
        q[robot.actuated_q] = (1.0 - t) * a0 + t * qa
        sol = _solve_closures(robot, q, robot.passive_v, max(tol, 1e-10))
        if not sol.converged:
            return None
        q = sol.q
    return q


def _ik_continuation(
    robot: Robot, start: np.ndarray, target: pin.SE3, tol: float
) -> np.ndarray | None:
    """Configuration reaching ``target`` from ``start`` by moving the platform in steps.

    Keeps the working and assembly modes of ``start``. ``None``: one step suffices, or a step
    failed (the caller then solves directly).
    """
    if robot.platform_frame is None:
        return None
    M0 = robot.platform_placement(start)
    rows = np.asarray(robot.task_rows, dtype=int)
    d = pin.log6(M0.actInv(target)).vector
    d[:3] = target.translation - M0.translation  # world-frame translation
    step = np.where(np.arange(6) < 3, CONTINUATION_STEP * _size(robot), CONTINUATION_STEP)
    n = int(np.ceil(min(np.max(np.abs(d[rows]) / step[rows], initial=0.0), MAX_CONTINUATION_STEPS)))
    if n <= 1:
        return None
    task = FramePoseTask(robot.model, robot.platform_frame, rows)
    rot = pin.log3(M0.rotation.T @ target.rotation)
    q = np.array(start, dtype=float)
    for t in np.linspace(0.0, 1.0, n + 1)[1:]:
        task.target = pin.SE3(M0.rotation @ pin.exp3(t * rot), M0.translation + t * d[:3])
        sol = solve_pose(robot, task, q, max(tol, 1e-10))
        if not sol.converged:
            return None
        q = sol.q
    return q


def solve_pose(
    robot: Robot,
    task: FramePoseTask,
    q0: np.ndarray,
    tol: float = DEFAULT_TOL,
    max_iter: int = 100,
    stall: float = 0.0,
) -> SolveResult:
    """Closures and platform pose solved together (the inverse geometric model, unchecked).

    The hot path of :func:`inverse_geometry` (no validation, no message): for callers that
    solve many poses, e.g. the numeric workspace.

    Args:
        robot: The robot.
        task: The platform pose task (its ``target`` set).
        q0: Initial configuration (nq,).
        tol: Residual threshold [m or rad].
        max_iter: Iteration cap.
        stall: Early stop of :func:`solvers.solve_lm` on a stalling residual (0: never).

    Returns:
        The solver's outcome: the constraint rows first (``robot.constraints.n_local`` of
        them: :meth:`solvers.ConstraintSet.local_residual`), then the task rows.

    """
    cs, data = robot.constraints, robot.data
    nc = cs.n_local

    def residual(q: np.ndarray) -> np.ndarray:
        r_c = cs.local_residual(data, q)  # runs the kinematics
        r_t = task.residual(data)
        return np.concatenate((r_c, r_t)) if nc else r_t

    def jacobian(q: np.ndarray) -> np.ndarray:  # at the last residual's configuration
        J_c = cs.local_jacobian_after_residual(data, q)  # also the joint Jacobians of the task
        J_t = task.jacobian(data)
        return np.concatenate((J_c, J_t)) if nc else J_t

    return solve_lm(
        robot.model, q0, residual, jacobian, tol=tol * _LOCAL_TOL, max_iter=max_iter, stall=stall
    )


def check_actuator_limits(robot: Robot, q: np.ndarray) -> None:
    """Raise :class:`JointLimitError` if an actuated coordinate is outside its limits.

    Args:
        robot: The robot.
        q: Configuration (nq,).

    """
    iq = robot.actuated_q
    lo = robot.model.lowerPositionLimit[iq]
    hi = robot.model.upperPositionLimit[iq]
    qa = q[iq]
    out = (qa < lo - 1e-12) | (qa > hi + 1e-12)
    if out.any():
        bad = np.flatnonzero(out)
        k = int(bad[0])
        raise JointLimitError(robot.actuators[k].joint, float(q[iq[k]]), float(lo[k]), float(hi[k]))
