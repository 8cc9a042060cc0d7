"""``pkdyn vibration``, ``size --fastest --band`` and the vibration design metrics, as a user
runs them: outputs, JSON keys and units, one-line errors naming the culprit."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.exceptions import InvalidInputError, PkdynError
from pkdyn.precision.vibration import vibration

BASE = ["vibration", "delta", "--actuator-stiffness", "2e4", "--payload", "0.5"]


def _json(capsys):
    return json.loads(capsys.readouterr().out)


def test_vibration_command_reports_the_figures_and_writes_its_files(tmp_path, capsys):
    csv_path, png, html = tmp_path / "v.csv", tmp_path / "v.png", tmp_path / "v.html"
    argv = [*BASE, "--trajectory", "p2p", "--cycle-time", "0.15", "--dwell", "0.2",
            "--band", "2e-5", "--json", "--csv", str(csv_path), "--plot", str(png),
            "--html", str(html)]  # fmt: skip
    assert main(argv) == 0
    out = _json(capsys)
    for key in (
        "peak_deviation",
        "residual_amplitude",
        "settling_time",
        "band",
        "frequencies",
        "method",
        "static_deflection",
        "dominant_modes",
        "feedforward",
        "damping",
    ):
        assert key in out, key  # fmt: skip
    assert out["method"] == "modal" and out["feedforward"] == "none"
    assert out["band"] == 2e-5 and out["dwell"] == 0.2
    assert len(out["frequencies"]["start"]) == len(out["frequencies"]["end"]) == 3
    assert out["damping"]["damping_ratio"] == 0.02
    assert 0.0 < out["residual_amplitude"] < out["peak_deviation"] < 1e-3
    with open(csv_path, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0][:4] == ["t", "deviation_x", "deviation_y", "deviation_z"]
    norm = np.array([float(r[4]) for r in rows[1:]])
    assert np.max(norm) == pytest.approx(out["peak_deviation"], rel=2e-3)
    assert png.stat().st_size > 1000 and "<html" in html.read_text()[:2000].lower()


def test_a_motion_read_from_a_file(tmp_path, capsys):
    t = np.linspace(0.0, 0.2, 201)
    u = t / 0.2
    x = -0.05 + 0.1 * (10 * u**3 - 15 * u**4 + 6 * u**5)
    path = tmp_path / "move.csv"
    rows = "".join(f"{a:.6f},{b:.9f},0,-0.4\n" for a, b in zip(t, x, strict=True))
    path.write_text("t,x,y,z\n" + rows)
    assert main([*BASE, "--trajectory", str(path), "--dwell", "0.2", "--json"]) == 0
    out = _json(capsys)
    assert out["trajectory"] == "move.csv (task space)" and out["duration"] == pytest.approx(0.2)
    assert main([*BASE, "--trajectory", str(path), "--cycle-time", "0.3"]) == 1
    assert "--cycle-time" in capsys.readouterr().err


def test_table_has_units_and_shaping_reports_the_unshaped_motion_too(capsys):
    argv = [*BASE, "--trajectory", "p2p", "--cycle-time", "0.15", "--dwell", "0.2",
            "--shaper", "zv"]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "peak deviation:" in text and " um" in text and "ZV shaping" in text
    assert "without shaping:" in text and " Hz" in text
    assert main([*argv, "--json"]) == 0
    out = _json(capsys)
    assert out["shaper"]["kind"] == "zv" and out["unshaped"]["shaper"] is None
    assert out["residual_amplitude"] < out["unshaped"]["residual_amplitude"]


@pytest.mark.parametrize(
    "extra, culprit",
    [
        (["--method", "multibody", "--actuator-stiffness", "inf"], "finite"),
        (["--band", "-1"], "band"),
        (["--dwell", "0"], "dwell"),
        (["--damping-ratio", "-0.1"], "damping_ratio"),
        (["--actuator-damping", "1", "2"], "actuator_damping"),
        (["--trajectory", "sine"], "rest"),
        (["--trajectory", "nope"], "trajectory"),
        (["--modes", "0"], "modes"),
        (["--shaper-modes", "2"], "--shaper-modes"),
        (["--scale", "0"], "--scale"),
        (["--slow", "-1"], "--slow"),
        (["--material", "cheese"], "cheese"),
    ],
)
def test_bad_options_are_one_line_naming_the_culprit(extra, culprit, capsys):
    assert main([*BASE, "--cycle-time", "0.3", *extra]) == 1
    err = capsys.readouterr().err
    assert err.startswith("pkdyn: error:") and err.count("\n") == 1 and culprit in err, err


def test_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as e:
        main([*BASE, "--method", "fem"])
    assert e.value.code == 2
    with pytest.raises(SystemExit) as e:
        main([*BASE, "--feedforward", "full"])
    assert e.value.code == 2


def test_bad_inputs_of_the_function_are_typed():
    robot = pkdyn.load("delta")
    for kwargs, name in (
        (dict(method="fem"), "method"),
        (dict(feedforward="full"), "feedforward"),
        (dict(shaper="zvdd"), "shaper"),
        (dict(band=float("nan")), "band"),
        (dict(dwell=1e3), "dwell"),
        (dict(payload=-1.0), "payload"),
        (dict(poses=1), "poses"),
        (dict(point=[0.0, 0.0]), "point"),
    ):
        with pytest.raises(InvalidInputError, match=name):
            vibration(robot, "adept", actuator_stiffness=2e4, **kwargs)
    with pytest.raises(InvalidInputError, match="robot"):
        vibration("delta", "adept")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="stiffness"):
        vibration(robot, "adept")  # the library Delta describes no servo stiffness


def test_size_fastest_settle_compares_shaped_and_unshaped(tmp_path, capsys):
    from support.slider import slider

    robot = slider(tmp_path, effort=12.0)
    urdf = tmp_path / "slider.urdf"
    argv = ["size", str(urdf), "--trajectory", "p2p", "--fastest", "--band", "5e-4",
            "--dwell", "0.05", "--actuator-stiffness", str((2 * np.pi * 20) ** 2),
            "--damping-ratio", "0.05", "--json"]  # fmt: skip
    assert main(argv) == 0
    out = _json(capsys)["settling"]
    u, s = out["unshaped"], out["shaped"]
    assert s["shaper"] == "zv" and u["shaper"] is None
    fastest = out["fastest_motion_time"]
    assert u["scale"] >= 1.0 and u["motion_time"] == pytest.approx(u["scale"] * fastest, rel=1e-9)
    assert u["settling_time"] <= 0.05 + 1e-12 and u["cycle_time"] == pytest.approx(
        u["motion_time"] + 0.05
    )
    # shaping buys a shorter cycle here (the residual of a bang-bang stop is mostly one mode)
    assert s["cycle_time"] < u["cycle_time"]
    # the search stops at the first settling slow-down: a little faster does not settle
    from pkdyn.dynamics.trajectory import named_task
    from pkdyn.precision.vibration_fastest import fastest_settling

    res = fastest_settling(
        robot, named_task(robot, "p2p"), 5e-4, 0.05, actuator_stiffness=(2 * np.pi * 20) ** 2,
        damping_ratio=0.05, shaper=None, max_scale=u["scale"] * 0.995,
    )  # fmt: skip
    assert res.unshaped.scale is None
    # the rigid feedforward cancels the one-mode system's vibration: the fastest motion settles
    rigid = fastest_settling(
        robot, named_task(robot, "p2p"), 5e-4, 0.05, actuator_stiffness=(2 * np.pi * 20) ** 2,
        damping_ratio=0.05, shaper=None, feedforward="rigid",
    )  # fmt: skip
    assert rigid.unshaped.scale == 1.0
    assert rigid.unshaped.vibration.peak_deviation < 1e-12


def test_settle_options_need_fastest(capsys):
    assert main(["size", "delta", "--band", "1e-4"]) == 1
    assert "--fastest" in capsys.readouterr().err
    assert main(["size", "delta", "--dwell", "0.2"]) == 1
    assert "--band" in capsys.readouterr().err


def test_design_metrics_trade_stiffness_for_settling(tmp_path):
    from pkdyn.design.context import Conditions, DesignContext
    from pkdyn.design.metrics import METRICS
    from pkdyn.design.study import Study

    c = Conditions(
        trajectory="p2p",
        trajectory_options={"duration": 0.15},
        payload=0.5,
        actuator_stiffness=2e4,
        band=5e-7,
        dwell=0.3,
    )
    robot = pkdyn.load("delta")
    ctx = DesignContext(robot, c)
    settle = METRICS["settling_time"](robot, ctx)
    residual = METRICS["residual_amplitude"](robot, ctx)
    total = METRICS["motion_settled"](robot, ctx)
    direct = vibration(robot, "p2p", cycle_time=0.15, payload=0.5, actuator_stiffness=2e4,
                       band=5e-7, dwell=0.3)  # fmt: skip
    assert settle == pytest.approx(direct.settling_time, rel=1e-9)
    assert residual == pytest.approx(direct.residual_amplitude, rel=1e-9)
    assert total == pytest.approx(0.15 + settle, rel=1e-9)
    assert settle > 0.0
    # a stiffer servo settles sooner
    stiff = DesignContext(robot, Conditions(**{**c.as_dict(), "actuator_stiffness": 8e4}))
    assert METRICS["settling_time"](robot, stiff) < settle
    # refused before any design is built: a duty cycle that ends in motion, no stiffness
    with pytest.raises(InvalidInputError, match="rest"):
        Study("delta", {"la": [0.18, 0.22]}, metrics=["settling_time"], trajectory="sine",
              settings={"actuator_stiffness": 2e4})  # fmt: skip
    with pytest.raises(InvalidInputError, match="stiffness"):
        Study("delta", {"la": [0.18, 0.22]}, metrics=["vibration"])
    with pytest.raises(InvalidInputError, match="band"):
        Conditions(band=-1.0)
    # a design that does not settle is infeasible, with the reason
    never = DesignContext(robot, Conditions(**{**c.as_dict(), "band": 1e-9, "dwell": 0.05}))
    with pytest.raises(PkdynError, match="does not settle"):
        METRICS["settling_time"](robot, never)
