"""Loop closures (point, hinge, weld) and their independent rows: residual, Jacobian, drift.

A closure joins a frame ``c1`` on the body of ``joint1`` (placement ``M1`` in that joint's frame)
to a frame ``c2`` on the body of ``joint2``. Conventions (exact derivatives with respect to a
velocity increment ``dq`` applied as ``pin.integrate(model, q, dq)``, checked against finite
differences in the tests; ``J_lin(p)`` the world linear Jacobian of a point, ``J_ang,k`` the world
angular Jacobian of body ``k``):

- **point** (spherical joint), 3 rows: ``r = p1 - p2`` [m], the world positions of the two frame
  origins; ``J = J_lin(p1) - J_lin(p2)``.
- **weld**, 6 rows: ``r = log6(c1Mc2)`` [m, rad]; ``J = Jlog6(c1Mc2) (J2 - Ad(c2Mc1) J1)`` with
  ``J1, J2`` the local Jacobians of the frames.
- **hinge** (revolute joint about the axis ``a``, the same unit vector in both frames), its 5
  independent rows: the point rows of the origins, then two axis rows
  ``r_k = f_k . a2`` [m] with ``a2 = R_c2 a`` and ``f_1 = -L R_c1 e_2``, ``f_2 = L R_c1 e_1``
  (``e_1, e_2, a`` a right-handed orthonormal frame in ``c1``, ``L`` = :data:`HINGE_ARM`): the
  displacement, normal to the axis, of the axis point at ``L`` from the origin, about ``L``
  times the relative rotation of ``c2`` from ``c1`` about ``R_c1 e_k`` (the units and scale of
  the former hinge of two points, whose tolerances and reports they keep);
  ``J_k = w_k^T (J_ang,2 - J_ang,1)``, ``w_k = a2 x f_k``.
- **planar closures**: where every joint moving either body turns about axes parallel to one
  world-fixed normal ``n`` or slides normal to it (:mod:`solvers.planar`), the rows out of the
  plane are zero by construction and dropped: a point keeps ``E (p1 - p2)`` (``E`` (2, 3) an
  orthonormal basis of the plane), a hinge about ``n`` the same two rows, a weld (or a hinge whose
  axis is not ``n``) those two and ``r = (R_c1^T n) . log3(c1Rc2)`` [rad], the relative rotation
  about ``n``, with ``J = n^T (J_ang,2 - J_ang,1)``. A closure whose out-of-plane gap is not zero
  at the model's neutral configuration keeps all its rows (it cannot close; the assembly then
  says so).

Second derivative along a motion ``(q, v, a)``: ``d^2 r / dt^2 = J a + gamma(q, v)``, the
acceleration drift ``gamma`` of :meth:`ClosureRows.drift` (classical accelerations of the
origins at ``a = 0`` for point rows, ``E`` times them for planar ones; for welds the relative
spatial acceleration at ``a = 0``, exact when the weld's relative velocity vanishes, as it does
on a closed mechanism; ``dw_k/dt . (w2 - w1) + w_k . (alpha2 - alpha1)`` for a hinge's axis rows
and ``n . (alpha2 - alpha1)`` for a planar rotation row, ``w`` and ``alpha`` the bodies' world
angular velocities and accelerations at ``a = 0``).

Reactions (:meth:`ClosureRows.reactions`): the multipliers ``lambda`` of the rows (``J^T lambda``
in the dynamics) are, per closure, the force [N] on ``joint1``'s body at ``p1``, world axes, for
point rows (``E^T lambda`` for planar ones); the wrench [N, N m] on ``joint2``'s body at its frame,
in that frame, for a weld's 6 rows; a moment ``-lambda_k w_k`` [N m] on ``joint1``'s body for a
hinge's axis rows and ``-lambda n`` for a planar rotation row. Each closure reports one force and
one moment on ``joint1``'s body at ``p1``, world axes.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from solvers.planar import PLANAR_TOL, plane_normal
from solvers.scratch import scratch_data

__all__ = [
    "CLOSURE_KINDS",
    "FREE_SCALE",
    "HINGE_ARM",
    "Closure",
    "ClosureRows",
    "size_bound",
    "support_mask",
]

CLOSURE_KINDS = ("point", "hinge", "weld")
"""The kinds of closure."""

HINGE_ARM = 0.1
"""Distance [m] along a hinge's axis of the point whose displacement its axis rows measure (and
of the second point of a hinge built from two points: the unreduced hinge, 6 rows of rank 5,
``reduce=False``)."""

_GAP_TOL = 1e-10
"""Largest out-of-plane gap (relative to the robot's size) [m or rad] of a planar closure whose
out-of-plane rows are dropped."""

_FREE_JOINTS = frozenset({"JointModelSpherical", "JointModelFreeFlyer"})
"""Joints whose world twist columns turn about three orthonormal axes at every configuration."""

FREE_SCALE = 1e9
"""Largest robot size [m] (``1 +`` the farthest joint origin at neutral) for which a closure moved
by one of :data:`_FREE_JOINTS` is known not to be planar without computing it (see
:meth:`ClosureRows._turns_freely`)."""


def size_bound(model: pin.Model) -> float:
    """``1 +`` the sum of the joint placements' offsets [m], compared with :data:`FREE_SCALE`.

    An upper bound of ``1 +`` the farthest joint origin at neutral (each origin is reached by
    its chain of placements); nothing to compute but the offsets' norms.

    Args:
        model: The model.

    Returns:
        The bound [m].

    """
    return 1.0 + sum(math.hypot(*M.translation) for M in model.jointPlacements)


_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_LOCAL = pin.ReferenceFrame.LOCAL
_3D = pin.ContactType.CONTACT_3D
_6D = pin.ContactType.CONTACT_6D


@dataclass(frozen=True, eq=False)  # SE3 fields: no boolean ==
class Closure:
    """One loop closure between two frames on two bodies.

    Attributes:
        name: Name, for messages and reports.
        kind: ``point``, ``hinge`` or ``weld`` (:data:`CLOSURE_KINDS`).
        joint1: Pinocchio joint id of the first body (0: the world).
        placement1: Frame ``c1`` in that joint's frame.
        joint2: Joint id of the second body.
        placement2: Frame ``c2`` in that joint's frame.
        axis: A hinge's axis, the same unit vector in ``c1`` and ``c2`` (ignored otherwise).

    """

    name: str
    kind: str
    joint1: int
    placement1: pin.SE3
    joint2: int
    placement2: pin.SE3
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)

    @classmethod
    def of(cls, cm: pin.RigidConstraintModel) -> Closure:
        """The point (CONTACT_3D) or weld (CONTACT_6D) closure of a rigid constraint model."""
        kind = "point" if cm.type == _3D else "weld"
        return cls(
            cm.name,
            kind,
            int(cm.joint1_id),
            pin.SE3(cm.joint1_placement),
            int(cm.joint2_id),
            pin.SE3(cm.joint2_placement),
        )


def support_mask(model: pin.Model, j: int) -> np.ndarray:
    """Indicator (nv,) of the velocity coordinates that move joint ``j``'s body."""
    mask = np.zeros(model.nv)
    while j > 0:
        jm = model.joints[j]
        mask[jm.idx_v : jm.idx_v + jm.nv] = 1.0
        j = model.parents[j]
    return mask


def _turn(R1: np.ndarray, R2: np.ndarray, n: np.ndarray) -> float:
    """The angle [rad] of ``c1Rc2 = R1^T R2`` about ``m = R1^T n``.

    ``atan2(m . vee(R - R^T) / 2, (tr R - 1) / 2)``: ``m . log3(R)`` for a rotation about
    ``m``, defined on a whole turn.
    """
    R = R1.T @ R2
    m = R1.T @ n
    s = 0.5 * (m[0] * (R[2, 1] - R[1, 2]) + m[1] * (R[0, 2] - R[2, 0]) + m[2] * (R[1, 0] - R[0, 1]))
    return math.atan2(s, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0))


