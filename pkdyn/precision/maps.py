"""Stiffness, deflection and lowest frequency over many poses and over workspace slices.

:func:`pose_figures` evaluates the design figures at platform poses by the fastest exact path:

- the library Gough-Stewart and Delta with the actuators' stiffness alone (rigid links, no
  spring of their own): the closed forms of :mod:`pkdyn.precision.vectorised`, all poses at once
  (frequencies: the Delta);
- any other robot, or compliant links: pose by pose, the general inverse geometric model (each
  pose warm-started from the previous solution) then the condensation
  (:func:`translational`) and :func:`pkdyn.precision.modes.modes` on the virtual-joint model
  built once.

The figures: ``stiffness_min``, the smallest principal translational stiffness [N/m] (forces
only; the design metric ``stiffness_min``); ``deflection``, the translation of the reference
point under a tool wrench [m]; ``f1``, the lowest natural frequency [Hz] (metric ``f1_min``).
Each pose is reached, or not; a reached pose where the figure is unbounded or undefined
(:mod:`pkdyn.precision.validity`) is **singular**, its figures NaN; ``near`` flags poses near a
serial singularity. Rigid actuators and nothing else compliant along a direction: ``inf``.

:func:`precision_map` maps them over a plane of the translation workspace with the map
convention of :mod:`pkdyn.precision.grid` (``plane``, ``center``, ``extent`` or ``bounds``,
``samples``; values ``[i_u, i_v]``), inside the robot's limits (:mod:`pkdyn.workspace`); plots:
:func:`pkdyn.plotting.plot_precision_map` (``result.plot()``).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.analysis.kinematics import NearSingularityWarning
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.inputs import is_complex
from pkdyn.model.arguments import public
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.precision.batched import batchable, translational_batch
from pkdyn.precision.condensation import compliance, reduce
from pkdyn.precision.elastic import ElasticModel, elastic_model
from pkdyn.precision.grid import (
    OK,
    PLANES,
    SINGULAR,
    UNREACHABLE,
    GridMap,
    map_validity,
    plane_grid,
    reach,
)
from pkdyn.precision.material import Material
from pkdyn.precision.modes import modes
from pkdyn.precision.stiffness import _point, _wrench
from pkdyn.precision.validity import PrecisionWarning, stiffness_check
from pkdyn.precision.vectorised import (
    VectorisedFigures,
    delta_figures,
    gough_stewart_figures,
    vectorised,
)
from pkdyn.progress import progress as progress_bar
from pkdyn.results import Result, jsonable
from pkdyn.threads import one_blas_thread
from pkdyn.units import quantity
from pkdyn.workspace.limits import REACHABLE

__all__ = [
    "FIELDS",
    "MAX_POSES",
    "PoseFigures",
    "PrecisionMap",
    "pose_figures",
    "precision_map",
    "translational",
]

FIELDS = {
    "stiffness_min": ("N/m", "smallest translational stiffness"),
    "deflection": ("m", "deflection under the tool wrench"),
    "f1": ("Hz", "lowest natural frequency"),
}
"""Map fields: unit and label."""

MAX_GENERAL_POSES = 200_000
"""Most poses evaluated on the general (pose-by-pose) path in one call: about 100 s."""
GENERAL_RATE = 2e3
"""Order of magnitude of the general path's speed [poses/s], for the estimate in messages."""
MAX_POSES = 4_000_000
"""Largest number of poses of one evaluation (refused up front beyond)."""


