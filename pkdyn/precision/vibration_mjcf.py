"""The elastic model as a MuJoCo model: servos, springs, dampers; and its run along a command.

:func:`elastic_mjcf` writes the MJCF export (:func:`pkdyn.model.formats.mjcf.to_mjcf`) of the
elastic model's robot (payload included) with

- each actuator a **position servo**: a ``position`` actuator of gain ``kp = k`` (its control the
  commanded joint coordinate), a ``velocity`` actuator of gain ``kv = c`` (its control the
  commanded rate: the damping acts on the error rate) and a ``motor`` for the feedforward, all
  on the joint side (gear 1), without control or force limits;
- the robot's joint springs and dampers as MuJoCo joint ``stiffness``, ``springref`` and
  ``damping`` (the export's own mapping), the servos' damping excepted;
- a site ``vibration/point`` at the reference point on the platform's body;
- each compliant link's virtual spring (a free joint inside the tree in pkdyn's model:
  :mod:`pkdyn.precision.elastic`) as **six joints in one body** at the link's elastic centre
  (the beam's mid-span, where its compliance is diagonal): slides along the spring frame's
  ``x``, ``y``, ``z``, then hinges about them (MuJoCo applies a body's joints in order), each
  with the spring's stiffness and damping on its axis (:func:`six_joint_robot`). At the
  undeformed pose both models have the same coordinates' tangent (the tip's velocity and
  angular velocity in the spring frame), hence the same stiffness and mass matrices: the
  tests check the exported model's static compliance and natural frequencies, computed from
  MuJoCo's own Jacobians and mass matrix, against :func:`pkdyn.precision.stiffness` and
  :func:`pkdyn.precision.modes.modes`. Away from it they differ at second order (pkdyn's
  spring acts on the tip's ``log6`` displacement, MuJoCo's on the translations and the three
  successive angles), which a vibration of micrometres does not see.

:func:`simulate_mujoco` runs it along a command (MuJoCo's own integrator and soft equality
constraints for the closures, made stiff for the time step), from the same static equilibrium
as the multibody method, and returns the reference point's deviation: an independent engine for
the checks of :mod:`pkdyn.precision.vibration`.

"""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.formats.mjcf import MjcfOptions, to_mjcf
from pkdyn.model.formats.mjcf_state import StateMap
from pkdyn.model.robot import Robot
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.vibration_command import Command, Hermite5
from pkdyn.precision.vibration_figures import Figures, figures
from solvers import ConstraintSet, PassiveForces

__all__ = [
    "INTEGRATORS",
    "POINT_SITE",
    "MujocoRun",
    "elastic_mjcf",
    "mujoco_figures",
    "simulate_mujoco",
    "six_joint_q",
    "six_joint_robot",
    "six_joint_v",
]

POINT_SITE = "vibration/point"
"""Name of the site at the reference point."""


INTEGRATORS = ("RK4", "implicitfast", "implicit", "Euler")
"""MuJoCo's integrators :func:`mujoco_figures` takes."""

_DENSE_NV = 150
"""Largest model (velocity coordinates) exported with MuJoCo's dense constraint Jacobian."""


def _num(x: float) -> str:
    text = repr(float(x))
    return text[:-2] if text.endswith(".0") else text


