"""What the drive tests share: the scratch directory of one example, argv building."""

from __future__ import annotations

import argparse
import contextlib
import re
import shutil
import tempfile
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from contract import fixtures as fx
from contract.kinds import Scratch

__all__ = ["PENDING_SETTINGS", "parser_of", "resolve", "scratch", "without"]


def PENDING_SETTINGS(reason: str | None) -> Any:  # noqa: N802 (a decorator factory)
    """Hypothesis settings of a case: one example, not shrunk, when it is known to fail until
    another branch is merged (``registry.PENDING``: its failure is expected, not studied)."""
    if reason is None:
        return lambda fn: fn
    from hypothesis import Phase, settings

    return settings(max_examples=1, phases=[Phase.explicit, Phase.reuse, Phase.generate])


@contextlib.contextmanager
def scratch(
    inputs: dict[str, Any], family: str | None, geometry: bool = False
) -> Iterator[Scratch]:
    """A fresh directory with the entry's valid input files, removed afterwards."""
    d = Path(tempfile.mkdtemp(prefix="pkdyn-contract-"))
    try:
        paths = {}
        for key, make in inputs.items():
            # (a plug-in is imported under its file's name, once per process: one name each)
            p = d / (f"{key[:-3]}_{uuid.uuid4().hex[:8]}.py" if key.endswith(".py") else key)
            p.write_bytes(make())
            paths[key] = p
        yield Scratch(d, fx.robot(family, geometry) if family else None, paths)
    finally:
        shutil.rmtree(d, ignore_errors=True)


def resolve(token: str, s: Scratch) -> str:
    """``{key}`` in a baseline token -> the path of input ``key`` (or of a new file ``key``)."""
    return re.sub(r"\{([^}]+)\}", lambda m: str(s.inputs.get(m[1], s.dir / m[1])), token)


_PARSERS: dict[tuple[str, ...], argparse.ArgumentParser] = {}


def parser_of(words: tuple[str, ...]) -> argparse.ArgumentParser:
    """The parser of a command."""
    if not _PARSERS:
        from pkdyn.cli import commands

        for c in commands():
            _PARSERS[c.words] = c.parser
    return _PARSERS[words]


def action_of(parser: argparse.ArgumentParser, option: str) -> argparse.Action:
    """The action of an option (any of its spellings) or a positional (its dest)."""
    for a in parser._actions:
        if option in a.option_strings or (not a.option_strings and a.dest == option):
            return a
    raise KeyError(option)


def without(argv: list[str], parser: argparse.ArgumentParser, option: str) -> list[str]:
    """``argv`` without ``option`` and without the options exclusive with it (their values too)."""
    action = action_of(parser, option)
    drop = set(action.option_strings)
    for g in parser._mutually_exclusive_groups:
        if action in g._group_actions:
            for a in g._group_actions:
                drop |= set(a.option_strings)
    out: list[str] = []
    i = 0
    while i < len(argv):
        tok = argv[i]
        if tok not in drop:
            out.append(tok)
            i += 1
            continue
        nargs = action_of(parser, tok).nargs
        i += 1
        if isinstance(nargs, int):
            i += nargs
        elif nargs is None:
            i += 1
        else:  # '+', '*', '?': up to the next option
            while i < len(argv) and not (argv[i].startswith("-") and not _number(argv[i])):
                i += 1
    return out


def _number(tok: str) -> bool:
    try:
        float(tok)
    except ValueError:
        return False
    return True
