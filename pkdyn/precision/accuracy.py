"""Accuracy: error budget of the platform pose for actuator and geometric errors.

At a configuration, the first-order sensitivities of :mod:`pkdyn.precision.sensitivity`
(``dx = J dqa + K dp``, pose errors in the task convention: platform origin displacement in
world axes [m], small rotation in the platform frame [rad]) turn error bounds into pose errors:

- **actuator errors** (:func:`actuator_errors`): a resolution ``r`` (the reading is rounded:
  error within ``+-r/2``) and a backlash ``b`` (the joint rests anywhere within ``+-b/2`` of the
  reading) per actuator [rad or m], each uniform and independent: half-width
  ``e = (r + b) / 2``, standard deviation ``sqrt(r^2 + b^2) / sqrt(12)``;
- **geometric errors** (:func:`geometric_errors`): a tolerance ``t`` per parameter of a
  :class:`~pkdyn.precision.parameters.ParameterModel` (placement twists, family shortcuts or the
  family builder's dimensions), each within ``+-t`` (``uniform``: standard deviation
  ``t / sqrt(3)``) or normal with ``t`` = 3 standard deviations (``normal``).

For each, per pose component: the **worst case** ``sum_k |A_ik| e_k`` (exact: a vertex of the
error box), the worst-case position error ``max |A_pos e|`` over the box (the largest of
``sum_k e_k |u . a_k|`` over unit directions ``u``: searched over 2,000 directions and refined
to a vertex), and the **RMS** ``sqrt(sum_k A_ik^2 s_k^2)``. Geometric errors are ranked by
their share of the position variance (:attr:`GeometricAccuracy.ranking`).

:func:`monte_carlo` checks the first order: it draws errors, rebuilds the robot with them
(:func:`pkdyn.precision.perturbation.perturbed`, or the family builder for family parameters)
and solves its forward geometry at the same actuator readings. :func:`accuracy_map` maps the
position errors over a grid of platform positions; :data:`DEFAULT_RESOLUTION` is the actuator
error of the ``error_max`` design metric.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.assembly import forward_geometry, inverse_geometry
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import (
    ParameterModel,
    built_placements,
    family_values,
    placements,
)
from pkdyn.precision.perturbation import perturbed, with_placements
from pkdyn.precision.sensitivity import pose_sensitivity
from pkdyn.progress import progress
from pkdyn.threads import one_blas_thread

__all__ = [
    "DEFAULT_RESOLUTION",
    "DISTRIBUTIONS",
    "AccuracyMap",
    "ActuatorAccuracy",
    "GeometricAccuracy",
    "MonteCarlo",
    "accuracy_map",
    "actuator_errors",
    "default_resolution",
    "largest_position_error",
    "geometric_errors",
    "monte_carlo",
    "pose_error",
    "worst_norm",
]

MAX_ERROR = 1e3
"""Largest resolution, backlash or tolerance accepted [m, rad or -]: first-order error budgets
are about small errors; beyond it an input is a unit or typing mistake."""

DEFAULT_RESOLUTION = (1e-4, 1e-5)
"""Actuator error assumed by the ``error_max`` design metric: (revolute [rad], prismatic [m])
resolution, about a 16-bit encoder on a revolute joint and a 10 um linear scale."""

DISTRIBUTIONS = ("uniform", "normal")
"""Error distributions: within ``+-t`` (uniform), or normal with ``t`` = 3 standard deviations."""

_GAP_TOL = 1e-9
"""Closure gap per unit parameter [m or rad per unit] above which a parameter is one the
mechanism cannot absorb (it would not assemble without deforming)."""


def pose_error(reference: pin.SE3, M: pin.SE3) -> np.ndarray:
    """Pose error (6,) of ``M`` from ``reference``: origin displacement and rotation.

    The displacement in world axes, the rotation in the reference frame.

    Args:
        reference: The nominal platform placement.
        M: The actual placement.

    Returns:
        ``[p - p0; log3(R0^T R)]`` [m, rad].

    """
    return np.concatenate(
        [M.translation - reference.translation, pin.log3(reference.rotation.T @ M.rotation)]
    )


def worst_norm(A: np.ndarray, half: np.ndarray, directions: int = 2000) -> float:
    """Largest ``|A e|`` over the box ``|e_k| <= half_k`` (A with 2 or 3 rows).

    The maximum of a convex function over a box is at a vertex; ``max |A e| = max_u sum_k half_k
    |u . a_k|`` over unit vectors ``u``, searched on a Fibonacci sphere and refined by the
    fixed-point ascent ``u <- A e(u) / |A e(u)|`` (each step moves to a better vertex).

    Args:
        A: Matrix (d, n), d <= 3.
        half: Half-widths (n,) >= 0.
        directions: Number of search directions.

    Returns:
        The worst-case norm.

    """
    A = np.asarray(A, dtype=float)
    if A.size == 0:
        return 0.0
    d = A.shape[0]
    k = np.arange(directions) + 0.5
    if d == 3:
        phi = np.arccos(1.0 - 2.0 * k / directions)
        theta = np.pi * (1.0 + 5.0**0.5) * k
        U = np.column_stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)])
    elif d == 2:
        t = 2.0 * np.pi * k / directions
        U = np.column_stack([np.cos(t), np.sin(t)])
    else:
        return float(np.sum(np.abs(A) @ half))
    score = np.abs(U @ A) @ half
    best = 0.0
    for i in np.argsort(score)[-8:]:  # refine the best few directions to vertices
        u = U[i]
        for _ in range(50):
            e = half * np.sign(u @ A)
            v = A @ e
            n = float(np.linalg.norm(v))
            if n == 0.0:
                break
            u_new = v / n
            if np.allclose(u_new, u, atol=1e-14):
                break
            u = u_new
        best = max(best, float(np.linalg.norm(A @ (half * np.sign(u @ A)))))
    return best


@dataclass
class _Budget:
    """Worst case and RMS of a linear error map ``dx = A e``."""

    worst: np.ndarray  # (6,) per component [m, rad]
    rms: np.ndarray  # (6,) per component
    position_worst: float  # [m]
    orientation_worst: float  # [rad]

    @property
    def position_rms(self) -> float:
        """RMS of the position error's norm [m]: ``sqrt(sum of the x, y, z variances)``."""
        return float(np.sqrt(np.sum(self.rms[:3] ** 2)))

    @property
    def orientation_rms(self) -> float:
        """RMS of the rotation error's norm [rad]."""
        return float(np.sqrt(np.sum(self.rms[3:] ** 2)))


