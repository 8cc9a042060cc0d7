"""Spring balancing: stiffness and preload that minimise the actuator torques.

- A pendulum arm balanced by a zero-free-length spring from a post above its pivot: the closed
  form ``k h d = m g r`` balances it exactly in every configuration (zero static torque).
- Delta (Adept cycle) and Gough-Stewart: the chosen springs lower the metric, and perturbing the
  stiffness or the preload raises it again (an optimum of the torques recomputed by the full
  model, not of the linear prediction); constraints (tension only, stiffness bound) hold.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.dynamics.balancing import (
    balance_springs,
    delta_balancing_springs,
    gough_stewart_balancing_springs,
    torque_metrics,
)
from pkdyn.dynamics.trajectory import named_trajectory
from pkdyn.exceptions import InvalidInputError
from pkdyn.model.description import FrameRef, SpringSpec
from pkdyn.model.passive import with_passive

M, R, H, D = 2.0, 0.3, 0.12, 0.1  # arm mass [kg], its centre of mass, post height, attachment

ARM = f"""<robot name="arm" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="{R} 0 0"/><mass value="{M}"/>
    <inertia ixx="0.001" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="50" velocity="5"/></joint>
  <transmission name="t"><type>transmission_interface/SimpleTransmission</type>
    <joint name="shoulder"/><actuator name="motor"><mechanicalReduction>1</mechanicalReduction>
    </actuator></transmission>
</robot>"""


def test_pendulum_is_balanced_exactly_by_the_closed_form_spring():
    robot = pkdyn.load_string(ARM, "arm")
    spring = SpringSpec(
        "post",
        FrameRef("base", pin.SE3(np.eye(3), np.array([0.0, 0.0, H]))),
        FrameRef("arm", pin.SE3(np.eye(3), np.array([D, 0.0, 0.0]))),
        0.0,
    )
    Q = np.linspace(-1.4, 1.4, 15)[:, None]
    res = balance_springs(robot, [spring], Q)
    g = -robot.model.gravity.linear[2]
    assert res.stiffness[0] == pytest.approx(M * g * R / (H * D), rel=1e-9)
    assert abs(res.rest_length[0]) < 1e-9
    assert np.max(np.abs(res.tau_before)) > 5.0  # [N m]
    assert np.max(np.abs(res.tau_after)) < 1e-9
    # the peak metric finds the same spring
    peak = balance_springs(robot, [spring], Q, metric="peak")
    assert peak.stiffness[0] == pytest.approx(res.stiffness[0], rel=1e-7)


def _objective(robot, samples, payload, metric):
    tau, rms, peak = torque_metrics(robot, samples, payload=payload)
    return float(np.sum(rms**2)) if metric == "rms" else float(np.max(peak))


@pytest.mark.parametrize("metric", ["rms", "peak"])
def test_delta_springs_are_an_optimum_of_the_recomputed_torques(metric):
    robot = pkdyn.load("delta", geometry=False)
    traj = named_trajectory(robot, "adept", cycle_time=1.5, dt=1e-2)
    springs = delta_balancing_springs(robot, anchor_height=0.1)
    res = balance_springs(robot, springs, traj, metric=metric, payload=1.0)
    assert res.robot.passive is not None and len(res.springs) == 3
    before = _objective(robot, traj, 1.0, metric)
    best = _objective(res.robot, traj, 1.0, metric)
    assert best < 0.7 * before  # slow heavy-ish work: gravity dominates
    if metric == "rms":  # the QP's prediction is what the full model gives
        np.testing.assert_allclose(res.rms_after**2 @ np.ones(3), best, rtol=1e-9)
    k, L0 = float(res.stiffness[0]), float(res.rest_length[0])
    for dk, dc in ((0.02, 0.0), (-0.02, 0.0), (0.0, 0.02), (0.0, -0.02)):
        k2 = k * (1 + dk)
        c2 = k * L0 * (1 + dc)
        other = [SpringSpec(s.name, s.frame1, s.frame2, k2, c2 / k2) for s in springs]
        assert _objective(with_passive(robot, springs=other), traj, 1.0, metric) > best


def test_constraints_hold():
    robot = pkdyn.load("delta", geometry=False)
    traj = named_trajectory(robot, "adept", cycle_time=0.5, dt=1e-2)
    springs = delta_balancing_springs(robot)
    res = balance_springs(robot, springs, traj, tension_only=True, max_stiffness=500.0)
    assert res.stiffness[0] <= 500.0 + 1e-9
    assert np.min(res.tension) >= -1e-9
    res = balance_springs(robot, springs, traj, rest_length=(0.0, 0.05))
    assert 0.0 <= res.rest_length[0] <= 0.05 + 1e-12


def test_gough_stewart_leg_springs_cut_the_leg_forces():
    robot = pkdyn.load("gough_stewart", geometry=False)
    traj = named_trajectory(robot, "sine", dt=2e-2)
    res = balance_springs(robot, gough_stewart_balancing_springs(robot), traj, payload=20.0)
    assert np.all(res.rms_after < 0.8 * res.rms_before)
    assert np.all(res.preload < 0.0)  # compression springs: the legs push the platform up


def test_bad_requests():
    robot = pkdyn.load("delta", geometry=False)
    traj = named_trajectory(robot, "adept", cycle_time=0.5, dt=2e-2)
    springs = delta_balancing_springs(robot)
    with pytest.raises(InvalidInputError, match="metric"):
        balance_springs(robot, springs, traj, metric="mean")
    with pytest.raises(InvalidInputError, match="groups"):
        balance_springs(robot, springs, traj, groups=[0, 2, 2])
    with pytest.raises(InvalidInputError, match="not a Gough-Stewart"):
        gough_stewart_balancing_springs(robot)
    quattro = pkdyn.load("delta", geometry=False, arms=4, bar_joint="universal")
    with pytest.raises(InvalidInputError, match="redundantly actuated"):
        balance_springs(quattro, delta_balancing_springs(quattro), traj.q[:2])
