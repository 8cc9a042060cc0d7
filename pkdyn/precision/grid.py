"""Maps over a plane of the translation workspace: one grid convention and one map result.

Every precision map (:func:`pkdyn.precision.maps.precision_map`,
:func:`pkdyn.precision.accuracy_maps.accuracy_map`) takes the same arguments and gives values
indexed the same way:

- ``plane``: the two coordinates that vary, ``xy``, ``xz`` or ``yz`` (``u`` the first, ``v`` the
  second);
- ``center``: a position (3,) [m] the plane goes through (default: the home pose's platform
  position); its third coordinate fixes the plane;
- ``extent``: the half-width of the square grid about ``center`` [m], or ``bounds``
  ``(u_min, u_max, v_min, v_max)`` [m]; neither: the robot's workspace box at that orientation;
- ``samples``: grid points per axis.

Values are arrays (nu, nv) indexed ``[i_u, i_v]`` (the first axis along ``u``). Each cell has
a status: ``ok`` (evaluated), ``unreachable`` (outside the reach or the limits: NaN) or
``singular`` (reached, but the figure is unbounded or undefined there: NaN,
:mod:`pkdyn.precision.validity`); ``near`` flags evaluated cells near a singularity. Extremes
("up to", "from") are taken over the evaluated cells only, and say so when there are none.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.assembly import inverse_geometry
from pkdyn.model.robot import Robot
from pkdyn.precision.validity import Flagged, Validity
from pkdyn.results import Result, jsonable
from pkdyn.units import quantity, vector

__all__ = [
    "OK",
    "map_validity",
    "reach",
    "PLANES",
    "SINGULAR",
    "STATUS",
    "UNREACHABLE",
    "GridMap",
    "PlaneGrid",
    "plane_grid",
]

PLANES = ("xy", "xz", "yz")
"""The coordinate planes a map can lie in."""

OK, UNREACHABLE, SINGULAR = 0, 1, 2
"""Cell status codes (:attr:`GridMap.status`)."""
STATUS = ("ok", "unreachable", "singular")
"""Their names, in JSON and CSV."""

MAX_SAMPLES = 2001
"""Most grid points per axis."""


def reach(
    robot: Robot,
    target: pin.SE3,
    starts: Sequence[np.ndarray | None],
    check_limits: bool = True,
) -> np.ndarray | None:
    """A configuration of ``robot`` with the platform at ``target``, or ``None``.

    The inverse geometric model from each start in turn (the previous pose of a map, then
    home: ``None`` starts from the model's own guess), the first that converges.
    """
    for start in starts:
        try:
            return inverse_geometry(robot, target, q_init=start, check_limits=check_limits).q
        except PkdynError:
            continue
    return None


def map_validity(m: GridMap, singular: str, near: str) -> Validity:
    """A map's flags: not valid without any evaluated cell; its singular and near cells.

    Args:
        m: The map.
        singular: Why a singular cell has no figure (completes "N reachable cells are
            singular (...)").
        near: What being near a singularity means for the figure.

    Returns:
        The validity.

    """
    c = m.counts()
    lines = []
    if c["singular"]:
        lines.append(f"{c['singular']} reachable cells are singular ({singular}): left out")
    if c["near"]:
        lines.append(f"{c['near']} cells are near a singularity: {near}")
    if c["ok"] == 0:
        lines.append(
            "no cell of the map is reachable and regular: give a center and extent inside the "
            "workspace"
        )
    return Validity(c["ok"] > 0, tuple(lines))


@dataclass(frozen=True, eq=False)  # numpy fields
class PlaneGrid:
    """A square or rectangular grid in a coordinate plane (module docstring).

    Attributes:
        plane: ``xy``, ``xz`` or ``yz``.
        u: Values of the first coordinate (nu,) [m].
        v: Values of the second coordinate (nv,) [m].
        fixed: The third coordinate [m].

    """

    plane: str
    u: np.ndarray
    v: np.ndarray
    fixed: float

    @property
    def axes(self) -> tuple[str, str]:
        """The names of ``u`` and ``v``."""
        return (self.plane[0], self.plane[1])

    @property
    def third(self) -> str:
        """The name of the fixed coordinate."""
        return next(c for c in "xyz" if c not in self.plane)

    @property
    def shape(self) -> tuple[int, int]:
        """``(nu, nv)``."""
        return (self.u.size, self.v.size)

    def positions(self) -> np.ndarray:
        """Platform positions (nu nv, 3) [m], ``u`` slowest: cell ``(i, j)`` is row ``i nv + j``."""
        U, V = np.meshgrid(self.u, self.v, indexing="ij")
        P = np.empty((U.size, 3))
        iu, iv = "xyz".index(self.plane[0]), "xyz".index(self.plane[1])
        P[:, iu], P[:, iv] = U.ravel(), V.ravel()
        P[:, 3 - iu - iv] = self.fixed
        return P


def plane_grid(
    robot: Robot,
    plane: str = "xy",
    center: Sequence[float] | np.ndarray | None = None,
    extent: float | None = None,
    samples: int = 31,
    bounds: Sequence[float] | np.ndarray | None = None,
    workspace: np.ndarray | None = None,
) -> PlaneGrid:
    """The grid of a map, its arguments checked (module docstring).

    Args:
        robot: The robot (its home pose and size).
        plane: ``xy``, ``xz`` or ``yz``.
        center: A position of the plane [m] (default: the home platform position).
        extent: Half-width of the grid about ``center`` [m] (> 0).
        samples: Points per axis (2 to 2001).
        bounds: ``(u_min, u_max, v_min, v_max)`` [m] instead of ``extent``.
        workspace: The workspace box (3, 2) [m], used when neither ``extent`` nor ``bounds``
            is given.

    Returns:
        The grid.

    Raises:
        InvalidInputError: A bad plane, centre, extent, bounds or sample count (named).

    """
    from pkdyn.inputs import count, positive
    from pkdyn.inputs import vector as checked_vector

    if not isinstance(plane, str) or plane not in PLANES:
        raise InvalidInputError("plane", f"'{plane}': use {', '.join(PLANES)}")
    samples = count("samples", samples, 2, MAX_SAMPLES)
    reach = 100.0 * robot.length_scale
    if center is None:
        c = robot.platform_placement(robot.q_home).translation.copy()
    else:
        c = checked_vector("center", center, 3, "m", bound=reach)
    iu, iv = "xyz".index(plane[0]), "xyz".index(plane[1])
    if bounds is not None:
        if extent is not None:
            raise InvalidInputError("extent", "give extent or bounds, not both")
        b = checked_vector("bounds", bounds, 4, "m", bound=reach)
        if not (b[0] < b[1] and b[2] < b[3]):
            raise InvalidInputError("bounds", f"{b.tolist()}: need u_min < u_max, v_min < v_max")
    elif extent is not None:
        e = positive("extent", extent, "m", bound=reach)
        b = np.array([c[iu] - e, c[iu] + e, c[iv] - e, c[iv] + e])
    elif workspace is not None:
        box = np.asarray(workspace, dtype=float)
        b = np.array([box[iu, 0], box[iu, 1], box[iv, 0], box[iv, 1]])
    else:
        e = 0.2 * robot.length_scale
        b = np.array([c[iu] - e, c[iu] + e, c[iv] - e, c[iv] + e])
    return PlaneGrid(
        plane,
        np.linspace(b[0], b[1], samples),
        np.linspace(b[2], b[3], samples),
        float(c[3 - iu - iv]),
    )


@dataclass(eq=False)  # numpy fields
class GridMap(Flagged, Result):
    """Figures over a :class:`PlaneGrid` (module docstring).

    Attributes:
        robot: The robot's name.
        grid: The grid.
        values: Field name -> values (nu, nv), NaN where not evaluated.
        status: Cell status (nu, nv): :data:`OK`, :data:`UNREACHABLE` or :data:`SINGULAR`.
        near: Evaluated cells near a singularity (nu, nv).
        units: Field name -> SI unit.
        labels: Field name -> what it is.
        worst: Field name -> ``min`` or ``max``: which extreme is the worst.
        orientation: Platform orientation (roll, pitch, yaw) [rad].
        method: How the figures were evaluated.
        options: The options of the figures (for titles and reports).
        validity: Whether the map as a whole means what it says, and its warnings.

    """

    robot: str
    grid: PlaneGrid
    values: dict[str, np.ndarray]
    status: np.ndarray
    near: np.ndarray
    units: dict[str, str]
    labels: dict[str, str]
    worst: dict[str, str]
    orientation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    method: str = ""
    options: dict[str, object] = field(default_factory=dict)
    validity: Validity = field(default_factory=Validity)

    # ------------------------------------------------------------------ the convention

    @property
    def plane(self) -> str:
        """``xy``, ``xz`` or ``yz``."""
        return self.grid.plane

    @property
    def u(self) -> np.ndarray:
        """Values of the first coordinate (nu,) [m]."""
        return self.grid.u

    @property
    def v(self) -> np.ndarray:
        """Values of the second coordinate (nv,) [m]."""
        return self.grid.v

    @property
    def axes(self) -> tuple[str, str]:
        """Names of ``u`` and ``v``."""
        return self.grid.axes

    @property
    def fixed(self) -> dict[str, float]:
        """The fixed coordinate [m] and the orientation (roll, pitch, yaw) [rad]."""
        roll, pitch, yaw = self.orientation
        return {self.grid.third: self.grid.fixed, "roll": roll, "pitch": pitch, "yaw": yaw}

    @property
    def reachable(self) -> np.ndarray:
        """Cells inside the reach and the limits (nu, nv)."""
        return np.asarray(self.status != UNREACHABLE)

    @property
    def evaluated(self) -> np.ndarray:
        """Cells with a figure (nu, nv)."""
        return np.asarray(self.status == OK)

    def extreme(self, name: str) -> float:
        """Worst value of a field over the evaluated cells (``nan`` when none is).

        The smallest of a stiffness or a frequency, the largest of a deflection or an error.
        """
        x = self._field(name)
        if not np.isfinite(x).any():
            return float("nan")
        return float(np.nanmax(x) if self.worst.get(name) == "max" else np.nanmin(x))

    def where(self, name: str) -> tuple[float, float] | None:
        """``(u, v)`` [m] of a field's worst cell, or ``None`` when no cell is evaluated."""
        x = self._field(name)
        if not np.isfinite(x).any():
            return None
        k = np.nanargmax(x) if self.worst.get(name) == "max" else np.nanargmin(x)
        i, j = np.unravel_index(int(k), x.shape)
        return float(self.u[i]), float(self.v[j])

    def _field(self, name: str) -> np.ndarray:
        if not isinstance(name, str) or name not in self.values:
            raise InvalidInputError(
                "field",
                f"name {name!r:.60} is not a field of this map: it holds "
                f"{', '.join(self.values) or 'nothing'}",
            )
        return np.asarray(self.values[name], dtype=float)

    def counts(self) -> dict[str, int]:
        """Number of cells of each status, and of near-singular ones."""
        out = {name: int(np.count_nonzero(self.status == k)) for k, name in enumerate(STATUS)}
        out["near"] = int(np.count_nonzero(self.near & (self.status == OK)))
        return out

    # ------------------------------------------------------------------ the protocol

    def to_json(self) -> dict[str, Any]:
        """JSON values: the grid, the cells' status, the fields (``null`` where not evaluated)."""
        worst = {}
        for name in self.values:
            at = self.where(name)
            worst[name] = {
                "value": jsonable(self.extreme(name)),
                "at": None if at is None else list(at),
                "is": "largest" if self.worst.get(name) == "max" else "smallest",
            }
        return {
            "robot": self.robot,
            "plane": self.plane,
            "axes": list(self.axes),
            "u": jsonable(self.u),
            "v": jsonable(self.v),
            "fixed": jsonable(self.fixed),
            "indexing": "values[i_u][i_v]",
            "status": [[STATUS[int(k)] for k in row] for row in self.status],
            "near": jsonable(self.near),
            "values": {name: jsonable(x) for name, x in self.values.items()},
            "units": dict(self.units),
            "worst": worst,
            "counts": self.counts(),
            "method": self.method,
            "options": jsonable(self.options),
            **self.validity.to_json(),
        }

    def table(self) -> str:
        """One line per field: its worst value over the evaluated cells and where; the counts."""
        c = self.counts()
        n = self.status.size
        a, b = self.axes
        head = (
            f"{self.robot}: map over {a} {b} at {self.grid.third} = "
            f"{quantity(self.grid.fixed, 'm')} ({self.u.size} x {self.v.size}, {a} "
            f"{vector([self.u[0], self.u[-1]], 'm')}, {b} {vector([self.v[0], self.v[-1]], 'm')}"
            f"): {c['ok']} of {n} cells evaluated, {c['unreachable']} unreachable, "
            f"{c['singular']} singular" + (f", {c['near']} near a singularity" if c["near"] else "")
        )
        lines = [head]
        for name in self.values:
            at = self.where(name)
            label = self.labels.get(name, name)
            if at is None:
                lines.append(f"  {label}: no cell evaluated (none reachable and regular)")
                continue
            word = "up to" if self.worst.get(name) == "max" else "down to"
            lines.append(
                f"  {label}: {word} {quantity(self.extreme(name), self.units.get(name, ''))} "
                f"at {a} {b} = {vector(at, 'm')}"
            )
        return "\n".join(lines + self.validity.lines())

    def write_csv(self, path: str | Path) -> Path:
        """The cells as CSV: ``<u>, <v>`` [m], ``status``, one column per field (SI units).

        Args:
            path: The file (written to a temporary name and renamed when complete).

        Returns:
            The path written.

        """
        import csv

        from pkdyn.files import atomic_write

        a, b = self.axes
        names = list(self.values)
        with atomic_write(path, newline="") as fh:
            w = csv.writer(fh)
            w.writerow(
                [f"{a}_m", f"{b}_m", "status", "near"]
                + [f"{n}_{self.units.get(n, '').replace(' ', '').replace('/', '_per_')}"
                   for n in names]
            )  # fmt: skip
            for i, u in enumerate(self.u):
                for j, v in enumerate(self.v):
                    row: list[object] = [repr(float(u)), repr(float(v))]
                    row += [STATUS[int(self.status[i, j])], bool(self.near[i, j])]
                    for n in names:
                        x = float(self.values[n][i, j])
                        row.append(repr(x) if math.isfinite(x) else "")
                    w.writerow(row)
        return Path(path)
