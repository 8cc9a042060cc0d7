"""Inputs are never outputs; reads refuse FIFOs and devices; numbers in any notation.

The matrix is built from the commands' own declarations (:mod:`pkdyn.cli._paths`): every
output option of every command is pointed at every input of the command and at every other
output, and must be refused before any work, the input left as it was. A test keeps the
declarations complete (every option that names a file is declared) and the table of base
command lines below in step with the commands.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest

from pkdyn.cli import commands, main
from pkdyn.cli._common import integer, number
from pkdyn.cli._paths import path_actions

ROBOT = "ROBOT"

BASE: dict[str, list[str]] = {
    "info": ["info", ROBOT],
    "urdf": ["urdf", ROBOT],
    "forward-geometry": ["fk", ROBOT, "--qa", "0", "0", "0"],
    "inverse-geometry": ["ik", ROBOT, "--pose", "0", "0", "-0.3"],
    "mobility": ["mobility", ROBOT],
    "jacobian": ["jacobian", ROBOT, "--qa", "0", "0", "0"],
    "singularity": ["singularity", ROBOT, "--qa", "0", "0", "0"],
    "statics": ["statics", ROBOT, "--qa", "0", "0", "0"],
    "simulate": ["simulate", ROBOT],
    "size": ["size", ROBOT],
    "collisions": ["collisions", ROBOT, "--qa", "0", "0", "0"],
    "workspace": ["workspace", ROBOT],
    "stiffness": ["stiffness", ROBOT, "--qa", "0", "0", "0"],
    "modes": ["modes", ROBOT, "--qa", "0", "0", "0"],
    "design": ["design"],
    "view": ["view", ROBOT],
    "mjcf": ["mjcf", ROBOT],
    "identify": ["identify", ROBOT],
    "tripod scenario": ["tripod", "scenario"],
    "accuracy": ["accuracy", ROBOT, "--qa", "0", "0", "0"],
    "calibrate": ["calibrate", ROBOT],
    "vibration": ["vibration", ROBOT],
}
"""A command line of each command with files (``ROBOT`` and the declared options are added)."""

NO_FILES = {"tripod", "demo", "list"}
"""Commands (or command groups) that name no file."""

PATH_DESTS = {
    "robot",
    "csv",
    "plot",
    "html",
    "out",
    "urdf",
    "save_study",
    "operating_points",
    "trajectory",
    "catalog",
    "gearboxes",
    "data",
    "predict",
    "measurements",
    "study",
    "points",
    "plugin",
}
"""Destinations of options that name files, whatever their command."""


def _commands():
    return [c for c in commands() if c.words]


def _name(action) -> str:
    if action.option_strings:
        return [s for s in action.option_strings if s.startswith("--")][0]
    return ROBOT


def _declared(words):
    cmd = next(c for c in _commands() if c.words == words)
    ins = [(_name(a), a) for a, r in path_actions(cmd.parser) if r.role == "input"]
    outs = [(_name(a), a, r) for a, r in path_actions(cmd.parser) if r.role == "output"]
    return ins, outs


def test_every_option_that_names_a_file_is_declared():
    for cmd in _commands():
        for action in cmd.parser._actions:
            metavar = " ".join(action.metavar) if isinstance(action.metavar, tuple) else ""
            metavar = metavar or str(action.metavar or "")
            looks = action.dest in PATH_DESTS or "FILE" in metavar or ".csv" in metavar
            names_only = bool(action.choices) or metavar == "NAME"  # (view --trajectory adept)
            if looks and action.dest != "help" and not names_only:
                assert hasattr(action, "pkdyn_path"), (cmd.words, action.option_strings)


def test_every_command_with_files_has_a_base_command_line():
    for cmd in _commands():
        name = " ".join(cmd.words)
        if list(path_actions(cmd.parser)):
            assert name in BASE, f"add '{name}' to BASE"
        elif name not in BASE:
            assert cmd.words[0] in NO_FILES, f"'{name}': no file? add it to NO_FILES or BASE"


# ---------------------------------------------------------------------- the matrix


def _cases():
    for name in BASE:
        ins, outs = _declared(tuple(name.split()))
        for o, _, _ in outs:
            for i, _ in ins:
                yield pytest.param(name, o, i, id=f"{name} {o} onto {i}")
            for o2, _, _ in outs:
                if o2 != o:
                    yield pytest.param(name, o, o2, id=f"{name} {o} onto {o2}")


def _command_line(tmp_path: Path, name: str, target: str, onto: str) -> tuple[list[str], Path]:
    """The command line writing ``target`` onto ``onto``'s file; that file."""
    ins, outs = _declared(tuple(name.split()))
    argv = list(BASE[name])
    files: dict[str, str] = {}
    for k, (opt, _) in enumerate(ins):
        path = tmp_path / (f"input{k}.csv" if opt != ROBOT else "robot.urdf")
        path.write_text(f"input {k}\n")
        files[opt] = str(path)
    argv = [files[ROBOT] if a == ROBOT else a for a in argv]
    for opt, _ in ins:
        if opt != ROBOT:
            argv += [opt, files[opt]]
    for k, (opt, _, role) in enumerate(outs):
        files.setdefault(opt, str(tmp_path / f"output{k}.{'png' if role.figure else 'csv'}"))
    if onto in files and onto not in [o for o, _, _ in outs]:
        files[target] = files[onto]  # onto an input
    else:
        files[target] = files[onto] = str(tmp_path / "same.csv")
    for opt, action, _ in outs:
        if opt in (target, onto) or action.required:
            argv += [opt, files[opt]]
    return argv, Path(files[onto])


