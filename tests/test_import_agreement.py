"""Imports that agree with each format's own tools (issue 35, item 3).

- MJCF attributes given with fewer values than their full form are completed as MuJoCo
  completes them (from the default class, else MuJoCo's built-in values), checked against
  MuJoCo itself: the same XML compiled by ``mujoco.MjModel.from_xml_string``, its compiled
  values compared with what pkdyn read; attributes MuJoCo needs in full are refused by both.
- A URDF ``<mimic>`` naming a missing or fixed joint is an error (as documented), unless the
  user leaves the mimics out.
- ``drake:ball_constraint`` needs both its points (Drake's parser requires them).
- A Gazebo ``<gazebo><joint type="ball">`` closes its loop as a point closure.
- An SDFormat ``revolute2`` with parallel axes (one degree of freedom) is refused.
- A malformed visual or collision shape is left out with a warning naming its line (URDF,
  SDFormat; MJCF where the geom carries no mass), and collision checks then say so.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import pkdyn
from pkdyn.analysis.collisions import CollisionChecker
from pkdyn.exceptions import DescriptionError, PkdynError

mujoco = pytest.importorskip("mujoco")

GAZEBO = Path(__file__).parent / "data" / "gazebo_dialect"


def _quiet(load, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load(*args, **kw)


# ------------------------------------------------------------------ MJCF: MuJoCo's own reading


def _model(defaults: str = "", bodies: str = "", after: str = "") -> str:
    return (
        f'<mujoco><compiler angle="radian"/><default>{defaults}</default><worldbody>'
        '<body name="a"><joint name="j1" axis="0 0 1"/><geom type="sphere" size="0.1"/>'
        f'{bodies}</body><body name="b" pos="1 0 0"><joint name="j2" axis="0 0 1"/>'
        f'<geom type="sphere" size="0.1"/></body></worldbody>{after}</mujoco>'
    )


def _body_masses(robot, mj):
    """Body masses of both engines, pkdyn's by body frame name."""
    model = robot.model
    ours = [model.inertias[model.frames[model.getFrameId(n)].parentJoint].mass for n in "ab"]
    return ours, [mj.body_mass[mj.body(n).id] for n in "ab"]


def _polycoef(robot, mj):
    (c,) = robot.description.couplings
    return list(c.coefficients) + [0.0] * (5 - len(c.coefficients)), list(mj.eq_data[0][:5])


def _gear(robot, mj):
    return [a.reduction for a in robot.actuators], list(mj.actuator_gear[:, 0])


def _effort(robot, mj):
    """Joint-side effort limit: ctrlrange x gain x gear (MuJoCo: gainprm[0] x gear[0])."""
    ours = [a.effort for a in robot.actuators]
    theirs = [
        mj.actuator_ctrlrange[k, 1] * mj.actuator_gainprm[k, 0] * mj.actuator_gear[k, 0]
        for k in range(mj.nu)
    ]
    return ours, theirs


def _stiffness(robot, mj):
    ours = [float(robot.passive.stiffness[robot.model.joints[1].idx_v])]
    return ours, [mj.jnt_stiffness[0]]


def _damping(robot, mj):
    return [float(robot.model.damping[0])], [mj.dof_damping[0]]


PARTIAL = {
    "geom size from the class": (
        _model('<geom type="box" size="0.1 0.2 0.3"/>', '<geom size="0.05"/>'),
        _body_masses,
    ),
    "geom size from a nested class": (
        _model(
            '<geom size="0.1 0.2 0.3"/><default class="c"><geom type="box" size="0.4"/></default>',
            '<geom class="c" size="0.01 0.02"/>',
        ),
        _body_masses,
    ),
    "geom size of a sphere with two values": (_model("", '<geom size="0.2 5"/>'), _body_masses),
    "polycoef of one value": (
        _model(after='<equality><joint joint1="j1" joint2="j2" polycoef="0.3"/></equality>'),
        _polycoef,
    ),
    "polycoef of three values": (
        _model(after='<equality><joint joint1="j1" joint2="j2" polycoef="0 2 0.5"/></equality>'),
        _polycoef,
    ),
    "gear of one value over a class": (
        _model(
            '<motor gear="5 1 0 0 0 0"/>',
            after='<actuator><motor joint="j1" gear="3"/><motor joint="j2"/></actuator>',
        ),
        _gear,
    ),
    "gainprm of one value": (
        _model(
            after='<actuator><general joint="j1" gainprm="2" ctrlrange="-1 1"/>'
            '<motor joint="j2" gear="4" ctrlrange="-2 2"/></actuator>'
        ),
        _effort,
    ),
    "stiffness of one value": (
        _model('<joint stiffness="2"/>'),
        _stiffness,
    ),
    "damping of one value": (_model('<joint damping="0.3"/>'), _damping),
}


