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
    with ball-jointed or universal-jointed bars (README figure: 15.2 N m)."""
    robot, traj, ef = run
    three = with_payload(pkdyn.load("delta", geometry=False), 1.0)
    t3 = inverse_dynamics(three, named_trajectory(three, "adept", cycle_time=0.5, dt=0.004))
    peak4, peak3 = np.abs(ef.tau).max(), np.abs(t3.tau).max()
    assert peak4 < peak3
    assert peak4 == pytest.approx(15.2, abs=0.1)