def _budget(A: np.ndarray, half: np.ndarray, std: np.ndarray) -> _Budget:
    return _Budget(
        worst=np.abs(A) @ half,
        rms=np.sqrt((A**2) @ (std**2)),
        position_worst=worst_norm(A[:3], half),
        orientation_worst=worst_norm(A[3:], half),
    )


def _per_actuator(
    robot: Robot, name: str, value: float | Sequence[float] | np.ndarray
) -> np.ndarray:
    """One value per actuator (a single value applies to all), finite and >= 0."""
    from pkdyn.inputs import vector

    n_a = len(robot.actuators)
    arr = vector(name, value, None, "rad or m", bound=MAX_ERROR)
    if arr.size not in (1, n_a):
        raise InvalidInputError(name, f"expected {n_a} values (or one for all), got {arr.size}")
    if arr.size == 1:
        arr = np.full(n_a, float(arr[0]))
    if np.any(arr < 0.0):
        k = int(np.flatnonzero(arr < 0.0)[0])
        raise InvalidInputError(
            name, f"{robot.actuators[k].name}: {arr[k]:g} is negative; give >= 0"
        )
    return arr


@dataclass
class ActuatorAccuracy(_Budget):
    """Pose error caused by actuator resolution and backlash at one configuration.

    Attributes:
        worst: Worst-case error per pose component (6,) [m, rad].
        rms: RMS error per pose component (6,) [m, rad].
        position_worst: Worst-case position error norm [m].
        orientation_worst: Worst-case rotation error norm [rad].
        J: Pose per actuator coordinate (6, n_a).
        half_width: Actuator error half-widths ``(r + b) / 2`` (n_a,) [rad or m].
        std: Actuator error standard deviations (n_a,) [rad or m].

    """

    J: np.ndarray = field(default_factory=lambda: np.zeros((6, 0)))
    half_width: np.ndarray = field(default_factory=lambda: np.zeros(0))
    std: np.ndarray = field(default_factory=lambda: np.zeros(0))


