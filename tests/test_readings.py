"""The one readings rule: Robot.joint_coordinates (encoder gains and offsets), used everywhere.

A description's ``<pkdyn:encoder gain offset>`` makes the actuated joint coordinate ``gain x
reading + offset``. Trajectory files, calibration measurements and identification motions hold
readings in their ``qa_`` columns; the forward geometry of the joint coordinates the rule gives is
the reference (a hand-computed ``gain * r + offset``).
"""

from __future__ import annotations

import numpy as np
import pytest
from support.urdf_edit import family_xml

import pkdyn
from pkdyn.exceptions import DescriptionError, InvalidInputError
from pkdyn.tables import write_table

GAIN, OFFSET = 1.01, 0.02


@pytest.fixture(scope="module")
def geared():
    """A five-bar whose first encoder reads 1 % short with a zero 20 mrad off."""
    robot = pkdyn.load("five_bar", geometry=False)
    text = family_xml(robot).replace(
        "<mechanicalReduction>",
        f'<pkdyn:encoder gain="{GAIN}" offset="{OFFSET}"/><mechanicalReduction>',
        1,
    )
    return pkdyn.load_string(text, "geared.urdf", geometry=False), text


def test_the_rule_batched_rates_and_its_inverse(geared):
    robot, _ = geared
    np.testing.assert_array_equal(robot.encoder_gains, [GAIN, 1.0])
    np.testing.assert_array_equal(robot.encoder_offsets, [OFFSET, 0.0])
    r = np.array([[1.0, 2.0], [-0.5, 0.25], [0.0, 0.0]])
    q = robot.joint_coordinates(r)
    np.testing.assert_allclose(q, np.column_stack([GAIN * r[:, 0] + OFFSET, r[:, 1]]))
    np.testing.assert_allclose(robot.joint_coordinates(r, rates=True)[:, 0], GAIN * r[:, 0])
    np.testing.assert_allclose(robot.readings(q), r, atol=1e-15)
    np.testing.assert_allclose(robot.readings(robot.joint_coordinates(r, True), True), r)
    assert robot.joint_coordinates(r[None]).shape == (1, 3, 2)
    with pytest.raises(InvalidInputError, match="expected 2 values per row"):
        robot.joint_coordinates([1.0, 2.0, 3.0])
    with pytest.raises(InvalidInputError, match="readings"):
        robot.joint_coordinates("abc")


def test_the_offset_is_checked(geared):
    _, text = geared
    for bad in ("inf", "nan", "x"):
        with pytest.raises(DescriptionError, match="offset"):
            pkdyn.load_string(
                text.replace(f'offset="{OFFSET}"', f'offset="{bad}"'), "x.urdf", geometry=False
            )


def test_trajectory_files_hold_readings(geared, tmp_path):
    from pkdyn.dynamics.trajectory_file import read_task_csv

    robot, _ = geared
    home = robot.readings(robot.q_home[robot.actuated_q])
    t = np.linspace(0.0, 1.0, 11)
    r = home + 0.05 * np.outer(np.sin(t), [1.0, -1.0])
    write_table(tmp_path / "r.csv", ["t", "qa_motor1", "qa_motor2"], np.column_stack([t, r]))
    traj = read_task_csv(robot, tmp_path / "r.csv")
    q = robot.q_home
    for k in (0, 5, 10):
        qa = np.array([GAIN * r[k, 0] + OFFSET, r[k, 1]])  # the rule, by hand
        q = pkdyn.forward_geometry(robot, qa, q_init=q).q
        np.testing.assert_allclose(traj.pose[k, :3], robot.platform_placement(q).translation)


def test_identification_checks_the_joint_coordinates_of_the_readings(geared):
    from pkdyn.identification import Measurements, identify

    robot, _ = geared
    t = np.linspace(0.0, 1.0, 50)
    qa = np.tile(robot.q_home[robot.actuated_q], (50, 1))
    qa[:, 0] = 3.17  # within +-pi and the check's 1 % of the range (0.063 rad)...
    r = robot.readings(qa)
    r[:, 0] = 3.17  # ...but as a reading: 1.01 x 3.17 + 0.02 = 3.2217 beyond it
    with pytest.raises(InvalidInputError, match="sample 0, column qa_motor1: 3.2217 rad lies"):
        identify(robot, Measurements(t, r, 0 * r, 0 * r, 0 * r))


@pytest.mark.parametrize("command", ["size", "simulate"])
def test_csv_files_written_hold_readings(geared, tmp_path, capsys, command):
    """``size --csv`` (and ``simulate --csv``) write readings: read back, the same motion."""
    from pkdyn.cli import main
    from pkdyn.tables import read_table

    robot, text = geared
    urdf = tmp_path / "geared.urdf"
    urdf.write_text(text)
    first, again = tmp_path / "first.csv", tmp_path / "again.csv"
    if command == "size":
        assert main(["size", str(urdf), "--trajectory", "sine", "--csv", str(first)]) == 0
    else:
        args = ["simulate", str(urdf), "--duration", "0.2", "--dt", "0.01", "--v0", "0.5", "-0.5"]
        assert main([*args, "--csv", str(first)]) == 0
    cols = [f"qa_{a}" for a in robot.actuator_names]
    table = read_table(first, "sample")
    r = table.select(cols)
    q = robot.joint_coordinates(r)
    # the readings are those of the motion's joint coordinates
    if command == "size":
        from pkdyn.dynamics.trajectory import named_trajectory

        motion = named_trajectory(robot, "sine", check_speeds=False).qa
        np.testing.assert_allclose(q, motion, rtol=0.0, atol=1e-9)
    else:  # (the simulation starts at home)
        np.testing.assert_allclose(q[0], robot.q_home[robot.actuated_q], rtol=0.0, atol=1e-9)
    assert not np.allclose(r[0], q[0], atol=1e-3)  # (the gain and offset show)
    assert main(["size", str(urdf), "--trajectory", str(first), "--csv", str(again)]) == 0
    capsys.readouterr()
    back = read_table(again, "sample").select(cols)
    # the same motion: the readings read back are the readings written (to the inverse
    # geometry's tolerance and the file's 10 digits), not off by the gain
    np.testing.assert_allclose(back, r, rtol=0.0, atol=1e-8)
    assert np.ptp(r[:, 0]) > 1e-3  # (a motion, not a pose held)
