"""No silent trees (issue 36, item 2): what an importer does not read is said, loops refused.

Any element of a URDF, SDFormat or MJCF file that pkdyn does not read -- at the top level or
inside a joint -- gives one warning naming it and its lines; an element whose name says it
closes a loop or couples joints (``loop``, ``closure``, ``constraint``, ``coupling``, ``mimic``,
in any namespace) is an error unless the user leaves it out (``ignore_elements`` /
``--ignore-element``), since the mechanism would otherwise load as a tree with the wrong
mobility.
"""

from __future__ import annotations

import warnings

import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.exceptions import DescriptionError, InvalidInputError

LINK = (
    '<link name="{n}"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
    'ixy="0" ixz="0" iyz="0"/></inertial></link>'
)


def urdf(extra: str = "", in_joint: str = "") -> str:
    return (
        '<robot name="r" xmlns:x="urn:example">\n'
        '<link name="base"/>\n' + LINK.format(n="a") + "\n"
        '<joint name="j" type="revolute"><parent link="base"/><child link="a"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>'
        f"{in_joint}</joint>\n{extra}\n</robot>"
    )


def _messages(load, *args, **kw) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load(*args, **kw)
    return [str(w.message) for w in caught]


UNREAD = {
    "top-level element": (urdf('<sensor name="s"/>\n<sensor name="t"/>'), "<sensor> at the top"),
    "namespaced element": (urdf("<x:settings/>"), "<x:settings> at the top level"),
    "inside a joint": (urdf(in_joint='<calibration rising="0.1"/>'), "<calibration> in a <joint>"),
    "gazebo settings": (urdf('<gazebo reference="a"><mu1>1</mu1></gazebo>'), "<gazebo> at"),
}


@pytest.mark.parametrize("text, words", UNREAD.values(), ids=list(UNREAD))
def test_urdf_elements_pkdyn_does_not_read_are_named_once(text, words):
    messages = [m for m in _messages(pkdyn.load_string, text, "r.urdf") if "not read" in m]
    assert len(messages) == 1 and words in messages[0] and "line" in messages[0], messages


def test_one_warning_per_element_name_with_its_count_and_lines():
    (message,) = [
        m
        for m in _messages(pkdyn.load_string, urdf('<sensor name="s"/>\n<sensor/>'), "r.urdf")
        if "not read" in m
    ]
    assert "2 elements (lines 5, 6)" in message


LOOP_LIKE = {
    "a loop of another dialect": urdf('<my_loop name="l"><a link="base"/></my_loop>'),
    "a namespaced closure": urdf('<x:closure name="c"/>'),
    "a constraint": urdf('<kinematic_constraint name="c"/>'),
    "a coupling in a joint": urdf(in_joint='<coupling joint="k"/>'),
    "a gear mimic in a joint": urdf(in_joint='<x:mimic joint="k"/>'),
}


@pytest.mark.parametrize("text", LOOP_LIKE.values(), ids=list(LOOP_LIKE))
def test_loop_like_elements_are_errors_unless_ignored(text):
    with pytest.raises(DescriptionError) as err:
        pkdyn.load_string(text, "r.urdf")
    message = str(err.value)
    assert "closes a loop or couples joints" in message and "(line " in message
    tag = message.split("<", 1)[1].split(">", 1)[0].split(" ", 1)[0]
    local = tag.split(":")[-1]
    assert f"--ignore-element {local}" in message
    messages = _messages(pkdyn.load_string, text, "r.urdf", ignore_elements=[local])
    assert any("ignored as asked" in m and f"<{tag}>" in m for m in messages), messages


def test_ignored_names_that_match_nothing_are_said():
    messages = _messages(pkdyn.load_string, urdf(), "r.urdf", ignore_elements=("lop",))
    assert any("no element named 'lop'" in m for m in messages)


