"""Pose-error maps: worst-case and RMS position errors over a plane of the workspace.

:func:`accuracy_map` takes the map convention of :mod:`pkdyn.precision.grid` (``plane``,
``center``, ``extent`` or ``bounds``, ``samples``; values ``[i_u, i_v]``), like
:func:`pkdyn.precision.maps.precision_map`. Cells outside the robot's reach or limits are
``unreachable`` (the workspace evaluator of :mod:`pkdyn.workspace` decides, then the inverse
geometric model from the previous cell, then from home); at a reached cell the actuator and
geometric budgets of :mod:`pkdyn.precision.budgets` are evaluated from one sensitivity; a cell
where they are unbounded or do not hold (:func:`pkdyn.precision.validity.budget_validity`) is
``singular``. The "up to" figures are over the evaluated cells, and say so when there are none.

The old call ``accuracy_map(robot, positions, resolution, backlash, model, tolerance, rotation,
shape, axes)`` with positions from :func:`slice_grid` still works for one release (a
:class:`DeprecationWarning`).
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
from pkdyn.model.arguments import public
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.precision.budgets import (
    _actuator_budget,
    _geometric_budget,
    _per_actuator,
    _std,
    _tolerances,
)
from pkdyn.precision.grid import (
    OK,
    PLANES,
    SINGULAR,
    UNREACHABLE,
    GridMap,
    PlaneGrid,
    map_validity,
    plane_grid,
    reach,
)
from pkdyn.precision.parameters import ParameterModel
from pkdyn.precision.sensitivity import pose_sensitivity
from pkdyn.precision.validity import PrecisionWarning, budget_validity
from pkdyn.progress import progress as progress_bar
from pkdyn.results import renamed_keyword
from pkdyn.threads import one_blas_thread

__all__ = ["FIELDS", "AccuracyMap", "accuracy_map", "slice_grid"]

FIELDS = {
    "actuator_worst": "worst-case position error, actuators",
    "actuator_rms": "RMS position error, actuators",
    "geometric_worst": "worst-case position error, tolerances",
    "geometric_rms": "RMS position error, tolerances",
}
"""Map fields (position errors [m])."""

MAX_CELLS = 100_000
"""Most cells of one map."""


@dataclass(eq=False)  # numpy fields
class AccuracyMap(GridMap):
    """Position errors over a plane (:class:`GridMap`: values ``[i_u, i_v]``, status, flags).

    Fields ``actuator_worst``, ``actuator_rms`` [m] and, with a parameter model,
    ``geometric_worst``, ``geometric_rms`` [m]. The flat views of the old result
    (``P``, ``valid``, ``actuator_worst``...) are kept for one release.
    """

    positions: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    legacy_shape: tuple[int, ...] | None = None

    @property
    def P(self) -> np.ndarray:  # noqa: N802 - the old attribute's name
        """Platform positions of the cells (N, 3) [m], ``u`` slowest."""
        return self.positions

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape ``(nu, nv)`` (or the old call's ``shape``)."""
        return self.legacy_shape if self.legacy_shape is not None else self.grid.shape

    @property
    def valid(self) -> bool | np.ndarray:  # type: ignore[override]
        """Old view: evaluated cells (N,) (the map's own flag: :attr:`validity`)."""
        return np.asarray(self.status == OK).reshape(-1)

    def _flat(self, name: str) -> np.ndarray:
        if name not in self.values:
            return np.full(self.status.size, np.nan)
        return np.asarray(self.values[name]).reshape(-1)

    @property
    def actuator_worst(self) -> np.ndarray:
        """Old view: worst-case position error of the actuator errors (N,) [m]."""
        return self._flat("actuator_worst")

    @property
    def actuator_rms(self) -> np.ndarray:
        """Old view: its RMS (N,) [m]."""
        return self._flat("actuator_rms")

    @property
    def geometric_worst(self) -> np.ndarray:
        """Old view: worst-case position error of the tolerances (N,) [m]."""
        return self._flat("geometric_worst")

    @property
    def geometric_rms(self) -> np.ndarray:
        """Old view: its RMS (N,) [m]."""
        return self._flat("geometric_rms")

    def field(self, name: str) -> np.ndarray:
        """One of the error fields on the grid (``[i_u, i_v]``)."""
        if not isinstance(name, str) or name not in FIELDS:
            raise InvalidInputError("field", f"'{name}': use {', '.join(FIELDS)}")
        return self._flat(name).reshape(self.shape)


