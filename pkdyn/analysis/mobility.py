"""Mobility of a closed-loop robot: Grübler-Kutzbach count, rank-based mobility, internal modes.

Two counts are reported side by side (seed 000, section 1.3.3; seed 001, Pasqui):

- **Grübler-Kutzbach** from the topology alone: ``MO = sum f_i - d * loops - n_k``, where
  ``f_i`` are the mobilities of the physical joints (tree joints, plus each closure: point 3,
  hinge 1, weld 0), ``loops`` the number of independent loops (:attr:`pkdyn.Robot.loops`), ``d``
  the dimension of the motion space (6, or 3 for a planar mechanism) and ``n_k`` the number of
  joint couplings (gears, mimic joints: one scalar equation each).
- **Rank-based** (Pasqui): ``Ic = sum f_i`` kinematic unknowns, ``Ec = d * loops + n_k``
  closure and coupling equations of rank ``rc``; mobility ``m = Ic - rc`` and degree of hyperstatism
  ``h = Ec - rc``; ``m = m_u + m_i`` (useful and internal mobilities). In a pkdyn model the
  free-flyer / planar joint of a platform adds coordinates that the closures then determine,
  so ``m`` is computed as ``nv - rank(J_c)`` at a generic assembled configuration (``J_c`` the
  closure Jacobian) and ``rc = Ic - m``. Unlike Grübler's count, ``m`` is right for
  overconstrained mechanisms (planar loops modelled in space, parallelograms of hinges).

The useful mobility ``m_u`` is the dimension of the platform's motion space (the controlled
pose components, ``pkdyn:platform task``) over the null space of ``J_c``; the others are
internal mobilities, which move some bodies but not the platform (the bars of a Delta spinning
about their axes). Each internal mobility is described in words when it is carried by one
joint, else by the joints it moves.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
import scipy.linalg

from pkdyn.exceptions import AssemblyError, InvalidInputError
from pkdyn.model.assembly import project
from pkdyn.model.description import CLOSURE_KINDS
from pkdyn.model.robot import MODELLING_JOINTS, Robot
from pkdyn.results import Result, deprecated_alias
from solvers import FramePoseTask, numerics

__all__ = [
    "CLOSURE_FREEDOM",
    "InternalMobility",
    "MobilityResult",
    "mobility",
    "format_mobility",
]

CLOSURE_FREEDOM = {kind: 6 - n for kind, n in CLOSURE_KINDS.items()}
"""Degrees of freedom of the joint a closure stands for: point 3, hinge 1, weld 0."""

RANK_TOL = 1e-8
"""Default relative singular-value threshold of the rank decisions."""

PLANAR_TOL = 1e-7
"""Angular tolerance [rad] of the planarity test (parallel / normal joint and hinge axes)."""

PERTURBATION = 0.05
"""Standard deviation of the random velocity-space step away from ``q_home`` [rad or m]."""

_WORLD = pin.ReferenceFrame.WORLD


@dataclass(frozen=True)
class InternalMobility:
    """One internal mobility: a motion of the mechanism that leaves the platform task still.

    Attributes:
        description: What moves, in words (``"bar1a spins about its axis (joint bar1a_upper)"``).
        joints: Names of the joints whose coordinates the motion changes.
        bodies: Names of the links it moves.
        direction: Unit velocity direction (nv,) [rad or m, normalised].

    """

    description: str
    joints: tuple[str, ...]
    bodies: tuple[str, ...]
    direction: np.ndarray = field(repr=False, compare=False)


@dataclass(frozen=True)
class MobilityResult(Result):
    """Mobility analysis of a robot (see :func:`mobility`).

    Attributes:
        robot: Robot name.
        d: Dimension of the motion space: 3 (planar mechanism) or 6.
        loops: Number of independent loops (cyclomatic number of the joint graph).
        joint_mobility: ``Ic = sum f_i`` over the physical joints and closures.
        grubler: Grübler-Kutzbach count ``MO = Ic - d * loops - couplings``.
        equations: ``Ec = d * loops + couplings``, number of closure (and coupling) equations
            in Pasqui's sense.
        nv: Velocity coordinates of the model (modelling joints included).
        closure_rows: Rows of the constraint Jacobian of the model (``robot.constraints``: a
            hinge gives 5 rows, a planar loop's closure its in-plane rows, a coupling 1).
        rank: Rank of the closure Jacobian ``J_c`` (closure_rows x nv) at ``q``; the platform's
            free-flyer or planar coordinates count in ``nv``, so ``mobility = nv - rank``.
        closure_rank: Pasqui's ``rc = Ic - m``, rank of the ``Ec`` closure equations.
        mobility: Mobility ``m`` (degrees of freedom, internal ones included).
        hyperstatism: Degree of hyperstatism ``h = Ec - rc`` (redundant closure equations).
        useful: Useful mobility ``m_u``: dimension of the platform task's motion space (all of
            ``mobility`` when the robot declares no platform).
        internal: Internal mobility ``m_i = m - m_u``.
        internal_modes: Description of each internal mobility.
        floating: Degrees of freedom of free-floating components (a floating base not tied to
            the ground): counted in ``mobility`` and in both counts' ``Ic`` (as in
            :meth:`pkdyn.Robot.mobility`: the Mini Cheetah has 18 = 6 + 12), said apart.
        q: Assembled configuration the ranks were computed at (nq,).
        singular_values: Singular values of ``J_c``, decreasing.
        couplings: Number of joint couplings (one row of ``J_c`` each).

    """

    robot: str
    d: int
    loops: int
    joint_mobility: int
    grubler: int
    equations: int
    nv: int
    closure_rows: int
    rank: int
    closure_rank: int
    mobility: int
    hyperstatism: int
    useful: int
    internal: int
    internal_modes: tuple[InternalMobility, ...]
    floating: int
    q: np.ndarray = field(repr=False, compare=False)
    singular_values: np.ndarray = field(repr=False, compare=False)
    couplings: int = 0

    @property
    def internal_names(self) -> tuple[str, ...]:
        """Description of each internal mobility."""
        return tuple(m.description for m in self.internal_modes)

    def table(self) -> str:
        """Both counts with their terms, the useful / internal split, the internal mobilities."""
        return format_mobility(self)

    as_json = deprecated_alias("as_json", "to_json")

    def to_json(self) -> dict[str, Any]:
        """The result as a JSON-serialisable dictionary.

        Returns:
            ``robot, grubler, mobility, useful, internal, hyperstatism, rank, d, loops,
            joint_mobility, equations, closure_rank, couplings, internal_names`` (integers,
            strings).

        """
        return {
            "robot": self.robot,
            "grubler": self.grubler,
            "mobility": self.mobility,
            "useful": self.useful,
            "internal": self.internal,
            "hyperstatism": self.hyperstatism,
            "rank": self.rank,
            "d": self.d,
            "loops": self.loops,
            "joint_mobility": self.joint_mobility,
            "equations": self.equations,
            "closure_rank": self.closure_rank,
            "couplings": self.couplings,
            "floating": self.floating,
            "internal_names": list(self.internal_names),
        }


def mobility(
    robot: Robot,
    q: np.ndarray | Sequence[float] | None = None,
    seed: int = 0,
    d: int | None = None,
    tol: float = RANK_TOL,
) -> MobilityResult:
    """Mobility of a robot by Grübler-Kutzbach and by the rank of its closure equations.

    Args:
        robot: The robot.
        q: Configuration (nq,) to analyse; it is projected onto the closures. By default, a
            generic configuration: ``q_home`` moved by a random step (seeded) and projected, so
            that special configurations (singular, symmetric) do not bias the ranks.
        seed: Seed of the random step.
        d: Dimension of the motion space, 3 or 6; by default 3 if the mechanism is planar (all
            joint axes parallel to a normal ``n``, prismatic axes normal to it, every closure a
            hinge about ``n`` or a weld, platform task within the plane), else 6. A platform
            task with an out-of-plane component declares a spatial model.
        tol: Relative tolerance of the ranks and null spaces (the rule of
            :mod:`solvers.numerics`).

    Returns:
        The analysis; ``grubler`` and ``mobility`` differ when closure equations are redundant
        (``hyperstatism > 0``) in a way the topology cannot see.

    Raises:
        InvalidInputError: Malformed ``q``, ``d`` not 3 or 6, or ``tol`` not in (0, 1).
        AssemblyError: The given ``q`` cannot be projected onto the closures.

    """
    if d is not None and d not in (3, 6):
        raise InvalidInputError("d", f"must be 3 or 6, got {d!r}")
    if not 0.0 < tol < 1.0:
        raise InvalidInputError("tol", f"must lie in (0, 1), got {tol!r}")
    qq = _generic_configuration(robot, seed) if q is None else project(robot, np.asarray(q))
    model, data = robot.model, robot.data

    physical = [j for j in range(1, model.njoints) if not _is_modelling(model, j)]
    kinds = {c.name: c.kind for c in robot.closures}
    Ic = sum(int(model.joints[j].nv) for j in physical)
    Ic += sum(CLOSURE_FREEDOM[kinds[name]] for name in dict.fromkeys(robot.constraint_owner))
    loops = robot.loops

    if robot.constraints.n:
        _, Jc = robot.constraints.residual_and_jacobian(data, qq)
    else:
        Jc = np.zeros((0, model.nv))
        pin.computeJointJacobians(model, data, qq)
    sv = np.linalg.svd(Jc, compute_uv=False) if Jc.size else np.zeros(0)
    rank = numerics.rank_of(sv, tol)
    # Free-floating components: their modelling joint's coordinates stay free; fix them.
    float_v = _floating_velocity_indices(robot)
    A = np.vstack([Jc, np.eye(model.nv)[float_v]])
    N = numerics.null_space(A, tol)
    m = N.shape[1]
    if d is None:
        d = 3 if _plane_normal(robot, physical) is not None else 6
    n_k = robot.constraints.nk
    Ec = d * loops + n_k
    rc = Ic - m

    useful, V = m, np.zeros((model.nv, 0))
    if robot.platform_frame is not None and m:
        task = FramePoseTask(model, robot.platform_frame, robot.task_rows)
        task.target = pin.SE3(pin.updateFramePlacement(model, data, robot.platform_frame))
        T = task.residual_and_jacobian(data)[1]
        TN = T @ N
        coeffs = numerics.null_space(TN, tol, scale=_scale(T)) if TN.size else np.eye(m)
        useful = m - coeffs.shape[1]
        V = N @ coeffs
    modes = _describe_internal(robot, V, tol)
    nf = len(float_v)  # a floating base's coordinates: degrees of freedom, counted and said
    return MobilityResult(
        robot=robot.name,
        d=d,
        loops=loops,
        joint_mobility=Ic + nf,
        grubler=Ic + nf - Ec,
        equations=Ec,
        nv=int(model.nv),
        closure_rows=int(Jc.shape[0]),
        rank=rank,
        closure_rank=rc,
        mobility=m + nf,
        hyperstatism=Ec - rc,
        useful=useful,
        internal=m - useful,
        internal_modes=modes,
        floating=nf,
        q=qq,
        singular_values=sv,
        couplings=n_k,
    )


def format_mobility(result: MobilityResult) -> str:
    """Human-readable report of a mobility analysis (several lines, no trailing newline).

    Args:
        result: The analysis.

    Returns:
        The report: both counts with their terms, the useful / internal split and the internal
        mobilities.

    """
    r = result
    space = "planar, d = 3" if r.d == 3 else "spatial, d = 6"
    coupled = f" - {r.couplings}" if r.couplings else ""
    floating = f" + {r.floating} free-floating" if r.floating else ""
    lines = [
        f"{r.robot}: mobility {r.mobility} = {r.useful} useful + {r.internal} internal"
        f"{floating} ({space}, {r.loops} loop{'' if r.loops == 1 else 's'}"
        + (f", {r.couplings} coupling{'' if r.couplings == 1 else 's'}" if r.couplings else "")
        + ")",
        f"  Grübler-Kutzbach: MO = sum f_i - d * loops{' - couplings' if coupled else ''} = "
        f"{r.joint_mobility} - {r.d} * {r.loops}{coupled} = {r.grubler}",
        f"  rank (Pasqui): Ic = {r.joint_mobility}, Ec = {r.equations}, rc = {r.closure_rank}; "
        f"m = Ic - rc = {r.mobility}, h = Ec - rc = {r.hyperstatism}",
        f"  {'constraint' if r.couplings else 'closure'} Jacobian: {r.closure_rows} x {r.nv}, "
        f"rank {r.rank}",
    ]
    if r.floating:
        lines.append(
            f"  free-floating: {r.floating} of them move a base not tied to the ground (its "
            "joint counts in sum f_i)"
        )
    if r.hyperstatism > 0:
        lines.append(
            f"  Grübler's count is wrong here: {r.hyperstatism} closure "
            f"{'equation is' if r.hyperstatism == 1 else 'equations are'} redundant "
            "(overconstrained mechanism)"
        )
    elif r.hyperstatism < 0:
        lines.append(f"  h < 0: the mechanism is not planar, d = {r.d} is too small")
    if r.internal_modes:
        lines.append("  internal mobilities:")
        lines.extend(f"    - {mode.description}" for mode in r.internal_modes)
    return "\n".join(lines)


def _is_modelling(model: pin.Model, j: int) -> bool:
    return bool(model.joints[j].shortname() in MODELLING_JOINTS)


def _scale(A: np.ndarray) -> float:
    return float(np.linalg.norm(A, 2)) if A.size else 0.0


def _generic_configuration(robot: Robot, seed: int) -> np.ndarray:
    """``q_home`` moved by a random step and projected onto the closures."""
    rng = np.random.default_rng(seed)
    step = rng.normal(0.0, PERTURBATION, robot.nv)
    for _ in range(6):
        try:
            return project(robot, pin.integrate(robot.model, robot.q_home, step))
        except AssemblyError:
            step *= 0.5
    return np.array(robot.q_home)


def _floating_velocity_indices(robot: Robot) -> np.ndarray:
    """Velocity indices of modelling joints that tie nothing to their parent's component."""
    model = robot.model
    comp = robot.components()
    idx: list[int] = []
    for j in range(1, model.njoints):
        if _is_modelling(model, j) and comp[j] != comp[model.parents[j]]:
            jm = model.joints[j]
            idx.extend(range(jm.idx_v, jm.idx_v + jm.nv))
    return np.array(idx, dtype=int)