def actuator_errors(
    robot: Robot,
    q: Sequence[float] | np.ndarray,
    resolution: float | Sequence[float] | np.ndarray = 0.0,
    backlash: float | Sequence[float] | np.ndarray = 0.0,
) -> ActuatorAccuracy:
    """Platform pose error from actuator resolution and backlash (module docstring).

    Args:
        robot: The robot.
        q: Assembled configuration (nq,).
        resolution: Per actuator (or one for all) [rad or m], >= 0.
        backlash: Per actuator (or one for all) [rad or m], >= 0.

    Returns:
        Worst-case and RMS pose errors.

    Raises:
        InvalidInputError: Negative, NaN or mis-sized errors.
        SingularConfigurationError: A parallel singularity (unbounded errors).

    """
    r = _per_actuator(robot, "resolution", resolution)
    b = _per_actuator(robot, "backlash", backlash)
    J = pose_sensitivity(robot, q).J
    half = 0.5 * (r + b)
    std = np.sqrt(r**2 + b**2) / np.sqrt(12.0)
    base = _budget(J, half, std)
    return ActuatorAccuracy(**base.__dict__, J=J, half_width=half, std=std)


def _std(tol: np.ndarray, distribution: str) -> np.ndarray:
    if distribution not in DISTRIBUTIONS:
        raise InvalidInputError(
            "distribution", f"'{distribution}': use {' or '.join(DISTRIBUTIONS)}"
        )
    return tol / np.sqrt(3.0) if distribution == "uniform" else tol / 3.0


def _tolerances(
    model: ParameterModel, tolerance: float | Sequence[float] | np.ndarray
) -> np.ndarray:
    from pkdyn.inputs import instance, vector

    instance("model", model, ParameterModel, "a ParameterModel (parameter_model(robot))")
    t = vector("tolerance", tolerance, None, "m, rad or -", bound=MAX_ERROR)
    if t.size not in (1, model.size):
        raise InvalidInputError(
            "tolerance", f"expected {model.size} values (or one for all), got {t.size}"
        )
    if t.size == 1:
        t = np.full(model.size, float(t[0]))
    if np.any(t < 0.0):
        k = int(np.flatnonzero(t < 0.0)[0])
        raise InvalidInputError("tolerance", f"{model.names[k]}: {t[k]:g} is negative; give >= 0")
    return t


