"""Singularity classification of any loaded robot (seed 001; Clavel's Delta families, seed 000).

With ``A x_dot = B qa_dot`` (:mod:`pkdyn.analysis.kinematics`):

- **serial** singularity, ``B`` rank-deficient: an actuator motion leaves the platform at rest
  (a chain is stretched or folded, it loses a degree of freedom); the singular directions are
  actuator-rate directions, the null space of ``B``.
- **parallel** singularity, ``A`` rank-deficient: the platform can move with the actuators
  locked (it gains an uncontrollable motion, forces are no longer transmitted in some
  direction); the singular directions are platform twists, the null space of ``A``.
- **both** at once.

Robots with fewer than 6 controlled components (Delta, planar robots) are also checked on the
full 6D platform twist: with the actuators locked, the platform must not gain *any* motion, not
even in an uncontrolled component such as the Delta nacelle's orientation. The gained 6D twists
are reported in ``platform_directions``; when they leave every task component at rest the
singularity is parallel with ``constraint=True``. The 6D check uses the platform relations in
the closure-force metric (continuous through the loss of a relation), with the number of
relations of the robot at ``q_home`` as reference.

When the hidden motion does move the task point (Clavel's family c: the nacelle turns about the
line through the nacelle joints of the third parallelogram, so its centre moves normal to the
nacelle plane), the task-level relations lose a dimension and ``A`` and ``B`` degenerate
together: to first order the actuators could also move while the centre stays put, the nacelle
turning. That is not a serial singularity (the platform is not at rest), so in this case the
serial test and ``cond_B`` use the 6D relations.

Measures: condition numbers (finite, capped at :data:`pkdyn.analysis.kinematics.COND_MAX`),
``distance``, the smallest of their inverses, and ``margin``, the scale-aware smallest singular
value (:func:`pkdyn.analysis.kinematics.relation_margins`: rates made dimensionless by the
robot's length, relations orthonormalised), all in ``[0, 1]`` (0: exactly singular). The
decisions use the margins, which see what a condition number cannot: every Delta arm stretched
along its bars at once shrinks ``B`` as a whole, ``cond(B)`` stays near 1. Below
:data:`pkdyn.analysis.kinematics.SINGULAR_TOL` a matrix is singular. ``near`` is set within
about 1e-4 of the robot's size (in pose) of a singularity: a parallel margin below
:data:`pkdyn.analysis.kinematics.NEAR_SINGULAR_TOL`, or a serial one below
:data:`pkdyn.analysis.kinematics.NEAR_SERIAL_TOL` (it grows like the square root of the
distance); a singular configuration is near too. A regular near-singular configuration also
issues a :class:`pkdyn.analysis.kinematics.NearSingularityWarning`.
"""

from __future__ import annotations

import warnings
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.analysis.kinematics import (
    NEAR_SERIAL_TOL,
    NEAR_SINGULAR_TOL,
    SINGULAR_TOL,
    KinematicModels,
    NearSingularityWarning,
    _cond,
    _relations,
    kinematic_models,
    relation_margins,
    robot_scales,
)
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.results import Result
from pkdyn.units import quantity
from solvers import numerics

__all__ = ["SingularityReport", "classify", "singularity_json"]

_PLATFORM_RELATIONS: dict[int, int] = {}
"""Number of 6D platform relations at ``q_home``, by ``id(robot)`` (dropped with the robot)."""


