"""URDF+ read as its authors mean it (issue 36, item 1), and written back in pkdyn's format.

The semantics are those of the dialect's reference code (urdfdom fork of mit-biomimetics, the
constraint embedding of ROAM-Lab-ND/generalized_rbda): a loop makes two origins coincide (three
translation rows, whatever its type); a coupling relates the *sums* of the joint coordinates on
the paths from the two links' nearest common ancestor, ``ratio * (predecessor path) =
(successor path)``; ``independent`` (default true; anything but ``true``/``True`` is false)
marks the coordinates a user drives. Checked on the public files and on small descriptions
built here, against hand-derived relations: the MIT Humanoid's ankle rotor turns with knee +
ankle, a chain's rotor with its link, a four-bar's coupler closes on the rocker.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.exceptions import DescriptionError
from pkdyn.model.description import LinearCouplingSpec
from pkdyn.model.formats.urdfplus import read_urdfplus
from pkdyn.model.formats.urdfplus_export import pkdyn_description
from pkdyn.model.formats.xmldoc import parse_xml

DATA = Path(__file__).parent / "data" / "public" / "generalized_rbda"


def _quiet(load, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load(*args, **kw)


def _plus(name: str):
    path = DATA / f"{name}.urdf"
    return _quiet(read_urdfplus, parse_xml(path.read_text(), path.name))


# ------------------------------------------------------------------ what the elements say


def test_four_bar_loop_is_a_point_closure_between_the_two_origins():
    plus = _plus("robot-models/four_bar")
    (c,) = plus.closures
    assert (c.name, c.kind) == ("loop1", "point")
    assert c.frame1.link == "link2" and np.allclose(c.frame1.placement.translation, [1, 0, 0])
    assert c.frame2.link == "link3" and np.allclose(c.frame2.placement.translation, [0.5, 0, 0])
    assert plus.independent == {"joint1": True, "joint2": False, "joint3": False}
    robot = pkdyn.load(DATA / "robot-models" / "four_bar.urdf")
    assert [a.joint for a in robot.actuators] == ["joint1"]
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.q_home)
    p2 = data.oMf[robot.model.getFrameId("link2")].act(np.array([1.0, 0, 0]))
    p3 = data.oMf[robot.model.getFrameId("link3")].act(np.array([0.5, 0, 0]))
    np.testing.assert_allclose(p2, p3, atol=1e-12)  # the two origins coincide at home


def test_a_coupling_relates_sums_along_the_paths_from_the_common_ancestor():
    """The MIT Humanoid leg's ankle rotor is geared to knee + ankle (ratio 12)."""
    couplings = {c.name: dict(c.terms) for c in _plus("robot-models/mit_humanoid_leg").couplings}
    assert couplings["ankle_transmission"] == {
        "knee_to_ankle": 12.0,
        "hipy_to_knee_link": 12.0,
        "hipy_to_ankle_rotor": -1.0,
    }
    assert couplings["knee_transmission"] == {"hipy_to_knee_link": 12.0, "hipy_to_knee_rotor": -1.0}


def test_the_parallel_chains_couple_sums_of_twenty_joints():
    (c,) = _plus("parallel_chains/explicit_depth40_loop_size40").couplings
    terms = dict(c.terms)
    assert len(terms) == 40 and c.offset == 0.0
    assert all(terms[f"joint_1_{k}"] == 1.0 and terms[f"joint_2_{k}"] == -1.0 for k in range(1, 21))


@pytest.mark.parametrize(
    "old, new",
    [
        ("history/four_bar_constraint_position", "robot-models/four_bar"),
        ("history/mini_cheetah_leg_constraint_rolling", "robot-models/mini_cheetah_leg"),
        ("history/mini_cheetah_leg_joint_constraint", "robot-models/mini_cheetah_leg"),
    ],
)
def test_older_spellings_read_as_the_current_ones(old, new):
    a, b = _plus(old), _plus(new)
    assert [c.kind for c in a.closures] == [c.kind for c in b.closures]
    for c, d in zip(a.closures, b.closures, strict=True):
        for f, g in ((c.frame1, d.frame1), (c.frame2, d.frame2)):
            assert f.link == g.link and f.placement.isApprox(g.placement, 1e-15)
    assert [(c.name, c.terms) for c in a.couplings] == [(c.name, c.terms) for c in b.couplings]


