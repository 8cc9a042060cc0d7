"""The fastest cycle (toppra on pkdyn's closed-loop inverse dynamics): limits, optimality,
forward simulation, slower cycles, impossible paths."""

import json

import numpy as np
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.dynamics import inverse_dynamics, simulate, with_payload
from pkdyn.dynamics.actuation import motor_efforts, with_drives
from pkdyn.dynamics.fastest import fastest_trajectory, joint_path
from pkdyn.dynamics.sizing import size
from pkdyn.dynamics.trajectory import JointTrajectory, map_task_trajectory, named_task
from pkdyn.exceptions import InfeasibleEffortError, TrajectoryError

PAYLOAD = 1.0


@pytest.fixture(scope="module")
def robot():
    return pkdyn.load("delta", geometry=False)


@pytest.fixture(scope="module")
def fine(robot):
    """The Adept path at 1001 samples and its fastest traversal with 1 kg."""
    path = joint_path(robot, named_task(robot, "adept", cycle_time=1.0, dt=1e-3))
    return path, fastest_trajectory(robot, path, payload=PAYLOAD)


@pytest.fixture(scope="module")
def coarse(robot):
    return joint_path(robot, named_task(robot, "adept", cycle_time=1.0, dt=4e-3))


def test_inverse_dynamics_along_it_uses_the_limits(robot, fine):
    """pkdyn's inverse dynamics along the result: within the limits (1e-3 relative), with a
    torque or speed limit active on almost every sample."""
    _, res = fine
    traj = res.trajectory
    ef = inverse_dynamics(with_payload(robot, PAYLOAD), traj)
    E = np.array([a.effort for a in robot.actuators])
    V = np.array([a.velocity for a in robot.actuators])
    torque = np.abs(ef.tau) / E
    speed = np.abs(traj.qa_dot) / V
    assert np.max(torque) <= 1.0 + 1e-3 and np.max(speed) <= 1.0 + 1e-3
    used = np.maximum(torque.max(axis=1), speed.max(axis=1))
    assert np.mean(used >= 1.0 - 1e-3) > 0.95
    assert res.active_fraction > 0.95 and np.max(torque) > 0.999 and np.max(speed) > 0.999
    # a real Adept cycle: faster than any feasible quintic one, slower than nothing
    assert 0.2 < res.cycle_time < 0.4
    assert np.all(np.diff(traj.t) > 0) and traj.t[0] == 0.0


def test_no_quintic_cycle_beats_it(robot, fine):
    """Any time law on the same path is a parametrisation: a feasible quintic Adept cycle is
    never faster than the optimum."""
    _, res = fine
    for T in (0.3, 0.4, 0.45, 0.5, 0.6):
        jt = map_task_trajectory(
            robot, named_task(robot, "adept", cycle_time=T, dt=4e-3), check_limits=False
        )
        if size(robot, jt, payload=PAYLOAD).feasible:
            assert T >= res.cycle_time


def test_forward_simulation_follows_the_path(robot, fine):
    """The efforts fed forward to the constrained forward dynamics (from rest, no feedback)
    follow the Adept path: < 1 mm from it over the whole 0.29 s cycle."""
    path, res = fine
    loaded = with_payload(robot, PAYLOAD)
    sim = simulate(loaded, res.cycle_time, 1e-3, q0=path.q[0], torque=res.joint_effort_at)
    task = path.task
    s = np.interp(sim.t, res.trajectory.t, path.t)
    target = np.column_stack([np.interp(s, task.t, task.pose[:, j]) for j in range(3)])
    got = np.array([loaded.platform_placement(q).translation for q in sim.q])
    err = np.linalg.norm(got - target, axis=1)
    assert np.max(err) < 1e-3
    # the inverse dynamics is linear in (sdd, sd^2): tau = A sdd + B sd^2 + C at every sample
    lin = res.A * res.s_ddot[:, None] + res.B * res.s_dot[:, None] ** 2 + res.C + res.P
    assert np.max(np.abs(lin - res.efforts.tau)) < 1e-8 * np.max(np.abs(res.efforts.tau))


def test_a_slower_cycle_is_never_infeasible(robot, fine):
    _, res = fine
    traj = res.trajectory
    for k in (1.0, 1.001, 1.1, 1.5, 3.0):
        slow = JointTrajectory(
            k * traj.t, traj.q, traj.v / k, traj.a / k**2, traj.actuated_q, traj.actuated_v
        )
        sized = size(robot, slow, payload=PAYLOAD)
        assert sized.feasible, k
        if k > 1.0:
            assert min(a.margin for a in sized.actuators) > 0.0


