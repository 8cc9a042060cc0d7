"""Interference of poses placed in closed form: the collision geometry without solving anything.

The definition is the one of :mod:`pkdyn.analysis.collisions`: coal distances between the
description's collision geometries, the pairs of
:func:`~pkdyn.analysis.collisions.interference_checker` (pairs touching by construction or
overlapping at home left out). A closed-form workspace evaluator knows, for each pose, where
every body is, and declares each body as one of:

- :class:`RigidBody`: placed by its joint frame's world rotation and translation per pose (the
  base, the platform, the Delta's arms);
- :class:`AxialBody`: a body whose shapes lie on one line, placed per pose by a point of the
  line and its direction (the legs of a Gough-Stewart platform, the Delta's bars); its shapes
  must be symmetric about the line (a cylinder or capsule along it, or a sphere on it), so the
  body's spin about the line does not matter.

For many poses at once, :meth:`PlacedInterference.bad` first bounds every pair's distance from
below, vectorised: two line shapes by their capsules' segment distance (a capsule contains a
cylinder; the bound is the distance itself when the closest points lie inside both segments),
after a first bound on the bodies of a group (a leg: one capsule spanning its parts); a line
shape and a rigid shape by the gap between their extents along the rigid shape's own axes (its
bounding box); two rigid shapes by the same with one box's corners. Coal is called only for
the pairs of the poses whose bound is below the margin and not exact: the verdicts are coal's,
as on the numeric path.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from pkdyn.analysis.collisions import interference_checker, segment_distance
from pkdyn.exceptions import PkdynError
from pkdyn.model.robot import Robot

__all__ = ["AxialBody", "PlacedInterference", "RigidBody"]

_TOL = 1e-9
_GJK_TOLERANCE = 1e-10
_INNER = 1e-9


@dataclass(frozen=True)
class RigidBody:
    """A body placed per pose by its joint frame's world rotation and translation.

    Attributes:
        key: Name of its placement (``None``: fixed at the world origin, the base).

    """

    key: str | None


@dataclass(frozen=True)
class AxialBody:
    """A body whose shapes lie on a line, placed per pose by a point and a direction.

    Attributes:
        key: Name of its placement: a point of the line (N, 3) [m] and its unit direction.
        axis: The line's unit direction in the body (joint) frame; the line passes through
            the body frame's origin.
        offset: Position of the placement's point along the line from the body frame's origin
            [m] (0: the point is the origin).
        group: Bodies on one line with the same group (a leg's two bodies) are first bounded
            together (-1: alone).

    """

    key: str
    axis: np.ndarray
    offset: float = 0.0
    group: int = -1


Body = RigidBody | AxialBody
Placements = dict[str, tuple[np.ndarray, np.ndarray]]
"""Per placement key: ``(point (N, 3), direction (N, 3))`` of an axial body or ``(rotation
(N, 3, 3), or (3, 3) when it is the same for every pose, translation (N, 3))`` of a rigid one
[m]."""


@dataclass(frozen=True)
class _LinePart:
    key: str
    s: float  # centre along the line from the placement's point [m]
    half: float  # half-length along the line (0: a sphere)
    radius: float
    round: bool  # capsule or sphere: the axis distance minus the radii is exact
    group: int


@dataclass(frozen=True)
class _RigidPart:
    key: str | None
    local: pin.SE3  # the shape in its body frame
    lo: np.ndarray  # its bounding box in its own frame (3,) [m]
    hi: np.ndarray


def _aabb(shape: coal.CollisionGeometry) -> tuple[np.ndarray, np.ndarray]:
    shape.computeLocalAABB()
    box = shape.aabb_local
    return np.array(box.min_), np.array(box.max_)


def _line_part(g: pin.GeometryObject, body: AxialBody, robot: Robot) -> _LinePart:
    axis = np.asarray(body.axis, dtype=float)
    c = np.array(g.placement.translation)
    if np.linalg.norm(c - (c @ axis) * axis) > _TOL:
        raise PkdynError(f"{robot.name}: '{g.name}' lies off its body's axis")
    shape = g.geometry
    s = float(c @ axis) - body.offset
    if isinstance(shape, coal.Sphere):
        return _LinePart(body.key, s, 0.0, float(shape.radius), True, body.group)
    if isinstance(shape, coal.Cylinder | coal.Capsule):
        if np.linalg.norm(np.cross(g.placement.rotation[:, 2], axis)) > _TOL:
            raise PkdynError(f"{robot.name}: '{g.name}' is not along its body's axis")
        return _LinePart(
            body.key,
            s,
            float(shape.halfLength),
            float(shape.radius),
            isinstance(shape, coal.Capsule),
            body.group,
        )
    raise PkdynError(
        f"{robot.name}: '{g.name}' is a {type(shape).__name__}, not a cylinder, capsule or "
        "sphere on its body's axis"
    )


class PlacedInterference:
    """Interference verdicts of poses placed in closed form (see the module docstring).

    Args:
        robot: The robot, loaded with geometry.
        bodies: How each body (joint id) carrying a checked shape is placed; the base (joint
            0) is fixed.

    Raises:
        PkdynError: No collision geometry, a shape on a body without placement, or a shape on
            an axial body that is not symmetric about its line.

    """

    def __init__(self, robot: Robot, bodies: dict[int, Body]) -> None:
        self.robot = robot
        self.checker = interference_checker(robot)
        gm = self.checker.geometry_model
        used = sorted({k for pair in self.checker.ids for k in pair})
        parts: dict[int, _LinePart | _RigidPart] = {}
        for k in used:
            g = gm.geometryObjects[k]
            j = int(g.parentJoint)
            body = RigidBody(None) if j == 0 else bodies.get(j)
            if body is None:
                raise PkdynError(
                    f"{robot.name}: '{g.name}' is on body '{robot.model.names[j]}', which this "
                    "closed form does not place: use the numeric workspace"
                )
            if isinstance(body, AxialBody):
                parts[k] = _line_part(g, body, robot)
            else:
                lo, hi = _aabb(g.geometry)
                parts[k] = _RigidPart(body.key, pin.SE3(g.placement), lo, hi)
        self.parts = parts
        self.shapes = {k: gm.geometryObjects[k].geometry for k in used}
        self._request = coal.DistanceRequest()
        self._request.gjk_tolerance = _GJK_TOLERANCE
        self._request.epa_tolerance = _GJK_TOLERANCE
        self._result = coal.DistanceResult()
        self.coal_calls = 0
        self._index()

    def _index(self) -> None:
        """Index arrays of the vectorised bounds."""
        line = [(k, p) for k, p in self.parts.items() if isinstance(p, _LinePart)]
        keys = [k for k, _ in line]
        col = {k: c for c, k in enumerate(keys)}
        self._line_keys = keys
        self._s = np.array([p.s for _, p in line])
        self._half = np.array([p.half for _, p in line])
        self._radius = np.array([p.radius for _, p in line])
        self._round = np.array([bool(p.round) for _, p in line])
        groups = [p.group if p.group >= 0 else -1 - c for c, (_, p) in enumerate(line)]
        names = sorted(set(groups))
        self._group = np.array([names.index(g) for g in groups], dtype=int)
        self._n_groups = len(names)
        self._members = [np.flatnonzero(self._group == g) for g in range(self._n_groups)]
        ll, lr, rr = [], [], []
        for c, (a, b) in enumerate(self.checker.ids):
            la, lb = a in col, b in col
            if la and lb:
                ll.append((c, col[a], col[b]))
            elif la or lb:
                lr.append((c, col[a] if la else col[b], b if la else a))
            else:
                rr.append((c, a, b))
        self._ll = np.array(ll, dtype=int).reshape(-1, 3)
        self._lr = lr
        self._rr = rr

    # ------------------------------------------------------------------ placements

    def _ends(self, where: Placements) -> tuple[np.ndarray, ...]:
        """End points (N, line parts, 3) of the line shapes' axis segments, points, directions."""
        pts, dirs = [], []
        for k in self._line_keys:
            p, u = where[self.parts[k].key]  # type: ignore[index]
            pts.append(p)
            dirs.append(u)
        O, U = np.stack(pts, axis=1), np.stack(dirs, axis=1)
        c = O + self._s[:, None] * U
        h = self._half[:, None] * U
        return c - h, c + h, O, U

    def _rigid(self, part: _RigidPart, where: Placements, n: int) -> tuple[np.ndarray, ...]:
        """World rotation ((N,) 3, 3) and translation (N, 3) of a rigid shape.

        One rotation (3, 3) serves every pose when it does not change.
        """
        if part.key is None:
            return part.local.rotation, np.broadcast_to(part.local.translation, (n, 3))
        R, t = where[part.key]
        if R.ndim == 2:
            return R @ part.local.rotation, t + part.local.translation @ R.T
        return R @ part.local.rotation, t + R @ part.local.translation

    @staticmethod
    def _to_local(R: np.ndarray, x: np.ndarray) -> np.ndarray:
        """``R^T x`` for points ``x`` (N, k, 3): one rotation (3, 3) or one per pose."""
        return x @ R if R.ndim == 2 else np.einsum("nji,nkj->nki", R, x)

    # ------------------------------------------------------------------ lower bounds

    @staticmethod
    def _box_gap(lo: np.ndarray, hi: np.ndarray, a: np.ndarray, b: np.ndarray, r: Any):
        """Largest per-axis gap between a box and the extents ``[a, b] +- r`` (...)."""
        pmin, pmax = np.minimum(a, b) - r, np.maximum(a, b) + r
        return np.max(np.maximum(lo - pmax, pmin - hi), axis=-1)

    def lower_bounds(self, where: Placements, n: int, margin: float = np.inf) -> np.ndarray:
        """A lower bound of every pair's distance (N, npairs) [m] for ``n`` poses.

        Below ``margin`` the bounds of two line shapes are their capsules' distance; above,
        they may be their groups' (cheaper).
        """
        return self._bounds(where, n, margin)[0]

    def _group_bounds(self, O: np.ndarray, U: np.ndarray) -> np.ndarray:
        """Segment distance minus radii of every pair of groups (N, G, G) [m].

        A group's shapes lie on one line: each spans ``s +- half`` along it from its
        placement's point; the group's capsule spans them all.
        """
        G, N = self._n_groups, O.shape[0]
        L0 = np.empty((N, G, 3))
        L1 = np.empty_like(L0)
        r = np.zeros(G)
        for g in range(G):
            mine = self._members[g]
            first = mine[0]
            origin, u = O[:, first], U[:, first]
            t = np.einsum("npk,nk->np", O[:, mine] - origin[:, None], u) + self._s[mine]
            L0[:, g] = origin + (t - self._half[mine]).min(axis=1)[:, None] * u
            L1[:, g] = origin + (t + self._half[mine]).max(axis=1)[:, None] * u
            r[g] = self._radius[mine].max()
        ia, ib = np.triu_indices(G, 1)
        out = np.full((N, G, G), -np.inf)
        d, _, _ = segment_distance(L0[:, ia], L1[:, ia], L0[:, ib], L1[:, ib])
        out[:, ia, ib] = d - r[ia] - r[ib]
        out[:, ib, ia] = out[:, ia, ib]
        return out

    def _bounds(self, where: Placements, n: int, margin: float) -> tuple[np.ndarray, np.ndarray]:
        """Lower bounds (N, npairs) [m] and where they are the distance itself."""
        out = np.empty((n, len(self.checker.ids)))
        exact = np.zeros(out.shape, dtype=bool)
        if self._line_keys:
            e0, e1, O, U = self._ends(where)
        if self._ll.size:
            c, i, j = self._ll.T
            gi, gj = self._group[i], self._group[j]
            grouped = self._n_groups < len(self._line_keys)  # some group holds several shapes
            if grouped:
                out[:, c] = self._group_bounds(O, U)[:, gi, gj]
                rows, k = np.nonzero(out[:, c] < margin)
            else:
                rows, k = np.nonzero(np.ones((n, c.size), dtype=bool))
            if rows.size:
                ii, jj = i[k], j[k]
                d, si, tj = segment_distance(e0[rows, ii], e1[rows, ii], e0[rows, jj], e1[rows, jj])
                out[rows, c[k]] = d - self._radius[ii] - self._radius[jj]
                exact[rows, c[k]] = (self._round[ii] | ((si > _INNER) & (si < 1.0 - _INNER))) & (
                    self._round[jj] | ((tj > _INNER) & (tj < 1.0 - _INNER))
                )
        rig = {
            k: self._rigid(p, where, n) for k, p in self.parts.items() if isinstance(p, _RigidPart)
        }
        for rk in {r for _, _, r in self._lr}:
            cols = [(c, i) for c, i, r in self._lr if r == rk]
            cc, ii = (np.array(x) for x in zip(*cols, strict=True))
            part = self.parts[rk]
            assert isinstance(part, _RigidPart)
            Rw, tw = rig[rk]
            a = self._to_local(Rw, e0[:, ii] - tw[:, None])  # in the shape's frame
            b = self._to_local(Rw, e1[:, ii] - tw[:, None])
            out[:, cc] = self._box_gap(part.lo, part.hi, a, b, self._radius[ii][:, None])
        for col, ka, kb in self._rr:
            pa, pb = self.parts[ka], self.parts[kb]
            assert isinstance(pa, _RigidPart) and isinstance(pb, _RigidPart)
            (Ra, ta), (Rb, tb) = rig[ka], rig[kb]
            corners = np.array(np.meshgrid(*zip(pb.lo, pb.hi, strict=True))).reshape(3, -1).T
            if Rb.ndim == 2:
                world = (corners @ Rb.T)[None] + tb[:, None]
            else:
                world = np.einsum("nij,kj->nki", Rb, corners) + tb[:, None]
            local = self._to_local(Ra, world - ta[:, None])
            out[:, col] = self._box_gap(pa.lo, pa.hi, local.min(axis=1), local.max(axis=1), 0.0)
        return out, exact

    # ------------------------------------------------------------------ exact distances

    def _transform(self, k: int, n: int, where: Placements) -> coal.Transform3s:
        part = self.parts[k]
        if isinstance(part, _RigidPart):
            if part.key is None:
                return coal.Transform3s(part.local.rotation, part.local.translation)
            R, t = where[part.key]
            Rn = R if R.ndim == 2 else R[n]
            return coal.Transform3s(Rn @ part.local.rotation, t[n] + Rn @ part.local.translation)
        p, u = where[part.key]
        rot = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), u[n]).toRotationMatrix()
        return coal.Transform3s(rot, p[n] + part.s * u[n])

    def distance(self, pair: int, n: int, where: Placements) -> float:
        """Coal's distance of pair ``pair`` (in ``checker.ids``) at pose ``n`` [m]."""
        a, b = self.checker.ids[pair]
        self._result.clear()
        self.coal_calls += 1
        return float(
            coal.distance(
                self.shapes[a],
                self._transform(a, n, where),
                self.shapes[b],
                self._transform(b, n, where),
                self._request,
                self._result,
            )
        )

    def bad(self, where: Placements, n: int, margin: float) -> np.ndarray:
        """(N,) True where a pair of the definition is closer than ``margin``.

        Args:
            where: The bodies' placements of ``n`` poses (:data:`Placements`).
            n: Number of poses.
            margin: Safety distance [m].

        """
        if n == 0:
            return np.zeros(0, dtype=bool)
        lb, exact = self._bounds(where, n, margin)
        close = lb < margin
        out = np.any(close & exact, axis=1)  # decided without coal
        unsure = close & ~exact
        for k in np.flatnonzero(unsure.any(axis=1) & ~out):
            pairs = np.flatnonzero(unsure[k])
            for pair in pairs[np.argsort(lb[k, pairs])]:  # the likeliest first
                if self.distance(int(pair), int(k), where) < margin:
                    out[k] = True
                    break
        return out
