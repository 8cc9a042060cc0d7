"""The ``pkdyn`` command line.

``ROBOT`` is a library family name or a URDF path; ``--param k=v`` overrides builder parameters;
``--json`` prints one JSON object. A user error prints one line on stderr and exits with 1.

Every command declares which of its arguments are files it reads and which it writes
(:mod:`pkdyn.cli._paths`); they are all checked together before the command runs (no output
onto an input or onto another output, no FIFO or device read), and the files a command reads
while it works are protected from its outputs too (:func:`pkdyn.files.recording_reads`).

Exit codes (:data:`EXIT_CODES`): 0 success, 1 user error (one line ``pkdyn: error: ...`` on
stderr), 2 usage error (bad arguments), 130 interrupted by Ctrl-C (SIGINT), 143 terminated
(SIGTERM). An interrupted run prints one line and leaves every output file as it was (files are
written to a temporary name and renamed when complete, :mod:`pkdyn.files`).

Each command group lives in its own module of this package and exposes ``register(sub)``; the
modules import their heavy dependencies inside the command functions so ``pkdyn --help`` is quick.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any, NoReturn

from pkdyn.exceptions import PkdynError

__all__ = ["EXIT_CODES", "Command", "commands", "main", "run"]

#: Command modules, in the order their commands appear in ``pkdyn --help``.
COMMAND_MODULES = (
    "geometry",
    "dynamics",
    "workspace",
    "precision",
    "vibration",
    "design",
    "viewer",
    "mjcf",
    "identification",
    "tripod",
    "accuracy",
    "calibration",
    "demo",
    "listing",
)

#: The module of each command: a command line naming one imports only that module.
COMMANDS = {
    "info": "geometry",
    "urdf": "geometry",
    "forward-geometry": "geometry",
    "fk": "geometry",
    "inverse-geometry": "geometry",
    "ik": "geometry",
    "mobility": "geometry",
    "jacobian": "geometry",
    "singularity": "geometry",
    "statics": "geometry",
    "simulate": "dynamics",
    "size": "dynamics",
    "stiffness": "precision",
    "modes": "precision",
    "vibration": "vibration",
    "collisions": "workspace",
    "workspace": "workspace",
    "design": "design",
    "view": "viewer",
    "mjcf": "mjcf",
    "identify": "identification",
    "tripod": "tripod",
    "accuracy": "accuracy",
    "calibrate": "calibration",
    "demo": "demo",
    "list": "listing",
}

EXIT_CODES = {
    0: "success",
    1: "user error (one line 'pkdyn: error: ...' on stderr)",
    2: "usage error (unknown option, missing or malformed argument)",
    130: "interrupted (Ctrl-C, SIGINT)",
    143: "terminated (SIGTERM)",
}
"""Exit codes of the ``pkdyn`` command."""

_EPILOG = "exit codes: " + ", ".join(f"{k} {v.split(' (')[0]}" for k, v in EXIT_CODES.items())


def _parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The parser; given the arguments, with only the named command's module (quick start)."""
    from pkdyn import __version__
    from pkdyn.cli._common import Parser  # (numpy: imported inside main's handlers)

    first = next((a for a in (sys.argv[1:] if argv is None else argv) if a[:1] != "-"), None)
    modules = (COMMANDS[first],) if first in COMMANDS else COMMAND_MODULES
    p = Parser(
        prog="pkdyn",
        description="Kinematics and dynamics of parallel robots.",
        epilog=_EPILOG,
    )
    p.add_argument("--version", action="version", version=f"pkdyn {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    target = sub if first not in COMMANDS else _OnlyCommand(sub, first)
    for name in modules:
        importlib.import_module(f"pkdyn.cli.{name}").register(target)
    return p


@dataclass(frozen=True)
class Command:
    """One command of the ``pkdyn`` parser, for references and checks of the help texts.

    Attributes:
        words: The command words after ``pkdyn`` (``("tripod", "scenario")``; ``()``: the
            top-level parser itself).
        aliases: Other names of the last word (``fk`` for ``forward-geometry``).
        help: The one-line help shown in the parent's list of commands.
        parser: The command's own parser.

    """

    words: tuple[str, ...]
    aliases: tuple[str, ...]
    help: str
    parser: argparse.ArgumentParser


def commands() -> Iterator[Command]:
    """Every command of ``pkdyn``, sub-commands after their parent, in ``pkdyn --help`` order.

    The first is the top-level parser (``words == ()``); an alias is reported with its
    command, not apart.
    """
    top = _parser([])
    yield Command((), (), "", top)
    yield from _sub_commands(top, ())


def _sub_commands(parser: argparse.ArgumentParser, words: tuple[str, ...]) -> Iterator[Command]:
    for action in parser._actions:
        if not isinstance(action, argparse._SubParsersAction):
            continue
        helps = {a.dest: a.help or "" for a in action._choices_actions}
        names: dict[int, list[str]] = {}
        for name, sp in action.choices.items():
            names.setdefault(id(sp), []).append(name)
        for name, sp in action.choices.items():
            first, *aliases = names[id(sp)]
            if name != first:
                continue
            yield Command((*words, name), tuple(aliases), helps.get(name, ""), sp)
            yield from _sub_commands(sp, (*words, name))


class _Skipped:
    """Stands for the parser of a sub-command this command line does not name (quick start).

    Every method call (``add_argument``, ``set_defaults``, ``add_mutually_exclusive_group``...)
    is accepted and returns the stand-in itself.
    """

    def __getattr__(self, name: str) -> Any:
        return lambda *args, **kwargs: self


class _OnlyCommand:
    """The sub-parsers action, building only the named command's parser (or its alias's)."""

    def __init__(self, sub: Any, command: str) -> None:
        self._sub, self._command = sub, command

    def add_parser(self, name: str, **kwargs: Any) -> Any:
        if self._command == name or self._command in kwargs.get("aliases", ()):
            return self._sub.add_parser(name, **kwargs)
        return _Skipped()


def _one_line_warning(message: Warning | str, category: type[Warning], *_: Any, **__: Any) -> None:
    text = " ".join(str(message).split())
    print(f"pkdyn: warning: {text}", file=sys.stderr)


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread (like KeyboardInterrupt for SIGINT)."""


def _on_sigterm(signum: int, frame: Any) -> None:
    raise _Terminated


def _quiet_stdout() -> None:
    """After a broken pipe (``pkdyn ... | head``): no 'Exception ignored' at exit."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass


def _last_word(message: str) -> None:
    """Print the one line of an interrupted run, deaf to a second Ctrl-C or SIGTERM meanwhile."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            signal.signal(sig, signal.SIG_IGN)
        except ValueError:  # not the main thread
            pass
    print(message, file=sys.stderr)


_SCIPY_COMMANDS = ("stiffness", "modes", "accuracy", "calibrate", "identify")
"""Commands whose linear algebra goes through SciPy (imported before the BLAS limit is set)."""


def run() -> NoReturn:
    """The ``pkdyn`` program (console script and ``python -m pkdyn``): :func:`main`, then exit.

    After an interrupt (exit 130 or 143) the one line is the last word: the standard error is
    closed to what the interpreter's shutdown may still print (a worker pool's threads
    stopping mid-write). In-process callers of :func:`main` keep their standard error.
    """
    code = main()
    if code in (130, 143):
        try:
            sys.stderr.flush()
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stderr.fileno())
        except (OSError, ValueError, AttributeError):
            pass
    sys.exit(code)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line.

    Args:
        argv: Arguments (default: ``sys.argv[1:]``).

    Returns:
        Exit code (:data:`EXIT_CODES`): 0 on success, 1 on a user error (one line on stderr),
        130 after Ctrl-C, 143 after SIGTERM (one line on stderr, no traceback). Usage errors
        exit with 2 through ``SystemExit``.

    """
    try:  # (only the main thread may install handlers)
        previous = signal.signal(signal.SIGTERM, _on_sigterm)
        previous_int = signal.getsignal(signal.SIGINT)
        handlers = True
    except ValueError:
        previous, previous_int, handlers = None, None, False
    shown = warnings.showwarning
    filters = list(warnings.filters)
    try:
        parser = _parser(argv)
        args = parser.parse_args(argv)
        warnings.showwarning = _one_line_warning
        # libraries' deprecation notices are for developers, not for command-line users
        warnings.filterwarnings("ignore", category=DeprecationWarning)
        warnings.filterwarnings("ignore", category=PendingDeprecationWarning)
        from pkdyn.threads import single_blas_thread

        if getattr(args, "command", None) in _SCIPY_COMMANDS:  # loaded first: BLAS limited too
            import scipy.linalg  # noqa: F401
        from pkdyn.cli._common import check_numbers
        from pkdyn.cli._paths import check_paths
        from pkdyn.files import recording_reads

        with recording_reads():  # outputs never replace a file the command read
            check_numbers(parser, args)  # no NaN
            check_paths(parser, args)  # every input and output, before any work
            with single_blas_thread():  # (many small matrices: pkdyn.threads)
                args.func(args)
    except PkdynError as err:
        text = " ".join(str(err).splitlines())
        print(f"pkdyn: error: {text}", file=sys.stderr)
        return 1
    except MemoryError:
        print(
            "pkdyn: error: out of memory: ask for less (fewer samples, designs or workers)",
            file=sys.stderr,
        )
        return 1
    except KeyboardInterrupt:
        _last_word("pkdyn: interrupted")
        return 130
    except _Terminated:
        _last_word("pkdyn: terminated")
        return 143
    except BrokenPipeError:
        _quiet_stdout()
        return 0
    finally:
        warnings.showwarning = shown
        warnings.filters[:] = filters  # type: ignore[index]
        if handlers:
            signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)
            signal.signal(
                signal.SIGINT, signal.default_int_handler if previous_int is None else previous_int
            )
    return 0
