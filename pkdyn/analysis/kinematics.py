"""Kinematic models of any loaded robot: parallel and serial matrices, Jacobians.

Pasqui's form of a parallel robot (seed 001): ``A(x, q) x_dot = B(x, q) qa_dot``, with ``A`` the
*parallel* matrix (``m x m``, ``m`` = number of controlled pose components) and ``B`` the
*serial* matrix (``m x n_a``). Then ``J = A^-1 B`` (direct kinematic model,
``x_dot = J qa_dot``) and ``J_inv = B^-1 A`` (inverse kinematic model, ``qa_dot = J_inv x_dot``).

Task-space velocity convention (the one of :class:`solvers.FramePoseTask` at zero error):
``x_dot`` stacks, for the controlled components among ``(x, y, z, rx, ry, rz)``, the linear
velocity of the platform frame origin in world axes [m/s] and the angular velocity of the
platform expressed in the **platform frame** [rad/s] (``R^T omega_world``, the derivative of
``log3(R0^T R)``). For planar robots and the Delta the two frames give the same components; for
6-DOF robots ``omega_world = R omega_platform``. Wrenches are the power conjugates: force in world
axes [N], moment about the platform frame origin in platform axes [N m].

General construction (no robot-specific code). With the closure Jacobian ``Jc`` (``nc x nv``) and
the platform task Jacobian ``Jx`` (``m x nv``), split into actuated (``_a``) and passive (``_p``)
velocity columns, every motion satisfies::

    [ Jc_a  Jc_p   0 ] [qa_dot]
    [ Jx_a  Jx_p  -I ] [ v_p   ]  = 0
                       [ x_dot ]

A left annihilator ``W = [W_c, W_x]`` of ``[Jc_p; Jx_p]`` (orthonormal basis of its left null
space, from an SVD) eliminates the passive velocities: ``W_x x_dot = (W_c Jc_a + W_x Jx_a)
qa_dot``. The rows of ``W_x`` are the platform wrenches the chains can transmit (Pasqui's
reciprocal screws) and those of ``W_c`` the matching closure forces. The stacked relation
``[B, -A] = [W_c Jc_a + W_x Jx_a, -W_x]`` may contain trivial (zero) rows, from redundant closure
equations (e.g. planar hinges); it is compressed by a second SVD to an **orthonormal basis of its
row space**, the ``m`` linear relations satisfied by every feasible ``(qa_dot, x_dot)``.

Non-uniqueness: any ``(G A, G B)`` with ``G`` invertible describes the same robot. The
normalisation used here (``[B, -A]`` with orthonormal rows, so ``A A^T + B B^T = I``) fixes
``A`` and ``B`` up to a left orthogonal factor, so their singular values (and condition numbers)
are well defined (for the chosen units: m, rad). ``J`` and ``J_inv`` are unique. Singularity
tests are rank tests on ``A`` (parallel: a platform motion with locked actuators) and ``B``
(serial: an actuator motion with the platform fixed), see :mod:`pkdyn.analysis.singularity`.
"""

from __future__ import annotations

import warnings
import weakref
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError, SingularConfigurationError
from pkdyn.model.arguments import public
from pkdyn.model.platform_jacobian import platform_jacobian as _platform_jacobian
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.results import Result, jsonable
from pkdyn.units import matrix, quantity
from solvers import ConstraintSet, numerics

__all__ = [
    "TASK_NAMES",
    "SINGULAR_TOL",
    "NEAR_SERIAL_TOL",
    "NEAR_SINGULAR_TOL",
    "COND_MAX",
    "ASSEMBLY_TOL",
    "check_assembled",
    "NearSingularityWarning",
    "KinematicModels",
    "kinematic_models",
    "PassiveMap",
    "passive_map",
    "platform_jacobian",
    "platform_twist",
    "actuator_rates",
    "joint_velocities",
    "jacobian_json",
]

TASK_NAMES = ("x", "y", "z", "rx", "ry", "rz")
"""Names of the pose components, indexed by ``Robot.task_rows``."""

