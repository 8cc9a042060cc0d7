"""Bad input and new-user paths, class by class (issue 24): one line, the culprit named.

Classes: numbers validated before arithmetic (CLI and API: zero, NaN, infinite, absurd, a
fraction where a count is due), API types at the public boundary, user callbacks wrapped,
signals (no traceback, old files intact), ``near`` within the documented distance of a
singularity, configurations with zero quaternions, misleading outputs (hinge reactions, missing
limits, negative zero, ``dof``), and what a new user tries: partial poses, limits reported,
trajectories from CSV files, hints worded for the command line, write permissions, simulation
outputs, close matches.
"""

from __future__ import annotations

import json
import math
import sys
import warnings

import numpy as np
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.exceptions import (
    InvalidInputError,
    ParameterError,
    SimulationError,
    UnreachablePoseError,
)


def _one_line(capsys, argv, code=1):
    assert main(argv) == code, argv
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("pkdyn: error:"), err
    assert "Traceback" not in err
    return err


# --------------------------------------------------------------------------------------------
# numbers validated before arithmetic, on the command line

CLI_NUMBERS = {
    "workspace step zero": (["workspace", "delta", "--step", "0"], "step: must be > 0"),
    "workspace step nan": (["workspace", "delta", "--step", "nan"], "--step: is nan"),
    "workspace samples one": (["workspace", "delta", "--samples", "1"], "samples"),
    "parameter overflow": (["info", "delta", "--param", "la=1e308"], "parameter 'la'"),
    "parameter nan": (["info", "delta", "--param", "la=nan"], "parameter 'la'"),
    "ik absurd pose": (["ik", "delta", "--pose", "1e308", "0", "0"], "out of reach"),
    "ik absurd hexapod": (
        ["ik", "gough_stewart", "--pose", "0", "0", "1e308", "0", "0", "0"],
        "out of reach",
    ),
    "jacobian absurd actuator": (
        ["jacobian", "delta", "--qa", "1e308", "0", "0"],
        "beyond any reachable value",
    ),
    "payload overflow": (["size", "delta", "--payload", "1e308"], "--payload"),
    "walker swing time": (
        ["tripod", "scenario", "--no-machining", "--swing-time", "1e308"],
        "swing_time",
    ),
    "walker huge plan": (
        ["tripod", "scenario", "--no-machining", "--swing-time", "1e9"],
        "samples",
    ),
    "walker tilt": (["tripod", "scenario", "--no-machining", "--tilt", "1e9"], "tilt"),
    "walker step": (["tripod", "scenario", "--no-machining", "--step", "1e308", "0"], "step dx"),
    "mjcf infinite step": (["mjcf", "five_bar", "--step", "inf"], "step"),
    "fastest dt": (["size", "delta", "--fastest", "--dt", "1e-300"], "dt"),
}


@pytest.mark.parametrize("argv, needle", CLI_NUMBERS.values(), ids=list(CLI_NUMBERS))
def test_numbers_are_checked_before_arithmetic_on_the_command_line(capsys, argv, needle):
    assert needle in _one_line(capsys, argv)


# --------------------------------------------------------------------------------------------
# API types at the public boundary, user callbacks


@pytest.fixture(scope="module")
def five_bar() -> pkdyn.Robot:
    return pkdyn.load("five_bar", geometry=False)


def _raise(exc: BaseException):
    def fn(t, q, v):
        raise exc

    return fn


API_TYPES = {
    "dt complex": (dict(dt=1e-3 + 1j), InvalidInputError, "dt: expected a real number"),
    "duration string": (dict(duration="x"), InvalidInputError, "duration: expected a real"),
    "record_every zero": (dict(record_every=0), InvalidInputError, "record_every"),
    "record_every fraction": (dict(record_every=2.5), InvalidInputError, "whole number"),
    "record_every bool": (dict(record_every=True), InvalidInputError, "whole number"),
    "step negative": (dict(step=-1.0), InvalidInputError, "step"),
    "integrator not a string": (dict(integrator=3), InvalidInputError, "integrator"),
    "torque not callable": (dict(torque=3), InvalidInputError, "expected a function"),
}


