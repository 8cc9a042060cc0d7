"""First-order sensitivity of the platform pose to actuator and geometric errors, through the loops.

The one derivative accuracy analysis and geometric calibration both need: how the platform pose
of a closed-loop robot moves when an actuator coordinate or a placement of the description
(:mod:`pkdyn.precision.parameters`) changes, the actuators held at their readings.

**Pose error convention** (the task convention of :mod:`pkdyn.analysis.kinematics`): ``dx`` (6,)
stacks the displacement of the platform frame origin in world axes [m] and the small rotation
of the platform in its own frame [rad] (``log3(R0^T R)``).

**Placement errors act as twists.** An error ``xi`` of a placement ``M`` (``M exp(xi)``) moves
every body downstream of it (a joint's subtree; for a closure frame or the platform, that frame
alone) by the world twist ``V = Ad(oF) xi``, ``oF`` the world placement of the placed frame
(for the joint placements, Pinocchio's kinematic regressor ``pin.computeJointKinematicRegressor``
gives these twists for every joint at once). A point ``p`` on a moved body moves by
``v + w x p``, a frame ``R`` turns by ``R^T w`` in its axes.
The closure residuals ``c(q, p)`` (:class:`solvers.ConstraintSet`: points ``p1 - p2``, welds
``log6(c1Mc2)``) and the platform pose ``x(q, p)`` then change at fixed ``q`` by ``C dp`` and
``X dp``. Gains change the actuated coordinates, ``dqa = diag(qa) G dp``.

**Through the loops.** With the actuators at their readings, the passive coordinates move to
keep the closures: ``Jc_p dq_p + Jc_a dqa + C dp = 0`` (minimum-norm ``dq_p``: internal
mobilities, like the spin of a Delta's bars, stay still), so that

    dx = J dqa + K dp,   J = Jx_a - Jx_p Jc_p^+ Jc_a,   K = X + J diag(qa) G - Jx_p Jc_p^+ C

with ``Jc`` the Jacobian of the robot's constraint layer (``robot.constraints.unreduced``: the
closures' rows, every one of them, then the joint couplings', which take part in the
elimination and depend on no placement; the closures' rows that vanish only by construction of
the nominal geometry, such as a planar loop's out-of-plane rows, are kept: placement errors
open them) and ``Jx`` the platform Jacobian; the elimination is
:func:`pkdyn.analysis.kinematics.passive_map` (:func:`solvers.numerics.passive_elimination`, with
the structural rank of ``Jc_p`` found at the robot's home). ``J`` is the direct
kinematic Jacobian of :func:`pkdyn.analysis.kinematics.kinematic_models` (all six pose rows).
Placement errors the passive joints cannot absorb (an over-constrained mechanism: the
out-of-plane errors of a planar five-bar) leave a closure residual at first order, reported in
:attr:`PoseSensitivity.closure_gap` (and, where the passive motion that absorbs a closure
residual would break a coupling, :attr:`PoseSensitivity.coupling_gap`): the mechanism would not
assemble without deforming.

The derivative is with respect to the parameters ``p`` of a :class:`ParameterModel` at a robot
already perturbed by ``at`` (the placement ``M0 exp(xi(at))`` moves by ``exp(Jexp6(xi) dxi)``),
so that a calibration's Gauss-Newton steps use the exact Jacobian.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
import scipy.sparse

from pkdyn.analysis.kinematics import passive_map
from pkdyn.exceptions import InvalidInputError, SingularConfigurationError
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot
from pkdyn.precision.parameters import ParameterModel, placement_frames
from solvers import numerics

__all__ = ["PoseSensitivity", "pose_sensitivity"]


@dataclass
class PoseSensitivity:
    """Platform pose sensitivities at one configuration.

    Attributes:
        q: The configuration (nq,).
        pose: Platform placement at ``q``.
        J: Pose per actuator coordinate (6, n_a) [m or rad per rad or m].
        K: Pose per parameter (6, n_par) [m or rad per parameter unit].
        closure_gap: Closure residual per parameter that no passive motion absorbs (nc, n_par)
            [m or rad per unit], rows of ``robot.constraints.unreduced.closures``: zero for
            parameters the mechanism accommodates.
        joints: Joint velocity coordinates per parameter (nv, n_par) [rad or m per unit]: how
            the loops (and couplings) move every joint when a parameter changes at fixed
            actuator readings (the actuated rows: the gains' effect); what encoders on
            passive joints see.
        coupling_gap: Coupling residual per parameter that no passive motion absorbs (nk,
            n_par) [rad or m per unit] (``None``: no couplings).

    """

    q: np.ndarray
    pose: pin.SE3
    J: np.ndarray
    K: np.ndarray
    closure_gap: np.ndarray
    joints: np.ndarray | None = None
    coupling_gap: np.ndarray | None = None

    @property
    def gap(self) -> np.ndarray:
        """Every constraint row's unabsorbed residual (n, n_par).

        The closure rows (m or rad), then the coupling rows (rad or m); zero columns for
        parameters the mechanism accommodates.
        """
        if self.coupling_gap is None or not self.coupling_gap.size:
            return self.closure_gap
        return np.vstack([self.closure_gap, self.coupling_gap])

    @property
    def position(self) -> np.ndarray:
        """Position rows of ``K`` (3, n_par) [m per unit]."""
        return self.K[:3]


def _skew(p: np.ndarray) -> np.ndarray:
    """Skew matrices (..., 3, 3) of vectors (..., 3)."""
    out = np.zeros(p.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -p[..., 2], p[..., 1]
    out[..., 1, 0], out[..., 1, 2] = p[..., 2], -p[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -p[..., 1], p[..., 0]
    return out


@dataclass
class _Plan:
    """What a parameter model moves on a robot structure (indices only, no placements).

    Entities are the two sides of every constraint model, then the platform, each on the body
    of a joint (``joints``); ``own[e]`` is the block of the entity's own placement (its
    closure's frame, the platform frame) among the used placements, or -1.
    """

    used: np.ndarray  # placement indices with non-zero rows in E
    rows: np.ndarray  # their E rows (6 per placement)
    joint_cols: np.ndarray  # (n_used,) regressor column block of each used joint placement
    own: np.ndarray  # (n_entities,) own placement's block among the used ones, or -1
    joints: np.ndarray  # (n_entities,) joint carrying each entity
    points: np.ndarray  # (n_points, 2): constraint index, row offset
    welds: np.ndarray  # (n_welds, 2)
    platform: int  # entity index of the platform (-1: none)
    fixed: dict[str, Any] = field(default_factory=dict)  # filled on first use


def _plan(robot: Robot, model: ParameterModel) -> _Plan:
    key = id(model)
    plan = _PLANS.get(key)
    if plan is not None:
        return plan
    n_pl = len(model.placements)
    used = np.flatnonzero(np.any(model.E.reshape(n_pl, 6, -1) != 0.0, axis=(1, 2)))
    block = {int(k): i for i, k in enumerate(used)}
    own_k: dict[tuple[str, int], int] = {}
    platform_k = -1
    for k, pl in enumerate(model.placements):
        if pl.kind == "closure":
            own_k[(pl.closure, pl.side)] = k
        elif pl.kind == "platform":
            platform_k = k
    joint_cols = np.array(
        [
            model.placements[k].joint - 1 if model.placements[k].kind == "joint" else -1
            for k in used
        ],
        dtype=np.int64,
    )
    own: list[int] = []
    joints: list[int] = []
    points: list[tuple[int, int]] = []
    welds: list[tuple[int, int]] = []
    cr = robot.constraints.unreduced.closure_rows  # (one base model per constraint model)
    offsets = cr.base_offsets if cr is not None else np.zeros(1, dtype=int)
    for i, (cm, owner) in enumerate(
        zip(robot.constraint_models, robot.constraint_owner, strict=True)
    ):
        own.append(block.get(own_k.get((owner, 1), -1), -1))
        own.append(block.get(own_k.get((owner, 2), -1), -1))
        joints += [int(cm.joint1_id), int(cm.joint2_id)]
        (points if cm.type == pin.ContactType.CONTACT_3D else welds).append((i, int(offsets[i])))
    platform = -1
    if robot.platform_frame is not None:
        platform = len(own)
        own.append(block.get(platform_k, -1))
        joints.append(int(robot.model.frames[robot.platform_frame].parentJoint))
    plan = _Plan(
        used,
        (6 * used[:, None] + np.arange(6)[None, :]).reshape(-1),
        joint_cols,
        np.asarray(own, dtype=np.int64),
        np.asarray(joints, dtype=np.int64),
        np.asarray(points, dtype=np.int64).reshape(-1, 2),
        np.asarray(welds, dtype=np.int64).reshape(-1, 2),
        platform,
    )
    _PLANS[key] = plan
    weakref.finalize(model, _PLANS.pop, key, None)
    return plan


_PLANS: dict[int, _Plan] = {}

_WORLD = pin.ReferenceFrame.WORLD


def _rigid_jacobians(
    robot: Robot, model: ParameterModel, data: pin.Data, at: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """``C`` (nc, n_par) and ``X`` (6, n_par): closures and platform per parameter, fixed ``q``.

    The world twist of each entity per placement twist: Pinocchio's kinematic regressor of its
    body (``pin.computeJointKinematicRegressor``, world axes: the spatial twist per right
    perturbation of every joint placement, the same for every frame of the body) for the joint
    placements, ``Ad(oF)`` for the entity's own placement (a closure frame, the platform).
    """
    plan = _plan(robot, model)
    n_par = model.size
    C = np.zeros((robot.constraints.unreduced.n, n_par))
    X = np.zeros((6, n_par))
    if plan.used.size == 0:
        return C, X
    n_used = plan.used.size
    fixed = plan.fixed
    if not fixed:  # (per model: what does not depend on the configuration)
        E0 = model.E[plan.rows].reshape(n_used, 6, n_par)
        is_joint = plan.joint_cols >= 0
        carriers = np.unique(plan.joints[plan.joints > 0])
        mine = np.unique(plan.own[plan.own >= 0])
        fixed.update(
            E=E0,
            is_joint=is_joint,
            cols=(6 * plan.joint_cols[is_joint][:, None] + np.arange(6)[None, :]).reshape(-1),
            EjT=scipy.sparse.csr_array(E0[is_joint].reshape(-1, n_par).T),
            carriers=carriers,
            on=plan.joints > 0,
            carrier=np.searchsorted(carriers, plan.joints[plan.joints > 0]),
            mine=mine,
            mine_at=tuple(model.placements[plan.used[k]] for k in mine),
            own=np.searchsorted(mine, plan.own[plan.own >= 0]),
        )
    E, EjT = fixed["E"], fixed["EjT"]
    if at is not None:
        xi = model.twists(at)[plan.used]
        E = np.einsum("kij,kjn->kin", np.array([pin.Jexp6(pin.Motion(x)) for x in xi]), E)
        EjT = scipy.sparse.csr_array(E[fixed["is_joint"]].reshape(-1, n_par).T)
    # world twists are those of the bodies: one regressor per joint carrying an entity
    S = np.zeros((plan.own.size, 6, n_par))  # world twist of each entity per parameter
    carriers, cols = fixed["carriers"], fixed["cols"]
    if cols.size and carriers.size:
        m = robot.model
        reg = np.vstack(
            [pin.computeJointKinematicRegressor(m, data, int(j), _WORLD)[:, cols] for j in carriers]
        )
        S[fixed["on"]] = (EjT @ reg.T).T.reshape(carriers.size, 6, n_par)[fixed["carrier"]]
    mine = fixed["mine"]
    if mine.size:  # the frame of a closure (a hinge's arms are offsets of it) or the platform
        ad = np.array([F.toActionMatrix() for F in placement_frames(robot, data, fixed["mine_at"])])
        own = fixed["own"]
        S[plan.own >= 0] += np.einsum("eij,ejn->ein", ad[own], E[mine[own]])
    cms = robot.constraint_models
    if plan.points.size:
        idx = plan.points[:, 0]
        pts = [cms[int(i)] for i in idx]
        p1 = np.array([(data.oMi[c.joint1_id] * c.joint1_placement).translation for c in pts])
        p2 = np.array([(data.oMi[c.joint2_id] * c.joint2_placement).translation for c in pts])
        S1, S2 = S[2 * idx], S[2 * idx + 1]
        d1 = S1[:, :3] - np.einsum("sij,sjn->sin", _skew(p1), S1[:, 3:])
        d2 = S2[:, :3] - np.einsum("sij,sjn->sin", _skew(p2), S2[:, 3:])
        rows = (plan.points[:, 1][:, None] + np.arange(3)[None, :]).reshape(-1)
        C[rows] = (d1 - d2).reshape(-1, n_par)
    for i, o in plan.welds:
        cm = cms[int(i)]
        oM1 = data.oMi[cm.joint1_id] * cm.joint1_placement
        oM2 = data.oMi[cm.joint2_id] * cm.joint2_placement
        op = pin.Jlog6(oM1.actInv(oM2)) @ oM2.inverse().toActionMatrix()
        C[o : o + 6] = op @ (S[2 * i + 1] - S[2 * i])
    if plan.platform >= 0:
        assert robot.platform_frame is not None
        oMf = data.oMf[robot.platform_frame]
        Sp = S[plan.platform]
        X[:3] = Sp[:3] - _skew(oMf.translation) @ Sp[3:]
        X[3:] = oMf.rotation.T @ Sp[3:]
    return C, X


def _structural_rank(robot: Robot) -> int:
    """Rank of the passive closure columns at home, by the elimination's rule (cached)."""
    key = id(robot.model)
    rank = _RANKS.get(key)
    if rank is None:
        cs = robot.constraints.unreduced  # (the rows placement errors can open)
        Jc = cs.jacobian(robot.data, robot.q_home)[:, robot.passive_v]
        rank = int(numerics.passive_elimination(Jc).rank)
        _RANKS[key] = rank
        weakref.finalize(robot.model, _RANKS.pop, key, None)
    return rank


_RANKS: dict[int, int] = {}


def pose_sensitivity(
    robot: Robot,
    q: Sequence[float] | np.ndarray,
    model: ParameterModel | None = None,
    at: Sequence[float] | np.ndarray | None = None,
) -> PoseSensitivity:
    """Platform pose per actuator coordinate and per geometric parameter, at ``q``.

    Args:
        robot: The robot (already perturbed by ``at`` when given: ``perturbed(...).robot``).
        q: An assembled configuration (nq,).
        model: The parameter model (``None``: actuator sensitivity only, ``K`` empty).
        at: Parameters (n_par,) the robot is perturbed by (default zero: the nominal robot).

    Returns:
        ``J``, ``K`` and the closure gap (module docstring).

    Raises:
        InvalidInputError: No platform frame, or malformed ``q`` / ``at``.
        SingularConfigurationError: A parallel singularity (the actuators do not determine
            the platform).

    """
    if robot.platform_frame is None:
        raise InvalidInputError("robot", f"{robot.name} declares no platform frame")
    qq = as_finite("q", q, robot.nq)
    data = robot.data
    cs = robot.constraints.unreduced  # (the rows placement errors can open)
    r = _structural_rank(robot) if cs.n else 0  # (at home: before q)
    pm = passive_map(robot, qq, angular="platform", rank=r, constraints=cs)
    if pm.elimination.singular:
        raise SingularConfigurationError(
            "parallel",
            f"parallel singularity: the passive joints of {robot.name} are not determined by "
            f"the actuators (closure Jacobian margin {pm.elimination.margin:.3g}); "
            "sensitivities are unbounded here",
        )
    Jc, a = pm.Jc, pm.actuated_v
    qa = qq[robot.actuated_q]
    J = pm.J
    V = None
    if model is None:
        K = np.zeros((6, 0))
        gap = np.zeros((Jc.shape[0], 0))
    else:
        p_at = None if at is None else as_finite("at", at, model.size)
        reading = qa if p_at is None else qa / (1.0 + model.gains(p_at))
        C, X = _rigid_jacobians(robot, model, data, p_at)
        Dg = reading[:, None] * model.G  # actuated coordinate per parameter (gains)
        rhs = C + Jc[:, a] @ Dg
        K = X + pm.Jx[:, a] @ Dg + pm.platform(rhs)
        gap = pm.elimination.gap(rhs)
        V = np.zeros((robot.nv, model.size))
        V[a] = Dg
        V[pm.passive_v] = pm.passive(rhs)
    return PoseSensitivity(
        qq,
        pin.SE3(data.oMf[robot.platform_frame]),
        J,
        K,
        gap[: cs.nc],
        V,
        gap[cs.nc :] if cs.nk else None,
    )
