"""SDFormat import: model graphs with loops, cut joints as closures, Drake's constraint elements.

References: the file's own link poses (every body frame must be where ``<pose>`` puts it at the
description's configuration), Drake's four-bar example geometry (closed form of the planar
four-bar), and example-robot-data's Cassie (loads, assembles, mobility by counting).
"""

from __future__ import annotations

import importlib.metadata
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.mobility import mobility

DATA = Path(__file__).parent / "data" / "public" / "erd_cassie_sdf"


def _erd_cassie() -> Path | None:
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    p = Path(
        str(
            dist.locate_file(
                "cmeel.prefix/share/example-robot-data/robots/cassie_description/robots/"
                "cassie_v2.sdf"
            )
        )
    )
    return p if p.is_file() else None


FOUR_BAR = """<?xml version="1.0"?>
<sdf version="1.9">
  <model name="four_bar">
    <!-- Drake's four-bar (examples/multibody/four_bar): crank 1 m, coupler 4.8 m, rocker 2 m,
         ground 4 m; assembled here with the crank upright: the coupler's far end is on the
         rocker's, the rocker tilted back -->
    <frame name="Wd" attached_to="world"><pose relative_to="world">-2 0 0 0 0 0</pose></frame>
    <frame name="Wr" attached_to="world"><pose relative_to="world">2 0 0 0 0 0</pose></frame>
    <link name="driver">
      <pose relative_to="Wd">0 0 0 0 0 0</pose>
      <inertial><pose>0 0.5 0 0 0 0</pose><mass>1</mass>
        <inertia><ixx>0.0833333</ixx><iyy>0</iyy><izz>0.0833333</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>
    </link>
    <frame name="Dc" attached_to="driver"><pose relative_to="driver">0 1 0 0 0 0</pose></frame>
    <link name="coupler">
      <pose relative_to="Dc">0 0 0 0 0 {coupler_yaw}</pose>
      <inertial><pose>2.4 0 0 0 0 0</pose><mass>1</mass>
        <inertia><ixx>0</ixx><iyy>1.92</iyy><izz>1.92</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>
      <collision name="c"><pose>2.4 0 0 0 1.5707963 0</pose>
        <geometry><cylinder><radius>0.05</radius><length>4.8</length></cylinder></geometry>
      </collision>
    </link>
    <frame name="Cr" attached_to="coupler"><pose relative_to="coupler">4.8 0 0 0 0 0</pose></frame>
    <link name="rocker">
      <pose relative_to="Wr">0 0 0 0 0 {rocker_yaw}</pose>
      <inertial><pose>0 1 0 0 0 0</pose><mass>2</mass>
        <inertia><ixx>0.666667</ixx><iyy>0</iyy><izz>0.666667</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>
    </link>
    <joint name="world_driver" type="revolute">
      <parent>world</parent><child>driver</child>
      <axis><xyz expressed_in="__model__">0 0 1</xyz></axis>
    </joint>
    <joint name="driver_coupler" type="revolute">
      <pose relative_to="Dc"/>
      <parent>driver</parent><child>coupler</child>
      <axis><xyz expressed_in="__model__">0 0 1</xyz></axis>
    </joint>
    <joint name="world_rocker" type="revolute">
      <parent>world</parent><child>rocker</child>
      <axis><xyz>0 0 1</xyz><limit><lower>-3</lower><upper>3</upper><effort>50</effort>
        </limit><dynamics><damping>0.2</damping></dynamics></axis>
    </joint>
    <joint name="{closing_name}" type="{closing_type}">
      <pose relative_to="Cr"/>
      <parent>coupler</parent><child>rocker</child>
      <axis><xyz expressed_in="__model__">0 0 1</xyz></axis>
    </joint>
  </model>
</sdf>
"""