def elastic_mjcf(
    em: ElasticModel,
    servo_damping: np.ndarray,
    point: np.ndarray | None = None,
    options: MjcfOptions | None = None,
    damping: np.ndarray | None = None,
) -> str:
    """MJCF text of the elastic model with its servos (see the module docstring).

    Args:
        em: The elastic model (its robot carries the payload).
        servo_damping: Servo damping per actuator (n_a,) [N m s/rad or N s/m].
        point: Reference point, platform frame [m] (default: its origin).
        options: Export options (default: 0.1 ms steps, RK4, no contacts, no geometry).
        damping: Viscous damping per extended velocity coordinate (nv_ext,) [SI] of the links'
            virtual springs (their entries only are read; default: none).

    Returns:
        The MJCF document.

    Raises:
        InvalidInputError: A rigid (infinite) actuator, or a damping of the wrong size.

    """
    k = np.asarray(em.actuator_stiffness, dtype=float)
    if not np.all(np.isfinite(k)):
        raise InvalidInputError("actuator_stiffness", "a servo needs a finite stiffness")
    c = np.asarray(servo_damping, dtype=float)
    if c.shape != k.shape or not np.all(np.isfinite(c)) or np.any(c < 0.0):
        raise InvalidInputError(
            "servo_damping", f"one finite coefficient >= 0 per actuator ({k.size})"
        )
    r = six_joint_robot(em, damping)
    opt = options or MjcfOptions(
        timestep=1e-4, integrator="RK4", contacts=False, visual=False, collision=False
    )
    root = ET.fromstring(to_mjcf(r, opt))
    option = root.find("option")
    if option is not None and r.nv <= _DENSE_NV:
        option.set("jacobian", "dense")  # (faster than MuJoCo's sparse choice at this size)
    for old in root.findall("actuator"):
        root.remove(old)
    act = ET.SubElement(root, "actuator")
    for a, ki, ci in zip(r.actuators, k, c, strict=True):
        ET.SubElement(act, "position", name=f"{a.name}/servo", joint=a.joint, kp=_num(ki))
        ET.SubElement(act, "velocity", name=f"{a.name}/damper", joint=a.joint, kv=_num(ci))
        ET.SubElement(act, "motor", name=f"{a.name}/feedforward", joint=a.joint, gear="1")
    fid = r.platform_frame
    assert fid is not None
    f = r.model.frames[fid]
    body_name = StateMap(r).body_names[f.parentJoint]
    p = np.zeros(3) if point is None else np.asarray(point, dtype=float)
    pos = f.placement.translation + f.placement.rotation @ p
    for body in root.iter("body"):
        if body.get("name") == body_name:
            site = ET.Element("site", name=POINT_SITE, pos=" ".join(_num(x) for x in pos))
            body.insert(0, site)
            break
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"


@dataclass(eq=False)  # numpy fields
class MujocoRun:
    """The reference point's deviation in a MuJoCo run.

    Attributes:
        t: Times (M,) [s].
        deviation: Actual minus commanded position (M, 3) [m], world axes.
        steps: MuJoCo steps taken.

    """

    t: np.ndarray
    deviation: np.ndarray
    steps: int


