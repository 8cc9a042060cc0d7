"""Gepetto sidecars in full (joint types, free flyer, platform), read defensively; onshape frames.

The five-bar fixture of ``test_sidecar`` (a plain URDF tree with loop frames) is reused. The
references are plain Pinocchio forward kinematics and joint-model facts (a SPHERICAL joint has 4
configuration coordinates, a UJOINT_XY the rotation ``R_x(a) R_y(b)``...).
"""

from __future__ import annotations

import os
import shutil
import stat
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn

DATA = Path(__file__).parent / "data"
FIVE_BAR = DATA / "gepetto_five_bar" / "five_bar.urdf"
BATTOBOT = DATA / "public" / "gepetto_battobot" / "robot.urdf"
REACHY = DATA / "public" / "reachy_mini" / "robot.urdf"
LOOP = "closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['3D']\n"


def _five_bar(tmp_path: Path, yaml_text: str) -> Path:
    path = tmp_path / "five_bar.urdf"
    shutil.copy(FIVE_BAR, path)
    (tmp_path / "robot.yaml").write_text(yaml_text)
    return path


def _load(path: Path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the fixture's rounded numbers (CAD-rounding warning)
        return pkdyn.load(path, geometry=False, **kw)


def test_spherical_ujoint_and_fixed_joint_types(tmp_path):
    yaml_text = LOOP + (
        "name_mot: ['mot1', 'mot2']\n"
        "joint_name: ['passive1', 'passive2']\njoint_type: ['SPHERICAL', 'UJOINT_ZY']\n"
    )
    robot = _load(_five_bar(tmp_path, yaml_text))
    model = robot.model
    assert model.joints[model.getJointId("passive1")].shortname() == "JointModelSpherical"
    uj = model.joints[model.getJointId("passive2")]
    assert uj.shortname() == "JointModelUniversal" and (uj.nq, uj.nv) == (2, 2)
    # UJOINT_ZY: about the joint frame's z, then the rotated y
    m1 = pin.Model()
    m1.addJoint(0, uj, pin.SE3.Identity(), "u")
    d1 = m1.createData()
    pin.forwardKinematics(m1, d1, np.array([0.3, -0.2]))
    expected = (
        pin.AngleAxis(0.3, np.array([0, 0, 1.0])).matrix()
        @ pin.AngleAxis(-0.2, np.array([0, 1.0, 0])).matrix()
    )
    np.testing.assert_allclose(d1.oMi[1].rotation, expected, atol=1e-15)
    assert model.nq == 1 + 4 + 1 + 2
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    fixed = _load(
        _five_bar(
            tmp_path,
            LOOP + "name_mot: ['mot1']\njoint_name: ['mot2']\njoint_type: ['FIXED']\n",
        )
    )
    assert not fixed.model.existJointName("mot2")
    assert fixed.model.existFrame("mot2", pin.FrameType.FIXED_JOINT)
    assert fixed.nq == 3 and fixed.mobility() == 1


def test_free_flyer_and_platform(tmp_path):
    yaml_text = LOOP + (
        "name_mot: ['mot1', 'mot2']\nfree_flyer: true\n"
        "platform: {frame: closedloop1_A, xyz: [0, 0, 0.01], task: 'x z'}\n"
    )
    robot = _load(_five_bar(tmp_path, yaml_text))
    assert robot.model.joints[1].shortname() == "JointModelFreeFlyer"
    assert robot.model.names[1] == "root_joint"
    assert robot.platform_frame is not None and list(robot.task_rows) == [0, 2]
    # the base link's inertia moved onto the free flyer; the loop frames kept their parents
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.q_home)
    A = data.oMf[robot.model.getFrameId("closedloop1_A", pin.BODY)]
    B = data.oMf[robot.model.getFrameId("closedloop1_B", pin.BODY)]
    assert np.linalg.norm(A.translation - B.translation) < 1e-10
    P = robot.platform_placement(robot.q_home)
    np.testing.assert_allclose(P.translation, A.act(np.array([0, 0, 0.01])), atol=1e-12)


def test_gepetto_battobot_legs():
    """Six 6D closures, UJOINT and SPHERICAL upgrades: assembles exactly (no search needed)."""
    robot = _load(BATTOBOT)
    shorts = {robot.model.joints[j].shortname() for j in range(1, robot.model.njoints)}
    assert {"JointModelUniversal", "JointModelSpherical"} <= shorts
    assert robot.closure_set.nc == 36 and len(robot.actuators) == 12
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-9
    assert robot.mobility() == 12


