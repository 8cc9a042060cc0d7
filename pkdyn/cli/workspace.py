"""Workspace and collision commands: ``workspace`` and ``collisions``."""

from __future__ import annotations

import argparse
import math
from typing import Any

from pkdyn.cli._common import emit, load, posed_command, robot_command

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


def _cmd_clavel(args: argparse.Namespace, robot: Any) -> None:
    from pkdyn.closed_form.delta_workspace import clavel_closed_form, clavel_numeric
    from pkdyn.exceptions import PkdynError

    p = robot.params
    if not all(hasattr(p, k) for k in ("ra", "rb", "la", "lb")):
        raise PkdynError(
            f"--clavel applies to the delta family (ra, rb, la, lb); {robot.name} is not one"
        )
    cf = clavel_closed_form(p, args.gamma_max, args.ab_min)
    nu, v_ws = clavel_numeric(
        p, args.gamma_max, args.ab_min, rays=args.rays, progress=not args.json
    )
    numeric = nu.as_json()
    numeric["V_workspace"] = v_ws
    payload = {
        "closed_form": cf.as_json(),
        "numeric": numeric,
        "limits": {"gamma_max": args.gamma_max, "ab_min": args.ab_min, "ab_max": math.pi},
        "difference": {k: numeric[k] - cf.as_json()[k] for k in ("D", "S", "H", "Hmax", "V", "zh")},
    }
    keys = ("D", "S", "H", "Hmax", "V", "zh")
    units = {"D": "m", "S": "m^2", "H": "m", "Hmax": "m", "V": "m^3", "zh": "m"}
    lines = [f"{'':6s}{'closed form':>16s}{'numeric':>16s}{'difference':>12s}"]
    lines += [
        f"{k:6s}{getattr(cf, k):16.9f}{getattr(nu, k):16.9f}{getattr(nu, k) - getattr(cf, k):12.2e}"
        f" {units[k]}"
        for k in keys
    ]
    lines.append(
        f"whole workspace volume (numeric): {v_ws:.6f} m^3 = {v_ws / max(cf.V, 1e-300):.3f} V "
        "(the prism misses the dome above and the cap below)"
    )
    emit(args, payload, "\n".join(lines))


def _cmd_workspace(args: argparse.Namespace) -> None:
    robot = load(args, geometry=False)
    if args.clavel:
        _cmd_clavel(args, robot)
        return


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
    sp = robot_command(sub, "workspace", "workspace: translation, orientation, dextrous; Clavel")
    sp.add_argument(
        "--clavel",
        action="store_true",
        help="Delta: Clavel's closed-form figures (seed 000, 1.4) beside the numeric ones",
    )
    sp.add_argument(
        "--gamma-max", type=float, default=math.radians(40.0), help="Clavel's limit 1 [rad]"
    )
    sp.add_argument(
        "--ab-min", type=float, default=math.radians(30.0), help="Clavel's (alpha+beta)_min [rad]"
    )
    sp.add_argument("--rays", type=int, default=72, help="Clavel: directions sampled")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_workspace)
