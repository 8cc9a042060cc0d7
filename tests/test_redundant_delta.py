"""The four-armed Delta (redundant actuation): least efforts, checked independently.

The redundant robot can never need more than the same robot with its fourth arm idle: that is one
of its solutions, so the least weighted-norm efforts weigh at most as much. The reference is
built here from the dynamics equation alone (RNEA, closure Jacobian, its null space), not from
the solver under test. The efforts used to come out antagonistic (hundreds of N m) with
ball-jointed bars, where the closure Jacobian's passive columns lose rank.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.dynamics import inverse_dynamics, with_payload
from pkdyn.dynamics.trajectory import named_trajectory
from solvers import numerics


@pytest.fixture(scope="module", params=["spherical", "universal"])
def run(request):
    robot = with_payload(pkdyn.load("delta", arms=4, bar_joint=request.param, geometry=False), 1.0)
    traj = named_trajectory(robot, "adept", cycle_time=0.5, dt=0.004)
    return robot, traj, inverse_dynamics(robot, traj, progress=False)


def reference(robot, q, v, a):
    """``G tau = f`` over the motions the closures allow (independent of the solver)."""
    b = pin.rnea(robot.model, robot.model.createData(), q, v, a)
    J = robot.closure_set.jacobian(robot.model.createData(), q)
    Z = numerics.null_space(J)
    S = np.zeros((len(robot.actuators), robot.nv))
    S[np.arange(len(robot.actuators)), robot.actuated_v] = 1.0
    return Z.T @ S.T, Z.T @ b


def test_least_efforts_weigh_no_more_than_with_the_fourth_arm_idle(run):
    robot, traj, ef = run
    w = 1.0 / np.array([a.effort for a in robot.actuators]) ** 2
    for k in range(0, traj.t.size, 5):
        G, f = reference(robot, traj.q[k], traj.v[k], traj.a[k])
        tau = ef.tau[k]
        scale = max(1.0, float(np.abs(f).max()))
        assert np.abs(G @ tau - f).max() < 1e-8 * scale  # the dynamics are satisfied
        idle = numerics.lstsq(G[:, :3], f)  # arm 4 idle: the three others carry everything
        assert np.abs(G[:, :3] @ idle - f).max() < 1e-8 * scale
        idle4 = np.append(idle, 0.0)
        assert w @ tau**2 <= w @ idle4**2 * (1 + 1e-9) + 1e-12, k
        # and it is the least one: no direction of the redundancy lowers it
        n = numerics.null_space(G)
        assert np.abs(n.T @ (w * tau)).max() < 1e-8 * max(1.0, float(np.abs(w * tau).max()))


def test_four_arms_need_less_than_three(run):
    """The Adept cycle (0.5 s, 1 kg): below the three-armed DELTA 580's 20.8 N m, the same
    with ball-jointed or universal-jointed bars (guide figure: 15.2 N m)."""
    robot, traj, ef = run
    three = with_payload(pkdyn.load("delta", geometry=False), 1.0)
    t3 = inverse_dynamics(three, named_trajectory(three, "adept", cycle_time=0.5, dt=0.004))
    peak4, peak3 = np.abs(ef.tau).max(), np.abs(t3.tau).max()
    assert peak4 < peak3
    assert peak4 == pytest.approx(15.2, abs=0.1)


@pytest.mark.parametrize("pose", [[0.0, 0.0, -0.35], [0.05, 0.03, -0.4], [-0.08, 0.06, -0.45]])
def test_kinematic_models_of_the_redundant_delta_against_differences(pose):
    """One relation per actuator: ``J_inv`` (4 x 3) by central differences of the inverse model.

    With four actuators for three platform coordinates every actuator rate is tied to the
    platform's: ``A`` is 4 x 3 and ``B`` 4 x 4. The models used to keep only three relations,
    which made ``J_inv`` wrong off home and the home pose a false parallel singularity.
    """
    import warnings

    from pkdyn.analysis.kinematics import kinematic_models
    from pkdyn.analysis.singularity import classify

    robot = pkdyn.load("delta", arms=4, geometry=False)
    q = pkdyn.inverse_geometry(robot, pose).q
    km = kinematic_models(robot, q)
    assert km.A.shape == (4, 3) and km.B.shape == (4, 4)
    h = 1e-6
    J_fd = np.zeros((4, 3))
    for i in range(3):
        up, down = np.array(pose), np.array(pose)
        up[i] += h
        down[i] -= h
        J_fd[:, i] = (
            pkdyn.inverse_geometry(robot, up, q_init=q).qa
            - pkdyn.inverse_geometry(robot, down, q_init=q).qa
        ) / (2 * h)
    assert np.max(np.abs(km.J_inv - J_fd)) < 1e-6 * max(1.0, float(np.max(np.abs(J_fd))))
    assert np.allclose(km.J @ km.J_inv, np.eye(3), atol=1e-9)  # consistent rates: x back
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # not even near a singularity
        report = classify(robot, q)
    assert report.kind == "regular" and report.margin > 0.05