def test_payload_rotor_inertia_and_losses_slow_it_down(robot, coarse):
    times = [fastest_trajectory(robot, coarse, payload=m).cycle_time for m in (0.0, 1.0, 2.0)]
    assert times[0] < times[1] < times[2]
    geared = with_drives(robot, rotor_inertia=5e-5)
    with_rotor = fastest_trajectory(geared, coarse, payload=1.0)
    assert with_rotor.cycle_time > 1.05 * times[1]
    lossy = with_drives(geared, efficiency=0.85, backdrive_efficiency=0.8, viscous=2e-4)
    lossy = with_drives(lossy, coulomb=0.03)
    res = fastest_trajectory(lossy, coarse, payload=1.0)
    assert res.cycle_time > with_rotor.cycle_time
    # the motor torques of the drive model, from pkdyn's inverse dynamics, are within the limit
    ef = inverse_dynamics(with_payload(lossy, 1.0), res.trajectory)
    tau_m = motor_efforts(lossy, ef.tau, res.trajectory.qa_dot)
    assert np.max(np.abs(20.0 * tau_m)) <= 40.0 * (1 + 1e-3)
    assert res.active_fraction > 0.9
    # limits from a catalog motor: its peak torque through the reduction, its speed
    slow = fastest_trajectory(robot, coarse, payload=1.0, effort=20.0, velocity=10.0)
    assert slow.cycle_time > times[1]
    assert np.max(slow.torque_utilisation) <= 1 + 1e-6


def test_impossible_paths_name_the_sample_and_why(robot, coarse):
    with pytest.raises(InfeasibleEffortError, match="hold the path at rest") as err:
        fastest_trajectory(robot, coarse, payload=60.0)
    assert err.value.sample is not None and err.value.actuator in robot.actuator_names
    assert "any speed" in str(err.value)
    with pytest.raises(TrajectoryError, match="out of reach") as err2:
        fastest_trajectory(robot, named_task(robot, "adept", depth=0.5, dt=4e-3))
    assert err2.value.sample is not None
    short = pkdyn.load("delta", geometry=False, alpha_max=1.3)
    with pytest.raises(TrajectoryError, match="outside its stroke") as err3:
        joint_path(short, named_task(short, "adept", cycle_time=1.0, dt=4e-3))
    assert "arm1" in str(err3.value) and err3.value.sample is not None


def test_cli_fastest(capsys):
    args = ["size", "delta", "--trajectory", "adept", "--fastest", "--payload", "1"]
    assert main(args + ["--dt", "4e-3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    fast = out["fastest"]
    assert 0.2 < fast["cycle_time"] < 0.4 and fast["active_fraction"] > 0.9
    assert out["feasible"] and out["duration"] == pytest.approx(fast["cycle_time"])
    assert max(a["peak"] for a in out["actuators"]) == pytest.approx(40.0, rel=1e-6)
    assert main(args + ["--dt", "4e-3"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("fastest cycle:") and "LIMITS EXCEEDED" not in text


def test_demo_prints_the_fastest_cycles(capsys):
    from pkdyn.cli.demo import run_fastest_demo

    out = run_fastest_demo(payloads=(1.0,), samples=126)
    text = capsys.readouterr().out
    assert "Fastest Adept cycle of the DELTA 580" in text and "check:" in text
    with_rotor, without = out[(1.0, 5e-5)], out[(1.0, 0.0)]
    assert with_rotor.cycle_time > without.cycle_time
    assert max(float(np.max(r.torque_utilisation)) for r in out.values()) <= 1 + 1e-6


def test_joint_springs_dampers_and_friction_are_honoured(robot, coarse):
    """With the robot's own passive elements (arm dampers, friction and a spring), pkdyn's
    inverse dynamics along the result (passive elements included) stays within the limits."""
    from pkdyn.model.description import PassiveSpec
    from pkdyn.model.passive import with_passive

    elements = [
        PassiveSpec(f"arm{i}", stiffness=(5.0,), rest=(0.6,), damping=(0.4,), friction=(0.5,))
        for i in (1, 2, 3)
    ]
    damped = with_passive(robot, elements)
    res = fastest_trajectory(damped, coarse, payload=1.0)
    ef = inverse_dynamics(with_payload(damped, 1.0), res.trajectory)
    assert np.max(np.abs(ef.tau)) <= 40.0 * (1 + 1e-3)
    assert np.max(np.abs(res.P)) > 1.0 and res.iterations > 1  # the dampers matter here
    assert res.active_fraction > 0.9
    # dampers and friction alone cost time (the spring above helps against gravity)
    lossy = [PassiveSpec(f"arm{i}", damping=(0.4,), friction=(0.5,)) for i in (1, 2, 3)]
    slow = fastest_trajectory(with_passive(robot, lossy), coarse, payload=1.0)
    assert slow.cycle_time > fastest_trajectory(robot, coarse, payload=1.0).cycle_time
