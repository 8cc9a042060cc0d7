"""Importers under careless or hostile input: one line per bad input, bounded work, no crash.

Each class of issue 29's (and issue 24's inertia) probes is one parametrised test, named after
the class; each case is one bad input and the words the one-line error must contain.
"""

from __future__ import annotations

import subprocess
import sys
import time
import warnings

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.exceptions import DescriptionError, InvalidInputError, JointLimitError, PkdynError

MJCF = """<mujoco model="m">{compiler}
  <default>{defaults}</default>
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="j" axis="{axis}" {joint}/>
      <geom size="0.1" {geom}/>
      {inertial}
      <body name="b" pos="0.2 0 0" {orient}><joint name="k"/><geom size="0.1"/></body>
    </body>
  </worldbody>
  {extra}
</mujoco>"""


def mjcf(**kw: str) -> str:
    base = dict(
        compiler="",
        defaults="",
        axis="0 0 1",
        joint="",
        geom="",
        inertial="",
        orient="",
        extra="",
    )
    base.update(kw)
    return MJCF.format(**base)


SDF = """<sdf version="1.9"><model name="s">
  <link name="a"><pose>0 0 1 0 0 0</pose>
    <inertial><mass>{mass}</mass><inertia><ixx>{ixx}</ixx><iyy>1</iyy><izz>1</izz></inertia>
    </inertial>
    <collision name="c"><geometry>{shape}</geometry></collision>
    <visual name="v"><geometry><sphere><radius>0.1</radius></sphere></geometry>
      <material><diffuse>{colour}</diffuse></material></visual>
  </link>
  <joint name="j" type="revolute"><parent>world</parent><child>a</child>
    <pose {pose_attrs}>{pose}</pose><axis><xyz>{axis}</xyz></axis></joint>
  {extra}
</model></sdf>"""


def sdf(**kw: str) -> str:
    base = dict(
        mass="1",
        ixx="1",
        shape="<box><size>0.1 0.1 0.1</size></box>",
        colour="1 0 0 1",
        pose_attrs="",
        pose="0 0 0 0 0 0",
        axis="0 0 1",
        extra="",
    )
    base.update(kw)
    return SDF.format(**base)


def _one_line(err: BaseException, *words: str) -> None:
    message = str(err)
    assert "\n" not in message, message
    for w in words:
        assert w in message, message


# ------------------------------------------------------------------ inputs never type-checked

NOT_INTEGERS = {
    "contype 1.5": mjcf(geom='contype="1.5"'),
    "conaffinity abc": mjcf(geom='conaffinity="abc"'),
    "group nan": mjcf(geom='group="nan"'),
    "inertiagrouprange x": mjcf(compiler='<compiler inertiagrouprange="0 x"/>'),
}


@pytest.mark.parametrize("text", NOT_INTEGERS.values(), ids=list(NOT_INTEGERS))
def test_mjcf_attributes_that_are_not_integers(text):
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text, "m.xml")
    _one_line(err.value, "expected integer", "line")


PINOCCHIO_REJECTS = {
    "negative density": (mjcf(geom='density="-1"'), "density=-1 is negative"),
    "negative geom mass": (mjcf(geom='mass="-2"'), "mass=-2 is negative"),
    "negative inertial mass": (
        mjcf(inertial='<inertial pos="0 0 0" mass="-1" diaginertia="1 1 1"/>'),
        "mass -1 kg is negative",
    ),
    "negative moment": (
        mjcf(inertial='<inertial pos="0 0 0" mass="1" diaginertia="-1 1 1"/>'),
        "not positive semi-definite",
    ),
    "overflowing geom": (mjcf(geom='pos="1e200 0 0"'), "not finite"),
}


@pytest.mark.parametrize("text, words", PINOCCHIO_REJECTS.values(), ids=list(PINOCCHIO_REJECTS))
def test_mjcf_mass_density_inertia_pinocchio_rejects(text, words):
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text, "m.xml")
    _one_line(err.value, words)


