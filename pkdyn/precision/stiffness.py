"""Stiffness and compliance of any loaded robot at a configuration (virtual-joint method).

Convention: the stiffness ``K`` maps a small platform displacement ``d`` [translation of the
reference point; rotation vector; world axes] to the restoring wrench the mechanism exerts
[force; moment about that point; world axes]: ``w = -K d``; a wrench ``w`` applied to the
platform moves it by ``d = C w`` with the compliance ``C = K^-1``. The reference point is the
platform frame's origin unless ``point`` is given (platform-frame coordinates, e.g. a tool tip).
Transported to another point (``d' = T d``, ``T = [[I, -[r]x], [0, I]]`` for the new point at
``r`` from the old one), ``K' = T^-T K T^-1``.

The sources of compliance and the method are those of :mod:`pkdyn.precision.elastic` and
:mod:`pkdyn.precision.condensation`. With the actuators' stiffness alone (rigid links, no other
spring) the result is Gosselin's ``K = J^T K_a J`` (1990), ``J`` the inverse kinematic Jacobian
(``qa_dot = J x_dot``) in this convention (the tests check it against
:attr:`pkdyn.analysis.kinematics.KinematicModels.J_inv`).

- ``K`` (task size ``m``) is the inverse of the compliance restricted to the task components:
  the stiffness along the controlled components with no moment (force) along the others;
  ``K6`` (6 x 6) exists when no platform direction is held rigidly (e.g. the Delta's rotations,
  blocked by its rigid parallelograms: give its links a material for a finite ``K6``).
- Principal stiffnesses: the inverses of the eigenvalues of the compliance's translation block
  (forces only) and rotation block (moments only) among the task components, with their
  directions (world axes), smallest first (the other directions: ``K6``).
- Loaded mode (``loaded=True``): the equilibrium under ``wrench`` (and the weight with
  ``gravity``) is solved (:mod:`pkdyn.precision.equilibrium`) and the tangent stiffness there,
  with the geometric terms of the load, is returned; ``deflection`` is then the nonlinear
  displacement.

Errors: a NaN, negative or zero stiffness, a wrench of the wrong size, a configuration that is
not assembled (:class:`pkdyn.exceptions.InvalidInputError`, naming the value); a parallel
singularity (the platform moves without deforming a spring: the stiffness is undefined) or a
serial one (the platform cannot move along a direction even when the springs deform: the
stiffness is unbounded) raise :class:`pkdyn.exceptions.SingularConfigurationError`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.analysis.kinematics import ASSEMBLY_TOL, TASK_NAMES
from pkdyn.exceptions import InvalidInputError, SingularConfigurationError
from pkdyn.inputs import is_complex
from pkdyn.model.arguments import public
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.precision.condensation import Reduced, compliance, reduce
from pkdyn.precision.elastic import ElasticModel, elastic_model
from pkdyn.precision.equilibrium import loaded_equilibrium, tangent_along
from pkdyn.precision.material import Material
from solvers import numerics

__all__ = [
    "COND_MAX",
    "SERIAL_TOL",
    "Principal",
    "Stiffness",
    "stiffness",
    "stiffness_json",
    "transport",
]

COND_MAX = 1e12
"""Largest condition number of the (scale-aware) 6x6 compliance for a finite ``K6``: beyond, a
platform direction is held rigidly (``K6`` is then ``None``)."""

SERIAL_TOL = 1e-9
"""Smallest relative singular value of the (scale-aware) platform motions the springs allow
along the task: below, the platform cannot move along a task direction (serial singularity)."""


@dataclass(frozen=True, eq=False)  # numpy fields
class Principal:
    """Principal stiffnesses of the translation (or rotation) block, smallest first.

    Attributes:
        stiffness: Principal stiffnesses (k,) [N/m or N m/rad].
        directions: Unit directions (k, 3), world axes (row ``i`` goes with ``stiffness[i]``).

    """

    stiffness: np.ndarray
    directions: np.ndarray


@dataclass(eq=False)  # numpy fields
class Stiffness:
    """Stiffness of a robot at one configuration (see the module docstring).

    Attributes:
        q: Configuration (nq,) (in the loaded mode: at equilibrium, link deflections dropped).
        task: Task component names (``m``).
        point: Reference point, platform frame [m].
        point_world: Reference point, world coordinates [m].
        compliance6: Compliance ``C`` (6, 6) [m/N, m/(N m), rad/N, rad/(N m)].
        K: Task stiffness (m, m) [N/m, N/rad, N m/m, N m/rad].
        K6: Full stiffness (6, 6), or ``None`` when a direction is held rigidly.
        translation: Principal translational stiffnesses (forces only), or ``None`` (no
            translation among the task components).
        rotation: Principal rotational stiffnesses (moments only), or ``None``.
        internal: Internal mobilities without stiffness (e.g. the spin of a Delta's bars).
        wrench: Applied wrench (6,) [N, N m], or ``None``.
        deflection: Platform displacement under ``wrench`` (6,) [m, rad], or ``None``.
        loaded: Whether the load's geometric terms are included.

    """

    q: np.ndarray
    task: tuple[str, ...]
    point: np.ndarray
    point_world: np.ndarray
    compliance6: np.ndarray
    K: np.ndarray
    K6: np.ndarray | None
    translation: Principal | None
    rotation: Principal | None
    internal: int
    wrench: np.ndarray | None = None
    deflection: np.ndarray | None = None
    loaded: bool = False

    @property
    def compliance(self) -> np.ndarray:
        """Task compliance (m, m): the inverse of ``K``."""
        rows = _rows(self.task)
        return np.array(self.compliance6[np.ix_(rows, rows)])

    @property
    def translational_min(self) -> float:
        """Smallest principal translational stiffness [N/m] (``nan`` without translations)."""
        return float(self.translation.stiffness[0]) if self.translation is not None else np.nan

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict: ``K``, ``compliance``, ``principal``, ``deflection`` (with a wrench)."""

        def mat(M: np.ndarray | None) -> list[list[float]] | None:
            return None if M is None else [[float(x) for x in row] for row in np.atleast_2d(M)]

        def principal(p: Principal | None) -> dict[str, Any] | None:
            if p is None:
                return None
            return {"stiffness": [float(x) for x in p.stiffness], "directions": mat(p.directions)}

        out: dict[str, Any] = {
            "task": list(self.task),
            "point": [float(x) for x in self.point],
            "point_world": [float(x) for x in self.point_world],
            "K": mat(self.K),
            "compliance": mat(self.compliance),
            "K6": mat(self.K6),
            "compliance6": mat(self.compliance6),
            "principal": {
                "translation": principal(self.translation),
                "rotation": principal(self.rotation),
            },
            "internal_mobilities": self.internal,
            "loaded": self.loaded,
            "convention": "w = -K d; d: [translation of the point, rotation vector], w: [force, "
            "moment about the point], world axes; K in N/m, N/rad, N m/m, N m/rad",
        }
        if self.deflection is not None and self.wrench is not None:
            out["wrench"] = [float(x) for x in self.wrench]
            out["deflection"] = [float(x) for x in self.deflection]
        return out


def _rows(task: Sequence[str]) -> list[int]:
    return [TASK_NAMES.index(t) for t in task]


def transport(K: np.ndarray, r: np.ndarray) -> np.ndarray:
    """A 6x6 stiffness moved to a point at ``r`` from its reference point (world axes) [m].

    Args:
        K: Stiffness (6, 6) at the old point.
        r: New point minus old point (3,) [m].

    Returns:
        ``T^-T K T^-1`` with ``T = [[I, -[r]x], [0, I]]`` (the new point's displacement is
        ``T d``).

    """
    from pkdyn.inputs import matrix, vector

    K = matrix("K", K, 6, 6, bound=np.inf)
    r = vector("r", r, 3, "m")
    T_inv = np.eye(6)
    T_inv[:3, 3:] = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    return np.asarray(T_inv.T @ K @ T_inv)


def _wrench(robot: Robot, wrench: Sequence[float] | np.ndarray | None) -> np.ndarray | None:
    if wrench is None:
        return None
    from pkdyn.inputs import MAX_MAGNITUDE

    rows = np.asarray(robot.task_rows, dtype=int)
    if isinstance(wrench, str | bytes | dict) or is_complex(wrench):
        raise InvalidInputError("wrench", f"expected numbers [N, N m], got {wrench!r:.60}")
    try:
        arr = np.atleast_1d(np.asarray(wrench, dtype=float)).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidInputError(
            "wrench", f"expected numbers [N, N m], got {wrench!r:.60}"
        ) from None
    if arr.size not in (6, rows.size):
        raise InvalidInputError(
            "wrench",
            f"{arr.size} values {np.array2string(arr, precision=4)}: expected 6 (fx fy fz mx my "
            f"mz) or the {rows.size} task components ({' '.join(TASK_NAMES[i] for i in rows)})",
        )
    if not np.all(np.isfinite(arr)):
        k = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise InvalidInputError("wrench", f"component {k + 1} is {arr[k]}: give finite values")
    if np.any(np.abs(arr) > MAX_MAGNITUDE):
        k = int(np.argmax(np.abs(arr)))
        raise InvalidInputError(
            "wrench",
            f"component {k + 1} = {arr[k]:g} is beyond any plausible force or moment "
            f"(at most {MAX_MAGNITUDE:g} N, N m)",
        )
    if arr.size == 6:
        return arr
    out = np.zeros(6)
    out[rows] = arr
    return out


def _principal(C6: np.ndarray, rows: list[int], block: tuple[int, int, int]) -> Principal | None:
    idx = [i for i in rows if i in block]
    if not idx:
        return None
    w, V = np.linalg.eigh(C6[np.ix_(idx, idx)])
    order = np.argsort(w)[::-1]  # largest compliance: smallest stiffness first
    D = np.zeros((len(idx), 3))
    for k, i in enumerate(idx):
        D[:, i - block[0]] = V[k, order]
    with np.errstate(divide="ignore"):
        return Principal(1.0 / w[order], D)


def _scaled(C: np.ndarray, rows: list[int], L: float) -> np.ndarray:
    W = np.array([1.0 if i < 3 else L for i in rows])
    return np.asarray(W[:, None] * C * W[None, :])


def _check_serial(red: Reduced, rows: list[int], L: float, name: str) -> None:
    """Raise when the allowed motions cannot move the platform along a task direction."""
    S = np.array([1.0 / L if i < 3 else 1.0 for i in rows])
    Jt = S[:, None] * red.Jz[rows]
    if numerics.rank(Jt, SERIAL_TOL) < len(rows):
        raise SingularConfigurationError(
            "serial",
            f"{name}: the platform cannot move along a task direction even when the springs "
            "deform (serial singularity, or nothing compliant along it): the stiffness is "
            "unbounded here",
        )


def _check_assembled(robot: Robot, q: np.ndarray) -> None:
    if robot.closure_set.nc == 0:
        return
    res = float(np.max(np.abs(robot.closure_set.residual(robot.data, q))))
    if res > ASSEMBLY_TOL:
        raise InvalidInputError(
            "q",
            f"not an assembled configuration of {robot.name} (closure residual {res:.3g}); "
            "obtain q from pkdyn.forward_geometry, inverse_geometry or project",
        )


def check_compliant(em: ElasticModel) -> None:
    """Refuse a model with nothing compliant (every actuator rigid, no spring, rigid links).

    Raises:
        InvalidInputError: Nothing deforms: the stiffness is infinite, not undefined.

    """
    if not em.links and not np.any(em.spring_stiffness() > 0.0):
        raise InvalidInputError(
            "actuator_stiffness",
            f"{em.base.name}: every actuator is rigid (inf) and nothing else is compliant (no "
            "joint spring, rigid links): the stiffness is infinite; give finite actuator "
            "stiffnesses or a material for the links",
        )


def _point(point: Sequence[float] | np.ndarray | None, robot: Robot | None = None) -> np.ndarray:
    """The reference point (3,) [m], checked: finite, within 100 robot sizes of the platform."""
    if point is None:
        return np.zeros(3)
    from pkdyn.inputs import vector

    reach = 100.0 * robot.length_scale if robot is not None else 1e9
    return vector("point", point, 3, "m", bound=reach)


def _result(
    em: ElasticModel,
    red: Reduced,
    q: np.ndarray,
    point: np.ndarray,
    wrench: np.ndarray | None,
    deflection: np.ndarray | None,
    loaded: bool,
) -> Stiffness:
    base = em.base
    C6, internal = compliance(em, red)
    rows = [int(i) for i in base.task_rows]
    L = base.length_scale
    _check_serial(red, rows, L, base.name)
    Ct = C6[np.ix_(rows, rows)]
    if numerics.rank(_scaled(Ct, rows, L), 1e-15) < len(rows):
        raise SingularConfigurationError(
            "parallel",
            f"{base.name}: the compliance is numerically singular here: a singular "
            "configuration, the stiffness is not defined",
        )
    K = np.linalg.inv(Ct)
    full = numerics.rank(_scaled(C6, list(range(6)), L), 1.0 / COND_MAX) == 6
    K6 = np.linalg.inv(C6) if full else None
    if wrench is not None and deflection is None:
        deflection = C6 @ wrench
    return Stiffness(
        q=q,
        task=tuple(TASK_NAMES[i] for i in rows),
        point=point,
        point_world=red.point,
        compliance6=C6,
        K=K,
        K6=K6,
        translation=_principal(C6, rows, (0, 1, 2)),
        rotation=_principal(C6, rows, (3, 4, 5)),
        internal=internal,
        wrench=wrench,
        deflection=deflection,
        loaded=loaded,
    )


@public
def stiffness(
    robot: Robot | ElasticModel,
    q: Sequence[float] | np.ndarray,
    actuator_stiffness: float | Sequence[float] | np.ndarray | None = None,
    *,
    material: str | Material | None = None,
    links: bool = True,
    point: Sequence[float] | np.ndarray | None = None,
    wrench: Sequence[float] | np.ndarray | None = None,
    loaded: bool = False,
    gravity: bool = False,
) -> Stiffness:
    """Stiffness, compliance, principal stiffnesses and deflection at a configuration.

    Args:
        robot: The robot (with its geometry when links are beams), or an
            :class:`~pkdyn.precision.elastic.ElasticModel` already built (then
            ``actuator_stiffness``, ``material`` and ``links`` are not used).
        q: Assembled configuration (nq,), e.g. ``pkdyn.inverse_geometry(robot, pose).q``.
        actuator_stiffness: Joint-side stiffness, one or one per actuator [N m/rad or N/m]
            (``inf``: rigid); ``None``: the description's ``<pkdyn:stiffness>``.
        material: Material of the slender links (preset name or
            :class:`~pkdyn.precision.material.Material`); ``None``: the description's, if any.
        links: Model the links' compliance (``False``: rigid links).
        point: Reference point, platform frame [m] (default: the platform frame's origin).
        wrench: Wrench on the platform (6: force [N], moment about the point [N m], world
            axes; or the task components): its deflection is reported.
        loaded: Solve the equilibrium under ``wrench`` (and the weight with ``gravity``) and
            include the load's geometric terms.
        gravity: With ``loaded``, the robot's weight is part of the load.

    Returns:
        The stiffness.

    Raises:
        InvalidInputError: A bad stiffness, material, point or wrench, a configuration that is
            not assembled, no platform, or ``loaded`` without a load.
        SingularConfigurationError: At a parallel singularity (stiffness undefined) or a serial
            one (stiffness unbounded).

    """
    from pkdyn.inputs import flag, instance

    instance("robot", robot, (Robot, ElasticModel), "a Robot (pkdyn.load) or an ElasticModel")
    loaded, gravity, links = flag("loaded", loaded), flag("gravity", gravity), flag("links", links)
    base = robot.base if isinstance(robot, ElasticModel) else robot
    if base.platform_frame is None:
        raise InvalidInputError("robot", f"{base.name} declares no platform frame")
    qq = as_finite("q", q, base.nq)
    _check_assembled(base, qq)
    p = _point(point, base)
    w = _wrench(base, wrench)
    if loaded and w is None and not gravity:
        raise InvalidInputError("loaded", "the loaded mode needs a wrench (or gravity=True)")
    em = (
        robot
        if isinstance(robot, ElasticModel)
        else elastic_model(robot, actuator_stiffness, material, links)
    )
    check_compliant(em)
    q_ext = em.embed(qq)
    if not loaded:
        return _result(em, reduce(em, q_ext, p), qq, p, w, None, False)
    load = np.zeros(6) if w is None else w
    eq = loaded_equilibrium(em, q_ext, p, load, gravity)
    qa_rest = np.array(q_ext[np.asarray(em.robot.actuated_q)])

    def tangent(N: np.ndarray) -> np.ndarray:
        return tangent_along(em, eq.q, eq.lambdas, qa_rest, p, load, gravity, N)

    red = reduce(em, eq.q, p, tangent)
    _, oMf0 = _frame(em, q_ext)
    M1 = red.placement
    d = np.concatenate(
        [
            M1.translation + M1.rotation @ p - (oMf0.translation + oMf0.rotation @ p),
            pin.log3(M1.rotation @ oMf0.rotation.T),
        ]
    )
    return _result(em, red, em.restrict(eq.q), p, w, d, True)


def _frame(em: ElasticModel, q: np.ndarray) -> tuple[int, pin.SE3]:
    r = em.robot
    fid = r.platform_frame
    assert fid is not None
    pin.framesForwardKinematics(r.model, r.data, q)
    return fid, pin.SE3(r.data.oMf[fid])


@public
def stiffness_json(robot: Robot, q: np.ndarray, **kwargs: Any) -> dict[str, Any]:
    """JSON-ready :func:`stiffness` for the CLI (keys of :meth:`Stiffness.to_json`)."""
    return stiffness(robot, q, **kwargs).to_json()
