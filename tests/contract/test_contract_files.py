"""Files: every output of every command onto every input of the same command, two outputs of
one command onto the same file, and what the harness's file classes do, run exhaustively (the
drive samples them).

An output that is an input (or another output) must be refused before any work: exit 1 or 2,
one line, the input unchanged byte for byte, no file left behind.
"""

from __future__ import annotations

import itertools

import pytest

from contract.contract import check_cli, file_changes, snapshot
from contract.drive import resolve, scratch
from contract.kinds import PathIn, PathOut
from contract.registry import CLI, pending
from contract.test_contract_cli import argv_for


def _pending(tid: str) -> list:
    reason = pending(tid)
    return [pytest.mark.xfail(strict=True, reason=reason)] if reason else []


def _onto_cases() -> list:
    out = []
    for entry in CLI:
        outputs = [o for o, a in entry.options.items() if isinstance(a.kind, PathOut)]
        read = {a.kind.key for a in entry.options.values() if isinstance(a.kind, PathIn)}
        inputs = sorted(k for k in entry.inputs if k in read or k == "robot.urdf")
        for o, key in itertools.product(outputs, inputs):
            tid = f"onto|{entry.name.replace(' ', '.')}|{o}|{key}"
            out.append(pytest.param(entry, o, key, id=tid, marks=_pending(tid)))
    return out


def _input_option(entry, key: str) -> list[str]:
    """The tokens that make the command read input ``key`` (its option, or the robot)."""
    if key == "robot.urdf":
        return []  # the robot positional, below
    for option, arg in entry.options.items():
        if isinstance(arg.kind, PathIn) and arg.kind.key == key:
            return [option, "{" + key + "}"]
    return []


@pytest.mark.parametrize("entry, output, key", _onto_cases())
def test_contract_onto_input_every_combination(entry, output, key):
    with scratch(entry.inputs, entry.robot) as s:
        target = s.inputs[key]
        argv = argv_for(entry, output, [str(target)], s)
        if key == "robot.urdf" and "robot" in entry.options:
            argv = [*entry.words, str(target), *argv[len(entry.words) + 1 :]]
        extra = [resolve(t, s) for t in _input_option(entry, key)]
        if extra and extra[0] not in argv:
            argv += extra
        before = snapshot(s.dir)
        check_cli(argv, (output.lstrip("-"), target.name, "input", "same file"), True, True, 30)
        changed, created, removed = file_changes(before, snapshot(s.dir))
        assert not changed and not removed and not created, (changed, created, removed)


def _two_outputs() -> list:
    out = []
    for entry in CLI:
        outputs = [o for o, a in entry.options.items() if isinstance(a.kind, PathOut)]
        for a, b in itertools.combinations(outputs, 2):
            tid = f"twice|{entry.name.replace(' ', '.')}|{a}|{b}"
            out.append(pytest.param(entry, a, b, id=tid, marks=_pending(tid)))
    return out


@pytest.mark.parametrize("entry, first, second", _two_outputs())
def test_contract_onto_input_two_outputs_one_file(entry, first, second):
    """Two outputs of one command given the same name: refused, nothing written."""
    with scratch(entry.inputs, entry.robot) as s:
        ext_a = entry.options[first].kind.ext
        target = s.dir / f"same{ext_a}"
        argv = argv_for(entry, first, [str(target)], s)
        argv = [*argv, second, str(target)]
        before = snapshot(s.dir)
        check_cli(
            argv, (first.lstrip("-"), second.lstrip("-"), "same", target.name), True, True, 30
        )
        changed, created, removed = file_changes(before, snapshot(s.dir))
        assert not changed and not removed and not created, (changed, created, removed)