@dataclass(eq=False)  # numpy fields
class PoseFigures(Result):
    """Figures per pose (NaN where not reached or singular).

    Attributes:
        valid: Evaluated (N,).
        stiffness_min: Smallest principal translational stiffness (N,) [N/m].
        deflection: Translation of the reference point under the wrench (N,) [m].
        f1: Lowest natural frequency (N,) [Hz].
        method: ``closed form`` or ``general``.
        reached: Reached (N,): ``reached & ~valid`` are the singular poses.
        near: Evaluated poses near a serial singularity (N,).

    """

    valid: np.ndarray
    stiffness_min: np.ndarray
    deflection: np.ndarray
    f1: np.ndarray
    method: str
    reached: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    near: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    @property
    def singular(self) -> np.ndarray:
        """Reached poses where the figures are unbounded or undefined (N,)."""
        return np.asarray(self.reached & ~self.valid)

    def to_json(self) -> dict[str, Any]:
        """JSON values per pose (``null`` where not evaluated) and the counts."""
        return {
            "method": self.method,
            "valid": jsonable(self.valid),
            "reached": jsonable(self.reached),
            "near": jsonable(self.near),
            "stiffness_min": jsonable(self.stiffness_min),
            "deflection": jsonable(self.deflection),
            "f1": jsonable(self.f1),
            "units": {"stiffness_min": "N/m", "deflection": "m", "f1": "Hz"},
        }

    def table(self) -> str:
        """Counts and the worst figures over the evaluated poses."""
        n = self.valid.size
        lines = [
            f"{int(self.valid.sum())} of {n} poses evaluated ({self.method}), "
            f"{int((~self.reached).sum())} not reached, {int(self.singular.sum())} singular, "
            f"{int(self.near.sum())} near a singularity"
        ]
        for name, unit, worst in (
            ("stiffness_min", "N/m", np.nanmin),
            ("deflection", "m", np.nanmax),
            ("f1", "Hz", np.nanmin),
        ):
            x = getattr(self, name)
            if np.isfinite(x).any() or np.isinf(x).any():
                lines.append(f"  {FIELDS[name][1]}: worst {quantity(float(worst(x)), unit)}")
        return "\n".join(lines)


