"""Orientation workspace at a fixed point (Merlet, seed 002, chapters 2 and 3).

The platform frame's origin ``C`` stays at a fixed position; the platform turns by ``theta1``
about a fixed axis ``X1``, then by ``theta2`` about a fixed axis ``X2`` (both in the base
frame): ``R = Rot(X2, theta2) Rot(X1, theta1) R0``. A unit vector ``N`` fixed to the platform
then points at ``N_e = R N`` on the unit sphere; for each ``theta1`` the reachable ``N_e`` form
arcs of a circle ``C^N``. The allowed arcs respect the leg strokes, the base joints' cones or
pyramids and the leg interference (legs as cylinders), as in Merlet's algorithm.

Merlet cuts each circle at its critical points: on a circle, ``rho_i^2`` and every
pyramid-face projection are ``a1 sin(theta2) + a2 cos(theta2) + a3`` (his eq. 2.4), so their
roots are closed forms (:func:`stroke_roots`, :func:`pyramid_roots`). Here the circle is cut at
those roots and at ``n2`` samples (for the leg interference, whose critical points are sampled),
each piece is tested at its middle, and each change of validity is refined by bisection to
``tol``: stroke and joint arcs are never missed, interference arcs shorter than the sampling
step can be.

``θ1`` and ``-θ1`` (``θ1`` and ``2π - θ1``) give the same circle ``C^N`` when ``N`` is ``X2``
but not the same platform orientations, hence Merlet's two sphere maps, for ``θ1`` in
``[0, π]`` and ``[π, 2π]``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.arguments import public
from pkdyn.model.description import PyramidLimit
from pkdyn.model.robot import Robot
from pkdyn.progress import progress as progress_bar
from pkdyn.results import Result, deprecated_alias, jsonable
from pkdyn.units import columns, quantity
from pkdyn.workspace.legs import HexapodLegs, leg_interference, leg_placements
from pkdyn.workspace.limits import LIMIT_KINDS, REACHABLE, check_kinds, pyramid_normals
from pkdyn.workspace.placed_interference import PlacedInterference

__all__ = [
    "MelStudy",
    "OrientationWorkspace",
    "orientation_workspace",
    "stroke_roots",
    "pyramid_roots",
    "mel_study",
    "rotations",
]


def _unit(name: str, v: Sequence[float]) -> np.ndarray:
    from pkdyn.inputs import vector

    a = vector(name, v, 3)
    n = float(np.linalg.norm(a)) if a.shape == (3,) else 0.0
    if not n > 1e-12 or not np.all(np.isfinite(a)):
        got = " ".join(f"{x:g}" for x in np.ravel(a))
        raise InvalidInputError(name, f"expected a non-zero 3-vector, got [{got}]")
    return a / n


TOL_MIN = 1e-14
"""Finest bisection tolerance on an angle [rad] (a few ulps of 2 pi: finer never ends)."""

MAX_ORIENTATIONS = 5_000_000
"""Most sampled orientations of one orientation workspace (refused beyond, with the estimate)."""


def _axis_angle(axis: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Rotations about ``axis`` by angles ``theta`` (...,) -> (..., 3, 3) (Rodrigues)."""
    K = pin.skew(axis)
    c, s = np.cos(theta)[..., None, None], np.sin(theta)[..., None, None]
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def rotations(
    X1: np.ndarray, X2: np.ndarray, R0: np.ndarray, theta1: np.ndarray, theta2: np.ndarray
) -> np.ndarray:
    """``Rot(X2, theta2) Rot(X1, theta1) R0`` for broadcast angle arrays -> (..., 3, 3)."""
    return _axis_angle(X2, theta2) @ _axis_angle(X1, theta1) @ R0