def _plane_normal(robot: Robot, physical: list[int]) -> np.ndarray | None:
    """Normal ``n`` of the plane of motion if the mechanism is planar, else ``None``.

    Uses the joint placements and Jacobians last computed in ``robot.data``. Revolute axes
    must be parallel to ``n`` and prismatic axes normal to it (angular tolerance
    :data:`PLANAR_TOL`), closures be hinges about ``n`` or welds, and the platform task use
    only in-plane translations and the rotation about ``n``.
    """
    model, data = robot.model, robot.data
    eps = PLANAR_TOL
    planar_roots = [
        j for j in range(1, model.njoints) if model.joints[j].shortname() == "JointModelPlanar"
    ]
    cols: list[np.ndarray] = []
    for j in sorted(physical + planar_roots):
        jm = model.joints[j]
        if jm.nv == 0:
            continue
        J = np.reshape(pin.getJointJacobian(model, data, j, _WORLD), (6, model.nv))
        cols.extend(J[:, jm.idx_v + k] for k in range(jm.nv))
    n = next((c[3:] / np.linalg.norm(c[3:]) for c in cols if np.linalg.norm(c[3:]) > eps), None)
    if n is None:
        return None
    for c in cols:  # a planar twist: rotation about n, velocity of the origin normal to n
        size = float(np.linalg.norm(c))
        if np.linalg.norm(np.cross(c[3:], n)) > eps * size or abs(c[:3] @ n) > eps * size:
            return None
    kinds = {c.name: c.kind for c in robot.closures}
    points: dict[str, list[np.ndarray]] = {}
    for cm, owner in zip(robot.constraint_models, robot.constraint_owner, strict=True):
        kind = kinds[owner]
        if kind == "point":
            return None
        if kind == "hinge":
            points.setdefault(owner, []).append(
                (data.oMi[cm.joint1_id] * cm.joint1_placement).translation
            )
    for pts in points.values():
        axis = pts[1] - pts[0]
        if np.linalg.norm(np.cross(axis, n)) > eps * np.linalg.norm(axis):
            return None
    if robot.platform_frame is not None:
        R = pin.updateFramePlacement(model, data, robot.platform_frame).rotation
        for k in robot.task_rows:
            if k < 3 and abs(n[k]) > eps:
                return None
            if k >= 3 and np.linalg.norm(np.cross(R[:, k - 3], n)) > eps:
                return None
    return n