def _four_bar_text(closing_type: str = "revolute", closing_name: str = "coupler_rocker") -> str:
    # crank upright (along y), rocker tip R on the circle of radius 2 about (2, 0) and at 4.8 from
    # the crank tip (-2, 1): pick the solution above the ground
    D = np.array([-2.0, 1.0])
    W = np.array([2.0, 0.0])
    d = np.linalg.norm(W - D)
    a = (4.8**2 - 2.0**2 + d**2) / (2 * d)
    h = math.sqrt(4.8**2 - a**2)
    u = (W - D) / d
    R = D + a * u + h * np.array([-u[1], u[0]])
    coupler_yaw = math.atan2(R[1] - D[1], R[0] - D[0])
    rocker_yaw = math.atan2(R[1] - W[1], R[0] - W[0]) - math.pi / 2  # rocker along its y axis
    return FOUR_BAR.format(
        coupler_yaw=repr(coupler_yaw),
        rocker_yaw=repr(rocker_yaw),
        closing_type=closing_type,
        closing_name=closing_name,
    )


def _load(tmp_path, text, name="m.sdf", **kw):
    path = tmp_path / name
    path.write_text(text)
    return pkdyn.load(path, **kw)


def test_four_bar_loop_closed_by_a_revolute_joint(tmp_path):
    robot = _load(tmp_path, _four_bar_text())
    assert [(c.name, c.kind) for c in robot.closures] == [("coupler_rocker", "hinge")]
    assert robot.nq == 3 and robot.loops == 1
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    assert robot.mobility() == 1
    i = robot.model.joints[robot.model.getJointId("world_rocker")].idx_v
    assert robot.model.damping[i] == 0.2 and robot.model.effortLimit[i] == 50.0
    assert robot.model.upperPositionLimit[i] == 3.0
    assert robot.collision_model.ngeoms == 1
    # the crank turned by 0.3 rad: the rocker tip and the coupler tip meet, at 2 m from Wr
    q0 = robot.q_home.copy()
    q0[0] += 0.3
    q = pkdyn.project(robot, q0)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    tip = data.oMf[robot.model.getFrameId("coupler", pin.BODY)].act(np.array([4.8, 0, 0]))
    assert np.linalg.norm(tip[:2] - [2.0, 0.0]) == pytest.approx(2.0, abs=1e-9)
    crank = data.oMf[robot.model.getFrameId("driver", pin.BODY)].act(np.array([0, 1.0, 0]))
    assert np.linalg.norm(tip - crank) == pytest.approx(4.8, abs=1e-9)


def test_body_frames_are_at_the_file_poses(tmp_path):
    robot = _load(tmp_path, _four_bar_text())
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, pin.neutral(robot.model))
    root = ET.fromstring(_four_bar_text())
    rocker_yaw = float(
        next(p for p in root.iter("pose") if p.get("relative_to") == "Wr").text.split()[5]
    )
    M = data.oMf[robot.model.getFrameId("rocker", pin.BODY)]
    np.testing.assert_allclose(M.translation, [2, 0, 0], atol=1e-15)
    np.testing.assert_allclose(M.rotation, pin.rpy.rpyToMatrix(0, 0, rocker_yaw), atol=1e-15)


@pytest.mark.parametrize("kind,closure,dof", [("ball", "point", 1), ("fixed", "weld", 0)])
def test_ball_and_fixed_cut_joints(tmp_path, kind, closure, dof):
    robot = _load(tmp_path, _four_bar_text(kind))
    assert [c.kind for c in robot.closures] == [closure]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    assert robot.mobility() == dof  # parallel axes keep a ball-closed four-bar planar; weld: rigid


def test_universal_cut_joint_trades_places_with_the_revolute_beside_it(tmp_path):
    axis = '<axis><xyz expressed_in="__model__">0 0 1</xyz></axis>'
    head, tail = _four_bar_text("universal").rsplit(axis, 1)
    text = head + axis + "<axis2><xyz>1 0 0</xyz></axis2>" + tail
    robot = _load(tmp_path, text)
    assert [c.name for c in robot.closures] == ["world_rocker"]  # the revolute closes the loop
    assert robot.model.existJointName("coupler_rocker")
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-9


def test_universal_cut_joint_without_a_revolute_beside_it_is_refused_naming_it(tmp_path):
    axis = '<axis><xyz expressed_in="__model__">0 0 1</xyz></axis>'
    head, tail = _four_bar_text("universal").rsplit(axis, 1)
    text = head + axis + "<axis2><xyz>1 0 0</xyz></axis2>" + tail
    text = text.replace(
        '<joint name="world_rocker" type="revolute">',
        '<joint name="world_rocker" type="prismatic">',
    )
    with pytest.raises(
        pkdyn.DescriptionError, match=r"coupler_rocker'> \(line \d+\).*closes a kinematic loop"
    ):
        _load(tmp_path, text)