@dataclass
class OrientationWorkspace(Result):
    """Allowed rotations at a fixed point, as arcs on Merlet's circles.

    Attributes:
        robot: Robot name.
        center: Position of ``C`` [m].
        N: Platform-fixed unit vector (platform frame).
        X1: First rotation axis (base frame).
        X2: Second rotation axis (base frame).
        R0: Reference platform orientation.
        theta1: Sampled first angles (n1,) [rad].
        theta2: Sampled second angles (n2,) [rad].
        codes: First limit broken per sample (n1, n2) (-1: allowed).
        arcs: Per ``theta1``, allowed ``theta2`` intervals ``(start, end)`` [rad] with
            ``start < end`` (``end`` may exceed 2 pi across the origin; ``(0, 2 pi)`` for a
            full circle).
        kinds: Limit kinds checked.
        margin: Safety distance for interference [m].

    """

    robot: str
    center: np.ndarray
    N: np.ndarray
    X1: np.ndarray
    X2: np.ndarray
    R0: np.ndarray
    theta1: np.ndarray
    theta2: np.ndarray
    codes: np.ndarray
    arcs: list[list[tuple[float, float]]] = field(default_factory=list)
    kinds: tuple[str, ...] = ()
    margin: float = 0.0

    @staticmethod
    def _angles(theta1: Any, theta2: Any) -> tuple[np.ndarray, np.ndarray]:
        """The two angle arrays (n,) each [rad], checked: finite, of one length."""
        from pkdyn.inputs import vector

        t1, t2 = vector("theta1", theta1, unit="rad"), vector("theta2", theta2, unit="rad")
        if t1.size != t2.size or t1.size == 0:
            raise InvalidInputError(
                "theta2", f"{t2.size} angles for {t1.size} theta1: give as many of each (>= 1)"
            )
        return t1, t2

    def direction(self, theta1: np.ndarray, theta2: np.ndarray) -> np.ndarray:
        """``N_e`` (..., 3) for angles (broadcast)."""
        theta1, theta2 = self._angles(theta1, theta2)
        return rotations(self.X1, self.X2, self.R0, theta1, theta2) @ self.N

    def jacobian(self, theta1: np.ndarray, theta2: np.ndarray) -> np.ndarray:
        """Area element ``|dN_e/dtheta1 x dN_e/dtheta2|`` of the (theta1, theta2) map."""
        theta1, theta2 = self._angles(theta1, theta2)
        n1 = (_axis_angle(self.X1, theta1) @ self.R0) @ self.N
        R2 = _axis_angle(self.X2, theta2)
        d1 = R2 @ np.cross(self.X1, n1)[..., :, None]
        Ne = R2 @ n1[..., :, None]
        d2 = np.cross(self.X2, Ne[..., 0])
        return np.linalg.norm(np.cross(d1[..., 0], d2), axis=-1)

    def full_circles(self) -> np.ndarray:
        """(n1,) True where the whole circle is allowed."""
        return np.array(
            [len(a) == 1 and a[0][1] - a[0][0] >= 2 * math.pi - 1e-9 for a in self.arcs]
        )

    def allowed_fraction(self) -> float:
        """Fraction of the (theta1, theta2) torus allowed (arc lengths)."""
        total = sum(e - s for arcs in self.arcs for s, e in arcs)
        return total / (2 * math.pi * len(self.arcs))

    def solid_angle(self, half: int | None = None) -> float:
        """Area of the allowed region on the unit sphere [sr].

        The (theta1, theta2) torus covers the band swept by ``N_e`` twice; the result is half
        the integral over the whole torus (at most 4 pi), or, with ``half`` 0 or 1, the
        integral over ``theta1`` in ``[0, pi)`` or ``[pi, 2 pi)`` (Merlet's two maps).

        Args:
            half: ``None``, 0 or 1.

        Returns:
            Solid angle [sr] (Gauss-Legendre in theta2 on each arc, rectangles in theta1).

        """
        x, w = np.polynomial.legendre.leggauss(8)
        if half is not None and (isinstance(half, bool) or half not in (0, 1)):
            raise InvalidInputError("half", f"expected None, 0 or 1, got {half!r:.40}")
        d1 = 2 * math.pi / len(self.theta1)
        total = 0.0
        for t1, arcs in zip(self.theta1, self.arcs, strict=True):
            in_half = half is None or (t1 < math.pi) == (half == 0)
            if not in_half:
                continue
            for s, e in arcs:
                t2 = 0.5 * (e - s) * x + 0.5 * (e + s)
                total += 0.5 * (e - s) * float(w @ self.jacobian(np.full(8, t1), t2)) * d1
        return 0.5 * total if half is None else total

    @property
    def limits_hit(self) -> dict[str, int]:
        """(theta1, theta2) samples rejected per limit kind (first kind broken)."""
        return {k: int(np.count_nonzero(self.codes == LIMIT_KINDS.index(k))) for k in self.kinds}

    def arc_points(self, per_radian: int = 40) -> list[np.ndarray]:
        """``N_e`` polylines (M, 3) of every allowed arc, for plots."""
        out = []
        from pkdyn.inputs import count

        per_radian = count("per_radian", per_radian, 1, 100_000)
        for t1, arcs in zip(self.theta1, self.arcs, strict=True):
            for s, e in arcs:
                t2 = np.linspace(s, e, max(2, int(per_radian * (e - s)) + 1))
                out.append(self.direction(np.full(t2.size, t1), t2))
        return out

    def bounds(self) -> np.ndarray | None:
        """Bounding box (3, 2) of the allowed ``N_e`` (on the samples), or ``None``."""
        m = self.codes == REACHABLE
        if not m.any():
            return None
        T1, T2 = np.meshgrid(self.theta1, self.theta2, indexing="ij")
        d = self.direction(T1[m], T2[m])
        return np.column_stack([d.min(axis=0), d.max(axis=0)])

    def tilt_max(self) -> float:
        """Largest angle [rad] between an allowed ``N_e`` and its reference ``R0 N``."""
        m = self.codes == REACHABLE
        if not m.any():
            return float("nan")
        T1, T2 = np.meshgrid(self.theta1, self.theta2, indexing="ij")
        d = self.direction(T1[m], T2[m])
        return float(np.max(np.arccos(np.clip(d @ (self.R0 @ self.N), -1.0, 1.0))))

    def table(self) -> str:
        """Allowed solid angle, its halves, full circles, largest tilt, rejections."""
        tilt = self.tilt_max()
        return "\n".join(
            [
                f"orientation workspace: {quantity(self.solid_angle(), 'sr')} allowed "
                f"({quantity(100 * self.allowed_fraction(), '%')} of the directions; halves "
                f"{quantity(self.solid_angle(0), 'sr')} and {quantity(self.solid_angle(1), 'sr')})",
                f"full circles: {int(self.full_circles().sum())}, largest tilt "
                + ("n/a" if not np.isfinite(tilt) else quantity(tilt, "rad"))
                + f" ({quantity(np.degrees(tilt), 'deg')})" * bool(np.isfinite(tilt)),
                f"samples: {int(self.codes.size)}, rejected by: "
                + ", ".join(f"{k} {v}" for k, v in self.limits_hit.items()),
            ]
        )

    as_json = deprecated_alias("as_json", "to_json")

    def to_json(self) -> dict[str, Any]:
        """``volume`` (solid angle [sr]), ``bounds``, ``samples``, ``limits_hit`` and more."""
        b = self.bounds()
        return jsonable(
            {
                "kind": "orientation",
                "volume": self.solid_angle(),
                "volume_unit": "sr",
                "solid_angle_halves": [self.solid_angle(0), self.solid_angle(1)],
                "allowed_fraction": self.allowed_fraction(),
                "full_circles": int(self.full_circles().sum()),
                "bounds": None if b is None else b.tolist(),
                "tilt_max": self.tilt_max(),
                "samples": int(self.codes.size),
                "limits_hit": self.limits_hit,
                "center": self.center.tolist(),
                "N": self.N.tolist(),
                "X1": self.X1.tolist(),
                "X2": self.X2.tolist(),
                "margin": self.margin,
            }
        )