def _perpendicular(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``e1, e2`` with ``(e1, e2, a)`` right-handed orthonormal."""
    t = np.eye(3)[int(np.argmin(np.abs(a)))]
    e1 = np.cross(a, t)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1)


@dataclass
class _Block:
    """Where one closure's rows come from (see :class:`ClosureRows`)."""

    closure: Closure
    offset: int
    size: int
    base: list[int]  # its base constraint models
    normal: np.ndarray | None  # plane normal of a planar closure
    rows: list[tuple[str, int]]  # (what, local row) per row: see ClosureRows._plan


class ClosureRows:
    """Rows of a set of closures on a Pinocchio model (see the module docstring).

    Point and weld rows are Pinocchio's C++ constraint models (copies with
    ``LOCAL_WORLD_ALIGNED`` 3D rows, ``d(p1 - p2)/dt``, and ``LOCAL`` 6D rows mapped to the
    convention of this module by ``-Jlog6(c1Mc2) Ad(c2Mc1)``): one ``getConstraintsJacobian``
    call per evaluation. Planar rows project them; a hinge's axis rows and planar rotation rows
    come from the world angular Jacobians of the two bodies (``data.J``).

    Args:
        model: The kinematic tree.
        closures: The closures (:class:`Closure`, or Pinocchio rigid constraint models: points
            and welds).
        reduce: Reduce hinges to their 5 independent rows and planar closures to their in-plane
            rows (``False``: a hinge is two points, 6 rows of rank 5; nothing is dropped).

    Attributes:
        closures: The closures.
        names, kinds, sizes: Per closure.
        offsets: Row offset of each closure, then the row count (n_closures + 1,).
        n: Number of rows.
        normals: Plane normal (3,) of each closure whose out-of-plane rows are dropped, else
            ``None``.

    Raises:
        ValueError: An unknown kind, a zero hinge axis, or a joint id out of range.

    """

    def __init__(
        self,
        model: pin.Model,
        closures: Sequence[Closure | pin.RigidConstraintModel],
        reduce: bool = True,
    ) -> None:
        self.model = model
        self.reduce = bool(reduce)
        self.closures = tuple(c if isinstance(c, Closure) else Closure.of(c) for c in closures)
        for c in self.closures:
            if c.kind not in CLOSURE_KINDS:
                raise ValueError(f"closure {c.name!r}: unknown kind {c.kind!r}")
            for j in (c.joint1, c.joint2):
                if not 0 <= int(j) < model.njoints:
                    raise ValueError(
                        f"closure {c.name!r}: joint id {j} is not a joint of the model"
                    )
            if c.kind == "hinge" and not np.linalg.norm(c.axis) > 0.0:
                raise ValueError(f"closure {c.name!r}: the hinge axis is zero")
        self._masks: dict[int, np.ndarray] = {}
        self._free: dict[int, bool] = {}
        self._loc: (
            tuple[
                pin.StdVec_RigidConstraintModel,
                pin.StdVec_RigidConstraintData,
                list[tuple[bool, int, pin.RigidConstraintModel, pin.RigidConstraintData]],
            ]
            | None
        ) = None
        self._base: list[tuple[bool, int, pin.SE3, int, pin.SE3]] = []
        normals = self._normals() if self.reduce else [None] * len(self.closures)
        self.blocks = [self._plan(c, n) for c, n in zip(self.closures, normals, strict=True)]
        self.names = [c.name for c in self.closures]
        self.kinds = [c.kind for c in self.closures]
        self.sizes = [b.size for b in self.blocks]
        self.offsets = np.concatenate([[0], np.cumsum(self.sizes)]).astype(int)
        for b, o in zip(self.blocks, self.offsets, strict=False):
            b.offset = int(o)
        self.n = int(self.offsets[-1])
        self.normals = [b.normal for b in self.blocks]
        self._build_base()
        self._build_maps()

    # ------------------------------------------------------------------ construction

    def mask(self, j: int) -> np.ndarray:
        """:func:`support_mask` of joint ``j`` (cached)."""
        m = self._masks.get(j)
        if m is None:
            m = self._masks[j] = support_mask(self.model, j)
        return m

    def _normals(self) -> list[np.ndarray | None]:
        """The plane normal of each closure whose out-of-plane rows vanish by construction."""
        model = self.model
        free = [self._turns_freely(c.joint1) or self._turns_freely(c.joint2) for c in self.closures]
        if all(free):
            # no plane to find (see _turns_freely): the joints' origins at neutral lie within the
            # sum of the joint placements' offsets, an upper bound of the scale checked below;
            # nothing to compute (a Data of a large model costs milliseconds to make)
            if size_bound(model) < FREE_SCALE:
                return [None] * len(self.closures)
        data = scratch_data(model)
        q0 = pin.neutral(model)
        pin.computeJointJacobians(model, data, q0)
        scale = 1.0 + max((float(np.linalg.norm(M.translation)) for M in data.oMi), default=0.0)
        out: list[np.ndarray | None] = []
        for c, turns in zip(self.closures, free, strict=True):
            if scale < FREE_SCALE and turns:
                out.append(None)
                continue
            cols = np.flatnonzero(self.mask(c.joint1) + self.mask(c.joint2))
            n = plane_normal(np.reshape(data.J, (6, model.nv))[:, cols])
            if n is not None:
                o1 = data.oMi[c.joint1] * c.placement1
                o2 = data.oMi[c.joint2] * c.placement2
                gap = abs(float(n @ (o1.translation - o2.translation))) / scale
                turn = float(np.linalg.norm(o1.rotation.T @ n - o2.rotation.T @ n))
                if not (gap <= _GAP_TOL and (c.kind == "point" or turn <= _GAP_TOL)):
                    n = None
            out.append(n)
        return out

    def _turns_freely(self, j: int) -> bool:
        """Whether a ball or free joint moves joint ``j``'s body (then no closure on it is planar).

        Such a joint's world twist columns turn about three orthonormal axes ``w_i`` (columns of
        its world rotation) whatever the configuration: for any unit ``n``, ``sum |w_i x n|^2 =
        2``, so one of them is at least ``sqrt(2/3)`` off ``n`` while its twist's norm is at most
        ``sqrt(1 + |p|^2)`` (``p`` its origin): :func:`~solvers.planar.plane_normal` finds no
        plane as long as ``|p| < 1e9`` m (checked by the caller), without the arithmetic.
        """
        found = self._free.get(j)
        if found is None:
            k, found = j, False
            while k > 0 and not found:
                found = self.model.joints[k].shortname() in _FREE_JOINTS
                k = int(self.model.parents[k])
            self._free[j] = found
        return found

    def _add_base(self, is_point: bool, c: Closure, off: pin.SE3 | None = None) -> int:
        M1, M2 = c.placement1, c.placement2
        if off is not None:
            M1, M2 = M1 * off, M2 * off
        self._base.append((is_point, int(c.joint1), pin.SE3(M1), int(c.joint2), pin.SE3(M2)))
        return len(self._base) - 1

    def _plan(self, c: Closure, n: np.ndarray | None) -> _Block:
        """Rows of one closure.

        Per row ``(what, k)``, ``what`` one of ``base`` (row ``k`` of the base rows of its first
        base model, or of its second for ``base2``), ``plane`` (row ``k`` of ``E (p1 - p2)``),
        ``axis`` (axis row ``k``), ``turn`` (planar rotation row).
        """
        axis = np.asarray(c.axis, dtype=float)
        axis = axis / max(float(np.linalg.norm(axis)), 1e-300)
        if n is not None:  # planar: in-plane translation, and the rotation about n if blocked
            base = [self._add_base(True, c)]
            rows = [("plane", 0), ("plane", 1)]
            if c.kind == "weld" or (c.kind == "hinge" and not self._along(c, axis, n)):
                rows.append(("turn", 0))
            return _Block(c, 0, len(rows), base, n, rows)
        if c.kind == "point":
            return _Block(c, 0, 3, [self._add_base(True, c)], None, [("base", k) for k in range(3)])
        if c.kind == "weld":
            return _Block(
                c, 0, 6, [self._add_base(False, c)], None, [("base", k) for k in range(6)]
            )
        if not self.reduce:  # two points on the axis
            base = [
                self._add_base(True, c),
                self._add_base(True, c, pin.SE3(np.eye(3), HINGE_ARM * axis)),
            ]
            rows = [("base", k) for k in range(3)] + [("base2", k) for k in range(3)]
            return _Block(c, 0, 6, base, None, rows)
        rows = [("base", k) for k in range(3)] + [("axis", 0), ("axis", 1)]
        return _Block(c, 0, 5, [self._add_base(True, c)], None, rows)

    def _along(self, c: Closure, axis: np.ndarray, n: np.ndarray) -> bool:
        """Whether a hinge's axis is parallel to the plane normal ``n`` (world, at neutral)."""
        data = scratch_data(self.model)
        pin.forwardKinematics(self.model, data, pin.neutral(self.model))
        a = (data.oMi[c.joint1] * c.placement1).rotation @ axis
        return float(np.linalg.norm(np.cross(a, n))) <= PLANAR_TOL

    def _build_base(self) -> None:
        model = self.model
        self._cms = pin.StdVec_RigidConstraintModel()
        self._cds = pin.StdVec_RigidConstraintData()
        sizes = [3 if it[0] else 6 for it in self._base]
        self.base_offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.nb = int(self.base_offsets[-1])
        for is_point, j1, M1, j2, M2 in self._base:
            kind = _3D if is_point else _6D
            c = pin.RigidConstraintModel(kind, model, j1, M1, j2, M2, _LWA if is_point else _LOCAL)
            self._cms.append(c)
            self._cds.append(c.createData())
        self._entries = [
            (it[0], int(o), cm, cd)
            for it, o, cm, cd in zip(
                self._base, self.base_offsets, self._cms, self._cds, strict=False
            )
        ]
        self._welds = [(int(o), cd) for is_point, o, _, cd in self._entries if not is_point]
        # the point rows' drift: per side, the joint and the point (translation only: the
        # classical acceleration in the joint frame, turned to world axes by the joint's rotation)
        self._pt_sides: list[tuple[int, list[tuple[int, pin.SE3]], bool]] | None = None
        self._other = [k for k, it in enumerate(self._base) if not it[0]]

    def _point_sides(self) -> list[tuple[int, list[tuple[int, pin.SE3]], bool]]:
        """The point base models' sides, for the drift (made on first use).

        Per point base model: its row offset, per side on a moving body ``(joint, point)`` (the
        point as a translation), and whether its first side moves.
        """
        if self._pt_sides is not None:
            return self._pt_sides
        self._pt_sides = [
            (
                int(self.base_offsets[k]),
                [(int(j), pin.SE3(np.eye(3), M.translation)) for j, M in ((j1, M1), (j2, M2)) if j],
                bool(j1),
            )
            for k, (is_point, j1, M1, j2, M2) in enumerate(self._base)
            if is_point
        ]
        return self._pt_sides

    def _local(
        self,
    ) -> tuple[
        pin.StdVec_RigidConstraintModel,
        pin.StdVec_RigidConstraintData,
        list[tuple[bool, int, pin.RigidConstraintModel, pin.RigidConstraintData]],
    ]:
        """The base models with ``LOCAL`` rows, their datas and entries (made on first use)."""
        if self._loc is None:
            cms = pin.StdVec_RigidConstraintModel()
            cds = pin.StdVec_RigidConstraintData()
            for is_point, j1, M1, j2, M2 in self._base:
                c = pin.RigidConstraintModel(
                    _3D if is_point else _6D, self.model, j1, M1, j2, M2, _LOCAL
                )
                cms.append(c)
                cds.append(c.createData())
            entries = [
                (it[0], int(o), cm, cd)
                for it, o, cm, cd in zip(self._base, self.base_offsets, cms, cds, strict=False)
            ]
            self._loc = (cms, cds, entries)
        return self._loc

    def _build_maps(self) -> None:
        """Index maps from the base rows to the rows (module docstring)."""
        dst: list[int] = []
        src: list[int] = []
        self._planes: list[tuple[int, int, np.ndarray]] = []  # (row, base row, E (2, 3))
        self._axes: list[tuple[int, int, np.ndarray, np.ndarray, int, int]] = []
        self._turns: list[tuple[int, int, np.ndarray, int, int]] = []
        for b in self.blocks:
            c = b.closure
            b0 = b.base[0]
            o0 = int(self.base_offsets[b0])
            for i, (what, k) in enumerate(b.rows):
                row = b.offset + i
                if what == "base":
                    dst.append(row)
                    src.append(o0 + k)
                elif what == "base2":
                    dst.append(row)
                    src.append(int(self.base_offsets[b.base[1]]) + k)
            if b.normal is not None:
                e1, e2 = _perpendicular(b.normal)
                self._planes.append((b.offset, o0, np.array([e1, e2])))
                if b.size == 3:
                    self._turns.append((b.offset + 2, b0, b.normal, c.joint1, c.joint2))
            elif any(w == "axis" for w, _ in b.rows):
                a = np.asarray(c.axis, dtype=float)
                a = a / np.linalg.norm(a)
                e1, e2 = _perpendicular(a)
                F = HINGE_ARM * np.column_stack([-e2, e1])  # L f_1, L f_2 in c1
                self._axes.append((b.offset + 3, b0, F, a, c.joint1, c.joint2))
        self._dst = np.array(dst, dtype=int)
        self._src = np.array(src, dtype=int)
        self.identity = (
            not self._planes
            and not self._axes
            and self.nb == self.n
            and bool(np.array_equal(self._src, np.arange(self.n)))
        )
        self._dmask = {(j1, j2): self.mask(j2) - self.mask(j1) for _, _, _, _, j1, j2 in self._axes}
        self._dmask.update({(j1, j2): self.mask(j2) - self.mask(j1) for *_, j1, j2 in self._turns})
        if self._planes:
            self._pl_dst = np.array([p[0] for p in self._planes], dtype=int)[:, None] + np.arange(2)
            self._pl_src = np.array([p[1] for p in self._planes], dtype=int)[:, None] + np.arange(3)
            self._pl_E = np.array([p[2] for p in self._planes])

    @functools.cached_property
    def movable(self) -> bool:
        """Whether :meth:`move` applies: the rows do not depend on the frames' placements.

        Points and welds alone, each Pinocchio's rows as they are, each moved by a ball or free
        joint (no plane to find whatever the placements, :meth:`_turns_freely`), on a model at
        most half :data:`FREE_SCALE` in size (placements moved by less than the robot's size
        keep it below the bound): a set of the moved closures made anew has the same rows.
        """
        if not (self.reduce and self.identity):
            return False
        if any(c.kind not in ("point", "weld") for c in self.closures):
            return False
        if not all(
            self._turns_freely(c.joint1) or self._turns_freely(c.joint2) for c in self.closures
        ):
            return False
        return size_bound(self.model) < 0.5 * FREE_SCALE

    def move(self, closures: Sequence[Closure]) -> None:
        """Put other frames' placements on the same closures, in place (:attr:`movable` sets).

        The rows of ``ClosureRows(model, closures)`` without making them: the constraint
        models' placements are written (Pinocchio's and the ``LOCAL`` copies), nothing else
        changes. The perturbed robots of a Monte Carlo, one after the other.

        Args:
            closures: The closures (same names, kinds and joints, in the same order), with the
                new placements.

        Raises:
            ValueError: The set is not :attr:`movable`, or the closures are not its own.

        """
        if not self.movable:
            raise ValueError("these closures' rows depend on their placements: make a new set")
        if len(closures) != len(self.closures) or any(
            (c.name, c.kind, int(c.joint1), int(c.joint2)) != (o.name, o.kind, o.joint1, o.joint2)
            for c, o in zip(closures, self.closures, strict=False)
        ):
            raise ValueError("move takes the same closures (names, kinds, joints, order)")
        local = self._loc[0] if self._loc is not None else None
        for k, (c, b) in enumerate(zip(closures, self.blocks, strict=True)):
            M1, M2 = pin.SE3(c.placement1), pin.SE3(c.placement2)
            is_point, j1, _, j2, _ = self._base[k]
            self._base[k] = (is_point, j1, M1, j2, M2)
            for cms in (self._cms, local):
                if cms is not None:
                    cms[k].joint1_placement = M1
                    cms[k].joint2_placement = M2
            b.closure = c
        self.closures = tuple(closures)
        self._pt_sides = None  # (made again on first use)

    @property
    def base_items(self) -> list[tuple[bool, int, pin.SE3, int, pin.SE3]]:
        """Per base constraint model: ``(is_point, joint1, placement1, joint2, placement2)``."""
        return self._base

    def base_models(self) -> list[pin.RigidConstraintModel]:
        """Copies of the base constraint models (3D points, 6D welds), ``LOCAL`` frames."""
        out = []
        for (is_point, j1, M1, j2, M2), c in zip(self._base, self._blocks_of_base(), strict=True):
            cm = pin.RigidConstraintModel(
                _3D if is_point else _6D, self.model, j1, M1, j2, M2, _LOCAL
            )
            cm.name = c
            out.append(cm)
        return out

    def pin_closures(self) -> list[Closure]:
        """The fewest points and welds with the same constraints, for Pinocchio's dynamics.

        Pinocchio's ``constraintDynamics`` takes 3D points and 6D welds: a point or a weld as it
        is; a planar hinge about the normal as the point of its origins (its other rows vanish
        by construction: half a hinge of two points' work); a planar weld, or a planar hinge
        across the plane, as a weld (nothing turns about the hinge's axis in the plane); a
        spatial hinge as two points on its axis, :data:`HINGE_ARM` apart (6 rows of rank 5,
        which the proximal solver settles).

        Returns:
            Point and weld closures (a spatial hinge ``N`` gives ``N`` and ``N/axis``).

        """
        out: list[Closure] = []
        for b in self.blocks:
            c = b.closure
            if b.normal is not None:
                out.append(dataclasses.replace(c, kind="weld" if b.size == 3 else "point"))
            elif c.kind == "hinge":
                a = np.asarray(c.axis, dtype=float)
                off = pin.SE3(np.eye(3), HINGE_ARM * a / np.linalg.norm(a))
                out.append(dataclasses.replace(c, kind="point"))
                out.append(
                    Closure(
                        c.name + "/axis",
                        "point",
                        c.joint1,
                        c.placement1 * off,
                        c.joint2,
                        c.placement2 * off,
                    )
                )
            else:
                out.append(c)
        return out

    def _blocks_of_base(self) -> list[str]:
        names = [""] * len(self._base)
        for b in self.blocks:
            for i, k in enumerate(b.base):
                names[k] = b.closure.name + ("/axis" if i else "")
        return names

    # ------------------------------------------------------------------ evaluation

    def calc(self, data: pin.Data) -> None:
        """Update the base constraint datas from the joint placements of ``data``."""
        model = self.model
        for _, _, cm, cd in self._entries:
            cm.calc(model, data, cd)

    def _base_residual(self) -> np.ndarray:
        r = np.empty(self.nb)
        for is_point, o, _, cd in self._entries:
            if is_point:
                r[o : o + 3] = cd.oMc1.translation
                r[o : o + 3] -= cd.oMc2.translation
            else:
                r[o : o + 6] = pin.log6(cd.c1Mc2).vector
        return r

    def residual(self, data: pin.Data, out: np.ndarray | None = None) -> np.ndarray:
        """Residual (n,) [m, rad] from the joint placements of ``data`` (updates the datas)."""
        model = self.model
        rb = np.empty(self.nb) if not self.identity or out is None else out
        for is_point, o, cm, cd in self._entries:  # (one loop: the datas and the base rows)
            cm.calc(model, data, cd)
            if is_point:
                rb[o : o + 3] = cd.oMc1.translation
                rb[o : o + 3] -= cd.oMc2.translation
            else:
                rb[o : o + 6] = pin.log6(cd.c1Mc2).vector
        if self.identity:
            return rb
        r = np.empty(self.n) if out is None else out
        r[self._dst] = rb[self._src]
        if self._planes:
            r[self._pl_dst] = np.einsum("mij,mj->mi", self._pl_E, rb[self._pl_src])
        cds = self._cds
        for o, b, F, a, _, _ in self._axes:
            cd = cds[b]
            a2 = cd.oMc2.rotation @ a
            r[o : o + 2] = (cd.oMc1.rotation @ F).T @ a2
        for o, b, n, _, _ in self._turns:
            cd = cds[b]
            r[o] = _turn(cd.oMc1.rotation, cd.oMc2.rotation, n)
        return r

    def jacobian_at(self, data: pin.Data) -> np.ndarray:
        """Jacobian (n, nv) from ``data`` after the joint Jacobians (updates the datas)."""
        model = self.model
        for _, _, cm, cd in self._entries:
            cm.calc(model, data, cd)
        if self.identity and not self._welds:  # (points alone: Pinocchio's rows as they are)
            J = pin.getConstraintsJacobian(model, data, self._cms, self._cds)
            return np.reshape(J, (self.nb, model.nv))
        return self.jacobian(data)

    def jacobian(self, data: pin.Data, out: np.ndarray | None = None) -> np.ndarray:
        """Jacobian (n, nv) from ``data`` after the joint Jacobians and :meth:`calc`."""
        model = self.model
        nv = model.nv
        Jb = np.reshape(
            pin.getConstraintsJacobian(model, data, self._cms, self._cds), (self.nb, nv)
        )
        for o, cd in self._welds:
            M = cd.c1Mc2
            Jb[o : o + 6] = -pin.Jlog6(M).dot(M.toActionMatrixInverse()).dot(Jb[o : o + 6])
        if self.identity:
            if out is None:
                return Jb
            out[:] = Jb
            return out
        J = np.empty((self.n, nv)) if out is None else out
        J[self._dst] = Jb[self._src]
        if self._planes:
            J[self._pl_dst] = np.einsum("mij,mjv->miv", self._pl_E, Jb[self._pl_src])
        if self._axes or self._turns:
            Jang = np.reshape(data.J, (6, nv))[3:]
            cds = self._cds
            for o, b, F, a, j1, j2 in self._axes:
                cd = cds[b]
                a2 = cd.oMc2.rotation @ a
                W = np.cross(a2, (cd.oMc1.rotation @ F).T)  # w_k = a2 x f_k, (2, 3)
                J[o : o + 2] = (W @ Jang) * self._dmask[(j1, j2)]
            for o, _, n, j1, j2 in self._turns:
                J[o] = (n @ Jang) * self._dmask[(j1, j2)]
        return J

    def local_residual(self, data: pin.Data, out: np.ndarray) -> None:
        """Contact-frame residual into ``out`` (n,), placements in ``data``.

        See :meth:`solvers.constraints.ConstraintSet.local_residual`; only when
        :attr:`identity`.
        """
        model = self.model
        for is_point, o, cm, cd in self._local()[2]:
            cm.calc(model, data, cd)
            if is_point:
                out[o : o + 3] = cd.c1Mc2.translation
            else:
                out[o : o + 6] = pin.log6(cd.c1Mc2).vector
        np.negative(out, out=out)

    def local_jacobian(self, data: pin.Data) -> np.ndarray:
        """Pinocchio's ``LOCAL`` constraint Jacobian (n, nv): only when :attr:`identity`."""
        cms, cds, _ = self._local()
        J = pin.getConstraintsJacobian(self.model, data, cms, cds)
        return np.reshape(J, (self.n, self.model.nv))

    def drift(self, data: pin.Data) -> np.ndarray:
        """Acceleration drift ``gamma`` (n,) from ``data`` after ``forwardKinematics(q, v, 0)``."""
        g = np.zeros(self.nb)
        classic, oMi, vel, acc = pin.classicAcceleration, data.oMi, data.v, data.a
        for o, sides, first in self._point_sides():  # classical accelerations of the points, world
            for i, (j, M) in enumerate(sides):
                lin = oMi[j].rotation.dot(classic(vel[j], acc[j], M))
                if i == 0 and first:
                    g[o : o + 3] = lin
                else:
                    g[o : o + 3] -= lin
        zero = pin.Motion.Zero()
        for k in self._other:  # welds: the relative spatial acceleration at a = 0
            _, j1, M1, j2, M2 = self._base[k]
            o = self.base_offsets[k]
            c1Mc2 = (data.oMi[j1] * M1).actInv(data.oMi[j2] * M2)
            v1 = c1Mc2.actInv(M1.actInv(data.v[j1])) if j1 else zero
            a1 = c1Mc2.actInv(M1.actInv(data.a[j1])) if j1 else zero
            v2 = M2.actInv(data.v[j2]) if j2 else zero
            a2 = M2.actInv(data.a[j2]) if j2 else zero
            nu = v2 - v1
            g[o : o + 6] = pin.Jlog6(c1Mc2) @ (a2 - a1 + nu.cross(v1)).vector
        if self.identity:
            return g
        out = np.empty(self.n)
        out[self._dst] = g[self._src]
        if self._planes:
            out[self._pl_dst] = np.einsum("mij,mj->mi", self._pl_E, g[self._pl_src])
        if self._axes or self._turns:
            z = np.zeros(3)

            def world(j: int) -> tuple[np.ndarray, np.ndarray]:
                if not j:
                    return z, z
                R = data.oMi[j].rotation
                return R @ data.v[j].angular, R @ data.a[j].angular

            for o, b, F, a, j1, j2 in self._axes:
                _, M1, _, M2 = self._base[b][1:]
                R1 = (data.oMi[j1] * M1).rotation
                R2 = (data.oMi[j2] * M2).rotation
                (w1, al1), (w2, al2) = world(j1), world(j2)
                a2 = R2 @ a
                da2 = np.cross(w2, a2)
                dw = w2 - w1
                for k in range(2):
                    f = R1 @ F[:, k]
                    df = np.cross(w1, f)
                    wk = np.cross(a2, f)
                    dwk = np.cross(da2, f) + np.cross(a2, df)
                    out[o + k] = dwk @ dw + wk @ (al2 - al1)
            for o, _, n, j1, j2 in self._turns:
                (_, al1), (_, al2) = world(j1), world(j2)
                out[o] = n @ (al2 - al1)
        return out

    def reactions(
        self, data: pin.Data, lam: np.ndarray
    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """One force and one moment per closure from the multipliers (module docstring).

        Args:
            data: Data whose joint placements are those of the configuration.
            lam: Multipliers (n,) [N, N m] of the rows.

        Returns:
            Per closure: the force [N] and moment [N m] on ``joint1``'s body about ``p1``, and
            ``p1`` [m], world axes.

        """
        self.calc(data)
        out = []
        cds = self._cds
        for b in self.blocks:
            c = b.closure
            lb = np.asarray(lam[b.offset : b.offset + b.size], dtype=float)
            cd = cds[b.base[0]]
            p = np.array(cd.oMc1.translation)
            force, moment = np.zeros(3), np.zeros(3)
            if b.normal is not None:
                e1, e2 = _perpendicular(b.normal)
                force = lb[0] * e1 + lb[1] * e2
                if b.size == 3:
                    moment = -lb[2] * b.normal
            elif c.kind == "point":
                force = lb.copy()
            elif c.kind == "weld":  # the wrench on body 2 in its frame: minus it, world axes
                R = cd.oMc2.rotation
                force, moment = -(R @ lb[:3]), -(R @ lb[3:])
            elif not self.reduce:  # two points: the second one's force and its moment
                p2 = np.array(cds[b.base[1]].oMc1.translation)
                force = lb[:3] + lb[3:]
                moment = np.cross(p2 - p, lb[3:])
            else:
                force = lb[:3].copy()
                a = np.asarray(c.axis, dtype=float) / np.linalg.norm(c.axis)
                e1, e2 = _perpendicular(a)
                a2 = cd.oMc2.rotation @ a
                for k, f in enumerate((-e2, e1)):
                    moment -= lb[3 + k] * np.cross(a2, cd.oMc1.rotation @ (HINGE_ARM * f))
            out.append((force, moment, p))
        return out

    def split(self, r: np.ndarray) -> dict[str, float]:
        """Norm of the rows of each closure, by name."""
        return {
            n: float(np.linalg.norm(r[self.offsets[k] : self.offsets[k + 1]]))
            for k, n in enumerate(self.names)
        }