def _bodies(model: pin.Model, joints: Sequence[int]) -> tuple[str, ...]:
    keep = set(joints)
    return tuple(
        f.name for f in model.frames if f.type == pin.FrameType.BODY and f.parentJoint in keep
    )


def _joints_of(model: pin.Model, v: np.ndarray, tol: float) -> list[int]:
    """Joints whose coordinates ``v`` changes (components above ``tol * max |v|``)."""
    big = float(np.max(np.abs(v))) if v.size else 0.0
    out = []
    for j in range(1, model.njoints):
        jm = model.joints[j]
        if jm.nv and np.max(np.abs(v[jm.idx_v : jm.idx_v + jm.nv])) > tol * big:
            out.append(j)
    return out


def _describe_internal(robot: Robot, V: np.ndarray, tol: float) -> tuple[InternalMobility, ...]:
    """Split the internal subspace ``V`` (nv, m_i) into modes and describe each.

    Modes carried by a single joint are found first (their supports are disjoint, so they are
    independent); the rest of the subspace gets a reduced-echelon basis (identity on pivot
    coordinates: few joints per mode).
    """
    model = robot.model
    if V.shape[1] == 0:
        return ()
    found: list[np.ndarray] = []
    for j in range(1, model.njoints):
        jm = model.joints[j]
        if jm.nv == 0:
            continue
        outside = np.ones(model.nv, dtype=bool)
        outside[jm.idx_v : jm.idx_v + jm.nv] = False
        C = numerics.null_space(V[outside], tol, scale=1.0)  # V orthonormal: singular values <= 1
        found.extend(V @ C[:, c] for c in range(C.shape[1]))
    if found:
        F = np.column_stack(found)
        R = numerics.range_space(V - F @ (F.T @ V), tol, scale=1.0)  # singular values <= 1
    else:
        R = V
    if R.shape[1]:
        _, _, piv = scipy.linalg.qr(R.T, pivoting=True)
        B = R @ np.linalg.inv(R[piv[: R.shape[1]]])
        found.extend(B[:, c] / np.linalg.norm(B[:, c]) for c in range(B.shape[1]))
    return tuple(_describe_mode(robot, v * np.sign(v[np.argmax(np.abs(v))])) for v in found)