@dataclass
class GeometricAccuracy(_Budget):
    """Pose error caused by geometric tolerances at one configuration.

    Attributes:
        worst: Worst-case error per pose component (6,) [m, rad].
        rms: RMS error per pose component (6,) [m, rad].
        position_worst: Worst-case position error norm [m].
        orientation_worst: Worst-case rotation error norm [rad].
        K: Pose per parameter (6, n_par).
        names: Parameter names (n_par,).
        tolerance: Tolerances (n_par,) [m, rad, -].
        std: Standard deviations (n_par,).
        not_assembling: Parameters the mechanism cannot absorb (over-constrained: it would not
            assemble with them without deforming); left out of the budget.

    """

    K: np.ndarray = field(default_factory=lambda: np.zeros((6, 0)))
    names: tuple[str, ...] = ()
    tolerance: np.ndarray = field(default_factory=lambda: np.zeros(0))
    std: np.ndarray = field(default_factory=lambda: np.zeros(0))
    not_assembling: tuple[str, ...] = ()

    def ranking(self, top: int | None = None) -> list[dict[str, Any]]:
        """Parameters by their share of the position variance, largest first.

        Args:
            top: Keep this many (default all).

        Returns:
            ``{"name", "tolerance", "position_rms", "position_worst", "orientation_rms",
            "share"}`` per parameter: its RMS and worst-case contributions [m, rad] and its
            share of the position variance (sums to 1).

        """
        pos = np.linalg.norm(self.K[:3], axis=0)
        rot = np.linalg.norm(self.K[3:], axis=0)
        var = (pos * self.std) ** 2
        total = float(np.sum(var)) or 1.0
        order = np.argsort(-var, kind="stable")[: top if top is not None else None]
        return [
            {
                "name": self.names[k],
                "tolerance": float(self.tolerance[k]),
                "position_rms": float(pos[k] * self.std[k]),
                "position_worst": float(pos[k] * self.tolerance[k]),
                "orientation_rms": float(rot[k] * self.std[k]),
                "share": float(var[k] / total),
            }
            for k in order
        ]


def geometric_errors(
    robot: Robot,
    q: Sequence[float] | np.ndarray,
    model: ParameterModel,
    tolerance: float | Sequence[float] | np.ndarray,
    distribution: str = "uniform",
) -> GeometricAccuracy:
    """Platform pose error from geometric tolerances, first order (module docstring).

    Args:
        robot: The nominal robot (the model's).
        q: Assembled configuration (nq,).
        model: The parameter model.
        tolerance: One per parameter (or one for all) [m, rad, -]; see
            :meth:`ParameterModel.tolerances` for lengths and angles.
        distribution: ``uniform`` or ``normal``.

    Returns:
        Worst-case and RMS pose errors and the ranking of the tolerances.

    Raises:
        InvalidInputError: Malformed tolerances or distribution.
        SingularConfigurationError: A parallel singularity.

    """
    t = _tolerances(model, tolerance)
    std = _std(t, distribution)
    s = pose_sensitivity(robot, q, model)
    gap = np.max(np.abs(s.gap), axis=0, initial=0.0) if s.gap.size else np.zeros(model.size)
    bad = gap > _GAP_TOL
    K = np.where(bad[None, :], 0.0, s.K)
    t_eff = np.where(bad, 0.0, t)
    std_eff = np.where(bad, 0.0, std)
    base = _budget(K, t_eff, std_eff)
    return GeometricAccuracy(
        **base.__dict__,
        K=K,
        names=model.names,
        tolerance=t,
        std=std_eff,
        not_assembling=tuple(n for n, b in zip(model.names, bad, strict=True) if b),
    )


@dataclass
class MonteCarlo:
    """Pose errors of robots drawn with random errors, solved exactly.

    Attributes:
        errors: Pose error of each sample (N, 6) [m, rad].
        failed: Samples that could not be assembled at the actuator readings.

    """

    errors: np.ndarray
    failed: int = 0

    @property
    def rms(self) -> np.ndarray:
        """RMS per pose component (6,) [m, rad]."""
        return np.sqrt(np.mean(self.errors**2, axis=0))

    @property
    def position_rms(self) -> float:
        """RMS of the position error's norm [m]."""
        return float(np.sqrt(np.mean(np.sum(self.errors[:, :3] ** 2, axis=1))))

    @property
    def position_max(self) -> float:
        """Largest position error norm among the samples [m]."""
        return float(np.max(np.linalg.norm(self.errors[:, :3], axis=1), initial=0.0))

    @property
    def orientation_rms(self) -> float:
        """RMS of the rotation error's norm [rad]."""
        return float(np.sqrt(np.mean(np.sum(self.errors[:, 3:] ** 2, axis=1))))