def _poses(P: np.ndarray, R: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(P, str | bytes | dict) or is_complex(P):
        raise InvalidInputError("P", f"expected finite positions (N, 3) [m], got {P!r:.60}")
    try:
        P = np.atleast_2d(np.asarray(P, dtype=float))
    except (TypeError, ValueError):
        raise InvalidInputError(
            "P", f"expected finite positions (N, 3) [m], got {P!r:.60}"
        ) from None
    if P.ndim != 2 or P.shape[1] != 3 or not np.all(np.isfinite(P)):
        raise InvalidInputError("P", f"expected finite positions (N, 3) [m], got {P.shape}")
    if P.shape[0] > MAX_POSES:
        raise InvalidInputError(
            "P", f"{P.shape[0]} poses: at most {MAX_POSES} per evaluation (split the grid)"
        )
    if R is None:
        return P, np.broadcast_to(np.eye(3), (P.shape[0], 3, 3))
    Rm = np.asarray(R, dtype=float)
    return P, np.broadcast_to(Rm, (P.shape[0], 3, 3)) if Rm.ndim == 2 else Rm


@one_blas_thread
@public
def pose_figures(
    robot: Robot,
    P: np.ndarray,
    R: np.ndarray | None = None,
    actuator_stiffness: float | Sequence[float] | np.ndarray | None = None,
    *,
    material: str | Material | None = None,
    links: bool = True,
    point: Sequence[float] | np.ndarray | None = None,
    wrench: Sequence[float] | np.ndarray | None = None,
    frequency: bool = False,
    method: str = "auto",
    progress: bool | None = None,
    workers: int | None = 1,
    scheduler: str | None = None,
    client: Any = None,
    timeout: float = 10.0,
) -> PoseFigures:
    """Stiffness, deflection and lowest frequency at platform poses (module docstring).

    Args:
        robot: The robot (with its geometry when links are beams).
        P: Platform frame positions (N, 3) [m].
        R: Platform orientations (N, 3, 3) or one (3, 3) (default: identity).
        actuator_stiffness: Joint-side stiffness, one or one per actuator [N m/rad or N/m];
            ``None``: the description's ``<pkdyn:stiffness>``.
        material: Material of the slender links; ``None``: the description's, if any.
        links: Model the links' compliance.
        point: Reference point, platform frame [m].
        wrench: Tool wrench (6: force [N], moment about the point [N m], world axes, or the task
            components): its deflection is reported.
        frequency: Compute the lowest natural frequency too.
        method: ``auto``, ``closed`` (refuse robots without a closed form) or ``general``.
        progress: Progress bar of the pose-by-pose path (``None``: when stderr is a terminal).
        workers: Local worker processes for the general path (1: this process; ``None``: as
            many as the machine justifies): chunks of :data:`CHUNK` poses, each starting its
            inverse geometric model from home (:mod:`pkdyn.precision.parallel`).
        scheduler: A Dask scheduler address for the general path.
        client: A connected ``distributed.Client`` instead of ``scheduler``.
        timeout: How long to wait for the scheduler or for a worker [s].

    Returns:
        The figures.

    Raises:
        InvalidInputError: Bad poses, stiffness, material, point, wrench or method, or too
            many poses.

    """
    if method not in ("auto", "closed", "general"):
        raise InvalidInputError("method", f"'{method}': use auto, closed or general")
    P, Rs = _poses(P, R)
    em = elastic_model(robot, actuator_stiffness, material, links)
    w = _wrench(robot, wrench)
    p = _point(point, robot)
    kind = vectorised(robot, frequency) if not em.links else None
    if method == "closed" and kind is None:
        raise InvalidInputError(
            "method",
            f"no closed form for {robot.name} with these options (closed forms: the library "
            "Gough-Stewart and three-armed ball-jointed Delta, actuator stiffness alone, "
            "frequencies for the Delta)",
        )
    if method != "general" and kind == "gough_stewart":
        k = em.actuator_stiffness
        if np.all(np.isfinite(k)):
            f = gough_stewart_figures(robot, P, R if R is not None else np.eye(3), k, p, w)
            return _closed(f)
    if method != "general" and kind == "delta" and np.all(np.isfinite(em.actuator_stiffness)):
        f = delta_figures(robot, P, em.actuator_stiffness, w, frequency)
        return _closed(f)
    if P.shape[0] > MAX_GENERAL_POSES:
        raise InvalidInputError(
            "P",
            f"{P.shape[0]} poses on the general (pose-by-pose) path would take about "
            f"{P.shape[0] / GENERAL_RATE / 60:.0f} min at ~{GENERAL_RATE:.0f} poses/s; give at "
            f"most {MAX_GENERAL_POSES} (a coarser grid)",
        )
    if workers != 1 or scheduler or client is not None:
        from pkdyn.precision.parallel import fingerprint, recipe, run_chunks

        options = (actuator_stiffness, material, links, p, w, frequency)
        payload = (recipe(robot), fingerprint(robot), bool(em.links), options)
        items = [(P[k : k + CHUNK], Rs[k : k + CHUNK]) for k in range(0, P.shape[0], CHUNK)]
        parts = run_chunks(_figures_chunk, payload, items, workers, scheduler, client, timeout, 1)
        return PoseFigures(
            np.concatenate([f.valid for f in parts]),
            np.concatenate([f.stiffness_min for f in parts]),
            np.concatenate([f.deflection for f in parts]),
            np.concatenate([f.f1 for f in parts]),
            "general",
            np.concatenate([f.reached for f in parts]),
            np.concatenate([f.near for f in parts]),
        )
    return _general(em, P, Rs, p, w, frequency, progress)


CHUNK = 64
"""Poses per chunk of the general path on worker processes or a Dask cluster."""


def _figures_chunk(payload: Any, items: list[tuple[np.ndarray, np.ndarray]]) -> list[PoseFigures]:
    """The general path on chunks of poses, in a worker (:mod:`pkdyn.precision.parallel`)."""
    from pkdyn.precision.parallel import worker_robot

    how, digest, geometry, (k, material, links, point, w, frequency) = payload
    robot = worker_robot(how, digest, geometry)
    em = elastic_model(robot, k, material, links)
    return [_general(em, P, R, point, w, frequency, False) for P, R in items]


def _closed(f: VectorisedFigures) -> PoseFigures:
    n = f.valid.size
    reached = f.reached if f.reached is not None else np.ones(n, dtype=bool)
    near = f.near if f.near is not None else np.zeros(n, dtype=bool)
    return PoseFigures(f.valid, f.stiffness_min, f.deflection, f.f1, "closed form", reached, near)


def translational(
    em: ElasticModel, q: np.ndarray, point: np.ndarray, w: np.ndarray | None
) -> tuple[float, float, bool]:
    """Smallest translational stiffness [N/m], deflection [m] and the near flag at ``q``.

    The smallest principal stiffness among the task's translation components (``inf``: rigid),
    and the translation of the point under ``w`` (``nan`` without ``w``). The lean path of the
    maps (no input checks): :func:`pkdyn.precision.condensation.reduce`,
    :func:`~pkdyn.precision.condensation.compliance` and the rule of
    :mod:`pkdyn.precision.validity`.

    Raises:
        SingularConfigurationError: The stiffness is undefined (parallel singularity) or
            unbounded (serial) at ``q``.

    """
    em = em.at(q)
    red = reduce(em, em.embed(q), point)
    C, _ = compliance(em, red)
    validity, _, _ = stiffness_check(em, red.q, point, C, q)
    rows = [int(i) for i in em.base.task_rows]
    t = [i for i in rows if i < 3]
    if not t:
        return float("nan"), float("nan"), bool(validity.warnings)
    top = float(np.linalg.eigvalsh(C[np.ix_(t, t)])[-1])
    kmin = 1.0 / top if top > 0.0 else float("inf")
    defl = float(np.linalg.norm((C @ w)[:3])) if w is not None else float("nan")
    return kmin, defl, bool(validity.warnings)


def _general(
    em: ElasticModel,
    P: np.ndarray,
    R: np.ndarray,
    point: np.ndarray,
    w: np.ndarray | None,
    frequency: bool,
    progress: bool | None,
) -> PoseFigures:
    robot = em.base
    N = P.shape[0]
    kmin, defl, f1 = np.full(N, np.nan), np.full(N, np.nan), np.full(N, np.nan)
    valid = np.zeros(N, dtype=bool)
    reached = np.zeros(N, dtype=bool)
    near = np.zeros(N, dtype=bool)
    q_prev = robot.q_home
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearSingularityWarning)
        warnings.simplefilter("ignore", PrecisionWarning)
        if batchable(em):  # the poses first, then the stiffness of all at once (batched)
            found, Q = [], []
            for i in progress_bar(range(N), "precision", "pose", progress, min_items=200):
                q = reach(robot, pin.SE3(R[i], P[i]), (q_prev, robot.q_home), check_limits=False)
                if q is not None:
                    found.append(i)
                    Q.append(q)
                    q_prev = q
            at = np.array(found, dtype=int)
            reached[at] = True
            kmin[at], defl[at], near[at], valid[at] = translational_batch(em, np.array(Q), point, w)
            if frequency:
                for i, q in zip(found, Q, strict=True):
                    if not valid[i]:
                        continue
                    try:
                        f1[i] = modes(em, q, point=point).f1
                    except PkdynError:
                        kmin[i] = defl[i] = np.nan
                        near[i] = valid[i] = False
            return PoseFigures(valid, kmin, defl, f1, "general", reached, near)
        for i in progress_bar(range(N), "precision", "pose", progress, min_items=200):
            q = reach(robot, pin.SE3(R[i], P[i]), (q_prev, robot.q_home), check_limits=False)
            if q is None:
                continue
            reached[i] = True
            q_prev = q
            try:
                kmin[i], defl[i], near[i] = translational(em, q, point, w)
                if frequency:
                    f1[i] = modes(em, q, point=point).f1
            except PkdynError:
                kmin[i] = defl[i] = np.nan
                near[i] = False
                continue
            valid[i] = True
    return PoseFigures(valid, kmin, defl, f1, "general", reached, near)


