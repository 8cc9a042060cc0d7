"""Workspace and collision commands: ``workspace`` and ``collisions``."""

from __future__ import annotations

import argparse
import math
from typing import Any

from pkdyn.cli._common import (
    configuration,
    emit,
    integer,
    load,
    number,
    posed_command,
    robot_command,
)
from pkdyn.cli._paths import output_option

__all__ = ["register"]


def _cmd_collisions(args: argparse.Namespace) -> None:
    from pkdyn.analysis.collisions import distance_report
    from pkdyn.exceptions import InvalidInputError

    robot, q = configuration(args, geometry=True)
    pairs = []
    for item in args.pair or []:
        a, sep, b = item.partition(",")
        if not sep or not a or not b:
            raise InvalidInputError("--pair", f"'{item}': expected NAME_A,NAME_B")
        pairs.append((a.strip(), b.strip()))
    rep = distance_report(robot, q, margin=args.margin, pairs=pairs or None)
    emit(args, rep, rep.table(top=args.top))


def _clavel(args: argparse.Namespace, robot: Any) -> Any:
    from pkdyn.exceptions import PkdynError
    from pkdyn.workspace.clavel import clavel_comparison

    if robot.family != "delta":
        raise PkdynError(
            f"--clavel applies to the delta family (ra, rb, la, lb); {robot.name} is not one"
        )
    return clavel_comparison(
        robot.params, args.gamma_max, args.ab_min, rays=args.rays, progress=_progress(args)
    )


def _progress(args: argparse.Namespace) -> bool | None:
    return False if args.json else None


def _translation(args: argparse.Namespace, robot: Any) -> Any:
    from pkdyn.workspace.translation import translation_workspace

    return translation_workspace(
        robot,
        rpy=args.rpy,
        bounds=_box(args.bounds),
        step=args.step,
        samples=args.samples,
        limits=args.limits,
        margin=args.margin,
        method=args.method,
        progress=_progress(args),
    )


def _orientation(args: argparse.Namespace, robot: Any) -> Any:
    from pkdyn.workspace.orientation import mel_study, orientation_workspace

    if args.mel:
        return mel_study(
            robot, args.center, args.vector, n1=args.n1, n2=args.n2, progress=_progress(args)
        )
    return orientation_workspace(
        robot,
        center=args.center,
        N=args.vector,
        X1=args.x1,
        X2=args.x2,
        rpy0=args.rpy,
        n1=args.n1,
        n2=args.n2,
        limits=args.limits,
        margin=args.margin,
        progress=_progress(args),
    )


def _dextrous(args: argparse.Namespace, robot: Any) -> Any:
    from pkdyn.workspace.dextrous import dextrous_workspace

    return dextrous_workspace(
        robot,
        bounds=_box(args.bounds),
        step=args.step,
        samples=args.samples,
        joint_limits=args.joint_limits,
        progress=_progress(args),
    )


def _box(values: list[float] | None) -> Any:
    return None if values is None else [values[0:2], values[2:4], values[4:6]]


def _cmd_workspace(args: argparse.Namespace) -> None:
    robot = load(args, geometry=True)
    if args.clavel:
        result = _clavel(args, robot)
    else:
        run = {"translation": _translation, "orientation": _orientation, "dextrous": _dextrous}
        result = run[args.kind](args, robot)
    if args.plot:
        result.plot(args.plot)
    emit(args, result)


def register(sub: Any) -> None:
    """Add this module's sub-commands to the ``pkdyn`` parser."""
    sp = posed_command(sub, "collisions", "minimum distances between legs, platform and base")
    sp.add_argument("--margin", type=number, default=0.0, help="safety margin [m]")
    sp.add_argument(
        "--pair",
        action="append",
        metavar="A,B",
        help="check only this pair of geometry or link names (repeatable)",
    )
    sp.add_argument("--top", type=integer, default=10, help="pairs listed in the text output")
    sp.set_defaults(func=_cmd_collisions)
    sp = robot_command(sub, "workspace", "workspace: translation, orientation, dextrous; Clavel")
    sp.add_argument(
        "--clavel",
        action="store_true",
        help="Delta: Clavel's closed-form figures (seed 000, 1.4) beside the numeric ones",
    )
    sp.add_argument(
        "--gamma-max", type=number, default=math.radians(40.0), help="Clavel's limit 1 [rad]"
    )
    sp.add_argument(
        "--ab-min", type=number, default=math.radians(30.0), help="Clavel's (alpha+beta)_min [rad]"
    )
    sp.add_argument("--rays", type=integer, default=72, help="Clavel: directions sampled")
    sp.add_argument(
        "--kind", choices=("translation", "orientation", "dextrous"), default="translation"
    )
    sp.add_argument(
        "--rpy",
        nargs=3,
        type=number,
        default=[0.0, 0.0, 0.0],
        metavar=("R", "P", "Y"),
        help="platform orientation (translation) or reference orientation (orientation) [rad]",
    )
    sp.add_argument(
        "--bounds",
        nargs=6,
        type=number,
        metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"),
        help="sampled box [m]",
    )
    sp.add_argument("--step", type=number, help="grid spacing [m]")
    sp.add_argument("--samples", type=integer, default=41, help="samples per axis (no --step)")
    sp.add_argument(
        "--limits",
        nargs="*",
        default=["stroke", "joint", "interference"],
        choices=("stroke", "joint", "interference"),
        help="limits checked besides reach",
    )
    sp.add_argument("--margin", type=number, default=0.0, help="interference safety distance [m]")
    sp.add_argument("--method", choices=("auto", "closed", "numeric"), default="auto")
    sp.add_argument(
        "--center",
        nargs=3,
        type=number,
        metavar=("X", "Y", "Z"),
        help="orientation: fixed point C [m]",
    )
    for flag, default, what in (
        ("--vector", (0.0, 0.0, 1.0), "platform-fixed vector N"),
        ("--x1", (1.0, 0.0, 0.0), "first rotation axis"),
        ("--x2", (0.0, 0.0, 1.0), "second rotation axis"),
    ):
        sp.add_argument(
            flag, nargs=3, type=number, default=list(default), help=f"orientation: {what}"
        )
    sp.add_argument("--n1", type=integer, default=180, help="orientation: theta1 samples")
    sp.add_argument("--n2", type=integer, default=360, help="orientation: theta2 samples")
    sp.add_argument(
        "--mel",
        action="store_true",
        help="orientation: Merlet's MEL study (strokes; + joints; + interference)",
    )
    sp.add_argument("--joint-limits", action="store_true", help="dextrous: base joint limits")
    output_option(sp, "--plot", figure=True, metavar="FILE", help="save a figure (png, pdf, svg)")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_workspace)