@pytest.mark.parametrize("xml, read", PARTIAL.values(), ids=list(PARTIAL))
def test_mjcf_attributes_with_fewer_values_read_as_mujoco_compiles_them(xml, read):
    mj = mujoco.MjModel.from_xml_string(xml)
    robot = _quiet(pkdyn.load_string, xml, "partial.xml")
    ours, theirs = read(robot, mj)
    np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=0.0)


REFUSED = {
    "axis of two values": _model(bodies='<body><joint axis="0 1"/><geom size="0.1"/></body>'),
    "range of one value": _model(bodies='<body><joint range="0"/><geom size="0.1"/></body>'),
    "pos of two values": _model(bodies='<geom pos="0 1" size="0.1"/>'),
    "quat of three values": _model(bodies='<geom quat="1 0 0" size="0.1"/>'),
}


@pytest.mark.parametrize("xml", REFUSED.values(), ids=list(REFUSED))
def test_mjcf_attributes_mujoco_needs_in_full_are_refused_by_both(xml):
    with pytest.raises(ValueError, match="enough data"):
        mujoco.MjModel.from_xml_string(xml)
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(xml, "partial.xml")
    assert "line 1" in str(err.value) and "\n" not in str(err.value)


def test_a_polynomial_spring_is_refused_not_linearised():
    """MuJoCo 4 completes ``stiffness="5"`` with its class's higher coefficients."""
    xml = _model('<joint stiffness="1 2 3"/>', after="").replace(
        '<joint name="j1" axis="0 0 1"/>', '<joint name="j1" axis="0 0 1" stiffness="5"/>'
    )
    mj = mujoco.MjModel.from_xml_string(xml)
    assert mj.jnt_stiffness[0] == 5.0 and list(mj.jnt_stiffnesspoly[0]) == [2.0, 3.0]
    with pytest.raises(DescriptionError, match="polynomial stiffness"):
        pkdyn.load_string(xml, "poly.xml")


# ------------------------------------------------------------------ URDF mimic, Drake, Gazebo

MIMIC = (
    '<robot name="m"><link name="base"/>'
    '<link name="a"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
    'ixy="0" ixz="0" iyz="0"/></inertial></link>'
    '<link name="b"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
    'ixy="0" ixz="0" iyz="0"/></inertial></link>'
    '<joint name="ja" type="revolute"><parent link="base"/><child link="a"/>'
    '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    '<joint name="jb" type="{kind}"><parent link="base"/><child link="b"/>'
    '<origin xyz="1 0 0"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" '
    'velocity="1"/><mimic joint="{source}" multiplier="2"/></joint></robot>'
)


@pytest.mark.parametrize(
    "kind, source, words",
    [
        ("revolute", "nowhere", "names joint 'nowhere', which does not exist"),
        ("fixed", "ja", "joint 'jb' is fixed"),
    ],
    ids=["missing source", "fixed joint"],
)
def test_a_mimic_of_a_missing_or_fixed_joint_is_an_error(kind, source, words):
    text = MIMIC.format(kind=kind, source=source)
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text, "m.urdf")
    assert "joint 'jb' <mimic>" in str(err.value) and words in str(err.value)
    with pytest.warns(UserWarning, match="ignored as asked.*1 <mimic>"):
        robot = pkdyn.load_string(text, "m.urdf", ignore_elements=["mimic"])
    assert robot.couplings == ()
    good = pkdyn.load_string(MIMIC.format(kind="revolute", source="ja"), "m.urdf")
    assert [c.name for c in good.couplings] == ["jb_mimic"]


DRAKE_BALL = (
    '<robot name="d" xmlns:drake="http://drake.mit.edu"><link name="world"/>'
    '<link name="a"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
    'ixy="0" ixz="0" iyz="0"/></inertial></link>'
    '<joint name="ja" type="continuous"><parent link="world"/><child link="a"/>'
    '<axis xyz="0 0 1"/></joint>'
    '<drake:ball_constraint><drake:ball_constraint_body_A name="a"/>{p}'
    '<drake:ball_constraint_body_B name="world"/>{q}</drake:ball_constraint></robot>'
)


