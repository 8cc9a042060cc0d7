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
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError, SingularConfigurationError
from pkdyn.model.arguments import public
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import PLATFORM_HINT, Robot
from solvers import FramePoseTask, numerics

__all__ = [
    "TASK_NAMES",
    "SINGULAR_TOL",
    "NEAR_SERIAL_TOL",
    "NEAR_SINGULAR_TOL",
    "COND_MAX",
    "ASSEMBLY_TOL",
    "NearSingularityWarning",
    "KinematicModels",
    "kinematic_models",
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
def platform_jacobian(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Full 6D platform Jacobian (6, nv) in the task convention, kinematics at ``q`` computed.

    Rows: linear velocity of the platform frame origin in world axes [m/s], then angular
    velocity in the platform frame [rad/s] (``FramePoseTask`` rows at zero error).

    Args:
        robot: The robot (must declare a platform).
        q: Configuration (nq,).

    Returns:
        Jacobian (6, nv) with respect to increments applied by ``pin.integrate``.

    """
    if robot.platform_frame is None:
        raise InvalidInputError(
            "robot", f"{robot.name} declares no platform frame; {PLATFORM_HINT}"
        )
    pin.computeJointJacobians(robot.model, robot.data, q)
    oMf = pin.updateFramePlacement(robot.model, robot.data, robot.platform_frame)
    task = FramePoseTask(robot.model, robot.platform_frame, np.arange(6))
    task.target = pin.SE3(oMf)
    return task.residual_and_jacobian(robot.data)[1]


def _checked_q(robot: Robot, q: Sequence[float] | np.ndarray) -> np.ndarray:
    qq = as_finite("q", q, robot.nq)
    if robot.closure_set.nc:
        res = float(np.max(np.abs(robot.closure_set.residual(robot.data, qq))))
        if res > ASSEMBLY_TOL:
            raise InvalidInputError(
                "q",
                f"not an assembled configuration of {robot.name} (closure residual {res:.3g}); "
                "obtain q from pkdyn.forward_geometry, inverse_geometry or project",
            )
    return qq


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
class KinematicModels:
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
    _cache: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

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
                V[p] = -numerics.lstsq(self.Jc[:, p], self.Jc[:, a], 1e-10)
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
        Jc = robot.closure_set.jacobian(robot.data, q) if robot.closure_set.nc else None
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
    Jc = robot.closure_set.jacobian(robot.data, qq) if robot.closure_set.nc else np.zeros((0, nv))
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
    km = kinematic_models(robot, q)
    out: dict[str, Any] = {
        "A": _matrix(km.A),
        "B": _matrix(km.B),
        "task": list(km.task),
        "actuators": list(km.actuators),
        "cond_A": km.cond_A,
        "cond_B": km.cond_B,
        "twist": "linear: platform origin velocity, world axes [m/s]; "
        "angular: platform frame [rad/s]",
    }
    for key in ("J", "J_inv"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NearSingularityWarning)
            try:
                out[key] = _matrix(getattr(km, key))
            except SingularConfigurationError:
                out[key] = None
    return out