@pytest.mark.parametrize("kwargs, error, needle", API_TYPES.values(), ids=list(API_TYPES))
def test_api_types_are_checked_at_the_boundary(five_bar, kwargs, error, needle):
    from pkdyn.dynamics import simulate

    args = {"duration": 0.01, "dt": 1e-3} | kwargs
    with pytest.raises(error, match=needle):
        simulate(five_bar, **args)


CALLBACKS = {
    "raises ValueError": (_raise(ValueError("boom")), "raised ValueError: boom", ValueError),
    "calls sys.exit": (_raise(SystemExit(3)), "raised SystemExit: 3", SystemExit),
    "returns a string": (lambda t, q, v: "abc", "returned 'abc' (str)", None),
    "returns a dict": (lambda t, q, v: {"a": 1}, "(dict)", None),
    "returns complex": (lambda t, q, v: np.array([1j, 0.0]), "complex", None),
    "returns ragged": (lambda t, q, v: [[1.0, 2.0], [3.0]], "(list)", None),
    "returns None": (lambda t, q, v: None, "returned None", None),
    "returns too many": (lambda t, q, v: np.zeros(3), "3 values for 2 actuators", None),
    "returns nan": (lambda t, q, v: np.array([np.nan, 0.0]), "finite", None),
}


@pytest.mark.parametrize(
    "fn, needle, cause", CALLBACKS.values(), ids=list(CALLBACKS)
)  # fmt: skip
@pytest.mark.parametrize("kind", ["torque", "motor_torque"])
def test_user_callbacks_are_wrapped_naming_the_function_and_time(five_bar, fn, needle, cause, kind):
    from pkdyn.dynamics import simulate

    with pytest.raises(SimulationError) as err:
        simulate(five_bar, 0.01, 1e-3, **{kind: fn})
    msg = str(err.value)
    assert msg.startswith("t = 0 s:") and f"the {kind} function" in msg and needle in msg
    assert err.value.time == 0.0
    if cause is not None:
        assert isinstance(err.value.__cause__, cause)


def test_keyboard_interrupt_in_a_callback_stays_an_interrupt(five_bar):
    from pkdyn.dynamics import simulate

    with pytest.raises(KeyboardInterrupt):
        simulate(five_bar, 0.01, 1e-3, torque=_raise(KeyboardInterrupt()))


def test_zero_quaternion_initial_state_is_refused_naming_the_joint():
    from pkdyn.dynamics import simulate

    delta = pkdyn.load("delta", geometry=False)
    jid = next(j for j in range(1, delta.model.njoints) if delta.model.joints[j].nq == 4)
    q = delta.q_home.copy()
    iq = delta.model.joints[jid].idx_q
    q[iq : iq + 4] = 0.0
    with pytest.raises(InvalidInputError, match=f"joint '{delta.model.names[jid]}'.*norm 0"):
        simulate(delta, 0.01, 1e-3, q0=q)
    q[iq : iq + 4] = [0.0, 0.0, 0.0, 1.0001]  # rounding: normalised, accepted
    res = simulate(delta, 0.002, 1e-3, q0=q)
    assert res.energy_drift() < 1e-6


def test_a_robot_at_rest_reports_no_drift(five_bar):
    """Nothing moves (the five-bar lies in the horizontal plane): drift against the floor."""
    from pkdyn.dynamics import simulate

    res = simulate(five_bar, 0.2, 1e-3)
    assert float(np.max(res.kinetic)) < 1e-20 and res.energy_drift() < 1e-6


def test_absurd_api_inputs(five_bar):
    delta = pkdyn.load("delta", geometry=False)
    with pytest.raises(UnreachablePoseError, match="times the robot's size"):
        pkdyn.inverse_geometry(delta, [0.0, 0.0, -1e9])
    with pytest.raises(InvalidInputError, match="beyond any reachable value"):
        pkdyn.forward_geometry(delta, [500.0, 0.0, 0.0], check_limits=False)
    with pytest.raises(ParameterError, match="beyond any plausible value"):
        pkdyn.load("delta", la=1e12)
    from pkdyn.library.delta import Params

    with pytest.raises(ParameterError, match="beyond any plausible value"):
        Params(la=1e300)


# --------------------------------------------------------------------------------------------
# signals: never a traceback, the previous file kept