def _nested_bodies(n: int) -> str:
    inner = "".join(
        f'<body name="b{i}" pos="0 0 0.01"><joint/><geom size="0.01"/>' for i in range(n)
    )
    return f"<mujoco><worldbody>{inner}{'</body>' * n}</worldbody></mujoco>"


def _nested_frames(n: int) -> str:
    inner = '<frame pos="0 0 0.01">' * n + '<body name="x"><joint/><geom size="0.1"/></body>'
    return f"<mujoco><worldbody>{inner}{'</frame>' * n}</worldbody></mujoco>"


def _nested_defaults(n: int) -> str:
    inner = "".join(f'<default class="c{i}">' for i in range(n)) + "</default>" * n
    return mjcf(defaults=inner)


def _sdf_chain(n: int) -> str:
    frames = "".join(
        f'<frame name="f{i}" attached_to="{"a" if i == 0 else f"f{i - 1}"}">'
        f'<pose relative_to="{"a" if i == 0 else f"f{i - 1}"}">0 0 0.001 0 0 0</pose></frame>'
        for i in range(n)
    )
    return sdf(pose_attrs=f'relative_to="f{n - 1}"', extra=frames)


def _deep_yaml(tmp_path, n: int):
    (tmp_path / "r.urdf").write_text(
        '<robot name="r"><link name="base"/><link name="a"/><joint name="j" type="revolute">'
        '<parent link="base"/><child link="a"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    (tmp_path / "r.yaml").write_text("closed_loop: " + "[" * n + "]" * n + "\n")
    return tmp_path / "r.urdf"


DEEP = {
    "300 nested bodies": (lambda tmp: _nested_bodies(300), "nested deeper than 200"),
    "500 nested frames": (lambda tmp: _nested_frames(500), "nested deeper than 200"),
    "150 nested default classes": (lambda tmp: _nested_defaults(150), "deeper than 100"),
}


@pytest.mark.parametrize("make, words", DEEP.values(), ids=list(DEEP))
def test_deep_nesting_is_refused_with_a_clear_message(tmp_path, make, words):
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(make(tmp_path), "deep.xml")
    _one_line(err.value, words)


def test_deep_sdf_frame_chain_is_walked_iteratively():
    robot = pkdyn.load_string(_sdf_chain(3000), "chain.sdf", geometry=False)  # no RecursionError
    assert robot.mobility() == 1
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, robot.q_home)
    assert data.oMi[1].translation[2] == pytest.approx(1.0 + 3.0, abs=1e-9)  # 3000 x 1 mm


def test_deep_yaml_sidecar_is_refused(tmp_path):
    with pytest.raises(DescriptionError) as err:
        pkdyn.load(_deep_yaml(tmp_path, 3000))
    _one_line(err.value, "nested deeper than 50")


SDF_COUNTS = {
    "box size of 2": (sdf(shape="<box><size>1 1</size></box>"), "expected 3 finite numbers"),
    "cylinder radius of 2": (
        sdf(shape="<cylinder><radius>1 2</radius><length>1</length></cylinder>"),
        "expected 1 finite numbers",
    ),
    "colour of 2": (sdf(colour="1 0"), "a colour is 3 or 4 numbers"),
}


@pytest.mark.parametrize("text, words", SDF_COUNTS.values(), ids=list(SDF_COUNTS))
def test_sdf_geometry_with_the_wrong_number_of_values(text, words):
    """The shape is left out with one warning naming it and its line; the robot loads."""
    with pytest.warns(UserWarning, match="shape is left out") as caught:
        robot = pkdyn.load_string(text, "s.sdf")
    (message,) = [str(w.message) for w in caught if "left out" in str(w.message)]
    assert words in message and "line" in message and "\n" not in message
    assert robot.nv > 0


