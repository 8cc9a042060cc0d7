"""Dynamic truth for identification tests: perturbed robots and their efforts from MuJoCo.

The truth's efforts come from MuJoCo (``mj_inverse`` on the exported model, projected onto the
actuators through MuJoCo's own closure Jacobian, :func:`pkdyn.model.formats.mjcf.
actuator_efforts`), the internal mobilities of the truth (a Delta's bar spin) following its own
dynamics; the motor friction is added by the drive model.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin

from pkdyn.dynamics.actuation import drives, with_drives
from pkdyn.identification.motion import MotionSampler
from pkdyn.model.formats.mjcf import MjcfOptions, StateMap, actuator_efforts, mujoco_model
from solvers import numerics


def perturbed(robot, rng):
    """Masses and rotational inertias scaled by 10-30 %, drives added."""
    model = pin.Model(robot.model)
    for j in range(1, model.njoints):
        I = model.inertias[j]
        if I.mass <= 0.0:
            continue
        s_m, s_i = (1.0 + rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 0.3) for _ in range(2))
        model.inertias[j] = pin.Inertia(I.mass * s_m, I.lever, I.inertia * s_i)
    truth = dataclasses.replace(robot, model=model, data=model.createData())
    n = len(robot.actuators)
    return with_drives(
        truth,
        rotor_inertia=rng.uniform(0.5e-5, 2e-5, n),
        viscous=rng.uniform(1e-4, 5e-4, n),
        coulomb=rng.uniform(0.01, 0.03, n),
    )


def multisine(robot, samples, dt, amp, seed, harmonics=5, f0=0.25, center=None):
    rng = np.random.default_rng(seed)
    t = np.arange(samples) * dt
    n = len(robot.actuators)
    mid = robot.q_home[robot.actuated_q] if center is None else center
    qa = np.tile(mid, (t.size, 1))
    qd, qdd = np.zeros_like(qa), np.zeros_like(qa)
    for h in range(1, harmonics + 1):
        w = 2 * np.pi * f0 * h
        A, B = amp * rng.uniform(-1, 1, n) / h, amp * rng.uniform(-1, 1, n) / h
        s, c = np.sin(w * t[:, None]), np.cos(w * t[:, None])
        qa += A * s + B * (c - 1)
        qd += w * (A * c - B * s)
        qdd += -w * w * (A * s + B * c)
    return t, qa, qd, qdd


def mujoco_efforts(truth, t, qa, qd, qdd):
    """Joint-side measured efforts (reduction x motor torque) of the truth, from MuJoCo."""
    sampler = MotionSampler(truth)
    mjm = mujoco_model(truth, MjcfOptions(contacts=False, visual=False, collision=False))
    import mujoco

    mjd = mujoco.MjData(mjm)
    smap = StateMap(truth)
    m, d = truth.model, truth.model.createData()
    n_a = len(truth.actuators)
    S = np.zeros((n_a, truth.nv))
    S[np.arange(n_a), truth.actuated_v] = 1.0
    N = np.array([a.reduction for a in truth.actuators])
    tau = np.empty_like(qa)
    for s in range(0, t.size, 256):
        e = min(t.size, s + 256)
        b = sampler.batch(t[s:e], qa[s:e], qd[s:e], qdd[s:e], s)
        for i in range(e - s):
            q, v, a = b.q[i], b.v[i], b.a[i].copy()
            Nm = numerics.null_space(np.vstack([b.J[i], S]), 1e-9, 1.0)
            if Nm.shape[1]:  # the truth's internal mobilities follow its own dynamics
                M = pin.crba(m, d, q)
                M = np.triu(M) + np.triu(M, 1).T
                a -= Nm @ np.linalg.solve(Nm.T @ M @ Nm, Nm.T @ pin.rnea(m, d, q, v, a))
            mjd.qpos[:] = smap.qpos(q)
            mjd.qvel[:] = smap.qvel(q, v)
            mjd.qacc[:] = smap.qacc(q, v, a)
            mujoco.mj_inverse(mjm, mjd)
            tau[s + i] = N * actuator_efforts(mjm, mjd)  # joint side, rotor inertia included
    return N * drives(truth).motor_effort(tau, qd)  # + motor friction, unit efficiency
