"""The command line on descriptions in other formats, with ``--home`` and ``--tol``."""

import json
from pathlib import Path

import pytest

from pkdyn.cli import main

DATA = Path(__file__).parent / "data" / "public"
CASSIE = str(DATA / "menagerie_cassie" / "cassie.xml")
REACHY = str(DATA / "reachy_mini" / "robot.urdf")


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_info_on_mjcf_and_sdf(capsys):
    code, out, _ = run(capsys, "info", CASSIE, "--json")
    assert code == 0
    info = json.loads(out)
    assert (info["nq"], info["dof"], info["loops"]) == (35, 22, 4)
    assert {c["type"] for c in info["closures"]} == {"point"}
    code, out, _ = run(capsys, "mobility", str(DATA / "erd_cassie_sdf" / "cassie_v2.sdf"), "--json")
    mob = json.loads(out)  # the floating base's 6 are counted, and said apart
    assert code == 0 and (mob["mobility"], mob["floating"]) == (18, 6)


def test_home_option(capsys):
    code, out, _ = run(capsys, "info", "four_bar_knee", "--home", "0.5", "--json")
    assert code == 0 and json.loads(out)["dof"] == 1
    code, _, err = run(capsys, "info", "four_bar_knee", "--home", "0.5", "0.1")
    assert code == 1
    assert err.startswith("pkdyn: error: home: 2 values; give the 1 actuator coordinates (motor)")
    assert len(err.strip().splitlines()) == 1


def test_tol_option(capsys):
    code, _, err = run(capsys, "info", REACHY)
    assert code == 0 and "pkdyn: warning:" in err and "CAD rounding" in err
    code, _, err = run(capsys, "info", REACHY, "--tol", "-1")
    assert code == 1 and "pkdyn: error: tol:" in err


def test_urdf_command_refuses_other_formats(capsys):
    code, _, err = run(capsys, "urdf", CASSIE)
    assert code == 1 and "is an MJCF description" in err


@pytest.mark.parametrize(
    "text,message",
    [("<scene/>", "cannot tell the format"), ("not xml", "not an XML document")],
)
def test_unknown_format_is_one_line(capsys, tmp_path, text, message):
    path = tmp_path / "robot.xml"
    path.write_text(text)
    code, _, err = run(capsys, "info", str(path))
    assert code == 1 and message in err and len(err.strip().splitlines()) == 1
