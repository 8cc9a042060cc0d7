"""Geometry and kinematic-analysis commands: info, urdf, geometric models, analyses.

Sub-commands: ``info``, ``urdf``, ``forward-geometry`` (alias ``fk``), ``inverse-geometry``
(alias ``ik``), ``mobility``, ``jacobian``, ``singularity``, ``statics``.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from pkdyn.cli._common import (
    configuration,
    emit,
    load,
    number,
    params,
    posed_command,
    qa_argument,
    robot_command,
)
from pkdyn.cli._paths import output_option
from pkdyn.exceptions import OutputError, PkdynError
from pkdyn.model.robot import PLATFORM_HINT

__all__ = ["register"]


def _cmd_info(args: argparse.Namespace) -> None:
    from pkdyn.model.info import robot_info

    emit(args, robot_info(load(args)))


def _cmd_urdf(args: argparse.Namespace) -> None:
    from pkdyn import library

    overrides = params(args.param)
    if args.robot in library.FAMILIES:
        from pkdyn.model.families import export_urdf

        load(args)  # every option checked (--home, --tol, --xacro-arg), as for a file
        fam = library.FAMILIES[args.robot]
        text = export_urdf(args.robot, fam.make_params(overrides))
    else:
        import pkdyn
        from pkdyn.model.formats.xmldoc import read_text
        from pkdyn.model.loader import detect_format

        load(args)  # validates the file
        text = read_text(args.robot, "description file")
        fmt = detect_format(text, args.robot)
        if fmt != "urdf":
            raise PkdynError(
                f"{args.robot} is an {fmt.upper()} description; 'pkdyn urdf' writes library "
                "robots and URDF files (use 'pkdyn mjcf' for a MuJoCo model)"
            )
        from pkdyn.model.formats.urdfplus_export import pkdyn_description

        text = pkdyn_description(  # URDF+ loops, couplings, actuation in pkdyn's elements
            text,
            args.robot,
            ignore_elements=tuple(args.ignore_element or ()),
            repair_inertias=args.repair_inertias,
        )
        del pkdyn
    if args.out:
        from pkdyn.files import atomic_write

        try:
            with atomic_write(args.out) as fh:
                fh.write(text)
        except OSError as err:
            raise OutputError(args.out, err.strerror or str(err)) from None
    else:
        sys.stdout.write(text)


def _cmd_fk(args: argparse.Namespace) -> None:
    import pkdyn

    robot = load(args)
    res = pkdyn.forward_geometry(robot, args.qa)
    if res.placement is None:
        raise PkdynError(
            f"{robot.name} declares no platform frame, so no pose to report; {PLATFORM_HINT}"
        )
    emit(args, res)


def _cmd_ik(args: argparse.Namespace) -> None:
    import pkdyn

    emit(args, pkdyn.inverse_geometry(load(args), args.pose))


def _cmd_mobility(args: argparse.Namespace) -> None:
    from pkdyn.analysis.mobility import mobility

    emit(args, mobility(load(args)))


def _cmd_jacobian(args: argparse.Namespace) -> None:
    from pkdyn.analysis.kinematics import kinematic_models

    emit(args, kinematic_models(*configuration(args)))


def _cmd_singularity(args: argparse.Namespace) -> None:
    import warnings

    from pkdyn.analysis.kinematics import NearSingularityWarning
    from pkdyn.analysis.singularity import classify

    robot, q = configuration(args)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearSingularityWarning)  # (the report says it)
        emit(args, classify(robot, q))


def _cmd_statics(args: argparse.Namespace) -> None:
    from pkdyn.analysis.statics import static_equilibrium

    robot, q = configuration(args)
    emit(args, static_equilibrium(robot, q, args.wrench, gravity=args.gravity))


def register(sub: Any) -> None:
    """Add this module's sub-commands to the ``pkdyn`` parser."""
    sp = robot_command(sub, "info", "model summary")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_info)
    sp = robot_command(sub, "urdf", "write the description")
    output_option(sp, "-o", "--out", deprecated=("--output",), help="output file (default: stdout)")
    sp.set_defaults(func=_cmd_urdf)
    sp = robot_command(
        sub, "forward-geometry", "direct geometric model (pkdyn.forward_geometry)", ("fk",)
    )
    qa_argument(sp, required=True)
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_fk)
    sp = robot_command(
        sub, "inverse-geometry", "inverse geometric model (pkdyn.inverse_geometry)", ("ik",)
    )
    sp.add_argument(
        "--pose", nargs="+", type=number, required=True, help="X Y Z [ROLL PITCH YAW] (m, rad)"
    )
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_ik)
    sp = robot_command(
        sub, "mobility", "mobility: Gruebler and rank-based (Pasqui), internal mobilities"
    )
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_mobility)
    posed_command(sub, "jacobian", "parallel-robot form A xd = B qd, J = A^-1 B").set_defaults(
        func=_cmd_jacobian
    )
    posed_command(
        sub, "singularity", "regular / serial / parallel / both, conditioning"
    ).set_defaults(func=_cmd_singularity)
    sp = posed_command(sub, "statics", "actuator efforts holding the platform against a wrench")
    sp.add_argument(
        "--wrench",
        nargs=6,
        type=number,
        default=[0.0] * 6,
        metavar=("FX", "FY", "FZ", "MX", "MY", "MZ"),
    )
    sp.add_argument("--gravity", action="store_true", help="include the robot's weight")
    sp.set_defaults(func=_cmd_statics)
