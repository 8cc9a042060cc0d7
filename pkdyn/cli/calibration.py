"""``pkdyn calibrate``: geometric calibration from measured poses, a calibrated URDF written.

The command reads the tables, calls :func:`pkdyn.calibration.calibrate` and prints the result's
``table()`` (``--json``: its ``to_json()``); it writes the calibrated description only when the
calibration can be trusted (:mod:`pkdyn.calibration.trust`), or with ``--accept``.
"""

from __future__ import annotations

import argparse
from typing import Any

from pkdyn.cli._common import emit, integer, load, number, robot_command
from pkdyn.cli._paths import input_option, output_option

__all__ = ["register"]


def _cmd_calibrate(args: argparse.Namespace) -> None:
    from pkdyn.calibration import calibrate, read_csv

    robot = load(args)
    m = read_csv(args.measurements, robot, args.implicit)
    validation = (
        read_csv(args.validation, robot, m.kind if m.kind in ("point", "plane") else None)
        if args.validation
        else None
    )
    res = calibrate(
        robot,
        m,
        model=args.model,
        noise=args.noise,
        holdout=args.holdout,
        validation=validation,
        robust=args.robust,
        gains=args.gains,
        seed=args.seed,
        tolerance=args.tolerance,
        accept=args.accept,
        residual_limit=args.residual_limit,
        correction_limit=args.correction_limit,
    )
    res.write_urdf(args.out)
    if args.plot:
        res.plot(args.plot)
    out: dict[str, Any] = res.to_json()
    out["output"] = args.out
    if args.plot:
        out["plot"] = args.plot
    what = "written" if res.trusted else "written although not trusted (--accept)"
    emit(args, out, res.table() + f"\n{what}: {args.out}")


def register(sub: Any) -> None:
    """Add this module's sub-commands to the ``pkdyn`` parser."""
    from pkdyn.calibration.trust import CORRECTION_LIMIT, RESIDUAL_LIMIT

    sp = robot_command(sub, "calibrate", "geometric calibration from measured platform poses")
    input_option(
        sp,
        "--measurements",
        required=True,
        metavar="FILE",
        help="table (CSV or Parquet): qa_<actuator> columns (encoder readings) and the measured "
        "x y z [rx ry rz] (m, rad), or a group column with --implicit, or q_<joint> columns "
        "(encoders on passive joints: self-calibration from extra sensors)",
    )
    output_option(
        sp,
        "-o",
        "--out",
        deprecated=("--output",),
        required=True,
        metavar="FILE.urdf",
        help="calibrated URDF to write",
    )
    sp.add_argument(
        "--model",
        default="auto",
        choices=("auto", "placements", "shortcuts", "family"),
        help="parameters: every placement, the family shortcuts (Delta, Gough-Stewart), or the "
        "family dimensions (default: shortcuts when the family has them)",
    )
    sp.add_argument("--gains", action="store_true", help="identify actuator gains too")
    sp.add_argument(
        "--noise",
        nargs="+",
        type=number,
        metavar="SIGMA",
        help="measurement noise: position [m] [orientation [rad]] (default: estimated)",
    )
    sp.add_argument(
        "--holdout", type=number, default=0.2, help="fraction held out for validation (0.2)"
    )
    input_option(
        sp,
        "--validation",
        metavar="FILE",
        help="held-out measurements (same columns) instead of --holdout: errors before/after",
    )
    sp.add_argument("--robust", default="huber", choices=("huber", "cauchy", "none"))
    sp.add_argument(
        "--implicit",
        choices=("point", "plane"),
        help="self-calibration: the platform held on one unknown point / plane per group",
    )
    sp.add_argument(
        "--tolerance",
        nargs="+",
        type=number,
        metavar="T",
        help="tolerances the corrections are judged against: length [m] angle [rad] [gain] "
        "(default: 0.5 %% of the robot's size, 0.5 deg, 0.5 %%)",
    )
    sp.add_argument(
        "--residual-limit",
        type=number,
        default=RESIDUAL_LIMIT,
        metavar="K",
        help=f"largest residual RMS trusted, times the stated noise ({RESIDUAL_LIMIT:g})",
    )
    sp.add_argument(
        "--correction-limit",
        type=number,
        default=CORRECTION_LIMIT,
        metavar="K",
        help=f"largest correction trusted, times its tolerance ({CORRECTION_LIMIT:g})",
    )
    sp.add_argument(
        "--accept",
        action="store_true",
        help="write the calibrated URDF even when the calibration is not trusted",
    )
    output_option(
        sp,
        "--plot",
        figure=True,
        metavar="FILE.png",
        help="residuals per pose and axis, before and after",
    )
    sp.add_argument("--seed", type=integer, default=0, help="seed of the hold-out split")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_calibrate)
