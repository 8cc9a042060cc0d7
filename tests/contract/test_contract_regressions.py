"""One named test per bad-input class (``test_contract_<class>_...``), with the cases the issues
reported: each keeps its class fixed whatever the drive happens to draw.

The contract is the harness's (``contract.contract``): API — a ``pkdyn.PkdynError`` of one line
naming the culprit, or a valid result; command line — one ``pkdyn: error:`` line, exit 1 or 2.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

import pkdyn
from contract import fixtures as fx
from contract.contract import check_api, check_cli, run_cli

DELTA_POSE = [0.0, 0.0, -0.4]


def refused(call, *names: str) -> str:
    """The call is refused by a one-line pkdyn error naming one of ``names``."""
    outcome, err = check_api(call, names, True, 30.0)
    assert outcome == "refused"
    return str(err)


def one_line(argv: list[str], *names: str, usage_ok: bool = True) -> str:
    """The command is refused with one ``pkdyn: error:`` line naming one of ``names``."""
    res = check_cli(argv, names, True, usage_ok, 30.0)
    return next(ln for ln in res.err.splitlines() if ln.startswith("pkdyn: error:"))


@pytest.fixture(scope="module")
def delta():
    return fx.robot("delta")


@pytest.fixture(scope="module")
def five_bar():
    return fx.robot("five_bar")


def _fd(robot):
    from pkdyn.dynamics import ForwardDynamics

    return ForwardDynamics(robot, "euler")


# ------------------------------------------------------------------------------ non_finite


def test_contract_non_finite_numbers_are_refused_naming_the_input(delta):
    refused(lambda: pkdyn.inverse_geometry(delta, [0.0, math.nan, -0.4]), "pose")
    refused(lambda: pkdyn.analysis.classify(delta, np.full(delta.nq, math.inf)), "q")
    refused(lambda: pkdyn.project(delta, delta.q_home, tol=math.nan), "tol")
    one_line(["ik", "delta", "--pose", "0", "0", "nan"], "pose", "nan")
    one_line(["simulate", "five_bar", "--dt", "nan"], "dt")


@pytest.mark.parametrize("dt", [math.nan, math.inf, 0.0, -1e-3])
def test_contract_non_finite_zero_negative_step_of_forward_dynamics(five_bar, dt):
    fd = _fd(five_bar)
    refused(lambda: fd.step(0.0, five_bar.q_home, np.zeros(five_bar.nv), dt), "dt")


# ------------------------------------------------------------------------------ huge


def test_contract_huge_counts_and_values_are_refused_up_front(delta, five_bar):
    refused(lambda: pkdyn.assembly_modes(five_bar, [1.2, 1.9], starts=10**12), "starts")
    refused(lambda: pkdyn.inverse_geometry(delta, [0.0, 0.0, -1e300]), "reach", "pose")
    one_line(["workspace", "delta", "--samples", "1000000000000"], "samples")
    one_line(["simulate", "five_bar", "--duration", "1e308"], "duration", "steps")


# ------------------------------------------------------------------------------ zero


def test_contract_zero_where_a_positive_number_is_due(five_bar):
    from pkdyn.dynamics import simulate

    refused(lambda: simulate(five_bar, 0.02, 0.0), "dt")
    refused(lambda: pkdyn.assembly_modes(five_bar, [1.2, 1.9], spread=0.0), "spread")
    one_line(["workspace", "delta", "--step", "0"], "step")
    one_line(["tripod", "scenario", "--no-machining", "--dt", "0"], "dt")


# ------------------------------------------------------------------------------ negative


def test_contract_negative_values_where_none_is_meaningful(five_bar):
    from pkdyn.dynamics import simulate

    refused(lambda: simulate(five_bar, -1.0, 1e-3), "duration")
    one_line(["size", "delta", "--payload", "-1"], "payload")


@pytest.mark.parametrize(
    "argv",
    [
        ["ik", "delta", "--pose", "0", "0", "-3.6e-1"],
        ["statics", "delta", "--pose", "0", "0", "-0.4", "--wrench", "0", "0", "-5e1", "0",
         "0", "0"],
        ["fk", "five_bar", "--qa", "1.2", "-5E-1"],
    ],
    ids=["pose", "wrench", "qa"],
)  # fmt: skip
def test_contract_negative_scientific_notation_is_a_number(argv):
    res = check_cli(argv, ("pose", "wrench", "qa"), False, False, 30.0)
    assert res.code == 0, res.err


# ------------------------------------------------------------------------------ wrong_type


@pytest.mark.parametrize(
    "joints",
    [[1, 2], 3, {"ankle_pitch": 1}, [["ankle_pitch"], ["ankle_roll", "x"]], None, [None]],
    ids=["ints", "int", "dict", "ragged", "None", "[None]"],
)
def test_contract_wrong_type_actuation_map_names(joints):
    ankle = fx.robot("parallel_ankle")
    refused(lambda: pkdyn.actuation_map(ankle, joints), "joints")
    if joints is not None:  # (actuators=None: every actuator, the default)
        refused(lambda: pkdyn.actuation_map(ankle, ["ankle_pitch", "ankle_roll"], joints), "actuat")


def test_contract_wrong_type_actuation_map_numbers():
    ankle = fx.robot("parallel_ankle")
    m = pkdyn.actuation_map(ankle, ["ankle_pitch", "ankle_roll"])
    refused(lambda: pkdyn.actuation_map(ankle, ["ankle_pitch", "ankle_roll"], q_ref="abc"), "q_ref")
    refused(lambda: pkdyn.actuation_map(ankle, ["ankle_pitch", "ankle_roll"], q_ref=[0.1]), "q_ref")
    refused(lambda: m.from_joints([[0.1, "x"]]), "qj")
    refused(lambda: m.from_joints({"a": 1}), "qj")
    refused(lambda: m.from_actuators([[0.1, 0.2], [0.3]]), "qa")


def test_contract_wrong_type_calibration_api(delta):
    from pkdyn.calibration import Measurements, calibrate

    refused(lambda: Measurements("position", "abc", np.zeros((2, 3))), "qa")
    refused(lambda: Measurements("position", [[0.1, 0.2, 0.3], [0.1]], np.zeros((2, 3))), "qa")
    refused(lambda: calibrate(delta, {"qa": [1, 2, 3]}), "measurements")
    refused(lambda: calibrate("delta", None), "robot")


def test_contract_wrong_type_identification_api(five_bar):
    from pkdyn.identification import Measurements, identify, parameter_set

    refused(lambda: Measurements("abc", [[0.1, 0.2]]), "t")
    refused(lambda: Measurements([0.0, 0.1], [[0.1, 0.2], [0.3]]), "qa")
    refused(lambda: identify(five_bar, [[0.0, 1.0]]), "measurements")
    refused(lambda: identify(five_bar, None), "measurements")
    refused(lambda: parameter_set(five_bar, 3), "groups", "parameters")


@pytest.mark.parametrize(
    "field, value",
    [("metrics", 3), ("metrics", None), ("ranges", [1, 2]), ("ranges", None), ("family", 3),
     ("n", "abc"), ("seed", -1), ("constraints", 3), ("objectives", {"a": 1}),
     ("requirement", 3), ("settings", [1])],
)  # fmt: skip
def test_contract_wrong_type_study_file_fields(tmp_path, field, value):
    import yaml

    from pkdyn.design import Study

    data = yaml.safe_load(fx.study_yaml())
    data[field] = value
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump(data))
    refused(lambda: Study.load(path), field, "study")
    one_line(["design", "--study", str(path), "--workers", "1"], field, "study")


@pytest.mark.parametrize(
    "text",
    ["closed_loop: 3\n", "name_mot: 3\n", "name_mot: [[a]]\n", "joint_name: {a: 1}\n",
     "type: [[a]]\n", "platform: 3\n", "closed_loop: null\n", "name_mot: null\n"],
)  # fmt: skip
def test_contract_wrong_type_sidecar_fields(tmp_path, text):
    """An int or a nested list where a list of names is due: refused, naming the field;
    ``null`` is a field not given: the robot loads as without it."""
    urdf = tmp_path / "r.urdf"
    urdf.write_bytes(fx.urdf_text("five_bar"))
    (tmp_path / "r.yaml").write_text(text)
    key = text.split(":")[0]
    if "null" in text:
        robot = pkdyn.load(str(urdf), geometry=False)
        assert robot.nq == fx.robot("five_bar").nq and len(robot.actuators) == 2
        return
    refused(lambda: pkdyn.load(str(urdf), geometry=False), key, "r.yaml")
    one_line(["info", str(urdf)], key, "r.yaml")


# ------------------------------------------------------------------------------ ragged


def test_contract_ragged_lists_are_refused_not_a_value_error(delta):
    from pkdyn.inputs import matrix, vector

    for value in ([[0.0, 0.0], [0.0]], [[0.0], [0.0, 0.0, 0.0]]):
        refused(lambda v=value: vector("x", v, 3), "x")
        refused(lambda v=value: matrix("x", v), "x")
    refused(lambda: pkdyn.forward_geometry(delta, [[0.5, 0.5], [0.5]]), "qa", "actuat")
    refused(lambda: pkdyn.analysis.static_equilibrium(delta, delta.q_home, [[0, 0], [1]]), "F")


# ------------------------------------------------------------------------------ empty


def test_contract_empty_lists_and_files(tmp_path, five_bar):
    refused(lambda: pkdyn.forward_geometry(five_bar, []), "qa", "actuat")
    refused(lambda: pkdyn.actuation_map(fx.robot("parallel_ankle"), []), "joints")
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    one_line(["size", "delta", "--trajectory", str(empty)], "empty.csv", "trajectory")
    one_line(["identify", "five_bar", "--measurements", str(empty), "-o", str(tmp_path / "x.urdf")],
             "empty.csv")  # fmt: skip


# ------------------------------------------------------------------------------ tables


def _tables(tmp_path: Path) -> dict[str, tuple[Path, list[str]]]:
    """Each table command: its valid input file and the command reading it."""
    traj, data, meas = tmp_path / "t.csv", tmp_path / "d.csv", tmp_path / "m.csv"
    traj.write_bytes(fx.trajectory_csv())
    data.write_bytes(fx.identification_csv())
    meas.write_bytes(fx.calibration_csv())
    out = str(tmp_path / "o.urdf")
    return {
        "trajectory": (traj, ["size", "delta", "--trajectory", "{}", "--json"]),
        "data": (data, ["identify", "five_bar", "--measurements", "{}", "-o", out, "--json"]),
        "measurements": (meas, ["calibrate", "delta", "--measurements", "{}", "-o", out,
                                "--json"]),
    }  # fmt: skip


def _argv(argv: list[str], path: Path) -> list[str]:
    return [str(path) if a == "{}" else a for a in argv]


@pytest.mark.parametrize("which", ["trajectory", "data", "measurements"])
def test_contract_header_only_tables(tmp_path, which):
    src, argv = _tables(tmp_path)[which]
    head = tmp_path / "head.csv"
    head.write_text(src.read_text().splitlines()[0] + "\n")
    one_line(_argv(argv, head), "head.csv", which)


@pytest.mark.parametrize("which", ["trajectory", "data", "measurements"])
@pytest.mark.parametrize("variant", ["bom", "crlf"])
def test_contract_bom_crlf_tables_read_like_plain_ones(tmp_path, which, variant):
    """A spreadsheet's byte-order mark, Windows line ends: the same result as without."""
    import json

    src, argv = _tables(tmp_path)[which]
    plain = run_cli(_argv(argv, src), 60)
    assert plain.code == 0, plain.err
    data = src.read_bytes()
    (tmp_path / variant).mkdir()
    other = tmp_path / variant / src.name
    other.write_bytes(b"\xef\xbb\xbf" + data if variant == "bom" else data.replace(b"\n", b"\r\n"))
    got = run_cli(_argv(argv, other), 60)
    assert got.code == 0, got.err
    a, b = json.loads(plain.out), json.loads(got.out)
    for key in ("output", "file", "trajectory", "seconds"):
        a.pop(key, None), b.pop(key, None)
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True).replace(
        f"/{variant}/", "/"
    )