def test_drake_ball_and_weld_constraints_in_sdf(tmp_path):
    text = (
        _four_bar_text()
        .replace(
            """    <joint name="coupler_rocker" type="revolute">
      <pose relative_to="Cr"/>
      <parent>coupler</parent><child>rocker</child>
      <axis><xyz expressed_in="__model__">0 0 1</xyz></axis>
    </joint>""",
            """    <drake:ball_constraint>
      <drake:ball_constraint_body_A>coupler</drake:ball_constraint_body_A>
      <drake:ball_constraint_p_AP>4.8 0 0</drake:ball_constraint_p_AP>
      <drake:ball_constraint_body_B>rocker</drake:ball_constraint_body_B>
      <drake:ball_constraint_p_BQ>0 2 0</drake:ball_constraint_p_BQ>
    </drake:ball_constraint>""",
        )
        .replace("<sdf version", '<sdf xmlns:drake="http://drake.mit.edu" version')
    )
    robot = _load(tmp_path, text)
    assert [(c.name, c.kind) for c in robot.closures] == [("ball_constraint1", "point")]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    weld = text.replace(
        "</model>",
        """<frame name="Rtip" attached_to="rocker"><pose relative_to="Cr"/></frame>
        <drake:weld_constraint><parent>Cr</parent><child>Rtip</child></drake:weld_constraint>
        </model>""",
    )
    robot = _load(tmp_path, weld, "w.sdf")
    assert [c.kind for c in robot.closures] == ["point", "weld"]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    assert robot.mobility() == 0


def test_drake_ball_constraint_in_urdf(tmp_path):
    urdf = """<robot name="fb" xmlns:drake="http://drake.mit.edu">
  <link name="ground"/>
  <link name="crank"><inertial><mass value="1"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3"
    iyz="0" izz="1e-3"/></inertial></link>
  <link name="rocker"><inertial><mass value="1"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3"
    iyz="0" izz="1e-3"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="ground"/><child link="crank"/>
    <origin xyz="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="5" velocity="5"/></joint>
  <joint name="j2" type="continuous"><parent link="ground"/><child link="rocker"/>
    <origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint>
  <drake:ball_constraint>
    <drake:ball_constraint_body_A name="crank"/>
    <drake:ball_constraint_p_AP value="0.5 0 0"/>
    <drake:ball_constraint_body_B name="rocker"/>
    <drake:ball_constraint_p_BQ value="-0.5 0 0"/>
  </drake:ball_constraint>
</robot>"""
    robot = _load(tmp_path, urdf, "fb.urdf")
    assert [(c.name, c.kind) for c in robot.closures] == [("ball_constraint1", "point")]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12


# ---------------------------------------------------------------------------------- Cassie


@pytest.mark.skipif(_erd_cassie() is None, reason="example-robot-data is not installed")
def test_example_robot_data_cassie_sdf():
    path = _erd_cassie()
    robot = pkdyn.load(path, geometry=False)
    assert robot.model.joints[1].shortname() == "JointModelFreeFlyer"  # pelvis floats
    kinds = sorted((c.name, c.kind) for c in robot.closures)
    assert kinds == [
        ("left-pitch-rod-joint", "point"),
        ("left-plantar-foot-joint", "point"),
        ("right-pitch-rod-joint", "point"),
        ("right-plantar-foot-joint", "point"),
    ]
    # the file's pose is assembled (cut joints at their own frames)
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12
    # link poses of the file (SDFormat 1.6: in the model frame)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.q_home)
    root = ET.parse(path).getroot()
    for link in root.iter("link"):
        x = np.array([float(t) for t in link.find("pose").text.split()])
        M = data.oMf[robot.model.getFrameId(link.get("name"), pin.BODY)]
        np.testing.assert_allclose(M.translation, x[:3], atol=1e-12)
        np.testing.assert_allclose(M.rotation, pin.rpy.rpyToMatrix(x[3:]), atol=1e-12)
    # 6 + 2 x (10 revolute joints - 2 x 2 independent equations of the planar rod loops)
    assert robot.mobility() == 18
    mob = mobility(robot)
    assert mob.loops == 4