def simulate_mujoco(
    em: ElasticModel,
    cmd: Command,
    servo_damping: np.ndarray,
    q0: np.ndarray,
    point: np.ndarray,
    rest: float,
    timestep: float = 1e-4,
    record: float = 2.5e-4,
    options: MjcfOptions | None = None,
    damping: np.ndarray | None = None,
) -> MujocoRun:
    """Run the elastic model in MuJoCo along ``cmd`` (see the module docstring).

    Args:
        em: The elastic model (its robot carries the payload).
        cmd: The command.
        servo_damping: Servo damping per actuator (n_a,).
        q0: Initial extended configuration (the static equilibrium of the start pose).
        point: Reference point, platform frame [m].
        rest: Time simulated after the motion [s].
        timestep: MuJoCo's step [s].
        record: Recording period [s] (a multiple of ``timestep``).
        options: Export options (default: ``timestep``, RK4, no contacts, no geometry).
        damping: Viscous damping of the links' virtual springs per extended velocity
            coordinate (nv_ext,) [SI] (default: none).

    Returns:
        The deviation at the recorded times.

    Raises:
        ImportError: MuJoCo is not installed.

    """
    try:
        import mujoco
    except ImportError as err:  # an optional dependency of the core
        raise ImportError("MuJoCo is not installed: pip install mujoco") from err
    opt = options or MjcfOptions(
        timestep=timestep, integrator="RK4", contacts=False, visual=False, collision=False
    )
    r = six_joint_robot(em, damping)
    model = mujoco.MjModel.from_xml_string(elastic_mjcf(em, servo_damping, point, opt, damping))
    data = mujoco.MjData(model)
    smap = StateMap(r)
    q6 = six_joint_q(em, q0)
    data.qpos[:] = smap.qpos(q6)
    data.qvel[:] = smap.qvel(q6, six_joint_v(em, q0, cmd.v[0]))
    act = cmd.actuators()
    from scipy.interpolate import CubicSpline

    ff = CubicSpline(cmd.t, cmd.tau_ff, axis=0)
    # commanded reference point
    from pkdyn.precision.vibration_multibody import platform_motion

    p, pd, pdd, _, _, _ = platform_motion(cmd.loaded, cmd.joint.q, cmd.joint.v, cmd.joint.a, point)
    target = Hermite5(cmd.t, p, pd, pdd)
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, POINT_SITE)
    n_a = len(em.robot.actuators)
    T = cmd.duration
    h = model.opt.timestep
    # the controls held over a step: their value at its middle for RK4; at its start for the
    # Euler-type integrators, whose new velocity (used for the new position) stands for the
    # middle of the step and the force it comes from for its start (symplectic Euler)
    lead = 0.5 if int(model.opt.integrator) == int(mujoco.mjtIntegrator.mjINT_RK4) else 0.0
    every = max(1, int(round(record / h)))
    steps = int(np.ceil((T + rest) / h))
    tm = h * (np.arange(steps) + lead)  # (controls of every step, at once)
    ctrl = np.empty((steps, 3 * n_a))
    qa, qad, _ = act(tm)
    ctrl[:, 0::3], ctrl[:, 1::3] = qa, qad
    ctrl[:, 2::3] = ff(np.minimum(tm, T))
    times, at = [], []
    for i in range(steps + 1):
        if i % every == 0:
            mujoco.mj_kinematics(model, data)
            times.append(i * h)
            at.append(np.array(data.site_xpos[site]))
        if i == steps:
            break
        data.ctrl[:] = ctrl[i]
        mujoco.mj_step(model, data)
    tt = np.array(times)
    dev = np.array(at) - target(tt)[0]
    return MujocoRun(tt, dev, steps)


def mujoco_figures(
    st: Any,
    cmd: Command,
    result: Any,
    timestep: float = 4e-5,
    integrator: str = "implicitfast",
    record: float = 2.4e-4,
) -> tuple[MujocoRun, Figures]:
    """MuJoCo's run of an analysis and its figures, to compare with the analysis's own.

    The elastic model of the set-up (payload included) exported with its servos' damping and
    its links' damping, run along ``cmd`` from the multibody method's start (the nonlinear
    static equilibrium of the first pose) for the time the analysis observes after the
    motion; the figures are read as the analysis's, about its static deflection.

    Args:
        st: The analysis's set-up (:func:`pkdyn.precision.vibration.prepare`).
        cmd: Its command.
        result: Its result (:class:`~pkdyn.precision.vibration_result.VibrationResult`).
        timestep: MuJoCo's step [s] (RK4: stable below about 2.8 / omega_max and the
            overdamped modes' rates; the Euler-type integrators, implicit in the dampers:
            below 2 / omega_max).
        integrator: ``RK4``, ``implicitfast``, ``implicit`` or ``Euler``.
        record: Recording period [s].

    Returns:
        The run and its figures (translation of the reference point).

    Raises:
        ImportError: MuJoCo is not installed.

    """
    from pkdyn.precision.vibration_multibody import equilibrium

    if integrator not in INTEGRATORS:
        raise InvalidInputError(
            "integrator", f"unknown {integrator!r} (one of {', '.join(INTEGRATORS)})"
        )
    em = st.elastic
    links = np.array(st.c, dtype=float)
    if em.robot.passive is not None:
        links -= np.asarray(em.robot.passive.damping)  # (the export writes the robot's own)
    links[np.asarray(em.robot.actuated_v)] = 0.0  # (the servos' is the velocity actuators')
    q0 = equilibrium(em, cmd.q[0], cmd.tau_ff[0], st.point)
    opts = MjcfOptions(
        timestep=timestep, integrator=integrator, contacts=False, visual=False, collision=False
    )
    run = simulate_mujoco(
        em, cmd, st.damping.actuator, q0, st.point, st.rest, timestep, record, opts, links
    )
    static = np.zeros(3)
    for i, c in enumerate(result.task):
        if c in ("x", "y", "z"):
            static["xyz".index(c)] = result.static_deflection[i]
    rate = np.gradient(run.deviation, run.t, axis=0)
    fig = figures(
        run.t, run.deviation, rate, static, cmd.duration, st.dwell, st.band, st.rest
    )  # fmt: skip
    return run, fig


