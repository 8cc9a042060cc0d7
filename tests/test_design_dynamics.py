"""The Delta's closed-form vectorised inverse dynamics against the general path."""

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.dynamics import inverse_dynamics, with_payload
from pkdyn.dynamics.delta import DeltaDynamics, delta_inverse_dynamics, has_delta_dynamics
from pkdyn.dynamics.trajectory import map_task_trajectory, named_task
from pkdyn.exceptions import PkdynError, TrajectoryError


def _general(robot, task, payload=0.0, offset=(0.0, 0.0, 0.0)):
    traj = map_task_trajectory(robot, task)
    loaded = with_payload(robot, payload, offset) if payload else robot
    return traj, inverse_dynamics(loaded, traj)


@pytest.mark.parametrize(
    "params, name, opts, payload, offset",
    [
        ({}, "adept", {"cycle_time": 0.5, "dt": 5e-3}, 1.0, (0.0, 0.0, 0.0)),
        ({"la": 0.25, "lb": 0.5, "ra": 0.12, "z_home": -0.45}, "sine", {"dt": 1e-2}, 0.0, (0,) * 3),
        ({"bar_mass": 0.1, "nacelle_mass": 0.4}, "p2p", {"dt": 5e-3}, 2.0, (0.01, -0.02, 0.03)),
    ],
)
def test_matches_the_general_inverse_dynamics(params, name, opts, payload, offset):
    robot = pkdyn.load("delta", geometry=False, **params)
    task = named_task(robot, name, **opts)
    traj, ef = _general(robot, task, payload, offset)
    loaded = with_payload(robot, payload, offset) if payload else robot
    fast = delta_inverse_dynamics(loaded, task)
    scale = max(1.0, float(np.max(np.abs(ef.tau))))
    assert np.max(np.abs(fast.tau - ef.tau)) < 1e-9 * scale
    assert np.max(np.abs(fast.qa - traj.qa)) < 1e-9
    assert np.max(np.abs(fast.qa_dot - traj.qa_dot)) < 1e-8
    scale = max(1.0, np.max(np.abs(traj.qa_ddot)))
    assert np.max(np.abs(fast.qa_ddot - traj.qa_ddot)) < 1e-6 * scale


def test_armature_and_gravity_are_read_from_the_model():
    robot = pkdyn.load("delta", geometry=False)
    model = pin.Model(robot.model)
    model.armature[robot.actuated_v] = [0.01, 0.02, 0.03]
    model.gravity.linear = np.array([1.0, -2.0, -9.0])
    import dataclasses

    edited = dataclasses.replace(robot, model=model, data=model.createData())
    task = named_task(edited, "adept", dt=1e-2)
    _, ef = _general(edited, task)
    fast = delta_inverse_dynamics(edited, task)
    assert np.max(np.abs(fast.tau - ef.tau)) < 1e-9 * np.max(np.abs(ef.tau))


def test_power_balance():
    """Actuator work = change of mechanical energy (independent of the formulation)."""
    robot = pkdyn.load("delta", geometry=False)
    task = named_task(robot, "adept", cycle_time=0.6, dt=2e-3)
    fast = delta_inverse_dynamics(robot, task)
    traj = map_task_trajectory(robot, task)
    from pkdyn.dynamics import mechanical_energy

    E = np.array([sum(mechanical_energy(robot, q, v)) for q, v in zip(traj.q, traj.v, strict=True)])
    P = np.sum(fast.power, axis=1)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (P[1:] + P[:-1]) * np.diff(task.t))])
    assert np.max(np.abs(work - (E - E[0]))) < 5e-3 * np.max(np.abs(E - E[0]))


def test_limits_and_refusals():
    robot = pkdyn.load("delta", geometry=False)
    with pytest.raises(TrajectoryError, match="velocity limit"):
        delta_inverse_dynamics(robot, named_task(robot, "adept", cycle_time=0.3, dt=1e-2))
    far = named_task(robot, "adept", cycle_time=0.5, depth=0.3, dt=1e-2)
    with pytest.raises(TrajectoryError):
        delta_inverse_dynamics(robot, far)
    assert not has_delta_dynamics(pkdyn.load("delta", geometry=False, bar_joint="universal"))
    with pytest.raises(PkdynError, match="inverse_dynamics"):
        DeltaDynamics(pkdyn.load("gough_stewart", geometry=False))


def test_payload_argument_equals_with_payload():
    robot = pkdyn.load("delta", geometry=False)
    task = named_task(robot, "adept", dt=1e-2)
    a = delta_inverse_dynamics(with_payload(robot, 1.5, (0.02, 0.0, -0.01)), task)
    b = delta_inverse_dynamics(robot, task, payload=1.5)
    assert np.max(np.abs(a.tau - b.tau)) < 1e-12 * np.max(np.abs(a.tau))
    with pytest.raises(PkdynError, match="payload"):
        delta_inverse_dynamics(robot, task, payload=-1.0)