class MelStudy(dict[str, OrientationWorkspace], Result):
    """Merlet's MEL study (:func:`mel_study`): name of the set of limits -> workspace."""

    def to_json(self) -> dict[str, Any]:
        """The last (most limited) case's figures, and every case under ``cases``."""
        cases = {name: ow.to_json() for name, ow in self.items()}
        out = dict(list(cases.values())[-1]) if cases else {}
        out["cases"] = cases
        return out

    def table(self) -> str:
        """The allowed solid angle of each set of limits."""
        rows = [
            [
                f"  {name}",
                quantity(ow.solid_angle(), "sr"),
                f"full circles {int(ow.full_circles().sum())}",
            ]
            for name, ow in self.items()
        ]
        return "MEL prototype study (Merlet ch. 3), allowed solid angle:\n" + columns(rows)


def _codes(
    legs: HexapodLegs,
    inter: PlacedInterference | None,
    C: np.ndarray,
    R: np.ndarray,
    kinds: tuple[str, ...],
    margin: float,
) -> np.ndarray:
    """First broken limit for platform orientations ``R`` (M, 3, 3) at ``C``."""
    v = legs.leg_vectors(np.broadcast_to(C, (R.shape[0], 3)), R)
    out = np.full(R.shape[0], REACHABLE, dtype=np.int8)
    for kind in kinds[1:]:
        todo = np.flatnonzero(out == REACHABLE)
        vv = v[todo]
        if kind == "stroke":
            bad = legs.stroke_bad(vv)
        elif kind == "joint":
            bad = legs.joint_bad(vv)
        else:
            assert inter is not None
            Ck = np.broadcast_to(C, (todo.size, 3))
            bad = inter.bad(leg_placements(inter.robot, legs, Ck, R[todo], vv), todo.size, margin)
        out[todo[bad]] = LIMIT_KINDS.index(kind)
    return out


