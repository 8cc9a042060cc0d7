"""The ``pkdyn`` command line.

``ROBOT`` is a library family name or a URDF path; ``--param k=v`` overrides builder parameters;
``--json`` prints one JSON object. A user error prints one line on stderr and exits with 1.

Each command group lives in its own module of this package and exposes ``register(sub)``; the
modules import their heavy dependencies inside the command functions so ``pkdyn --help`` is quick.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from collections.abc import Sequence
from typing import Any

from pkdyn.cli._common import Parser
from pkdyn.exceptions import PkdynError

__all__ = ["main"]

#: Command modules, in the order their commands appear in ``pkdyn --help``.
COMMAND_MODULES = (
    "geometry",
    "dynamics",
    "workspace",
    "design",
    "viewer",
    "mjcf",
    "tripod",
    "demo",
)


def _parser() -> argparse.ArgumentParser:
    p = Parser(prog="pkdyn", description="Kinematics and dynamics of parallel robots.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for name in COMMAND_MODULES:
        importlib.import_module(f"pkdyn.cli.{name}").register(sub)
    return p


def _one_line_warning(message: Warning | str, category: type[Warning], *_: Any, **__: Any) -> None:
    print(f"pkdyn: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line.

    Args:
        argv: Arguments (default: ``sys.argv[1:]``).

    Returns:
        Exit code: 0 on success, 1 on a user error (one line on stderr).

    """
    args = _parser().parse_args(argv)
    warnings.showwarning = _one_line_warning
    try:
        args.func(args)
    except PkdynError as err:
        print(f"pkdyn: error: {err}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        return 0
    return 0
