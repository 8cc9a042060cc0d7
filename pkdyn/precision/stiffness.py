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
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.analysis.kinematics import TASK_NAMES, check_assembled
from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.precision._format import chop
from pkdyn.precision.condensation import Reduced, compliance, reduce
from pkdyn.precision.elastic import ElasticModel, elastic_model
from pkdyn.precision.equilibrium import loaded_equilibrium, tangent_along
from pkdyn.precision.material import Material
from pkdyn.precision.validity import (
    UNBOUNDED_COMPLIANCE,
    Flagged,
    Validity,
    stiffness_check,
)
from pkdyn.results import Result, jsonable
from pkdyn.threads import one_blas_thread
from pkdyn.units import quantity, vector
from solvers import numerics

__all__ = [
    "COND_MAX",
    "Principal",
    "Stiffness",
    "stiffness",
    "stiffness_json",
    "transport",
]

COND_MAX = 1e12
"""Largest condition number of the (scale-aware) 6x6 compliance for a finite ``K6``: beyond, a
platform direction is held rigidly (``K6`` is then ``None``)."""


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
class Stiffness(Flagged, Result):
    """Stiffness of a robot at one configuration (see the module docstring).

    Attributes:
        q: Configuration (nq,) (in the loaded mode: at equilibrium, link deflections dropped).
        task: Task component names (``m``).
        point: Reference point, platform frame [m].
        point_world: Reference point, world coordinates [m].
        compliance6: Compliance ``C`` (6, 6) [m/N, m/(N m), rad/N, rad/(N m)].
        K: Task stiffness (m, m) [N/m, N/rad, N m/m, N m/rad]; ``inf`` along the directions
            held rigidly by rigid actuators (:attr:`rigid_directions`).
        K6: Full stiffness (6, 6), or ``None`` when a direction is held rigidly.
        translation: Principal translational stiffnesses (forces only), or ``None`` (no
            translation among the task components).
        rotation: Principal rotational stiffnesses (moments only), or ``None``.
        internal: Internal mobilities without stiffness (e.g. the spin of a Delta's bars).
        wrench: Applied wrench (6,) [N, N m], or ``None``.
        deflection: Platform displacement under ``wrench`` (6,) [m, rad], or ``None``.
        loaded: Whether the load's geometric terms are included.
        rigid_directions: Unit task directions (k, m) held rigidly by rigid (``inf``) actuators:
            infinite stiffness, zero compliance along them.
        validity: ``valid`` and ``warnings`` (:mod:`pkdyn.precision.validity`).
        robot: The robot's name.
        links: Names of the compliant links.
        actuator_stiffness: Each actuator's stiffness (n_a,) [N m/rad or N/m] (``inf``: rigid).
        length: The robot's size [m] (rotations and moments judged through it in tables).

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
    rigid_directions: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    validity: Validity = field(default_factory=Validity)
    robot: str = ""
    links: tuple[str, ...] = ()
    actuator_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    length: float = 1.0

    @property
    def rigid(self) -> bool:
        """Every task direction is held rigidly (rigid actuators, nothing else compliant)."""
        return bool(self.rigid_directions.shape[0] == len(self.task) and len(self.task) > 0)

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
        """JSON values: ``K``, ``compliance``, ``principal``, ``deflection``, ``valid``...

        Infinite stiffnesses (rigid directions) are ``null``, with ``rigid`` and
        ``rigid_directions`` saying which.
        """

        def principal(p: Principal | None) -> dict[str, Any] | None:
            if p is None:
                return None
            return {"stiffness": jsonable(p.stiffness), "directions": jsonable(p.directions)}

        out: dict[str, Any] = {
            "robot": self.robot,
            "task": list(self.task),
            "point": jsonable(self.point),
            "point_world": jsonable(self.point_world),
            "K": jsonable(self.K),
            "compliance": jsonable(self.compliance),
            "K6": jsonable(self.K6),
            "compliance6": jsonable(self.compliance6),
            "principal": {
                "translation": principal(self.translation),
                "rotation": principal(self.rotation),
            },
            "internal_mobilities": self.internal,
            "loaded": self.loaded,
            "rigid": self.rigid,
            "rigid_directions": jsonable(self.rigid_directions),
            **self.validity.to_json(),
            "links": list(self.links),
            "actuator_stiffness": jsonable(self.actuator_stiffness),
            "convention": "w = -K d; d: [translation of the point, rotation vector], w: [force, "
            "moment about the point], world axes; K in N/m, N/rad, N m/m, N m/rad; null: "
            "infinite (rigid)",
        }
        if self.deflection is not None and self.wrench is not None:
            out["wrench"] = jsonable(self.wrench)
            out["deflection"] = jsonable(self.deflection)
        return out

    def table(self) -> str:
        """``K`` with its units, the principal stiffnesses, the deflection, the flags."""
        head = f"stiffness of {self.robot or 'the robot'}"
        head += f" at the point {vector(self.point, 'm')} of the platform frame"
        if self.loaded:
            head += " (loaded: tangent stiffness at the equilibrium under the load)"
        lines = [head]
        if self.rigid:
            lines.append(
                "rigid: every actuator is held rigidly (inf) and nothing else is compliant: "
                "infinite stiffness, zero compliance, no deflection"
            )
        else:
            lines.append(f"K ({' '.join(self.task)}), rows and columns in that order:")
            lines += _matrix_lines(self.K, self.task, self.length)
        for name, p, unit in (
            ("translational", self.translation, "N/m"),
            ("rotational", self.rotation, "N m/rad"),
        ):
            if p is None or self.rigid:
                continue
            parts = [
                f"{quantity(k, unit)} along {vector(chop(d, 1.0), '', 3)}"
                for k, d in zip(p.stiffness, p.directions, strict=True)
            ]
            lines.append(f"principal {name} stiffness (world axes): " + "; ".join(parts))
        if self.rigid_directions.shape[0] and not self.rigid:
            for d in self.rigid_directions:
                lines.append(f"rigid along {vector(chop(d, 1.0), '', 3)} ({' '.join(self.task)}): "
                             "held by rigid actuators")  # fmt: skip
        if self.internal:
            lines.append(f"internal mobilities without stiffness: {self.internal}")
        if self.deflection is not None:
            scale = float(np.abs(self.deflection[:3]).max()) / self.length
            d = chop(self.deflection, max(scale, float(np.abs(self.deflection[3:]).max())))
            lines.append(
                f"deflection: {', '.join(quantity(x, 'm') for x in d[:3])} (translation); "
                f"{', '.join(quantity(x, 'rad') for x in d[3:])} (rotation)"
            )
        if self.links:
            lines.append(f"compliant links: {', '.join(self.links)}")
        return "\n".join(lines + self.validity.lines())


_UNITS = {
    (True, True): "N/m",
    (True, False): "N/rad",
    (False, True): "N m/m",
    (False, False): "N m/rad",
}


def _matrix_lines(K: np.ndarray, task: Sequence[str], length: float) -> list[str]:
    """Rows of a stiffness matrix, each entry with its unit (force/moment per length/angle).

    Entries are judged in the robot's scale (moments and rotations through its size
    ``length``): round-off below it prints as zero.
    """
    S = np.array([1.0 if not t.startswith("r") else 1.0 / length for t in task])
    finite = np.isfinite(K)
    Ks = np.where(finite, K, 0.0) * np.outer(S, S)
    scale = float(np.abs(Ks).max()) if Ks.size else 0.0
    K = np.where(finite & (np.abs(Ks) < 1e-12 * scale), 0.0, K)
    out = []
    for i, ti in enumerate(task):
        cells = []
        for j, tj in enumerate(task):
            unit = _UNITS[(not ti.startswith("r"), not tj.startswith("r"))]
            cells.append(quantity(float(K[i, j]), unit))
        out.append(f"  {ti}: " + ", ".join(cells))
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
    from pkdyn.inputs import MAX_MAGNITUDE, number_array

    rows = np.asarray(robot.task_rows, dtype=int)
    arr = number_array("wrench", wrench, "numbers [N, N m]")
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


def _principal(
    C6: np.ndarray, rows: list[int], block: tuple[int, int, int], cut: float = 0.0
) -> Principal | None:
    """Principal stiffnesses of a block; compliances at or below ``cut``: rigid (``inf``)."""
    idx = [i for i in rows if i in block]
    if not idx:
        return None
    w, V = np.linalg.eigh(C6[np.ix_(idx, idx)])
    w = np.where(w <= cut, 0.0, w)
    order = np.argsort(w)[::-1]  # largest compliance: smallest stiffness first
    D = np.zeros((len(idx), 3))
    for k, i in enumerate(idx):
        D[:, i - block[0]] = V[k, order]
    with np.errstate(divide="ignore"):
        return Principal(1.0 / w[order], D)


def _scaled(C: np.ndarray, rows: list[int], L: float) -> np.ndarray:
    W = np.array([1.0 if i < 3 else L for i in rows])
    return np.asarray(W[:, None] * C * W[None, :])


def nothing_compliant(em: ElasticModel) -> bool:
    """Every actuator rigid (``inf``), no spring, rigid links: the robot is rigid."""
    return not em.links and not np.any(em.spring_stiffness() > 0.0)


def _point(point: Sequence[float] | np.ndarray | None, robot: Robot | None = None) -> np.ndarray:
    """The reference point (3,) [m], checked: finite, within 100 robot sizes of the platform."""
    if point is None:
        return np.zeros(3)
    from pkdyn.inputs import vector

    reach = 100.0 * robot.length_scale if robot is not None else 1e9
    return vector("point", point, 3, "m", bound=reach)


def _with_rigid(
    Ct: np.ndarray, rows: list[int], L: float, k_ref: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(K, rigid directions)``: the inverse of ``Ct`` with ``inf`` along held directions.

    In the scaled compliance ``C' = k_ref S C S`` (:mod:`pkdyn.precision.validity`), the
    directions at the cut-off are held rigidly; ``K`` is the inverse on the others, ``inf``
    (with the sign of the rigid projector) where a held direction enters.
    """
    S = np.array([1.0 / L if i < 3 else 1.0 for i in rows])
    w, V = np.linalg.eigh(0.5 * k_ref * np.outer(S, S) * (Ct + Ct.T))
    held = w <= UNBOUNDED_COMPLIANCE * max(float(w[-1]), 1.0)
    Ks = k_ref * (V[:, ~held] / w[~held]) @ V[:, ~held].T  # the inverse of C' times k_ref
    P = V[:, held] @ V[:, held].T
    Ks = np.where(np.abs(P) > 1e-9, np.where(P > 0.0, np.inf, -np.inf), Ks)
    K = Ks * np.outer(S, S)
    D = V[:, held].T / S[None, :]
    D /= np.maximum(np.linalg.norm(D, axis=1, keepdims=True), 1e-300)
    return K, D


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
    validity, rigid, k_ref = stiffness_check(em, red.q, point, C6, q)
    Ct = C6[np.ix_(rows, rows)]
    cut = 0.0  # compliance [rad/(N m)] at or below which a direction is rigid
    if rigid.shape[0]:
        cut = UNBOUNDED_COMPLIANCE * max(float(np.abs(C6).max()) / L**2, 1.0 / max(k_ref, 1e-300))
        K, rigid = _with_rigid(Ct, rows, L, k_ref)
        K6 = None
    else:
        K = np.linalg.inv(Ct)
        full = numerics.rank(_scaled(C6, list(range(6)), L), 1.0 / COND_MAX) == 6
        K6 = np.linalg.inv(C6) if full else None
    if wrench is not None and deflection is None:
        deflection = C6 @ wrench
    validity.warn(stacklevel=4)
    return Stiffness(
        q=q,
        task=tuple(TASK_NAMES[i] for i in rows),
        point=point,
        point_world=red.point,
        compliance6=C6,
        K=K,
        K6=K6,
        translation=_principal(C6, rows, (0, 1, 2), cut * L**2),
        rotation=_principal(C6, rows, (3, 4, 5), cut),
        internal=internal,
        wrench=wrench,
        deflection=deflection,
        loaded=loaded,
        rigid_directions=rigid,
        validity=validity,
        robot=base.name,
        links=tuple(dict.fromkeys(lc.link for lc in em.links)),
        actuator_stiffness=np.array(em.actuator_stiffness, dtype=float),
        length=L,
    )