@public
def orientation_workspace(
    robot: Robot,
    center: Sequence[float] | None = None,
    N: Sequence[float] = (0.0, 0.0, 1.0),
    X1: Sequence[float] = (1.0, 0.0, 0.0),
    X2: Sequence[float] = (0.0, 0.0, 1.0),
    rpy0: Sequence[float] = (0.0, 0.0, 0.0),
    n1: int = 180,
    n2: int = 360,
    limits: Sequence[str] = ("stroke", "joint", "interference"),
    margin: float = 0.0,
    tol: float = 1e-10,
    progress: bool | None = None,
) -> OrientationWorkspace:
    """Merlet's orientation workspace of a leg robot at a fixed point.

    Args:
        robot: A leg robot (see :mod:`pkdyn.workspace.legs`), with geometry for
            ``interference``.
        center: Position of the platform frame origin ``C`` [m] (default: home).
        N: Platform-fixed unit vector whose reachable directions are mapped (platform frame).
        X1: First rotation axis (base frame).
        X2: Second rotation axis (base frame).
        rpy0: Reference orientation ``R0`` (roll, pitch, yaw) [rad].
        n1: Samples of ``theta1`` over ``[0, 2 pi)``.
        n2: Samples of ``theta2`` over ``[0, 2 pi)`` before the arc ends are refined.
        limits: Kinds checked: ``stroke``, ``joint``, ``interference``.
        margin: Safety distance for interference [m].
        tol: Bisection tolerance on the arc ends [rad].
        progress: Progress bar: ``True`` / ``False`` force it on / off, ``None`` (default)
            shows it when stderr is a terminal.

    Returns:
        The orientation workspace.

    Raises:
        InvalidInputError: Bad vectors, sample counts or limit kinds.
        PkdynError: Not a leg robot, or interference without collision geometry.

    """
    legs = HexapodLegs.from_robot(robot, "the orientation workspace")
    kinds = check_kinds(limits)
    inter = None
    if "interference" in kinds:
        if not robot.collision_model.ngeoms:
            raise InvalidInputError(
                "limits",
                f"{robot.name}: interference needs collision geometry: give the links "
                "<collision> elements (in Python, load with geometry=True), or leave "
                "interference out (--limits stroke joint; limits=('stroke', 'joint'))",
            )
        inter = leg_interference(robot)
    from pkdyn.inputs import count, non_negative, positive, vector

    n1 = count("n1", n1, 2)
    n2 = count("n2", n2, 8)
    margin = non_negative("margin", margin, "m")
    tol = positive("tol", tol, "rad")
    if tol < TOL_MIN:
        raise InvalidInputError(
            "tol", f"{tol:g} rad: below the {TOL_MIN:g} rad floating point resolves on an angle"
        )
    if n1 * n2 > MAX_ORIENTATIONS:
        raise InvalidInputError(
            "samples",
            f"n1 x n2 = {n1} x {n2} = {n1 * n2:.3g} orientations (about "
            f"{n1 * n2 / 2e4 / 60:.2g} min); at most {MAX_ORIENTATIONS:.0e}",
        )
    if center is None:
        C = robot.platform_placement(robot.q_home).translation.copy()
    else:
        C = vector("center", center, 3, "m")
    Nv, x1, x2 = _unit("N", N), _unit("X1", X1), _unit("X2", X2)
    R0 = pin.rpy.rpyToMatrix(vector("rpy0", rpy0, 3, "rad"))
    t1 = 2 * math.pi * np.arange(n1) / n1
    t2 = 2 * math.pi * np.arange(n2) / n2
    codes = np.empty((n1, n2), dtype=np.int8)
    arcs: list[list[tuple[float, float]]] = []
    for i in progress_bar(range(n1), "orientation workspace", "row", progress, leave=False):
        R = rotations(x1, x2, R0, np.full(n2, t1[i]), t2)
        codes[i] = _codes(legs, inter, C, R, kinds, margin)
        arcs.append(_arcs(legs, inter, C, x1, x2, R0, float(t1[i]), t2, kinds, margin, tol))
    return OrientationWorkspace(
        robot=robot.name,
        center=C,
        N=Nv,
        X1=x1,
        X2=x2,
        R0=R0,
        theta1=t1,
        theta2=t2,
        codes=codes,
        arcs=arcs,
        kinds=kinds,
        margin=float(margin),
    )


