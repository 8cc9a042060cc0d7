"""Import II: Gazebo and Drake dialects, revolute2, missing meshes, xacro, MuJoCo welds, exports.

Physics, not re-runs: pkdyn's Gazebo-dialect four-bar (``tests/data/gazebo_dialect``) read from
its URDF (``<gazebo><joint>``) and from its two SDFormat twins moves and weighs the same way; the
Strandbeest's crank drives every leg (one degree of freedom plus its floating crossbar); MuJoCo
itself counts the weld model's degrees of freedom (3) and the cross-check module compares the
dynamics (``tests/test_mujoco_crosscheck.py``).
"""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.collisions import CollisionChecker
from pkdyn.analysis.mobility import mobility
from pkdyn.exceptions import DescriptionError, ParameterError, PkdynError

PUBLIC = Path(__file__).parent / "data" / "public"
GAZEBO = Path(__file__).parent / "data" / "gazebo_dialect"
STRANDBEEST = PUBLIC / "drake_strandbeest" / "StrandbeestConstraints.urdf.xacro"


def _quiet(load, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load(*args, **kw)


# ------------------------------------------------------------------ Gazebo loops in URDF


def _com(robot: pkdyn.Robot, q: np.ndarray) -> np.ndarray:
    """Centre of mass of the linkage [m]: the same masses, wherever each format puts frames."""
    return np.array(pin.centerOfMass(robot.model, robot.model.createData(), q))


def test_gazebo_joint_closes_the_urdf_four_bar_like_its_sdformat_twin():
    urdf = pkdyn.load(GAZEBO / "four_bar_split_fixed.urdf")
    sdf = pkdyn.load(GAZEBO / "four_bar_split_fixed.sdf")
    whole = pkdyn.load(GAZEBO / "four_bar.sdf")  # the coupler in one piece, the loop in the graph
    assert [(c.name, c.kind) for c in urdf.closures] == [("coupler_splice", "weld")]
    assert [c.kind for c in whole.closures] == ["hinge"]
    assert urdf.mobility() == sdf.mobility() == whole.mobility() == 1 == mobility(urdf).mobility
    # the URDF's assembled configurations, joint by joint, assemble the SDFormat models too, and
    # put the mass at the same place (two importers, three descriptions, one linkage)
    rng = np.random.default_rng(0)
    for _ in range(3):
        q1 = pkdyn.project(
            urdf, pin.integrate(urdf.model, urdf.q_home, 0.3 * rng.standard_normal(urdf.nv))
        )
        assert pkdyn.closure_residual(urdf, q1) < 1e-10
        assert np.linalg.norm(q1 - urdf.q_home) > 1e-2  # it moved
        for other in (sdf, whole):
            q2 = other.q_home.copy()
            for name in ("crank_pivot", "crank_pin", "rocker_pivot", "rocker_pin"):
                if not other.model.existJointName(name):
                    continue  # the joint ``whole`` cuts to close its loop
                a = urdf.model.joints[urdf.model.getJointId(name)]
                b = other.model.joints[other.model.getJointId(name)]
                c, s_ = (
                    q1[a.idx_q : a.idx_q + 2]
                    if a.nq == 2
                    else (np.cos(q1[a.idx_q]), np.sin(q1[a.idx_q]))
                )
                q2[b.idx_q] = np.arctan2(s_, c)
            assert pkdyn.closure_residual(other, q2) < 1e-9
            np.testing.assert_allclose(_com(urdf, q1), _com(other, q2), atol=1e-9)


GAZEBO_BAD = {
    "prismatic closes a loop": (
        'type="fixed">',
        'type="prismatic">',
        "coupler_splice'> type 'prismatic'",
    ),
    "unknown child": (
        "<child>coupler_rear</child>",
        "<child>bar_XX</child>",
        "<child>bar_XX</child>",
    ),
    "no parent": ("<parent>coupler_front</parent>", "", "needs <parent> and <child>"),
    "pose of 5": ("<pose>0.15 0 0 0 0 0</pose>", "<pose>0.15 0 0 0 0</pose>", "<pose>"),
}


@pytest.mark.parametrize("old, new, words", GAZEBO_BAD.values(), ids=list(GAZEBO_BAD))
def test_gazebo_joints_are_never_ignored_silently(old, new, words):
    text = (GAZEBO / "four_bar_split_fixed.urdf").read_text()
    assert old in text
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text.replace(old, new), "g.urdf")
    assert words in str(err.value) and "\n" not in str(err.value)