@pytest.mark.parametrize("which", ["trajectory", "data", "measurements"])
def test_contract_non_utf8_tables(tmp_path, which):
    src, argv = _tables(tmp_path)[which]
    latin = tmp_path / "latin.csv"
    latin.write_bytes(src.read_bytes().replace(b"\n", " \xe9\n".encode("latin-1"), 1))
    one_line(_argv(argv, latin), "latin.csv", which)


@pytest.mark.parametrize("which", ["trajectory", "data", "measurements", "catalog"])
def test_contract_huge_cell_beyond_the_csv_field_limit(tmp_path, which):
    """``_csv.Error: field larger than field limit (131072)`` used to escape as a traceback."""
    if which == "catalog":
        cat = tmp_path / "cat.csv"
        cat.write_text("name,rated_torque [N m]\nm1," + "1" * 200_000 + "\n")
        one_line(["size", "delta", "--dt", "0.004", "--catalog", str(cat)], "cat.csv")
        return
    src, argv = _tables(tmp_path)[which]
    lines = src.read_text().splitlines()
    lines[1] = lines[1] + "x" * 200_000
    big = tmp_path / "big.csv"
    big.write_text("\n".join(lines) + "\n")
    one_line(_argv(argv, big), "big.csv", which)


# ------------------------------------------------------------------------------ fifo, device, link


