"""Command-line conventions: version, ``python -m pkdyn``, parameters, help, list, units, exit
codes, signals (one line, 130 / 143), outputs written whole or not at all."""

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import pkdyn
from pkdyn.cli import COMMANDS, EXIT_CODES, commands, main
from pkdyn.model.families import FAMILIES

PKDYN = str(Path(sys.executable).with_name("pkdyn"))


def run(*argv, timeout=120):
    return subprocess.run(
        [PKDYN, *argv], capture_output=True, text=True, timeout=timeout, check=False
    )


def test_version_and_python_m_pkdyn():
    out = run("--version")
    assert out.returncode == 0 and out.stdout.strip() == f"pkdyn {pkdyn.__version__}"
    mod = subprocess.run(
        [sys.executable, "-m", "pkdyn", "info", "five_bar", "--json"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert mod.returncode == 0, mod.stderr
    assert json.loads(mod.stdout)["name"] == "five_bar"


def test_param_several_at_once_or_repeated(capsys):
    a = ["info", "delta", "--json"]
    assert main([*a, "--param", "la=0.25", "lb=0.45"]) == 0
    once = json.loads(capsys.readouterr().out)
    assert main([*a, "--param", "la=0.25", "--param", "lb=0.45"]) == 0
    assert json.loads(capsys.readouterr().out) == once
    # and it is the robot those parameters describe
    robot = pkdyn.load("delta", la=0.25, lb=0.45, geometry=False)
    assert once["nq"] == robot.nq


@pytest.mark.parametrize(
    "argv, culprit",
    [
        (["info", "delta", "--param", "la"], "'la': expected NAME=VALUE"),
        (["info", "delta", "--param", "la=0.3", "la=0.4"], "'la' is given twice"),
        (["info", "delta", "--param", "nope=1"], "'nope'"),
        (["info", "delta", "--param", "la=abc"], "'la'"),
    ],
)
def test_param_errors_are_one_line(argv, culprit, capsys):
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert culprit in err and err.count("\n") == 1 and err.startswith("pkdyn: error:")


@pytest.mark.parametrize(
    "argv, hint",
    [
        ([], "see pkdyn --help"),
        (["info"], "see pkdyn info --help"),
        (["fk", "delta", "--qa", "x"], "see pkdyn forward-geometry --help"),
        (["nosuchcommand"], "see pkdyn --help"),
        (["tripod", "scenario", "--cycles", "x"], "see pkdyn tripod scenario --help"),
    ],
)
def test_usage_errors_exit_2_with_one_hint(argv, hint, capsys):
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.count("--help") == 1 and hint in err
    assert "pkdyn pkdyn" not in err


def test_help_documents_the_exit_codes():
    out = run("--help")
    assert out.returncode == 0
    text = " ".join(out.stdout.split())
    for code in EXIT_CODES:
        assert f"{code} " in text
    assert "list" in out.stdout


def test_list_shows_every_family_and_parameter_from_the_registry(capsys):
    import dataclasses

    assert main(["list", "--json"]) == 0
    listed = {f["name"]: f for f in json.loads(capsys.readouterr().out)["families"]}
    assert list(listed) == list(FAMILIES)
    for name, fam in FAMILIES.items():
        fields = [f.name for f in dataclasses.fields(fam.params)]
        assert [p["name"] for p in listed[name]["parameters"]] == fields
        assert all(p["doc"] for p in listed[name]["parameters"]), name  # documented
    assert main(["list", "--params"]) == 0
    text = capsys.readouterr().out
    assert "la = 0.2  # Arm length [m]." in text


def test_info_reports_platform_dof_and_internal_mobilities_apart(capsys):
    expected = {"delta": (3, 6), "gough_stewart": (6, 0), "five_bar": (2, 0)}
    for name, (dof, internal) in expected.items():
        assert main(["info", name, "--json"]) == 0
        info = json.loads(capsys.readouterr().out)
        assert (info["dof"], info["internal"]) == (dof, internal), name
    # the universal-jointed bars cannot spin: no internal mobility (seed 000)
    assert main(["info", "delta", "--param", "bar_joint=universal", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["dof"], info["internal"]) == (3, 0)


def test_prismatic_actuators_in_newtons_and_metres_per_second(capsys):
    assert main(["info", "gough_stewart", "--json"]) == 0
    acts = json.loads(capsys.readouterr().out)["actuation"]
    assert {a["type"] for a in acts} == {"prismatic"}
    assert acts[0]["units"] == {"position": "m", "velocity": "m/s", "effort": "N"}
    assert main(["info", "gough_stewart"]) == 0
    assert "800 N, 250 mm/s" in capsys.readouterr().out
    assert main(["size", "gough_stewart", "--trajectory", "sine", "--cycle-time", "1"]) == 0
    table = capsys.readouterr().out
    assert "[N]" in table and "[m/s]" in table and "[rad/s]" not in table.split("\n")[2]
    assert main(["ik", "gough_stewart", "--pose", "0", "0", "0.6"]) == 0
    assert capsys.readouterr().out.split("\n")[0].endswith(" m")
    assert main(["size", "delta", "--cycle-time", "0.6"]) == 0
    assert "[N m]" in capsys.readouterr().out


def test_repr_of_a_robot_is_one_short_line():
    robot = pkdyn.load("delta", geometry=False)
    text = repr(robot)
    assert "\n" not in text and len(text) < 300
    assert "'delta'" in text and "nv=27" in text and "3 actuators" in text


def test_json_output_is_never_nan_or_infinity(capsys):
    args = ["statics", "delta", "--pose", "0", "0", "-0.4", "--wrench", "1e308", "0", "0", "0"]
    assert main([*args, "0", "0", "--json"]) == 1
    err = capsys.readouterr().err
    assert "F: wrench" in err and "overflows" in err and err.count("\n") == 1


def test_plot_without_a_known_extension_is_an_error_before_any_work(tmp_path, capsys):
    target = tmp_path / "efforts"
    t0 = time.perf_counter()
    assert main(["size", "delta", "--plot", str(target)]) == 1
    assert time.perf_counter() - t0 < 5.0  # refused before the inverse dynamics
    err = capsys.readouterr().err
    assert str(target) in err and "extension" in err
    assert list(tmp_path.iterdir()) == []  # no PATH.png beside it
    assert main(["size", "delta", "--plot", str(tmp_path / "efforts.xyz")]) == 1
    assert "unknown figure format '.xyz'" in capsys.readouterr().err


def test_outputs_to_a_missing_directory_are_refused_before_the_work(tmp_path, capsys):
    for argv in (
        ["size", "delta", "--csv", str(tmp_path / "no" / "a.csv")],
        ["urdf", "delta", "-o", str(tmp_path / "no" / "a.urdf")],
        ["mjcf", "delta", "-o", str(tmp_path / "no" / "a.xml")],
        ["view", "delta", "--html", str(tmp_path / "no" / "a.html")],
    ):
        assert main(argv) == 1, argv
        err = capsys.readouterr().err
        assert str(tmp_path / "no") in err and err.count("\n") == 1


# ------------------------------------------------------------------------------------ signals

READY = "import sys; from pkdyn.cli import main; print('ready', flush=True); sys.exit(main({}))"


@pytest.mark.parametrize(
    "sig, code, word", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")]
)
def test_signals_print_one_line_and_exit_130_or_143(sig, code, word, tmp_path):
    """A long run stopped by Ctrl-C or SIGTERM: one line, no traceback, the old file intact."""
    csv = tmp_path / "adept.csv"
    csv.write_text("previous results\n")
    argv = ["size", "delta", "--cycles", "200", "--csv", str(csv)]
    proc = subprocess.Popen(
        [sys.executable, "-c", READY.format(argv)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline().strip() == "ready"
        time.sleep(1.5)  # inside main(): loading, mapping the trajectory
        assert proc.poll() is None, proc.communicate()
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == code, err
    assert err.strip().splitlines()[-1] == f"pkdyn: {word}"
    assert "Traceback" not in err and len([x for x in err.splitlines() if "pkdyn:" in x]) == 1
    assert csv.read_text() == "previous results\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adept.csv"]  # no temporary left


def test_broken_pipe_is_quiet():
    proc = subprocess.run(
        f"{PKDYN} urdf delta | head -c 10",
        shell=True,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert proc.stdout.startswith("<?xml") or proc.stdout.startswith("<")
    assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr, proc.stderr


def test_exit_codes_documented_in_the_guide():
    page = Path(__file__).resolve().parents[1] / "docs" / "guide" / "conventions.md"
    text = page.read_text(encoding="utf-8")
    for code in EXIT_CODES:
        assert f"`{code}`" in text, code


def test_env_without_bytecode_cache_still_runs():
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    out = subprocess.run(
        [PKDYN, "info", "five_bar"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=False,
    )
    assert out.returncode == 0 and "five_bar" in out.stdout


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_each_command_parses_alone_and_has_its_help(command, capsys):
    """A command line naming one command builds only that command's parser (quick start)."""
    from pkdyn.cli import _parser

    with pytest.raises(SystemExit) as stop:
        _parser([command, "--help"]).parse_args([command, "--help"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.startswith("usage: pkdyn ")
    sub = next(a for a in _parser([command])._actions if hasattr(a, "choices") and a.choices)
    full = next(a for a in _parser(["--help"])._actions if hasattr(a, "choices") and a.choices)
    assert command in sub.choices and set(sub.choices) < set(full.choices)
    assert set(full.choices) == set(COMMANDS)  # every registered command has its quick start


# Sphinx markup a terminal would show as it is: roles (:func:`x`), literals (``x``), `x`
RST = re.compile(r":[a-z]+(?::[a-z]+)?:`|``|(?<![\w'])`[^`\s][^`]*`")


def test_markup_detector_sees_roles_and_literals_not_plain_text():
    for marked in (":func:`pkdyn.load`", "``None``", "see :py:meth:`x`", "the `x` value"):
        assert RST.search(marked), marked
    for plain in ("|x| <= 1", "x: y", "don't", "a 'quoted' word", "10:30"):
        assert not RST.search(plain), plain


@pytest.mark.parametrize("command", list(commands()), ids=lambda c: " ".join(c.words) or "pkdyn")
def test_every_help_is_plain_text(command):
    text = command.parser.format_help() + command.help
    found = RST.search(text)
    assert found is None, f"pkdyn {' '.join(command.words)} --help shows {found.group(0)!r}"


def test_the_parameter_list_is_plain_text(capsys):
    assert main(["list", "--params"]) == 0
    text = capsys.readouterr().out
    assert "z_home = None  # Nacelle height" in text
    found = RST.search(text)
    assert found is None, f"pkdyn list --params shows {found.group(0)!r}"
    assert main(["list", "--json"]) == 0
    docs = [
        p["doc"] for f in json.loads(capsys.readouterr().out)["families"] for p in f["parameters"]
    ]
    assert not [d for d in docs if RST.search(d)]