SINGULAR_TOL = 1e-7
"""A configuration is exactly singular when a scale-aware margin (:func:`relation_margins`) is
below this.

Not much smaller: at a serial singularity (a fold of the inverse model: an arm stretched along
its bars) the configuration of a given pose is only determined to about sqrt(machine epsilon),
1.5e-8, which is then its margin; URDF descriptions store 10 significant digits, so a
configuration built to be singular is singular to ~1e-10 in the loaded model. A configuration
1e-6 rad from a singularity keeps a margin near 1e-6: near-singular, not singular."""

NEAR_SINGULAR_TOL = 1e-4
"""Below this parallel margin (of ``A``) a configuration is flagged near-singular.

The documented distance: a configuration is *near-singular* when it lies within about 1e-4 of
the robot's size (in platform pose: 0.1 mm on a 1 m robot, 1e-4 rad) of a singular one. A
parallel margin grows linearly with that distance (0.77 times the rotation on the 3-RRR), so
its threshold is 1e-4; a serial margin like its square root (:data:`NEAR_SERIAL_TOL`)."""

NEAR_SERIAL_TOL = 1e-2
"""Below this serial margin (of ``B``) a configuration is flagged near-singular.

Serial singularities lie on the workspace boundary, where the inverse model folds: the margin
grows like the square root of the distance to it (0.54 sqrt(d / 1 m) on the Delta: 5.4e-4 at
1 um from its lowest point, 5.4e-3 at 0.1 mm), so the distance of :data:`NEAR_SINGULAR_TOL`
(1e-4 of the size) is a margin of sqrt(1e-4) = 1e-2."""

COND_MAX = 1e16
"""Condition numbers are reported finite, capped at this value (exactly singular matrices)."""

ASSEMBLY_TOL = 1e-6
"""Largest closure residual component [m or rad] accepted for an 'assembled' configuration."""


class NearSingularityWarning(UserWarning):
    """The configuration is close to a singularity: velocities and efforts are ill-conditioned."""


def _cond(s: np.ndarray, n: int) -> float:
    """Condition number (capped, finite) from singular values ``s`` of a matrix of rank <= n."""
    if n == 0:
        return 1.0
    if s.size < n or s[0] <= 0.0:
        return COND_MAX
    smin = float(s[n - 1])
    if smin <= float(s[0]) / COND_MAX:
        return COND_MAX
    return float(s[0]) / smin


