"""Which arguments of a command are files it reads and which it writes, checked before any work.

Every command declares its path arguments with :func:`input_option` and :func:`output_option`
(instead of ``add_argument``): the declaration is kept on the argparse action, so that
:func:`check_paths` (run by :func:`pkdyn.cli.main` between parsing and the command) finds every
input and output of the command named on the command line, whatever the command, and hands
them to :func:`pkdyn.files.resolve_paths`: inputs are regular files of bounded size (no FIFO, no
device), outputs are files pkdyn may write, and no output is an input or another output. Figure
outputs also have their format checked, and every output's directory is tried for writing.

An input that may also be a name (``ROBOT``: a library family or a file; ``--trajectory``:
``adept`` or a CSV file; ``--catalog``: ``example`` or a file) is a file when a file of that name
exists; otherwise the command treats it as a name.

``-o/--out`` is the one spelling of a command's main output; ``--output`` still works for one
release, with a warning (:func:`output_option`'s ``deprecated``).
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pkdyn.cli._spelling import spelled_option
from pkdyn.exceptions import OutputError

__all__ = [
    "INPUT_LIMIT",
    "PathRole",
    "check_figure",
    "check_paths",
    "chosen_parser",
    "input_option",
    "output_option",
    "path_actions",
]

INPUT_LIMIT = 1 << 30
"""Largest input file a command line reads [bytes] (1 GiB; readers apply their own, smaller
limits as they read)."""


@dataclass(frozen=True)
class PathRole:
    """What a path argument is.

    Attributes:
        role: ``input`` or ``output``.
        figure: An output figure (its extension must name a matplotlib format).
        or_name: An input that may be a name instead of a file (a file when one exists).
        companions: For an output: the paths of every file written from the value (a study's
            ``--out`` writes its table as CSV and Parquet, its study file and a partial file).

    """

    role: str
    figure: bool = False
    or_name: bool = False
    companions: Callable[[str], list[str]] | None = field(default=None, compare=False)


def input_option(
    parser: Any,
    *flags: str,
    or_name: bool = False,
    deprecated: tuple[str, ...] = (),
    **kwargs: Any,
) -> Any:
    """``parser.add_argument(*flags, **kwargs)`` for a file the command reads.

    Args:
        parser: The command's parser (or a group of it).
        *flags: Option strings, or the positional's name.
        or_name: The value may be a name instead (a file only when a file of that name exists).
        deprecated: Old option strings still accepted for one release, with a warning.
        **kwargs: As for ``add_argument``.

    Returns:
        The argparse action.

    """
    action = spelled_option(parser, *flags, deprecated=deprecated, **kwargs)
    action.pkdyn_path = PathRole("input", or_name=or_name)
    return action


def output_option(
    parser: Any,
    *flags: str,
    figure: bool = False,
    companions: Callable[[str], list[str]] | None = None,
    deprecated: tuple[str, ...] = (),
    **kwargs: Any,
) -> Any:
    """``parser.add_argument(*flags, **kwargs)`` for a file the command writes.

    Args:
        parser: The command's parser (or a group of it).
        *flags: Option strings (``-o``, ``--out``; ``--csv``, ``--plot``...).
        figure: A figure (format checked from the extension).
        companions: Every file written from the value (default: the value itself).
        deprecated: Old option strings still accepted for one release, with a warning
            (``--output``).
        **kwargs: As for ``add_argument``.

    Returns:
        The argparse action.

    """
    action = spelled_option(parser, *flags, deprecated=deprecated, **kwargs)
    action.pkdyn_path = PathRole("output", figure=figure, companions=companions)
    return action


def chosen_parser(parser: Any, args: argparse.Namespace) -> Any:
    """The parser of the (sub-)command ``args`` were parsed for (``pkdyn tripod scenario``)."""
    p = parser
    while True:
        sub = next(
            (a for a in getattr(p, "_actions", ()) if isinstance(a, argparse._SubParsersAction)),
            None,
        )
        if sub is None or sub.choices is None:
            return p
        name = getattr(args, sub.dest, None)
        if name not in sub.choices:
            return p
        p = sub.choices[name]


def path_actions(parser: Any) -> Iterator[tuple[argparse.Action, PathRole]]:
    """The path arguments a parser declares, with their roles."""
    for action in getattr(parser, "_actions", ()):
        role = getattr(action, "pkdyn_path", None)
        if role is not None:
            yield action, role


def _values(value: Any) -> list[str]:
    if value is None:
        return []
    if isinstance(value, str | os.PathLike):
        return [os.fspath(value)]
    out: list[str] = []
    for v in value:
        out.extend(_values(v))
    return out


def _name(action: argparse.Action) -> str:
    if action.option_strings:
        longs = [s for s in action.option_strings if s.startswith("--")]
        return (longs or action.option_strings)[0]
    return str(action.metavar or action.dest).upper()


def check_figure(option: str, path: str) -> None:
    """Refuse a figure file whose extension names no matplotlib format.

    Raises:
        OutputError: No extension, or an unknown one (the message lists the known ones).

    """
    from matplotlib.figure import Figure

    from pkdyn.files import shown

    p = Path(path)
    supported = Figure().canvas.get_supported_filetypes()
    fmt = p.suffix.lower().lstrip(".")
    if fmt not in supported:
        known = ", ".join(f".{k}" for k in sorted(supported))
        what = f"unknown figure format '{p.suffix}'" if fmt else "no file extension"
        raise OutputError(shown(path), f"{option}: {what}; name the file with one of {known}")


def check_paths(parser: Any, args: argparse.Namespace) -> None:
    """Check every path the command named on the command line, before it runs (module doc).

    Raises:
        InvalidInputError: An input is not a regular file (or is missing, or too large).
        OutputError: An output cannot be written, is an input or another output, or a figure
            has no known format.

    """
    from pkdyn.files import PathArg, check_writable, resolve_paths

    inputs: list[PathArg] = []
    outputs: list[tuple[PathArg, PathRole]] = []
    for action, role in path_actions(chosen_parser(parser, args)):
        for value in _values(getattr(args, action.dest, None)):
            name = _name(action)
            if role.role == "input":
                if role.or_name and not os.path.lexists(value):
                    continue  # a name (a library robot, a built-in trajectory...)
                inputs.append(PathArg(name, value))
            else:
                paths = role.companions(value) if role.companions else [value]
                outputs.extend((PathArg(name, p), role) for p in paths)
    if not inputs and not outputs:
        return
    resolve_paths(inputs, [o for o, _ in outputs], INPUT_LIMIT)
    for out, role in outputs:
        if role.figure:
            check_figure(out.option, out.path)
        try:
            check_writable(out.path)  # (root passes os.access; /proc takes no new file)
        except OutputError as err:
            raise OutputError(out.path, f"{out.option}: {str(err).split(': ', 1)[1]}") from None
