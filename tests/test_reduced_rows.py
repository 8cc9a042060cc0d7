"""Closures reduced to their independent rows change no effort and no reaction.

Hinges give 5 rows instead of two points' 6 (rank 5), planar loops their in-plane rows only: on
every library robot and the public models (``tests/data/public``), against the same robot with
every row (``robot.constraints.unreduced``, the rows of the former closure set):

- statics under gravity and a platform wrench: the actuator efforts, each closure's generalized
  force, and its force and moment where the statics determine them (the reactions of an
  over-constrained loop are not: only the efforts are compared there; nor the out-of-plane
  components of a planar loop's);
- inverse dynamics along a short actuator motion: the same;

to 1e-12 of the robot's effort (and reaction) scale.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from test_public_models import MODELS

import pkdyn
from pkdyn.analysis.statics import closure_reactions, static_equilibrium
from pkdyn.dynamics import inverse_dynamics
from pkdyn.dynamics.joint_motion import actuator_trajectory
from pkdyn.dynamics.trajectory import named_trajectory
from solvers import numerics

LIBRARY = ["delta", "five_bar", "planar_3rrr", "tripod", "gough_stewart", "four_bar_knee",
           "parallel_ankle"]  # fmt: skip
TOL = 1e-12


def _robot(name: str) -> pkdyn.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if name in MODELS:
            return MODELS[name][0]()
        return pkdyn.load(name, geometry=False)


@pytest.fixture(scope="module", params=LIBRARY + list(MODELS))
def pair(request):
    robot = _robot(request.param)
    full = dataclasses.replace(robot, constraints=robot.constraints.unreduced)
    return request.param, robot, full


def _compare(robot, full, q, tau_r, lam_r, tau_f, lam_f) -> None:
    """Efforts; per closure its generalized force ``J_k^T lambda_k`` (what the dynamics see of
    it, unique unless the loops are over-constrained), and its force and moment where the
    statics determine them (not a planar loop's out-of-plane components, which no equation
    involves: the set with every row reports its minimum-norm split there)."""
    scale = max(float(np.abs(tau_f).max(initial=0.0)), 1e-300)
    np.testing.assert_allclose(tau_r, tau_f, rtol=0, atol=TOL * scale)
    data = robot.model.createData()
    cs, cf = robot.constraints, full.constraints
    if not _determinate(robot, q):
        return
    Jr, Jf = cs.jacobian(data, q), cf.jacobian(data, q)
    g_r, g_f = [], []
    for name in cs.names:
        i, k = cs.names.index(name), cf.names.index(name)
        a, b = slice(cs.offsets[i], cs.offsets[i + 1]), slice(cf.offsets[k], cf.offsets[k + 1])
        g_r.append(Jr[a].T @ lam_r[a])
        g_f.append(Jf[b].T @ lam_f[b])
    g_scale = max(max(float(np.abs(g).max()) for g in g_f), scale)
    for name, x, y in zip(cs.names, g_r, g_f, strict=True):
        np.testing.assert_allclose(x, y, rtol=0, atol=TOL * g_scale, err_msg=name)
    red = closure_reactions(robot, q, lam_r)
    ref = closure_reactions(full, q, lam_f)
    f_scale = max(max(float(np.abs(r.force).max()) for r in ref.values()), scale)
    m_scale = max(max(float(np.abs(r.moment).max()) for r in ref.values()), scale)
    normals = dict(zip(cs.closures.names, cs.closure_rows.normals, strict=True))
    for name, r in ref.items():
        n = normals[name]
        if n is None:
            np.testing.assert_allclose(red[name].force, r.force, rtol=0, atol=TOL * f_scale)
            np.testing.assert_allclose(red[name].moment, r.moment, rtol=0, atol=TOL * m_scale)
        else:  # in-plane force, moment about the normal
            P = np.eye(3) - np.outer(n, n)
            np.testing.assert_allclose(P @ red[name].force, P @ r.force, rtol=0, atol=TOL * f_scale)
            assert abs(n @ (red[name].moment - r.moment)) <= TOL * m_scale


def _determinate(robot: pkdyn.Robot, q: np.ndarray) -> bool:
    """Whether efforts and constraint forces are unique at ``q`` (``[S^T Jc^T]`` of full
    column rank, the robot's reduced rows)."""
    J = robot.constraints.jacobian(robot.model.createData(), q)
    S = np.zeros((robot.nv, len(robot.actuators)))
    S[robot.actuated_v, np.arange(len(robot.actuators))] = 1.0
    K = np.hstack([S, J.T])
    return numerics.rank(K, 1e-9) == K.shape[1]


def test_statics_unchanged(pair):
    name, robot, full = pair
    if robot.constraints.closure_rows.identity:  # nothing to reduce: the same set
        assert robot.constraints.unreduced is robot.constraints
    q = robot.q_home
    rng = np.random.default_rng(0)
    F = None
    if robot.platform_frame is not None and robot.dof(q) == len(robot.task_rows):
        F = rng.uniform(-1.0, 1.0, len(robot.task_rows)) * 10.0
    try:
        ref = static_equilibrium(full, q, F, gravity=True)
    except pkdyn.PkdynError:  # no platform, or singular for it (the dynamics below cover it)
        pytest.skip(f"{name}: no platform statics at home")
    st = static_equilibrium(robot, q, F, gravity=True)
    _compare(robot, full, q, st.tau, st.lambdas, ref.tau, ref.lambdas)


def test_inverse_dynamics_unchanged(pair):
    """Along a short motion: the platform's point-to-point move (library robots with a
    platform), or an actuator motion mapped through the loops."""
    name, robot, full = pair
    if name in LIBRARY and robot.platform_frame is not None:
        traj = named_trajectory(robot, "p2p", check_limits=False)
        traj = dataclasses.replace(traj, t=traj.t[::8], q=traj.q[::8], v=traj.v[::8], a=traj.a[::8])
    else:
        T, n = 0.4, len(robot.actuators)
        t = np.linspace(0.0, T, 5)
        w = 2 * np.pi / T
        amp = 0.01 * np.ones(n)
        qa0 = robot.q_home[robot.actuated_q]
        traj = actuator_trajectory(
            robot,
            t,
            qa0 + np.outer(np.sin(w * t), amp),
            np.outer(w * np.cos(w * t), amp),
            np.outer(-(w**2) * np.sin(w * t), amp),
        )
    out = inverse_dynamics(robot, traj, progress=False)
    ref = inverse_dynamics(full, traj, progress=False)
    assert robot.constraints.n <= full.constraints.n
    assert out.constraint_forces.shape[1] == robot.constraints.n
    for k in range(traj.t.size):
        _compare(
            robot, full, traj.q[k], out.tau[k], out.constraint_forces[k], ref.tau[k],
            ref.constraint_forces[k],
        )  # fmt: skip