def test_gazebo_revolute_joint_is_a_hinge_about_its_axis():
    text = (GAZEBO / "four_bar_split_fixed.urdf").read_text()
    text = text.replace('type="fixed">\n      <pose>', 'type="revolute">\n      <pose>').replace(
        "<child>coupler_rear</child>", "<child>coupler_rear</child><axis><xyz>0 0 1</xyz></axis>"
    )
    robot = pkdyn.load_string(text, "g.urdf")
    assert [(c.name, c.kind) for c in robot.closures] == [("coupler_splice", "hinge")]
    assert robot.mobility() == 2  # two bars jointed at E: a five-bar


# ------------------------------------------------------------------ Drake's dialect

DRAKE_URDF = """<?xml version="1.0"?>
<!-- Drake's parser takes comments with -- inside them -->
<robot {ns} name="fourbar">
  <link name="crank"><inertial><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="coupler"><inertial><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="rocker"><inertial><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="a" type="continuous"><parent link="world"/><child link="crank"/>
    <axis xyz="0 0 1"/></joint>
  <joint name="b" type="continuous"><parent link="crank"/><child link="coupler"/>
    <origin xyz="0 1 0"/><axis xyz="0 0 1"/></joint>
  <joint name="d" type="continuous"><parent link="world"/><child link="rocker"/>
    <origin xyz="2 0 0"/><axis xyz="0 0 1"/></joint>
  <drake:ball_constraint>
    <drake:ball_constraint_body_A name="coupler"/>
    <drake:ball_constraint_p_AP value="2 0 0"/>
    <drake:ball_constraint_body_B name="rocker"/>
    <drake:ball_constraint_p_BQ value="0 1 0"/>
  </drake:ball_constraint>
</robot>
"""


@pytest.mark.parametrize(
    "ns",
    ["", 'xmlns:drake="http://drake.mit.edu"', 'xmlns="http://drake.mit.edu"'],
    ids=["drake prefix undeclared", "declared", "drake default namespace"],
)
def test_drake_dialect_implicit_world_undeclared_prefix_and_comments(ns):
    robot = pkdyn.load_string(DRAKE_URDF.format(ns=ns), "drake.urdf")
    assert [(c.name, c.kind) for c in robot.closures] == [("ball_constraint1", "point")]
    assert robot.mobility() == 1 and pkdyn.closure_residual(robot, robot.q_home) < 1e-12


def test_lenient_parsing_still_refuses_entities():
    entity = '<!DOCTYPE robot [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n'
    text = DRAKE_URDF.format(ns="").replace('<?xml version="1.0"?>\n', entity)
    with pytest.raises(DescriptionError, match="entity"):
        pkdyn.load_string(text, "xxe.urdf")
    mjcf = '<!DOCTYPE m [<!ENTITY a "b">]><!-- a -- b --><mujoco><worldbody/></mujoco>'
    with pytest.raises(DescriptionError, match="entity"):
        pkdyn.load_string(mjcf, "xxe.xml")


# ------------------------------------------------------------------ xacro


def test_strandbeest_xacro_loads_with_its_drake_constraints():
    robot = pkdyn.load(STRANDBEEST)
    assert len(robot.closures) == 36 and {c.kind for c in robot.closures} == {"point"}
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-9
    # the crossbar floats (no joint holds it in Drake): 6 + the crank's 1
    assert robot.mobility() == 7 and robot.model.names[1] == "crossbar_root_joint"
    # the crank drives every leg: hold the crossbar and the crank, nothing else moves
    J = robot.closure_set.jacobian(robot.model.createData(), robot.q_home)
    crank = robot.model.joints[robot.model.getJointId("joint_crossbar_crank")].idx_v
    held = np.vstack([J, np.eye(robot.nv)[:6], np.eye(robot.nv)[crank]])
    assert np.linalg.matrix_rank(held, 1e-9 * np.abs(held).max()) == robot.nv


XACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="arm">
  <xacro:arg name="length" default="0.5"/>
  <xacro:property name="L" value="$(arg length)"/>
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="${L/2} 0 0"/><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


def test_xacro_arguments_from_python_and_the_cli(tmp_path):
    path = tmp_path / "arm.urdf.xacro"
    path.write_text(XACRO)
    com = pkdyn.load(path).model.inertias[1].lever[0]
    assert com == pytest.approx(0.25)
    assert pkdyn.load(path, xacro_args={"length": 2}).model.inertias[1].lever[0] == 1.0
    run = subprocess.run(
        [sys.executable, "-m", "pkdyn", "info", str(path), "--xacro-arg", "length:=2", "--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    with pytest.raises(ParameterError, match="xacro_args"):
        pkdyn.load(GAZEBO / "four_bar.sdf", xacro_args={"a": "1"})
    bad = subprocess.run(
        [sys.executable, "-m", "pkdyn", "info", str(path), "--xacro-arg", "length=2"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "NAME:=VALUE" in bad.stderr


@pytest.mark.parametrize(
    "text, words",
    [
        (XACRO.replace("$(arg length)", "${undefined_name}"), "expansion failed"),
        (
            XACRO.replace('<?xml version="1.0"?>', '<!DOCTYPE r [<!ENTITY e "x">]>'),
            "entity",
        ),
    ],
    ids=["undefined property", "entity"],
)
def test_bad_xacro_is_one_line(tmp_path, text, words):
    path = tmp_path / "bad.xacro"
    path.write_text(text)
    with pytest.raises(DescriptionError) as err:
        pkdyn.load(path)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_xacro_package_missing_says_how_to_install(tmp_path, monkeypatch):
    path = tmp_path / "arm.urdf.xacro"
    path.write_text(XACRO)
    monkeypatch.setitem(sys.modules, "xacro", None)
    with pytest.raises(DescriptionError, match=r'pip install "pkdyn\[xacro\]"'):
        pkdyn.load(path)


# ------------------------------------------------------------------ SDFormat revolute2


def test_gazebo_stewart_with_revolute2_joints():
    robot = pkdyn.load(PUBLIC / "gazebo_stewart" / "model.sdf")
    names = list(robot.model.names)
    assert "top_ball1_joint_1" in names and "top_ball1_joint_2" in names
    # each axis with its own limits, from <axis> and <axis2>
    for k in (1, 2):
        j = robot.model.joints[robot.model.getJointId(f"top_ball3_joint_{k}")]
        assert robot.model.upperPositionLimit[j.idx_q] == pytest.approx(0.786)
    assert len(robot.closures) == 6 and {c.kind for c in robot.closures} == {"hinge"}
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-9
    assert robot.mobility() == 12  # base and platform both float: 6 + 6


REV2_LOOP = """<sdf version="1.7"><model name="m">
  <link name="a"><pose>0 1 0 0 0 0</pose><inertial><mass>1</mass>
    <inertia><ixx>0.1</ixx><iyy>0.1</iyy><izz>0.1</izz></inertia></inertial></link>
  <link name="b"><pose>1 1 0 0 0 0</pose><inertial><mass>1</mass>
    <inertia><ixx>0.1</ixx><iyy>0.1</iyy><izz>0.1</izz></inertia></inertial></link>
  <joint name="wa" type="ball"><parent>world</parent><child>a</child>
    <pose>0 -1 0 0 0 0</pose></joint>
  <joint name="ab" type="ball"><parent>a</parent><child>b</child><pose>-1 0 0 0 0 0</pose></joint>
  <joint name="wb" type="revolute2"><parent>world</parent><child>b</child>
    <pose>0 -1 0 0 0 0</pose>
    <axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper></limit>
      <dynamics><damping>0.5</damping></dynamics></axis>
    <axis2><xyz>1 0 0</xyz><limit><lower>-0.2</lower><upper>0.3</upper></limit></axis2>
  </joint>
</model></sdf>"""


def test_revolute2_as_the_cut_joint_of_a_loop():
    robot = pkdyn.load_string(REV2_LOOP, "rev2.sdf")
    cut = [c for c in robot.closures]
    assert [(c.name, c.kind) for c in cut] == [("wb_2", "hinge")]
    j1 = robot.model.joints[robot.model.getJointId("wb_1")]
    assert robot.model.upperPositionLimit[j1.idx_q] == 1.0 and robot.model.damping[j1.idx_v] == 0.5
    np.testing.assert_allclose(cut[0].axis, [1.0, 0.0, 0.0], atol=1e-12)
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12


# ------------------------------------------------------------------ missing meshes


def _with_missing_meshes(fmt: str) -> tuple[str, str]:
    if fmt == "urdf":
        text = (GAZEBO / "four_bar_split_fixed.urdf").read_text()
        text = text.replace(
            '<box size="0.11 0.015 0.015"/>', '<mesh filename="package://nowhere/bar.stl"/>'
        )
        return text, "x.urdf"
    if fmt == "sdf":
        text = (GAZEBO / "four_bar.sdf").read_text()
        start = text.index("<box>")
        end = text.index("</box>", start) + len("</box>")
        return text[:start] + "<mesh><uri>model://nowhere/bar.dae</uri></mesh>" + text[end:], (
            "x.sdf"
        )
    return (PUBLIC / "reachy_mini_mjcf" / "reachy_mini.xml").read_text(), "x.xml"


@pytest.mark.parametrize("fmt", ["urdf", "sdf", "mjcf"])
def test_missing_meshes_load_with_one_warning_and_collision_checks_name_them(fmt):
    text, name = _with_missing_meshes(fmt)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = pkdyn.load_string(text, name, package_dirs=[])
    meshes = [str(w.message) for w in caught if "mesh file(s) not found" in str(w.message)]
    assert len(meshes) == 1 and "kinematics and dynamics are complete" in meshes[0]
    assert robot.missing_meshes and robot.missing_meshes[0] in meshes[0]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-9
    with pytest.raises(PkdynError, match="mesh file") as err:
        CollisionChecker(robot)
    assert robot.missing_meshes[0] in str(err.value)


def test_missing_mesh_that_carries_a_body_mass_says_the_dynamics_are_incomplete():
    text = (
        '<mujoco><asset><mesh name="m" file="gone.stl"/></asset><worldbody><body name="a">'
        '<joint/><geom type="mesh" mesh="m"/><geom size="0.1"/></body></worldbody></mujoco>'
    )
    with pytest.warns(UserWarning, match=r"dynamics are incomplete: a \(gone.stl\)"):
        pkdyn.load_string(text, "x.xml", geometry=False)


def test_viewer_says_which_meshes_it_cannot_draw():
    pytest.importorskip("meshcat")
    from pkdyn.viewer.scene import Scene

    text, name = _with_missing_meshes("urdf")
    robot = _quiet(pkdyn.load_string, text, name, package_dirs=[])
    with pytest.warns(UserWarning, match="package://nowhere/bar.stl"):
        Scene(robot)


# ------------------------------------------------------------------ MuJoCo semantics


def test_weld_torquescale_zero_is_a_point_constraint_at_the_anchor():
    robot = pkdyn.load(PUBLIC / "mujoco_testdata" / "weld.xml")
    kinds = {c.name: c.kind for c in robot.closures}
    assert kinds["anchor no torques"] == "point" and kinds["weak torques"] == "weld"
    assert robot.mobility() == 3  # MuJoCo's own count for this model: beam2 turns about its anchor
    point = next(c for c in robot.closures if c.name == "anchor no torques")
    np.testing.assert_allclose(point.frame2.placement.translation, [0.0, -2.0, 0.0])


def test_onshape_mjcf_closing_sites_are_closed_once():
    robot = _quiet(pkdyn.load, PUBLIC / "reachy_mini_mjcf" / "reachy_mini.xml", geometry=False)
    assert [c.name for c in robot.closures] == [f"connect{k}" for k in range(1, 6)]
    assert robot.mobility() == 15


def test_kangaroo_like_names_the_closure_that_cannot_be_assembled():
    with pytest.raises(pkdyn.LoopClosureError) as err:
        _quiet(pkdyn.load, PUBLIC / "gepetto_kangaroo_like" / "robot.urdf")
    assert "closure 'loop7'" in str(err.value) and "closedloop7_A" in str(err.value)