def test_vendored_cassie_sdf_with_its_sidecar():
    robot = pkdyn.load(DATA / "cassie_v2.sdf")
    assert robot.collision_model.ngeoms == 9
    assert [a.name for a in robot.actuators][:2] == ["left-roll-op", "left-yaw-op"]  # sidecar
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12


def test_missing_meshes_warn_once_naming_the_files(tmp_path):
    mesh = (
        '<visual name="v{k}"><geometry><mesh><uri>model://nowhere/part{k}.stl</uri></mesh>'
        "</geometry></visual>"
    )
    text = _four_bar_text().replace(
        '<collision name="c">', mesh.format(k=1) + mesh.format(k=2) + '<collision name="c">'
    )
    with pytest.warns(UserWarning, match=r"2 mesh file\(s\) not found.*part1\.stl, .*part2\.stl"):
        robot = _load(tmp_path, text)
    assert robot.visual_model.ngeoms == 0 and robot.collision_model.ngeoms == 1


# ---------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "edit,culprit",
    [
        (
            (
                'type="revolute">\n      <pose relative_to="Dc"/>',
                'type="gearbox">\n      <pose relative_to="Dc"/>',
            ),
            r"<joint name='driver_coupler'> \(line 36\): gearbox joints are not supported",
        ),
        (
            (
                'type="revolute">\n      <pose relative_to="Dc"/>',
                'type="revolute2">\n      <pose relative_to="Dc"/>',
            ),
            r"line 36\): a revolute2 joint needs <axis2>",
        ),
        (
            ("<child>driver</child>", "<child>drivr</child>"),
            "'drivr', which is not a link or frame",
        ),
        (('<pose relative_to="Wd">', '<pose relative_to="coupler">'), "cycle"),
        (("</model>", '<model name="inner"/></model>'), r"<model name='inner'> \(line \d+\)"),
        (("<mass>2</mass>", "<mass>-2</mass>"), "negative"),
        (
            (
                "</model>",
                '<joint name="x" type="screw"><parent>world</parent><child>rocker</child>'
                "</joint></model>",
            ),
            "screw joints are not supported",
        ),
        (("</model>", '<drake:joint name="p" type="planar"/></model>'), "drake:joint"),
    ],
)
def test_bad_sdf_names_the_element(tmp_path, edit, culprit):
    text = _four_bar_text().replace(*edit)
    if "drake:" in edit[1]:
        text = text.replace("<sdf version", '<sdf xmlns:drake="http://drake.mit.edu" version')
    with pytest.raises(pkdyn.DescriptionError, match=culprit):
        _load(tmp_path, text)


def test_one_model_per_file(tmp_path):
    text = "<sdf version='1.9'><world name='w'><model name='a'/><model name='b'/></world></sdf>"
    with pytest.raises(pkdyn.DescriptionError, match="found 2 models"):
        _load(tmp_path, text)


def test_universal_tree_joint(tmp_path):
    text = """<sdf version="1.9"><model name="u">
      <link name="base"/>
      <link name="cross"><pose>0 0 1 0 0 0.3</pose>
        <inertial><mass>1</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial></link>
      <joint name="fix" type="fixed"><parent>world</parent><child>base</child></joint>
      <joint name="u" type="universal"><parent>base</parent><child>cross</child>
        <axis><xyz>1 0 0</xyz></axis><axis2><xyz>0 1 0</xyz></axis2></joint>
    </model></sdf>"""
    robot = _load(tmp_path, text)
    jm = robot.model.joints[robot.model.getJointId("u")]
    assert jm.shortname() == "JointModelUniversal" and jm.nq == 2
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.array([0.4, -0.7]))
    R = data.oMf[robot.model.getFrameId("cross", pin.BODY)].rotation
    R0 = pin.rpy.rpyToMatrix(0, 0, 0.3)  # the joint frame is the child's (yawed by 0.3)
    expected = (
        R0
        @ pin.AngleAxis(0.4, np.array([1.0, 0, 0])).matrix()
        @ pin.AngleAxis(-0.7, np.array([0, 1.0, 0])).matrix()
    )
    np.testing.assert_allclose(R, expected, atol=1e-12)