@dataclass
class SingularityReport(Result):
    """Singularity analysis of one configuration.

    Attributes:
        kind: ``"regular"``, ``"serial"``, ``"parallel"`` or ``"both"``.
        cond_A: Condition number of the parallel matrix ``A`` (finite).
        cond_B: Condition number of the serial matrix ``B`` (finite; of the 6D relations when
            the task relations degenerate, see the module docstring).
        cond_platform: Condition number of the 6D platform relations (robots with ``m < 6``;
            equals ``cond_A`` otherwise).
        distance: ``min(1 / cond_A, 1 / cond_B, 1 / cond_platform)`` in ``[0, 1]``.
        margin: Smallest scale-aware margin of ``A``, ``B`` and the 6D relations
            (:func:`pkdyn.analysis.kinematics.relation_margins`), in ``[0, 1]``: ``kind`` and
            ``near`` are decided on it (0: exactly singular).
        near: Within about 1e-4 of the robot's size of a singular configuration (see the module
            docstring); set for singular configurations too.
        constraint: The parallel singularity lets the platform move in uncontrolled
            components (only these).
        parallel_directions: (k, m) unit platform velocities (task components) in the
            (near-)null space of ``A``.
        serial_directions: (k, n_a) unit actuator rates in the (near-)null space of ``B``.
        platform_directions: (k, 6) unit platform twists ``[v_world; omega_platform]`` the
            locked actuators do not prevent (6D check, robots with ``m < 6``).
        task: Controlled pose components.
        actuators: Actuated joint names.

    """

    kind: str
    cond_A: float
    cond_B: float
    cond_platform: float
    distance: float
    margin: float
    near: bool
    constraint: bool
    parallel_directions: np.ndarray
    serial_directions: np.ndarray
    platform_directions: np.ndarray
    task: tuple[str, ...]
    actuators: tuple[str, ...]

    def table(self) -> str:
        """The kind, the scale-aware margin and the conditions; the singular directions."""
        lines = [
            f"{self.kind}: margin = {quantity(self.margin)} (scale-aware, 0: singular), "
            f"cond(A) = {quantity(self.cond_A)}, cond(B) = {quantity(self.cond_B)} "
            "(dimensionless)"
            + ("; near a singularity" if self.near and self.kind == "regular" else "")
        ]
        task = [f"{c} [{'m/s' if c in 'xyz' else 'rad/s'}]" for c in self.task]
        for D, what, names in (
            (self.parallel_directions, "uncontrolled platform velocity", task),
            (
                self.serial_directions,
                "actuator rates that do not move the platform",
                list(self.actuators),
            ),
        ):
            for d in np.atleast_2d(D):
                if d.size:
                    parts = ", ".join(f"{n} {_num(v)}" for n, v in zip(names, d, strict=True))
                    lines.append(f"  {what} (unit direction): {parts}")
        return "\n".join(lines)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict (see :func:`singularity_json`)."""
        return {
            "kind": self.kind,
            "cond_A": self.cond_A,
            "cond_B": self.cond_B,
            "cond_platform": self.cond_platform,
            "distance": self.distance,
            "margin": self.margin,
            "near": self.near,
            "constraint": self.constraint,
            "directions": {
                "parallel": self.parallel_directions.tolist(),
                "serial": self.serial_directions.tolist(),
                "platform": self.platform_directions.tolist(),
            },
            "task": list(self.task),
            "actuators": list(self.actuators),
        }


def _num(v: float) -> str:
    return quantity(v if abs(v) > 1e-12 else 0.0, "", 3)


def _null_dirs(M: np.ndarray, n: int, tol: float) -> tuple[float, np.ndarray]:
    """Condition number of ``M`` (rank n expected) and right singular vectors below ``tol``."""
    cols = M.shape[1]
    if M.size == 0:
        return 1.0, np.zeros((0, cols))
    _, s, Vt = np.linalg.svd(M, full_matrices=True)
    cond = _cond(s, n)
    sfull = np.zeros(cols)
    sfull[: s.size] = s
    return cond, np.asarray(Vt[min(n, numerics.rank_of(sfull, tol)) : n])


def _platform_relations(robot: Robot, km: KinematicModels) -> np.ndarray:
    """Rows ``[B6, -A6]`` of the 6D platform relations (W metric), as many as at ``q_home``."""
    a, p = km.actuated_v, km.passive_v
    rel = _relations(km.Jc, km.J6, a, p)
    r6 = _PLATFORM_RELATIONS.get(id(robot))
    if r6 is None:
        home = kinematic_models(robot, robot.q_home)
        ref = _relations(home.Jc, home.J6, a, p)
        r6 = numerics.rank_of(ref.s, SINGULAR_TOL)
        _PLATFORM_RELATIONS[id(robot)] = r6
        weakref.finalize(robot, _PLATFORM_RELATIONS.pop, id(robot), None)
    if rel.R.size == 0:
        return np.zeros((0, 6))
    U, _, _ = np.linalg.svd(rel.R, full_matrices=True)
    return np.asarray(U.T[:r6] @ rel.R)


def _directions(
    rows: np.ndarray, k: int, n: int, scale: np.ndarray, tol: float, first: bool
) -> tuple[float, np.ndarray]:
    """Margin and (near-)singular directions of one block of orthonormal relation rows.

    ``rows`` are ``[B', -A']`` (scaled, :func:`relation_margins`); the block is the first
    ``k`` columns (``first``: ``B'``) or the last ones (``A'``), ``n`` its expected rank. The
    directions are converted back to physical rates (times ``scale``) and normalised.
    """
    M = rows[:, :k] if first else -rows[:, rows.shape[1] - k :]
    if M.size == 0 or n == 0:
        return 1.0, np.zeros((0, k))
    _, s, Vt = np.linalg.svd(M, full_matrices=True)
    sfull = np.zeros(k)
    sfull[: s.size] = s
    margin = float(sfull[n - 1]) if n <= sfull.size else 0.0
    keep = np.flatnonzero(sfull[:n] < tol)
    D = np.asarray(Vt[keep]) * scale
    norms = np.linalg.norm(D, axis=1, keepdims=True)
    return margin, D / np.where(norms > 0, norms, 1.0)


@public
def classify(
    robot: Robot,
    q: Sequence[float] | np.ndarray,
    tol: float = SINGULAR_TOL,
    near_tol: float = NEAR_SINGULAR_TOL,
    near_serial_tol: float = NEAR_SERIAL_TOL,
) -> SingularityReport:
    """Classify a configuration as regular, serial, parallel or both.

    The tests are scale-aware (:func:`pkdyn.analysis.kinematics.relation_margins`): rates made
    dimensionless by the robot's length, relations orthonormalised, the smallest singular
    values of ``A'`` and ``B'`` (the margins, in ``[0, 1]``) compared with ``tol`` and
    ``near_tol``.

    Args:
        robot: Any loaded robot with a platform.
        q: Assembled configuration (nq,).
        tol: Margin below which a matrix is singular.
        near_tol: Parallel margin below which a configuration is flagged near-singular.
        near_serial_tol: Serial margin below which a configuration is flagged near-singular.

    Returns:
        The report; condition numbers are finite.

    Raises:
        InvalidInputError: Malformed or unassembled ``q``, or no platform.

    """
    km = kinematic_models(robot, q)
    m, n_a = km.m, km.n_a
    rows_task = np.asarray(robot.task_rows, dtype=int)
    a_scale, x_scale = robot_scales(robot, rows_task)
    _, _, rel = relation_margins(km.A, km.B, a_scale, x_scale)
    cond_A = _null_dirs(km.A, m, near_tol)[0]
    r = km.A.shape[0]  # relations: m, or n_a under redundant actuation
    cond_B = _null_dirs(km.B, min(r, n_a), near_tol)[0]
    margin_A, par = _directions(rel, m, m, x_scale, near_tol, first=False)
    margin_B, ser = _directions(rel, n_a, min(r, n_a), a_scale, near_tol, first=True)
    if m < 6:
        rows = _platform_relations(robot, km)
        A6 = -rows[:, n_a:]
        cond_P = _null_dirs(A6, min(A6.shape), near_tol)[0]
        six_a, six_x = robot_scales(robot, np.arange(6))
        if rows.shape[0]:
            _, _, rel6 = relation_margins(A6, rows[:, :n_a], six_a, six_x)
        else:
            rel6 = np.zeros((0, n_a + 6))
        margin_P, plat = _directions(rel6, 6, min(rel6.shape[0], 6), six_x, near_tol, first=False)
        if km.relation_gap < tol:
            # The task relations lost a dimension: a hidden (uncontrolled-component) platform
            # motion moves the task point, so A and B both degenerate. Whether an actuator
            # motion leaves the *whole* platform at rest is decided on the 6D relations.
            cond_B = _null_dirs(rows[:, :n_a], min(rows.shape[0], n_a), near_tol)[0]
            margin_B, ser = _directions(
                rel6, n_a, min(rel6.shape[0], n_a), a_scale, near_tol, first=True
            )
    else:
        cond_P, margin_P = cond_A, margin_A
        plat = par
    parallel_task = margin_A < tol
    parallel_6d = margin_P < tol
    parallel = parallel_task or parallel_6d
    serial = margin_B < tol
    kind = {
        (False, False): "regular",
        (False, True): "serial",
        (True, False): "parallel",
        (True, True): "both",
    }[(parallel, serial)]
    worst = max(cond_A, cond_B, cond_P)
    margin = min(margin_A, margin_B, margin_P)
    near_parallel = min(margin_A, margin_P) < near_tol
    near_serial = margin_B < near_serial_tol
    near = near_parallel or near_serial
    if near and kind == "regular":
        which = "parallel" if near_parallel else "serial"
        warnings.warn(
            f"{robot.name}: near a {which} singularity (scale-aware margin {margin:.3g}, "
            f"condition number {worst:.3g}); velocities and efforts are ill-conditioned here",
            NearSingularityWarning,
            stacklevel=2,
        )
    return SingularityReport(
        kind=kind,
        cond_A=cond_A,
        cond_B=cond_B,
        cond_platform=cond_P,
        distance=1.0 / worst,
        margin=margin,
        near=near,
        constraint=parallel_6d and not parallel_task,
        parallel_directions=par,
        serial_directions=ser,
        platform_directions=plat,
        task=km.task,
        actuators=km.actuators,
    )


def singularity_json(robot: Robot, q: Sequence[float] | np.ndarray) -> dict[str, Any]:
    """JSON-ready singularity report for the CLI.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).

    Returns:
        ``{"kind", "cond_A", "cond_B", "cond_platform", "distance", "near", "constraint",
        "directions": {"parallel", "serial", "platform"}, "task", "actuators"}``.

    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearSingularityWarning)
        return classify(robot, q).to_json()