@pytest.mark.parametrize("missing", ["p_AP", "p_BQ"])
def test_drake_ball_constraint_needs_both_points(missing):
    points = {
        "p": '<drake:ball_constraint_p_AP value="0 0 0"/>',
        "q": '<drake:ball_constraint_p_BQ value="0 0 0"/>',
    }
    points["p" if missing == "p_AP" else "q"] = ""
    with pytest.raises(DescriptionError, match=f"missing drake:ball_constraint_{missing}"):
        pkdyn.load_string(DRAKE_BALL.format(**points), "d.urdf")


def test_gazebo_ball_joint_is_a_point_closure():
    """Documented as a point closure: it closes the loop on the three translations."""
    text = (GAZEBO / "four_bar_split_fixed.urdf").read_text()
    assert 'type="fixed">' in text
    robot = _quiet(pkdyn.load_string, text.replace('type="fixed">', 'type="ball">'), "g.urdf")
    assert [(c.name, c.kind) for c in robot.closures] == [("coupler_splice", "point")]
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-9
    weld = _quiet(pkdyn.load_string, text, "g.urdf")
    assert robot.mobility() > weld.mobility()  # three rotations freed at the splice


# ------------------------------------------------------------------ SDFormat revolute2

SDF_R2 = """<sdf version="1.7"><model name="r2">
  <link name="base"/>
  <link name="arm"><inertial><mass>1</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy>
    <izz>0.01</izz></inertia></inertial></link>
  <joint name="fix" type="fixed"><parent>world</parent><child>base</child></joint>
  <joint name="r2" type="revolute2"><parent>base</parent><child>arm</child>
    <axis><xyz>0 0 1</xyz></axis><axis2><xyz>{axis2}</xyz></axis2></joint>
</model></sdf>"""


def test_sdf_revolute2_with_parallel_axes_is_refused():
    robot = pkdyn.load_string(SDF_R2.format(axis2="1 0 0"), "r2.sdf")
    assert robot.nv == 2
    for axis2 in ("0 0 1", "0 0 -2"):
        with pytest.raises(DescriptionError) as err:
            pkdyn.load_string(SDF_R2.format(axis2=axis2), "r2.sdf")
        assert "<joint name='r2'> (line 6)" in str(err.value) and "parallel" in str(err.value)


# ------------------------------------------------------------------ malformed shapes

SDF_SHAPES = """<sdf version="1.7"><model name="s">
  <link name="base"/>
  <link name="arm"><inertial><mass>1</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy>
    <izz>0.01</izz></inertia></inertial>
    <visual name="v"><geometry><sphere><radius> 0.1" </radius></sphere></geometry></visual>
    <collision name="c"><geometry><box><size>0.1 0.1</size></box></geometry></collision>
    <collision name="ok"><geometry><sphere><radius>0.05</radius></sphere></geometry></collision>
  </link>
  <joint name="fix" type="fixed"><parent>world</parent><child>base</child></joint>
  <joint name="j" type="revolute"><parent>base</parent><child>arm</child>
    <axis><xyz>0 0 1</xyz></axis></joint>
</model></sdf>"""


def test_sdf_malformed_shapes_are_left_out_naming_their_line():
    """The public Gazebo Stewart platform's typo (``0.1"``) costs one shape, not the robot."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = pkdyn.load_string(SDF_SHAPES, "s.sdf")
    messages = [str(w.message) for w in caught if "left out" in str(w.message)]
    assert any("line 5" in m and "visual shape is left out" in m for m in messages), messages
    assert any("line 6" in m and "collision shape is left out" in m for m in messages), messages
    assert len(robot.visual_model.geometryObjects) == 0
    assert len(robot.collision_model.geometryObjects) == 1
    with pytest.raises(PkdynError, match="left out when it was loaded.*line 6"):
        CollisionChecker(robot)


def test_mjcf_malformed_geom_without_mass_is_left_out_with_mass_is_refused():
    geoms = '<geom type="box" size="0.1 nan 0.1"/><geom type="sphere" size="0.1"/>'
    inertial = '<inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>'
    xml = (
        f'<mujoco><worldbody><body name="a"><joint name="j"/>{inertial}{geoms}</body>'
        "</worldbody></mujoco>"
    )
    with pytest.warns(UserWarning, match=r"<geom> \(line 1\).*collision geom is left out"):
        robot = pkdyn.load_string(xml, "g.xml")
    assert len(robot.collision_model.geometryObjects) == 1 and robot.dropped_collisions
    with pytest.raises(DescriptionError, match="NaN"):  # the geoms give the body its mass
        pkdyn.load_string(xml.replace(inertial, ""), "g.xml")
