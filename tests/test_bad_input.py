"""Bad input, class by class: each case raises the documented error type, whose message names
the culprit (element, parameter, option, file) - never a traceback, a hang, a crash or a silent
wrong answer.

Classes: descriptions (numbers, physics, tree, pkdyn elements, namespace, meshes), sizes that
would exhaust memory or crash Pinocchio, builder parameters, geometric-model inputs, numeric
arguments of the analyses and of the dynamics, bounded work, simulation faults, outputs.
"""

from __future__ import annotations

import pytest

import pkdyn
from pkdyn.exceptions import (
    DescriptionError,
)

# --------------------------------------------------------------------------------------------
# descriptions

NS = 'xmlns:pkdyn="urn:pkdyn:urdf:1"'
INERTIA = '<inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/>'


def doc(
    mass="1",
    inertia=("0.01", "0.01", "0.01"),
    geom='<cylinder radius="0.01" length="0.3"/>',
    axis="0 0 1",
    limit='lower="-1" upper="1" effort="5" velocity="3"',
    extra="",
    ns=NS,
    arm_parent="base",
    transmissions=1,
) -> str:
    """A pendulum (``arm`` on revolute ``j``) hinged back to the base by a closure, a pkdyn
    description; each argument is one thing a case breaks."""
    ixx, iyy, izz = inertia
    trans = "".join(
        f'<transmission name="t{k}"><type>transmission_interface/SimpleTransmission</type>'
        f'<joint name="j"/><actuator name="m{k}"><mechanicalReduction>1</mechanicalReduction>'
        "</actuator></transmission>"
        for k in range(transmissions)
    )
    return (
        f'<robot name="bad" {ns}><link name="base"/>'
        f'<link name="arm"><inertial><mass value="{mass}"/>'
        + INERTIA.format(ixx=ixx, iyy=iyy, izz=izz)
        + f"</inertial><collision><geometry>{geom}</geometry></collision></link>"
        f'<joint name="j" type="revolute"><parent link="{arm_parent}"/><child link="arm"/>'
        f'<axis xyz="{axis}"/><limit {limit}/></joint>'
        '<pkdyn:closure name="c" type="hinge"><pkdyn:frame link="arm"/>'
        '<pkdyn:frame link="base"/></pkdyn:closure>'
        '<pkdyn:platform link="arm" task="rz"/>'
        f"{trans}{extra}</robot>"
    )


def test_the_base_document_is_valid():
    robot = pkdyn.load_string(doc(), "ok.urdf", geometry=True)
    assert robot.nv == 1 and len(robot.closures) == 1 and len(robot.actuators) == 1


BAD_DESCRIPTIONS = {
    # masses
    "negative mass": (doc(mass="-1"), "link 'arm' <mass value='-1'>"),
    "zero mass": (doc(mass="0"), "link 'arm' <mass value='0'>"),
    "nan mass": (doc(mass="nan"), "link 'arm' <mass> attribute value='nan'"),
    "text mass": (doc(mass="heavy"), "link 'arm' <mass> attribute value='heavy'"),
    # inertias
    "negative moment": (doc(inertia=("-0.01", "0.01", "0.01")), "link 'arm' <inertia>"),
    "indefinite inertia": (
        doc(inertia=("0.01", "0.01", "0.01")).replace('ixy="0"', 'ixy="0.05"'),
        "not positive semi-definite",
    ),
    "triangle violated": (doc(inertia=("0.01", "0.01", "0.05")), "triangle inequality"),
    "text inertia": (doc(inertia=("a", "0.01", "0.01")), "<inertia> attribute ixx='a'"),
    # geometry sizes (would silently drop the body from the collision checks)
    "nan radius": (doc(geom='<sphere radius="nan"/>'), "<sphere> attribute radius='nan'"),
    "inf length": (doc(geom='<cylinder radius="0.01" length="inf"/>'), "length='inf'"),
    "negative box": (doc(geom='<box size="0.1 -0.2 0.1"/>'), "<box> attribute size="),
    "zero radius": (doc(geom='<sphere radius="0"/>'), "<sphere> attribute radius='0'"),
    "box two sizes": (doc(geom='<box size="0.1 0.2"/>'), "expected 3 numbers"),
    "zero mesh scale": (
        doc(geom='<mesh filename="x.stl" scale="0 1 1"/>'),
        "<mesh> attribute scale='0 1 1'",
    ),
    # joints
    "zero axis": (doc(axis="0 0 0"), "joint 'j' <axis xyz='0 0 0'>"),
    "inverted limits": (doc(limit='lower="1" upper="-1" effort="5" velocity="3"'), "lower='1'"),
    "negative effort": (doc(limit='lower="-1" upper="1" effort="-5" velocity="3"'), "effort"),
    # tree
    "own parent": (doc(arm_parent="arm"), "joint 'j'"),
    "two parents": (
        doc(
            extra='<link name="b2"/><joint name="j2" type="fixed"><parent link="b2"/>'
            '<child link="arm"/></joint>'
        ),
        "joint 'j2'",
    ),
    "cycle": (
        doc(
            extra='<link name="x"/><link name="y"/>'
            '<joint name="jx" type="fixed"><parent link="y"/><child link="x"/></joint>'
            '<joint name="jy" type="fixed"><parent link="x"/><child link="y"/></joint>'
        ),
        "cycle",
    ),
    "unknown parent link": (doc(arm_parent="nowhere"), "joint 'j' <parent link='nowhere'>"),
    # pkdyn elements
    "two transmissions on one joint": (doc(transmissions=2), "transmission 't1'"),
    "duplicate pkdyn:joint": (
        doc(
            extra='<pkdyn:joint name="j" type="spherical"/><pkdyn:joint name="j" type="spherical"/>'
        ),
        "pkdyn:joint 'j'",
    ),
    "two platforms": (doc(extra='<pkdyn:platform link="base"/>'), "<pkdyn:platform>"),
    "unknown pkdyn element": (doc(extra='<pkdyn:closur name="x"/>'), "<pkdyn:closur>"),
    "mistyped namespace": (doc(ns='xmlns:pkdyn="urn:pkdyn:urdf:2"'), "urn:pkdyn:urdf:2"),
    "misspelt namespace": (doc(ns='xmlns:pkdyn="urn:pkydn:urdf:1"'), "urn:pkydn:urdf:1"),
    "missing mesh": (
        doc(geom='<mesh filename="package://nowhere/meshes/arm.stl"/>'),
        "link 'arm' <mesh filename='package://nowhere/meshes/arm.stl'>",
    ),
}


