"""Deprecated spellings of options (``size --settle``, ``modes --count``...) keep the contract.

A former spelling (``pkdyn.cli._spelling``) is kept for one release: it must parse to exactly
what the new spelling parses to, print one ``pkdyn: warning:`` line naming the new spelling (a
warning line is not an error line: the run exits 0), and a bad value given under it is refused
like one given under the new spelling (one ``pkdyn: error:`` line). The drive
(``test_contract_cli.py``) drives each option under its one spelling; this file covers the
others, and fails naming a deprecated spelling it does not know.
"""

from __future__ import annotations

import contextlib
import io

import pytest

from contract.contract import check_cli
from contract.drive import action_of, parser_of, resolve, scratch, without
from contract.registry import CLI

VALUES: dict[str, list[str]] = {
    "--out": ["o.out"],
    "--qa": ["0.1", "0.2"],
    "--band": ["1e-4"],
    "--top": ["2"],
    "--param": ["lb=0.4"],
    "--step": ["0.002"],
    "--measurements": ["m.csv"],
}
"""A value each renamed option parses (by its new spelling): ``--q`` is parsed as ``--qa``."""


def _deprecated() -> list:
    from pkdyn.cli import commands

    out = []
    for c in commands():
        if not c.words:
            continue
        for a in c.parser._actions:
            for old in getattr(a, "deprecated", ()):
                new = next(o for o in a.option_strings if o.startswith("--") and o != old)
                out.append(pytest.param(c.words, new, old, id=f"{' '.join(c.words)}|{old}"))
    return out


def _entry(words: tuple[str, ...]):
    return next(e for e in CLI if e.words == words)


def _parse(words: tuple[str, ...], argv: list[str]) -> tuple[dict, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        ns = parser_of(words).parse_args(argv)
    return vars(ns), err.getvalue()


@pytest.mark.parametrize("words, new, old", _deprecated())
def test_contract_deprecated_spelling_parses_as_the_new_one_with_a_warning(words, new, old):
    assert new in VALUES, f"a renamed option {new} ({old}) without a value in VALUES"
    parser = parser_of(words)
    base = without(list(_entry(words).baseline), parser, new)
    value = VALUES[new][: 1 if action_of(parser, new).nargs in (None, "?") else None]
    plain, quiet = _parse(words, [*base, new, *value])
    former, warned = _parse(words, [*base, old, *value])
    assert plain == former, f"pkdyn {' '.join(words)} {old}: parsed unlike {new}"
    assert not quiet.strip(), f"the new spelling {new} warns: {quiet}"
    lines = warned.splitlines()
    assert len(lines) == 1 and lines[0].startswith("pkdyn: warning:"), warned
    assert old in lines[0] and new in lines[0], lines[0]


@pytest.mark.parametrize(
    "argv, refuse",
    [
        (["modes", "delta", "--pose", "0", "0", "-0.4", "--actuator-stiffness", "2e4",
          "--count", "3"], False),
        (["modes", "delta", "--pose", "0", "0", "-0.4", "--actuator-stiffness", "2e4",
          "--count", "0"], True),
        (["fk", "five_bar", "--q", "1.2", "1.9"], False),
        (["fk", "five_bar", "--q", "1.2", "nan"], True),
        (["identify", "five_bar", "--data", "{data.csv}", "-o", "{out.urdf}"], False),
        (["identify", "five_bar", "--data", "{no_such.csv}", "-o", "{out.urdf}"], True),
        (["mjcf", "five_bar", "--timestep", "-1e-3", "-o", "{out.xml}"], True),
    ],
    ids=["modes--count", "modes--count-0", "fk--q", "fk--q-nan", "identify--data",
         "identify--data-missing", "mjcf--timestep-negative"],
)  # fmt: skip
def test_contract_deprecated_spelling_runs_under_the_contract(argv, refuse):
    """Exit 0 with a warning line, or one error line naming the option: never a failure the
    warning line would cause (it is not an error line)."""
    from contract import fixtures as fx

    inputs = {"data.csv": fx.identification_csv}
    with scratch(inputs, None) as s:
        argv = [resolve(t, s) for t in argv]
        names = ("count", "top", "q", "qa", "data", "measurements", "no_such", "timestep", "step")
        res = check_cli(argv, names, refuse, True, 30.0)
    warnings = [ln for ln in res.err.splitlines() if ln.startswith("pkdyn: warning:")]
    assert len(warnings) == 1 and "deprecated" in warnings[0], res.err
