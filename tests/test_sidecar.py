"""Gepetto example-parallel-robots sidecars: a plain URDF plus ``robot.yaml``.

The fixture ``tests/data/gepetto_five_bar`` is a planar five-bar written as a plain URDF tree
(no pkdyn elements) with loop frames ``closedloop1_A`` / ``closedloop1_B`` and motors ``mot1`` /
``mot2``; its ``robot.yaml`` closes the loop. References are plain Pinocchio forward kinematics
of the two loop frames.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn

DATA = Path(__file__).parent / "data" / "gepetto_five_bar"
FIVE_BAR = DATA / "five_bar.urdf"


def _loop_frames(robot: pkdyn.Robot, q: np.ndarray) -> tuple[pin.SE3, pin.SE3]:
    """World placements of the two loop frames, by plain Pinocchio forward kinematics."""
    model = robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return tuple(
        pin.SE3(data.oMf[model.getFrameId(name, pin.FrameType.BODY)])
        for name in ("closedloop1_A", "closedloop1_B")
    )


def _copy_urdf(tmp_path: Path, name: str = "five_bar.urdf") -> Path:
    path = tmp_path / name
    shutil.copy(FIVE_BAR, path)
    return path


def _with_sidecar(tmp_path: Path, yaml_text: str) -> Path:
    """A copy of the five-bar URDF with ``robot.yaml`` next to it."""
    path = _copy_urdf(tmp_path)
    (tmp_path / "robot.yaml").write_text(yaml_text)
    return path


def _idx(robot: pkdyn.Robot, joint: str, attr: str = "idx_q") -> int:
    return getattr(robot.model.joints[robot.model.getJointId(joint)], attr)


def test_robot_yaml_next_to_the_urdf_is_picked_up():
    robot = pkdyn.load(FIVE_BAR, geometry=False)
    (closure,) = robot.closures
    assert closure.kind == "point"  # type '3D'
    assert (closure.frame1.link, closure.frame2.link) == ("closedloop1_A", "closedloop1_B")
    (cm,) = robot.constraint_models
    assert cm.type == pin.ContactType.CONTACT_3D
    # the loop frames are fixed-joint links: their constraint sits on the parent moving joint
    assert (cm.joint1_id, cm.joint2_id) == (
        robot.model.getJointId("passive1"),
        robot.model.getJointId("passive2"),
    )
    assert robot.closure_set.nc == 3


def test_actuators_from_name_mot():
    robot = pkdyn.load(FIVE_BAR, geometry=False)
    assert robot.actuated_joint_names == ["mot1", "mot2"]
    assert list(robot.actuated_q) == [_idx(robot, "mot1"), _idx(robot, "mot2")]
    passive = sorted(_idx(robot, j, "idx_v") for j in ("passive1", "passive2"))
    assert sorted(robot.passive_v) == passive
    for act in robot.actuators:  # limits from the joints' URDF <limit>
        assert (act.reduction, act.effort, act.velocity) == (1.0, 3.0, 8.0)


def test_loaded_robot_is_assembled():
    robot = pkdyn.load(FIVE_BAR, geometry=False)
    A, B = _loop_frames(robot, robot.q_home)
    assert np.linalg.norm(A.translation - B.translation) < 1e-10
    # planar five-bar: 4 joints, a point closure of rank 2 in the plane
    assert robot.mobility() == 2


def test_forward_geometry_closes_the_loop():
    robot = pkdyn.load(FIVE_BAR, geometry=False)
    qa = robot.q_home[robot.actuated_q] + np.array([0.1, -0.05])
    res = pkdyn.forward_geometry(robot, qa)
    np.testing.assert_allclose(res.qa, qa, rtol=0, atol=1e-15)
    np.testing.assert_allclose(res.q[robot.actuated_q], qa, rtol=0, atol=1e-15)
    A, B = _loop_frames(robot, res.q)
    assert np.linalg.norm(A.translation - B.translation) < 1e-10
    # the loop point moved with the motors
    A0, _ = _loop_frames(robot, robot.q_home)
    assert np.linalg.norm(A.translation - A0.translation) > 1e-3


def test_explicit_sidecar_6d_weld(tmp_path):
    side = tmp_path / "weld.yaml"
    side.write_text(
        "closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['6d']\n"
        "name_mot: ['mot1', 'mot2']\n"
    )
    robot = pkdyn.load(FIVE_BAR, sidecar=side, geometry=False)  # wins over robot.yaml
    (closure,) = robot.closures
    assert closure.kind == "weld"
    (cm,) = robot.constraint_models
    assert cm.type == pin.ContactType.CONTACT_6D
    assert robot.closure_set.nc == 6
    assert robot.actuated_joint_names == ["mot1", "mot2"]
    A, B = _loop_frames(robot, robot.q_home)
    assert np.linalg.norm(A.translation - B.translation) < 1e-10
    np.testing.assert_allclose(A.rotation, B.rotation, atol=1e-10)
    assert robot.mobility() == 1  # the weld also locks the relative rotation in the plane
    qa = robot.q_home[robot.actuated_q] + np.array([0.02, 0.0])
    with pytest.raises(pkdyn.AssemblyError):  # one actuator too many for a weld
        pkdyn.forward_geometry(robot, qa)


def test_yaml_with_the_urdf_stem_is_picked_up(tmp_path):
    path = _copy_urdf(tmp_path, "fb.urdf")
    (tmp_path / "fb.yaml").write_text(
        "closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['3d']\nname_mot: ['mot2']\n"
    )
    robot = pkdyn.load(path, geometry=False)
    assert [c.kind for c in robot.closures] == ["point"]
    assert robot.actuated_joint_names == ["mot2"]


def test_without_sidecar_the_tree_stays_open(tmp_path):
    robot = pkdyn.load(_copy_urdf(tmp_path), geometry=False)
    assert robot.closures == ()
    assert robot.closure_set.nc == 0
    assert robot.actuators == ()


def test_mismatched_list_lengths(tmp_path):
    path = _with_sidecar(
        tmp_path, "closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['3D', '6D']\n"
    )
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load(path, geometry=False)
    assert err.value.culprit == "type"
    assert "2 types for 1 closed_loop pairs" in str(err.value)
    assert "robot.yaml" in str(err.value)


def test_unknown_closure_type(tmp_path):
    path = _with_sidecar(
        tmp_path, "closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['5d']\n"
    )
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load(path, geometry=False)
    assert "'5d'" in str(err.value)
    assert "3D or 6D" in str(err.value)


def test_name_mot_matching_no_joint(tmp_path):
    path = _with_sidecar(
        tmp_path,
        "closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['3D']\n"
        "name_mot: ['mot1', 'motor_z']\n",
    )
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load(path, geometry=False)
    assert "'motor_z'" in str(err.value)
    assert "matches no joint" in str(err.value)


def test_closed_loop_naming_a_missing_frame(tmp_path):
    path = _with_sidecar(
        tmp_path, "closed_loop: [['closedloop1_A', 'closedloop9_B']]\ntype: ['3D']\n"
    )
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load(path, geometry=False)
    assert "'closedloop9_B'" in str(err.value)


def test_closed_loop_entry_must_be_a_pair(tmp_path):
    path = _with_sidecar(tmp_path, "closed_loop: [['closedloop1_A']]\ntype: ['3D']\n")
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load(path, geometry=False)
    assert "closed_loop[0]" in str(err.value)


@pytest.mark.parametrize("text", ["closed_loop: [[", "- just\n- a list\n"], ids=["yaml", "list"])
def test_malformed_sidecar(tmp_path, text):
    side = tmp_path / "bad.yaml"
    side.write_text(text)
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load(FIVE_BAR, sidecar=side, geometry=False)
    assert err.value.culprit == "YAML"
    assert "bad.yaml" in str(err.value)
