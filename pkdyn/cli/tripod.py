"""Walking-tripod commands: ``pkdyn tripod scenario`` (seed 003, modes PP and BE).

``--branches 4`` runs the four-branch walker the paper proposes: the same plan, its swings with
the nacelle path chosen by the redundancy resolution (:mod:`pkdyn.tripod.redundancy`); each swing's
JSON entry adds ``redundancy`` (the objective's values, baseline and chosen path).
"""

from __future__ import annotations

import argparse
from typing import Any

from pkdyn.cli._common import Parser, add_param_option, emit, integer, number, params
from pkdyn.cli._paths import output_option
from pkdyn.exceptions import InvalidInputError, PkdynError

__all__ = ["register"]


def _cmd_scenario(args: argparse.Namespace) -> None:
    import pkdyn
    from pkdyn.tripod.analysis import run_scenario
    from pkdyn.tripod.machining import MachiningPlan
    from pkdyn.tripod.scenario import WalkPlan

    overrides = params(args.param)
    if args.branches is not None:
        overrides["branches"] = args.branches
    robot = pkdyn.load("tripod", geometry=True, **overrides)
    if args.stride < 1:
        raise InvalidInputError("--stride", f"must be >= 1, got {args.stride}")
    plan = WalkPlan(
        step=(args.step[0], args.step[1]),
        cycles=args.cycles,
        lift=args.lift,
        tilt=args.tilt,
        swing_time=args.swing_time,
        reconfiguration_time=args.reconfiguration_time,
        dt=args.dt,
        machining=None if args.no_machining else MachiningPlan(),
        surface_radius=args.surface_radius,
    )
    report = run_scenario(robot, plan, stride=args.stride, allocation=args.allocation)
    if args.plot:
        report.plot(args.plot)
    if args.html:
        _html(robot, report, args.html)
    emit(args, report)
    bad = report.violations()
    if bad:
        more = f" (and {len(bad) - 1} more, see the report)" if len(bad) > 1 else ""
        raise PkdynError(f"the scenario is not feasible: {bad[0]}{more}")


def _html(robot: Any, report: Any, path: str) -> None:
    from pkdyn.viewer import animate, export_html

    scene = animate(robot, report.t, report.q)
    export_html(scene, path)


def register(sub: Any) -> None:
    """Add ``pkdyn tripod ...`` to the ``pkdyn`` parser."""
    sp = sub.add_parser("tripod", help="walking tripod (Yang et al.): modes PP / BE, scenario")
    tsub = sp.add_subparsers(dest="tripod_command", required=True, parser_class=Parser)
    sc = tsub.add_parser(
        "scenario",
        help="machining, reconfiguration and swing of each branch, repeated; checks per phase",
    )
    add_param_option(sc)
    sc.add_argument(
        "--branches",
        type=integer,
        choices=(3, 4),
        help="3: the tripod (default); 4: the four-branch walker (redundancy while swinging)",
    )
    sc.add_argument(
        "--allocation",
        choices=("norm", "max"),
        default="norm",
        help="the walker's redundant actuation in PP: least norm (default) or least largest force",
    )
    sc.add_argument("--cycles", type=integer, default=2, help="walking cycles (default 2)")
    sc.add_argument(
        "--step",
        nargs=2,
        type=number,
        default=[0.10, 0.0],
        metavar=("DX", "DY"),
        help="foot displacement per cycle [m] (default 0.10 0)",
    )
    sc.add_argument("--lift", type=number, default=0.03, help="foot lift [m] (default 0.03)")
    sc.add_argument(
        "--tilt", type=number, default=0.10, help="nacelle tilt at swing end [rad] (default 0.1)"
    )
    sc.add_argument("--swing-time", type=number, default=2.5, help="[s] (default 2.5)")
    sc.add_argument("--reconfiguration-time", type=number, default=1.5, help="[s] (default 1.5)")
    sc.add_argument("--dt", type=number, default=0.05, help="sample period [s] (default 0.05)")
    sc.add_argument("--no-machining", action="store_true", help="walk only")
    sc.add_argument(
        "--surface-radius",
        type=number,
        default=float("inf"),
        metavar="R",
        help="walk across a cylindrical support of radius R [m] (default: a plane)",
    )
    sc.add_argument(
        "--stride", type=integer, default=1, help="singularity margin every N samples (default 1)"
    )
    sc.add_argument("--json", action="store_true")
    output_option(
        sc, "--plot", figure=True, metavar="FILE", help="save the summary figure (png, pdf, svg)"
    )
    output_option(sc, "--html", metavar="FILE", help="save a meshcat animation (static HTML)")
    sc.set_defaults(func=_cmd_scenario)