@pytest.mark.parametrize("name, target, onto", list(_cases()))
def test_an_output_onto_an_input_or_another_output_is_refused(
    tmp_path, capsys, monkeypatch, name, target, onto
):
    monkeypatch.chdir(tmp_path)
    argv, victim = _command_line(tmp_path, name, target, onto)
    before = victim.read_text() if victim.exists() else None
    assert main(argv) == 1, argv
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "same file" in err, err
    assert (victim.read_text() if victim.exists() else None) == before


def _robot(tmp_path: Path) -> Path:
    path = tmp_path / "robot.urdf"
    assert main(["urdf", "five_bar", "-o", str(path)]) == 0
    return path


@pytest.mark.parametrize("how", ["symlink", "hard link", "relative", "dot-dot", "link to dir"])
def test_links_and_relative_paths_do_not_slip_through(tmp_path, capsys, monkeypatch, how):
    robot = _robot(tmp_path)
    before = robot.read_bytes()
    (tmp_path / "sub").mkdir()
    monkeypatch.chdir(tmp_path / "sub")
    if how == "symlink":
        (tmp_path / "link.urdf").symlink_to(robot)
        out = str(tmp_path / "link.urdf")
    elif how == "hard link":
        os.link(robot, tmp_path / "hard.urdf")
        out = str(tmp_path / "hard.urdf")
    elif how == "relative":
        monkeypatch.chdir(tmp_path)
        out = "./robot.urdf"
    elif how == "dot-dot":
        out = "../robot.urdf"
    else:
        (tmp_path / "d").symlink_to(tmp_path)
        out = str(tmp_path / "d" / "robot.urdf")
    assert main(["simulate", str(robot), "--duration", "0.01", "--csv", out]) == 1
    err = capsys.readouterr().err
    assert "same file as the input ROBOT" in err and err.count("\n") == 1
    assert robot.read_bytes() == before


def test_a_study_table_never_replaces_its_study_file(tmp_path, capsys):
    study = tmp_path / "s.study.yaml"
    study.write_text("family: delta\n")
    assert main(["design", "--study", str(study), "--out", str(tmp_path / "s.csv")]) == 1
    assert "same file as the input --study" in capsys.readouterr().err
    assert study.read_text() == "family: delta\n"


def test_a_file_read_while_working_is_never_written(tmp_path, capsys):
    """The description's YAML sidecar is read by the loader, not named on the command line."""
    robot = _robot(tmp_path)
    sidecar = tmp_path / "robot.yaml"
    sidecar.write_text("closed_loop: []\n")
    assert main(["mjcf", str(robot), "-o", str(sidecar)]) == 1
    err = capsys.readouterr().err
    assert "this command read" in err and err.count("\n") == 1
    assert sidecar.read_text() == "closed_loop: []\n"


# ---------------------------------------------------------------------- trailing slash


def test_a_trailing_slash_means_a_directory(tmp_path, capsys):
    old = tmp_path / "old.urdf"
    old.write_text("keep")
    assert main(["urdf", "five_bar", "-o", f"{old}/"]) == 1
    assert "trailing slash names a directory, but" in capsys.readouterr().err
    assert old.read_text() == "keep"
    assert main(["urdf", "five_bar", "-o", f"{tmp_path / 'newdir'}/"]) == 1
    assert "names a directory (trailing slash)" in capsys.readouterr().err
    assert not (tmp_path / "newdir").exists()
    assert main(["simulate", "five_bar", "--csv", f"{tmp_path}/"]) == 1
    assert "a directory, not a regular file" in capsys.readouterr().err


# ---------------------------------------------------------------------- inputs


@pytest.fixture
def fifo(tmp_path):
    """A FIFO; a thread feeds it after 20 s, so that a regression fails instead of hanging."""
    path = tmp_path / "fifo.csv"
    os.mkfifo(path)
    done = threading.Event()

    def unblock():
        if not done.wait(20.0):
            with open(path, "w") as fh:
                fh.write("garbage")

    threading.Thread(target=unblock, daemon=True).start()
    yield path
    done.set()


def _input_cases():
    for name in BASE:
        ins, _ = _declared(tuple(name.split()))
        for opt, _ in ins:
            for source in ("fifo", "link to /dev/zero", "directory"):
                yield pytest.param(name, opt, source, id=f"{name} {opt} {source}")


