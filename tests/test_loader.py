"""The loader: formats told apart, one typed line for each kind of bad description."""

import os
from pathlib import Path

import pytest

import pkdyn

FOUR_BAR = Path(__file__).parent / "data" / "mobility" / "four_bar.urdf"


@pytest.mark.parametrize(
    "text,culprit",
    [
        ("<robot name='r'><link name='a'/></robot>", None),
        ("<mujoco model='m'><worldbody/></mujoco>", None),
        ("<scene/>", "<scene>"),
        ("", "file"),
        ("\x00\x01", "file"),
        (
            "<?xml version='1.0'?><!DOCTYPE r [<!ENTITY a 'aaaa'>]><robot name='r'>&a;</robot>",
            "entity 'a' (line 1)",
        ),
    ],
)
def test_format_detection_and_entities(text, culprit):
    if culprit is None:
        assert pkdyn.load_string(text, "x", geometry=False).nq == 0
        return
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load_string(text, "x", geometry=False)
    assert err.value.culprit == culprit
    assert len(str(err.value).splitlines()) == 1


def test_unknown_urdf_joint_type_names_the_joint_and_its_line():
    text = FOUR_BAR.read_text().replace(
        'name="coupler" type="revolute"', 'name="coupler" type="ball"'
    )
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load_string(text, "fb.urdf", geometry=False)
    assert err.value.culprit == "<joint name='coupler'> (line 27)"
    assert "unknown joint type 'ball'" in str(err.value) and "pkdyn:joint" in str(err.value)


def test_a_loop_that_cannot_close_is_a_description_error():
    text = FOUR_BAR.read_text().replace('<origin xyz="0.3 0 0"', '<origin xyz="0.9 0 0"')
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load_string(text, "fb.urdf", geometry=False)
    assert isinstance(err.value, pkdyn.AssemblyError) and isinstance(
        err.value, pkdyn.LoopClosureError
    )
    assert err.value.closure == "C" and err.value.culprit == "closure 'C'"
    assert "between 'coupler' and 'rocker'" in str(err.value)


def test_closure_between_frames_that_do_not_exist():
    text = FOUR_BAR.read_text().replace(
        'link="rocker" xyz="0.25 0 0"', 'link="rockr" xyz="0.25 0 0"'
    )
    with pytest.raises(pkdyn.DescriptionError, match="closure 'C'.*'rockr', which does not exist"):
        pkdyn.load_string(text, "fb.urdf", geometry=False)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_description_fifo_is_refused(tmp_path):
    fifo = tmp_path / "robot.urdf"
    os.mkfifo(fifo)
    with pytest.raises(pkdyn.DescriptionError, match="not a regular file"):
        pkdyn.load(fifo)
