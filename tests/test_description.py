"""The pkdyn description format (URDF + ``urn:pkdyn:urdf:1`` elements) and every user error.

Fixtures live in ``tests/data/closures``: a planar four-bar closed by a hinge, a spatial RSSR
four-bar (ball joint, point closure), a chain welded back to its base (universal, prismatic and
spherical joints) and a one-joint pendulum hinged to the base. References are plain Pinocchio
(``pin.buildModelFromUrdf``, forward kinematics) and the numbers written in the fixtures.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.model.description import ConeLimit

DATA = Path(__file__).parent / "data" / "closures"
FOUR_BAR = DATA / "four_bar_hinge.urdf"
RSSR = DATA / "rssr_point.urdf"
WELD = DATA / "weld_universal.urdf"
PENDULUM = DATA / "pendulum_hinge.urdf"

# Closure frames as written in the fixtures: (link, xyz, rpy) of each side.
FIXTURE_CLOSURES = {
    FOUR_BAR: ("hinge", ("coupler", (0.3, 0, 0), (0, 0, 0)), ("rocker", (0.25, 0, 0), (0, 0, 0))),
    RSSR: ("point", ("coupler", (0, 0, 0.269258), (0, 0, 0)), ("rocker", (0, 0, 0.2), (0, 0, 0))),
    WELD: ("weld", ("base", (0, 0, 0.4), (0.3, -0.2, 0.5)), ("tool", (0, 0, 0), (0.3, -0.2, 0.5))),
    PENDULUM: ("hinge", ("bob", (0.2, 0, 0), (0, 0, 0)), ("base", (0.2, 0, 0), (0, 0, 0))),
}


def _edit(path: Path, old: str, new: str) -> str:
    """Fixture text with one exact occurrence of ``old`` replaced."""
    text = path.read_text()
    assert text.count(old) == 1, f"fixture edit {old!r} does not apply to {path.name}"
    return text.replace(old, new)


def _load_text(text: str, source: str = "edited") -> pkdyn.Robot:
    return pkdyn.load_string(text, source, geometry=False)


def _shortnames(robot: pkdyn.Robot) -> dict[str, str]:
    m = robot.model
    return {m.names[j]: m.joints[j].shortname() for j in range(1, m.njoints)}


def _frame_in_world(model: pin.Model, data: pin.Data, link: str, xyz, rpy) -> pin.SE3:
    """World placement of a frame on a link, from plain Pinocchio forward kinematics."""
    M = pin.SE3(pin.rpy.rpyToMatrix(np.array(rpy, dtype=float)), np.array(xyz, dtype=float))
    if link == "base":
        return M
    return data.oMf[model.getFrameId(link, pin.FrameType.BODY)] * M


@pytest.fixture(scope="module")
def delta_robot() -> pkdyn.Robot:
    return pkdyn.load("delta", geometry=False)


# --------------------------------------------------------------------------------------------
# The format
# --------------------------------------------------------------------------------------------


def test_four_bar_sizes_and_joint_types():
    robot = pkdyn.load(FOUR_BAR, geometry=False)
    assert (robot.nq, robot.nv) == (3, 3)
    assert _shortnames(robot) == {
        "crank_joint": "JointModelRY",
        "coupler_joint": "JointModelRY",
        "rocker_joint": "JointModelRY",
    }


def test_hinge_closure_is_two_point_constraints_along_the_axis():
    robot = pkdyn.load(FOUR_BAR, geometry=False)
    assert [c.kind for c in robot.closures] == ["hinge"]
    np.testing.assert_allclose(robot.closures[0].axis, [0, 1, 0])
    assert len(robot.constraint_models) == 2
    assert robot.constraint_owner == ["coupler_rocker", "coupler_rocker"]
    assert all(cm.type == pin.ContactType.CONTACT_3D for cm in robot.constraint_models)
    # Pinocchio's constraint models: two points (6 rows of rank 5); the constraint layer keeps
    # the independent rows: a hinge's 5, of which this planar loop's 2 in-plane ones
    assert robot.constraints.unreduced.nc == 6 and robot.constraints.nc == 2
    # the second point pair is offset from the first along the hinge axis, on both bodies
    cm1, cm2 = robot.constraint_models
    for a, b in (
        (cm1.joint1_placement, cm2.joint1_placement),
        (cm1.joint2_placement, cm2.joint2_placement),
    ):
        offset = b.translation - a.translation
        assert np.linalg.norm(offset) > 1e-3
        np.testing.assert_allclose(np.cross(offset, [0, 1, 0]), 0, atol=1e-12)


def test_planar_four_bar_has_one_degree_of_freedom():
    # Grubler in the plane: 3 joints, one loop of a hinge -> 1 dof (the hinge's 6 spatial
    # equations have rank 2 here)
    robot = pkdyn.load(FOUR_BAR, geometry=False)
    assert robot.mobility() == 1


def test_point_closure_and_spherical_joint():
    robot = pkdyn.load(RSSR, geometry=False)
    assert (robot.nq, robot.nv) == (1 + 4 + 1, 1 + 3 + 1)
    assert _shortnames(robot) == {
        "crank_joint": "JointModelRZ",
        "ball": "JointModelSpherical",
        "rocker_joint": "JointModelRX",
    }
    assert len(robot.constraint_models) == 1
    assert robot.constraint_models[0].type == pin.ContactType.CONTACT_3D
    assert robot.constraint_owner == ["coupler_rocker"]
    assert robot.closure_set.nc == 3
    assert robot.mobility() == 5 - 3


def test_cone_limit_is_parsed():
    robot = pkdyn.load(RSSR, geometry=False)
    (spec,) = robot.description.joints
    assert (spec.name, spec.kind) == ("ball", "spherical")
    assert isinstance(spec.limit, ConeLimit)
    np.testing.assert_allclose(spec.limit.axis, [0, 0, 1])
    assert spec.limit.half_angle == pytest.approx(0.9)


def test_weld_closure_on_the_base_and_universal_joint():
    robot = pkdyn.load(WELD, geometry=False)
    assert (robot.nq, robot.nv) == (1 + 2 + 1 + 4, 1 + 2 + 1 + 3)
    assert _shortnames(robot) == {
        "yaw": "JointModelRZ",
        "cardan": "JointModelUniversal",
        "slide": "JointModelPZ",
        "wrist": "JointModelSpherical",
    }
    (cm,) = robot.constraint_models
    assert cm.type == pin.ContactType.CONTACT_6D
    assert cm.joint1_id == 0  # the base link is the universe joint's body
    assert cm.joint2_id == robot.model.getJointId("wrist")
    assert robot.constraint_owner == ["tool_weld"]
    assert robot.closure_set.nc == 6
    assert robot.mobility() == 7 - 6


def test_universal_joint_turns_about_axis_then_axis2():
    robot = pkdyn.load(WELD, geometry=False)
    model = robot.model
    data = model.createData()
    jid = model.getJointId("cardan")
    rng = np.random.default_rng(1)
    for _ in range(3):
        q = pin.neutral(model)
        a, b = rng.uniform(-1.2, 1.2, 2)
        q[model.joints[jid].idx_q : model.joints[jid].idx_q + 2] = a, b
        pin.forwardKinematics(model, data, q)
        # placeholder <axis xyz="1 0 0"> first, then axis2="0 1 0" in the rotated frame
        R = pin.exp3(np.array([a, 0.0, 0.0])) @ pin.exp3(np.array([0.0, b, 0.0]))
        np.testing.assert_allclose(data.liMi[jid].rotation, R, atol=1e-12)
        np.testing.assert_allclose(data.liMi[jid].translation, [0, 0, 0.1], atol=1e-12)


def test_upgraded_model_keeps_the_urdf_tree():
    robot = pkdyn.load(WELD, geometry=False)
    ref = pin.buildModelFromUrdf(str(WELD))
    m = robot.model
    assert list(m.names) == list(ref.names)
    assert list(m.parents) == list(ref.parents)
    for j in range(1, ref.njoints):
        assert m.jointPlacements[j].isApprox(ref.jointPlacements[j], 1e-12)
        assert m.inertias[j].isApprox(ref.inertias[j], 1e-12)
    # limits of the joints that were not upgraded are kept
    for name in ("yaw", "slide"):
        jm, jr = m.joints[m.getJointId(name)], ref.joints[ref.getJointId(name)]
        for attr in ("lowerPositionLimit", "upperPositionLimit"):
            assert getattr(m, attr)[jm.idx_q] == getattr(ref, attr)[jr.idx_q]
        for attr in ("effortLimit", "velocityLimit"):
            assert getattr(m, attr)[jm.idx_v] == getattr(ref, attr)[jr.idx_v]
    # every body frame of the URDF is still there, on the same joint
    for f in ref.frames:
        if f.type == pin.FrameType.BODY:
            fid = m.getFrameId(f.name, pin.FrameType.BODY)
            assert m.frames[fid].parentJoint == f.parentJoint


def test_actuators_of_the_four_bar():
    robot = pkdyn.load(FOUR_BAR, geometry=False)
    (act,) = robot.actuators
    assert (act.name, act.joint) == ("crank_motor", "crank_joint")
    assert act.reduction == 10.0
    assert (act.effort, act.velocity) == (5.0, 3.0)  # from the joint's <limit>
    jm = robot.model.joints[robot.model.getJointId("crank_joint")]
    assert list(robot.actuated_q) == [jm.idx_q]
    assert list(robot.actuated_v) == [jm.idx_v]
    assert sorted(robot.passive_v) == sorted(set(range(3)) - {jm.idx_v})


def test_actuator_without_reduction_and_prismatic_actuator():
    (crank,) = pkdyn.load(RSSR, geometry=False).actuators
    assert (crank.name, crank.joint, crank.reduction) == ("crank_motor", "crank_joint", 1.0)
    assert (crank.effort, crank.velocity) == (2.0, 6.0)
    robot = pkdyn.load(WELD, geometry=False)
    (screw,) = robot.actuators
    assert (screw.name, screw.joint, screw.reduction) == ("screw", "slide", 2.0)
    assert (screw.effort, screw.velocity) == (100.0, 0.5)
    assert list(robot.actuated_joints) == [robot.model.getJointId("slide")]


def test_platform_frame_and_task():
    robot = pkdyn.load(FOUR_BAR, geometry=False)
    assert list(robot.task_rows) == [0, 2]  # task="x z"
    model = robot.model
    frame = model.frames[robot.platform_frame]
    assert frame.parentJoint == model.getJointId("coupler_joint")
    data = model.createData()
    q = pin.integrate(model, robot.q_home, np.array([0.3, -0.2, 0.1]))
    pin.framesForwardKinematics(model, data, q)
    expected = _frame_in_world(model, data, "coupler", (0.15, 0, 0.05), (0, 0, 0.3))
    assert robot.platform_placement(q).isApprox(expected, 1e-12)


def test_platform_task_defaults_to_the_full_pose():
    robot = pkdyn.load(WELD, geometry=False)
    assert list(robot.task_rows) == list(range(6))
    assert robot.model.frames[robot.platform_frame].parentJoint == robot.model.getJointId("wrist")


@pytest.mark.parametrize("path", list(FIXTURE_CLOSURES), ids=lambda p: p.stem)
def test_home_configuration_closes_the_loops(path):
    robot = pkdyn.load(path, geometry=False)
    kind, (l1, x1, r1), (l2, x2, r2) = FIXTURE_CLOSURES[path]
    model = robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.q_home)
    M1 = _frame_in_world(model, data, l1, x1, r1)
    M2 = _frame_in_world(model, data, l2, x2, r2)
    assert np.linalg.norm(M1.translation - M2.translation) < 1e-10
    if kind == "weld":
        np.testing.assert_allclose(M1.rotation, M2.rotation, atol=1e-10)
    if kind == "hinge":  # the y axes (hinge axis) coincide
        np.testing.assert_allclose(M1.rotation[:, 1], M2.rotation[:, 1], atol=1e-10)


def test_geometry_models_are_built():
    robot = pkdyn.load(FOUR_BAR, geometry=True)
    assert robot.visual_model.ngeoms == 1
    assert robot.visual_model.geometryObjects[0].parentJoint == robot.model.getJointId(
        "coupler_joint"
    )


# --------------------------------------------------------------------------------------------
# User errors: exception type and a message naming the culprit
# --------------------------------------------------------------------------------------------


def test_malformed_xml(tmp_path):
    bad = tmp_path / "broken.urdf"
    bad.write_text(FOUR_BAR.read_text().replace("</robot>", ""))
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load(bad, geometry=False)
    assert err.value.culprit == "XML"
    assert "broken.urdf" in str(err.value)
    assert "malformed" in str(err.value)


def test_root_element_must_be_a_known_format():
    with pytest.raises(pkdyn.DescriptionError, match="<scene>.*cannot tell the format"):
        _load_text("<scene version='1.6'/>")
    with pytest.raises(pkdyn.DescriptionError, match="found 0 models"):
        _load_text("<sdf version='1.6'/>")  # an SDFormat file, but without a model


def test_closure_naming_a_missing_link():
    text = _edit(FOUR_BAR, 'link="rocker" xyz="0.25 0 0"', 'link="rockr" xyz="0.25 0 0"')
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "'rockr'" in str(err.value)
    assert "coupler_rocker" in str(err.value)


def test_unknown_closure_type():
    text = _edit(FOUR_BAR, 'type="hinge"', 'type="hing"')
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "'hing'" in str(err.value)
    assert "coupler_rocker" in str(err.value)


def test_closure_needs_two_frames():
    text = _edit(FOUR_BAR, '<pkdyn:frame link="rocker" xyz="0.25 0 0" rpy="0 0 0"/>', "")
    with pytest.raises(pkdyn.DescriptionError, match="coupler_rocker.*two"):
        _load_text(text)


def test_unknown_pkdyn_joint_type():
    text = _edit(RSSR, 'type="spherical"', 'type="ballsocket"')
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "'ballsocket'" in str(err.value)
    assert "'ball'" in str(err.value)


def test_pkdyn_joint_naming_a_missing_joint():
    text = _edit(RSSR, '<pkdyn:joint name="ball"', '<pkdyn:joint name="bal"')
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "'bal'" in str(err.value)


def test_transmission_naming_a_missing_joint():
    text = _edit(
        FOUR_BAR,
        '<joint name="crank_joint">\n      <hardwareInterface>',
        '<joint name="crank_jnt">\n      <hardwareInterface>',
    )
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "'crank_jnt'" in str(err.value)
    assert "crank_motor" in str(err.value)


_PLAIN = (
    '<robot name="plain"><link name="base"/><link name="arm"/>'
    '<joint name="j" type="revolute"><parent link="base"/><child link="arm"/>'
    '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="4" velocity="2"/></joint>'
    "{transmissions}</robot>"
)


def test_plain_urdf_skips_ros_control_transmissions_pkdyn_cannot_use():
    # without pkdyn elements, transmissions are ros_control metadata: keep the usable ones
    text = _PLAIN.format(
        transmissions='<transmission name="gone"><type>SimpleTransmission</type>'
        '<joint name="removed_joint"/><actuator name="m0"/></transmission>'
        '<transmission name="wrist" type="WristTransmission">'
        '<flexJoint name="j"/><rightActuator name="m1"/></transmission>'
        '<transmission name="diff"><type>transmission_interface/DifferentialTransmission</type>'
        '<joint name="j"/><actuator name="m2"/></transmission>'
        '<transmission name="ok"><type>transmission_interface/SimpleTransmission</type>'
        '<joint name="j"/><actuator name="m3"><mechanicalReduction>-3</mechanicalReduction>'
        "</actuator></transmission>"
    )
    robot = _load_text(text)
    assert [(a.name, a.joint, a.reduction) for a in robot.actuators] == [("m3", "j", -3.0)]
    assert (robot.actuators[0].effort, robot.actuators[0].velocity) == (4.0, 2.0)


def test_ros1_style_reduction_in_the_transmission():
    text = _PLAIN.format(
        transmissions='<transmission name="t" type="pr2_mechanism_model/SimpleTransmission">'
        '<actuator name="m"/><joint name="j"/><mechanicalReduction>50</mechanicalReduction>'
        "</transmission>"
    )
    (act,) = _load_text(text).actuators
    assert (act.name, act.joint, act.reduction) == ("m", "j", 50.0)


def test_transmission_with_invalid_reduction():
    text = _edit(FOUR_BAR, "<mechanicalReduction>10<", "<mechanicalReduction>nan<")
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "crank_transmission" in str(err.value)
    assert "mechanicalReduction" in str(err.value)


@pytest.mark.parametrize(
    "placeholder",
    [
        '<joint name="ball" type="fixed">',
        '<joint name="ball" type="prismatic"><limit lower="-1" upper="1" effort="1" velocity="1"/>',
    ],
    ids=["fixed", "prismatic"],
)
def test_spherical_placeholder_must_be_revolute(placeholder):
    text = _edit(RSSR, '<joint name="ball" type="continuous">', placeholder)
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "pkdyn:joint 'ball'" in str(err.value)


def test_universal_needs_axis2():
    text = _edit(WELD, 'type="universal" axis2="0 1 0"', 'type="universal"')
    with pytest.raises(pkdyn.DescriptionError, match="'cardan'.*axis2"):
        _load_text(text)


def test_universal_axes_must_be_orthogonal():
    text = _edit(WELD, 'axis2="0 1 0"', 'axis2="1 1 0"')
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "'cardan'" in str(err.value)
    assert "orthogonal" in str(err.value)


def test_nan_in_a_closure_frame_xyz():
    text = _edit(FOUR_BAR, 'xyz="0.25 0 0"', 'xyz="nan 0 0"')
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "xyz='nan 0 0'" in str(err.value)


def test_nan_in_a_joint_origin_xyz():
    text = _edit(FOUR_BAR, '<origin xyz="0.3 0 0"', '<origin xyz="0.3 nan 0"')
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "'rocker_joint'" in str(err.value)
    assert "xyz='0.3 nan 0'" in str(err.value)


def test_nan_mass_is_not_silently_dropped():
    # the URDF parser would drop the whole <inertial> (massless link) without a word
    text = _edit(FOUR_BAR, '<mass value="0.4"/>', '<mass value="NaN"/>')
    with pytest.raises(pkdyn.DescriptionError) as err:
        _load_text(text)
    assert "'rocker'" in str(err.value)
    assert "<mass>" in str(err.value)


def test_unknown_robot_name():
    with pytest.raises(pkdyn.UnknownRobotError) as err:
        pkdyn.load("deltaa")
    assert "'deltaa'" in str(err.value)
    assert "delta" in err.value.known


def test_unknown_builder_parameter():
    with pytest.raises(pkdyn.ParameterError) as err:
        pkdyn.load("delta", foo=1)
    assert err.value.name == "foo"
    assert "'foo'" in str(err.value)


@pytest.mark.parametrize("value", [-1, 0.0, "abc", math.nan, math.inf], ids=repr)
def test_invalid_parameter_value(value):
    with pytest.raises(pkdyn.ParameterError) as err:
        pkdyn.load("delta", geometry=False, la=value)
    assert err.value.name == "la"
    assert "'la'" in str(err.value)
    if value == "abc":
        assert "'abc'" in str(err.value)


def test_builder_parameters_are_rejected_for_files():
    with pytest.raises(pkdyn.ParameterError, match="'la'"):
        pkdyn.load(FOUR_BAR, la=0.2)


def test_delta_with_bars_too_short_for_the_home_height():
    # with lb = 0.1 m the nacelle cannot hang 0.35 m below the base
    with pytest.raises(pkdyn.ParameterError) as err:
        pkdyn.load("delta", geometry=False, lb=0.1)
    assert err.value.name == "z_home"
    assert "z_home" in str(err.value)


def test_closure_whose_frames_cannot_meet():
    # coupler and rocker ends at 0.05 m: |B - D| >= 0.2 m > 0.05 + 0.05 m
    text = _edit(FOUR_BAR, 'link="coupler" xyz="0.3 0 0"', 'link="coupler" xyz="0.05 0 0"')
    text = text.replace('link="rocker" xyz="0.25 0 0"', 'link="rocker" xyz="0.05 0 0"')
    with pytest.raises(pkdyn.AssemblyError) as err:
        _load_text(text, "short_four_bar")
    assert not isinstance(err.value, pkdyn.UnreachablePoseError)
    assert err.value.closure == "coupler_rocker"
    assert "'coupler_rocker'" in str(err.value)
    assert err.value.residual > 0.05


def test_forward_geometry_rejects_nan(delta_robot):
    qa = delta_robot.q_home[delta_robot.actuated_q].copy()
    qa[1] = math.nan
    with pytest.raises(pkdyn.InvalidInputError) as err:
        pkdyn.forward_geometry(delta_robot, qa)
    assert "actuated coordinates" in str(err.value)
    assert "#2" in str(err.value)


def test_forward_geometry_rejects_a_wrong_count(delta_robot):
    with pytest.raises(pkdyn.InvalidInputError) as err:
        pkdyn.forward_geometry(delta_robot, [0.1, 0.2])
    assert "expected 3 values, got 2" in str(err.value)


def test_forward_geometry_rejects_a_bad_initial_guess(delta_robot):
    with pytest.raises(pkdyn.InvalidInputError, match="q_init"):
        pkdyn.forward_geometry(
            delta_robot, delta_robot.q_home[delta_robot.actuated_q], q_init=np.zeros(3)
        )


def test_inverse_geometry_of_a_far_pose(delta_robot):
    with pytest.raises(pkdyn.UnreachablePoseError) as err:
        pkdyn.inverse_geometry(delta_robot, [0.0, 0.0, -5.0])
    assert "out of reach" in str(err.value)


def test_inverse_geometry_rejects_a_malformed_pose(delta_robot):
    with pytest.raises(pkdyn.InvalidInputError, match="pose"):
        pkdyn.inverse_geometry(delta_robot, [0.0, math.inf, -0.3])
    with pytest.raises(pkdyn.InvalidInputError, match="3 or 6"):
        pkdyn.inverse_geometry(delta_robot, [0.0, -0.3])


# Malformed documents: each must raise a PkdynError (never a raw RuntimeError / ValueError
# from the parser or from Pinocchio).
_HEAD = '<robot name="r" xmlns:pkdyn="urn:pkdyn:urdf:1"><link name="base"/>'
_ARM = (
    '<link name="arm"><inertial><mass value="1"/>'
    '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>{geom}</link>'
    '<joint name="j" type="{jtype}"><parent link="base"/><child link="arm"/>'
    '<axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
)


def _doc(ext: str = "", jtype: str = "revolute", geom: str = "") -> str:
    return _HEAD + _ARM.format(jtype=jtype, geom=geom) + ext + "</robot>"


def _closure(kind: str, f1: str, f2: str, axis: str = "") -> str:
    return (
        f'<pkdyn:closure name="c" type="{kind}"{axis}>'
        f"<pkdyn:frame {f1}/><pkdyn:frame {f2}/></pkdyn:closure>"
    )


MALFORMED = {
    "empty": "",
    "not xml": "robot name='x'",
    "urdf child missing": _doc().replace('<child link="arm"/>', '<child link="nope"/>'),
    "closure on one body": _doc(_closure("point", 'link="arm"', 'link="arm" xyz="1 0 0"')),
    "closure universe to base": _doc(_closure("point", 'link="universe"', 'link="base"')),
    "closure without name": _doc(_closure("point", 'link="arm"', 'link="base"')).replace(
        'name="c" ', ""
    ),
    "frame without link": _doc(_closure("point", 'xyz="0 0 0"', 'link="base"')),
    "frame xyz two numbers": _doc(_closure("point", 'link="arm" xyz="1 2"', 'link="base"')),
    "frame rpy text": _doc(_closure("point", 'link="arm" rpy="a b c"', 'link="base"')),
    "hinge zero axis": _doc(_closure("hinge", 'link="arm"', 'link="base"', ' axis="0 0 0"')),
    "duplicate closure": _doc(2 * _closure("point", 'link="arm"', 'link="base"')),
    "joint without name": _doc('<pkdyn:joint type="spherical"/>', jtype="continuous"),
    "cone bad angle": _doc(
        '<pkdyn:joint name="j" type="spherical"><pkdyn:cone half_angle="wide"/></pkdyn:joint>',
        jtype="continuous",
    ),
    "pyramid one angle": _doc(
        '<pkdyn:joint name="j" type="spherical"><pkdyn:pyramid half_angles="0.5"/></pkdyn:joint>',
        jtype="continuous",
    ),
    "universal parallel axes": _doc(
        '<pkdyn:joint name="j" type="universal" axis2="2 0 0"/>', jtype="continuous"
    ),
    "platform missing link": _doc('<pkdyn:platform link="nacelle"/>'),
    "platform bad task": _doc('<pkdyn:platform link="arm" task="x y w"/>'),
    "platform empty task": _doc('<pkdyn:platform link="arm" task=""/>'),
    "transmission without joint": _doc(
        '<pkdyn:platform link="arm"/><transmission name="t"><actuator name="m"/></transmission>'
    ),
    "reduction text": _doc(
        '<transmission name="t"><joint name="j"/><actuator name="m">'
        "<mechanicalReduction>ten</mechanicalReduction></actuator></transmission>"
    ),
    "reduction zero": _doc(
        '<transmission name="t"><joint name="j"/><actuator name="m">'
        "<mechanicalReduction>0</mechanicalReduction></actuator></transmission>"
    ),
    "limit effort nan": _doc().replace('effort="1"', 'effort="nan"'),
    "axis inf": _doc().replace('<axis xyz="1 0 0"/>', '<axis xyz="inf 0 0"/>'),
    "inertia nan": _doc().replace('ixx="1"', 'ixx="nan"'),
    "unreachable closure": _doc(_closure("point", 'link="arm"', 'link="base" xyz="0 0 1"')),
}


@pytest.mark.parametrize("text", list(MALFORMED.values()), ids=list(MALFORMED))
def test_malformed_documents_raise_pkdyn_errors(text):
    with pytest.raises(pkdyn.PkdynError) as err:
        pkdyn.load_string(text, "bad.urdf", geometry=True, package_dirs=[])
    assert str(err.value).strip()


def test_unreadable_file_is_a_description_error(tmp_path):
    path = tmp_path / "binary.urdf"
    path.write_bytes(b"\xff\xfe\x00robot")
    with pytest.raises(pkdyn.DescriptionError, match="binary.urdf"):
        pkdyn.load(path)


def test_a_directory_is_not_a_robot(tmp_path):
    with pytest.raises(pkdyn.UnknownRobotError):
        pkdyn.load(tmp_path)


@pytest.mark.parametrize(
    "limit",
    ['<pkdyn:cone axis="0 0 1" half_angle="-0.3"/>', '<pkdyn:pyramid half_angles="0.5 2.0"/>'],
)
def test_bad_passive_limit_names_the_joint(limit):
    text = (
        '<robot name="r" xmlns:pkdyn="urn:pkdyn:urdf:1"><link name="a"/><link name="b"/>'
        '<joint name="s" type="continuous"><parent link="a"/><child link="b"/></joint>'
        f'<pkdyn:joint name="s" type="spherical">{limit}</pkdyn:joint></robot>'
    )
    with pytest.raises(pkdyn.DescriptionError, match="'s'"):
        pkdyn.load_string(text, "lim.urdf", geometry=False)


def test_an_actuated_continuous_joint_drives_one_coordinate():
    """A transmission on a continuous joint: the joint becomes a revolute joint of one
    coordinate (no cos/sin pair), unbounded, with its axis, limits of effort and velocity."""
    text = _doc(
        '<pkdyn:platform link="arm"/><transmission name="t"><joint name="j"/></transmission>',
        jtype="continuous",
    )
    robot = pkdyn.load_string(text, "ok.urdf")
    assert robot.nq == robot.nv == 1 and robot.actuated_q.tolist() == [0]
    assert np.isinf(robot.model.upperPositionLimit[0])
    plain = pkdyn.load_string(
        text.replace('<transmission name="t"><joint name="j"/></transmission>', ""), "plain.urdf"
    )
    assert plain.nq == 2  # unactuated: Pinocchio's unbounded joint, as the URDF parser reads it
