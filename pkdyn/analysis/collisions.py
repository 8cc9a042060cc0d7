"""Minimum distances between the bodies of a robot, with coal, and analytic segment distances.

**Interference, the one definition** (used by :func:`distance_report`, the ``collisions``
command and both workspace paths, closed form and numeric): two collision geometries of
``robot.collision_model`` interfere when coal's distance between them is below the safety
margin. Every pair is checked - leg against leg, leg against platform, leg against base,
platform against base - except two geometries on the same body, or on bodies joined by a
physical tree joint or by a loop closure (they touch by construction; the platform's free-flyer
is a modelling device, so the platform is checked against the base), and pairs that already
overlap at the home configuration (parts nested by design, a rod in its cylinder):
:func:`interference_checker` builds that set and lists the overlapping pairs it leaves out. A
negative distance is a penetration depth.

:func:`distance_report` computes the distances of that set (or of explicit pairs) at a
configuration.

:func:`segment_distance` is the vectorised analytic distance between segments (Ericson's
closest-point algorithm); legs modelled as cylinders of radius ``r`` along ``A_i B_i``
(Merlet, seed 002, section 2.5) interfere when it falls below ``r_i + r_j``. It agrees with
coal's capsule distance to 1e-9 m (see the tests).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.arguments import public
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.results import Result, deprecated_alias, jsonable
from pkdyn.units import columns, quantity

__all__ = [
    "PairDistance",
    "CollisionReport",
    "CollisionChecker",
    "collision_pairs",
    "distance_report",
    "interference_checker",
    "segment_distance",
    "segment_distance_parts",
]

_GJK_TOLERANCE = 1e-10
"""Convergence tolerance of coal's GJK/EPA for the reported distances [m]."""


@dataclass(frozen=True)
class PairDistance(Result):
    """Distance between two collision geometries.

    Attributes:
        a: Name of the first geometry object.
        b: Name of the second geometry object.
        distance: Signed distance [m] (negative: penetration depth).
        point_a: Nearest point on ``a``, world frame (3,) [m].
        point_b: Nearest point on ``b``, world frame (3,) [m].

    """

    a: str
    b: str
    distance: float
    point_a: np.ndarray
    point_b: np.ndarray

    def to_json(self) -> dict[str, Any]:
        """Plain-JSON form (lists of floats) [m]."""
        return jsonable(
            {
                "a": self.a,
                "b": self.b,
                "distance": self.distance,
                "point_a": self.point_a,
                "point_b": self.point_b,
            }
        )

    as_json = deprecated_alias("as_json", "to_json")

    def table(self) -> str:
        """``a - b  distance``."""
        return f"{self.a} - {self.b}: {quantity(self.distance, 'm')}"


@dataclass
class CollisionReport(Result):
    """Distances between geometry pairs at one configuration.

    Attributes:
        min_distance: Smallest pair distance [m] (``inf`` without pairs).
        pairs: Every checked pair, closest first.
        in_collision: ``min_distance < margin``.
        margin: Safety margin [m] the report was made with.
        excluded: Pairs left out because they overlap at home (parts nested by design).

    """

    min_distance: float
    pairs: list[PairDistance] = field(default_factory=list)
    in_collision: bool = False
    margin: float = 0.0
    excluded: list[tuple[str, str]] = field(default_factory=list)

    @property
    def colliding(self) -> list[PairDistance]:
        """The pairs closer than the margin."""
        return [p for p in self.pairs if p.distance < self.margin]

    def to_json(self) -> dict[str, Any]:
        """Plain-JSON form: ``min_distance`` (``None`` if no pair), ``in_collision``, ``pairs``."""
        finite = bool(np.isfinite(self.min_distance))
        return jsonable(
            {
                "min_distance": float(self.min_distance) if finite else None,
                "in_collision": self.in_collision,
                "margin": self.margin,
                "pairs": [p.to_json() for p in self.pairs],
                "excluded": [list(p) for p in self.excluded],
            }
        )

    as_json = deprecated_alias("as_json", "to_json")

    def table(self, top: int = 10) -> str:
        """The smallest distance, the verdict, and the ``top`` closest pairs (0: all)."""
        from pkdyn.inputs import count

        top = count("top", top, 0)
        state = "IN COLLISION" if self.in_collision else "clear"
        lines = [
            f"min distance {quantity(self.min_distance, 'm')} ({state}, margin "
            f"{quantity(self.margin, 'm')})"
        ]
        shown = self.pairs[:top] if top else self.pairs
        rows = [[f"  {p.a}", "-", p.b, quantity(p.distance, "m")] for p in shown]
        if rows:
            lines.append(columns(rows))
        return "\n".join(lines)