@pytest.mark.parametrize("which", ["trajectory", "data", "measurements"])
@pytest.mark.parametrize("kind", ["fifo", "device", "link"])
def test_contract_fifo_device_link_inputs_are_refused_before_reading(tmp_path, which, kind):
    _, argv = _tables(tmp_path)[which]
    if kind == "fifo":
        path = tmp_path / "pipe.csv"
        os.mkfifo(path)
    elif kind == "device":
        path = Path("/dev/zero")
    else:
        path = tmp_path / "zero.csv"
        path.symlink_to("/dev/zero")
    one_line(_argv(argv, path), path.name, which)


# ------------------------------------------------------------------------------ onto_input


def test_contract_onto_input_predicted_efforts_onto_the_motion(tmp_path):
    """``identify --predict other.csv --csv other.csv`` overwrote the measured motion."""
    data, other = tmp_path / "d.csv", tmp_path / "o.csv"
    data.write_bytes(fx.identification_csv())
    other.write_bytes(fx.identification_csv(9, 1.0))
    before = other.read_bytes()
    argv = ["identify", "five_bar", "--measurements", str(data), "-o", str(tmp_path / "x.urdf"),
            "--predict", str(other), "--csv", str(other)]  # fmt: skip
    one_line(argv, "o.csv", "csv")
    assert other.read_bytes() == before


