"""Closed-form limits of the Delta for workspace sampling (Clavel's inverse model, vectorised).

For nacelle positions ``P`` the arm angles come from :func:`pkdyn.closed_form.delta.inverse`
(working branch); the rest is read from the loaded model, so the checks are those of the
description, not of the builder's parameters:

- ``reach``: Clavel's inverse model has a solution;
- ``stroke``: arm angles within the arm joints' limits;
- ``joint``: each bar's upper ball (or universal) joint inside its cone: the bar direction
  (from the elbow to its closure point on the nacelle) in the joint frame;
- ``interference``: the one definition of :mod:`pkdyn.analysis.collisions` (coal distances
  between the collision geometries: bars, arms, nacelle and base), the geometry placed from the
  arm angles and the nacelle position (:mod:`pkdyn.workspace.placed_interference`).
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np
import pinocchio as pin

from pkdyn.analysis.collisions import segment_distance_parts
from pkdyn.closed_form.delta import inverse
from pkdyn.exceptions import PkdynError
from pkdyn.model.description import ConeLimit, PyramidLimit
from pkdyn.model.robot import Robot
from pkdyn.workspace.limits import LIMIT_KINDS, REACHABLE, PoseEvaluator, direction_margin
from pkdyn.workspace.placed_interference import (
    AxialBody,
    PlacedInterference,
    Placements,
    RigidBody,
)

__all__ = ["CONE_BOUND", "DeltaEvaluator"]

CONE_BOUND = 1e-9
"""Distance from a cone's ``cos(half_angle)`` beyond which a cheaper cosine of a bar's tilt
gives the same verdict as :func:`~pkdyn.workspace.limits.direction_margin` (both are within
1e-13 of the exact one: a factor of 1e4)."""


def _rot_y(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    R = np.zeros(a.shape + (3, 3))
    R[..., 0, 0], R[..., 0, 2], R[..., 1, 1], R[..., 2, 0], R[..., 2, 2] = c, s, 1.0, -s, c
    return R


class DeltaEvaluator(PoseEvaluator):
    """Closed-form Delta limits (see the module docstring).

    Args:
        robot: A library Delta (``parallelogram="ball"``), with geometry for ``interference``.

    Raises:
        PkdynError: Not a library Delta with ball-jointed parallelograms.

    """

    method = "closed form (Clavel's inverse model)"

    @staticmethod
    def accepts(robot: Robot) -> bool:
        """Whether this closed form covers the robot.

        It needs a library Delta (``ra``, ``rb``, ``la``, ``lb`` known) with three arms
        ``arm1..3`` and ball-jointed parallelograms.
        """
        p = robot.params
        return (
            robot.family == "delta"
            and p.parallelogram == "ball"
            and len(robot.actuators) == 3
            and {"arm1", "arm2", "arm3"} <= set(robot.model.names)
        )

    def __init__(self, robot: Robot) -> None:
        super().__init__(robot)
        if not self.accepts(robot):
            raise PkdynError(f"{robot.name}: the closed-form Delta workspace needs a library Delta")
        model = robot.model
        arms = [model.getJointId(f"arm{i}") for i in (1, 2, 3)]
        if any(model.joints[j].shortname() != "JointModelRY" for j in arms):
            raise PkdynError(f"{robot.name}: arms must turn about their y axis")
        self.M_arm = [model.jointPlacements[j] for j in arms]
        iq = [model.idx_qs[j] for j in arms]
        self.lo = np.array(model.lowerPositionLimit[iq])
        self.hi = np.array(model.upperPositionLimit[iq])
        specs = {j.name: j for j in robot.description.joints}
        nacelle = model.frames[robot.platform_frame].parentJoint if robot.platform_frame else -1
        self.bars: list[tuple[int, pin.SE3, np.ndarray, ConeLimit | PyramidLimit | None]] = []
        bar_joints = []
        for cm in robot.constraint_models:
            j1, j2 = int(cm.joint1_id), int(cm.joint2_id)
            if j2 != nacelle or model.parents[j1] not in arms:
                continue
            arm = arms.index(int(model.parents[j1]))
            spec = specs.get(model.names[j1])
            bar_joints.append(j1)
            self.bars.append(
                (
                    arm,
                    model.jointPlacements[j1],
                    np.array(cm.joint2_placement.translation),
                    spec.limit if spec is not None else None,
                )
            )
        self._arm_joints = [int(j) for j in arms]
        self._bar_joints = [int(j) for j in bar_joints]
        self._interference: PlacedInterference | None = None
        self.lb = float(robot.params.lb)
        radius = {
            int(g.parentJoint): float(getattr(g.geometry, "radius", 0.0))
            for g in robot.collision_model.geometryObjects
        }
        self.arm_r = np.array([radius.get(j, 0.0) for j in arms])
        self.bar_r = max((radius.get(j, 0.0) for j in bar_joints), default=0.0)
        self.la = float(robot.params.la)
        self._pair_index: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    @cached_property
    def _bar_points(self) -> list[np.ndarray]:
        """Each bar's lower ball centre in its frame (the interference definition's axes)."""
        cms = self.robot.constraint_models
        return [
            np.array(next(cm.joint1_placement.translation for cm in cms if int(cm.joint1_id) == j))
            for j in self._bar_joints
        ]

    @cached_property
    def _nacelle_joint(self) -> pin.SE3:
        """The nacelle joint frame when the platform frame is at 0: ``(R_home, 0) frame^-1``."""
        robot = self.robot
        assert robot.platform_frame is not None
        fp = robot.model.frames[robot.platform_frame].placement
        home = robot.platform_placement(robot.q_home)
        return pin.SE3(home.rotation, np.zeros(3)) * fp.inverse()

    def _elbows(self, alpha: np.ndarray) -> tuple[np.ndarray, list[np.ndarray], np.ndarray]:
        """Arm rotations (N, 3, 3, 3), bar joint centres per bar (N, 3), arm tips (N, 3, 3)."""
        R_arm = np.stack([self.M_arm[k].rotation @ _rot_y(alpha[:, k]) for k in range(3)], axis=1)
        O = np.array([m.translation for m in self.M_arm])
        E = [O[k] + R_arm[:, k] @ Mb.translation for k, Mb, _, _ in self.bars]
        tip = O[None] + R_arm @ np.array([self.la, 0.0, 0.0])
        return R_arm, E, tip

    def violations(
        self,
        P: np.ndarray,
        R: np.ndarray,
        kinds: tuple[str, ...],
        margin: float,
        solved: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> np.ndarray:
        """See :meth:`PoseEvaluator.violations`; the nacelle keeps its orientation (R ignored).

        ``solved``: Clavel's inverse model at ``P`` (``inverse(params, P)``) when the caller
        has it.
        """
        return self._violations(P, kinds, margin, solved)[0]

    def _violations(
        self,
        P: np.ndarray,
        kinds: tuple[str, ...],
        margin: float,
        solved: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> tuple[np.ndarray, tuple[np.ndarray, list[np.ndarray], np.ndarray] | None]:
        """:meth:`violations`, and the elbows of the poses that pass (when it made them).

        Returns:
            The codes (N,) and, when the elbows were made (``joint`` or ``interference``
            checked), ``(todo, E, tip)``: the indices of the poses within every limit checked,
            their bar joint centres per bar (n, 3) and arm tips (n, 3, 3), as
            ``_elbows(alpha[todo])`` makes them (its rows are computed one pose at a time).

        """
        P = np.atleast_2d(np.asarray(P, dtype=float))
        alpha, ok = inverse(self.robot.params, P) if solved is None else solved
        out = np.full(P.shape[0], REACHABLE, dtype=np.int8)
        out[~ok] = LIMIT_KINDS.index("reach")
        todo = np.flatnonzero(ok)
        if todo.size == 0:
            return out, None
        a = alpha[todo]
        if "stroke" in kinds:
            bad = np.any((a < self.lo) | (a > self.hi), axis=1)
            out[todo[bad]] = LIMIT_KINDS.index("stroke")
            todo, a = todo[~bad], a[~bad]
        if not ({"joint", "interference"} & set(kinds)) or todo.size == 0:
            return out, None
        R_arm, E, tip = self._elbows(a)
        Pk = P[todo]
        if "joint" in kinds:
            bad = np.zeros(todo.size, dtype=bool)
            cs: tuple[np.ndarray, np.ndarray] | None = None
            axes: dict[tuple[int, bytes], np.ndarray] = {}
            for b, (k, Mb, p_nac, lim) in enumerate(self.bars):
                if lim is None:
                    continue
                u = Pk + p_nac - E[b]
                if isinstance(lim, ConeLimit):
                    if cs is None:
                        cs = (np.cos(a), np.sin(a))
                    outside = self._outside_cone(k, Mb, lim, cs, u, axes)
                    if outside is not None:
                        bad |= outside
                        continue
                d = np.einsum("nji,nj->ni", R_arm[:, k] @ Mb.rotation, u)
                bad |= direction_margin(lim, d) < 0.0
            out[todo[bad]] = LIMIT_KINDS.index("joint")
            todo, Pk, tip, R_arm = todo[~bad], Pk[~bad], tip[~bad], R_arm[~bad]
            E = [e[~bad] for e in E]
        if "interference" in kinds and todo.size:
            bad = self.interference.bad(self._placements(Pk, R_arm, E), todo.size, margin)
            out[todo[bad]] = LIMIT_KINDS.index("interference")
            keep = ~bad
            todo, tip, E = todo[keep], tip[keep], [e[keep] for e in E]
        return out, (todo, E, tip)

    def _outside_cone(
        self,
        k: int,
        Mb: pin.SE3,
        lim: ConeLimit,
        cs: tuple[np.ndarray, np.ndarray],
        u: np.ndarray,
        axes: dict[tuple[int, bytes], np.ndarray] | None = None,
    ) -> np.ndarray | None:
        """Poses whose bar leaves its cone, where every verdict is sure; else ``None``.

        The cosine of the bar's tilt ``u . w / |u|``, with ``w`` the cone's axis carried by the
        arm (``R_arm Mb.rotation axis``, from the arm angles' cosines and sines ``cs``), against
        ``cos(half_angle)``: this and :func:`~pkdyn.workspace.limits.direction_margin`'s
        cosine (the bar direction turned into the joint frame) are both within 1e-13 of the
        cosine of the stored vectors (unit axes, a few roundings of numbers of at most about
        1), and the arc cosine turns a difference in cosines into a larger one in angles: a
        cosine farther than :data:`CONE_BOUND` from ``cos(half_angle)`` gives
        ``direction_margin``'s verdict. ``None`` (the caller computes ``direction_margin`` on
        every pose, as before) when one pose is closer, or not finite. ``axes``: the carried
        axes already made for these poses, by arm and axis (filled).
        """
        ax = np.asarray(lim.axis, dtype=float)
        v = Mb.rotation @ ax  # the cone's axis in the arm frame
        key = (k, v.tobytes())
        w = None if axes is None else axes.get(key)
        if w is None:  # (an arm's bars share it)
            c, s = cs[0][:, k], cs[1][:, k]
            w = np.stack([c * v[0] + s * v[2], np.broadcast_to(v[1], c.shape), c * v[2] - s * v[0]])
            w = self.M_arm[k].rotation @ w  # (3, N), world axes
            if axes is not None:
                axes[key] = w
        n = np.sqrt(np.einsum("ni,ni->n", u, u))
        x = np.einsum("ni,in->n", u, w) / n
        bound = CONE_BOUND * max(1.0, float(np.linalg.norm(ax)))
        cos_h = math.cos(lim.half_angle)
        outside = x < cos_h - bound
        sure = outside | (x > cos_h + bound)  # (NaN: not sure)
        if not (bool(np.all(sure)) and bool(np.all((n > 1e-100) & (n < 1e100)))):
            return None
        return outside

    @property
    def interference(self) -> PlacedInterference:
        """The interference definition on the Delta's poses (built on first use).

        Bars lie on their axes from the elbow to the nacelle, arms and nacelle are rigid (the
        nacelle keeps its home orientation).
        """
        if self._interference is None:
            model = self.robot.model
            bodies: dict[int, RigidBody | AxialBody] = {
                j: RigidBody(f"arm{k}") for k, j in enumerate(self._arm_joints)
            }
            for b, j in enumerate(self._bar_joints):
                p = self._bar_points[b]
                bodies[j] = AxialBody(f"bar{b}", p / np.linalg.norm(p))
            assert self.robot.platform_frame is not None
            frame = model.frames[self.robot.platform_frame]
            bodies[int(frame.parentJoint)] = RigidBody("nacelle")
            self._interference = PlacedInterference(self.robot, bodies)
        return self._interference

    def _placements(self, P: np.ndarray, R_arm: np.ndarray, E: list[np.ndarray]) -> Placements:
        """Placements of :attr:`interference`'s bodies at nacelle positions ``P`` (N, 3)."""
        n = P.shape[0]
        O = np.array([m.translation for m in self.M_arm])
        out: Placements = {
            f"arm{k}": (R_arm[:, k], np.broadcast_to(O[k], (n, 3))) for k in range(3)
        }
        for b, (_, _, p_nac, _) in enumerate(self.bars):
            d = P + p_nac - E[b]
            out[f"bar{b}"] = (E[b], d / np.linalg.norm(d, axis=-1, keepdims=True))
        M = self._nacelle_joint  # the nacelle joint frame when the platform frame is at 0
        out["nacelle"] = (np.array(M.rotation), P + M.translation)
        return out

    def _pairs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The clearance's segment pairs: first, second segment, sum of radii (n_pairs,).

        Segments ``0..n_bars-1`` are the bars, ``n_bars + k`` arm ``k``; in the order of
        :meth:`_clearance`'s pairs: per bar, the bars of other arms after it, then the other
        arms.
        """
        if self._pair_index is None:
            nb = len(self.bars)
            first, second, radii = [], [], []
            for b1, (k1, _, _, _) in enumerate(self.bars):
                for b2 in range(b1 + 1, nb):
                    if self.bars[b2][0] != k1:  # bars of different arms
                        first.append(b1)
                        second.append(b2)
                        radii.append(2 * self.bar_r)
                for k in range(3):
                    if k != k1:  # a bar and another arm
                        first.append(b1)
                        second.append(nb + k)
                        radii.append(self.bar_r + self.arm_r[k])
            self._pair_index = (np.array(first), np.array(second), np.array(radii))
        return self._pair_index

    def _clearance(self, P: np.ndarray, E: list[np.ndarray], tip: np.ndarray) -> np.ndarray:
        if self.bar_r <= 0.0:
            raise PkdynError(
                f"{self.robot.name}: interference needs collision geometry (geometry=True)"
            )
        # the segments' starts and directions, their squared lengths once per segment (not per
        # pair): the arithmetic of segment_distance on the pairs, element for element
        O = np.array([m.translation for m in self.M_arm])
        n = P.shape[0]
        start = np.empty((len(self.bars) + 3, n, 3))
        axis = np.empty_like(start)
        for b, (_, _, p_nac, _) in enumerate(self.bars):
            start[b] = E[b]
            axis[b] = (P + p_nac) - E[b]
        for k in range(3):
            start[len(self.bars) + k] = O[k]
            axis[len(self.bars) + k] = tip[:, k] - np.broadcast_to(O[k], P.shape)
        sq = np.einsum("...i,...i->...", axis, axis)
        i1, i2, radii = self._pairs()
        d, _, _ = segment_distance_parts(axis[i1], axis[i2], start[i1] - start[i2], sq[i1], sq[i2])
        return np.min(d - radii[:, None], axis=0)

    def clearance(self, P: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
        """Smallest distance between the bars and the arms, as axis distances minus radii [m].

        Bars of different arms against each other and bars against the other arms, as
        capsules of their collision radius (negative: they overlap): a clearance figure (design
        metric); the ``interference`` verdicts use the full definition (:attr:`interference`).

        Args:
            P: Nacelle positions (N, 3) [m].
            alpha: Their arm angles (N, 3) [rad] (Clavel's inverse model) when the caller has
                them.

        Returns:
            (N,) clearances [m]; NaN where the position is out of reach.

        """
        P = np.atleast_2d(np.asarray(P, dtype=float))
        if alpha is None:
            alpha, ok = inverse(self.robot.params, P)
        else:
            ok = np.all(np.isfinite(alpha), axis=1)
        out = np.full(P.shape[0], np.nan)
        if ok.any():
            _, E, tip = self._elbows(alpha[ok])
            out[ok] = self._clearance(P[ok], E, tip)
        return out

    def default_bounds(self, R: np.ndarray) -> np.ndarray:
        """Box reachable with arms and bars stretched: ``|x|, |y| <= ra + la + lb``, z below."""
        p = self.robot.params
        L = p.ra - p.rb + p.la + p.lb
        return np.array([[-L, L], [-L, L], [-(p.la + p.lb), 0.0]])