def slice_grid(
    center: Sequence[float] | np.ndarray, axes: str, extent: float, samples: int
) -> tuple[np.ndarray, tuple[int, int]]:
    """A square grid of positions in a coordinate plane through ``center`` (``u`` slowest).

    Deprecated with the old call of :func:`accuracy_map`: give it ``plane``, ``center``,
    ``extent`` and ``samples``.

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
    if axes not in PLANES:
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
    i, j = "xyz".index(axes[0]), "xyz".index(axes[1])
    u = np.linspace(-extent, extent, int(samples))
    grid = PlaneGrid(axes, c[i] + u, c[j] + u, float(c[3 - i - j]))
    return grid.positions(), (int(samples), int(samples))


def _legacy_grid(P: np.ndarray, shape: tuple[int, ...] | None, axes: tuple[str, str]) -> PlaneGrid:
    """The plane grid of the old call's positions (a :func:`slice_grid`, else one column)."""
    plane = f"{axes[0]}{axes[1]}"
    if plane not in PLANES:
        raise InvalidInputError("axes", f"{axes}: two of x, y, z in order (xy, xz, yz)")
    iu, iv = "xyz".index(axes[0]), "xyz".index(axes[1])
    if shape is not None and len(shape) == 2 and shape[0] * shape[1] == len(P):
        G = P.reshape(shape[0], shape[1], 3)
        return PlaneGrid(plane, G[:, 0, iu].copy(), G[0, :, iv].copy(), float(P[0, 3 - iu - iv]))
    return PlaneGrid(plane, P[:, iu].copy(), P[:1, iv].copy(), float(P[0, 3 - iu - iv]))


@renamed_keyword("progress_bar", "progress")
@public
@one_blas_thread
def accuracy_map(
    robot: Robot,
    plane: str | np.ndarray = "xy",
    *legacy: Any,
    center: Sequence[float] | np.ndarray | None = None,
    extent: float | None = None,
    samples: int = 15,
    bounds: Sequence[float] | None = None,
    resolution: float | Sequence[float] | np.ndarray = 0.0,
    backlash: float | Sequence[float] | np.ndarray = 0.0,
    model: ParameterModel | None = None,
    tolerance: float | Sequence[float] | np.ndarray = 0.0,
    distribution: str = "uniform",
    rpy: Sequence[float] | None = None,
    limits: Sequence[str] = ("stroke", "joint"),
    progress: bool | None = None,
    positions: np.ndarray | None = None,
    rotation: np.ndarray | None = None,
    shape: tuple[int, ...] | None = None,
    axes: tuple[str, str] | None = None,
) -> AccuracyMap:
    """Worst-case and RMS position errors over a plane of the workspace (module docstring).

    Args:
        robot: The robot.
        plane: ``xy``, ``xz`` or ``yz`` (:mod:`pkdyn.precision.grid`).
        *legacy: The old positional arguments after ``positions`` (deprecated).
        center: A position of the plane [m] (default: the home pose's).
        extent: Half-width of the grid about ``center`` [m].
        samples: Grid points per axis (default 15).
        bounds: ``(u_min, u_max, v_min, v_max)`` [m] instead of ``extent`` (neither: the
            workspace's box).
        resolution: Actuator resolution (per actuator or one) [rad or m].
        backlash: Actuator backlash (per actuator or one) [rad or m].
        model: Parameter model of the geometric tolerances (``None``: actuator errors only).
        tolerance: Tolerances of ``model``'s parameters.
        distribution: ``uniform`` or ``normal`` (the tolerances' RMS).
        rpy: Platform orientation (roll, pitch, yaw) [rad] (default: the home orientation).
        limits: Limit kinds a cell must respect besides the reach (``stroke``, ``joint``).
        progress: Force the progress bar on or off (``progress_bar``: its former name, kept
            for one release).
        positions: Deprecated (the old call): platform positions (N, 3) [m].
        rotation: Deprecated: the platform orientation (3, 3) (give ``rpy``).
        shape: Deprecated: the grid shape of ``positions``.
        axes: Deprecated: the names of the two varying coordinates of ``positions``.

    Returns:
        The map.

    Raises:
        InvalidInputError: A bad plane, centre, extent, bounds, sample count or error value.

    """
    if not isinstance(plane, str) or positions is not None or (legacy and plane not in PLANES):
        names = ("resolution", "backlash", "model", "tolerance", "rotation", "shape", "axes",
                 "progress")  # fmt: skip
        if len(legacy) > len(names):
            raise InvalidInputError("accuracy_map", f"{len(legacy) + 2} positional arguments")
        old = dict(zip(names, legacy, strict=False))
        warnings.warn(
            "accuracy_map(robot, positions, ...) is deprecated: give plane=, center=, extent=, "
            "samples= (the map convention of pkdyn.precision.grid)",
            DeprecationWarning,
            stacklevel=3,
        )
        return _legacy(
            robot,
            plane if positions is None else positions,
            old.get("resolution", resolution),
            old.get("backlash", backlash),
            old.get("model", model),
            old.get("tolerance", tolerance),
            old.get("rotation", rotation),
            old.get("shape", shape),
            old.get("axes", axes) or ("x", "y"),
            old.get("progress", progress),
        )
    if legacy:
        raise InvalidInputError(
            "accuracy_map", "give center, extent, samples... by name (after robot and plane)"
        )
    from pkdyn.workspace.translation import evaluator_for

    R = (
        robot.platform_placement(robot.q_home).rotation
        if rpy is None
        else pin.rpy.rpyToMatrix(*as_finite("rpy", rpy, 3))
    )
    errors = _errors(robot, resolution, backlash, model, tolerance, distribution)
    ev = evaluator_for(robot)
    box = ev.default_bounds(R) if extent is None and bounds is None else None
    grid = plane_grid(robot, plane, center, extent, samples, bounds, box)
    P = grid.positions()
    if len(P) > MAX_CELLS:
        raise InvalidInputError("samples", f"{len(P)} cells: at most {MAX_CELLS}")
    inside = ev.violations(P, R, ("reach", *limits), 0.0) < 0
    return _map(robot, grid, P, R, inside, errors, progress, None)