_AXES = (pin.JointModelPX, pin.JointModelPY, pin.JointModelPZ)
_HINGES = (pin.JointModelRX, pin.JointModelRY, pin.JointModelRZ)


def _virtual(em: ElasticModel) -> list[int]:
    """Joint ids of the links' virtual springs in the elastic model's robot."""
    model = em.robot.model
    first = {int(row[0]) for row in np.asarray(em.deflection_v)}
    return [
        j for j in range(1, model.njoints) if model.joints[j].nv == 6 and model.idx_vs[j] in first
    ]


def _six() -> pin.JointModel:
    jm = pin.JointModelComposite(_AXES[0]())
    for make in (*_AXES[1:], *_HINGES):
        jm.addJoint(make())
    return jm


def six_joint_robot(em: ElasticModel, damping: np.ndarray | None = None) -> Robot:
    """The elastic model's robot with each virtual spring as six joints (module docstring).

    Each compliant link's free joint becomes a composite of three prismatic (``x``, ``y``,
    ``z``) and three revolute joints (about ``x``, ``y``, ``z``) at the same place, holding the
    same body; its six velocity coordinates keep their indices (their configuration is the
    translation and the successive angles, ``M = T(p) Rx(a) Ry(b) Rz(c)``), the spring's
    stiffness and ``damping`` on them. The robot itself when no link is compliant.

    Args:
        em: The elastic model.
        damping: Viscous damping per extended velocity coordinate (nv_ext,) [SI]; the virtual
            springs' entries become the joints' damping (default: none).

    Returns:
        A robot for the MJCF export (its ``passive`` and ``model.damping`` as described).

    Raises:
        InvalidInputError: A damping of the wrong size, or a virtual spring whose tip part has
            no mass (MuJoCo needs one on every moving body).

    """
    r = em.robot
    if not em.links:
        return r
    model = r.model
    virtual = set(_virtual(em))
    for j in sorted(virtual):
        if model.inertias[j].mass <= 0.0:
            first = [int(row[0]) for row in np.asarray(em.deflection_v)]
            link = em.links[first.index(int(model.idx_vs[j]))].link
            raise InvalidInputError(
                "links",
                f"link '{link}': the part past its virtual spring carries no mass of its own "
                "(its inertia could not be split at the spring), and MuJoCo needs a mass on "
                "every moving body; describe the link's mass as its material's "
                '(mass="from-material") or keep it rigid to export the elastic model',
            )
    new = pin.Model()
    new.name = model.name
    new.gravity = model.gravity
    for j in range(1, model.njoints):
        jm = model.joints[j]
        sv = slice(jm.idx_v, jm.idx_v + jm.nv)
        if j in virtual:
            joint, lo, hi = _six(), np.full(6, -np.inf), np.full(6, np.inf)
        else:
            sq = slice(jm.idx_q, jm.idx_q + jm.nq)
            joint, lo, hi = jm, model.lowerPositionLimit[sq], model.upperPositionLimit[sq]
        nid = new.addJoint(
            int(model.parents[j]), joint, model.jointPlacements[j], model.names[j],
            model.effortLimit[sv], model.velocityLimit[sv], lo, hi,
        )  # fmt: skip
        new.appendBodyToJoint(nid, model.inertias[j], pin.SE3.Identity())
    for name in ("armature", "damping", "friction", "rotorInertia", "rotorGearRatio"):
        setattr(new, name, np.array(getattr(model, name)))
    if damping is not None:
        c = np.asarray(damping, dtype=float)
        if c.shape != (model.nv,):
            raise InvalidInputError(
                "damping", f"one coefficient per extended velocity coordinate ({model.nv})"
            )
        values = np.array(new.damping)
        d = np.asarray(em.deflection_v).ravel()
        values[d] = c[d]
        new.damping = values
    for fid, f in enumerate(model.frames):
        if fid:
            new.addFrame(
                pin.Frame(f.name, f.parentJoint, f.parentFrame, f.placement, f.type, f.inertia),
                False,
            )
    cms = pin.StdVec_RigidConstraintModel()
    for cm in r.constraint_models:
        c6 = pin.RigidConstraintModel(
            cm.type, new, cm.joint1_id, cm.joint1_placement, cm.joint2_id, cm.joint2_placement,
            cm.reference_frame,
        )  # fmt: skip
        c6.name = cm.name
        cms.append(c6)
    cs = r.constraints
    reduce = cs.closure_rows.reduce if cs.closure_rows is not None else True
    P = r.passive
    passive = None
    if P is not None:
        passive = PassiveForces(
            new,
            stiffness=P.stiffness,
            rest=six_joint_q(em, P.rest),
            damping=P.damping,
            friction=P.friction,
            smoothing=P.smoothing,
            springs=list(P.springs),
        )
    iq = np.array([new.joints[int(j)].idx_q for j in r.actuated_joints], dtype=int)
    return dataclasses.replace(
        r,
        model=new,
        data=new.createData(),
        constraint_models=cms,
        constraints=ConstraintSet(
            new, list(cs.closure_specs), list(cs.coupling_specs), reduce=reduce
        ),
        actuated_q=iq,
        q_home=six_joint_q(em, r.q_home),
        passive=passive,
    )


