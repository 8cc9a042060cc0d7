"""``pkdyn calibrate``: geometric calibration from measured poses, a calibrated URDF written."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from pkdyn.cli._common import emit, integer, load, number, robot_command
from pkdyn.cli._paths import input_option, output_option

__all__ = ["register"]


def _cmd_calibrate(args: argparse.Namespace) -> None:
    from pkdyn.calibration import calibrate, read_csv
    from pkdyn.calibration.writer import write_calibrated

    robot = load(args)
    m = read_csv(args.measurements, robot, args.implicit)
    res = calibrate(
        robot,
        m,
        model=args.model,
        noise=args.noise,
        holdout=args.holdout,
        robust=args.robust,
        gains=args.gains,
        seed=args.seed,
    )
    write_calibrated(res, args.out)
    out = res.as_dict()
    out["output"] = args.out
    field, unit, what = (
        ("joint_rms", "rad or m", "passive joint error RMS")
        if m.kind == "joints"
        else ("position_rms", "m", "position error RMS")
    )
    lines = [
        f"{res.model.kind} model: {res.identifiability.rank} of {res.model.size} parameters "
        f"identified from {res.calibration_rows.size} poses ({m.kind})",
        f"{what}: {getattr(res.before, field):.4g} {unit} before, "
        f"{getattr(res.after, field):.4g} {unit} after (calibration poses)",
    ]
    if res.validation_after is not None and res.validation_before is not None:
        lines.append(
            f"held-out poses ({res.validation_rows.size}): "
            f"{getattr(res.validation_before, field):.4g} {unit} before, "
            f"{getattr(res.validation_after, field):.4g} {unit} after"
        )
    unid = out["unidentifiable"]
    if unid:
        names = ", ".join(u["name"] for u in unid[:8]) + (" ..." if len(unid) > 8 else "")
        lines.append(f"not identifiable (held at nominal): {names}")
    if len(res.outliers):
        rows = np.asarray(res.outliers) + 2  # CSV lines (the header is line 1)
        shown = ", ".join(str(int(r)) for r in rows[:8]) + (" ..." if len(rows) > 8 else "")
        lines.append(f"outliers (down-weighted by the robust weights): CSV lines {shown}")
    if res.not_assembling:
        lines.append(f"not assembling (held at nominal): {len(res.not_assembling)} parameters")
    idx = res.identifiability.indices
    lines.append(
        "observability: "
        + ", ".join(f"{k} = {v:.3g}" for k, v in idx.items())
        + " (O4: noise amplification index)"
    )
    lines.append(f"written: {args.out}")
    emit(args, out, "\n".join(lines))


def register(sub: Any) -> None:
    """Add this module's sub-commands to the ``pkdyn`` parser."""
    sp = robot_command(sub, "calibrate", "geometric calibration from measured platform poses")
    input_option(
        sp,
        "--measurements",
        required=True,
        metavar="FILE.csv",
        help="CSV: qa_<actuator> columns (encoder readings) and the measured x y z [rx ry rz] "
        "(m, rad), or a group column with --implicit, or q_<joint> columns (encoders on "
        "passive joints: self-calibration from extra sensors)",
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
    sp.add_argument("--robust", default="huber", choices=("huber", "cauchy", "none"))
    sp.add_argument(
        "--implicit",
        choices=("point", "plane"),
        help="self-calibration: the platform held on one unknown point / plane per group",
    )
    sp.add_argument("--seed", type=integer, default=0, help="seed of the hold-out split")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_calibrate)
