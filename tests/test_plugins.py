"""Plug-ins load only when their user asks: ``--plugin``, ``load_plugin`` or an installed entry
point; a study file naming ``module:attribute`` never imports code by itself.

The plug-in of these tests writes a marker file when imported: a refused study leaves none.
"""

import itertools
import sys
import textwrap

import pytest

from pkdyn.cli import main
from pkdyn.design import Study, load_plugin, metric, plugins, run_study
from pkdyn.exceptions import InvalidInputError

_names = itertools.count()

CODE = """
from pathlib import Path
Path(__file__).with_name("imported.txt").write_text("imported")
from pkdyn.design import Metric, Parametrisation, metric

arm = Metric("arm_{k}", "m", lambda robot, ctx: robot.params.la)


def _scaled(values, defaults):
    return {{"la": 0.25 * float(values["k"])}}


scaled = Parametrisation("scaled_{k}", ("k",), _scaled)


@metric("bar_{k}", "m", "the bar length")
def bar(robot, ctx):
    return robot.params.lb
"""


@pytest.fixture
def plugin(tmp_path, monkeypatch):
    """A plug-in module ``plug_K`` in ``tmp_path`` (on the path, the working directory)."""
    k = next(_names)
    name = f"plug_{k}"
    (tmp_path / f"{name}.py").write_text(textwrap.dedent(CODE.format(k=k)))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.chdir(tmp_path)
    return name, k, tmp_path / "imported.txt"


def _study_file(tmp_path, body):
    f = tmp_path / "s.yaml"
    f.write_text("family: delta\nn: 2\nranges: {la: [0.2, 0.3]}\n" + body)
    return str(f)


@pytest.mark.parametrize("kind", ["metric", "parametrisation"])
def test_a_study_file_never_imports_code(plugin, tmp_path, capsys, kind):
    name, k, marker = plugin
    if kind == "metric":
        body = f"metrics: ['{name}:arm']\n"
    else:
        body = f"metrics: [moving_mass]\nparametrisation: '{name}:scaled'\n"
    f = _study_file(tmp_path, body)
    assert main(["design", "--study", f, "--workers", "1"]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert f"module '{name}' is not a loaded plug-in" in err and f"--plugin {name}" in err
    assert not marker.exists() and name not in sys.modules
    with pytest.raises(InvalidInputError, match="never imports code"):
        Study("delta", {"la": (0.2, 0.3)}, metrics=[f"{name}:arm"])
    assert not marker.exists()


def test_plugin_on_the_command_line(plugin, tmp_path, capsys):
    name, k, marker = plugin
    f = _study_file(tmp_path, f"metrics: ['{name}:arm', bar_{k}]\n")
    assert main(["design", "--study", f, "--plugin", name, "--workers", "1", "--json"]) == 0
    assert marker.exists()
    import json

    best = json.loads(capsys.readouterr().out)["best"]
    assert best[f"arm_{k}"] == best["la"]
    s = Study.load(f)
    t = run_study(s, workers=1).designs
    assert list(t.column(f"arm_{k}")) == list(t.column("la"))
    assert t.column(f"bar_{k}")[0] == pytest.approx(s.space.params(t.x[0]).lb)


def test_plugin_file_and_parametrisation(plugin, tmp_path):
    name, k, marker = plugin
    load_plugin(str(tmp_path / f"{name}.py"))
    s = Study("delta", {"k": (0.8, 1.2)}, metrics=["moving_mass"], n=2,
              parametrisation=f"{name}:scaled")  # fmt: skip
    t = run_study(s, workers=2).designs  # a file plug-in travels to the workers by value
    assert t.feasible.all()
    assert [s.space.params(x).la for x in t.x] == pytest.approx(0.25 * t.column("k"))


def test_installed_entry_point(tmp_path, monkeypatch):
    k = next(_names)
    name = f"plug_{k}"
    (tmp_path / f"{name}.py").write_text(textwrap.dedent(CODE.format(k=k)))
    info = tmp_path / f"{name}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[pkdyn.plugins]\nmine = {name}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(plugins, "_ENTRY_POINTS", [])
    s = Study("delta", {"la": (0.2, 0.3)}, metrics=[f"bar_{k}", f"{name}:arm"], n=2)
    assert s.metric_names == [f"bar_{k}", f"arm_{k}"]
    assert (tmp_path / "imported.txt").exists()


@pytest.mark.parametrize(
    "arg, match",
    [
        ("no_such_module_xyz", "no module named 'no_such_module_xyz'"),
        ("./missing.py", "is not a .py file"),
        ("broken", "'broken' failed to import: ZeroDivisionError: division by zero"),
    ],
)
def test_bad_plugins_are_one_line(tmp_path, monkeypatch, capsys, arg, match):
    (tmp_path / "broken.py").write_text("1 / 0\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.chdir(tmp_path)
    code = main(["design", "delta", "--range", "la=0.2:0.3", "--metric", "moving_mass",
                 "--plugin", arg])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1 and match in err, err


def test_a_plugin_cannot_replace_a_built_in_metric():
    with pytest.raises(InvalidInputError, match="'peak_effort' is a built-in name"):
        metric("peak_effort", "N m")(lambda robot, ctx: 0.0)