@dataclass(eq=False)  # numpy fields
class PrecisionMap(GridMap):
    """Stiffness, deflection and lowest frequency over a plane (:class:`GridMap`).

    Values ``[i_u, i_v]`` (the map convention of :mod:`pkdyn.precision.grid`); fields
    ``stiffness_min`` [N/m], ``deflection`` [m] (with a wrench), ``f1`` [Hz] (with
    ``frequency``).
    """


@one_blas_thread
@public
def precision_map(
    robot: Robot,
    plane: str = "xy",
    *,
    center: Sequence[float] | np.ndarray | None = None,
    extent: float | None = None,
    samples: int = 31,
    bounds: Sequence[float] | None = None,
    rpy: Sequence[float] = (0.0, 0.0, 0.0),
    actuator_stiffness: float | Sequence[float] | np.ndarray | None = None,
    material: str | Material | None = None,
    links: bool = True,
    point: Sequence[float] | np.ndarray | None = None,
    wrench: Sequence[float] | np.ndarray | None = None,
    frequency: bool = False,
    limits: Sequence[str] = ("stroke", "joint"),
    method: str = "auto",
    progress: bool | None = None,
    value: float | None = None,
    workers: int | None = 1,
    scheduler: str | None = None,
    client: Any = None,
    timeout: float = 10.0,
) -> PrecisionMap:
    """Stiffness (and deflection, lowest frequency) over a plane of the translation workspace.

    Args:
        robot: The robot.
        plane: ``xy``, ``xz`` or ``yz`` (:mod:`pkdyn.precision.grid`).
        center: A position of the plane [m] (default: the home pose's).
        extent: Half-width of the grid about ``center`` [m].
        samples: Grid points per axis.
        bounds: ``(u_min, u_max, v_min, v_max)`` [m] instead of ``extent`` (neither: the
            workspace's box).
        rpy: Platform orientation [rad] (roll, pitch, yaw; ignored by a Delta).
        actuator_stiffness: Joint-side stiffness [N m/rad or N/m]; ``None``: described.
        material: Material of the undescribed slender links.
        links: Model the links' compliance.
        point: Reference point, platform frame [m].
        wrench: Tool wrench for the ``deflection`` field (6 values or the task components).
        frequency: Also map the lowest frequency ``f1``.
        limits: Limit kinds a pose must respect to be mapped (``reach`` always).
        method: ``auto``, ``closed`` or ``general`` (:func:`pose_figures`).
        progress: Progress bar of the pose-by-pose path.
        value: Deprecated: the third coordinate of the plane [m] (give ``center``).
        workers: Local worker processes of the general path (:func:`pose_figures`).
        scheduler: A Dask scheduler address of the general path.
        client: A connected ``distributed.Client`` instead of ``scheduler``.
        timeout: How long to wait for the scheduler or for a worker [s].

    Returns:
        The map.

    Raises:
        InvalidInputError: A bad plane, centre, extent, bounds, sample count or option.

    """
    from pkdyn.inputs import vector as checked_vector
    from pkdyn.workspace.translation import evaluator_for

    R = pin.rpy.rpyToMatrix(*as_finite("rpy", rpy, 3))
    if value is not None:
        warnings.warn(
            "precision_map(value=...) is deprecated: give center=[x, y, z] (the map convention "
            "of pkdyn.precision.grid)",
            DeprecationWarning,
            stacklevel=3,
        )
        from pkdyn.inputs import real

        v = real("value", value, "m", bound=100.0 * robot.length_scale)
        c = (
            robot.platform_placement(robot.q_home).translation.copy()
            if center is None
            else np.array(checked_vector("center", center, 3, "m"), dtype=float)
        )
        if isinstance(plane, str) and plane in PLANES:
            c[next(i for i, a in enumerate("xyz") if a not in plane)] = v
        center = c
    ev = evaluator_for(robot, progress=progress)
    box = ev.default_bounds(R) if extent is None and bounds is None else None
    grid = plane_grid(robot, plane, center, extent, samples, bounds, box)
    P = grid.positions()
    from pkdyn.workspace.limits import check_kinds

    codes = ev.violations(P, R, check_kinds(limits), 0.0)
    inside = codes == REACHABLE
    fig = pose_figures(
        robot,
        P[inside],
        R,
        actuator_stiffness,
        material=material,
        links=links,
        point=point,
        wrench=wrench,
        frequency=frequency,
        method=method,
        progress=progress,
        workers=workers,
        scheduler=scheduler,
        client=client,
        timeout=timeout,
    )
    shape = grid.shape
    status = np.full(P.shape[0], UNREACHABLE, dtype=np.int8)
    status[np.flatnonzero(inside)[fig.reached]] = SINGULAR
    status[np.flatnonzero(inside)[fig.valid]] = OK
    near = np.zeros(P.shape[0], dtype=bool)
    near[inside] = fig.near & fig.valid
    values = {}
    for name in ("stiffness_min", "deflection", "f1"):
        if name == "deflection" and wrench is None or name == "f1" and not frequency:
            continue
        full = np.full(P.shape[0], np.nan)
        full[inside] = np.where(fig.valid, getattr(fig, name), np.nan)
        values[name] = full.reshape(shape)
    out = PrecisionMap(
        robot=robot.name,
        grid=grid,
        values=values,
        status=status.reshape(shape),
        near=near.reshape(shape),
        units={k: FIELDS[k][0] for k in values},
        labels={k: FIELDS[k][1] for k in values},
        worst={k: ("max" if k == "deflection" else "min") for k in values},
        orientation=(float(rpy[0]), float(rpy[1]), float(rpy[2])),
        method=fig.method,
        options={
            "actuator_stiffness": None
            if actuator_stiffness is None
            else np.atleast_1d(np.asarray(actuator_stiffness, dtype=float)).tolist(),
            "material": None if material is None else str(getattr(material, "name", material)),
            "point": None if point is None else list(np.asarray(point, float)),
            "wrench": None if wrench is None else list(np.asarray(wrench, float)),
        },
    )
    out.validity = map_validity(
        out, "the figure is unbounded or undefined there", "their figures are steep there"
    )
    return out