@pytest.mark.parametrize(
    "where", ["loading the command", "writing the csv"], ids=["imports", "writer"]
)
def test_an_interrupt_anywhere_prints_one_line(capsys, tmp_path, monkeypatch, where):
    csv_file = tmp_path / "out.csv"
    csv_file.write_text("previous\n")
    if where == "loading the command":
        import importlib

        real = importlib.import_module

        def interrupted(name, *a, **k):
            if name.startswith("pkdyn.cli."):
                raise KeyboardInterrupt
            return real(name, *a, **k)

        monkeypatch.setattr(importlib, "import_module", interrupted)
    else:
        from pkdyn.dynamics import sizing

        def interrupted(self, path):
            raise KeyboardInterrupt

        monkeypatch.setattr(sizing.SizingResult, "write_csv", interrupted)
    assert main(["size", "delta", "--dt", "0.004", "--csv", str(csv_file)]) == 130
    err = capsys.readouterr().err
    assert err.strip() == "pkdyn: interrupted" and "Traceback" not in err
    assert csv_file.read_text() == "previous\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]
    import signal

    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored


# --------------------------------------------------------------------------------------------
# near: within the documented distance of a singularity


@pytest.mark.parametrize("d", [1e-6, 1e-5, 1e-4])
def test_poses_near_the_delta_serial_boundary_are_near(d):
    """The Delta's lowest point (every arm along its bars) is a serial singularity: a pose
    within 1e-4 of its size (0.08 mm) of it is near (the serial margin grows like sqrt)."""
    from pkdyn.analysis.kinematics import NEAR_SERIAL_TOL
    from pkdyn.analysis.singularity import classify

    delta = pkdyn.load("delta", geometry=False)
    z0 = -0.566370020393029
    q = pkdyn.inverse_geometry(delta, [0.0, 0.0, z0 + d], check_limits=False).q
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = classify(delta, q)
    assert rep.kind == "regular" and rep.near and rep.margin < NEAR_SERIAL_TOL
    q0 = pkdyn.inverse_geometry(delta, [0.0, 0.0, z0], check_limits=False).q
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        singular = classify(delta, q0)
    assert singular.kind == "serial" and singular.near  # singular implies near


