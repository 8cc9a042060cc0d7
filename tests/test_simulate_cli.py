"""``pkdyn simulate --v0 / --torque``: an initial velocity and a constant effort, against physics.

- ``--v0`` with the actuators' rates starts on the closed-loop manifold (``Jc v = 0``), with
  those rates, and with the kinetic energy ``0.5 v^T M v`` of that velocity (``M`` from
  Pinocchio's CRBA, independently of the simulator);
- a constant ``--torque`` does the work ``tau . (qa_end - qa_start)`` (a constant effort's work
  is exact from the positions alone), which equals the change of kinetic plus potential energy
  (no damping in the five-bar);
- the README's example moves the five-bar and shows it.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.cli import main


def _run(capsys, argv):
    assert main(argv) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def five_bar():
    return pkdyn.load("five_bar")


def _csv(path):
    data = np.genfromtxt(path, delimiter=",", names=True)
    return data


def test_initial_actuator_rates_start_on_the_manifold_with_their_kinetic_energy(
    capsys, tmp_path, five_bar
):
    qa_dot = np.array([1.0, -1.0])
    out = tmp_path / "run.csv"
    argv = ["simulate", "five_bar", "--duration", "0.05", "--v0", "1", "-1e0"]
    res = _run(capsys, [*argv, "--csv", str(out), "--json"])
    data = _csv(out)
    names = five_bar.actuator_names
    got = np.array([data[f"qa_dot_{n}"][0] for n in names])
    np.testing.assert_allclose(got, qa_dot, atol=1e-12)
    # the full velocity the simulation started from: the recorded one, checked on the manifold
    from pkdyn.analysis.kinematics import joint_velocities
    from pkdyn.dynamics import simulate

    v = joint_velocities(five_bar, five_bar.q_home, qa_dot)
    Jc = five_bar.closure_set.jacobian(five_bar.model.createData(), five_bar.q_home)
    assert np.max(np.abs(Jc @ v)) < 1e-12 * np.max(np.abs(v))
    sim = simulate(five_bar, 0.05, 1e-3, v0=v)
    np.testing.assert_allclose(sim.v[0], v, atol=1e-12)
    M = pin.crba(five_bar.model, five_bar.model.createData(), five_bar.q_home)
    M = np.triu(M) + np.triu(M, 1).T
    ke = 0.5 * v @ M @ v
    assert data["kinetic"][0] == pytest.approx(ke, rel=1e-9)
    assert res["actuators"][0]["peak_rate"] >= 1.0 - 1e-9
    # nothing but inertia acts on the horizontal five-bar: its kinetic energy is kept
    assert np.max(np.abs(data["kinetic"] - ke)) < 1e-6 * ke


def test_every_velocity_coordinate_can_be_given(capsys, tmp_path, five_bar):
    from pkdyn.analysis.kinematics import joint_velocities

    v = joint_velocities(five_bar, five_bar.q_home, [0.5, 0.2])
    out = tmp_path / "run.csv"
    argv = ["simulate", "five_bar", "--duration", "0.01", "--csv", str(out)]
    _run(capsys, [*argv, "--json", "--v0", *[repr(float(x)) for x in v]])
    data = _csv(out)
    rates = [data[f"qa_dot_{n}"][0] for n in five_bar.actuator_names]
    np.testing.assert_allclose(rates, [0.5, 0.2], atol=1e-12)


@pytest.mark.parametrize(
    "robot, torque", [("five_bar", ["0.5", "-2e-1"]), ("delta", ["1", "-5E-1", "0"])]
)
def test_a_constant_torque_does_the_work_the_energy_gains(capsys, tmp_path, robot, torque):
    out = tmp_path / "run.csv"
    argv = ["simulate", robot, "--duration", "0.2", "--torque", *torque, "--csv", str(out)]
    res = _run(capsys, [*argv, "--json"])
    data = _csv(out)
    r = pkdyn.load(robot)
    tau = np.array([float(x) for x in torque])
    dqa = np.array([data[f"qa_{n}"][-1] - data[f"qa_{n}"][0] for n in r.actuator_names])
    work = float(tau @ dqa)  # a constant effort: exact from the positions
    gain = (data["kinetic"][-1] - data["kinetic"][0]) + (
        data["potential"][-1] - data["potential"][0]
    )
    scale = max(abs(work), float(np.max(data["kinetic"])))
    assert abs(work) > 1e-3  # it moved
    assert gain == pytest.approx(work, abs=1e-6 * scale)
    assert res["work"] == pytest.approx(work, abs=1e-6 * scale)


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["--v0", "1"], "--v0: expected 2 or 4 values, got 1"),
        (["--torque", "1", "2", "3"], "--torque: expected 2 values, got 3"),
        (["--v0", "1", "inf"], "--v0: value #2 is inf"),
    ],
)
def test_bad_initial_states_are_one_line(capsys, argv, needle):
    assert main(["simulate", "five_bar", *argv]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err


def test_the_readme_example_moves(capsys):
    assert main(["simulate", "five_bar", "--v0", "1", "-1", "--duration", "0.5"]) == 0
    text = capsys.readouterr().out
    rows = {line.split()[0]: line.split() for line in text.splitlines()[2:4]}
    for name in ("motor1", "motor2"):
        start, end = float(rows[name][1]), float(rows[name][3])
        assert abs(end - start) > 0.3  # rad: half a radian in half a second
    assert "energy drift" in text
