"""Error budgets of the platform pose: actuator errors, geometric tolerances, their ranking.

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
their share of the position variance (:meth:`GeometricAccuracy.ranking`,
:class:`ToleranceRanking`). Each budget says whether it holds at its pose
(:func:`pkdyn.precision.validity.budget_validity`: refused at a parallel singularity, not valid
at a serial one, warnings near either). :func:`accuracy_budget` puts both budgets (and a Monte
Carlo check, :mod:`pkdyn.precision.monte_carlo`) in one result, naming the values it assumed.
:data:`DEFAULT_RESOLUTION` is the actuator error of the ``error_max`` design metric
(:func:`largest_position_error`).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.robot import Robot
from pkdyn.precision._format import chop
from pkdyn.precision.grid import reach
from pkdyn.precision.parameters import ParameterModel
from pkdyn.precision.sensitivity import pose_sensitivity
from pkdyn.precision.validity import Flagged, PrecisionWarning, Validity, budget_validity
from pkdyn.results import Result, jsonable
from pkdyn.threads import one_blas_thread
from pkdyn.units import quantity

__all__ = [
    "DEFAULT_RESOLUTION",
    "DEFAULT_TOLERANCE",
    "DISTRIBUTIONS",
    "MAX_ERROR",
    "VERTEX_COLUMNS",
    "ActuatorAccuracy",
    "Budget",
    "GeometricAccuracy",
    "ToleranceRanking",
    "actuator_errors",
    "box_worst",
    "closed_form_position_worst",
    "closed_form_sensitivity",
    "default_resolution",
    "geometric_errors",
    "largest_position_error",
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

DEFAULT_TOLERANCE = (5e-5, 5e-4)
"""Geometric tolerances assumed when none is given: (lengths [m], angles [rad]), +-0.05 mm and
+-0.5 mrad, a careful machining (the ``accuracy`` command names them when it uses them)."""


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


VERTEX_COLUMNS = 12
"""Up to this many columns, :func:`worst_norm` evaluates every vertex of the box (2^(n-1))."""


def _signs(n: int) -> np.ndarray:
    """The sign vectors of half the box's vertices (2^(n-1), n): the others are their opposites."""
    k = np.arange(2 ** max(n - 1, 0))
    bits = (k[:, None] >> np.arange(n - 1)[None, :]) & 1
    return np.concatenate([1.0 - 2.0 * bits, np.ones((k.size, 1))], axis=1)[:, :n]