@pytest.mark.parametrize("text, culprit", BAD_DESCRIPTIONS.values(), ids=list(BAD_DESCRIPTIONS))
def test_bad_descriptions_name_the_element(text, culprit):
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text, "bad.urdf", geometry=True, package_dirs=[])
    message = str(err.value)
    assert culprit in message, message
    assert message.startswith("bad.urdf: ") and "\n" not in message


def test_plain_urdf_keeps_zero_masses_and_warns_for_impossible_inertias():
    """ROS descriptions give massless frames mass 0 and often rounded inertias: they load."""
    text = doc(mass="0", ns="").replace("<pkdyn:", "<x_").replace("</pkdyn:", "</x_")
    robot = pkdyn.load_string(text, "plain.urdf", geometry=False)
    assert robot.closures == ()
    odd = doc(inertia=("0.01", "0.01", "0.05"), ns="")
    odd = odd.replace("<pkdyn:", "<x_").replace("</pkdyn:", "</x_")
    with pytest.warns(UserWarning, match="link 'arm'.*triangle inequality"):
        pkdyn.load_string(odd, "plain.urdf", geometry=False)


def chain(n: int, parent=lambda i: f"l{i - 1}", jtype="revolute") -> str:
    links = "".join(
        f'<link name="l{i}"><inertial><mass value="1"/>'
        + INERTIA.format(ixx="0.01", iyy="0.01", izz="0.01")
        + "</inertial></link>"
        for i in range(1, n + 1)
    )
    joints = "".join(
        f'<joint name="j{i}" type="{jtype}"><parent link="{parent(i)}"/><child link="l{i}"/>'
        '<origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i in range(1, n + 1)
    )
    return f'<robot name="chain"><link name="l0"/>{links}{joints}</robot>'


@pytest.mark.parametrize(
    "n, parent, culprit",
    [
        (5000, lambda i: f"l{i - 1}", "deeper than 1000"),  # segfaulted inside Pinocchio
        (1500, lambda i: f"l{i - 1}", "deeper than 1000"),
        (600, lambda i: "l0", "nv = 600"),  # createData would need ~14 GB
        (300, lambda i: f"l{i - 1}", "nv = 300"),
    ],
    ids=["chain 5000", "chain 1500", "star 600", "chain 300"],
)
def test_models_too_large_for_pinocchio_are_refused_before_it_runs(n, parent, culprit):
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(chain(n, parent), "big.urdf", geometry=False)
    assert culprit in str(err.value) and "big.urdf" in str(err.value)


def test_a_large_but_reasonable_chain_loads():
    robot = pkdyn.load_string(chain(120), "chain.urdf", geometry=False)
    assert robot.nv == 120