@pytest.mark.parametrize("name, option, source", list(_input_cases()))
def test_every_input_refuses_fifos_devices_and_directories(
    tmp_path, fifo, capsys, monkeypatch, name, option, source
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "zero.csv").symlink_to("/dev/zero")
    (tmp_path / "dir.csv").mkdir()
    bad = {"fifo": str(fifo), "link to /dev/zero": "zero.csv", "directory": "dir.csv"}[source]
    (tmp_path / "x.csv").write_text("x\n")  # (required inputs besides the one tested)
    argv = [bad if a == ROBOT and option == ROBOT else a for a in BASE[name]]
    argv = ["five_bar" if a == ROBOT else a for a in argv]
    cmd = next(c for c in _commands() if c.words == tuple(name.split()))
    tested = next((a for a in cmd.parser._actions if option in a.option_strings), None)
    argv += _required(cmd, tested, tuple(argv))
    if option != ROBOT:
        argv += [option, bad]
    assert main(argv) == 1, argv
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot be read" in err and "not a regular file" in err, err


def test_api_readers_refuse_a_fifo(tmp_path, fifo):
    import pkdyn
    from pkdyn.dynamics.trajectory_file import read_task_csv

    robot = pkdyn.load("five_bar", geometry=False)
    with pytest.raises(pkdyn.InvalidInputError, match="FIFO"):
        read_task_csv(robot, fifo)


# ---------------------------------------------------------------------- numbers


def _numeric_options():
    for cmd in _commands():
        for action in cmd.parser._actions:
            if action.type in (number, integer) and action.option_strings and not action.choices:
                yield pytest.param(cmd, action, id=f"{' '.join(cmd.words)} {_name(action)}")


def _dummy(action) -> list[str]:
    n = action.nargs if isinstance(action.nargs, int) else 1
    if action.type in (number, integer):
        return ["0"] * n
    if action.choices:
        return [str(next(iter(action.choices)))] * n
    return ["x.csv"] * n


def _argv_with(cmd, tested, text: str) -> list[str]:
    """A command line that parses: the required arguments, then ``tested`` with ``text``."""
    argv = list(cmd.words)
    for a in cmd.parser._actions:
        if not a.option_strings and a.nargs not in ("?", "*") and a.dest != "help":
            argv.append("five_bar")  # ROBOT
    argv += _required(cmd, tested)
    n = tested.nargs if isinstance(tested.nargs, int) else 1
    return [*argv, _name(tested), *([text] * n)]


def _required(cmd, tested, given: tuple[str, ...] = ()) -> list[str]:
    """The required options of ``cmd`` other than ``tested`` and those ``given``, dummies."""
    argv: list[str] = []
    for a in cmd.parser._actions:
        if a.option_strings and a.required and a is not tested:
            argv += [_name(a), *_dummy(a)]
    for g in cmd.parser._mutually_exclusive_groups:
        members = {s for a in g._group_actions for s in a.option_strings}
        if g.required and tested not in g._group_actions and not members & set(given):
            a = g._group_actions[0]
            argv += [_name(a), *_dummy(a)]
    return argv


@pytest.mark.parametrize("cmd, action", list(_numeric_options()))
@pytest.mark.parametrize("text", ["-3.6e-1", "-5E+1", "-.5", "-1e-3", "-7"])
def test_negative_numbers_in_any_notation_are_values(cmd, action, text):
    from pkdyn.cli import _parser

    argv = _argv_with(cmd, action, text)
    if action.type is integer and not float(text).is_integer():
        with pytest.raises(SystemExit):  # a count: a usage error, not an unknown option
            _parser(argv).parse_args(argv)
        return
    args = _parser(argv).parse_args(argv)
    value = getattr(args, action.dest)
    flat = value if isinstance(value, list) else [value]
    flat = [v for item in flat for v in (item if isinstance(item, list) else [item])]
    assert flat[-1] == float(text)


@pytest.mark.parametrize(
    "cmd, action", [p for p in _numeric_options() if p.values[1].type is number]
)
def test_nan_is_refused_on_every_numeric_option(capsys, cmd, action):
    assert main(_argv_with(cmd, action, "-nan")) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is nan (not a number)" in err


def test_a_mistyped_option_gets_a_suggestion(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["ik", "delta", "--poze", "0", "0", "-0.3"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unrecognized option '--poze'; did you mean '--pose'" in err
    with pytest.raises(SystemExit):
        main(["simulate", "five_bar", "--durations", "1"])
    assert "did you mean '--duration'" in capsys.readouterr().err


def test_old_output_spelling_warns_for_one_release(tmp_path, capsys):
    assert main(["urdf", "five_bar", "--output", str(tmp_path / "r.urdf")]) == 0
    assert "--output is deprecated" in capsys.readouterr().err
    assert (tmp_path / "r.urdf").exists()
