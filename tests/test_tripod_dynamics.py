"""Inverse dynamics of the tripod in modes PP and BE, checked by independent physics.

- PP with the machining wrench: the wrench's share of the efforts equals ``-J^T F`` from the
  kinematic models (statics by virtual work, :mod:`pkdyn.analysis.statics`);
- BE (locks as constraints): the efforts fed to the constrained forward dynamics
  (``pin.constraintDynamics``) give back the accelerations; the actuators' power equals the rate
  of change of the mechanical energy (locks and clamps do no work);
- the joint trajectory of a swing is consistent: finite differences of ``q`` and ``v``.
"""

import math

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.statics import actuator_efforts
from pkdyn.closed_form import tripod as tripod_cf
from pkdyn.dynamics import actuation, inverse_dynamics
from pkdyn.dynamics.trajectory import map_task_trajectory
from pkdyn.library import tripod
from pkdyn.tripod import Stance, be_mode, mode_robot, pp_mode
from pkdyn.tripod.machining import MachiningPlan, machining_task, surface_pose
from pkdyn.tripod.scenario import swing_task
from solvers import ForwardDynamics

P = tripod.Params()
TOOL = pin.SE3(np.eye(3), np.array([0.0, 0.0, -P.tool_offset]))
HOME_TOOL = np.array([0.0, 0.0, P.nacelle_height - P.tool_offset, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def robot() -> pkdyn.Robot:
    return pkdyn.load("tripod", geometry=False)


@pytest.fixture(scope="module")
def swing(robot):
    """Branch 2 swinging 6 cm forward (lift 2 cm) from a tilted nacelle, sampled at 5 ms."""
    st = Stance.default(P)
    phi = tripod_cf.PHI[1]
    M = pin.SE3(pin.exp3(0.1 * np.array([-math.sin(phi), math.cos(phi), 0.0])), np.r_[0, 0, 0.6])
    pp = mode_robot(robot, st, pp_mode())
    q0 = pkdyn.inverse_geometry(pp, M * TOOL, check_limits=False).q
    be = mode_robot(robot, st, be_mode(robot, q0, 2), q0)
    f = st.footholds[1]
    end = pin.SE3(f.rotation, f.translation + np.array([0.06, 0.0, 0.0]))
    task = swing_task(f, end, 0.02, 1.0, 0.005)
    return be, map_task_trajectory(be, task, q_init=q0, check_limits=False, progress=False)


def test_machining_wrench_share_is_the_statics(robot):
    st = Stance.default(P)
    pp = mode_robot(robot, st, pp_mode())
    plan = MachiningPlan()
    rng = np.random.default_rng(0)
    for y in (-0.06, 0.0, 0.05):
        pose = surface_pose(plan, HOME_TOOL, 0.03, y, -plan.depth)
        q = pkdyn.inverse_geometry(pp, pose, check_limits=False).q
        traj = pkdyn.dynamics.trajectory.JointTrajectory(
            np.zeros(1),
            q[None],
            np.zeros((1, robot.nv)),
            np.zeros((1, robot.nv)),
            robot.actuated_q,
            robot.actuated_v,
        )
        F = np.r_[rng.uniform(-300, 300, 3), rng.uniform(-5, 5, 3)]
        with_w = inverse_dynamics(pp, traj, wrench=F, progress=False).tau[0]
        without = inverse_dynamics(pp, traj, progress=False).tau[0]
        assert np.allclose(with_w - without, actuator_efforts(pp, q, F), atol=1e-8)


def test_machining_task_follows_the_skin(robot):
    plan = MachiningPlan()
    task, W = machining_task(plan, HOME_TOOL, dt=0.02)
    assert np.allclose(task.pose[0], HOME_TOOL) and np.allclose(task.pose[-1], HOME_TOOL)
    axis_yz = np.array([0.0, HOME_TOOL[2] - plan.clearance - plan.radius])
    h = np.linalg.norm(task.pose[:, 1:3] - axis_yz, axis=1) - plan.radius
    assert h.min() == pytest.approx(-plan.depth, abs=1e-12)
    cutting = np.abs(W).sum(axis=1) > 0
    assert np.all(h[cutting] < 1e-12)  # wrench only while the tip is in the material
    # the spindle axis (platform z) stays normal to the skin: roll = -beta, beta = asin(y / R)
    R_tool = [pin.rpy.rpyToMatrix(p[3:]) for p in task.pose]
    for k in np.flatnonzero(h < 0.0):
        n = np.r_[0.0, task.pose[k, 1], task.pose[k, 2] - axis_yz[1]]
        n /= np.linalg.norm(n)
        assert np.allclose(R_tool[k][:, 2], n, atol=1e-12)
        # the thrust pushes back along the normal, the cutting torque opposes the spindle
        if cutting[k]:
            assert W[k, :3] @ n > 0.0
            assert W[k, 5] == -plan.torque
    assert cutting.sum() > 0.2 * np.sum(h < 0.0)
    # the derivatives of the samples are the sampled derivatives (central differences)
    dt = np.diff(task.t)
    fd = (task.pose[2:] - task.pose[:-2]) / (dt[1:] + dt[:-1])[:, None]
    assert np.max(np.abs(fd - task.pose_d[1:-1])) < 2e-3 * np.max(np.abs(task.pose_d))
    with pytest.raises(pkdyn.InvalidInputError):
        machining_task(plan, np.r_[HOME_TOOL[:3], 0.1, 0.0, 0.0])
    with pytest.raises(pkdyn.InvalidInputError):
        MachiningPlan(clearance=0.005)


def test_swing_trajectory_is_consistent_by_finite_differences(robot, swing):
    be, jt = swing
    dt = jt.t[1] - jt.t[0]
    for k in range(1, jt.t.size - 1, 7):
        dq = pin.difference(robot.model, jt.q[k - 1], jt.q[k + 1]) / (2 * dt)
        assert np.max(np.abs(dq - jt.v[k])) < 1e-3 * max(1.0, np.max(np.abs(jt.v)))
        dv = (jt.v[k + 1] - jt.v[k - 1]) / (2 * dt)
        assert np.max(np.abs(dv - jt.a[k])) < 2e-2 * max(1.0, np.max(np.abs(jt.a)))
        # closures, clamps and locks: J v = 0 and J a = -drift
        J = be.closure_set.jacobian(be.data, jt.q[k])
        assert np.max(np.abs(J @ jt.v[k])) < 1e-10
        gamma = be.closure_set.drift(be.data, jt.q[k], jt.v[k])
        assert np.max(np.abs(J @ jt.a[k] + gamma)) < 1e-8


def test_be_efforts_reproduce_the_motion_in_forward_dynamics(robot, swing):
    be, jt = swing
    eff = inverse_dynamics(be, jt, progress=False)
    assert np.max(eff.residual) < 1e-8
    fd = ForwardDynamics(robot.model, list(be.constraint_models), actuation(be), project=False)
    for k in range(0, jt.t.size, 20):
        a = fd.acceleration(jt.q[k], jt.v[k], fd.actuation.generalized(eff.tau[k], robot.nv))
        assert np.max(np.abs(a - jt.a[k])) < 1e-6 * max(1.0, np.max(np.abs(jt.a)))


def test_be_actuator_power_is_the_rate_of_mechanical_energy(robot, swing):
    be, jt = swing
    eff = inverse_dynamics(be, jt, progress=False)
    power = np.sum(eff.tau * jt.qa_dot, axis=1)
    E = eff.kinetic + eff.potential
    dt = jt.t[1] - jt.t[0]
    dE = (E[2:] - E[:-2]) / (2 * dt)
    scale = np.max(np.abs(power))
    assert scale > 1.0  # the swing lifts a 10 kg branch
    assert np.max(np.abs(dE - power[1:-1])) < 1e-3 * scale


def test_q6_lock_carries_the_swinging_branch_weight_moment(robot, swing):
    """At rest the lock of q6 holds the branch's weight moment about the edge P_L P_R."""
    be, jt = swing
    q = jt.q[0]
    model, data = robot.model, robot.data
    zero = np.zeros(robot.nv)
    traj = pkdyn.dynamics.trajectory.JointTrajectory(
        np.zeros(1), q[None], zero[None], zero[None], robot.actuated_q, robot.actuated_v
    )
    lam = inverse_dynamics(be, traj, progress=False).constraint_forces[0]
    cs = be.constraints  # (the rows of the inverse dynamics' constraint forces)
    k = cs.names.index("lock:branch2_q6[0]")
    rows = np.arange(cs.offsets[k], cs.offsets[k + 1])
    j6 = model.getJointId("branch2_q6")
    iv = model.joints[j6].idx_v
    torque = float(cs.jacobian(be.data, q)[rows, iv] @ lam[rows])
    # moment of the weights of the bodies beyond q6 about its axis (through P_L, along u)
    pin.forwardKinematics(model, data, q)
    axis = data.oMi[j6].rotation[:, 0]
    P_L = data.oMi[j6].translation
    g = -model.gravity.linear
    expected = 0.0
    for j in range(j6, model.njoints):
        if _below(model, j, j6):
            Y = model.inertias[j]
            c = data.oMi[j].act(Y.lever)
            expected += Y.mass * g @ np.cross(axis, c - P_L)
    assert abs(expected) > 1.0  # a real load
    assert torque == pytest.approx(expected, rel=1e-9, abs=1e-9)


def _below(model: pin.Model, j: int, ancestor: int) -> bool:
    while j > 0:
        if j == ancestor:
            return True
        j = model.parents[j]
    return False
