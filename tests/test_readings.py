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