# absurd axes: either read exactly (a unit vector from huge components) or refused, never
# an overflow that turns into a zero axis and a singular mass matrix (an SVD failure later)
ABSURD_AXES = {
    "mjcf 1e308": (lambda: pkdyn.load_string(mjcf(axis="1e308 1e308 0"), "m.xml"), None),
    "sdf 1e308": (lambda: pkdyn.load_string(sdf(axis="1e308 0 1e308"), "s.sdf"), None),
    "urdf 1e308": (
        lambda: pkdyn.load_string(
            '<robot name="r"><link name="base"/><link name="a"><inertial><mass value="1"/>'
            '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>'
            '<joint name="j" type="revolute"><parent link="base"/><child link="a"/>'
            '<axis xyz="1e308 1e308 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/>'
            "</joint></robot>",
            "u.urdf",
        ),
        "length overflows",
    ),
    "mjcf 1e-320": (lambda: pkdyn.load_string(mjcf(axis="1e-320 0 0"), "m.xml"), "zero axis"),
}


@pytest.mark.parametrize("load, words", ABSURD_AXES.values(), ids=list(ABSURD_AXES))
def test_absurd_axes(load, words):
    if words is not None:
        with pytest.raises(DescriptionError) as err:
            load()
        _one_line(err.value, words)
        return
    robot = load()
    M = pin.crba(robot.model, robot.model.createData(), robot.q_home)
    assert np.all(np.isfinite(M)) and np.linalg.eigvalsh(0.5 * (M + M.T)).min() > 0.0


# ------------------------------------------------------------------ unbounded work


def test_include_tree_that_multiplies_is_capped(tmp_path):
    levels = 7
    for k in range(levels):
        body = "".join(f'<include file="f{k + 1}.xml"/>' for _ in range(10))
        (tmp_path / f"f{k}.xml").write_text(f"<mujoco>{body}</mujoco>")
    (tmp_path / f"f{levels}.xml").write_text("<mujoco/>")
    (tmp_path / "top.xml").write_text(
        '<mujoco><include file="f0.xml"/><worldbody><body><joint/><geom size="1"/></body>'
        "</worldbody></mujoco>"
    )
    start = time.perf_counter()
    with pytest.raises(DescriptionError) as err:
        pkdyn.load(tmp_path / "top.xml")
    assert time.perf_counter() - start < 5.0
    _one_line(err.value, "more than 100 <include>")


def test_mjcf_with_1e5_bodies_is_refused_up_front():
    text = (
        "<mujoco><worldbody>" + '<body><geom size="1"/></body>' * 100_001 + "</worldbody></mujoco>"
    )
    start = time.perf_counter()
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text, "big.xml")
    assert time.perf_counter() - start < 10.0
    _one_line(err.value, "more than 10000 bodies")


# ------------------------------------------------------------------ silent wrong answers


def test_zero_norm_quaternions_are_refused():
    text = mjcf(extra='<keyframe><key name="home" qpos="0.1 0.2"/></keyframe>')
    assert pkdyn.load_string(text, "m.xml").mobility() == 2  # the well-formed key loads
    free = (
        '<mujoco><worldbody><body name="f"><freejoint/><geom size="0.1"/></body></worldbody>'
        '<keyframe><key name="home" qpos="0 0 1 0 0 0 0"/></keyframe></mujoco>'
    )
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(free, "m.xml")
    _one_line(err.value, "quaternion", "is zero")
    ok = free.replace("0 0 1 0 0 0 0", "0 0 1 1 0 0 0")
    robot = pkdyn.load_string(ok, "m.xml")
    with pytest.raises(InvalidInputError) as err:
        pkdyn.load_string(ok, "m.xml", home=np.zeros(robot.nq))
    _one_line(err.value, "joint 'f_joint'", "norm 0")


