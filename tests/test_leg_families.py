"""The leg families: parameters, homes derived from them, committed descriptions."""

import math

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.closed_form import four_bar_knee as knee_cf
from pkdyn.closed_form import parallel_ankle as ankle_cf


@pytest.mark.parametrize(
    "params",
    [{}, {"h": 0.3, "rod": 0.3}, {"x_foot": -0.1, "e": 0.05, "z_foot": -0.02, "crank": 0.04}],
)
def test_ankle_home_is_level_for_any_geometry(params):
    robot = pkdyn.load("parallel_ankle", **params)
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    m = robot.model
    for j in ("ankle_pitch", "ankle_roll"):
        assert robot.q_home[m.joints[m.getJointId(j)].idx_q] == pytest.approx(0.0, abs=1e-12)
    assert robot.mobility() == 2
    # the rods keep their length: crank end to heel point
    theta = robot.q_home[robot.actuated_q]
    C = ankle_cf.crank_points(robot.params, theta)[0]
    P = ankle_cf.foot_points(robot.params, np.zeros(2))[0]
    np.testing.assert_allclose(np.linalg.norm(C - P, axis=1), robot.params.rod, rtol=1e-12)
    # the platform frame is the foot's: level at home
    np.testing.assert_allclose(
        robot.platform_placement(robot.q_home).rotation, np.eye(3), atol=1e-12
    )


@pytest.mark.parametrize("knee_home", [-0.1, 0.3, 1.2])
def test_knee_home_from_parameters(knee_home):
    robot = pkdyn.load("four_bar_knee", knee_home=knee_home)
    m = robot.model
    assert robot.q_home[m.joints[m.getJointId("knee")].idx_q] == pytest.approx(knee_home, abs=1e-12)
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    phi, _ = knee_cf.motor_from_knee(robot.params, np.array([knee_home]))
    assert robot.q_home[robot.actuated_q][0] == pytest.approx(float(phi[0]), abs=1e-12)
    # the platform (shank end) is at shank_length from the knee, turned by the knee angle
    M = robot.platform_placement(robot.q_home)
    L = robot.params.shank_length
    np.testing.assert_allclose(
        M.translation, [-L * math.sin(knee_home), 0, -L * math.cos(knee_home)], atol=1e-12
    )


@pytest.mark.parametrize(
    "family,params,name",
    [
        ("parallel_ankle", {"rod": 0.1}, "rod"),
        ("parallel_ankle", {"crank": -0.05}, "crank"),
        ("four_bar_knee", {"knee_home": 3.0}, "knee_home"),
        ("four_bar_knee", {"r1": 0.0}, "r1"),
    ],
)
def test_bad_parameters(family, params, name):
    with pytest.raises(pkdyn.ParameterError, match=f"parameter '{name}'"):
        pkdyn.load(family, **params)


def test_knee_holding_torque_by_virtual_work():
    """At rest, the motor torque of the inverse dynamics is the gravity load's virtual work."""
    from pkdyn.dynamics import inverse_dynamics
    from pkdyn.dynamics.trajectory import JointTrajectory

    robot = pkdyn.load("four_bar_knee", knee_home=0.6)
    q = robot.q_home
    data = robot.model.createData()
    g = pin.computeGeneralizedGravity(robot.model, data, q)
    Jc = robot.closure_set.jacobian(data, q)
    z = np.linalg.svd(Jc)[2][-1]  # the one motion of the linkage
    dq_dqa = z / z[robot.actuated_v[0]]
    zero = np.zeros((1, robot.nv))
    traj = JointTrajectory(np.zeros(1), q[None], zero, zero, robot.actuated_q, robot.actuated_v)
    tau = inverse_dynamics(robot, traj).tau[0, 0]
    assert tau == pytest.approx(dq_dqa @ g, rel=1e-9)
    assert abs(tau) > 1.0  # the 3 kg leg is held
