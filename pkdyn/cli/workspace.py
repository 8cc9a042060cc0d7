"""Workspace and collision commands: ``workspace`` and ``collisions``."""

from __future__ import annotations

import argparse
from typing import Any

from pkdyn.cli._common import emit, load, posed_command

__all__ = ["register"]


def _posed_robot(args: argparse.Namespace) -> tuple[Any, Any]:
    """Robot with geometry and the configuration named by ``--pose`` or ``--q``."""
    import pkdyn

    robot = load(args, geometry=True)
    if args.q is not None:
        return robot, pkdyn.forward_geometry(robot, args.q, check_limits=False).q
    return robot, pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q


def _cmd_collisions(args: argparse.Namespace) -> None:
    from pkdyn.collisions import distance_report
    from pkdyn.exceptions import InvalidInputError

    robot, q = _posed_robot(args)
    pairs = []
    for item in args.pair or []:
        a, sep, b = item.partition(",")
        if not sep or not a or not b:
            raise InvalidInputError("--pair", f"'{item}': expected NAME_A,NAME_B")
        pairs.append((a.strip(), b.strip()))
    rep = distance_report(robot, q, margin=args.margin, pairs=pairs or None)
    shown = rep.pairs[: args.top] if args.top else rep.pairs
    lines = [
        f"min distance {rep.min_distance * 1e3:.3f} mm "
        f"({'IN COLLISION' if rep.in_collision else 'clear'}, margin {args.margin * 1e3:g} mm)"
    ]
    lines += [f"  {p.a:>22s} - {p.b:<22s} {p.distance * 1e3:9.3f} mm" for p in shown]
    emit(args, rep.as_json(), "\n".join(lines))


def register(sub: Any) -> None:
    """Add this module's sub-commands to the ``pkdyn`` parser."""
    sp = posed_command(sub, "collisions", "minimum distances between legs, platform and base")
    sp.add_argument("--margin", type=float, default=0.0, help="safety margin [m]")
    sp.add_argument(
        "--pair",
        action="append",
        metavar="A,B",
        help="check only this pair of geometry or link names (repeatable)",
    )
    sp.add_argument("--top", type=int, default=10, help="pairs listed in the text output")
    sp.set_defaults(func=_cmd_collisions)