# ------------------------------------------------------------------------------ plug-ins, exits


def test_contract_plugin_named_like_an_installed_module(tmp_path):
    import json

    from pkdyn.design import load_plugin

    for name in ("json", "numpy", "yaml"):
        path = tmp_path / f"{name}.py"
        path.write_text("X = 1\n")
        refused(lambda p=path: load_plugin(str(p)), "plugin", f"{name}.py")
        argv = ["design", "delta", "--plugin", str(path), "--range", "la=0.2:0.3",
                "--metric", "moving_mass", "--n", "2", "--workers", "1"]  # fmt: skip
        one_line(argv, f"{name}.py")
    assert json.dumps([1]) == "[1]"  # the standard library's json still in place


EXIT_PLUGIN = "import sys\nsys.exit(0)\n"
EXIT_METRIC = (
    "import sys\nfrom pkdyn.design import metric\n\n\n"
    "@metric('contract_exits', '-', 'exits')\ndef exits(robot, ctx):\n    sys.exit(0)\n"
)


@pytest.mark.parametrize("where", ["plugin", "metric"])
def test_contract_exits_in_a_plugin_or_metric_fail_the_study(tmp_path, where):
    """``sys.exit`` inside user code made a study exit 0 with no table."""
    plugin = tmp_path / f"exits_{where}.py"
    plugin.write_text(EXIT_PLUGIN if where == "plugin" else EXIT_METRIC)
    out = tmp_path / "study.csv"
    argv = ["design", "delta", "--plugin", str(plugin), "--range", "la=0.2:0.3", "--metric",
            "contract_exits" if where == "metric" else "moving_mass", "--n", "2", "--workers",
            "1", "--out", str(out)]  # fmt: skip
    line = one_line(argv, "exit", "plugin")
    assert "sys.exit" in line or "SystemExit" in line, line
    assert not out.exists()


# ------------------------------------------------------------------------------ identification