def test_singular_poses_are_near_in_the_cli(capsys):
    assert main(["singularity", "delta", "--pose", "0", "0", "-0.566370020393029", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["kind"] == "serial" and out["near"] is True


# --------------------------------------------------------------------------------------------
# misleading outputs


def test_hinge_reactions_are_one_force_and_one_moment(capsys):
    assert main(["statics", "five_bar", "--qa", "1.2", "1.9", "--wrench", "10", "5", "0", "0",
                 "0", "0", "--json"]) == 0  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert list(out["reactions"]) == ["loop"]  # not 'loop' and 'loop/axis', each half
    r = out["reactions"]["loop"]
    assert set(r) == {"force", "moment", "point"} and np.linalg.norm(r["force"]) > 1.0


def test_no_margin_without_a_limit_and_no_negative_zero():
    from pkdyn.dynamics.sizing import _margin, percent

    assert math.isnan(_margin(3.0, math.inf))
    assert percent(math.nan).strip() == "-"
    assert percent(-1e-12) == "   0.0%" and "-0.0" not in percent(-4e-4)


def test_fastest_cycle_table_has_no_negative_zero(capsys):
    """The fastest cycle uses its limits exactly: margins of -1e-9 print as 0.0 %."""
    assert main(["size", "delta", "--fastest", "--dt", "0.005"]) == 0
    out = capsys.readouterr().out
    assert "-0.0%" not in out and "   0.0%" in out


def test_one_meaning_of_dof(capsys):
    delta = pkdyn.load("delta", geometry=False)
    assert main(["info", "delta", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["dof"] == delta.dof() == 3 and info["internal"] == 6 and delta.mobility() == 9


# --------------------------------------------------------------------------------------------
# what a new user tries, through the CLI


def test_ik_with_the_controlled_components_only(capsys):
    assert main(["ik", "five_bar", "--pose", "0.0", "0.45", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    robot = pkdyn.load("five_bar", geometry=False)
    fk = pkdyn.forward_geometry(robot, out["qa"])
    np.testing.assert_allclose(fk.position[:2], [0.0, 0.45], atol=1e-9)
    err = _one_line(capsys, ["ik", "five_bar", "--pose", "0", "0.45", "0", "0"])
    assert "the 2 components five_bar controls (x y)" in err


@pytest.mark.parametrize(
    "argv, needle",
    [
        (
            ["size", "delta", "--cycle-time", "0.25", "--dt", "0.001"],
            "limits exceeded: motor1 speed",
        ),
        (["size", "delta", "--payload", "1e6", "--dt", "0.002"], "limits exceeded: motor1 torque"),
    ],
    ids=["speed", "torque"],
)
def test_size_reports_exceeded_limits_and_says_no(capsys, argv, needle):
    """Speed and torque alike: the table with the negative margin, then one line, exit 1."""
    assert main(argv) == 1
    cap = capsys.readouterr()
    assert "LIMITS EXCEEDED" in cap.out and "%" in cap.out
    assert cap.err.strip().count("\n") == 0 and needle in cap.err


@pytest.mark.parametrize("space", ["actuator", "task"])
def test_size_a_trajectory_read_from_csv(capsys, tmp_path, space):
    """The Adept cycle written by ``size --csv`` (actuators) or as platform positions, read
    back: the same peaks to the finite differences' accuracy (0.5 % at 1 ms, 2 % at 2 ms)."""
    src = tmp_path / "adept.csv"
    assert main(["size", "delta", "--dt", "0.002", "--csv", str(src), "--json"]) == 0
    ref = json.loads(capsys.readouterr().out)
    if space == "task":
        from pkdyn.dynamics.trajectory import named_task

        delta = pkdyn.load("delta", geometry=False)
        task = named_task(delta, "adept", dt=0.002)
        rows = ["t,x,y,z"] + [
            f"{t:.10g},{p[0]:.12g},{p[1]:.12g},{p[2]:.12g}"
            for t, p in zip(task.t, task.pose, strict=True)
        ]
        src = tmp_path / "adept_task.csv"
        src.write_text("\n".join(rows) + "\n")
    assert main(["size", "delta", "--trajectory", str(src), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert f"({space} space)" in got["trajectory"]
    for a, b in zip(ref["actuators"], got["actuators"], strict=True):
        assert b["peak"] == pytest.approx(a["peak"], rel=2e-2)
        assert b["peak_speed"] == pytest.approx(a["peak_speed"], rel=2e-2)


@pytest.mark.parametrize(
    "text, needle",
    [
        ("t,qa_motor1\n0,0\n0.1,0\n0.2,0\n", "qa_motor2"),
        ("x,y,z\n0,0,-0.3\n0,0,-0.3\n0,0,-0.3\n", "no column 't'"),
        ("t,x,y,z\n0,0,0,-0.3\n0,0,0,-0.3\n0.1,0,0,-0.3\n", "does not increase"),
        (
            "t,x,y,z\n0,0,0,-0.3\n0.1,0,zero,-0.3\n0.2,0,0,-0.3\n",
            "line 3, column y: 'zero' is not a number",
        ),
        ("t,x,y\n0,0,0\n0.1,0,0\n0.2,0,0\n", "missing z"),
    ],
    ids=["actuator missing", "no time", "time backwards", "text", "task component missing"],
)
def test_bad_trajectory_files_name_the_line_or_column(capsys, tmp_path, text, needle):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    assert needle in _one_line(capsys, ["size", "delta", "--trajectory", str(path)])


def test_platform_hints_say_how_to_declare_one():
    text = """<robot name="arm" xmlns:pkdyn="urn:pkdyn:urdf:1"><link name="base"/>
      <link name="l"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01"
      ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j" type="revolute"><parent link="base"/><child link="l"/><axis xyz="0 0 1"/>
      <limit lower="-1" upper="1" effort="5" velocity="3"/></joint>
      <transmission name="t"><type>transmission_interface/SimpleTransmission</type>
      <joint name="j"/><actuator name="m"><mechanicalReduction>1</mechanicalReduction>
      </actuator></transmission></robot>"""
    robot = pkdyn.load_string(text, "arm.urdf", geometry=False)
    for call in (
        lambda: pkdyn.inverse_geometry(robot, [0.1, 0.0, 0.0]),
        lambda: robot.platform_placement(robot.q_home),
    ):
        with pytest.raises(pkdyn.PkdynError, match="pkdyn:platform.*platform: \\{frame"):
            call()


def test_cli_worded_hints_for_missing_geometry(capsys):
    from pkdyn.analysis.collisions import CollisionChecker

    robot = pkdyn.load("five_bar", geometry=False)
    with pytest.raises(pkdyn.PkdynError, match="<collision> elements") as err:
        CollisionChecker(robot)
    assert "geometry=True" in str(err.value)  # the API wording comes second
    from pkdyn.workspace.translation import translation_workspace

    with pytest.raises(InvalidInputError, match=r"--limits stroke joint; limits=\('stroke'"):
        translation_workspace(robot, samples=3, limits=("interference",))


@pytest.mark.parametrize(
    "path, needle",
    [
        ("/proc/x.csv", "does not accept new files"),
        ("/no/such/dir/x.csv", "does not exist"),
    ],
)
def test_write_permission_messages(capsys, path, needle):
    assert needle in _one_line(capsys, ["size", "delta", "--csv", path])


def test_simulate_csv_plot_and_html(capsys, tmp_path):
    csv_file, png, html = tmp_path / "s.csv", tmp_path / "s.png", tmp_path / "s.html"
    argv = ["simulate", "five_bar", "--duration", "0.05", "--csv", str(csv_file)]
    assert main([*argv, "--plot", str(png), "--html", str(html)]) == 0
    head = csv_file.read_text().splitlines()
    assert head[0].split(",")[:3] == ["t", "qa_motor1", "qa_motor2"]
    assert "closure_residual" in head[0] and len(head) == 52
    assert png.read_bytes()[:4] == b"\x89PNG" and html.stat().st_size > 10_000


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["simulat", "delta"], "did you mean 'simulate'"),
        (["info", "delt"], "did you mean 'delta'"),
        (["info", "delta", "--param", "laa=0.3"], "did you mean 'la'"),
        (["size", "delta", "--trajectory", "adpet"], "did you mean 'adept'"),
    ],
    ids=["command", "robot", "parameter", "trajectory"],
)
def test_close_matches(capsys, argv, needle):
    if argv[0] == "simulat":  # a usage error: exit 2
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == 2
    else:
        assert main(argv) == 1
    assert needle in capsys.readouterr().err


def test_home_found_near_a_dead_centre_is_reported():
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from test_home import COUPLER, CRANK, ROCKER, _load, _straight_four_bar

    with pytest.warns(
        UserWarning, match=r"lies \d.*rad of actuator 'motor' motion from a singular"
    ):
        robot = _load(_straight_four_bar(CRANK + COUPLER + ROCKER))
    from pkdyn.model.home import dead_centre_distance

    d, unit, name = dead_centre_distance(robot, robot.q_home)
    assert unit == "rad" and name == "motor" and d < 1e-4
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        regular = _load(_straight_four_bar(0.45))  # a home far from any dead centre: silent
    assert dead_centre_distance(regular, regular.q_home) is None


def test_redundant_actuation_has_no_dead_centre_warning():
    """Redundant actuators cannot move one at a time: no dead-centre warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        walker = pkdyn.load("tripod", branches=4, geometry=False)
        four_arms = pkdyn.load("delta", arms=4, geometry=False)
    from pkdyn.model.home import dead_centre_distance

    for robot in (walker, four_arms):
        assert robot.actuated_v.size > robot.dof()
        assert dead_centre_distance(robot, robot.q_home) is None


@pytest.mark.parametrize("sig, code", [("SIGINT", 130), ("SIGTERM", 143)])
def test_the_live_viewer_exits_130_or_143(sig, code):
    """The README's exit codes: Ctrl-C 130, SIGTERM 143 (it used to exit 0)."""
    import signal
    import subprocess
    from pathlib import Path

    exe = str(Path(sys.executable).with_name("pkdyn"))
    proc = subprocess.Popen(
        [exe, "view", "five_bar"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        line = proc.stdout.readline() if proc.stdout else ""
        assert "viewer at http://127.0.0.1" in line, (
            line,
            proc.stderr.read() if proc.stderr else "",
        )
        proc.send_signal(getattr(signal, sig))
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    assert proc.returncode == code, err
    assert "viewer stopped" in out and "Traceback" not in err