def _arcs(
    legs: HexapodLegs,
    inter: PlacedInterference | None,
    C: np.ndarray,
    x1: np.ndarray,
    x2: np.ndarray,
    R0: np.ndarray,
    t1: float,
    t2: np.ndarray,
    kinds: tuple[str, ...],
    margin: float,
    tol: float,
) -> list[tuple[float, float]]:
    """Allowed theta2 intervals on one circle.

    The circle is cut at the samples and at Merlet's critical points of the stroke and pyramid
    limits (closed form), so no stroke or joint arc is missed however coarse the sampling; the
    validity is tested in the middle of each piece and every change is refined by bisection.
    """
    cuts = [t2]
    if "stroke" in kinds:
        cuts.append(stroke_roots(legs, C, x1, x2, R0, t1))
    if "joint" in kinds:
        cuts.append(pyramid_roots(legs, C, x1, x2, R0, t1))
    b = np.unique(np.concatenate(cuts) % (2 * math.pi))
    mid = 0.5 * (b + np.append(b[1:], b[0] + 2 * math.pi))
    ok = _codes(legs, inter, C, rotations(x1, x2, R0, np.full(mid.size, t1), mid), kinds, margin)
    ok = ok == REACHABLE
    if ok.all():
        return [(0.0, 2 * math.pi)]
    if not ok.any():
        return []
    k = np.flatnonzero(ok != np.roll(ok, -1))  # change between middles k and k + 1
    lo = mid[k]
    hi = np.where(k + 1 < mid.size, mid[(k + 1) % mid.size], mid[0] + 2 * math.pi)
    inside_lo = ok[k]
    a, bb = np.where(inside_lo, lo, hi), np.where(inside_lo, hi, lo)  # a allowed, bb not
    while np.max(np.abs(bb - a)) > tol:
        m = 0.5 * (a + bb)
        good = _codes(legs, inter, C, rotations(x1, x2, R0, np.full(m.size, t1), m), kinds, margin)
        g = good == REACHABLE
        a, bb = np.where(g, m, a), np.where(g, bb, m)
    ends = a % (2 * math.pi)
    starts_here = ~inside_lo  # forbidden -> allowed: an arc starts at this change
    out = []
    m_count = len(k)
    first = int(np.argmax(starts_here))
    for j in range(m_count):
        idx = (first + j) % m_count
        if starts_here[idx]:
            s0, e0 = float(ends[idx]), float(ends[(idx + 1) % m_count])
            out.append((s0, e0 if e0 > s0 else e0 + 2 * math.pi))
    return out


def _sinusoid_roots(a1: float, a2: float, a3: float) -> list[float]:
    """Roots in ``[0, 2 pi)`` of ``a1 sin(t) + a2 cos(t) + a3 = 0``."""
    amp = math.hypot(a1, a2)
    if amp == 0.0 or abs(a3) > amp:
        return []
    phase, d = math.atan2(a1, a2), math.acos(-a3 / amp)
    return [(phase + d) % (2 * math.pi), (phase - d) % (2 * math.pi)]