def _describe_mode(robot: Robot, v: np.ndarray) -> InternalMobility:
    """Describe the motion ``v`` (nv,): which bodies move, and how if they move as one."""
    model, data = robot.model, robot.data
    joints = _joints_of(model, v, 1e-6)
    names = tuple(model.names[j] for j in joints)
    label = ("joint " if len(names) == 1 else "joints ") + ", ".join(names)
    twists = {
        j: np.reshape(pin.getJointJacobian(model, data, j, _WORLD), (6, model.nv)) @ v
        for j in range(1, model.njoints)
    }
    size = max(float(np.linalg.norm(t)) for t in twists.values())
    moved = [j for j, t in twists.items() if np.linalg.norm(t) > 1e-6 * size]
    bodies = _bodies(model, moved)
    if not moved:
        return InternalMobility(f"internal motion of {label}", names, bodies, v)
    who = " + ".join(bodies) if bodies else ", ".join(model.names[j] for j in moved)
    many = len(bodies) > 1
    twist = twists[moved[0]]
    rigid = all(np.linalg.norm(twists[j] - twist) <= 1e-6 * size for j in moved)
    lin, ang = twist[:3], twist[3:]
    w = float(np.linalg.norm(ang))
    if not rigid:
        text = f"{who} {'move' if many else 'moves'} ({label})"
    elif w <= 1e-9 * size:
        text = f"{who} {'slide' if many else 'slides'} ({label})"
    else:
        # points where the moving group meets the rest: joints and closure frames
        anchors = [
            data.oMi[j].translation
            for j in range(1, model.njoints)
            if (j in moved) != (model.parents[j] in moved)
        ]
        for cm in robot.constraint_models:
            one, two = cm.joint1_id in moved, cm.joint2_id in moved
            if one != two:
                jid, M = (
                    (cm.joint1_id, cm.joint1_placement)
                    if one
                    else (cm.joint2_id, cm.joint2_placement)
                )
                anchors.append((data.oMi[jid] * M).translation)
        reach = max((float(np.linalg.norm(a - b)) for a in anchors for b in anchors), default=0.0)
        still = all(
            np.linalg.norm(lin + np.cross(ang, a)) <= 1e-6 * w * max(reach, 1e-3) for a in anchors
        )
        if still and reach > 1e-6:
            verb = "spin about their common axis" if many else "spins about its axis"
        else:
            verb = "turn" if many else "turns"
        text = f"{who} {verb} ({label})"
    return InternalMobility(text, names, bodies, v)