def test_name_mot_names_are_literal(tmp_path):
    """Gepetto's loader takes joint names: 'mot' or '^mot' are no patterns."""
    for pattern in ("mot", "^mot", "mot.*"):
        with pytest.raises(pkdyn.DescriptionError) as err:
            _load(_five_bar(tmp_path, LOOP + f"name_mot: ['{pattern}']\n"))
        assert f"name_mot '{pattern}': matches no joint" in str(err.value)


@pytest.mark.parametrize(
    "text,culprit,message",
    [
        (LOOP + "name_mot: mot1\n", "name_mot", "the string 'mot1'"),
        (LOOP + "name_mot: 3\n", "name_mot", "expected a list of names, got int"),
        (LOOP + "name_mot: [[mot1]]\n", "name_mot[0]", "expected a name, got list"),
        (
            LOOP + "joint_name: [passive1]\njoint_type: [BALL]\n",
            "joint_type[0]='BALL'",
            "SPHERICAL",
        ),
        (
            LOOP + "joint_name: [passive1]\njoint_type: [UJOINT_XX]\n",
            "joint_type[0]='UJOINT_XX'",
            "differ",
        ),
        (LOOP + "joint_name: [passive1, passive2]\njoint_type: [SPHERICAL]\n", "joint_type", "1 "),
        (LOOP + "free_flyer: yes please\n", "free_flyer", "true or false"),
        (LOOP + "platform: closedloop1_A\n", "platform", "mapping with 'frame'"),
        (LOOP + "platform: {frame: closedloop1_A, task: 'x w'}\n", "platform.task 'x w'", "among"),
        (LOOP + "platform: {frame: closedloop1_A, xyz: [0, 0]}\n", "platform.xyz", "3"),
        ("closed_loop: [[a, 1]]\ntype: [3D]\n", "closed_loop[0]", "pair of frame names"),
    ],
)
def test_mistyped_sidecar_keys(tmp_path, text, culprit, message):
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load(_five_bar(tmp_path, text))
    assert err.value.culprit == culprit
    assert message in str(err.value) and "robot.yaml" in str(err.value)


def test_yaml_alias_bomb_is_refused_at_once(tmp_path):
    bomb = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [{', '.join(['*' + p] * 9)}]\n"
        for p, c in zip("abcdefgh", "bcdefghi", strict=True)
    )
    bomb += "name_mot: *i\n" + LOOP
    with pytest.raises(pkdyn.DescriptionError, match="YAML.*anchors are not allowed"):
        _load(_five_bar(tmp_path, bomb))


def test_too_many_yaml_nodes(tmp_path, monkeypatch):
    from pkdyn.model.formats import gepetto

    monkeypatch.setattr(gepetto, "MAX_NODES", 50)
    text = LOOP + "name_mot: [" + ", ".join(["mot1"] * 60) + "]\n"
    with pytest.raises(pkdyn.DescriptionError, match="more than 50 YAML nodes"):
        _load(_five_bar(tmp_path, text))


def test_regex_like_names_cannot_hang(tmp_path):
    evil = "(a+)+$" + "a" * 40 + "!"
    with pytest.raises(pkdyn.DescriptionError, match="matches no joint"):
        _load(_five_bar(tmp_path, LOOP + f"name_mot: ['{evil}']\n"))


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_sidecar_from_a_fifo_is_refused(tmp_path):
    fifo = tmp_path / "side.yaml"
    os.mkfifo(fifo)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    with pytest.raises(pkdyn.DescriptionError, match="not a regular file"):
        _load(FIVE_BAR, sidecar=fifo)  # returns at once: the FIFO is never opened


def test_sidecar_or_description_from_a_device_is_refused():
    with pytest.raises(pkdyn.DescriptionError, match="not a regular file"):
        _load(FIVE_BAR, sidecar="/dev/zero")
    with pytest.raises(pkdyn.DescriptionError, match="not a regular file"):
        pkdyn.load("/dev/zero")


def test_oversized_sidecar_is_refused(tmp_path, monkeypatch):
    from pkdyn.model.formats import xmldoc

    monkeypatch.setattr(xmldoc, "MAX_FILE_BYTES", 100)
    path = tmp_path / "big.yaml"
    path.write_text(LOOP * 10)
    with pytest.raises(pkdyn.DescriptionError, match="at most 0 MiB|MiB"):
        _load(FIVE_BAR, sidecar=path)


def test_unknown_keys_and_absent_joint_names_warn(tmp_path):
    text = LOOP + "colour: blue\njoint_name: [nowhere]\njoint_type: [SPHERICAL]\n"
    with pytest.warns(UserWarning) as record:
        pkdyn.load(_five_bar(tmp_path, text), geometry=False)
    messages = " | ".join(str(w.message) for w in record)
    assert "unknown sidecar keys ignored: colour" in messages
    assert "joint_name entries that name no joint" in messages and "nowhere" in messages


