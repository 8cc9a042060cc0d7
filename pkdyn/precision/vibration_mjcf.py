"""The elastic model as a MuJoCo model: servos, springs, dampers; and its run along a command.

:func:`elastic_mjcf` writes the MJCF export (:func:`pkdyn.model.formats.mjcf.to_mjcf`) of the
elastic model's robot (payload included) with

- each actuator a **position servo**: a ``position`` actuator of gain ``kp = k`` (its control the
  commanded joint coordinate), a ``velocity`` actuator of gain ``kv = c`` (its control the
  commanded rate: the damping acts on the error rate) and a ``motor`` for the feedforward, all
  on the joint side (gear 1), without control or force limits;
- the robot's joint springs and dampers as MuJoCo joint ``stiffness``, ``springref`` and
  ``damping`` (the export's own mapping), the servos' damping excepted;
- a site ``vibration/point`` at the reference point on the platform's body.

:func:`simulate_mujoco` runs it along a command (MuJoCo's own integrator and soft equality
constraints for the closures, made stiff for the time step), from the same static equilibrium
as the multibody method, and returns the reference point's deviation: an independent engine for
the checks of :mod:`pkdyn.precision.vibration`.

Compliant links (the free virtual joints inside the tree) are not exported yet: MuJoCo's free
joints hang on the world only; the export refuses them.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.formats.mjcf import MjcfOptions, to_mjcf
from pkdyn.model.formats.mjcf_state import StateMap
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.vibration_command import Command, Hermite5

__all__ = ["POINT_SITE", "MujocoRun", "elastic_mjcf", "simulate_mujoco"]

POINT_SITE = "vibration/point"
"""Name of the site at the reference point."""


def _num(x: float) -> str:
    text = repr(float(x))
    return text[:-2] if text.endswith(".0") else text


def elastic_mjcf(
    em: ElasticModel,
    servo_damping: np.ndarray,
    point: np.ndarray | None = None,
    options: MjcfOptions | None = None,
) -> str:
    """MJCF text of the elastic model with its servos (see the module docstring).

    Args:
        em: The elastic model (its robot carries the payload).
        servo_damping: Servo damping per actuator (n_a,) [N m s/rad or N s/m].
        point: Reference point, platform frame [m] (default: its origin).
        options: Export options (default: 0.1 ms steps, RK4, no contacts, no geometry).

    Returns:
        The MJCF document.

    Raises:
        InvalidInputError: Compliant links (not exported yet), or a rigid (infinite) actuator.

    """
    if em.links:
        raise InvalidInputError(
            "links",
            "the MJCF export of the elastic model takes rigid links only (a compliant link's "
            "virtual free joint cannot hang inside a MuJoCo tree yet)",
        )
    k = np.asarray(em.actuator_stiffness, dtype=float)
    if not np.all(np.isfinite(k)):
        raise InvalidInputError("actuator_stiffness", "a servo needs a finite stiffness")
    r = em.robot
    opt = options or MjcfOptions(
        timestep=1e-4, integrator="RK4", contacts=False, visual=False, collision=False
    )
    root = ET.fromstring(to_mjcf(r, opt))
    for old in root.findall("actuator"):
        root.remove(old)
    act = ET.SubElement(root, "actuator")
    c = np.asarray(servo_damping, dtype=float)
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
    r = em.robot
    model = mujoco.MjModel.from_xml_string(elastic_mjcf(em, servo_damping, point, opt))
    data = mujoco.MjData(model)
    smap = StateMap(r)
    data.qpos[:] = smap.qpos(q0)
    data.qvel[:] = smap.qvel(q0, cmd.v[0])
    act = cmd.actuators()
    from scipy.interpolate import CubicSpline

    ff = CubicSpline(cmd.t, cmd.tau_ff, axis=0)
    # commanded reference point
    from pkdyn.precision.vibration_multibody import platform_motion

    p, pd, pdd, _, _, _ = platform_motion(cmd.loaded, cmd.joint.q, cmd.joint.v, cmd.joint.a, point)
    target = Hermite5(cmd.t, p, pd, pdd)
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, POINT_SITE)
    n_a = len(r.actuators)
    T = cmd.duration
    h = model.opt.timestep
    every = max(1, int(round(record / h)))
    steps = int(np.ceil((T + rest) / h))
    times, dev = [], []
    for i in range(steps + 1):
        t = i * h
        if i % every == 0:
            mujoco.mj_forward(model, data)
            times.append(t)
            dev.append(np.array(data.site_xpos[site]) - target(t)[0])
        if i == steps:
            break
        tm = t + 0.5 * h  # controls are held over a step: their value at its middle
        qa, qad, _ = act(tm)
        data.ctrl[0 : 3 * n_a : 3] = qa
        data.ctrl[1 : 3 * n_a : 3] = qad
        data.ctrl[2 : 3 * n_a : 3] = ff(min(tm, T))
        mujoco.mj_step(model, data)
    return MujocoRun(np.array(times), np.array(dev), steps)