def _angles(R: np.ndarray) -> np.ndarray:
    """``(a, b, c)`` with ``R = Rx(a) Ry(b) Rz(c)`` [rad]."""
    b = math.asin(max(-1.0, min(1.0, float(R[0, 2]))))
    return np.array([math.atan2(-R[1, 2], R[2, 2]), b, math.atan2(-R[0, 1], R[0, 0])])


def _rates(abc: np.ndarray) -> np.ndarray:
    """``E`` (3, 3) with the angular velocity in the moved frame ``omega = E (a', b', c')``."""
    _, b, c = abc
    Rz_T = pin.rpy.rpyToMatrix(0.0, 0.0, -c)
    Ry_T = pin.rpy.rpyToMatrix(0.0, -b, 0.0)
    e = np.eye(3)
    return np.column_stack([Rz_T @ Ry_T @ e[0], Rz_T @ e[1], e[2]])


def six_joint_q(em: ElasticModel, q: np.ndarray) -> np.ndarray:
    """The configuration of :func:`six_joint_robot` (nq_6,) of an extended one (nq_ext,)."""
    if not em.links:
        return np.array(q, dtype=float)
    model = em.robot.model
    virtual = set(_virtual(em))
    out = []
    for j in range(1, model.njoints):
        jm = model.joints[j]
        x = np.asarray(q[jm.idx_q : jm.idx_q + jm.nq], dtype=float)
        if j in virtual:
            M = pin.XYZQUATToSE3(x)
            x = np.concatenate([M.translation, _angles(M.rotation)])
        out.append(x)
    return np.concatenate(out) if out else np.zeros(0)


def six_joint_v(em: ElasticModel, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The velocity of :func:`six_joint_robot` (nv,) of an extended state ``(q, v)``.

    A free joint's velocity is its tip's, in the tip frame: ``(R^T p', omega)``; the six
    joints' rates are ``p' = R v_lin`` and the angles' rates ``E^-1 omega``.
    """
    out = np.array(v, dtype=float)
    if not em.links:
        return out
    model = em.robot.model
    for j in _virtual(em):
        jm = model.joints[j]
        M = pin.XYZQUATToSE3(np.asarray(q[jm.idx_q : jm.idx_q + 7], dtype=float))
        i = jm.idx_v
        abc = _angles(M.rotation)
        out[i : i + 3] = M.rotation @ v[i : i + 3]
        out[i + 3 : i + 6] = np.linalg.solve(_rates(abc), v[i + 3 : i + 6])
    return out
