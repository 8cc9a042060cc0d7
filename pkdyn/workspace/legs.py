"""Closed-form limits of leg robots (Gough-Stewart and kin), read from the description.

A *leg robot* here: every actuator is a prismatic joint whose parent is a spherical or
universal joint on the base and whose body is closed on the platform by a ``point`` closure
(U-P-S or S-P-S legs). Then, for a platform placement ``(p, R)``, leg ``i`` is the segment
``A_i -> B_i = p + R b_i`` and every limit is a closed form in the leg vector
``v_i = B_i - A_i`` (Merlet, seed 002):

- stroke: ``rho_i = |v_i|`` within the prismatic joint's limits (plus the constant offset
  between the joint coordinate and ``|A_i B_i|``, zero for the library);
- base joint: the leg direction inside the joint's cone or pyramid (the limit axis must be the
  leg direction in the joint's child frame, so the limit depends on ``v_i`` only);
- interference: the one definition of :mod:`pkdyn.analysis.collisions` (coal distances between
  the collision geometries: leg against leg, base and platform; platform against base), the
  geometry placed from the leg vectors (:mod:`pkdyn.workspace.placed_interference`: each
  leg's two bodies on its axis, the platform rigid).

For a fixed orientation every component of ``v_i`` and every projection ``v_i . n`` is a sum
of one function of ``x``, one of ``y`` and one of ``z``; :meth:`HexapodEvaluator.grid` uses that
to check a whole grid with broadcast additions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.analysis.collisions import segment_distance
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.model.description import ConeLimit, PyramidLimit
from pkdyn.model.robot import Robot
from pkdyn.workspace.limits import LIMIT_KINDS, REACHABLE, PoseEvaluator, direction_margin
from pkdyn.workspace.placed_interference import (
    AxialBody,
    PlacedInterference,
    Placements,
    RigidBody,
)

__all__ = ["HexapodLegs", "HexapodEvaluator", "leg_interference", "leg_placements"]

_PRISMATIC_AXES = {"PX": (1.0, 0.0, 0.0), "PY": (0.0, 1.0, 0.0), "PZ": (0.0, 0.0, 1.0)}


def _prismatic_axis(jm: pin.JointModel) -> np.ndarray | None:
    name = jm.shortname()
    for key, ax in _PRISMATIC_AXES.items():
        if name.endswith(key):
            return np.array(ax)
    if "PrismaticUnaligned" in name:
        return np.asarray(jm.extract().axis, dtype=float)
    return None


@dataclass(frozen=True)
class HexapodLegs:
    """Geometry and limits of the legs of a leg robot, in Merlet's notation.

    Attributes:
        names: Actuated joint of each leg.
        A: Base joint centres (n, 3) [m], world frame.
        B: Platform joint centres (n, 3) [m], platform frame.
        rho_min: Smallest leg length ``|A_i B_i|`` (n,) [m].
        rho_max: Largest leg length (n,) [m].
        radius: Leg radius (n,) [m] (from the collision geometry; 0 without geometry).
        R0: Orientation of each base joint frame in the world (n, 3, 3).
        limits: Cone or pyramid of each base joint (joint frame), or ``None``.
        sign: +1 or -1 per leg: the limit axis is ``sign`` times the leg direction.

    """

    names: tuple[str, ...]
    A: np.ndarray
    B: np.ndarray
    rho_min: np.ndarray
    rho_max: np.ndarray
    radius: np.ndarray
    R0: np.ndarray
    limits: tuple[ConeLimit | PyramidLimit | None, ...]
    sign: np.ndarray

    @property
    def n(self) -> int:
        """Number of legs."""
        return len(self.names)

    @classmethod
    def from_robot(cls, robot: Robot, purpose: str = "") -> HexapodLegs:
        """Read the legs from a loaded robot.

        Args:
            robot: A leg robot (see the module docstring).
            purpose: What the legs are read for, named in the error message.

        Returns:
            The legs.

        Raises:
            PkdynError: The robot is not a leg robot, or a limit depends on more than the leg
                direction.

        """
        model = robot.model
        if robot.platform_frame is None:
            raise PkdynError(f"{robot.name}: no platform frame, not a leg robot")
        frame = model.frames[robot.platform_frame]
        j_plat = int(frame.parentJoint)
        specs = {j.name: j for j in robot.description.joints}
        points: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        for cm in robot.constraint_models:
            if cm.type != pin.ContactType.CONTACT_3D:
                continue
            for ja, Ma, jb, Mb in (
                (cm.joint1_id, cm.joint1_placement, cm.joint2_id, cm.joint2_placement),
                (cm.joint2_id, cm.joint2_placement, cm.joint1_id, cm.joint1_placement),
            ):
                if jb == j_plat:
                    points[int(ja)] = (np.array(Ma.translation), np.array(Mb.translation))
        names, A, B, lo, hi, R0, limits, sign = [], [], [], [], [], [], [], []
        for act, jp in zip(robot.actuators, robot.actuated_joints, strict=True):
            jp = int(jp)
            jm = model.joints[jp]
            e = _prismatic_axis(jm)
            ju = int(model.parents[jp])
            base_kind = model.joints[ju].shortname()
            if (
                e is None
                or model.parents[ju] != 0
                or base_kind not in ("JointModelSpherical", "JointModelUniversal")
                or jp not in points
            ):
                need = f"{purpose} needs a leg robot (Gough-Stewart kind): " if purpose else ""
                raise PkdynError(
                    f"{robot.name}: {need}actuator '{act.joint}' is not a prismatic leg between "
                    "a spherical/universal base joint and a point closure on the platform"
                )
            Mp = model.jointPlacements[jp]
            e_p = Mp.rotation @ e  # leg direction in the base joint's child frame
            p_rod, p_plat = points[jp]
            lateral = p_rod - (p_rod @ e) * e
            t_lat = Mp.translation - (Mp.translation @ e_p) * e_p
            if np.linalg.norm(lateral) > 1e-9 or np.linalg.norm(t_lat) > 1e-9:
                raise PkdynError(
                    f"{robot.name}: leg '{act.joint}': the platform joint is off the leg axis"
                )
            offset = float(Mp.translation @ e_p + p_rod @ e)
            iq = model.idx_qs[jp]
            names.append(act.joint)
            Mu = model.jointPlacements[ju]
            A.append(np.array(Mu.translation))
            R0.append(np.array(Mu.rotation))
            B.append(frame.placement.actInv(p_plat))
            lo.append(model.lowerPositionLimit[iq] + offset)
            hi.append(model.upperPositionLimit[iq] + offset)
            spec = specs.get(model.names[ju])
            lim = spec.limit if spec is not None else None
            s = 1.0
            if lim is not None:
                c = float(np.asarray(lim.axis) @ e_p)
                if abs(abs(c) - 1.0) > 1e-9:
                    raise PkdynError(
                        f"{robot.name}: joint '{model.names[ju]}': its limit axis is not the leg "
                        "direction; use the numeric workspace"
                    )
                s = math.copysign(1.0, c)
            limits.append(lim)
            sign.append(s)
        radius = np.array(
            [_leg_radius(robot, int(model.parents[int(j)]), int(j)) for j in robot.actuated_joints]
        )
        return cls(
            names=tuple(names),
            A=np.array(A),
            B=np.array(B),
            rho_min=np.array(lo),
            rho_max=np.array(hi),
            radius=radius,
            R0=np.array(R0),
            limits=tuple(limits),
            sign=np.array(sign),
        )

    def leg_vectors(self, P: np.ndarray, R: np.ndarray) -> np.ndarray:
        """Leg vectors ``v_i = p + R b_i - A_i`` (N, n, 3) [m].

        Args:
            P: Platform positions (N, 3) [m].
            R: Platform orientation (3, 3) or per position (N, 3, 3).

        """
        P = np.atleast_2d(np.asarray(P, dtype=float))
        RB = np.einsum("ij,kj->ki", R, self.B)[None] if R.ndim == 2 else R @ self.B.T
        if R.ndim == 3:
            RB = np.swapaxes(RB, 1, 2)
        return P[:, None, :] + RB - self.A[None]

    def stroke_bad(self, v: np.ndarray) -> np.ndarray:
        """(N,) True where a leg length is off its stroke."""
        rho2 = np.einsum("nki,nki->nk", v, v)
        return np.any((rho2 < self.rho_min**2) | (rho2 > self.rho_max**2), axis=1)

    def joint_margins(self, v: np.ndarray) -> np.ndarray:
        """Angular margin of each base joint (N, n) [rad] (``inf`` for unlimited joints)."""
        out = np.full(v.shape[:2], np.inf)
        for i, lim in enumerate(self.limits):
            if lim is not None:
                d = self.sign[i] * (v[:, i, :] @ self.R0[i])  # leg direction, joint frame
                out[:, i] = direction_margin(lim, d)
        return out

    def joint_bad(self, v: np.ndarray) -> np.ndarray:
        """(N,) True where a base joint is outside its cone or pyramid."""
        return np.any(self.joint_margins(v) < 0.0, axis=1)

    def pair_distances(self, v: np.ndarray) -> np.ndarray:
        """Distance between the axes of every pair of legs minus both radii (N, npairs) [m]."""
        i, j = np.triu_indices(self.n, 1)
        A = self.A
        d, _, _ = segment_distance(A[i], A[i] + v[:, i], A[j], A[j] + v[:, j])
        return d - (self.radius[i] + self.radius[j])

    def interference_bad(self, v: np.ndarray, margin: float) -> np.ndarray:
        """(N,) True where two legs are closer than ``margin``."""
        if v.shape[0] == 0:
            return np.zeros(0, dtype=bool)
        return np.any(self.pair_distances(v) < margin, axis=1)


def leg_interference(robot: Robot) -> PlacedInterference:
    """The interference definition on a leg robot's poses (placed from the leg vectors).

    Each leg's two bodies (the base joint's child and the prismatic joint's) lie on its axis:
    the first placed at ``A_i``, the second at ``B_i`` (its closure point); the platform is
    rigid.

    Args:
        robot: A leg robot loaded with geometry.

    Returns:
        The evaluator; feed it :func:`leg_placements`.

    Raises:
        PkdynError: No collision geometry, or a leg shape not symmetric about its axis.

    """
    model = robot.model
    bodies: dict[int, RigidBody | AxialBody] = {}
    for i, jp in enumerate(robot.actuated_joints):
        jp = int(jp)
        e = _prismatic_axis(model.joints[jp])
        assert e is not None
        b_offset = float(_closure_point(robot, jp) @ e)
        bodies[int(model.parents[jp])] = AxialBody(
            f"leg{i}", model.jointPlacements[jp].rotation @ e, 0.0, i
        )
        bodies[jp] = AxialBody(f"rod{i}", e, b_offset, i)
    assert robot.platform_frame is not None
    bodies[int(model.frames[robot.platform_frame].parentJoint)] = RigidBody("platform")
    return PlacedInterference(robot, bodies)


def leg_placements(
    robot: Robot, legs: HexapodLegs, P: np.ndarray, R: np.ndarray, v: np.ndarray
) -> Placements:
    """The bodies' placements of :func:`leg_interference` at platform poses.

    Args:
        robot: The leg robot.
        legs: Its legs.
        P: Platform positions (N, 3) [m].
        R: Platform orientation (3, 3) or per pose (N, 3, 3).
        v: Leg vectors (N, n, 3) of those poses [m].

    """
    n = v.shape[0]
    P = np.atleast_2d(np.asarray(P, dtype=float))
    assert robot.platform_frame is not None
    fp = robot.model.frames[robot.platform_frame].placement  # the frame in its joint
    Rj = R @ fp.rotation.T  # (3, 3) when one orientation for every pose
    tj = P - (fp.translation @ Rj.T if Rj.ndim == 2 else Rj @ fp.translation)
    out: Placements = {"platform": (Rj, tj)}
    u = v / np.linalg.norm(v, axis=-1, keepdims=True)
    for i in range(legs.n):
        out[f"leg{i}"] = (np.broadcast_to(legs.A[i], (n, 3)), u[:, i])
        out[f"rod{i}"] = (legs.A[i] + v[:, i], u[:, i])
    return out


def _closure_point(robot: Robot, jp: int) -> np.ndarray:
    """The platform joint centre on leg body ``jp`` (its closure point), in ``jp``'s frame."""
    for cm in robot.constraint_models:
        if cm.joint1_id == jp:
            return np.array(cm.joint1_placement.translation)
        if cm.joint2_id == jp:
            return np.array(cm.joint2_placement.translation)
    raise PkdynError(f"{robot.name}: leg joint '{robot.model.names[jp]}' has no closure")