def test_gepetto_naming_convention_without_joint_name(tmp_path):
    path = _five_bar(tmp_path, LOOP + "name_mot: ['mot1', 'mot2']\n")
    path.write_text(path.read_text().replace("passive1", "spherical_passive1"))
    with pytest.warns(UserWarning, match="1 revolute joints named '\\*spherical\\*' become ball"):
        robot = pkdyn.load(path, geometry=False)
    jm = robot.model.joints[robot.model.getJointId("spherical_passive1")]
    assert jm.shortname() == "JointModelSpherical"
    (tmp_path / "robot.yaml").write_text(LOOP + "name_mot: [mot1, mot2]\njoint_name: []\n")
    robot = _load(path)
    assert robot.model.joints[robot.model.getJointId("spherical_passive1")].nq == 1


def test_loop_frames_without_a_sidecar_warn(tmp_path):
    path = tmp_path / "five_bar.urdf"
    shutil.copy(FIVE_BAR, path)
    with pytest.warns(UserWarning, match="closedloop1 look like Gepetto loop frames"):
        robot = pkdyn.load(path, geometry=False)
    assert robot.closures == ()


# ---------------------------------------------------------------------------------- onshape

ONSHAPE = """<robot name="onshape">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.05 0 0"/><mass value="0.1"/>
    <inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <link name="b"><inertial><origin xyz="0.05 0 0"/><mass value="0.1"/>
    <inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <link name="c"><inertial><origin xyz="0.05 0 0"/><mass value="0.1"/>
    <inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <joint name="motor" type="revolute"><origin xyz="0 0 0" rpy="0 0 0"/>
    <parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit effort="10" velocity="10" lower="-3.14" upper="3.14"/></joint>
  <joint name="passive" type="revolute"><origin xyz="0.1 0 0" rpy="0 0 1.5708"/>
    <parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
    <limit effort="10" velocity="10" lower="-3.14" upper="3.14"/></joint>
  <joint name="rocker" type="revolute"><origin xyz="0.2 0.1 0" rpy="0 0 3.14159"/>
    <parent link="base"/><child link="c"/><axis xyz="0 0 1"/>
    <limit effort="10" velocity="10" lower="-3.14" upper="3.14"/></joint>
  <!-- Frame closing_pin_1 (dummy link + fixed joint) -->
  <link name="closing_pin_1"><inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="1e-9"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="closing_pin_1_frame" type="fixed"><origin xyz="0.1 0 0" rpy="0 0 0"/>
    <parent link="b"/><child link="closing_pin_1"/><axis xyz="0 0 0"/></joint>
  <link name="closing_pin_2"><inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="1e-9"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="closing_pin_2_frame" type="fixed"><origin xyz="0.1 0 0" rpy="0 0 0"/>
    <parent link="c"/><child link="closing_pin_2"/><axis xyz="0 0 0"/></joint>
  {z_frames}
</robot>"""

Z_FRAMES = """
  <link name="closing_pin_1_z"/>
  <joint name="closing_pin_1_z_frame" type="fixed"><origin xyz="0.1 0 0.1"/>
    <parent link="b"/><child link="closing_pin_1_z"/></joint>
  <link name="closing_pin_2_z"/>
  <joint name="closing_pin_2_z_frame" type="fixed"><origin xyz="0.1 0 0.1"/>
    <parent link="c"/><child link="closing_pin_2_z"/></joint>
"""


@pytest.mark.parametrize("z,kind", [("", "point"), (Z_FRAMES, "hinge")])
def test_onshape_closing_frames_close_loops(tmp_path, z, kind):
    path = tmp_path / "robot.urdf"
    path.write_text(ONSHAPE.format(z_frames=z))
    with pytest.warns(
        UserWarning, match="misses the closures by up to .*closing_pin.*CAD rounding"
    ):
        robot = pkdyn.load(path, geometry=False)  # rpy 1.5708: the %g rounding of pi/2
    assert [(c.name, c.kind) for c in robot.closures] == [("closing_pin", kind)]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    assert robot.mobility() == 1


def test_reachy_mini_onshape_export_loads_with_the_cad_rounding_warning():
    with pytest.warns(UserWarning, match=r"misses the closures by up to 7\.\de-07"):
        robot = pkdyn.load(REACHY, geometry=False)
    assert [c.name for c in robot.closures] == [f"closing_{k}" for k in range(1, 6)]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    assert [a.name for a in robot.actuators] == ["yaw_body"] + [f"stewart_{k}" for k in range(1, 7)]