def box_worst(A: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Largest ``|A_i e|`` over the box ``|e_k| <= half_k``, every vertex evaluated.

    Args:
        A: Matrices (..., d, n), n <= :data:`VERTEX_COLUMNS`.
        half: Half-widths (n,) >= 0.

    Returns:
        The worst-case norms (...).

    """
    A = np.asarray(A, dtype=float)
    E = _signs(A.shape[-1]) * np.asarray(half, dtype=float)[None, :]  # (m, n) vertices
    V = np.matmul(A, E.T)  # (..., d, m)
    return np.sqrt(np.max(np.sum(V * V, axis=-2), axis=-1))


def worst_norm(A: np.ndarray, half: np.ndarray, directions: int = 2000) -> float:
    """Largest ``|A e|`` over the box ``|e_k| <= half_k`` (A with 2 or 3 rows).

    The maximum of a convex function over a box is at a vertex: up to
    :data:`VERTEX_COLUMNS` columns every vertex is evaluated (:func:`box_worst`). Beyond,
    ``max |A e| = max_u sum_k half_k |u . a_k|`` over unit vectors ``u`` is searched on a
    Fibonacci sphere and refined by the fixed-point ascent ``u <- A e(u) / |A e(u)|`` (each
    step moves to a better vertex).

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
    if A.shape[1] <= VERTEX_COLUMNS:
        return float(box_worst(A, half))
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


_COMPONENTS = ("x", "y", "z", "rx", "ry", "rz")
_UNITS = ("m", "m", "m", "rad", "rad", "rad")


@dataclass
class Budget(Flagged, Result):
    """Worst case and RMS of a linear error map ``dx = A e`` (the two budgets' base).

    Attributes:
        worst: Worst-case error per pose component (6,) [m, rad].
        rms: RMS error per pose component (6,) [m, rad].
        position_worst: Worst-case position error norm [m].
        orientation_worst: Worst-case rotation error norm [rad].
        validity: ``valid`` and ``warnings`` at this pose (:mod:`pkdyn.precision.validity`).
        length: The robot's size [m] (rotations judged through it in tables).

    """

    worst: np.ndarray
    rms: np.ndarray
    position_worst: float
    orientation_worst: float
    validity: Validity = field(default_factory=Validity)
    length: float = 1.0

    @property
    def position_rms(self) -> float:
        """RMS of the position error's norm [m]: ``sqrt(sum of the x, y, z variances)``."""
        return float(np.sqrt(np.sum(self.rms[:3] ** 2)))

    @property
    def orientation_rms(self) -> float:
        """RMS of the rotation error's norm [rad]."""
        return float(np.sqrt(np.sum(self.rms[3:] ** 2)))

    def to_json(self) -> dict[str, Any]:
        """``worst_case``, ``rms`` per component, position and orientation norms, flags."""
        return {
            "pose_components": list(_COMPONENTS),
            "worst_case": jsonable(self.worst),
            "rms": jsonable(self.rms),
            "position_worst": self.position_worst,
            "position_rms": self.position_rms,
            "orientation_worst": self.orientation_worst,
            "orientation_rms": self.orientation_rms,
            **self.validity.to_json(),
        }

    def _summary(self) -> str:
        scale = max(self.position_worst / self.length, self.orientation_worst)
        orientation_worst, orientation_rms = (
            float(x) for x in chop(np.array([self.orientation_worst, self.orientation_rms]), scale)
        )
        return (
            f"worst-case position {quantity(self.position_worst, 'm')}, RMS "
            f"{quantity(self.position_rms, 'm')}; rotation "
            f"{quantity(orientation_worst, 'rad')} worst-case, RMS "
            f"{quantity(orientation_rms, 'rad')}"
        )

    def _components(self) -> str:
        S = np.array([1.0 / self.length] * 3 + [1.0] * 3)
        scale = float(np.max(np.abs(self.worst) * S, initial=0.0))
        worst, rms = chop(self.worst * S, scale) / S, chop(self.rms * S, scale) / S
        return "  per component, worst case (RMS): " + ", ".join(
            f"{c} {quantity(w, u)} ({quantity(r, u)})"
            for c, w, r, u in zip(_COMPONENTS, worst, rms, _UNITS, strict=True)
        )

    def table(self) -> str:
        """The budget's figures with their units."""
        return "\n".join([self._summary(), self._components(), *self.validity.lines()])


def _budget(A: np.ndarray, half: np.ndarray, std: np.ndarray) -> dict[str, Any]:
    return {
        "worst": np.abs(A) @ half,
        "rms": np.sqrt((A**2) @ (std**2)),
        "position_worst": worst_norm(A[:3], half),
        "orientation_worst": worst_norm(A[3:], half),
    }


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
class ActuatorAccuracy(Budget):
    """Pose error caused by actuator resolution and backlash at one configuration.

    Attributes:
        worst: Worst-case error per pose component (6,) [m, rad].
        rms: RMS error per pose component (6,) [m, rad].
        position_worst: Worst-case position error norm [m].
        orientation_worst: Worst-case rotation error norm [rad].
        J: Pose per actuator coordinate (6, n_a).
        half_width: Actuator error half-widths ``(r + b) / 2`` (n_a,) [rad or m].
        std: Actuator error standard deviations (n_a,) [rad or m].
        resolution: Resolutions (n_a,) [rad or m].
        backlash: Backlashes (n_a,) [rad or m].
        units: Each actuator's unit (``rad`` or ``m``).

    """

    J: np.ndarray = field(default_factory=lambda: np.zeros((6, 0)))
    half_width: np.ndarray = field(default_factory=lambda: np.zeros(0))
    std: np.ndarray = field(default_factory=lambda: np.zeros(0))
    resolution: np.ndarray = field(default_factory=lambda: np.zeros(0))
    backlash: np.ndarray = field(default_factory=lambda: np.zeros(0))
    units: tuple[str, ...] = ()

    def to_json(self) -> dict[str, Any]:
        """The budget (:meth:`Budget.to_json`), ``J``, the errors assumed."""
        return {
            **super().to_json(),
            "J": jsonable(self.J),
            "resolution": jsonable(self.resolution),
            "backlash": jsonable(self.backlash),
            "half_width": jsonable(self.half_width),
        }

    def headline(self) -> str:
        """One line: the actuator errors assumed and the position and rotation figures."""
        errs = ", ".join(
            f"{quantity(r, u)} + {quantity(b, u)}"
            for r, b, u in zip(self.resolution, self.backlash, self.units, strict=True)
        )
        return f"actuator errors (resolution + backlash per actuator: {errs}): {self._summary()}"

    def table(self) -> str:
        """The actuator errors assumed and the budget."""
        return "\n".join([self.headline(), self._components(), *self.validity.lines()])


@one_blas_thread
@public
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
        Worst-case and RMS pose errors, flagged where the first order does not hold.

    Raises:
        InvalidInputError: Negative, NaN or mis-sized errors.
        SingularConfigurationError: A parallel singularity (unbounded errors).

    """
    r = _per_actuator(robot, "resolution", resolution)
    b = _per_actuator(robot, "backlash", backlash)
    s = pose_sensitivity(robot, q)
    validity = budget_validity(robot, s.q)
    validity.warn()
    return _actuator_budget(robot, s.J, r, b, validity)


def _actuator_budget(
    robot: Robot, J: np.ndarray, r: np.ndarray, b: np.ndarray, validity: Validity
) -> ActuatorAccuracy:
    half = 0.5 * (r + b)
    std = np.sqrt(r**2 + b**2) / np.sqrt(12.0)
    units = tuple("m" if p else "rad" for p in robot.actuator_prismatic)
    return ActuatorAccuracy(
        **_budget(J, half, std),
        validity=validity,
        length=robot.length_scale,
        J=J,
        half_width=half,
        std=std,
        resolution=r,
        backlash=b,
        units=units,
    )


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
class ToleranceRanking(Result):
    """Parameters by their share of the position variance, largest first.

    Attributes:
        entries: ``{"name", "unit", "tolerance", "position_rms", "position_worst",
            "orientation_rms", "share"}`` per parameter [m, rad; share of the variance, sums to
            1 over all parameters].
        total: Number of parameters ranked (``entries`` may hold fewer: the top ones).

    """

    entries: list[dict[str, Any]]
    total: int

    def to_json(self) -> dict[str, Any]:
        """``{"ranking": entries, "parameters": total}``."""
        return {"ranking": jsonable(self.entries), "parameters": self.total}

    def table(self) -> str:
        """One line per parameter: its RMS contribution and share."""
        lines = [
            f"largest contributions (share of the position variance, {self.total} parameters):"
        ]
        for e in self.entries:
            tol = quantity(e["tolerance"], e["unit"] if e["unit"] != "-" else "")
            lines.append(
                f"  {e['name']} (+-{tol}): {quantity(e['position_rms'], 'm')} RMS "
                f"({100 * e['share']:.1f} %)"
            )
        return "\n".join(lines)


@dataclass
class GeometricAccuracy(Budget):
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
        units: Parameter units (n_par,).
        model: The parameter model's kind.
        distribution: ``uniform`` or ``normal``.
        top: Parameters :meth:`table` and :meth:`to_json` rank (``None``: all).

    """

    K: np.ndarray = field(default_factory=lambda: np.zeros((6, 0)))
    names: tuple[str, ...] = ()
    tolerance: np.ndarray = field(default_factory=lambda: np.zeros(0))
    std: np.ndarray = field(default_factory=lambda: np.zeros(0))
    not_assembling: tuple[str, ...] = ()
    units: tuple[str, ...] = ()
    model: str = ""
    distribution: str = "uniform"
    top: int | None = 10

    def ranking(self, top: int | None = None) -> list[dict[str, Any]]:
        """Parameters by their share of the position variance, largest first.

        Args:
            top: Keep this many (default all).

        Returns:
            ``{"name", "tolerance", "position_rms", "position_worst", "orientation_rms",
            "share"}`` per parameter: its RMS and worst-case contributions [m, rad] and its
            share of the position variance (sums to 1).

        """
        if top is not None:
            from pkdyn.inputs import count

            top = count("top", top, 1)
        pos = np.linalg.norm(self.K[:3], axis=0)
        rot = np.linalg.norm(self.K[3:], axis=0)
        var = (pos * self.std) ** 2
        total = float(np.sum(var)) or 1.0
        order = np.argsort(-var, kind="stable")[: top if top is not None else None]
        units = self.units or ("",) * len(self.names)
        return [
            {
                "name": self.names[k],
                "unit": units[k],
                "tolerance": float(self.tolerance[k]),
                "position_rms": float(pos[k] * self.std[k]),
                "position_worst": float(pos[k] * self.tolerance[k]),
                "orientation_rms": float(rot[k] * self.std[k]),
                "share": float(var[k] / total),
            }
            for k in order
        ]

    def ranked(self, top: int | None = None) -> ToleranceRanking:
        """:meth:`ranking` as a result (``table()``, ``to_json()``, ``plot()``)."""
        return ToleranceRanking(self.ranking(top), len(self.names))

    def to_json(self) -> dict[str, Any]:
        """The budget (:meth:`Budget.to_json`), the model, the ranking, ``not_assembling``."""
        return {
            **super().to_json(),
            "model": self.model,
            "parameters": len(self.names),
            "distribution": self.distribution,
            "ranking": jsonable(self.ranking(self.top)),
            "not_assembling": list(self.not_assembling),
        }

    def headline(self) -> str:
        """One line: the model and the position and rotation figures."""
        return (
            f"geometric tolerances ({self.model}, {len(self.names)} parameters, "
            f"{self.distribution}): {self._summary()}"
        )

    def _left_out(self) -> list[str]:
        if not self.not_assembling:
            return []
        more = len(self.not_assembling) - 8
        return [
            "left out (the mechanism cannot absorb them without deforming): "
            + ", ".join(self.not_assembling[:8])
            + (f" and {more} more" if more > 0 else "")
        ]

    def table(self) -> str:
        """The budget, then the ranking of the tolerances."""
        lines = [self.headline(), self._components()]
        if self.top != 0:
            lines.append(self.ranked(self.top).table())
        return "\n".join(lines + self._left_out() + self.validity.lines())


@one_blas_thread
@public
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
        Worst-case and RMS pose errors and the ranking of the tolerances, flagged where the
        first order does not hold.

    Raises:
        InvalidInputError: Malformed tolerances or distribution.
        SingularConfigurationError: A parallel singularity.

    """
    t = _tolerances(model, tolerance)
    std = _std(t, distribution)
    s = pose_sensitivity(robot, q, model)
    validity = budget_validity(robot, s.q)
    validity.warn()
    return _geometric_budget(model, s, t, std, distribution, validity, robot.length_scale)


def _geometric_budget(
    model: ParameterModel,
    s: Any,
    t: np.ndarray,
    std: np.ndarray,
    distribution: str,
    validity: Validity,
    length: float = 1.0,
) -> GeometricAccuracy:
    gap = np.max(np.abs(s.gap), axis=0, initial=0.0) if s.gap.size else np.zeros(model.size)
    bad = gap > _GAP_TOL
    K = np.where(bad[None, :], 0.0, s.K)
    t_eff = np.where(bad, 0.0, t)
    std_eff = np.where(bad, 0.0, std)
    return GeometricAccuracy(
        **_budget(K, t_eff, std_eff),
        validity=validity,
        length=length,
        K=K,
        names=model.names,
        tolerance=t,
        std=std_eff,
        not_assembling=tuple(n for n, b in zip(model.names, bad, strict=True) if b),
        units=model.units,
        model=model.kind,
        distribution=distribution,
    )


def default_resolution(robot: Robot) -> np.ndarray:
    """:data:`DEFAULT_RESOLUTION` per actuator (n_a,) [rad or m]: revolute or prismatic."""
    return np.where(robot.actuator_prismatic, DEFAULT_RESOLUTION[1], DEFAULT_RESOLUTION[0])


@one_blas_thread
def largest_position_error(
    robot: Robot,
    positions: np.ndarray,
    rotations: np.ndarray | None = None,
    resolution: float | Sequence[float] | np.ndarray | None = None,
    backlash: float | Sequence[float] | np.ndarray = 0.0,
    reached: bool = False,
) -> float:
    """Largest worst-case position error of actuator errors over platform poses [m].

    The ``error_max`` design metric: each pose reached by the inverse geometric model (the
    family's closed form when it has one, else from the previous pose), then
    :func:`actuator_errors`' worst-case position error. The library Delta and Gough-Stewart
    take their first-order sensitivity in closed form, every pose at once
    (:func:`closed_form_position_worst`; the general path where it declines).

    Args:
        robot: The robot.
        positions: Platform positions (N, 3) [m].
        rotations: Platform orientations (N, 3, 3) (default: identity).
        resolution: Actuator resolution (default :func:`default_resolution`).
        backlash: Actuator backlash [rad or m].
        reached: The poses are known to be reached within the limits (a required workspace's
            check): the closed forms need not check the limits again.

    Returns:
        The largest error [m] over the poses reached.

    Raises:
        InvalidInputError: No pose could be reached, or a singular one (unbounded error).

    """
    P = np.atleast_2d(np.asarray(positions, dtype=float))
    R = np.broadcast_to(np.eye(3), (len(P), 3, 3)) if rotations is None else rotations
    res = default_resolution(robot) if resolution is None else resolution
    r = _per_actuator(robot, "resolution", res)
    b = _per_actuator(robot, "backlash", backlash)
    if P.shape[0]:
        fast = closed_form_position_worst(robot, P, np.asarray(R), 0.5 * (r + b), reached)
        if fast is not None:
            return float(np.max(fast))
    worst, reached_n = 0.0, 0
    q_prev = None
    for p, rot in zip(P, R, strict=True):
        q = reach(robot, pin.SE3(np.asarray(rot), p), (None, q_prev))
        if q is None:
            continue
        q_prev = q
        reached_n += 1
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PrecisionWarning)
            worst = max(worst, actuator_errors(robot, q, res, backlash).position_worst)
    if reached_n == 0:
        raise InvalidInputError("positions", "no pose was reached: no position error to report")
    return worst


def closed_form_position_worst(
    robot: Robot, P: np.ndarray, R: np.ndarray, half: np.ndarray, reached: bool = False
) -> np.ndarray | None:
    """Worst-case position error per pose (N,) [m] from the families' closed-form Jacobians.

    The position rows of :func:`closed_form_sensitivity` over the box of half-widths ``half``
    (:func:`box_worst`). ``None`` where the closed forms decline (the general path decides).

    Args:
        robot: The robot.
        P: Platform positions (N, 3) [m].
        R: Platform orientations (N, 3, 3) or (3, 3).
        half: Actuator error half-widths (n_a,) [rad or m].
        reached: The poses are known to be reached within the limits.

    Returns:
        The worst-case position errors, or ``None``.

    """
    J = closed_form_sensitivity(robot, P, R, reached)
    return None if J is None else box_worst(J, half)


def closed_form_sensitivity(
    robot: Robot, P: np.ndarray, R: np.ndarray, reached: bool = False
) -> np.ndarray | None:
    """Platform position per actuator coordinate (N, 3, n_a) of the library families, closed form.

    The first-order map of actuator errors to the platform position is the inverse of the
    closed form's inverse Jacobian (:mod:`pkdyn.precision.vectorised`: the Delta's Clavel rows
    read from the loaded model, the Gough-Stewart's leg rows), every pose at once: the position
    rows of :func:`pkdyn.precision.sensitivity.pose_sensitivity`'s ``J``. ``None`` (the general
    path decides, naming what is wrong) for other robots, and where a pose is out of reach or
    within a margin of the closed forms' singularities.

    Args:
        robot: The robot.
        P: Platform positions (N, 3) [m].
        R: Platform orientations (N, 3, 3) or (3, 3).
        reached: The poses are known to be reached within the limits (else the Delta's are
            checked; the Gough-Stewart's are left to the general path).

    Returns:
        The sensitivities [m/rad or m/m], or ``None``.

    """
    from pkdyn.precision.vectorised import _delta_jacobian, _gs_rows, inv3, vectorised

    P = np.atleast_2d(np.asarray(P, dtype=float))
    kind = vectorised(robot)
    if kind == "delta":
        from pkdyn.dynamics.delta import DeltaDynamics

        if not np.allclose(R, np.eye(3)):
            return None
        dd = DeltaDynamics(robot)
        ok, Jinv, _, _, _, margin = _delta_jacobian(dd, P)
        if not (ok.all() and np.all(margin > 10.0 * _NEAR_MARGIN)):
            return None
        if not reached:
            from pkdyn.closed_form.delta import inverse

            alpha, inside = inverse(dd.params, P - dd.f_off)
            lim = np.all((alpha >= dd.lo) & (alpha <= dd.hi), axis=1)
            if not np.all(inside & lim & _delta_mode(dd.params, P - dd.f_off)):
                return None
        J, _ = inv3(Jinv)
        return np.asarray(J)
    if kind == "gough_stewart" and reached:
        rows = _gs_rows(robot.params.a, robot.params.b, P, R, None)
        s = np.linalg.svd(rows, compute_uv=False)
        if not np.all(s[:, -1] > 10.0 * _NEAR_MARGIN * s[:, 0]):
            return None
        return np.asarray(np.linalg.inv(rows)[:, :3, :])
    return None


_NEAR_MARGIN = 1e-3
"""Relative margin to a singularity below which the closed forms leave a pose to the general
path (which flags or refuses it by the rule of :mod:`pkdyn.precision.validity`)."""


def _delta_mode(params: Any, P: np.ndarray) -> np.ndarray:
    from pkdyn.model.families import FAMILIES

    return np.asarray(FAMILIES["delta"]._module().in_working_mode(params, P))