def test_home_outside_the_joint_limits_is_refused_like_fk():
    robot = pkdyn.load("delta")
    hi = robot.model.upperPositionLimit[robot.actuated_q]
    with pytest.raises(JointLimitError):
        pkdyn.forward_geometry(robot, hi + 0.5)
    with pytest.raises(JointLimitError) as err:
        pkdyn.load("delta", home=hi + 0.5)
    _one_line(err.value, robot.actuators[0].joint)
    run = subprocess.run(
        [sys.executable, "-m", "pkdyn", "info", "delta", "--home", *map(str, hi + 0.5)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 1
    assert run.stderr.startswith("pkdyn: error: ") and run.stderr.count("\n") == 1


NOT_PHYSICAL = {
    "mjcf negative armature": (mjcf(joint='armature="-0.1"'), "armature='-0.1' is negative"),
    "mjcf negative damping": (mjcf(joint='damping="-1"'), "damping='-1' is negative"),
    "mjcf triangle inequality": (
        mjcf(inertial='<inertial pos="0 0 0" mass="1" diaginertia="1 1 3"/>'),
        "triangle inequality",
    ),
    "mjcf zero inertia": (
        mjcf(inertial='<inertial pos="0 0 0" mass="1" diaginertia="0 0 0"/>'),
        "all-zero inertia tensor",
    ),
    "sdf triangle inequality": (sdf(ixx="3"), "triangle inequality"),
    "sdf negative mass": (sdf(mass="-1"), "mass -1 kg is negative"),
    "sdf quat_xyzw 0 0 0 0": (
        sdf(pose_attrs='rotation_format="quat_xyzw"', pose="0 0 0 0 0 0 0"),
        "non-zero quaternion",
    ),
}


@pytest.mark.parametrize("text, words", NOT_PHYSICAL.values(), ids=list(NOT_PHYSICAL))
def test_non_physical_values_are_refused(text, words):
    name = "s.sdf" if text.startswith("<sdf") else "m.xml"
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text, name)
    _one_line(err.value, words)


def test_zero_inertia_is_refused_in_pkdyn_descriptions_and_kept_as_a_point_mass_in_plain_urdf():
    link = (
        '<link name="a"><inertial><mass value="1"/>'
        '<inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>'
    )
    joint = (
        '<joint name="j" type="revolute"><parent link="base"/><child link="a"/>'
        '<origin xyz="0.1 0 0"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    )
    plain = f'<robot name="r"><link name="base"/>{link}{joint}</robot>'
    assert pkdyn.load_string(plain, "plain.urdf").mobility() == 1  # a point mass off the axis
    ns = 'xmlns:pkdyn="urn:pkdyn:urdf:1"'
    strict = plain.replace('<robot name="r">', f'<robot name="r" {ns}>').replace(
        "</robot>", '<pkdyn:platform link="a"/></robot>'
    )
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(strict, "strict.urdf")
    _one_line(err.value, "link 'a'", "all-zero inertia tensor")


def test_huge_xyaxes_give_a_rotation():
    robot = pkdyn.load_string(mjcf(orient='xyaxes="1e300 1e300 0 -1e300 1e300 0"'), "m.xml")
    R = robot.model.jointPlacements[2].rotation
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-12) and np.linalg.det(R) == pytest.approx(1)
    assert np.allclose(R[:, 0], [2**-0.5, 2**-0.5, 0.0])


@pytest.mark.parametrize("xyz", ["'100'", "true", "[1, 2]", "{a: 1}"])
def test_sidecar_xyz_must_be_three_numbers(tmp_path, xyz):
    (tmp_path / "r.urdf").write_text(
        '<robot name="r"><link name="base"/><link name="a"/><joint name="j" type="revolute">'
        '<parent link="base"/><child link="a"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    (tmp_path / "r.yaml").write_text(f"platform: {{frame: a, xyz: {xyz}}}\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(PkdynError) as err:
            pkdyn.load(tmp_path / "r.urdf")
    _one_line(err.value, "platform.xyz")