def _draw(rng: np.random.Generator, t: np.ndarray, distribution: str) -> np.ndarray:
    if distribution == "uniform":
        return rng.uniform(-1.0, 1.0, t.size) * t
    return rng.normal(0.0, 1.0, t.size) * (t / 3.0)


@one_blas_thread
def monte_carlo(
    robot: Robot,
    q: Sequence[float] | np.ndarray,
    model: ParameterModel,
    tolerance: float | Sequence[float] | np.ndarray,
    samples: int = 200,
    distribution: str = "uniform",
    seed: int = 0,
    progress_bar: bool | None = None,
) -> MonteCarlo:
    """Pose errors of ``samples`` robots with random geometric errors, solved exactly.

    Each sample draws the parameters, rebuilds the robot (family parameters: the family builder
    run with them; other models: :func:`~pkdyn.precision.perturbation.perturbed`) and solves its
    forward geometry at the actuator readings of ``q`` (gains applied). Parameters the mechanism
    cannot absorb (:attr:`GeometricAccuracy.not_assembling`) are left at zero.

    Args:
        robot: The nominal robot.
        q: Assembled configuration (nq,): the actuator readings and the nominal pose.
        model: The parameter model.
        tolerance: One per parameter (or one for all).
        samples: Number of robots (at most 100,000).
        distribution: ``uniform`` or ``normal``.
        seed: Random seed.
        progress_bar: Force the progress bar on or off (default: on a terminal).

    Returns:
        The sampled pose errors.

    Raises:
        InvalidInputError: Malformed tolerances, distribution or sample count.

    """
    from pkdyn.inputs import count
    from pkdyn.inputs import seed as _seed

    qq = as_finite("q", q, robot.nq)
    t = _tolerances(model, tolerance)
    _std(t, distribution)
    try:
        samples = count("samples", samples, 1, 100_000)
    except InvalidInputError:
        raise InvalidInputError("samples", f"{samples}: give 1 to 100,000") from None
    seed = _seed("seed", seed)
    gap = pose_sensitivity(robot, qq, model).gap
    if gap.size:
        t = np.where(np.max(np.abs(gap), axis=0) > _GAP_TOL, 0.0, t)
    nominal = robot.platform_placement(qq)
    readings = qq[robot.actuated_q]
    rng = np.random.default_rng(seed)
    errors, failed = [], 0
    family = model.kind == "family parameters"
    for _ in progress(range(int(samples)), "Monte Carlo", "robot", progress_bar, min_items=50):
        dp = _draw(rng, t, distribution)
        try:
            if family:
                sample = _family_sample(robot, model, dp)
                qa = readings * (1.0 + model.gains(dp))
            else:
                pert = perturbed(robot, model, dp)
                sample, qa = pert.robot, pert.joint_coordinates(readings)
            res = forward_geometry(sample, qa, q_init=qq, check_limits=False)
        except PkdynError:
            failed += 1
            continue
        assert res.placement is not None
        errors.append(pose_error(nominal, res.placement))
    return MonteCarlo(np.array(errors).reshape(-1, 6), failed)


def _family_sample(robot: Robot, model: ParameterModel, dp: np.ndarray) -> Robot:
    """The robot its family builder gives with the model's parameters moved by ``dp``."""
    params = family_values(robot, model, model.nominal + dp)
    return with_placements(robot, placements(robot), built_placements(robot, params))


