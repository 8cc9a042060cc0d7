"""pkdyn against MuJoCo on the exported models (``pkdyn.model.formats.mjcf``), per library robot.

- Forward step: pkdyn's Euler step (one constrained-dynamics evaluation, Baumgarte) against
  ``mj_step`` (``implicitfast``, soft closures, contacts off), both at 1 ms.
- Inverse dynamics, one sample: ``InverseDynamics.solve`` against ``mj_inverse`` plus the
  projection onto the actuators (``pkdyn.model.formats.mjcf.actuator_efforts``: least squares on
  ``[moment^T J_eq^T]``).
- Agreement at random consistent states: forward accelerations (MuJoCo at the stiffest
  impedances, extrapolated to hard closures) and actuator efforts, relative errors.

(Named ``vs_mujoco`` so that it does not shadow the ``mujoco`` package.)
Run ``python bench/vs_mujoco.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import mujoco
import numpy as np
from timing import ROBOTS, Row, consistent_state, paired, print_table, us

import pkdyn
from pkdyn.model.formats.mjcf import MjcfOptions, StateMap, actuator_efforts, mujoco_model
from solvers import Actuation, ForwardDynamics, InverseDynamics

IMPEDANCES = (0.9999, 0.9998, 0.9996)


def _agreement(robot, model, smap, act, fd0, inv, states) -> tuple[float, float, float]:
    """Worst relative errors: soft FD, extrapolated FD, ID."""
    data = mujoco.MjData(model)
    eps = np.array([(1.0 - d) / d for d in IMPEDANCES])
    worst = np.zeros(3)
    for q, v, tau in states:
        a = fd0.acceleration(q, v, act.generalized(tau, robot.nv))
        soft = []
        for d in IMPEDANCES:
            model.eq_solimp[:, :3] = d, d, 0.001
            data.qpos[:] = smap.qpos(q)
            data.qvel[:] = smap.qvel(q, v)
            data.ctrl[:] = tau
            mujoco.mj_forward(model, data)
            soft.append(smap.a(q, v, data.qacc))
        hard = np.linalg.solve(np.vander(eps, 3, increasing=True), np.array(soft))[0]
        data.qacc[:] = smap.qacc(q, v, a)
        mujoco.mj_inverse(model, data)
        t_mj = actuator_efforts(model, data)
        t_pk = inv.solve(q, v, a).tau
        scale = np.linalg.norm(a)
        errs = (
            np.linalg.norm(soft[0] - a) / scale,
            np.linalg.norm(hard - a) / scale,
            np.linalg.norm(t_mj - t_pk) / np.linalg.norm(t_pk),
        )
        worst = np.maximum(worst, errs)
    model.eq_solimp[:, :3] = 0.99, 0.9999, 0.001
    return float(worst[0]), float(worst[1]), float(worst[2])


def robot_rows(name: str, n: int = 1000) -> list[Row]:
    robot = pkdyn.load(name, geometry=False)
    smap = StateMap(robot)
    model = mujoco_model(robot, MjcfOptions(contacts=False))
    model.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    data = mujoco.MjData(model)
    red = np.array([a.reduction for a in robot.actuators])
    act = Actuation(robot.actuated_v, gains=red, names=robot.actuator_names)
    q, v = consistent_state(robot)
    tau0 = np.zeros(act.n)

    def torque(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return tau0

    fd = ForwardDynamics(
        robot.model, robot.constraint_models, act, integrator="euler", project=False
    )
    data.qpos[:] = smap.qpos(q)
    data.qvel[:] = smap.qvel(q, v)
    qpos, qvel = data.qpos.copy(), data.qvel.copy()

    def mj_step() -> None:
        data.qpos[:] = qpos
        data.qvel[:] = qvel
        mujoco.mj_step(model, data)

    t_pk, t_mj, ratio = paired(lambda: fd.step(0.0, q, v, 1e-3, torque), mj_step, n)
    rows: list[Row] = [
        (
            f"{name}: forward step (1 ms), pkdyn `euler` vs MuJoCo `mj_step`",
            f"{us(t_pk)} vs {us(t_mj)}: {ratio:.2f}x",
            "-",
        )
    ]
    fd0 = ForwardDynamics(robot.model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    a = fd0.acceleration(q, v, act.generalized(np.ones(act.n), robot.nv))
    inv = InverseDynamics(robot.model, robot.constraint_models, act)
    qacc = smap.qacc(q, v, a)

    def mj_inverse() -> np.ndarray:
        data.qpos[:] = qpos
        data.qvel[:] = qvel
        data.qacc[:] = qacc
        mujoco.mj_inverse(model, data)
        return actuator_efforts(model, data)

    t_pk, t_mj, ratio = paired(lambda: inv.solve(q, v, a), mj_inverse, max(1, n // 2))
    rows.append(
        (
            f"{name}: inverse dynamics, one sample, pkdyn vs `mj_inverse` + projection",
            f"{us(t_pk)} vs {us(t_mj)}: {ratio:.2f}x",
            "<= 1.0x",
        )
    )
    rng = np.random.default_rng(7)
    states = []
    for k in range(3):
        qk, vk = consistent_state(robot, seed=k + 1, speed=2.0)
        states.append(
            (
                qk,
                vk,
                0.5
                * rng.uniform(-1.0, 1.0, act.n)
                * np.array([x.effort for x in robot.actuators])
                / red,
            )
        )
    model.opt.tolerance = 1e-15
    model.opt.iterations = 1000
    soft, hard, idr = _agreement(robot, model, smap, act, fd0, inv, states)
    rows.append(
        (
            f"{name}: agreement with MuJoCo, 3 random states (relative)",
            f"accelerations {soft:.1e} (impedance 0.9999), {hard:.1e} (extrapolated to hard "
            f"closures); actuator efforts {idr:.1e}",
            "-",
        )
    )
    return rows


def rows() -> list[Row]:
    out: list[Row] = []
    for name in ROBOTS:
        out += robot_rows(name)
    return out


if __name__ == "__main__":
    print_table(rows())