def prepared(
    robot: Robot | ElasticModel,
    q: Sequence[float] | np.ndarray,
    actuator_stiffness: float | Sequence[float] | np.ndarray | None,
    material: str | Material | None,
    links: bool,
    shear: bool,
    point: Sequence[float] | np.ndarray | None,
    wrench: Sequence[float] | np.ndarray | None,
) -> tuple[ElasticModel, np.ndarray, np.ndarray, np.ndarray | None]:
    """The inputs of :func:`stiffness` and :func:`pkdyn.precision.modes.modes`, checked.

    Returns:
        ``(em, q, point, wrench)``: the elastic model at ``q`` (rebuilt for a prismatic leg's
        stroke), the configuration, the reference point (3,), the wrench (6,) or ``None``.

    Raises:
        InvalidInputError: Not a robot, no platform, a malformed or unassembled ``q``, a bad
            point, wrench, stiffness or material (named).

    """
    from pkdyn.inputs import flag, instance

    instance("robot", robot, (Robot, ElasticModel), "a Robot (pkdyn.load) or an ElasticModel")
    links = flag("links", links)
    base = robot.base if isinstance(robot, ElasticModel) else robot
    if base.platform_frame is None:
        raise InvalidInputError("robot", f"{base.name} declares no platform frame")
    qq = as_finite("q", q, base.nq)
    check_assembled(base, qq)
    p = _point(point, base)
    w = _wrench(base, wrench)
    em = (
        robot
        if isinstance(robot, ElasticModel)
        else elastic_model(robot, actuator_stiffness, material, links, shear)
    ).at(qq)
    return em, qq, p, w


@one_blas_thread
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
    shear: bool = True,
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
        shear: Include the beams' shear deflection (Timoshenko; ``False``: Euler-Bernoulli).

    Returns:
        The stiffness.

    Raises:
        InvalidInputError: A bad stiffness, material, point or wrench, a configuration that is
            not assembled, no platform, or ``loaded`` without a load.
        SingularConfigurationError: At a parallel singularity (stiffness undefined) or a serial
            one (stiffness unbounded).

    """
    from pkdyn.inputs import flag

    loaded, gravity = flag("loaded", loaded), flag("gravity", gravity)
    em, qq, p, w = prepared(robot, q, actuator_stiffness, material, links, shear, point, wrench)
    if loaded and w is None and not gravity:
        raise InvalidInputError("loaded", "the loaded mode needs a wrench (or gravity=True)")
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