@dataclass
class AccuracyMap:
    """Position errors over a grid of platform positions.

    Attributes:
        P: Platform positions (N, 3) [m].
        valid: Reached, regular positions (N,).
        actuator_worst: Worst-case position error of the actuator errors (N,) [m] (NaN where
            not valid).
        actuator_rms: Its RMS (N,) [m].
        geometric_worst: Worst-case position error of the tolerances (N,) [m] (NaN without a
            parameter model).
        geometric_rms: Its RMS (N,) [m].
        shape: Grid shape (for plots), or ``(N,)``.
        axes: Names of the grid's two varying coordinates (for plots), e.g. ``("x", "y")``.

    """

    P: np.ndarray
    valid: np.ndarray
    actuator_worst: np.ndarray
    actuator_rms: np.ndarray
    geometric_worst: np.ndarray
    geometric_rms: np.ndarray
    shape: tuple[int, ...]
    axes: tuple[str, str] = ("x", "y")

    def field(self, name: str) -> np.ndarray:
        """One of the error fields reshaped to the grid."""
        if name not in ("actuator_worst", "actuator_rms", "geometric_worst", "geometric_rms"):
            raise InvalidInputError(
                "field",
                f"'{name}': use actuator_worst, actuator_rms, geometric_worst or geometric_rms",
            )
        return np.asarray(getattr(self, name)).reshape(self.shape)


def slice_grid(
    center: Sequence[float] | np.ndarray, axes: str, extent: float, samples: int
) -> tuple[np.ndarray, tuple[int, int]]:
    """A square grid of positions in a coordinate plane through ``center``.

    Args:
        center: Centre of the grid (3,) [m].
        axes: The two varying coordinates, ``xy``, ``xz`` or ``yz``.
        extent: Half-width of the square [m].
        samples: Samples per side (2..201).

    Returns:
        Positions (samples^2, 3) [m] and the grid shape.

    """
    from pkdyn.inputs import count, positive, vector

    c = vector("center", center, 3, "m")
    if axes not in ("xy", "xz", "yz"):
        raise InvalidInputError("axes", f"'{axes}': use xy, xz or yz")
    try:
        samples = count("samples", samples, 2, 201)
    except InvalidInputError:
        raise InvalidInputError("samples", f"{samples}: give 2 to 201 per side") from None
    try:
        extent = positive("extent", extent, "m", bound=1e3)
    except InvalidInputError:
        raise InvalidInputError(
            "extent", f"{extent}: give a half-width > 0 m (at most 1e3)"
        ) from None
    i, j = ("xyz".index(axes[0]), "xyz".index(axes[1]))
    u = np.linspace(-extent, extent, int(samples))
    U, V = np.meshgrid(u, u, indexing="ij")
    P = np.tile(c, (U.size, 1))
    P[:, i] += U.ravel()
    P[:, j] += V.ravel()
    return P, (int(samples), int(samples))