def _joint_adjacency(robot: Robot) -> set[tuple[int, int]]:
    """Joint pairs whose bodies touch by construction: a physical tree joint or a closure."""
    out: set[tuple[int, int]] = set()
    for a, b in robot._physical_edges():
        out.add((min(a, b), max(a, b)))
    return out


def _resolve(gm: pin.GeometryModel, model: pin.Model, name: str) -> list[int]:
    """Geometry ids named ``name``: a geometry object, or every geometry on a link/frame."""
    if gm.existGeometryName(name):
        return [int(gm.getGeometryId(name))]
    ids = [
        k
        for k, g in enumerate(gm.geometryObjects)
        if g.parentFrame < model.nframes and model.frames[g.parentFrame].name == name
    ]
    if not ids:
        known = ", ".join(g.name for g in gm.geometryObjects)
        raise InvalidInputError("pairs", f"no collision geometry or link named '{name}' ({known})")
    return ids


def collision_pairs(
    robot: Robot, pairs: Sequence[tuple[str, str]] | None = None
) -> list[tuple[int, int]]:
    """Geometry-id pairs to check.

    Args:
        robot: The robot (loaded with ``geometry=True``).
        pairs: Explicit pairs of geometry or link names (a link stands for all its geometries);
            ``None`` selects every pair except geometries on the same body or on bodies joined by
            a physical tree joint or a loop closure.

    Returns:
        Sorted list of ``(i, j)`` geometry ids with ``i < j``.

    Raises:
        InvalidInputError: A name is neither a geometry nor a link with geometry.

    """
    gm, model = robot.collision_model, robot.model
    if pairs is not None:
        out: set[tuple[int, int]] = set()
        for na, nb in pairs:
            for i in _resolve(gm, model, na):
                for j in _resolve(gm, model, nb):
                    if i != j:
                        out.add((min(i, j), max(i, j)))
        return sorted(out)
    adjacent = _joint_adjacency(robot)
    objs = gm.geometryObjects
    chosen = []
    for i in range(len(objs)):
        for j in range(i + 1, len(objs)):
            ji, jj = int(objs[i].parentJoint), int(objs[j].parentJoint)
            if ji == jj or (min(ji, jj), max(ji, jj)) in adjacent:
                continue
            chosen.append((i, j))
    return chosen


