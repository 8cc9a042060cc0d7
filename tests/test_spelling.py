"""One spelling per option: in every command and every public function, one meaning, one name.

The command line is read from its parser (:func:`pkdyn.cli.commands`): every option of every
command. A meaning of the table below has one spelling; a former spelling is only accepted as a
deprecated alias of it (it warns, for one release). Options with the same help text in two
commands mean the same and must be spelled the same. The public functions are read from their
signatures: no former keyword remains a parameter, and each is still accepted, with a
``DeprecationWarning``, by the function it was renamed in.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import pkgutil
import warnings
from collections import defaultdict

import pytest

import pkdyn
from pkdyn.cli import _parser, commands
from pkdyn.exceptions import InvalidInputError
from pkdyn.results import renamed_keyword

MEANINGS = {
    "the command's main output file": ("--out", ("--output",)),
    "builder parameters NAME=VALUE": ("--param", ("--fix",)),
    "actuated joint coordinates": ("--qa", ("--q",)),
    "settling band on the tool's deviation [m]": ("--band", ("--settle",)),
    "how many entries of a ranked list are shown": ("--top", ("--show", "--count")),
    "the table of measurements a command reads": ("--measurements", ("--data",)),
    "integration step of a simulation [s]": ("--step", ("--timestep",)),
}
"""Meaning: (its one spelling, former spellings accepted for one release with a warning)."""

API_FORMER = {"progress_bar": "progress", "show": "top", "centre": "center", "output": "out"}
"""Keywords no public function has any more (the spelling of every other function instead)."""


def _options():
    """``(command words, action)`` of every option of every command (help and version aside)."""
    for command in commands():
        for action in command.parser._actions:
            if isinstance(
                action,
                argparse._SubParsersAction | argparse._HelpAction | argparse._VersionAction,
            ):
                continue
            if action.option_strings:
                yield " ".join(command.words) or "pkdyn", action


def _spellings(action) -> tuple[str, ...]:
    """The option strings of ``action`` without its deprecated ones."""
    old = getattr(action, "deprecated", ())
    return tuple(s for s in action.option_strings if s not in old)


def test_a_meaning_has_one_spelling_and_former_ones_only_warn():
    bad = []
    for where, action in _options():
        for meaning, (spelling, former) in MEANINGS.items():
            for old in former:
                if old not in action.option_strings:
                    continue
                if spelling not in _spellings(action):
                    bad.append(f"{where}: {old} means {meaning}: spell it {spelling}")
                elif old not in getattr(action, "deprecated", ()):
                    bad.append(f"{where}: {old} is an alias of {spelling}, not deprecated")
    assert not bad, "\n".join(bad)


def test_options_with_the_same_help_are_spelled_the_same():
    by_help = defaultdict(set)
    for where, action in _options():
        if action.help and action.help != argparse.SUPPRESS:
            by_help[action.help].add((_spellings(action), where))
    bad = [
        f"{help_!r}: " + "; ".join(f"{'/'.join(s)} in {w}" for s, w in sorted(found))
        for help_, found in by_help.items()
        if len({s for s, _ in found}) > 1
    ]
    assert not bad, "\n".join(bad)


def test_every_command_uses_the_one_spelling():
    """The meanings of the table are where they should be (the check above sees them)."""
    seen = defaultdict(set)
    for where, action in _options():
        for meaning, (spelling, _) in MEANINGS.items():
            if spelling in _spellings(action):
                seen[meaning].add(where)
    assert {"urdf", "mjcf", "calibrate", "identify", "design"} <= seen[
        "the command's main output file"
    ]
    assert {"size", "modes", "accuracy", "collisions"} <= seen[
        "how many entries of a ranked list are shown"
    ]
    assert {"size", "vibration", "design"} <= seen["settling band on the tool's deviation [m]"]
    assert {"calibrate", "identify"} <= seen["the table of measurements a command reads"]
    assert {"simulate", "mjcf"} <= seen["integration step of a simulation [s]"]


@pytest.mark.parametrize(
    ("command", "old", "new"),
    [
        (["fk", "delta"], ["--q", "0.1", "0.2", "0.3"], ["--qa", "0.1", "0.2", "0.3"]),
        (["size", "delta", "--fastest"], ["--settle", "1e-4"], ["--band", "1e-4"]),
        (["size", "delta"], ["--show", "2"], ["--top", "2"]),
        (["modes", "delta", "--qa", "0.5", "0.5", "0.5"], ["--count", "3"], ["--top", "3"]),
        (["identify", "five_bar", "-o", "x.urdf"], ["--data", "m.csv"],
         ["--measurements", "m.csv"]),
        (["mjcf", "delta"], ["--timestep", "2e-3"], ["--step", "2e-3"]),
        (["design", "delta"], ["--fix", "la=0.2", "--fix", "lb=0.4"],
         ["--param", "la=0.2", "--param", "lb=0.4"]),
        (["urdf", "delta"], ["--output", "x.urdf"], ["-o", "x.urdf"]),
    ],
)  # fmt: skip
def test_a_former_spelling_parses_as_the_new_one_with_one_warning(capsys, command, old, new):
    old, new = command + old, command + new
    parsed = _parser(old).parse_args(old)
    err = capsys.readouterr().err
    assert vars(parsed) == vars(_parser(new).parse_args(new))
    former = next(w for w in old if w not in new)
    assert err.count("\n") == 1 and f"pkdyn: warning: {former} is deprecated" in err
    assert capsys.readouterr().err == ""  # (the new spelling says nothing)


def _public_functions():
    """``(name, function)`` of every public function and method of pkdyn's core and plots."""
    seen = set()
    for info in pkgutil.walk_packages(pkdyn.__path__, "pkdyn."):
        if ".cli" in info.name or ".viewer" in info.name or info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name, None)
            members = [(name, obj)] if inspect.isfunction(obj) else []
            if inspect.isclass(obj):
                members = [
                    (f"{name}.{m}", f)
                    for m, f in vars(obj).items()
                    if inspect.isfunction(f) and (not m.startswith("_") or m == "__init__")
                ]
            for _, fn in members:
                if id(fn) not in seen:
                    seen.add(id(fn))
                    yield f"{fn.__module__}.{fn.__qualname__}", fn


