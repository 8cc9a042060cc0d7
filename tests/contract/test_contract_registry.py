"""The registry is complete: every command and option of ``pkdyn`` and every public function,
class and method of pkdyn is registered (``tests/contract/registry.py``), and nothing
registered is gone. A new entry point fails here, by name, until it is registered.
"""

from __future__ import annotations

import argparse
import importlib
import inspect

import pytest

from contract.drive import parser_of
from contract.registry import API, CLI, EXEMPT
from contract.test_contract_api import resolve_public

PUBLIC_MODULES = (
    "pkdyn",
    "pkdyn.analysis",
    "pkdyn.calibration",
    "pkdyn.cli",
    "pkdyn.design",
    "pkdyn.dynamics",
    "pkdyn.identification",
    "pkdyn.library",
    "pkdyn.plotting",
    "pkdyn.precision",
    "pkdyn.tripod",
    "pkdyn.viewer",
    "pkdyn.workspace",
    "solvers",
)
"""The public packages: their ``__all__`` is the API (``docs/api.rst`` documents the same)."""


def _commands() -> dict[tuple[str, ...], argparse.ArgumentParser]:
    from pkdyn.cli import commands

    return {c.words: c.parser for c in commands() if c.words}


def _options(parser: argparse.ArgumentParser) -> set[str]:
    """Every option (its first long spelling) and positional (its dest) of a parser."""
    out = set()
    for a in parser._actions:
        if isinstance(a, argparse._HelpAction | argparse._VersionAction):
            continue
        if isinstance(a, argparse._SubParsersAction):
            continue
        if not a.option_strings:
            out.add(a.dest)
        else:
            out.add(next((o for o in a.option_strings if o.startswith("--")), a.option_strings[0]))
    return out


def _is_group(parser: argparse.ArgumentParser) -> bool:
    """A command that only groups sub-commands (``pkdyn tripod``)."""
    return any(isinstance(a, argparse._SubParsersAction) for a in parser._actions)


def test_every_command_is_registered():
    have = {c for c, p in _commands().items() if not _is_group(p)}
    registered = {e.words for e in CLI}
    missing = sorted(" ".join(w) for w in have - registered)
    gone = sorted(" ".join(w) for w in registered - have)
    assert not missing, f"commands not registered in tests/contract/registry.py CLI: {missing}"
    assert not gone, f"registered commands that no longer exist: {gone}"


@pytest.mark.parametrize("entry", CLI, ids=[e.name for e in CLI])
def test_every_option_is_registered(entry):
    have = _options(parser_of(entry.words))
    registered = set(entry.options)
    missing, gone = sorted(have - registered), sorted(registered - have)
    assert not missing, f"pkdyn {entry.name}: options not registered: {missing}"
    assert not gone, f"pkdyn {entry.name}: registered options that no longer exist: {gone}"


def _key(obj: object, owner: type | None = None, method: str = "") -> tuple:
    """What identifies an entry point whatever public name reaches it."""
    return (id(owner), method) if owner is not None else (id(obj), "")


def _public() -> dict[tuple, str]:
    """Every public callable: ``__all__`` functions and classes (exceptions aside) and the
    public methods of the classes (defined in the class, not inherited), by a public name."""
    out: dict[tuple, str] = {}
    for mod_name in PUBLIC_MODULES:
        mod = importlib.import_module(mod_name)
        for name in mod.__all__:
            obj = getattr(mod, name)
            if not callable(obj) or (inspect.isclass(obj) and issubclass(obj, BaseException)):
                continue  # constants, exceptions
            out.setdefault(_key(obj), f"{mod_name}.{name}")
            if inspect.isclass(obj):
                for attr, value in vars(obj).items():
                    if attr.startswith("_"):
                        continue
                    fn = value.__func__ if isinstance(value, staticmethod | classmethod) else value
                    if inspect.isfunction(fn):
                        out.setdefault(_key(obj, obj, attr), f"{mod_name}.{name}.{attr}")
    return out


def _registered_key(name: str) -> tuple:
    owner_name, _, attr = name.rpartition(".")
    try:
        owner = resolve_public(owner_name)
    except (ImportError, AttributeError):
        owner = None
    if inspect.isclass(owner) and attr in vars(owner):
        return _key(None, owner, attr)
    return _key(resolve_public(name))


def test_every_public_function_class_and_method_is_registered():
    public = _public()
    registered: dict[tuple, str] = {}
    gone = []
    for e in EXEMPT:  # an exemption of a class that covers its methods
        if e.methods:
            cls = resolve_public(e.name)
            for attr in vars(cls):
                registered[_key(None, cls, attr)] = f"{e.name}.{attr}"
    for name in [e.name for e in API] + [e.name for e in EXEMPT]:
        try:
            registered[_registered_key(name)] = name
        except (ImportError, AttributeError):
            gone.append(name)
    missing = sorted(n for k, n in public.items() if k not in registered)
    assert not gone, f"registered in tests/contract but no longer public: {gone}"
    assert not missing, (
        f"{len(missing)} public entry points not registered in tests/contract/registry*.py "
        f"(API or EXEMPT): {missing}"
    )


def test_nothing_is_registered_twice():
    names = [e.name for e in API] + [e.name for e in EXEMPT]
    twice = sorted({n for n in names if names.count(n) > 1})
    assert not twice, f"registered twice: {twice}"


def _aliases() -> list:
    from pkdyn.cli import commands

    out = []
    for c in commands():
        for alias in c.aliases:
            entry = next((e for e in CLI if e.words == c.words), None)
            out.append(pytest.param(entry, alias, id=f"{' '.join(c.words)}={alias}"))
    return out


@pytest.mark.parametrize("entry, alias", _aliases())
def test_every_alias_runs_its_command(entry, alias):
    """An alias (``fk``, ``ik``) is the registered command: the same baseline, the same output."""
    from contract.contract import run_cli
    from contract.drive import resolve, scratch

    assert entry is not None, "the command of this alias is not registered"
    with scratch(entry.inputs, entry.robot) as s:
        base = [resolve(t, s) for t in entry.baseline]
        words = list(entry.words)
        plain = run_cli([*words, *base], entry.timeout)
        other = run_cli([*words[:-1], alias, *base], entry.timeout)
    assert plain.code == other.code == 0, (plain.err, other.err)
    assert plain.out == other.out


def _parameters(name: str) -> set[str] | None:
    """The parameter names of a registered callable (``None``: it takes ``**kwargs``)."""
    obj = resolve_public(name)
    sig = inspect.signature(obj.__init__ if inspect.isclass(obj) else obj)
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in sig.parameters.values()):
        return None
    return set(sig.parameters)


@pytest.mark.parametrize("entry", [e for e in API if e.call is None], ids=lambda e: e.name)
def test_every_registered_argument_is_a_parameter(entry):
    """An argument renamed (``progress_bar`` -> ``progress``) is driven under its new name: the
    former one, kept for one release, would only test the deprecation's forwarding."""
    params = _parameters(entry.name)
    if params is None:
        return
    gone = sorted(set(entry.args) - params)
    assert not gone, f"{entry.name}: registered arguments it no longer takes: {gone}"