def _circle_terms(
    legs: HexapodLegs, i: int, C: np.ndarray, X2: np.ndarray, R1: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Leg vector on the circle: ``v_i(theta2) = u + cos(theta2) w_perp + sin(theta2) X2 x w``."""
    w = R1 @ legs.B[i]
    w_par = (w @ X2) * X2
    return C - legs.A[i] + w_par, w - w_par, np.cross(X2, w)


def stroke_roots(
    legs: HexapodLegs,
    C: np.ndarray,
    X1: np.ndarray,
    X2: np.ndarray,
    R0: np.ndarray,
    theta1: float,
) -> np.ndarray:
    """Closed-form theta2 [rad] where a leg reaches a stroke end (Merlet's eq. 2.4).

    With ``w = Rot(X1, theta1) R0 b_i`` split along ``X2``, ``rho_i^2 = a3 + a2 cos(theta2) +
    a1 sin(theta2)``; ``rho_i = rho_min`` or ``rho_max`` then has up to two roots each.

    Args:
        legs: Leg geometry.
        C: Fixed point [m].
        X1: First axis (unit).
        X2: Second axis (unit).
        R0: Reference orientation.
        theta1: First angle [rad].

    Returns:
        Sorted roots in ``[0, 2 pi)`` [rad].

    """
    R1 = _axis_angle(X1, np.array(theta1)) @ R0
    roots: list[float] = []
    for i in range(legs.n):
        u, c, s = _circle_terms(legs, i, C, X2, R1)
        a3, a2, a1 = float(u @ u + c @ c), 2.0 * float(u @ c), 2.0 * float(u @ s)
        for rho in (legs.rho_min[i], legs.rho_max[i]):
            roots += _sinusoid_roots(a1, a2, a3 - rho**2)
    return np.sort(np.array(roots))


def pyramid_roots(
    legs: HexapodLegs,
    C: np.ndarray,
    X1: np.ndarray,
    X2: np.ndarray,
    R0: np.ndarray,
    theta1: float,
) -> np.ndarray:
    """Closed-form theta2 [rad] where a leg meets a face of its base joint's pyramid.

    A face through ``A_i`` with normal ``n`` is met where ``n . v_i = 0``, again
    ``a1 sin(theta2) + a2 cos(theta2) + a3 = 0`` (Merlet, section 2.4). Cone limits give no
    such roots (their ends are found by bisection).

    Returns:
        Sorted roots in ``[0, 2 pi)`` [rad].

    """
    R1 = _axis_angle(X1, np.array(theta1)) @ R0
    roots: list[float] = []
    for i, lim in enumerate(legs.limits):
        if not isinstance(lim, PyramidLimit):
            continue
        u, c, s = _circle_terms(legs, i, C, X2, R1)
        for n in pyramid_normals(lim):
            nw = legs.sign[i] * (legs.R0[i] @ n)
            roots += _sinusoid_roots(float(nw @ s), float(nw @ c), float(nw @ u))
    return np.sort(np.array(roots))


MEL_CASES = {
    "stroke": ("stroke",),
    "stroke+joint": ("stroke", "joint"),
    "stroke+joint+interference": ("stroke", "joint", "interference"),
}
"""Merlet's three studies of the MEL prototype (chapter 3, Figs. 3.2-3.10)."""


@public
def mel_study(
    robot: Robot,
    center: Sequence[float] | None = None,
    N: Sequence[float] = (0.0, 0.0, 1.0),
    n1: int = 90,
    n2: int = 360,
    progress: bool | None = None,
) -> MelStudy:
    """Merlet's MEL prototype study: the platform normal under rotations about x then z.

    Three maps at the same point: leg strokes only, plus the base joints' square-hole
    pyramids, plus leg interference (legs of the robot's collision radius, 8 mm for the
    library's MEL prototype).

    Args:
        robot: The Gough-Stewart platform (``pkdyn.load("gough_stewart")``), with geometry.
        center: Fixed point [m] (default: home).
        N: Platform-fixed vector (default the platform normal).
        n1: Samples of theta1.
        n2: Samples of theta2.
        progress: Progress bars: ``True`` / ``False`` force them on / off, ``None`` (default)
            shows them when stderr is a terminal.

    Returns:
        Case name -> orientation workspace, in the order of :data:`MEL_CASES`.

    """
    return MelStudy(
        {
            name: orientation_workspace(
                robot,
                center,
                N,
                (1.0, 0.0, 0.0),
                (0.0, 0.0, 1.0),
                n1=n1,
                n2=n2,
                limits=kinds,
                progress=progress,
            )
            for name, kinds in MEL_CASES.items()
        }
    )
