"""The pkdyn command line: JSON keys, round trips, one-line errors with non-zero exit."""

import json
import subprocess
import sys

import numpy as np
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.closed_form import delta as cf


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_info_json_keys(capsys):
    code, out, _ = run(capsys, "info", "delta", "--json")
    assert code == 0
    info = json.loads(out)
    assert set(info) >= {"name", "nq", "nv", "dof", "actuated", "loops", "closures"}
    assert info["actuated"] == ["arm1", "arm2", "arm3"]
    assert info["actuators"] == ["motor1", "motor2", "motor3"]
    assert info["loops"] == 5 and info["dof"] == 3 and info["internal"] == 6  # bar spins
    assert {c["type"] for c in info["closures"]} == {"point"}


@pytest.mark.parametrize(
    ("inverse", "forward", "option"),
    [("inverse-geometry", "forward-geometry", "--qa"), ("ik", "fk", "--qa")],
)
def test_ik_then_fk_round_trip(capsys, inverse, forward, option):
    code, out, _ = run(capsys, inverse, "delta", "--pose", "0.05", "-0.02", "-0.4", "--json")
    assert code == 0
    qa = json.loads(out)["qa"]
    alpha, _ = cf.inverse(pkdyn.load("delta", geometry=False).params, np.array([0.05, -0.02, -0.4]))
    np.testing.assert_allclose(qa, alpha[0], atol=1e-9)
    code, out, _ = run(capsys, forward, "delta", option, *map(repr, qa), "--json")
    fk = json.loads(out)
    np.testing.assert_allclose(fk["position"], [0.05, -0.02, -0.4], atol=1e-9)
    assert set(fk) >= {"position", "rpy", "q", "qa"}
    assert len(fk["q"]) == pkdyn.load("delta", geometry=False).nq


def test_param_override_changes_the_robot(capsys):
    code, out, _ = run(capsys, "info", "delta", "--param", "bar_joint=universal", "--json")
    assert code == 0 and json.loads(out)["dof"] == 3


def test_urdf_to_file_loads(tmp_path, capsys):
    path = tmp_path / "gs.urdf"
    code, _, _ = run(capsys, "urdf", "gough_stewart", "--param", "leg_radius=0.01", "-o", str(path))
    assert code == 0
    robot = pkdyn.load(str(path), geometry=False)
    assert robot.mobility() == 6


@pytest.mark.parametrize(
    "argv, culprit",
    [
        (["info", "nosuchrobot"], "nosuchrobot"),
        (["info", "delta", "--param", "foo=1"], "foo"),
        (["info", "delta", "--param", "la"], "la"),
        (["info", "delta", "--param", "la=-0.2"], "la"),
        (["ik", "delta", "--pose", "1", "2", "3"], "out of reach"),
        (["ik", "delta", "--pose", "1", "2"], "pose"),
        (["fk", "delta", "--qa", "0.1", "nan", "0.2"], "nan"),
        (["fk", "delta", "--qa", "0.1", "0.2"], "3 values"),
        (["fk", "gough_stewart", "--qa", "0.4", "0.4", "0.4", "0.4", "0.4", "0.4"], "leg1"),
        (["urdf", "delta", "-o", "/nonexistent/dir/x.urdf"], "x.urdf"),
    ],
)
def test_user_errors_are_one_line(capsys, argv, culprit):
    code, out, err = run(capsys, *argv)
    assert code == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pkdyn: error:")
    assert culprit in lines[0]
    assert "Traceback" not in err


def test_console_script_bad_usage_one_line():
    proc = subprocess.run(
        [sys.executable, "-m", "pkdyn.cli", "fk", "delta"], capture_output=True, text=True
    )
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1


def test_malformed_file_is_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'></robot>")
    code, _, err = run(capsys, "info", str(bad))
    assert code == 1 and "bad.urdf" in err and len(err.strip().splitlines()) == 1


def test_mobility_json(capsys):
    code, out, _ = run(capsys, "mobility", "delta", "--json")
    assert code == 0
    m = json.loads(out)
    assert {"grubler", "mobility", "internal", "hyperstatism", "rank"} <= set(m)
    assert (m["grubler"], m["mobility"], m["internal"], m["hyperstatism"]) == (9, 9, 6, 0)


def test_mobility_text_names_internal_modes(capsys):
    code, out, _ = run(capsys, "mobility", "delta")
    assert code == 0 and "spins" in out


def test_jacobian_json_matches_fk_differences(capsys):
    """J from the CLI against central differences of the direct geometric model."""
    robot = pkdyn.load("delta", geometry=False)
    qa = pkdyn.inverse_geometry(robot, [0.03, -0.02, -0.38]).qa
    code, out, _ = run(capsys, "jacobian", "delta", "--qa", *map(str, qa.tolist()), "--json")
    assert code == 0
    J = np.array(json.loads(out)["J"])
    assert {"A", "B"} <= set(json.loads(out))
    h = 1e-6
    Jfd = np.column_stack(
        [
            (
                pkdyn.forward_geometry(robot, qa + h * e).position
                - pkdyn.forward_geometry(robot, qa - h * e).position
            )
            / (2 * h)
            for e in np.eye(3)
        ]
    )
    np.testing.assert_allclose(J, Jfd, atol=1e-6)


def test_singularity_json_keys(capsys):
    code, out, _ = run(
        capsys, "singularity", "planar_3rrr", "--pose", "0", "0", "0", "0", "0", "0.1", "--json"
    )
    s = json.loads(out)
    assert code == 0 and s["kind"] == "regular"
    assert {"kind", "cond_A", "cond_B", "directions"} <= set(s)


def test_statics_virtual_work(capsys):
    """tau . dq + F . dx = 0 for a small motion of the hexapod, with tau from the CLI."""
    robot = pkdyn.load("gough_stewart", geometry=False)
    pose = np.array([0.01, -0.02, robot.params.home_height() + 0.01, 0.02, 0.0, 0.05])
    F = np.array([3.0, -2.0, -100.0, 0.0, 0.0, 0.0])  # pure force: moment convention irrelevant
    code, out, _ = run(
        capsys,
        "statics",
        "gough_stewart",
        "--pose",
        *map(str, pose),
        "--wrench",
        *map(str, F),
        "--json",
    )
    assert code == 0
    tau = np.array(json.loads(out)["tau"])
    dx = np.array([1e-6, 2e-6, -1e-6])
    a = pkdyn.inverse_geometry(robot, pose[:3].tolist() + pose[3:].tolist())
    M = a.placement
    import pinocchio as pin

    target = pin.SE3(M.rotation, M.translation + dx)
    dq = pkdyn.inverse_geometry(robot, target, q_init=a.q).qa - a.qa
    assert abs(tau @ dq + F[:3] @ dx) < 1e-9 * np.abs(F).max()
