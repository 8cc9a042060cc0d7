"""Shared pieces of the command line: parameters, loading, output, configuration arguments."""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from pkdyn.exceptions import PkdynError

__all__ = [
    "Parser",
    "configuration",
    "emit",
    "fmt",
    "load",
    "params",
    "posed_command",
    "qa_argument",
    "robot_command",
]


class Parser(argparse.ArgumentParser):
    """Argument parser whose errors are one line and exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"pkdyn: error: {message} (see pkdyn {self.prog.split()[-1]} --help)\n")


def params(items: Sequence[str] | None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise PkdynError(f"--param '{item}': expected NAME=VALUE")
        out[key.strip()] = value.strip()
    return out


def load(args: argparse.Namespace, geometry: bool = False) -> Any:
    import pkdyn

    extra: dict[str, Any] = {}
    if getattr(args, "home", None) is not None:
        extra["home"] = args.home
    if getattr(args, "tol", None) is not None:
        extra["tol"] = args.tol
    return pkdyn.load(args.robot, geometry=geometry, **extra, **params(args.param))


def emit(args: argparse.Namespace, payload: dict[str, Any], text: str) -> None:
    if args.json:
        print(json.dumps(payload))
    else:
        print(text)


def fmt(v: np.ndarray) -> str:
    return " ".join(f"{x:.6f}" for x in v)


def configuration(args: argparse.Namespace) -> tuple[Any, np.ndarray]:
    """The robot and the assembled configuration named by ``--pose`` or ``--qa``."""
    import pkdyn

    robot = load(args)
    if args.qa is not None:
        return robot, pkdyn.forward_geometry(robot, args.qa, check_limits=False).q
    return robot, pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q


def qa_argument(parser: Any, required: bool = False) -> None:
    """Add ``--qa QA...`` (actuator coordinates, in actuator order; ``--q`` is an alias)."""
    parser.add_argument(
        "--qa",
        "--q",
        dest="qa",
        nargs="+",
        type=float,
        required=required,
        metavar="QA",
        help="actuator coordinates in actuator order (rad or m)",
    )


def robot_command(
    sub: Any, name: str, help_: str, aliases: tuple[str, ...] = ()
) -> argparse.ArgumentParser:
    """A sub-command taking ``ROBOT`` and ``--param NAME=VALUE`` (also called ``aliases``)."""
    sp: argparse.ArgumentParser = sub.add_parser(name, help=help_, aliases=list(aliases))
    sp.add_argument("robot", help="library family name, or a URDF, MJCF or SDFormat file")
    sp.add_argument("--param", action="append", metavar="NAME=VALUE", help="builder parameter")
    sp.add_argument(
        "--home",
        nargs="+",
        type=float,
        metavar="Q",
        help="home configuration to assemble: actuator coordinates, or a full configuration",
    )
    sp.add_argument(
        "--tol",
        type=float,
        metavar="TOL",
        help="assembly tolerance (m or rad): closure errors of a CAD-rounded description that "
        "are absorbed with a warning (default 1e-4)",
    )
    return sp


def posed_command(sub: Any, name: str, help_: str) -> argparse.ArgumentParser:
    """A robot sub-command at one configuration given by ``--pose`` or ``--qa``, with ``--json``."""
    sp = robot_command(sub, name, help_)
    where = sp.add_mutually_exclusive_group(required=True)
    where.add_argument("--pose", nargs="+", type=float, help="X Y Z [ROLL PITCH YAW] (m, rad)")
    qa_argument(where)
    sp.add_argument("--json", action="store_true")
    return sp
