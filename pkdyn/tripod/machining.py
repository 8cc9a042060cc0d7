"""Machining in mode PP: a contouring pass and drilled holes on a wing-box-like skin.

The workpiece under the nacelle at a station is a cylindrical skin of radius ``radius`` (axis
along the station's x, the walking direction; like the upper skin of a wing box, crowned along
its chord): in station coordinates ``(x', y', z)`` (origin below the nacelle on the support,
axes of the support), the surface is ``y' = R sin(beta)``, ``z = z_c - R (1 - cos beta)``, with
outward normal ``n = (0, sin beta, cos beta)``; its crown ``z_c`` is ``clearance`` below the
spindle tip at the station's home pose. The spindle axis (the platform's ``z``) is kept along
``n``: the tool pose at angle ``beta``, height ``h`` above the skin, is
``[x', (R + h) sin beta, z_c - R + (R + h) cos beta, -beta, 0, 0]`` (roll ``-beta``), a
5-axis task in which the nacelle tilts with the curvature.

The machining cycle at a station (all moves rest-to-rest, quintic, in pose coordinates):

1. approach above the start of the contour, plunge to ``depth``, contour along the arc from
   ``beta_a`` to ``beta_b`` (the tool follows the curvature), retract;
2. for each hole: move above it (``approach`` along the normal), plunge to ``depth`` (drilling),
   retract;
3. return to the station's home pose.

The machining wrench is the one the workpiece applies to the tool (convention of
:mod:`pkdyn.analysis.statics`: force in world axes [N], moment in platform axes [N m]): while
drilling, a thrust ``thrust`` along ``+n`` and the cutting torque ``-torque`` about the spindle
axis; while contouring, the cutting force ``-feed_force`` along the feed direction,
``normal_force`` along ``+n`` and the milling torque ``-torque`` about the spindle axis. Plunges
(the holes, and the entry of the contouring pass) carry the drilling wrench while the tip is below
the skin; retracts and rapid moves carry no wrench.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkdyn.dynamics.profiles import motion_law
from pkdyn.dynamics.trajectory import TaskTrajectory, concatenate, point_to_point
from pkdyn.exceptions import InvalidInputError

__all__ = ["MachiningPlan", "machining_task", "surface_pose"]


@dataclass(frozen=True)
class MachiningPlan:
    """Workpiece and machining cycle at one station (SI units).

    Attributes:
        radius: Curvature radius of the skin [m].
        clearance: Crown of the skin below the spindle tip at the station's home pose [m].
        approach: Height above the skin of the approach / retract positions [m].
        depth: Depth of the holes and of the contouring pass [m].
        contour_x: Station ``x'`` of the contouring pass [m].
        contour_y: Chordwise ``y'`` of its start and end [m].
        holes_x: Station ``x'`` of the holes [m].
        holes_y: Chordwise ``y'`` of the holes [m].
        thrust: Drilling thrust [N].
        torque: Cutting torque about the spindle axis [N m].
        feed_force: Contouring force opposing the feed [N].
        normal_force: Contouring force along the skin normal [N].
        move_time: Duration of a rapid move [s].
        plunge_time: Duration of a plunge (drilling feed) or retract [s].
        contour_time: Duration of the contouring pass [s].

    """

    radius: float = 1.5
    clearance: float = 0.02
    approach: float = 0.008
    depth: float = 0.004
    contour_x: float = -0.04
    contour_y: tuple[float, float] = (-0.06, 0.06)
    holes_x: float = 0.04
    holes_y: tuple[float, ...] = (-0.06, 0.0, 0.06)
    thrust: float = 300.0
    torque: float = 3.0
    feed_force: float = 150.0
    normal_force: float = 80.0
    move_time: float = 1.0
    plunge_time: float = 0.8
    contour_time: float = 3.0

    def __post_init__(self) -> None:
        for name in ("radius", "approach", "move_time", "plunge_time", "contour_time"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0.0:
                raise InvalidInputError(name, f"must be > 0, got {value!r}")
        if not np.isfinite(self.depth) or self.depth < 0.0:
            raise InvalidInputError("depth", f"must be >= 0, got {self.depth!r}")
        if not self.clearance > self.approach:
            raise InvalidInputError(
                "clearance",
                f"the skin must lie more than approach ({self.approach}) below the tool's home "
                f"pose, got {self.clearance!r}",
            )
        ys = (*self.contour_y, *self.holes_y)
        if max(abs(y) for y in ys) >= 0.5 * self.radius:
            raise InvalidInputError("holes_y", "chordwise positions must stay within radius / 2")


def surface_pose(plan: MachiningPlan, home: np.ndarray, x: float, y: float, h: float) -> np.ndarray:
    """Tool pose ``[x, y, z, roll, pitch, yaw]`` at height ``h`` above the skin point ``(x', y')``.

    Args:
        plan: The machining plan.
        home: Spindle tip pose at the station's home (6,) [m, rad] (level, yaw 0).
        x: Station ``x'`` [m].
        y: Chordwise ``y'`` of the skin point [m].
        h: Height above the skin along its normal (negative: below the surface) [m].

    Returns:
        The pose (6,) [m, rad].

    """
    R = plan.radius
    beta = float(np.arcsin(y / R))
    z_c = home[2] - plan.clearance
    return np.array(
        [
            home[0] + x,
            home[1] + (R + h) * np.sin(beta),
            z_c - R + (R + h) * np.cos(beta),
            -beta,
            0.0,
            home[5],
        ]
    )


def _normal_and_tangent(beta: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([0.0, np.sin(beta), np.cos(beta)]), np.array([0.0, np.cos(beta), -np.sin(beta)])


def _plunge_wrench(plan: MachiningPlan, beta: float) -> np.ndarray:
    """Drilling (plunging) wrench at skin angle ``beta``: thrust along ``+n``, cutting torque."""
    nrm, _ = _normal_and_tangent(beta)
    return np.concatenate([plan.thrust * nrm, [0.0, 0.0, -plan.torque]])


def _contour(
    plan: MachiningPlan, home: np.ndarray, h: float, dt: float
) -> tuple[TaskTrajectory, np.ndarray]:
    """The contouring arc at height ``h`` and its wrench samples."""
    R = plan.radius
    b0, b1 = (float(np.arcsin(y / R)) for y in plan.contour_y)
    law = motion_law("quintic", plan.contour_time)
    n = max(2, int(round(plan.contour_time / dt)) + 1)
    t = np.linspace(0.0, plan.contour_time, n)
    s, sd, sdd = law(t)
    beta = b0 + (b1 - b0) * s
    bd, bdd = (b1 - b0) * sd, (b1 - b0) * sdd
    rho = R + h
    z0 = home[2] - plan.clearance - R
    pose = np.zeros((n, 6))
    pose[:, 0] = home[0] + plan.contour_x
    pose[:, 1] = home[1] + rho * np.sin(beta)
    pose[:, 2] = z0 + rho * np.cos(beta)
    pose[:, 3] = -beta
    pose[:, 5] = home[5]
    pd = np.zeros((n, 6))
    pd[:, 1] = rho * np.cos(beta) * bd
    pd[:, 2] = -rho * np.sin(beta) * bd
    pd[:, 3] = -bd
    pdd = np.zeros((n, 6))
    pdd[:, 1] = rho * (np.cos(beta) * bdd - np.sin(beta) * bd**2)
    pdd[:, 2] = -rho * (np.sin(beta) * bdd + np.cos(beta) * bd**2)
    pdd[:, 3] = -bdd
    sign = 1.0 if b1 >= b0 else -1.0
    W = np.zeros((n, 6))
    for k, b in enumerate(beta):
        nrm, tan = _normal_and_tangent(float(b))
        W[k, :3] = -plan.feed_force * sign * tan + plan.normal_force * nrm
        W[k, 5] = -plan.torque
    return TaskTrajectory(t, pose, pd, pdd, name="contouring"), W


def machining_task(
    plan: MachiningPlan, home: np.ndarray, dt: float = 0.05
) -> tuple[TaskTrajectory, np.ndarray]:
    """The machining cycle at a station: spindle-tip trajectory and machining wrench.

    Args:
        plan: Workpiece and cycle.
        home: Spindle tip pose at the station's home ``[x, y, z, roll, pitch, yaw]`` [m, rad],
            level (roll = pitch = 0).
        dt: Sample period [s].

    Returns:
        The trajectory (starting and ending at rest at ``home``) and the wrench (N, 6) on the
        tool at each sample (force world [N], moment platform axes [N m]).

    Raises:
        InvalidInputError: ``home`` is not level or not 6 finite numbers.

    """
    home = np.asarray(home, dtype=float).reshape(-1)
    if home.size != 6 or not np.all(np.isfinite(home)):
        raise InvalidInputError("home", f"expected 6 finite numbers, got {home!r}")
    if abs(home[3]) > 1e-9 or abs(home[4]) > 1e-9:
        raise InvalidInputError("home", "the station's home pose must be level (roll = pitch = 0)")
    parts: list[TaskTrajectory] = []
    wrenches: list[np.ndarray] = []

    def move(p0: np.ndarray, p1: np.ndarray, T: float, wrench: np.ndarray | None = None) -> None:
        seg = point_to_point(p0, p1, T, dt=dt)
        parts.append(seg)
        W = np.zeros((seg.t.size, 6))
        if wrench is not None:  # while the tip is below the skin
            axis = np.array([home[1], home[2] - plan.clearance - plan.radius])
            h = np.linalg.norm(seg.pose[:, 1:3] - axis, axis=1) - plan.radius
            W[h < 0.0] = wrench
        wrenches.append(W)

    def pose(x: float, y: float, h: float) -> np.ndarray:
        return surface_pose(plan, home, x, y, h)

    # contouring pass
    start = pose(plan.contour_x, plan.contour_y[0], plan.approach)
    move(home, start, plan.move_time)
    move(
        start,
        pose(plan.contour_x, plan.contour_y[0], -plan.depth),
        plan.plunge_time,
        _plunge_wrench(plan, -float(start[3])),
    )
    arc, W = _contour(plan, home, -plan.depth, dt)
    parts.append(arc)
    wrenches.append(W)
    end = pose(plan.contour_x, plan.contour_y[1], -plan.depth)
    last = pose(plan.contour_x, plan.contour_y[1], plan.approach)
    move(end, last, plan.plunge_time)
    # drilling
    for y in plan.holes_y:
        above = pose(plan.holes_x, y, plan.approach)
        bottom = pose(plan.holes_x, y, -plan.depth)
        move(last, above, plan.move_time)
        move(above, bottom, plan.plunge_time, _plunge_wrench(plan, -float(above[3])))
        move(bottom, above, plan.plunge_time)
        last = above
    move(last, home, plan.move_time)
    task = concatenate(parts, name="machining")
    W_all = np.vstack([wrenches[0]] + [w[1:] for w in wrenches[1:]])
    return task, W_all
