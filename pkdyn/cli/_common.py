"""Shared pieces of the command line: parameters, loading, output, configuration arguments."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable, Sequence
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
    "robot_command",
]

Handler = Callable[[argparse.Namespace], None]


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

    return pkdyn.load(args.robot, geometry=geometry, **params(args.param))


def emit(args: argparse.Namespace, payload: dict[str, Any], text: str) -> None:
    if args.json:
        print(json.dumps(payload))
    else:
        print(text)


def fmt(v: np.ndarray) -> str:
    return " ".join(f"{x:.6f}" for x in v)


def configuration(args: argparse.Namespace) -> tuple[Any, np.ndarray]:
    """The robot and the assembled configuration named by ``--pose`` or ``--q``."""
    import pkdyn

    robot = load(args)
    if args.q is not None:
        return robot, pkdyn.forward_geometry(robot, args.q, check_limits=False).q
    return robot, pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q


def robot_command(sub: Any, name: str, help_: str) -> argparse.ArgumentParser:
    """A sub-command taking ``ROBOT`` and ``--param NAME=VALUE``."""
    sp: argparse.ArgumentParser = sub.add_parser(name, help=help_)
    sp.add_argument("robot", help="library family name or URDF path")
    sp.add_argument("--param", action="append", metavar="NAME=VALUE", help="builder parameter")
    return sp


def posed_command(sub: Any, name: str, help_: str) -> argparse.ArgumentParser:
    """A robot sub-command at one configuration given by ``--pose`` or ``--q``, with ``--json``."""
    sp = robot_command(sub, name, help_)
    where = sp.add_mutually_exclusive_group(required=True)
    where.add_argument("--pose", nargs="+", type=float, help="X Y Z [ROLL PITCH YAW] (m, rad)")
    where.add_argument("--q", nargs="+", type=float, help="actuated coordinates")
    sp.add_argument("--json", action="store_true")
    return sp