class CollisionChecker:
    """Reusable coal distance evaluator for one robot and one set of pairs.

    Holds its own geometry model copy (with the collision pairs) and geometry data, so checking
    many configurations does not rebuild them and ``robot.collision_model`` is left untouched.

    Args:
        robot: The robot (loaded with ``geometry=True``).
        pairs: Explicit geometry/link name pairs, or ``None`` for the default selection
            (see :func:`collision_pairs`).

    Raises:
        PkdynError: The robot has no collision geometry pair to check, or mesh files of its
            description were not found (naming them).

    """

    def __init__(self, robot: Robot, pairs: Sequence[tuple[str, str]] | None = None) -> None:
        if robot.missing_meshes:
            from pkdyn.model.warn import missing_list

            raise PkdynError(
                f"{robot.name}: collision checks need the geometry of "
                f"{len(robot.missing_meshes)} mesh file(s) that were not found when it was "
                f"loaded: {missing_list(robot.missing_meshes)} (pass package_dirs= or fix "
                "the paths)"
            )
        if robot.dropped_collisions:
            raise PkdynError(
                f"{robot.name}: collision checks need the collision geometry that was left out "
                f"when it was loaded (malformed): {'; '.join(robot.dropped_collisions[:3])}"
                + (" ..." if len(robot.dropped_collisions) > 3 else "")
                + " (fix the description)"
            )
        self.robot = robot
        self.ids = collision_pairs(robot, pairs)
        if not self.ids:
            raise PkdynError(
                f"{robot.name}: no collision geometry pair to check: give the links <collision> "
                "elements in the description (in Python, also load it with geometry=True)"
            )
        self.geometry_model = robot.collision_model.copy()
        self.geometry_model.removeAllCollisionPairs()
        for i, j in self.ids:
            self.geometry_model.addCollisionPair(pin.CollisionPair(i, j))
        self.geometry_data = pin.GeometryData(self.geometry_model)
        for req in self.geometry_data.distanceRequests:
            req.gjk_tolerance = _GJK_TOLERANCE
            req.epa_tolerance = _GJK_TOLERANCE
        self.data = robot.model.createData()
        names = [g.name for g in self.geometry_model.geometryObjects]
        self.names = [(names[i], names[j]) for i, j in self.ids]
        self.excluded: list[tuple[str, str]] = []  # (interference_checker: overlap at home)

    def distances(self, q: np.ndarray) -> np.ndarray:
        """Signed distance of every pair (in ``self.ids`` order) at ``q`` [m]."""
        pin.computeDistances(
            self.robot.model, self.data, self.geometry_model, self.geometry_data, q
        )
        return np.array([r.min_distance for r in self.geometry_data.distanceResults])

    def report(self, q: np.ndarray, margin: float = 0.0) -> CollisionReport:
        """Full report at ``q`` (see :func:`distance_report`)."""
        q = as_finite("q", q, self.robot.nq)
        d = self.distances(q)
        res = self.geometry_data.distanceResults
        pairs = [
            PairDistance(
                a,
                b,
                float(d[k]),
                np.array(res[k].getNearestPoint1()),
                np.array(res[k].getNearestPoint2()),
            )
            for k, (a, b) in enumerate(self.names)
        ]
        pairs.sort(key=lambda p: p.distance)
        dmin = pairs[0].distance
        return CollisionReport(dmin, pairs, bool(dmin < margin), float(margin), self.excluded)


def interference_checker(robot: Robot) -> CollisionChecker:
    """The pairs of the interference definition (module docstring), as a checker.

    Every default pair (:func:`collision_pairs`) except those closer than 0 at
    ``robot.q_home``; those are listed in the checker's ``excluded`` attribute.

    Args:
        robot: The robot (loaded with ``geometry=True``).

    Returns:
        The checker (``excluded``: the name pairs left out).

    Raises:
        PkdynError: The robot has no collision geometry pair to check, or every pair overlaps
            at home.

    """
    full = CollisionChecker(robot)
    d = full.distances(robot.q_home)
    keep = [n for n, x in zip(full.names, d, strict=True) if x >= 0.0]
    excluded = [n for n, x in zip(full.names, d, strict=True) if x < 0.0]
    if not keep:
        raise PkdynError(
            f"{robot.name}: every collision pair already overlaps at home: no interference "
            "to check (give the parts collision geometry that does not overlap at rest)"
        )
    checker = full if not excluded else CollisionChecker(robot, keep)
    checker.excluded = excluded
    return checker


def _pairs(pairs: Any) -> list[tuple[str, str]]:
    """Pairs of names (two strings each), or a refusal naming ``pairs``."""
    from pkdyn.inputs import names

    if isinstance(pairs, str | bytes) or not isinstance(pairs, Sequence | np.ndarray):
        raise InvalidInputError("pairs", f"expected pairs of names, got {pairs!r:.60}")
    out = []
    for p in pairs:
        two = names("pairs", p, what="geometry or link") if not isinstance(p, str) else (p,)
        if len(two) != 2:
            raise InvalidInputError("pairs", f"expected pairs of two names, got {p!r:.60}")
        out.append((two[0], two[1]))
    return out