@one_blas_thread
def accuracy_map(
    robot: Robot,
    positions: np.ndarray,
    resolution: float | Sequence[float] | np.ndarray = 0.0,
    backlash: float | Sequence[float] | np.ndarray = 0.0,
    model: ParameterModel | None = None,
    tolerance: float | Sequence[float] | np.ndarray = 0.0,
    rotation: np.ndarray | None = None,
    shape: tuple[int, ...] | None = None,
    axes: tuple[str, str] = ("x", "y"),
    progress_bar: bool | None = None,
) -> AccuracyMap:
    """Worst-case and RMS position errors over platform positions (e.g. :func:`slice_grid`).

    Each position is reached by the inverse geometric model (from the previous solution, then
    from home), within the actuator limits; unreachable or singular positions are not valid.

    Args:
        robot: The robot.
        positions: Platform positions (N, 3) [m].
        resolution: Actuator resolution (per actuator or one) [rad or m].
        backlash: Actuator backlash (per actuator or one) [rad or m].
        model: Parameter model of the geometric tolerances (``None``: actuator errors only).
        tolerance: Tolerances of ``model``'s parameters.
        rotation: Platform orientation (3, 3) (default: the home orientation).
        shape: Grid shape of the positions (default ``(N,)``).
        axes: Names of the two varying coordinates (plots).
        progress_bar: Force the progress bar on or off.

    Returns:
        The map.

    """
    if isinstance(positions, str | bytes | dict):
        raise InvalidInputError("positions", "expected finite (N, 3) positions [m]")
    try:
        P = np.atleast_2d(np.asarray(positions, dtype=float))
    except (TypeError, ValueError):
        raise InvalidInputError("positions", "expected finite (N, 3) positions [m]") from None
    if P.ndim != 2 or P.shape[1] != 3 or not np.all(np.isfinite(P)):
        raise InvalidInputError("positions", "expected finite (N, 3) positions [m]")
    if P.shape[0] > 100_000:
        raise InvalidInputError("positions", f"{P.shape[0]} positions: give at most 100,000")
    R = (
        robot.platform_placement(robot.q_home).rotation
        if rotation is None
        else np.asarray(rotation)
    )
    n = len(P)
    out = {k: np.full(n, np.nan) for k in ("aw", "ar", "gw", "gr")}
    valid = np.zeros(n, dtype=bool)
    q_prev = robot.q_home
    for k in progress(range(n), "accuracy map", "pose", progress_bar, min_items=200):
        q = None
        for q0 in (q_prev, robot.q_home):
            try:
                q = inverse_geometry(robot, pin.SE3(R, P[k]), q_init=q0).q
                break
            except PkdynError:
                continue
        if q is None:
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                act = actuator_errors(robot, q, resolution, backlash)
                if model is not None:
                    geo = geometric_errors(robot, q, model, tolerance)
        except PkdynError:
            continue
        q_prev = q
        valid[k] = True
        out["aw"][k], out["ar"][k] = act.position_worst, act.position_rms
        if model is not None:
            out["gw"][k], out["gr"][k] = geo.position_worst, geo.position_rms
    return AccuracyMap(P, valid, out["aw"], out["ar"], out["gw"], out["gr"], shape or (n,), axes)


def default_resolution(robot: Robot) -> np.ndarray:
    """:data:`DEFAULT_RESOLUTION` per actuator (n_a,) [rad or m]: revolute or prismatic."""
    return np.where(robot.actuator_prismatic, DEFAULT_RESOLUTION[1], DEFAULT_RESOLUTION[0])


def largest_position_error(
    robot: Robot,
    positions: np.ndarray,
    rotations: np.ndarray | None = None,
    resolution: float | Sequence[float] | np.ndarray | None = None,
    backlash: float | Sequence[float] | np.ndarray = 0.0,
) -> float:
    """Largest worst-case position error of actuator errors over platform poses [m].

    The ``error_max`` design metric: each pose reached by the inverse geometric model (the
    family's closed form when it has one, else from the previous pose), then
    :func:`actuator_errors`' worst-case position error.

    Args:
        robot: The robot.
        positions: Platform positions (N, 3) [m].
        rotations: Platform orientations (N, 3, 3) (default: identity).
        resolution: Actuator resolution (default :func:`default_resolution`).
        backlash: Actuator backlash [rad or m].

    Returns:
        The largest error [m] over the poses reached.

    Raises:
        InvalidInputError: No pose could be reached, or a singular one (unbounded error).

    """
    P = np.atleast_2d(np.asarray(positions, dtype=float))
    R = np.broadcast_to(np.eye(3), (len(P), 3, 3)) if rotations is None else rotations
    res = default_resolution(robot) if resolution is None else resolution
    worst, reached = 0.0, 0
    q_prev = None
    for p, rot in zip(P, R, strict=True):
        q = None
        for q0 in (None, q_prev):
            try:
                q = inverse_geometry(robot, pin.SE3(np.asarray(rot), p), q_init=q0).q
                break
            except PkdynError:
                continue
        if q is None:
            continue
        q_prev = q
        reached += 1
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            worst = max(worst, actuator_errors(robot, q, res, backlash).position_worst)
    if reached == 0:
        raise InvalidInputError("positions", "no pose was reached: no position error to report")
    return worst
