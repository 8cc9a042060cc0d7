"""The ``vibration`` command: how the tool deviates along a motion and settles after it."""

from __future__ import annotations

import argparse
from typing import Any

from pkdyn.cli._common import emit, integer, load, number, robot_command
from pkdyn.cli._paths import input_option, output_option
from pkdyn.exceptions import InvalidInputError

__all__ = ["register"]


def _cmd_vibration(args: argparse.Namespace) -> None:
    from pkdyn.precision.vibration import vibration

    if args.scale is not None and not args.scale > 0.0:
        raise InvalidInputError("--scale", f"must be > 0, got {args.scale:g}")
    if not args.slow > 0.0:
        raise InvalidInputError("--slow", f"must be > 0, got {args.slow:g}")
    if args.trajectory.lower().endswith(".csv"):
        if args.cycle_time is not None:
            raise InvalidInputError(
                "--cycle-time", "does not apply to a trajectory read from a file"
            )
    if args.shaper_modes != 1 and args.shaper is None:
        raise InvalidInputError("--shaper-modes", "needs --shaper zv|zvd")
    robot = load(args, geometry=args.material is not None or args.html is not None)
    options: dict[str, Any] = {
        "cycle_time": args.cycle_time,
        "payload": args.payload,
        "actuator_stiffness": args.actuator_stiffness,
        "material": args.material,
        "links": not args.rigid_links,
        "damping_ratio": args.damping_ratio,
        "actuator_damping": args.actuator_damping,
        "feedforward": args.feedforward,
        "band": args.band,
        "dwell": args.dwell,
        "method": args.method,
        "modes": args.modes,
        "poses": args.poses,
        "point": args.point,
        "dt": args.dt,
        "profile": args.profile,
    }
    trajectory = args.trajectory
    result = vibration(
        robot, trajectory, shaper=args.shaper, shaper_modes=args.shaper_modes, **options
    )
    unshaped = None
    if args.shaper is not None:  # what shaping buys: the same motion unshaped
        unshaped = vibration(robot, trajectory, **options)
    payload = result.to_json()
    text = [result.table()]
    if unshaped is not None:
        payload["unshaped"] = unshaped.to_json()
        text += ["", "without shaping:", unshaped.table()]
    if args.csv:
        result.write_csv(args.csv)
        payload["csv"] = args.csv
    if args.plot:
        result.plot(args.plot, compare=[] if unshaped is None else [unshaped])
        payload["plot"] = args.plot
    if args.html:
        from pkdyn.viewer import animate_vibration
        from pkdyn.viewer.vibration import exaggerated

        scale = exaggerated(result, args.scale)[2] if args.scale is None else args.scale
        scene = animate_vibration(result, scale=scale, slow=args.slow)
        try:
            path = scene.save_html(args.html)
        finally:
            scene.close()
        payload["html"] = str(path)
        text.append(f"wrote {path}: deformation x {scale:.3g}, played {args.slow:g} times slower")
    emit(args, payload, "\n".join(text))


def register(sub: Any) -> None:
    """Add ``vibration`` to the ``pkdyn`` parser."""
    sp = robot_command(
        sub,
        "vibration",
        "how the tool deviates from its rigid motion along a motion, and settles after it",
    )
    input_option(
        sp,
        "--trajectory",
        or_name=True,
        default="adept",
        metavar="NAME|FILE.csv",
        help="adept, p2p, or a CSV file (a column t [s] and qa_<actuator> columns or the "
        "controlled pose components); from rest to rest",
    )
    sp.add_argument(
        "--cycle-time", type=number, default=None, help="adept: cycle time; p2p: move duration [s]"
    )
    sp.add_argument("--payload", type=number, default=0.0, help="payload at the tool [kg]")
    sp.add_argument(
        "--actuator-stiffness",
        nargs="+",
        type=number,
        metavar="K",
        help="servo stiffness, one or one per actuator [N m/rad or N/m] (default: the "
        "description's <pkdyn:stiffness>)",
    )
    sp.add_argument(
        "--damping-ratio",
        type=number,
        default=None,
        metavar="Z",
        help="damping ratio of the first mode at the middle pose: servo c = 2 Z k / omega_1, "
        "links beta k with beta = 2 Z / omega_1 (default 0.02)",
    )
    sp.add_argument(
        "--actuator-damping",
        nargs="+",
        type=number,
        metavar="C",
        help="servo damping on the error rate, one or one per actuator [N m s/rad or N s/m] "
        "(default: from --damping-ratio)",
    )
    sp.add_argument(
        "--feedforward",
        choices=("none", "gravity", "rigid"),
        default="none",
        help="servo feedforward: none (default), gravity (static load held), rigid (rigid "
        "inverse dynamics)",
    )
    sp.add_argument(
        "--material",
        help="model the slender links as beams of this material (steel, aluminium, carbon)",
    )
    sp.add_argument(
        "--rigid-links", action="store_true", help="ignore the links' described compliance"
    )
    sp.add_argument(
        "--band", type=number, default=1e-4, help="settling band on the deviation [m] (1e-4)"
    )
    sp.add_argument(
        "--dwell",
        type=number,
        default=0.5,
        help="time after the motion within which the tool must settle [s] (0.5)",
    )
    sp.add_argument(
        "--method",
        choices=("modal", "multibody"),
        default="modal",
        help="modal: the modes along the path superposed (fast); multibody: the elastic model "
        "simulated (the reference)",
    )
    sp.add_argument(
        "--shaper",
        choices=("zv", "zvd"),
        default=None,
        help="shape the command from the modes along the path (the unshaped result is "
        "reported too)",
    )
    sp.add_argument(
        "--shaper-modes", type=integer, default=1, metavar="N", help="modes the shaper targets (1)"
    )
    sp.add_argument(
        "--modes",
        type=integer,
        default=None,
        metavar="N",
        help="modes integrated, the lowest (default: up to 8 times the first frequency)",
    )
    sp.add_argument(
        "--poses",
        type=integer,
        default=None,
        metavar="N",
        help="poses along the motion where the modes are computed (modal method; 33, or 65 "
        "with compliant links; every sample on the library Delta with rigid links, in closed "
        "form)",
    )
    sp.add_argument(
        "--point",
        nargs=3,
        type=number,
        metavar=("X", "Y", "Z"),
        help="tool point in the platform frame [m] (default: its origin)",
    )
    sp.add_argument("--profile", choices=("quintic", "jerk"), default="quintic")
    sp.add_argument("--dt", type=number, default=1e-3, help="sample period of the motion [s]")
    output_option(
        sp,
        "--csv",
        metavar="FILE",
        help="write the time series (t, deviation_<c>, deviation_norm, deviation_from_rest)",
    )
    output_option(
        sp,
        "--plot",
        figure=True,
        metavar="FILE.png",
        help="plot the deviation against time with the band",
    )
    output_option(
        sp,
        "--html",
        metavar="FILE",
        help="save a meshcat animation, the deformation exaggerated (static HTML)",
    )
    sp.add_argument(
        "--scale",
        type=number,
        default=None,
        help="exaggeration of the deformation in --html (default: peak shown as 5 %% of the "
        "robot's size)",
    )
    sp.add_argument("--slow", type=number, default=20.0, help="slow-motion factor of --html (20)")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_vibration)
