"""``pkdyn mjcf``: write a MuJoCo model (MJCF) of a robot."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from pkdyn.cli._common import load, number, robot_command
from pkdyn.cli._paths import output_option
from pkdyn.cli._spelling import spelled_option
from pkdyn.inputs import positive

__all__ = ["register"]


def _cmd_mjcf(args: argparse.Namespace) -> None:
    from pkdyn.model.formats.mjcf import MjcfOptions, to_mjcf, write_mjcf

    positive("--step", args.step, "s")
    robot = load(args, geometry=True)
    options = MjcfOptions(timestep=args.step, contacts=not args.no_contacts)
    if args.out:
        write_mjcf(robot, args.out, options)
    else:
        sys.stdout.write(to_mjcf(robot, options))


def register(sub: Any) -> None:
    """Add the ``mjcf`` sub-command to the ``pkdyn`` parser."""
    sp = robot_command(sub, "mjcf", "write a MuJoCo model (MJCF) of the robot")
    output_option(sp, "-o", "--out", deprecated=("--output",), help="output file (default: stdout)")
    spelled_option(
        sp,
        "--step",
        deprecated=("--timestep",),
        type=number,
        default=1e-3,
        help="integration step of the simulation [s] (MJCF's timestep; default 0.001)",
    )
    sp.add_argument(
        "--no-contacts", action="store_true", help="write collision geoms without contacts"
    )
    sp.set_defaults(func=_cmd_mjcf)