def test_no_public_function_keeps_a_former_spelling():
    bad = [
        f"{name}({p}=...): spell it {API_FORMER[p]}"
        for name, fn in _public_functions()
        for p in inspect.signature(fn).parameters
        if p in API_FORMER
    ]
    assert not bad, "\n".join(bad)


def test_renamed_keywords_still_work_with_a_warning():
    renamed = {
        name: fn.renamed_keywords
        for name, fn in _public_functions()
        if getattr(fn, "renamed_keywords", None)
    }
    # the renames of this release, each on the functions that had the old spelling
    assert renamed["pkdyn.precision.monte_carlo.monte_carlo"] == {"progress_bar": "progress"}
    assert renamed["pkdyn.identification.identify.identify"] == {"data": "measurements"}
    assert renamed["pkdyn.precision.modes.Modes.table"] == {"count": "top"}
    assert renamed["pkdyn.dynamics.selection.Selection.table"] == {"show": "top"}
    for name, mapping in renamed.items():
        params = inspect.signature(inspect.unwrap(dict(_public_functions())[name])).parameters
        for old, new in mapping.items():
            assert new in params and old not in params, name
    robot = pkdyn.load("five_bar", geometry=False)
    from pkdyn.identification import identify

    with pytest.warns(
        DeprecationWarning, match=r"identify\(data=...\) is deprecated.*measurements="
    ):
        with pytest.raises(InvalidInputError, match="measurements"):
            identify(robot, data="run.csv")


def test_the_keyword_rename_passes_the_value_and_refuses_both():
    @renamed_keyword("progress_bar", "progress")
    def work(n: int, progress: bool | None = None) -> tuple[int, bool | None]:
        return n, progress

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert work(3, progress=True) == (3, True)
        assert work(3, False) == (3, False)  # (positional: unchanged)
    with pytest.warns(DeprecationWarning, match="progress_bar"):
        assert work(3, progress_bar=True) == (3, True)
    with pytest.raises(InvalidInputError, match="progress_bar: give progress only"):
        work(3, progress=True, progress_bar=False)
    assert work.renamed_keywords == {"progress_bar": "progress"}