def test_loop_constraint_parent_and_child_are_the_two_frames():
    """``<loop_constraint>``: ``<parent link>`` + ``<parent_origin>``, ``<child ...>`` likewise."""
    (c,) = _plus("history/four_bar_loop_constraint").closures
    assert (c.name, c.kind) == ("constraint1", "point")
    assert c.frame1.link == "link3" and np.allclose(c.frame1.placement.translation, [0.3, 0, 0])
    assert c.frame2.link == "link2" and np.allclose(c.frame2.placement.translation, [0.2, 0, 0])


def test_independent_reads_as_the_reference_parser_and_says_so():
    """urdfdom reads anything but ``true``/``True`` as false: ``"fasle"`` is false, with a word."""
    path = DATA / "history" / "four_bar_loop_constraint.urdf"
    with pytest.warns(UserWarning, match=r"independent='fasle'.*read as false"):
        plus = read_urdfplus(parse_xml(path.read_text(), path.name))
    assert plus.independent["joint3"] is False


def test_dependent_joints_no_relation_constrains_are_named():
    with pytest.warns(UserWarning, match=r"10 joint\(s\) declared dependent.*move freely"):
        robot = pkdyn.load(DATA / "robot-models" / "tello_legs.urdf")
    assert robot.mobility() == robot.nv == 20


def test_transmissions_decide_the_actuators_where_a_file_has_them():
    text = (
        (DATA / "robot-models" / "four_bar.urdf")
        .read_text()
        .replace(
            "</robot>",
            '<transmission name="m"><type>transmission_interface/SimpleTransmission</type>'
            '<joint name="joint3"/><actuator name="m"><mechanicalReduction>2</mechanicalReduction>'
            "</actuator></transmission></robot>",
        )
    )
    robot = pkdyn.load_string(text, "four_bar.urdf")
    assert [(a.name, a.joint, a.reduction) for a in robot.actuators] == [("m", "joint3", 2.0)]


def test_independent_joints_that_cannot_be_the_actuators_are_said():
    text = (DATA / "robot-models" / "four_bar.urdf").read_text()
    text = text.replace(
        'name="joint2" type="revolute" independent="false"',
        'name="joint2" type="revolute" independent="true"',
    )
    with pytest.warns(UserWarning, match="related by.*2 coordinates for a mobility of 1"):
        robot = pkdyn.load_string(text, "four_bar.urdf")
    assert robot.actuators == () and robot.mobility() == 1  # not assembled in conflict


def test_continuous_independent_joints_are_actuated_with_one_coordinate():
    """The older four-bar's joints are continuous: the actuated one drives one coordinate."""
    robot = _quiet(pkdyn.load, DATA / "history" / "four_bar_loop_constraint.urdf")
    (a,) = robot.actuators
    jm = robot.model.joints[robot.model.getJointId(a.joint)]
    assert (jm.nq, jm.nv) == (1, 1) and robot.mobility() == 1
    passive = robot.model.joints[robot.model.getJointId("joint2")]
    assert passive.nq == 2  # unactuated continuous joints keep Pinocchio's (cos, sin)


def test_an_unaligned_continuous_joint_keeps_its_axis_when_actuated():
    urdf = (
        '<robot name="u"><link name="base"/><link name="a"><inertial><mass value="1"/>'
        '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="j" type="continuous" independent="true"><parent link="base"/>'
        '<child link="a"/><origin xyz="0.1 0.2 0.3" rpy="0.1 0.2 0.3"/>'
        '<axis xyz="0 -0.6 0.8"/></joint></robot>'
    )
    robot = pkdyn.load_string(urdf, "u.urdf")
    ref = pin.buildModelFromXML(urdf)
    assert robot.nq == 1 and ref.nq == 2
    for angle in (0.3, -2.0, 7.0):  # the same motion: one angle against (cos, sin)
        d1, d2 = robot.model.createData(), ref.createData()
        pin.forwardKinematics(robot.model, d1, np.array([angle]))
        pin.forwardKinematics(ref, d2, np.array([np.cos(angle), np.sin(angle)]))
        assert d1.oMi[1].isApprox(d2.oMi[1], 1e-12)


