"""Passive elements of a description on its model: checked, then built as solver forces.

The description's ``<dynamics>``, ``<pkdyn:passive>`` and ``<pkdyn:spring>`` elements (see
:mod:`pkdyn.model.description`) become one :class:`solvers.PassiveForces`; Pinocchio's own
``model.damping`` and ``model.friction`` are set to the same values (the MJCF export writes
them). Checks need the model: the joint exists and moves, one value or one per degree of freedom,
no friction on a joint that cannot carry it (a fixed joint; a floating or planar joint, which
places a platform or a floating base and rubs on nothing), rest positions inside the joint
limits (the cone or pyramid of a spherical joint included), spring ends on two bodies.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import DescriptionError
from pkdyn.model.build import resolve_frame
from pkdyn.model.description import JointSpec, PassiveSpec, SpringSpec
from pkdyn.model.robot import MODELLING_JOINTS, Robot
from solvers import FrameSpring, PassiveForces

__all__ = [
    "FRICTION_SMOOTHING",
    "passive_forces",
    "passive_summary",
    "rest_configuration",
    "with_passive",
]

FRICTION_SMOOTHING = 1e-2
"""Speed [rad/s or m/s] at which the smooth Coulomb friction reaches 76 % of its level."""

_UNITS = {"stiffness": "N m/rad or N/m", "damping": "N m s/rad or N s/m", "friction": "N m or N"}


def _single(jm: pin.JointModel) -> pin.Model:
    m = pin.Model()
    m.addJoint(0, jm, pin.SE3.Identity(), "j")
    return m


def rest_configuration(jm: pin.JointModel, rest: Sequence[float] | np.ndarray) -> np.ndarray:
    """Configuration (nq,) of one joint displaced by ``rest`` (nv,) from its zero configuration.

    Args:
        jm: The joint model.
        rest: Displacement (nv,): angle or position, the angles of a universal joint, the
            rotation vector of a spherical joint [rad or m].

    Returns:
        ``pin.integrate(neutral, rest)`` on that joint alone.

    """
    m = _single(jm)
    return np.asarray(pin.integrate(m, pin.neutral(m), np.asarray(rest, dtype=float)))


def _per_dof(
    source: str, culprit: str, values: tuple[float, ...], nv: int, signed: bool = False
) -> np.ndarray:
    if not values:
        return np.zeros(nv)
    for x in values:
        if not math.isfinite(x):
            raise DescriptionError(source, culprit, f"{x} is not finite")
        if not signed and x < 0.0:
            raise DescriptionError(source, culprit, f"{x:g} is negative; it must be >= 0")
    if len(values) not in (1, nv):
        dofs = "one degree of freedom (give 1 value)"
        if nv > 1:
            dofs = f"{nv} degrees of freedom (give 1 value or {nv})"
        raise DescriptionError(source, culprit, f"{len(values)} values for a joint of {dofs}")
    return np.array(np.broadcast_to(np.asarray(values, dtype=float), (nv,)))


def _check_rest(
    source: str,
    model: pin.Model,
    jid: int,
    q_rest: np.ndarray,
    rest: np.ndarray,
    limit: JointSpec | None,
) -> None:
    name = model.names[jid]
    jm = model.joints[jid]
    if jm.nq == jm.nv:
        lo = model.lowerPositionLimit[jm.idx_q : jm.idx_q + jm.nq]
        hi = model.upperPositionLimit[jm.idx_q : jm.idx_q + jm.nq]
        for k in range(jm.nq):
            finite = math.isfinite(lo[k]) and math.isfinite(hi[k]) and lo[k] < hi[k]
            if finite and not lo[k] <= q_rest[k] <= hi[k]:
                which = "" if jm.nq == 1 else f" (degree of freedom {k + 1})"
                raise DescriptionError(
                    source,
                    f"joint '{name}' rest={q_rest[k]:g}{which}",
                    f"outside the joint limits [{lo[k]:g}, {hi[k]:g}]; put the spring's rest "
                    "position inside them",
                )
    if limit is not None and limit.limit is not None and jm.shortname() == "JointModelSpherical":
        R = pin.exp3(rest)
        if limit.limit.margin(R) < 0.0:
            raise DescriptionError(
                source,
                f"joint '{name}' rest",
                "the rest rotation lies outside the joint's cone / pyramid limit",
            )


def _first_nonzero(spec: PassiveSpec) -> str | None:
    for f in ("friction", "stiffness", "damping"):
        if any(getattr(spec, f)):
            return f
    return None


def passive_forces(
    model: pin.Model,
    passive: Sequence[PassiveSpec],
    springs: Sequence[SpringSpec],
    source: str,
    joint_names: Sequence[str] = (),
    joints: Sequence[JointSpec] = (),
    preload: bool = False,
) -> PassiveForces | None:
    """Check the passive elements against the model and build their solver forces.

    Sets ``model.damping`` and ``model.friction`` (per velocity coordinate) to the
    description's values.

    Args:
        model: The model (spherical / universal joints already upgraded).
        passive: Per-joint passive elements.
        springs: Two-frame springs.
        source: File or robot name, for error messages.
        joint_names: Every joint of the URDF, fixed ones included (to tell a fixed joint from a
            missing one).
        joints: The joint upgrades (their cone / pyramid limits bound the rest rotation).
        preload: Accept a rest position outside the joint limits (a spring preloaded over the
            whole range, as MuJoCo's ``springref`` may be: the Menagerie grippers rest their
            linkage springs at 2.62 rad on joints limited to 0.8 rad).

    Returns:
        The forces, or ``None`` when nothing is passive.

    Raises:
        DescriptionError: The culprit joint or spring and field, and what would fix it.

    """
    nv = model.nv
    stiffness, damping, friction = np.zeros(nv), np.zeros(nv), np.zeros(nv)
    q_rest = pin.neutral(model)
    upgrades = {j.name: j for j in joints}
    for spec in passive:
        name = spec.joint
        if not model.existJointName(name):
            field = _first_nonzero(spec)
            if field is None:  # e.g. <dynamics damping="0"/> on a fixed joint: nothing to do
                continue
            if name in joint_names:
                raise DescriptionError(
                    source,
                    f"joint '{name}' {field}",
                    f"a fixed joint has no motion: it cannot carry {field}; remove it or make "
                    "the joint move",
                )
            raise DescriptionError(
                source, f"pkdyn:passive joint '{name}'", "no joint of that name in the URDF"
            )
        jid = model.getJointId(name)
        jm = model.joints[jid]
        iv = slice(jm.idx_v, jm.idx_v + jm.nv)
        values = {
            f: _per_dof(source, f"joint '{name}' {f}", getattr(spec, f), jm.nv, f == "rest")
            for f in ("stiffness", "damping", "friction", "rest")
        }
        if np.any(values["friction"]) and jm.shortname() in MODELLING_JOINTS:
            raise DescriptionError(
                source,
                f"joint '{name}' friction",
                "a floating or planar joint places a platform or a floating base and rubs on "
                "nothing: it cannot carry friction; put the friction on the hardware joints",
            )
        stiffness[iv] = values["stiffness"]
        damping[iv] = values["damping"]
        friction[iv] = values["friction"]
        if spec.rest:
            qj = rest_configuration(jm, values["rest"])
            if not preload:
                _check_rest(source, model, jid, qj, values["rest"], upgrades.get(name))
            q_rest[jm.idx_q : jm.idx_q + jm.nq] = qj
    frame_springs = []
    for sp in springs:
        what = f"spring '{sp.name}'"
        _per_dof(source, f"{what} stiffness", (sp.stiffness,), 1)
        _per_dof(source, f"{what} rest_length", (sp.rest_length,), 1, signed=True)
        j1, M1 = resolve_frame(model, sp.frame1, source, what)
        j2, M2 = resolve_frame(model, sp.frame2, source, what)
        if j1 == j2:
            raise DescriptionError(
                source, what, "both ends are on the same body; the spring would do nothing"
            )
        frame_springs.append(FrameSpring(j1, M1, j2, M2, sp.stiffness, sp.rest_length, sp.name))
    model.damping[:] = damping
    model.friction[:] = friction
    live_springs = any(sp.stiffness > 0.0 for sp in frame_springs)
    if not (np.any(stiffness) or np.any(damping) or np.any(friction) or live_springs):
        return None  # nothing passive (PassiveForces.empty), without building the solver
    forces = PassiveForces(
        model,
        stiffness=stiffness,
        rest=q_rest,
        damping=damping,
        friction=friction,
        smoothing=FRICTION_SMOOTHING,
        springs=frame_springs,
    )
    return None if forces.empty else forces


def with_passive(
    robot: Robot,
    joints: Sequence[PassiveSpec] = (),
    springs: Sequence[SpringSpec] = (),
    keep: bool = True,
) -> Robot:
    """A copy of ``robot`` with other passive elements (same joints, closures and home).

    Args:
        robot: The robot (unchanged).
        joints: Per-joint passive elements; a joint named here replaces the robot's own entry
            for that joint.
        springs: Two-frame springs; a spring of the same name replaces the robot's own.
        keep: Keep the robot's other passive elements (``False``: only those given here).

    Returns:
        The copy, its description and ``passive`` updated (``model.damping`` and
        ``model.friction`` of its own model copy too).

    Raises:
        DescriptionError: As for a description (the joint or spring and field at fault).

    """
    desc = robot.description
    new_joints = {p.joint: p for p in joints}
    new_springs = {s.name: s for s in springs}
    old_j = [p for p in desc.passive if p.joint not in new_joints] if keep else []
    old_s = [s for s in desc.springs if s.name not in new_springs] if keep else []
    desc = dataclasses.replace(
        desc,
        passive=tuple(old_j) + tuple(new_joints.values()),
        springs=tuple(old_s) + tuple(new_springs.values()),
    )
    model = pin.Model(robot.model)
    forces = passive_forces(
        model, desc.passive, desc.springs, robot.source, desc.joint_names, desc.joints
    )
    return dataclasses.replace(
        robot, model=model, data=model.createData(), description=desc, passive=forces
    )


def _body_of(model: pin.Model, joint: int) -> str:
    """Name of the link a joint carries (its first body frame; the root link for joint 0)."""
    for f in model.frames:
        if f.parentJoint == joint and f.type == pin.FrameType.BODY:
            return str(f.name)
    return str(model.names[joint])


def passive_summary(robot: Robot) -> dict[str, list[dict[str, Any]]]:
    """The robot's passive elements as they enter the physics, JSON-ready.

    Args:
        robot: The robot.

    Returns:
        ``{"joints": [...], "springs": [...]}``: per joint with any element, its non-zero
        ``stiffness``, ``rest`` (displacement from the joint's zero configuration), ``damping``,
        ``friction`` and ``armature`` (``model.armature``, reflected rotor inertia [kg m^2 or
        kg]) per degree of freedom; per two-frame spring its ``name``, the two links,
        ``stiffness`` [N/m], ``rest_length`` [m] and ``length`` / ``tension`` at ``q_home``.

    """
    P = robot.passive
    out: dict[str, list[dict[str, Any]]] = {"joints": [], "springs": []}
    model = robot.model
    if P is None and not np.any(model.armature):
        return out
    zero = np.zeros(model.nv)
    rest = pin.neutral(model) if P is None else P.rest
    deviation_at_rest = pin.difference(model, pin.neutral(model), rest)
    for j in range(1, model.njoints):
        jm = model.joints[j]
        iv = slice(jm.idx_v, jm.idx_v + jm.nv)
        entry: dict[str, Any] = {"joint": str(model.names[j])}
        for name, values in (
            ("stiffness", (zero if P is None else P.stiffness)[iv]),
            ("damping", (zero if P is None else P.damping)[iv]),
            ("friction", (zero if P is None else P.friction)[iv]),
            ("armature", model.armature[iv]),
        ):
            if np.any(values):
                entry[name] = [float(x) for x in values]
        if "stiffness" in entry:
            entry["rest"] = [float(x) for x in deviation_at_rest[iv]]
        if len(entry) > 1:
            out["joints"].append(entry)
    if P is None:
        return out
    for s, (length, tension) in zip(P.springs, P.spring_state(robot.q_home), strict=True):
        out["springs"].append(
            {
                "name": s.name,
                "link1": _body_of(model, s.joint1),
                "link2": _body_of(model, s.joint2),
                "stiffness": float(s.stiffness),
                "rest_length": float(s.rest_length),
                "length": float(length),
                "tension": float(tension),
            }
        )
    return out