def _errors(
    robot: Robot,
    resolution: Any,
    backlash: Any,
    model: ParameterModel | None,
    tolerance: Any,
    distribution: str,
) -> tuple[np.ndarray, np.ndarray, ParameterModel | None, np.ndarray, np.ndarray, str]:
    r = _per_actuator(robot, "resolution", resolution)
    b = _per_actuator(robot, "backlash", backlash)
    if model is None:
        return r, b, None, np.zeros(0), np.zeros(0), distribution
    t = _tolerances(model, tolerance)
    return r, b, model, t, _std(t, distribution), distribution


def _legacy(
    robot: Robot,
    positions: Any,
    resolution: Any,
    backlash: Any,
    model: ParameterModel | None,
    tolerance: Any,
    rotation: np.ndarray | None,
    shape: tuple[int, ...] | None,
    axes: tuple[str, str],
    progress: bool | None,
) -> AccuracyMap:
    if isinstance(positions, str | bytes | dict):
        raise InvalidInputError("positions", "expected finite (N, 3) positions [m]")
    try:
        P = np.atleast_2d(np.asarray(positions, dtype=float))
    except (TypeError, ValueError):
        raise InvalidInputError("positions", "expected finite (N, 3) positions [m]") from None
    if P.ndim != 2 or P.shape[1] != 3 or not np.all(np.isfinite(P)) or len(P) == 0:
        raise InvalidInputError("positions", "expected finite (N, 3) positions [m]")
    if P.shape[0] > MAX_CELLS:
        raise InvalidInputError("positions", f"{P.shape[0]} positions: give at most 100,000")
    R = (
        robot.platform_placement(robot.q_home).rotation
        if rotation is None
        else np.asarray(rotation)
    )
    errors = _errors(robot, resolution, backlash, model, tolerance, "uniform")
    grid = _legacy_grid(P, shape, axes)
    inside = np.ones(len(P), dtype=bool)
    return _map(robot, grid, P, R, inside, errors, progress, shape or (len(P),))


def _map(
    robot: Robot,
    grid: PlaneGrid,
    P: np.ndarray,
    R: np.ndarray,
    inside: np.ndarray,
    errors: tuple[np.ndarray, np.ndarray, ParameterModel | None, np.ndarray, np.ndarray, str],
    progress: bool | None,
    legacy_shape: tuple[int, ...] | None,
) -> AccuracyMap:
    r, b, model, t, std, distribution = errors
    n = len(P)
    out = {k: np.full(n, np.nan) for k in FIELDS}
    status = np.full(n, UNREACHABLE, dtype=np.int8)
    near = np.zeros(n, dtype=bool)
    q_prev = robot.q_home
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearSingularityWarning)
        warnings.simplefilter("ignore", PrecisionWarning)
        for k in progress_bar(range(n), "accuracy map", "pose", progress, min_items=200):
            if not inside[k]:
                continue
            q = reach(robot, pin.SE3(R, P[k]), (q_prev, robot.q_home))
            if q is None:
                continue
            q_prev = q
            status[k] = SINGULAR
            try:
                validity = budget_validity(robot, q)
                s = pose_sensitivity(robot, q, model)
            except PkdynError:
                continue
            if not validity.valid:
                continue
            status[k] = OK
            near[k] = bool(validity.warnings)
            act = _actuator_budget(robot, s.J, r, b, validity)
            out["actuator_worst"][k], out["actuator_rms"][k] = act.position_worst, act.position_rms
            if model is not None:
                geo = _geometric_budget(
                    model, s, t, std, distribution, validity, robot.length_scale
                )
                out["geometric_worst"][k] = geo.position_worst
                out["geometric_rms"][k] = geo.position_rms
    keep = list(FIELDS) if model is not None else ["actuator_worst", "actuator_rms"]
    gshape = grid.shape
    amap = AccuracyMap(
        robot=robot.name,
        grid=grid,
        values={name: out[name].reshape(gshape) for name in keep},
        status=status.reshape(gshape),
        near=near.reshape(gshape),
        units={name: "m" for name in keep},
        labels={name: FIELDS[name] for name in keep},
        worst={name: "max" for name in keep},
        orientation=tuple(float(x) for x in pin.rpy.matrixToRpy(R)),  # type: ignore[arg-type]
        method="first order (pkdyn.precision.budgets)",
        options={
            "resolution": r.tolist(),
            "backlash": b.tolist(),
            "model": None if model is None else model.kind,
            "distribution": distribution,
        },
        positions=P,
        legacy_shape=legacy_shape,
    )
    amap.validity = map_validity(
        amap,
        "the first order is unbounded or does not hold there",
        "errors are amplified there",
    )
    return amap