# ------------------------------------------------------------------ malformed URDF+

BASE = (DATA / "robot-models" / "four_bar.urdf").read_text()
LOOP = BASE[BASE.index("<loop") : BASE.index("</loop>") + len("</loop>")]

BAD = {
    "loop without name": (LOOP.replace(' name="loop1"', ""), "missing attribute 'name'"),
    "loop without type": (LOOP.replace(' type="revolute"', ""), "missing attribute 'type'"),
    "unknown loop type": (LOOP.replace('type="revolute"', 'type="ball"'), "unknown loop type"),
    "missing link": (LOOP.replace('link="link3"', 'link="link9"'), "link 'link9' does not exist"),
    "no successor": (
        LOOP[: LOOP.index("<successor")] + LOOP[LOOP.index("</successor>") + 12 :],
        "missing <successor",
    ),
    "origin of two numbers": (LOOP.replace('xyz="0.5 0.0 0.0"', 'xyz="0.5 0"'), "3 finite"),
    "zero ratio": (
        '<coupling name="c"><predecessor link="link1"/><successor link="link3"/>'
        '<ratio value="0"/></coupling>',
        "non-zero",
    ),
    "ratio text": (
        '<coupling name="c"><predecessor link="link1"/><successor link="link3"/>'
        '<ratio value="six"/></coupling>',
        "is not a number",
    ),
    "ratio without value": (
        '<coupling name="c"><predecessor link="link1"/><successor link="link3"/>'
        "<ratio/></coupling>",
        "needs a value",
    ),
    "coupling to itself": (
        '<coupling name="c"><predecessor link="link1"/><successor link="link1"/></coupling>',
        "to itself",
    ),
    "unknown constraint type": (
        '<constraint name="c" type="gear"><predecessor link="link1"/>'
        '<successor link="link3"/></constraint>',
        "constraint type 'gear'",
    ),
    "joint_constraint without gear ratio": (
        '<joint_constraint name="c"><parent link="link1"/><child link="link3"/></joint_constraint>',
        "missing <gear_ratio",
    ),
    "duplicate names": (LOOP + LOOP, "name 'loop1' is given to two"),
}


@pytest.mark.parametrize("element, words", BAD.values(), ids=list(BAD))
def test_malformed_urdfplus_names_the_element_and_its_line(element, words):
    text = BASE.replace(LOOP, element)
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text, "bad.urdf")
    message = str(err.value)
    assert words in message and "(line " in message and "\n" not in message, message


def test_a_coupling_path_through_a_floating_joint_is_refused():
    text = (
        (DATA / "variable_four_bar" / "four_bar_branch_1_1.urdf")
        .read_text()
        .replace(
            "</robot>",
            '<coupling name="c"><predecessor link="link_1"/><successor link="ground"/></coupling>'
            "</robot>",
        )
    )
    with pytest.raises(DescriptionError, match="'world_to_base' \\(floating\\)"):
        _quiet(pkdyn.load_string, text, "bad.urdf")


# ------------------------------------------------------------------ back to pkdyn's format