@public
def distance_report(
    robot: Robot,
    q: np.ndarray,
    margin: float = 0.0,
    pairs: Sequence[tuple[str, str]] | None = None,
) -> CollisionReport:
    """Distances between the robot's collision geometries at a configuration (coal).

    Args:
        robot: The robot (loaded with ``geometry=True``).
        q: Configuration (nq,), normally assembled.
        margin: Safety margin [m]: the report is ``in_collision`` when a pair is closer.
        pairs: Explicit pairs of geometry or link names; default: the interference definition
            (every pair except those on the same body, on bodies joined by a physical joint or
            a loop closure, and those overlapping at home: listed in ``excluded``).

    Returns:
        The report, pairs sorted closest first.

    Raises:
        InvalidInputError: Bad ``q`` or an unknown name in ``pairs``.
        PkdynError: No collision geometry pair to check.

    """
    from pkdyn.inputs import non_negative

    margin = non_negative("margin", margin, "m")
    if pairs is not None:
        pairs = _pairs(pairs)
    checker = interference_checker(robot) if pairs is None else CollisionChecker(robot, pairs)
    return checker.report(q, margin)


def segment_distance(
    p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distance between segments ``[p1, q1]`` and ``[p2, q2]``, vectorised (Ericson, 2005).

    The unclamped line-line parameter ``s`` is clamped to [0, 1], ``t`` follows from it and,
    when clamped, ``s`` is recomputed from the clamped ``t``; degenerate (point) segments are
    handled.

    Args:
        p1: Start points of the first segments (..., 3) [m].
        q1: End points of the first segments (..., 3) [m].
        p2: Start points of the second segments (..., 3) [m].
        q2: End points of the second segments (..., 3) [m]; all four broadcast together.

    Returns:
        ``(d, s, t)``: distances (...) [m] and parameters of the closest points
        ``p1 + s (q1 - p1)`` and ``p2 + t (q2 - p2)`` (...).

    """
    d1 = np.asarray(q1, dtype=float) - p1
    d2 = np.asarray(q2, dtype=float) - p2
    r = np.asarray(p1, dtype=float) - p2
    a = np.einsum("...i,...i->...", d1, d1)
    e = np.einsum("...i,...i->...", d2, d2)
    return segment_distance_parts(d1, d2, r, a, e)


def segment_distance_parts(
    d1: np.ndarray, d2: np.ndarray, r: np.ndarray, a: np.ndarray, e: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`segment_distance` from its parts (the arithmetic after them, the same bits).

    For callers that pair a few segments many ways: each segment's direction and squared
    length made once, gathered per pair (an element of ``einsum`` over the last axis does not
    depend on the other elements).

    Args:
        d1: Directions ``q1 - p1`` of the first segments (..., 3) [m].
        d2: Directions ``q2 - p2`` of the second segments (..., 3) [m].
        r: ``p1 - p2`` (..., 3) [m].
        a: ``d1 . d1`` (...) [m^2], as ``np.einsum("...i,...i->...", d1, d1)``.
        e: ``d2 . d2`` (...) [m^2], likewise.

    Returns:
        ``(d, s, t)`` as :func:`segment_distance`.

    """
    f = np.einsum("...i,...i->...", d2, r)
    c = np.einsum("...i,...i->...", d1, r)
    b = np.einsum("...i,...i->...", d1, d2)
    tiny = 1e-300
    a_ok = a > tiny
    e_ok = e > tiny
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > 1e-14 * a * e, np.clip((b * f - c * e) / denom, 0.0, 1.0), 0.0)
        s = np.where(a_ok, s, 0.0)
        t = np.where(e_ok, (b * s + f) / e, 0.0)
        lo, hi = t < 0.0, t > 1.0
        t = np.clip(t, 0.0, 1.0)
        s_lo = np.clip(-c / a, 0.0, 1.0)
        s_hi = np.clip((b - c) / a, 0.0, 1.0)
    s = np.where(a_ok & lo, s_lo, np.where(a_ok & hi, s_hi, s))
    # Second segment a point: project it on the first (the first a point: t above is exact).
    s = np.where(a_ok & ~e_ok, s_lo, s)
    diff = r + s[..., None] * d1 - t[..., None] * d2
    return np.sqrt(np.einsum("...i,...i->...", diff, diff)), s, t