def relation_margins(
    A: np.ndarray, B: np.ndarray, a_scale: np.ndarray, x_scale: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scale-aware singular values of ``A`` and ``B``: the singularity rule.

    :func:`solvers.numerics.scaled_margins`, the relations' rank cut at :data:`SINGULAR_TOL`;
    kinds are decided by comparing the smallest values with :data:`SINGULAR_TOL` and
    :data:`NEAR_SINGULAR_TOL`.
    """
    return numerics.scaled_margins(A, B, a_scale, x_scale, SINGULAR_TOL)


def robot_scales(robot: Robot, task_rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``a_scale`` and ``x_scale`` of :func:`relation_margins` for a robot and task rows.

    Translations and prismatic actuator rates are divided by :attr:`Robot.length_scale`, so
    that the margins are dimensionless and the same for the robot at any size.
    """
    L = robot.length_scale
    a_scale = robot.actuator_scale
    x_scale = np.where(np.asarray(task_rows) < 3, L, 1.0)
    return a_scale, x_scale


@public
def platform_jacobian(
    robot: Robot,
    q: np.ndarray | None,
    *,
    point: np.ndarray | None = None,
    angular: str = "platform",
) -> np.ndarray:
    """Full 6D platform Jacobian (6, nv) in the task convention, kinematics at ``q`` computed.

    Rows: linear velocity of the platform frame origin (or of ``point``) in world axes [m/s],
    then angular velocity in the platform frame [rad/s] (``FramePoseTask`` rows at zero error;
    ``angular="world"``: world axes, the precision convention). The one construction,
    :func:`pkdyn.model.platform_jacobian.platform_jacobian`.

    Args:
        robot: The robot (must declare a platform).
        q: Configuration (nq,) (``None``: the joint Jacobians in ``robot.data`` are current).
        point: Reference point in the platform frame [m] (default: its origin).
        angular: ``platform`` (the task convention) or ``world``.

    Returns:
        Jacobian (6, nv) with respect to increments applied by ``pin.integrate``.

    """
    return _platform_jacobian(robot, q, point=point, angular=angular)


@dataclass(eq=False)  # numpy fields
class PassiveMap:
    """The closures solved for the passive rates at one configuration (the one elimination).

    With the closure Jacobian ``Jc`` split into actuated and passive columns, the passive rates
    that keep the loops closed are ``v_p = -Jc_p^+ (Jc_a qa_dot + r)`` for closure residual
    rates ``r`` (:func:`solvers.numerics.passive_elimination`: minimum norm, so internal
    mobilities stay still), and the platform moves by ``J qa_dot``,
    ``J = Jx_a - Jx_p Jc_p^+ Jc_a``.

    Attributes:
        Jc: Closure Jacobian (nc, nv) (the robot's constraint layer: closures and couplings).
        Jx: Platform Jacobian (6, nv) (:func:`platform_jacobian`).
        elimination: The elimination of ``Jc_p``.
        actuated_v: Velocity indices of the actuators (n_a,).
        passive_v: Velocity indices of the passive coordinates (n_p,).

    """

    Jc: np.ndarray
    Jx: np.ndarray
    elimination: numerics.PassiveElimination
    actuated_v: np.ndarray
    passive_v: np.ndarray

    def passive(self, rhs: np.ndarray) -> np.ndarray:
        """Passive rates (n_p,) or (n_p, k) absorbing closure residual rates ``rhs``."""
        return -self.elimination.solve(rhs)

    def platform(self, rhs: np.ndarray) -> np.ndarray:
        """Platform motion (6,) or (6, k) of the passive rates absorbing ``rhs``."""
        return np.asarray(self.Jx[:, self.passive_v] @ self.passive(rhs))

    @property
    def J(self) -> np.ndarray:
        """Platform motion per actuator rate (6, n_a): the direct kinematic Jacobian."""
        a = self.actuated_v
        return np.asarray(self.Jx[:, a] + self.platform(self.Jc[:, a]))

    @property
    def V(self) -> np.ndarray:
        """Joint velocities per actuator rate (nv, n_a) (passive ones minimum-norm)."""
        a, p = self.actuated_v, self.passive_v
        V = np.zeros((self.Jc.shape[1], a.size))
        V[a, np.arange(a.size)] = 1.0
        V[p] = self.passive(self.Jc[:, a])
        return V


def passive_map(
    robot: Robot,
    q: np.ndarray,
    *,
    angular: str = "platform",
    point: np.ndarray | None = None,
    rank: int | None = None,
    constraints: ConstraintSet | None = None,
) -> PassiveMap:
    """Closure and platform Jacobians at ``q`` with the passive joints eliminated.

    Args:
        robot: The robot (with a platform frame).
        q: Configuration (nq,) (not checked: the caller's).
        angular: Axes of the platform Jacobian's angular rows (``platform``: task convention).
        point: Reference point of the platform Jacobian, platform frame [m].
        rank: Structural rank of the passive closure columns (``None``: decided at ``q``).
        constraints: The constraint rows (default ``robot.constraints``; the pose
            sensitivities take ``robot.constraints.unreduced``, whose rows placement errors
            can open).

    Returns:
        The map; the kinematics and joint Jacobians of ``robot.data`` are at ``q``.

    """
    cs = robot.constraints if constraints is None else constraints
    if cs.n:  # (runs the kinematics and joint Jacobians at q; closures and couplings)
        Jc = cs.jacobian(robot.data, q)
        Jx = _platform_jacobian(robot, None, point=point, angular=angular)
    else:
        Jc = np.zeros((0, robot.nv))
        Jx = _platform_jacobian(robot, q, point=point, angular=angular)
    a, p = np.asarray(robot.actuated_v), np.asarray(robot.passive_v)
    el = numerics.passive_elimination(Jc[:, p], rank=rank)
    return PassiveMap(Jc, Jx, el, a, p)


def _checked_q(robot: Robot, q: Sequence[float] | np.ndarray) -> np.ndarray:
    qq = as_finite("q", q, robot.nq)
    check_assembled(robot, qq)
    return qq


def check_assembled(robot: Robot, q: np.ndarray) -> None:
    """Refuse a configuration that does not close the robot's loops (within ``ASSEMBLY_TOL``).

    Args:
        robot: The robot (its ``data`` is used).
        q: Configuration (nq,), finite.

    Raises:
        InvalidInputError: A closure residual above :data:`ASSEMBLY_TOL`, with its size.

    """
    if robot.constraints.n == 0:
        return
    res = float(np.max(np.abs(robot.constraints.residual(robot.data, q))))
    if res > ASSEMBLY_TOL:
        raise InvalidInputError(
            "q",
            f"not an assembled configuration of {robot.name} (closure residual {res:.3g}); "
            "obtain q from pkdyn.forward_geometry, inverse_geometry or project",
        )


@dataclass
class _Relations:
    """Relations ``A x_dot = B qa_dot`` of one row selection, before normalisation."""

    R: np.ndarray  # (k, n_a + m): [B, -A] rows in the W metric
    s: np.ndarray  # singular values of R


def _relations(Jc: np.ndarray, Jx: np.ndarray, a: np.ndarray, p: np.ndarray) -> _Relations:
    """Eliminate the passive velocities between closure and platform equations."""
    m = Jx.shape[0]
    M = np.vstack([Jc[:, p], Jx[:, p]])
    W = numerics.left_null_space(M, 1e-10)  # (k, nc + m)
    nc = Jc.shape[0]
    Wc, Wx = W[:, :nc], W[:, nc:]
    R = np.hstack([Wc @ Jc[:, a] + Wx @ Jx[:, a], -Wx]) if W.size else np.zeros((0, a.size + m))
    s = np.linalg.svd(R, compute_uv=False) if R.size else np.zeros(0)
    return _Relations(R, s)


@dataclass
class KinematicModels(Result):
    """Kinematic models of a robot at one configuration.

    ``A x_dot = B qa_dot`` with ``[B, -A]`` orthonormal rows (see the module docstring). ``J``
    and ``J_inv`` are computed on request and raise at exactly singular configurations.

    Attributes:
        q: The configuration (nq,).
        task: Names of the controlled pose components (``m`` of them).
        actuators: Actuated joint names (``n_a``).
        A: Parallel matrix (r, m) [task units: m for rows' linear parts, rad for angular]:
            ``r = m`` relations, or ``r = n_a`` under redundant actuation (``n_a > m``).
        B: Serial matrix (r, n_a).
        sigma_A: Singular values of ``A`` (descending).
        sigma_B: Singular values of ``B`` (descending).
        relation_gap: Ratio of the ``r``-th singular value of the raw relation matrix to the
            largest (small: the robot's mobility degenerates, e.g. a lost degree of freedom).
        margin_A: Scale-aware smallest singular value of ``A`` (:func:`relation_margins`),
            in ``[0, 1]``: the parallel-singularity test.
        margin_B: The same for ``B``: the serial-singularity test.
        Jc: Closure Jacobian (nc, nv) at ``q``.
        Jx: Platform Jacobian rows of the task (m, nv) at ``q``.
        J6: Full platform Jacobian (6, nv) at ``q``.
        actuated_v: Velocity indices of the actuators.
        passive_v: Velocity indices of the passive coordinates.
        actuator_units: Unit of each actuator coordinate (``rad`` or ``m``).

    """

    q: np.ndarray
    task: tuple[str, ...]
    actuators: tuple[str, ...]
    A: np.ndarray
    B: np.ndarray
    sigma_A: np.ndarray
    sigma_B: np.ndarray
    relation_gap: float
    margin_A: float
    margin_B: float
    Jc: np.ndarray
    Jx: np.ndarray
    J6: np.ndarray
    actuated_v: np.ndarray
    passive_v: np.ndarray
    actuator_units: tuple[str, ...] = ()
    _cache: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    def _optional(self, key: str) -> np.ndarray | None:
        """``J`` or ``J_inv``, or ``None`` where it does not exist (a singularity)."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NearSingularityWarning)
            try:
                return np.asarray(getattr(self, key))
            except SingularConfigurationError:
                return None

    def to_json(self) -> dict[str, Any]:
        """The models as JSON values.

        Returns:
            ``A``, ``B``, ``J``, ``J_inv`` (``None`` at a parallel / serial singularity),
            ``task``, ``actuators``, ``cond_A``, ``cond_B`` and the ``twist`` convention.

        """
        return jsonable(
            {
                "A": np.atleast_2d(self.A),
                "B": np.atleast_2d(self.B),
                "J": self._optional("J"),
                "J_inv": self._optional("J_inv"),
                "task": list(self.task),
                "actuators": list(self.actuators),
                "cond_A": self.cond_A,
                "cond_B": self.cond_B,
                "twist": "linear: platform origin velocity, world axes [m/s]; "
                "angular: platform frame [rad/s]",
            }
        )

    def table(self) -> str:
        """``J`` and ``J_inv`` with their units by row and column, ``A``, ``B``, conditions."""
        task = [f"{c} [{'m' if c in 'xyz' else 'rad'}]" for c in self.task]
        units = self.actuator_units or ("",) * self.n_a
        acts = [f"{n} [{u}]" if u else n for n, u in zip(self.actuators, units, strict=True)]
        lines = []
        J = self._optional("J")
        if J is None:
            lines.append("J: none (parallel singularity: A is singular)")
        else:
            lines += ["J = d(pose)/d(qa), x_dot = J qa_dot:", matrix(np.atleast_2d(J), task, acts)]
        J_inv = self._optional("J_inv")
        if J_inv is None:
            lines.append("J_inv: none (serial singularity: B is singular)")
        else:
            lines += ["J_inv = d(qa)/d(pose):", matrix(np.atleast_2d(J_inv), acts, task)]
        rows = [f"relation {k + 1}" for k in range(np.atleast_2d(self.A).shape[0])]
        lines += [
            "A, B: A x_dot = B qa_dot, rows of [B, -A] orthonormal (unit scale):",
            matrix(
                np.hstack([np.atleast_2d(self.A), np.atleast_2d(self.B)]),
                rows,
                [f"A:{c}" for c in self.task] + [f"B:{a}" for a in self.actuators],
            ),
            f"cond(A) = {quantity(self.cond_A)}, cond(B) = {quantity(self.cond_B)} (dimensionless)",
            "twist: linear velocity of the platform origin, world axes [m/s]; angular, platform "
            "frame [rad/s]",
        ]
        return "\n".join(lines)

    @property
    def m(self) -> int:
        """Number of controlled pose components."""
        return len(self.task)

    @property
    def n_a(self) -> int:
        """Number of actuators."""
        return len(self.actuators)

    @property
    def cond_A(self) -> float:
        """Condition number of ``A`` (finite, capped at :data:`COND_MAX`)."""
        return _cond(self.sigma_A, self.m)

    @property
    def cond_B(self) -> float:
        """Condition number of ``B`` (finite, capped at :data:`COND_MAX`)."""
        return _cond(self.sigma_B, min(self.B.shape))

    def _check(self, which: str) -> None:
        """Raise at an exact singularity of ``A`` (parallel) or ``B`` (serial), warn near one."""
        matrix, jac = ("A", "J") if which == "parallel" else ("B", "J_inv")
        cond = self.cond_A if which == "parallel" else self.cond_B
        margin = self.margin_A if which == "parallel" else self.margin_B
        near = NEAR_SINGULAR_TOL if which == "parallel" else NEAR_SERIAL_TOL
        if margin < SINGULAR_TOL:
            raise SingularConfigurationError(
                which,
                f"{which} singularity: {matrix} is singular (scale-aware margin {margin:.3g}, "
                f"condition number {cond:.3g}), so {jac} does not exist at this configuration",
            )
        if margin < near:
            warnings.warn(
                f"near a {which} singularity: scale-aware margin of {matrix} is {margin:.3g} "
                f"(condition number {cond:.3g})",
                NearSingularityWarning,
                stacklevel=3,
            )

    @property
    def J(self) -> np.ndarray:
        """Direct kinematic Jacobian (m, n_a): ``x_dot = J qa_dot``.

        Raises:
            SingularConfigurationError: ``A`` is singular (parallel singularity).

        """
        if "J" not in self._cache:
            self._check("parallel")
            self._cache["J"] = numerics.lstsq(self.A, self.B, numerics.machine_rtol(self.A))
        return np.array(self._cache["J"])

    @property
    def J_inv(self) -> np.ndarray:
        """Inverse kinematic Jacobian (n_a, m): ``qa_dot = J_inv x_dot``.

        Raises:
            SingularConfigurationError: ``B`` is singular (serial singularity).

        """
        if "J_inv" not in self._cache:
            self._check("serial")
            self._cache["J_inv"] = numerics.lstsq(self.B, self.A, numerics.machine_rtol(self.B))
        return np.array(self._cache["J_inv"])

    @property
    def V(self) -> np.ndarray:
        """Joint velocity map (nv, n_a): ``v = V qa_dot`` (all coordinates, passive included).

        The passive velocities are the minimum-norm solution of the closure equations, so
        internal mobilities (e.g. the spin of the Delta's ball-jointed bars) stay at rest.

        Raises:
            SingularConfigurationError: Parallel singularity (the passive velocities are not
                determined by the actuator rates).

        """
        if "V" not in self._cache:
            self._check("parallel")
            nv = self.Jc.shape[1]
            a, p = self.actuated_v, self.passive_v
            V = np.zeros((nv, a.size))
            V[a, np.arange(a.size)] = 1.0
            if self.Jc.shape[0]:
                V[p] = -numerics.passive_elimination(self.Jc[:, p]).solve(self.Jc[:, a])
            self._cache["V"] = V
        return np.array(self._cache["V"])


_RELATION_COUNTS: dict[tuple[int, tuple[int, ...]], int] = {}


def _relation_count(robot: Robot, rows: np.ndarray) -> int:
    """Number of independent velocity relations between actuators and task, at least ``m``.

    ``n_a + m - mobility``: ``m`` when the actuators control the platform exactly, ``n_a`` under
    redundant actuation (the four-armed Delta: 4 relations between 4 actuator rates and 3
    platform rates). A structural count, taken at ``q_home`` (cached per robot): at a singular
    configuration the missing relations are zero rows of ``A`` and ``B``.
    """
    key = (id(robot), tuple(int(r) for r in rows))
    count = _RELATION_COUNTS.get(key)
    if count is None:
        q = robot.q_home
        Jc = robot.constraints.jacobian(robot.data, q) if robot.constraints.n else None
        Jc = np.zeros((0, robot.nv)) if Jc is None else Jc
        Jx = platform_jacobian(robot, q)[rows]
        rel = _relations(Jc, Jx, np.asarray(robot.actuated_v), np.asarray(robot.passive_v))
        count = max(rows.size, numerics.rank_of(rel.s, SINGULAR_TOL))
        _RELATION_COUNTS[key] = count
        weakref.finalize(robot, _RELATION_COUNTS.pop, key, None)
    return count


@public
def kinematic_models(robot: Robot, q: Sequence[float] | np.ndarray) -> KinematicModels:
    """Parallel matrix ``A``, serial matrix ``B`` and Jacobians of a robot at ``q``.

    Args:
        robot: Any loaded robot with a platform.
        q: Assembled configuration (nq,), e.g. ``pkdyn.forward_geometry(robot, qa).q``.

    Returns:
        The kinematic models; ``J`` / ``J_inv`` are evaluated on access.

    Raises:
        InvalidInputError: Malformed ``q``, not assembled, or no platform frame.

    """
    qq = _checked_q(robot, q)
    rows = np.asarray(robot.task_rows, dtype=int)
    r = _relation_count(robot, rows)  # (at home, once: before the kinematics at q)
    nv = robot.nv
    Jc = robot.constraints.jacobian(robot.data, qq) if robot.constraints.n else np.zeros((0, nv))
    J6 = platform_jacobian(robot, qq)
    Jx = J6[rows]
    a, p = np.asarray(robot.actuated_v), np.asarray(robot.passive_v)
    m, n_a = rows.size, a.size
    rel = _relations(Jc, Jx, a, p)
    # orthonormal basis of the relation row space: its r most significant directions, r the
    # number of relations at home (at least m): m, or n_a under redundant actuation (every
    # actuator rate is then tied to the platform's)
    if rel.R.size:
        _, s, Vt = np.linalg.svd(rel.R, full_matrices=False)
    else:
        s, Vt = np.zeros(0), np.zeros((0, n_a + m))
    # relations beyond the numerical rank (a degenerate mobility) are left as zero rows, which
    # makes both A and B singular
    k = min(r, numerics.rank_of(s, SINGULAR_TOL))
    basis = np.zeros((r, n_a + m))
    basis[:k] = Vt[:k]
    B = basis[:, :n_a]
    A = -basis[:, n_a:]
    gap = float(s[r - 1] / s[0]) if s.size >= r and s[0] > 0 else 0.0
    sA, sB, _ = relation_margins(A, B, *robot_scales(robot, rows))
    return KinematicModels(
        q=qq,
        task=tuple(TASK_NAMES[i] for i in rows),
        actuators=tuple(robot.actuator_names),
        A=A,
        B=B,
        sigma_A=np.linalg.svd(A, compute_uv=False),
        sigma_B=np.linalg.svd(B, compute_uv=False),
        relation_gap=gap,
        margin_A=float(sA[-1]) if sA.size else 1.0,
        margin_B=float(sB[-1]) if sB.size else 1.0,
        Jc=Jc,
        Jx=Jx,
        J6=J6,
        actuated_v=a,
        passive_v=p,
        actuator_units=tuple("m" if pr else "rad" for pr in robot.actuator_prismatic),
    )


def platform_twist(
    robot: Robot, q: Sequence[float] | np.ndarray, qa_dot: Sequence[float] | np.ndarray
) -> np.ndarray:
    """Direct kinematic model: platform velocity from actuator rates.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        qa_dot: Actuator rates in actuator order [rad/s or m/s].

    Returns:
        ``x_dot`` (m,) in the task convention (module docstring) [m/s, rad/s].

    Raises:
        SingularConfigurationError: Parallel singularity.

    """
    km = kinematic_models(robot, q)
    return km.J @ as_finite("qa_dot", qa_dot, km.n_a)


def actuator_rates(
    robot: Robot, q: Sequence[float] | np.ndarray, x_dot: Sequence[float] | np.ndarray
) -> np.ndarray:
    """Inverse kinematic model: actuator rates from a platform velocity.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        x_dot: Platform velocity (m,) in the task convention [m/s, rad/s].

    Returns:
        ``qa_dot`` (n_a,) [rad/s or m/s].

    Raises:
        SingularConfigurationError: Serial singularity.

    """
    km = kinematic_models(robot, q)
    return km.J_inv @ as_finite("x_dot", x_dot, km.m)


def joint_velocities(
    robot: Robot, q: Sequence[float] | np.ndarray, qa_dot: Sequence[float] | np.ndarray
) -> np.ndarray:
    """All joint velocities (nv,) from actuator rates (passive ones minimum-norm).

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        qa_dot: Actuator rates [rad/s or m/s].

    Returns:
        ``v`` (nv,), with ``pin.integrate(model, q, v dt)`` staying assembled to first order.

    Raises:
        SingularConfigurationError: Parallel singularity.

    """
    km = kinematic_models(robot, q)
    return km.V @ as_finite("qa_dot", qa_dot, km.n_a)


def _matrix(M: np.ndarray) -> list[list[float]]:
    return [[float(v) for v in row] for row in np.atleast_2d(M)]


def jacobian_json(robot: Robot, q: Sequence[float] | np.ndarray) -> dict[str, Any]:
    """JSON-ready kinematic models for the CLI.

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).

    Returns:
        ``{"A", "B", "J", "J_inv", "task", "actuators", "cond_A", "cond_B", "twist"}``;
        ``J`` (``J_inv``) is ``None`` at a parallel (serial) singularity.

    """
    return kinematic_models(robot, q).to_json()