@pytest.mark.parametrize(
    "name",
    [
        "robot-models/four_bar",
        "robot-models/six_bar",
        "robot-models/mit_humanoid_leg",
        "robot-models/revolute_rotor_chain",
        "history/four_bar_loop_constraint",
        "parallel_chains/explicit_depth5_loop_size6",
    ],
)
def test_written_in_pkdyn_format_it_loads_as_the_same_robot(name, tmp_path):
    path = DATA / f"{name}.urdf"
    a = _quiet(pkdyn.load, path, repair_inertias=True)
    text = _quiet(pkdyn_description, path.read_text(), path.name, repair_inertias=True)
    assert "<loop" not in text and "independent=" not in text and "pkdyn:" in text
    out = tmp_path / "written.urdf"
    out.write_text(text)
    b = _quiet(pkdyn.load, out)
    assert (a.nq, a.nv, a.mobility()) == (b.nq, b.nv, b.mobility())
    assert [(c.name, c.kind) for c in a.closures] == [(c.name, c.kind) for c in b.closures]
    assert [(c.name, getattr(c, "terms", None)) for c in a.couplings] == [
        (c.name, getattr(c, "terms", None)) for c in b.couplings
    ]
    assert [(x.name, x.joint, x.reduction) for x in a.actuators] == [
        (x.name, x.joint, x.reduction) for x in b.actuators
    ]
    np.testing.assert_allclose(b.q_home, a.q_home, atol=1e-9)
    Ma = pin.crba(a.model, a.model.createData(), a.q_home)
    Mb = pin.crba(b.model, b.model.createData(), a.q_home)
    np.testing.assert_allclose(np.triu(Mb), np.triu(Ma), rtol=0, atol=1e-12 * np.abs(Ma).max())


def test_the_pkdyn_format_refuses_what_only_a_repair_can_write():
    path = DATA / "robot-models" / "planar_leg_linkage.urdf"
    with pytest.raises(DescriptionError, match="triangle inequality.*repair_inertias=True"):
        _quiet(pkdyn_description, path.read_text(), path.name)


def test_a_plain_urdf_is_written_as_it_is():
    path = DATA / "robot-models" / "double_pendulum.urdf"
    assert pkdyn_description(path.read_text(), path.name) == path.read_text()


def test_ignore_elements_reads_the_file_as_a_tree_when_asked():
    with pytest.warns(UserWarning, match="ignored as asked"):
        robot = pkdyn.load(DATA / "robot-models" / "four_bar.urdf", ignore_elements=("loop",))
    assert robot.closures == () and robot.mobility() == 3
    assert not any(isinstance(c, LinearCouplingSpec) for c in robot.couplings)


@pytest.mark.parametrize(
    "name",
    [
        "robot-models/revolute_rotor_chain",
        "robot-models/mit_humanoid_leg",
        "parallel_chains/explicit_depth5_loop_size6",
        "robot-models/four_bar",
    ],
)
def test_the_mjcf_export_reads_back_as_the_same_mechanism(name):
    """Rotor couplings as joint equalities, sums as fixed tendons held by tendon equalities,
    loops as connects: pkdyn's MJCF import reads them back, the same relations by joint name."""
    from pkdyn.model.formats.mjcf import to_mjcf

    robot = _quiet(pkdyn.load, DATA / f"{name}.urdf", geometry=False, repair_inertias=True)
    text = to_mjcf(robot)
    back = _quiet(pkdyn.load_string, text, "export.xml", geometry=False)
    assert (back.nv, back.mobility()) == (robot.nv, robot.mobility())
    assert len(back.couplings) == len(robot.couplings)
    assert len(back.closures) == len(robot.closures)
    q = np.zeros(back.nq)
    for jid in range(1, robot.model.njoints):
        jm = robot.model.joints[jid]
        angle = robot.q_home[jm.idx_q]
        if jm.nq == 2:  # a continuous joint: its angle
            angle = np.arctan2(robot.q_home[jm.idx_q + 1], robot.q_home[jm.idx_q])
        q[back.model.joints[back.model.getJointId(robot.model.names[jid])].idx_q] = angle
    r, _ = back.constraints.residual_and_jacobian(back.model.createData(), q)
    assert float(np.abs(r).max()) < 1e-9  # pkdyn's home satisfies the re-read relations
    if any(isinstance(c, LinearCouplingSpec) and len(c.terms) > 2 for c in robot.couplings):
        assert "<tendon" in text and "<fixed" in text
    if any(len(getattr(c, "terms", ())) == 2 for c in robot.couplings):
        assert re.search(r"<joint [^>]*joint1=", text.split("<equality>")[1])
