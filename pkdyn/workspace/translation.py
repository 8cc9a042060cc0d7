"""Constant-orientation (translation) workspace of any robot, sampled on a grid.

:func:`translation_workspace` samples platform positions on a regular grid at a fixed
platform orientation and classifies each one by the first limit it breaks (see
:mod:`pkdyn.workspace.limits`: reach, actuator stroke or angle, passive-joint cone or pyramid,
interference). The check is vectorised where a closed form exists (leg robots such as the
Gough-Stewart platform: :mod:`pkdyn.workspace.legs`; the Delta: :mod:`pkdyn.workspace.delta`)
and done with the general inverse model and coal otherwise, by continuation over the grid
(:mod:`pkdyn.workspace.numeric`).

The result (:class:`TranslationWorkspace`) gives the volume (sample count times cell volume; an
area for planar robots), the bounding box, planar slices and the boundary samples.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.inputs import count, positive
from pkdyn.model.arguments import public
from pkdyn.model.robot import PLATFORM_HINT, Robot
from pkdyn.results import Result, deprecated_alias, jsonable
from pkdyn.units import quantity
from pkdyn.workspace.limits import LIMIT_KINDS, REACHABLE, PoseEvaluator, check_kinds

__all__ = [
    "CLOSED_FORM_EVALUATORS",
    "TranslationWorkspace",
    "evaluator_for",
    "translation_workspace",
]

AXES = ("x", "y", "z")


@dataclass
class TranslationWorkspace(Result):
    """A sampled constant-orientation workspace.

    Attributes:
        robot: Robot name.
        rpy: Platform orientation (roll, pitch, yaw) [rad].
        axes: Grid coordinates along x, y, z [m] (one value on an axis the robot does not
            control, e.g. z for a planar robot).
        codes: First limit broken per sample (nx, ny, nz): index in
            :data:`pkdyn.workspace.limits.LIMIT_KINDS`, or -1 where reachable.
        kinds: Limit kinds checked.
        margin: Safety distance used for interference [m].
        method: How the samples were checked.

    """

    robot: str
    rpy: np.ndarray
    axes: tuple[np.ndarray, np.ndarray, np.ndarray]
    codes: np.ndarray
    kinds: tuple[str, ...]
    margin: float
    method: str
    dims: tuple[int, ...] = field(default=(0, 1, 2))

    @property
    def reachable(self) -> np.ndarray:
        """Boolean mask of the reachable samples (nx, ny, nz)."""
        return self.codes == REACHABLE

    @property
    def step(self) -> np.ndarray:
        """Grid spacing per axis [m] (0 on a single-sample axis)."""
        return np.array([a[1] - a[0] if a.size > 1 else 0.0 for a in self.axes])

    @property
    def cell(self) -> float:
        """Volume [m^3] (area [m^2] for planar robots) of one sample's cell."""
        return float(np.prod([self.step[d] for d in self.dims]))

    @property
    def volume(self) -> float:
        """Workspace volume [m^3] (area [m^2] for planar robots): reachable samples x cell."""
        return float(np.count_nonzero(self.reachable)) * self.cell

    @property
    def samples(self) -> int:
        """Number of samples."""
        return int(self.codes.size)

    @property
    def limits_hit(self) -> dict[str, int]:
        """Samples rejected per limit kind (each counted for the first kind it breaks)."""
        return {k: int(np.count_nonzero(self.codes == LIMIT_KINDS.index(k))) for k in self.kinds}

    @property
    def bounds(self) -> np.ndarray | None:
        """Bounding box of the reachable samples (3, 2) [m], or ``None`` if empty."""
        idx = np.nonzero(self.reachable)
        if idx[0].size == 0:
            return None
        return np.array([[a[i.min()], a[i.max()]] for a, i in zip(self.axes, idx, strict=True)])

    @property
    def touches_box(self) -> bool:
        """Whether reachable samples lie on a face of the sampled box (the box may be small)."""
        m = self.reachable
        for d in self.dims:
            if m.shape[d] > 1 and (np.take(m, 0, axis=d).any() or np.take(m, -1, axis=d).any()):
                return True
        return False

    def points(self, mask: np.ndarray | None = None) -> np.ndarray:
        """Positions (M, 3) [m] of the samples selected by ``mask`` (default: reachable)."""
        if mask is not None:
            m = np.asarray(mask) if isinstance(mask, np.ndarray | list | tuple) else None
            if m is None or m.dtype != bool or m.shape != self.codes.shape:
                raise InvalidInputError(
                    "mask", f"expected a boolean array of the grid's shape {self.codes.shape}"
                )
        idx = np.nonzero(self.reachable if mask is None else mask)
        return np.column_stack([a[i] for a, i in zip(self.axes, idx, strict=True)])

    def boundary_mask(self) -> np.ndarray:
        """Reachable samples with an unreachable neighbour (or the box's edge) on a grid axis."""
        m = self.reachable
        inner = m.copy()
        for d in self.dims:
            if m.shape[d] == 1:
                continue
            padded = np.pad(m, [(1, 1) if k == d else (0, 0) for k in range(3)])
            lo = np.take(padded, np.arange(0, m.shape[d]), axis=d)
            hi = np.take(padded, np.arange(2, m.shape[d] + 2), axis=d)
            inner &= lo & hi
        return m & ~inner

    def boundary(self) -> np.ndarray:
        """Boundary samples (M, 3) [m] (see :meth:`boundary_mask`)."""
        return self.points(self.boundary_mask())

    def slice(self, axis: str, value: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Planar slice through the nearest grid plane.

        Args:
            axis: ``x``, ``y`` or ``z``: the slice is normal to it.
            value: Coordinate of the slice [m].

        Returns:
            ``(u, v, codes)``: the coordinates of the two other axes and the (nu, nv) codes.

        """
        if axis not in AXES:
            raise InvalidInputError("axis", f"'{axis}': use x, y or z")
        d = AXES.index(axis)
        from pkdyn.inputs import real

        value = real("value", value, "m")
        k = int(np.argmin(np.abs(self.axes[d] - value)))
        others = [i for i in range(3) if i != d]
        return self.axes[others[0]], self.axes[others[1]], np.take(self.codes, k, axis=d)

    @property
    def kind(self) -> str:
        """``translation`` or ``dextrous`` (every orientation: :mod:`pkdyn.workspace.dextrous`)."""
        return "dextrous" if self.method.startswith("dextrous") else "translation"

    def table(self) -> str:
        """Volume, bounds of the reachable samples, samples and what rejected them."""
        unit = "m^3" if len(self.dims) == 3 else "m^2"
        lines = [f"{self.kind} workspace: volume {quantity(self.volume, unit)}"]
        b = self.bounds
        if b is not None:
            lines.append(
                "bounds: "
                + ", ".join(
                    f"{ax} [{quantity(lo, 'm')}, {quantity(hi, 'm')}]"
                    for ax, (lo, hi) in zip(AXES, b, strict=True)
                )
            )
        lines.append(
            f"samples: {self.samples} ({int(np.count_nonzero(self.reachable))} reachable), "
            "rejected by: " + ", ".join(f"{k} {v}" for k, v in self.limits_hit.items())
        )
        if self.touches_box:
            lines.append("note: reachable samples touch the sampled box; widen --bounds")
        return "\n".join(lines)

    as_json = deprecated_alias("as_json", "to_json")

    def to_json(self) -> dict[str, Any]:
        """``volume``, ``bounds``, ``samples``, ``limits_hit`` and the sampling description."""
        b = self.bounds
        out = {
            "kind": self.kind,
            "volume": self.volume,
            "volume_unit": "m^3" if len(self.dims) == 3 else "m^2",
            "bounds": None if b is None else b.tolist(),
            "samples": self.samples,
            "reachable": int(np.count_nonzero(self.reachable)),
            "limits_hit": self.limits_hit,
            "rpy": [float(x) for x in self.rpy],
            "step": self.step.tolist(),
            "box": [[float(a[0]), float(a[-1])] for a in self.axes],
            "touches_box": self.touches_box,
            "margin": self.margin,
            "method": self.method,
        }
        if self.kind == "dextrous":
            out.pop("rpy")
        return jsonable(out)


def _delta_evaluator(robot: Robot) -> PoseEvaluator | None:
    from pkdyn.workspace.delta import DeltaEvaluator

    return DeltaEvaluator(robot) if DeltaEvaluator.accepts(robot) else None


def _leg_evaluator(robot: Robot) -> PoseEvaluator | None:
    from pkdyn.workspace.legs import HexapodEvaluator

    return HexapodEvaluator(robot) if HexapodEvaluator.accepts(robot) else None


CLOSED_FORM_EVALUATORS: dict[str | None, Callable[[Robot], PoseEvaluator | None]] = {
    "delta": _delta_evaluator,
    "gough_stewart": _leg_evaluator,
    None: _leg_evaluator,
}
"""Closed-form pose evaluators by family name (:attr:`pkdyn.Robot.family`); the key ``None``
serves robots of no family (described by their users), whose legs are recognised from the
structure. A factory returns ``None`` when the robot's parameters or structure do not fit its
closed form; the robot then takes the numeric path."""


def evaluator_for(
    robot: Robot, method: str = "auto", progress: bool | None = False
) -> PoseEvaluator:
    """The pose evaluator of a robot.

    Args:
        robot: The robot.
        method: ``auto`` (closed form when the robot has one, see
            :data:`CLOSED_FORM_EVALUATORS`), ``closed`` or ``numeric``.
        progress: Progress bar of the numeric evaluator over the poses: ``True`` / ``False``
            force it on / off, ``None`` shows it when stderr is a terminal (default off: the
            workspace samplers show their own).

    Returns:
        A :class:`pkdyn.workspace.limits.PoseEvaluator`.

    Raises:
        InvalidInputError: Unknown method, or ``closed`` for a robot without a closed form.

    """
    from pkdyn.workspace.numeric import NumericEvaluator

    if method not in ("auto", "closed", "numeric"):
        raise InvalidInputError("method", f"'{method}': use auto, closed or numeric")
    if method != "numeric":
        factory = CLOSED_FORM_EVALUATORS.get(robot.family)
        ev = None if factory is None else factory(robot)
        if ev is not None:
            return ev
        if method == "closed":
            raise InvalidInputError(
                "method", f"{robot.name} has no closed-form workspace check; use numeric"
            )
    return NumericEvaluator(robot, progress=progress)


def _grid_axes(
    box: np.ndarray, step: float | None, n: int, dims: Sequence[int], home: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if step is None:
        n = count("samples", n, minimum=2, maximum=MAX_GRID_SAMPLES)
    else:
        step = positive("step", step, "m")
    axes = []
    for d in range(3):
        if d not in dims:
            axes.append(np.array([home[d]]))
            continue
        lo, hi = float(box[d, 0]), float(box[d, 1])
        if not hi > lo:
            raise InvalidInputError("bounds", f"{AXES[d]}: need min < max, got {lo}, {hi}")
        if step is None:
            axes.append(np.linspace(lo, hi, n))
            continue
        cells = (hi - lo) / step
        if cells > MAX_GRID_SAMPLES:
            raise InvalidInputError(
                "step",
                f"{step:g} m gives {cells:.3g} samples along {AXES[d]} alone; use a coarser step",
            )
        k = int(np.floor(cells + 1e-9)) + 1
        if k < 2:
            raise InvalidInputError("step", f"{step} m leaves fewer than 2 samples along {AXES[d]}")
        axes.append(lo + step * np.arange(k))
    total = float(np.prod([a.size for a in axes]))
    if total > MAX_GRID_SAMPLES:
        shape = " x ".join(str(a.size) for a in axes)
        raise InvalidInputError(
            "step" if step is not None else "samples",
            f"a {shape} grid is {total:.3g} poses (about {total / 1e5 / 60:.2g} min in closed "
            f"form, {total / 1e3 / 3600:.2g} h numerically, {total * 100 / 1e9:.2g} GB); at "
            f"most {MAX_GRID_SAMPLES:.0e}: a coarser grid or a smaller box",
        )
    return axes[0], axes[1], axes[2]


MAX_GRID_SAMPLES = 10_000_000
"""Most poses of one workspace grid (~100 bytes each; 10^5 poses/s in closed form, ~10^3
numerically): larger requests are refused before any work, with the estimate."""


@public
def translation_workspace(
    robot: Robot,
    rpy: Sequence[float] = (0.0, 0.0, 0.0),
    bounds: np.ndarray | Sequence[Sequence[float]] | None = None,
    step: float | None = None,
    samples: int = 41,
    limits: Sequence[str] = ("stroke", "joint", "interference"),
    margin: float = 0.0,
    method: str = "auto",
    progress: bool | None = None,
    evaluator: PoseEvaluator | None = None,
) -> TranslationWorkspace:
    """Sample the constant-orientation workspace on a grid.

    Args:
        robot: The robot (loaded with geometry for ``interference``).
        rpy: Platform orientation (roll, pitch, yaw) [rad]; ignored by the Delta, whose
            nacelle keeps its orientation.
        bounds: Box to sample (3, 2) [m]; default: a box the evaluator knows contains it.
        step: Grid spacing [m]; default: ``samples`` per axis.
        samples: Samples per controlled axis when ``step`` is not given.
        limits: Kinds checked besides reach: ``stroke``, ``joint``, ``interference``.
        margin: Safety distance for interference [m].
        method: ``auto``, ``closed`` or ``numeric`` (see :func:`evaluator_for`).
        progress: Progress bar: ``True`` / ``False`` force it on / off, ``None`` (default)
            shows it when stderr is a terminal.
        evaluator: Use this evaluator instead of choosing one.

    Returns:
        The sampled workspace.

    Raises:
        InvalidInputError: Bad orientation, box, step, limit kind or method.
        PkdynError: The robot has no platform frame.

    """
    if robot.platform_frame is None:
        raise PkdynError(
            f"{robot.name} declares no platform frame: no workspace to sample; {PLATFORM_HINT}"
        )
    from pkdyn.inputs import matrix, non_negative, vector

    rpy_a = vector("rpy", rpy, 3, "rad")
    margin = non_negative("margin", margin, "m")
    kinds = check_kinds(limits)
    if "interference" in kinds and not robot.collision_model.ngeoms:
        raise InvalidInputError(
            "limits",
            f"{robot.name}: interference needs collision geometry: give the links <collision> "
            "elements (in Python, load with geometry=True), or leave interference out "
            "(--limits stroke joint; limits=('stroke', 'joint'))",
        )
    ev = evaluator if evaluator is not None else evaluator_for(robot, method, progress)
    R = pin.rpy.rpyToMatrix(rpy_a)
    dims = tuple(int(d) for d in robot.task_rows if d < 3)
    box = ev.default_bounds(R) if bounds is None else matrix("bounds", bounds, 3, 2, "m")
    if box.shape != (3, 2) or not np.all(np.isfinite(box)):
        raise InvalidInputError("bounds", "expected 3 rows (min, max) of finite numbers [m]")
    home = robot.platform_placement(robot.q_home).translation
    xs, ys, zs = _grid_axes(box, step, samples, dims, home)
    codes = ev.box_grid(xs, ys, zs, R, kinds, margin, progress)
    return TranslationWorkspace(
        robot=robot.name,
        rpy=rpy_a,
        axes=(xs, ys, zs),
        codes=codes,
        kinds=kinds,
        margin=float(margin),
        method=ev.method,
        dims=dims,
    )