def _leg_radius(robot: Robot, *joints: int) -> float:
    """Largest cylinder/capsule/sphere radius of the collision geometry on these joints' bodies."""
    r = 0.0
    for g in robot.collision_model.geometryObjects:
        if int(g.parentJoint) in joints and hasattr(g.geometry, "radius"):
            r = max(r, float(g.geometry.radius))
    return r


class HexapodEvaluator(PoseEvaluator):
    """Closed-form limits of a leg robot, vectorised (see the module docstring).

    Args:
        robot: A leg robot, loaded with geometry for ``interference`` (leg radii).

    """

    method = "closed form (leg vectors)"

    @staticmethod
    def accepts(robot: Robot) -> bool:
        """Whether :meth:`HexapodLegs.from_robot` recognises the robot's legs."""
        try:
            HexapodLegs.from_robot(robot)
        except PkdynError:
            return False
        return True

    def __init__(self, robot: Robot) -> None:
        super().__init__(robot)
        self.legs = HexapodLegs.from_robot(robot)
        self._interference: PlacedInterference | None = None

    @property
    def interference(self) -> PlacedInterference:
        """The interference of the robot's collision geometry (built on first use)."""
        if self._interference is None:
            self._interference = leg_interference(self.robot)
        return self._interference

    def _interference_bad(
        self, P: np.ndarray, R: np.ndarray, v: np.ndarray, margin: float
    ) -> np.ndarray:
        return self.interference.bad(leg_placements(self.robot, self.legs, P, R, v), len(v), margin)

    def _need_radius(self, kinds: tuple[str, ...]) -> None:
        if "interference" in kinds and not self.robot.collision_model.ngeoms:
            raise InvalidInputError(
                "limits",
                f"{self.robot.name}: interference needs collision geometry: give the links "
                "<collision> elements (in Python, load with geometry=True), or leave "
                "interference out (--limits stroke joint; limits=('stroke', 'joint'))",
            )
        if "interference" in kinds:
            self.interference  # noqa: B018 (built now: a shape it cannot place raises here)

    def violations(
        self, P: np.ndarray, R: np.ndarray, kinds: tuple[str, ...], margin: float
    ) -> np.ndarray:
        """See :meth:`PoseEvaluator.violations` (``reach`` never fails: legs are prismatic)."""
        self._need_radius(kinds)
        v = self.legs.leg_vectors(P, R)
        out = np.full(v.shape[0], REACHABLE, dtype=np.int8)
        for kind in kinds[1:]:
            todo = np.flatnonzero(out == REACHABLE)
            vv = v[todo]
            if kind == "stroke":
                bad = self.legs.stroke_bad(vv)
            elif kind == "joint":
                bad = self.legs.joint_bad(vv)
            else:
                Pk = np.atleast_2d(np.asarray(P, dtype=float))[todo]
                Rk = R if R.ndim == 2 else R[todo]
                bad = self._interference_bad(Pk, Rk, vv, margin)
            out[todo[bad]] = LIMIT_KINDS.index(kind)
        return out

    def grid(
        self,
        xs: np.ndarray,
        ys: np.ndarray,
        z: float,
        R: np.ndarray,
        kinds: tuple[str, ...],
        margin: float,
    ) -> np.ndarray:
        """Violation codes on the plane grid ``xs x ys`` at height ``z`` (nx, ny).

        Stroke and joint limits are broadcast sums of per-axis terms; interference is checked
        on the positions that pass them.
        """
        self._need_radius(kinds)
        legs = self.legs
        c = legs.A - legs.B @ R.T  # v_i = p - c_i
        X = xs[:, None] - c[None, :, 0]  # (nx, n)
        Y = ys[:, None] - c[None, :, 1]
        Z = z - c[:, 2]  # (n,)
        out = np.full((xs.size, ys.size), REACHABLE, dtype=np.int8)
        if "stroke" in kinds:
            bad = np.zeros(out.shape, dtype=bool)
            X2, Y2, Z2 = X**2, Y**2, Z**2
            for i in range(legs.n):
                rho2 = X2[:, i, None] + Y2[None, :, i] + Z2[i]
                bad |= (rho2 < legs.rho_min[i] ** 2) | (rho2 > legs.rho_max[i] ** 2)
            out[bad] = LIMIT_KINDS.index("stroke")
        if "joint" in kinds:
            bad = np.zeros(out.shape, dtype=bool)
            for i, lim in enumerate(legs.limits):
                if lim is not None:
                    bad |= self._joint_grid_bad(i, lim, X[:, i], Y[:, i], Z[i])
            out[(out == REACHABLE) & bad] = LIMIT_KINDS.index("joint")
        if "interference" in kinds:
            ia, ib = np.nonzero(out == REACHABLE)
            if ia.size:
                P = np.column_stack([xs[ia], ys[ib], np.full(ia.size, z)])
                bad = self._interference_bad(P, R, legs.leg_vectors(P, R), margin)
                out[ia[bad], ib[bad]] = LIMIT_KINDS.index("interference")
        return out

    def _joint_grid_bad(
        self, i: int, lim: ConeLimit | PyramidLimit, X: np.ndarray, Y: np.ndarray, Z: float
    ) -> np.ndarray:
        """Joint-limit violation of leg ``i`` on the grid, from separable projections."""
        legs = self.legs

        def proj(n_joint: np.ndarray) -> np.ndarray:
            n = legs.sign[i] * (legs.R0[i] @ n_joint)  # world direction of a joint-frame vector
            return X[:, None] * n[0] + Y[None, :] * n[1] + Z * n[2]

        ax = np.asarray(lim.axis, dtype=float)
        pa = proj(ax)
        if isinstance(lim, ConeLimit):
            h = lim.half_angle
            if h >= math.pi / 2:
                rho = np.sqrt(X[:, None] ** 2 + Y[None, :] ** 2 + Z**2)
                return pa < rho * math.cos(h)
            rho2 = X[:, None] ** 2 + Y[None, :] ** 2 + Z**2
            return (pa <= 0.0) | (pa * pa < rho2 * math.cos(h) ** 2)
        ref = np.asarray(lim.ref, dtype=float)
        pr, pn = proj(ref), proj(np.cross(ax, ref))
        if max(lim.half_angles) >= math.pi / 2:
            a1 = np.arctan2(pr, pa)
            a2 = np.arctan2(pn, pa)
            return (np.abs(a1) > lim.half_angles[0]) | (np.abs(a2) > lim.half_angles[1])
        t1, t2 = math.tan(lim.half_angles[0]), math.tan(lim.half_angles[1])
        return (pa <= 0.0) | (np.abs(pr) > t1 * pa) | (np.abs(pn) > t2 * pa)

    def default_bounds(self, R: np.ndarray) -> np.ndarray:
        """Box of the positions where every leg can reach: within ``rho_max`` of each ``c_i``."""
        c = self.legs.A - self.legs.B @ R.T
        r = self.legs.rho_max
        lo = np.max(c - r[:, None], axis=0)
        hi = np.min(c + r[:, None], axis=0)
        lo[2] = max(lo[2], float(np.min(c[:, 2])))  # the platform stays above its base joints
        if np.any(hi <= lo):
            raise PkdynError(f"{self.robot.name}: the legs cannot all reach at this orientation")
        return np.column_stack([lo, hi])