@pytest.mark.parametrize("bad", ["", "a b", "<loop>", 3])
def test_ignore_elements_must_be_names(bad):
    with pytest.raises(InvalidInputError, match="ignore_elements"):
        pkdyn.load_string(urdf(), "r.urdf", ignore_elements=[bad])


def test_library_robots_take_no_ignore_elements():
    with pytest.raises(pkdyn.ParameterError, match="ignore_elements"):
        pkdyn.load("delta", ignore_elements=("loop",))


def test_cli_ignore_element_is_repeatable(tmp_path, capsys):
    path = tmp_path / "r.urdf"
    path.write_text(urdf('<x:closure name="c"/><x:coupling name="k"/>'))
    assert main(["mobility", str(path)]) == 1
    assert "pkdyn: error:" in capsys.readouterr().err
    code = main(
        ["mobility", str(path), "--ignore-element", "closure", "--ignore-element", "coupling"]
    )
    assert code in (0, None)
    assert "mobility 1" in capsys.readouterr().out


# ------------------------------------------------------------------ SDFormat and MJCF

SDF = """<sdf version="1.9"><model name="m">
  <plugin name="p" filename="x.so"/>
  <link name="base"/>
  <link name="a"><inertial><mass>1</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy>
    <izz>0.01</izz></inertia></inertial></link>
  <joint name="fix" type="fixed"><parent>world</parent><child>base</child></joint>
  <joint name="j" type="revolute"><parent>base</parent><child>a</child>
    <axis><xyz>0 0 1</xyz>{axis}</axis>{joint}</joint>
</model></sdf>"""


def test_sdf_unread_elements_are_named():
    text = SDF.format(axis="<initial_position>0.1</initial_position>", joint="<physics/>")
    messages = [m for m in _messages(pkdyn.load_string, text, "m.sdf") if "not read" in m]
    assert any("<plugin> in the <model>" in m and "line 2" in m for m in messages)
    assert any("<physics> in a <joint>" in m for m in messages)
    assert any("<initial_position> in a joint's <axis>" in m for m in messages)


@pytest.mark.parametrize(
    "axis, joint",
    [
        ('<mimic joint="other"><multiplier>2</multiplier></mimic>', ""),
        ("", '<drake:mimic joint="other" multiplier="2"/>'),
    ],
    ids=["SDFormat 1.11 mimic", "drake:mimic"],
)
def test_sdf_mimics_pkdyn_does_not_read_are_refused(axis, joint):
    text = SDF.format(axis=axis, joint=joint)
    if "drake:" in text:
        text = text.replace("<sdf ", '<sdf xmlns:drake="http://drake.mit.edu" ')
    with pytest.raises(DescriptionError, match="closes a loop or couples joints"):
        pkdyn.load_string(text, "m.sdf")


MJCF = (
    '<mujoco><worldbody><body name="a"><joint name="j"/><geom size="0.1"/>'
    '<site name="s"/></body></worldbody>{extra}</mujoco>'
)


def test_mjcf_unread_sections_are_named():
    extra = (
        '<sensor><jointpos joint="j"/></sensor><visual/><contact><exclude body1="a" '
        'body2="world"/></contact><tendon><spatial name="t"><site site="s"/></spatial></tendon>'
    )
    text = MJCF.format(extra=extra)
    messages = [m for m in _messages(pkdyn.load_string, text, "m.xml") if "not read" in m]
    for words in ("<sensor> at the top", "<visual> at the top", "<contact> at the top"):
        assert any(words in m for m in messages), (words, messages)
    assert any("<spatial> in <tendon>" in m for m in messages)


def test_transmissions_pkdyn_does_not_read_are_named():
    text = urdf(
        '<transmission name="d"><type>transmission_interface/DifferentialTransmission</type>'
        '<joint name="j"/></transmission>'
    )
    messages = _messages(pkdyn.load_string, text, "r.urdf")
    assert any("'d' (DifferentialTransmission) not read" in m for m in messages), messages
