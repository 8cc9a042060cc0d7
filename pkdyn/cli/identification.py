"""``pkdyn identify``: dynamic parameters from a measured motion, written as a description.

The command reads the tables, calls :func:`pkdyn.identification.identify` and prints the
result's ``table()`` (``--json``: its ``to_json()``); ``--predict`` compares the identified
model with another motion.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from pkdyn.cli._common import emit, load, number, robot_command
from pkdyn.cli._paths import input_option, output_option

__all__ = ["register"]


def _cmd_identify(args: argparse.Namespace) -> None:
    from pkdyn.exceptions import InvalidInputError
    from pkdyn.identification import identify, read_measurements
    from pkdyn.identification.filtering import derivatives
    from pkdyn.tables import write_table
    from pkdyn.units import quantity

    if args.csv and not args.predict:
        raise InvalidInputError("--csv", "needs --predict (the motion to predict)")
    robot = load(args)
    names = robot.actuator_names
    data = read_measurements(args.measurements, names, need_tau=True)
    other = read_measurements(args.predict, names, need_tau=False) if args.predict else None
    res = identify(robot, data, parameters=args.parameters, cutoff=args.cutoff)
    payload: dict[str, Any] = res.to_json()
    text = [res.table()]
    if other is not None:
        qa, qd, qdd = other.qa, other.qa_dot, other.qa_ddot
        if qd is None or qdd is None:
            qa, qd, qdd = derivatives(other.t, other.qa, args.cutoff)
        tau = res.predict(other.t, qa, qd, qdd)
        pred: dict[str, Any] = {"file": args.predict, "samples": int(other.t.size)}
        if other.tau is not None:
            err = tau - other.tau
            rms = np.sqrt(np.mean(err**2, axis=0))
            scale = np.sqrt(np.mean(other.tau**2, axis=0))
            pred["rms_error"] = dict(zip(names, rms.tolist(), strict=True))
            pred["relative_rms_error"] = dict(
                zip(names, (rms / np.where(scale > 0, scale, 1.0)).tolist(), strict=True)
            )
            units = ["N" if p else "N m" for p in robot.actuator_prismatic]
            text.append(
                f"prediction of {args.predict}: RMS error "
                + ", ".join(
                    f"{n} {quantity(r, u)}" for n, r, u in zip(names, rms, units, strict=True)
                )
            )
        if args.csv:
            cols = ["t", *(f"tau_{n}" for n in names)]
            write_table(args.csv, cols, np.column_stack([other.t, tau]))
            pred["csv"] = args.csv
        payload["prediction"] = pred
    res.write_urdf(args.out)
    if args.plot:
        res.plot(args.plot)
        payload["plot"] = args.plot
    payload["output"] = args.out
    text.append(f"identified description written to {args.out}")
    emit(args, payload, "\n".join(text))


def register(sub: Any) -> None:
    """Add ``identify`` to the ``pkdyn`` parser."""
    sp = robot_command(
        sub, "identify", "identify masses, inertias, friction, rotor inertias from a motion"
    )
    input_option(
        sp,
        "--measurements",
        deprecated=("--data",),
        required=True,
        metavar="FILE",
        help="measured motion (CSV or Parquet): columns t, qa_<actuator> (readings), optional "
        "qa_dot_*, qa_ddot_*, and tau_<actuator> (joint-side efforts)",
    )
    output_option(
        sp,
        "-o",
        "--out",
        deprecated=("--output",),
        required=True,
        metavar="FILE.urdf",
        help="identified description",
    )
    sp.add_argument(
        "--parameters",
        default="inertia,friction,rotor",
        metavar="GROUPS",
        help="groups to identify, among inertia, payload, friction, rotor "
        "(default inertia,friction,rotor; payload: a load on the platform)",
    )
    sp.add_argument(
        "--cutoff",
        type=number,
        default=None,
        metavar="HZ",
        help="cut-off of the zero-phase position filter when rates are not given "
        "(default 5%% of the sampling rate)",
    )
    input_option(sp, "--predict", metavar="OTHER.csv", help="another motion to predict")
    output_option(
        sp, "--csv", metavar="PREDICTED.csv", help="write t and tau_<actuator> of --predict"
    )
    output_option(
        sp,
        "--plot",
        figure=True,
        metavar="FILE.png",
        help="the fit per actuator: measured, predicted, residual",
    )
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_identify)
