"""The public API under bad input: every registered function, class and method, every argument,
every bad-input class of the argument's kind (``contract.kinds``), a few values each drawn by
hypothesis.

The contract (``contract.contract.check_api``): a valid result (no NaN) or a
``pkdyn.PkdynError`` of one line naming the culprit; never a bare ``ValueError``,
``TypeError``, ``LinAlgError``, ``KeyError``, ``IndexError``, ``SystemExit``; within the time
limit; the robot passed in unchanged; input files unchanged; a refusal leaves no file behind.
"""

from __future__ import annotations

import importlib
import warnings
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings

from contract.contract import check_api, file_changes, snapshot, temporaries
from contract.drive import PENDING_SETTINGS, scratch
from contract.kinds import PathIn, PathOut
from contract.registry import API, pending

settings.load_profile("contract")


def resolve_public(name: str) -> Any:
    """The object of a public name (``pkdyn.analysis.classify``, ``pkdyn.Robot.dof``)."""
    parts = name.split(".")
    obj: Any = importlib.import_module(parts[0])
    prefix = parts[0]
    for p in parts[1:]:
        prefix += "." + p
        obj = getattr(obj, p) if hasattr(obj, p) else importlib.import_module(prefix)
    return obj


def bound_call(entry, s, replaced: dict[str, Any]):
    """The entry's call with its baseline arguments, some replaced."""
    kwargs = {k: a.value(s) for k, a in entry.args.items()}
    kwargs |= replaced
    kwargs = {k: v for k, v in kwargs.items() if v is not None or k in replaced}
    if entry.call is not None:
        return lambda: entry.call(s, **kwargs)
    if entry.obj is not None:
        method = entry.name.rsplit(".", 1)[1]
        target = getattr(entry.obj(s), method)
    else:
        target = resolve_public(entry.name)
    return lambda: target(**kwargs)


def fingerprint(robot) -> tuple:
    """What an entry point must not change in the robot it is given."""
    if robot is None:
        return ()
    m = robot.model
    return (
        robot.q_home.tobytes(),
        m.nq,
        m.nv,
        np.asarray(m.gravity.linear).tobytes(),
        float(sum(i.mass for i in m.inertias)),
        np.asarray(m.lowerPositionLimit).tobytes(),
        len(robot.constraint_models),
    )


def _cases() -> list:
    out = []
    for entry in API:
        marks = [pytest.mark.slow] if entry.slow else []
        if entry.baseline:
            out.append(pytest.param(entry, None, None, id=f"{entry.name}|baseline", marks=marks))
        for arg_name, arg in entry.args.items():
            for cls in arg.kind.api():
                if cls in arg.skip or (not entry.baseline and cls != "wrong_type"):
                    continue
                tid = f"{entry.name}|{arg_name}|{cls}"
                m = list(marks)
                reason = pending(tid)
                if reason:
                    m.append(pytest.mark.xfail(strict=True, reason=reason))
                out.append(pytest.param(entry, arg_name, cls, id=tid, marks=m))
    return out


def _run(entry, arg_name, case):
    with scratch(entry.inputs, entry.robot, entry.geometry) as s:
        before_robot = fingerprint(s.robot)
        replaced = {} if arg_name is None else {arg_name: case.make(s)}
        arg = entry.args.get(arg_name) if arg_name else None
        names = (arg.names or (arg_name,)) if arg else ()
        if arg_name and hasattr(replaced[arg_name], "__fspath__"):
            names = (*names, str(replaced[arg_name]), replaced[arg_name].name)
        elif arg_name and isinstance(arg.kind if arg else None, PathOut | PathIn):
            names = (*names, str(replaced[arg_name]))  # (a path given as a str)
        call = bound_call(entry, s, replaced)
        before = snapshot(s.dir)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            outcome, _ = check_api(
                call, names, case.refuse if case else False, entry.timeout, entry.nan_ok
            )
        if arg_name is None:
            assert outcome == "accepted", f"the registered baseline call is refused: {_}"
        changed, created, removed = file_changes(before, snapshot(s.dir))
        assert not changed and not removed, f"input files changed {changed} or removed {removed}"
        if outcome == "refused":
            assert not created, f"a refused call left files: {created}"
        else:
            assert not temporaries(created), f"temporaries left: {temporaries(created)}"
        assert fingerprint(s.robot) == before_robot, "the robot given was changed"


@pytest.mark.parametrize("entry, arg_name, cls", _cases())
def test_contract_api(entry, arg_name, cls):
    if arg_name is None:  # the registered baseline is a valid call
        from contract.kinds import Case

        _run(entry, None, Case("baseline", "", lambda s: None, refuse=False))
        return

    @PENDING_SETTINGS(pending(f"{entry.name}|{arg_name}|{cls}"))
    @given(case=entry.args[arg_name].kind.api()[cls])
    def run(case):
        _run(entry, arg_name, case)

    run()