def test_contract_zero_efforts_and_tiny_cutoff_in_identify(tmp_path):
    """All-zero efforts or a tiny ``--cutoff`` raised numpy's ``LinAlgError``."""
    lines = fx.positions_csv().decode().splitlines()
    head = lines[0].split(",")
    zero = [lines[0]] + [
        ",".join("0" if head[i].startswith("tau") else v for i, v in enumerate(ln.split(",")))
        for ln in lines[1:]
    ]
    z, p = tmp_path / "zero.csv", tmp_path / "pos.csv"
    z.write_text("\n".join(zero) + "\n")
    p.write_bytes(fx.positions_csv())
    out = str(tmp_path / "x.urdf")
    one_line(["identify", "five_bar", "--measurements", str(z), "-o", out], "tau", "zero.csv")
    for cutoff in ("1e-300", "1e-6", "5e-324"):
        one_line(["identify", "five_bar", "--measurements", str(p), "-o", out, "--cutoff", cutoff],
                 "cutoff")  # fmt: skip
    assert not Path(out).exists()


# ------------------------------------------------------------------------------ after the merge


def test_contract_wrong_type_path_is_not_a_file_descriptor(tmp_path, delta):
    """An int path was opened as a file descriptor (``3``: whatever the process had open)."""
    from pkdyn.calibration import Measurements, read_csv, write_csv

    refused(lambda: read_csv(3, delta), "path")
    m = Measurements("position", np.zeros((2, 3)), np.zeros((2, 3)))
    refused(lambda: write_csv(3, delta, m), "path")


def test_contract_trailing_slash_on_a_figure_writes_nothing(tmp_path):
    """``fig.png/`` was written as ``fig.png``: pathlib drops the slash the user typed."""
    from pkdyn.plotting._save import save_figure

    matplotlib = pytest.importorskip("matplotlib.figure")
    target = f"{tmp_path}/fig.png/"
    refused(lambda: save_figure(matplotlib.Figure(), target, 50), target, "fig.png")
    assert list(tmp_path.iterdir()) == []


def test_contract_non_finite_readings_are_refused(delta):
    """NaN readings turned into NaN joint coordinates, and ``rates="no"`` counted as true."""
    refused(lambda: delta.joint_coordinates([0.0, math.nan, 0.0]), "readings")
    refused(lambda: delta.readings([0.0, 0.0, math.inf]), "qa")
    refused(lambda: delta.joint_coordinates([0.0, 0.0, 0.0], rates="no"), "rates")


@pytest.mark.parametrize("i", [-1, 2.5, math.nan, 10**12, "0"])
def test_contract_fraction_negative_huge_row_index(i):
    """``where(i)`` answered for a negative row, and raised IndexError or ValueError else."""
    from pkdyn.calibration import Measurements

    m = Measurements("position", np.zeros((2, 3)), np.zeros((2, 3)))
    refused(lambda: m.where(i), "i")


def test_contract_wrong_type_result_given_to_a_plot():
    """A plotter given something else than its result raised AttributeError or TypeError."""
    from pkdyn.plotting import plot_grid_map, plot_mel_study, plot_vibration

    refused(lambda: plot_grid_map(3), "result")
    refused(lambda: plot_vibration("result.csv"), "result")
    refused(lambda: plot_mel_study({}), "study")


@pytest.mark.parametrize(
    "argv",
    [
        ["stiffness", "delta", "--pose", "0", "0", "-0.4", "--actuator-stiffness", "2e4"],
        ["accuracy", "delta", "--pose", "0", "0", "-0.4", "--samples", "4"],
        ["modes", "five_bar", "--map", "xy", "--grid", "3", "--actuator-stiffness", "2e4"],
    ],
    ids=["stiffness", "accuracy", "modes-map"],
)
@pytest.mark.parametrize("address", ["", " "], ids=["empty", "blank"])
def test_contract_empty_scheduler_address_is_refused(argv, address):
    """``--scheduler ''`` ran on local processes (an empty address counted as none) where the
    work is shared, and was ignored where it is not (a closed form)."""
    one_line([*argv, "--scheduler", address], "--scheduler")


def test_contract_empty_scheduler_address_is_refused_by_the_api(delta):
    from pkdyn.executors import make_executor
    from pkdyn.precision import monte_carlo

    refused(lambda: make_executor(scheduler=""), "scheduler")
    refused(lambda: make_executor(scheduler=8786), "scheduler")
    from pkdyn.precision.parameters import parameter_model

    q = fx.q_at("delta", tuple(DELTA_POSE))
    model = parameter_model(delta, "auto")
    refused(lambda: monte_carlo(delta, q, model, 1e-5, 4, scheduler="  "), "scheduler")
