"""Geometry and kinematic-analysis commands: info, urdf, geometric models, analyses.

Sub-commands: ``info``, ``urdf``, ``forward-geometry`` (alias ``fk``), ``inverse-geometry``
(alias ``ik``), ``mobility``, ``jacobian``, ``singularity``, ``statics``.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import numpy as np

from pkdyn.cli._common import (
    configuration,
    emit,
    fmt,
    gains_of,
    load,
    output_path,
    params,
    posed_command,
    qa_argument,
    robot_command,
    units,
)
from pkdyn.exceptions import OutputError, PkdynError
from pkdyn.model.description import CouplingSpec
from pkdyn.model.robot import PLATFORM_HINT

__all__ = ["register"]


def _limit(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def _cmd_info(args: argparse.Namespace) -> None:
    robot = load(args)
    closures = [{"name": c.name, "type": c.kind} for c in robot.closures]
    joints, names = robot.actuated_joint_names, robot.actuator_names
    dof, internal = robot.mobility_split()
    actuation = [
        {
            "name": a.name,
            "joint": a.joint,
            "type": "prismatic" if prismatic else "revolute",
            "effort": _limit(a.effort),
            "velocity": _limit(a.velocity),
            "reduction": a.reduction,
            "units": {"position": u[0], "velocity": u[1], "effort": u[2]},
        }
        for a, prismatic, u in zip(
            robot.actuators, robot.actuator_prismatic, units(robot), strict=True
        )
    ]
    payload = {
        "name": robot.name,
        "nq": robot.nq,
        "nv": robot.nv,
        "dof": dof,
        "internal": internal,
        "actuated": joints,
        "actuators": names,
        "actuation": actuation,
        "loops": robot.loops,
        "closures": closures,
        "couplings": [
            {
                "name": c.name,
                "joint": c.joint,
                "source": c.source,
                "coefficients": list(c.coefficients),
                "joint_ref": c.joint_ref,
                "source_ref": c.source_ref,
            }
            for c in robot.couplings
        ],
    }
    from pkdyn.model.passive import passive_summary

    passive = passive_summary(robot)
    payload["passive"] = passive

    def limits(a: dict[str, Any]) -> str:
        u = a["units"]
        eff = "-" if a["effort"] is None else f"{a['effort']:g} {u['effort']}"
        vel = "-" if a["velocity"] is None else f"{a['velocity']:g} {u['velocity']}"
        return f"{a['joint']} ({a['name']}, {a['type']}, {eff}, {vel})"

    lines = [
        f"{robot.name}: nq={robot.nq} nv={robot.nv} dof={dof} internal={internal} "
        f"loops={robot.loops}",
        "actuated: " + ", ".join(limits(a) for a in actuation),
        "closures: " + ", ".join(f"{c['name']} ({c['type']})" for c in closures),
    ]
    if robot.couplings:
        lines.append("couplings: " + ", ".join(_coupling_text(c) for c in robot.couplings))
    lines.append("passive: " + (_passive_text(passive) or "none"))
    emit(args, payload, "\n".join(lines))


def _coupling_text(c: CouplingSpec) -> str:
    """``name (joint = p(source))`` of a coupling, coefficients constant term first."""
    coef = " ".join(f"{v:.6g}" for v in c.coefficients)
    if c.source is None:
        return f"{c.name} ({c.joint} locked at {c.joint_ref + c.coefficients[0]:.6g})"
    return f"{c.name} ({c.joint} from {c.source}, coefficients {coef})"


def _values(x: list[float]) -> str:
    return " ".join(f"{v:.4g}" for v in x)


def _passive_text(passive: dict[str, Any]) -> str:
    """One line per passive element (SI units: stiffness N m/rad or N/m, rest rad or m, ...)."""
    rows = []
    for e in passive["joints"]:
        parts = []
        if "stiffness" in e:
            parts.append(f"stiffness {_values(e['stiffness'])} rest {_values(e['rest'])}")
        for k in ("damping", "friction", "armature"):
            if k in e:
                parts.append(f"{k} {_values(e[k])}")
        rows.append(f"\n  joint {e['joint']}: " + ", ".join(parts))
    for s in passive["springs"]:
        rows.append(
            f"\n  spring {s['name']} ({s['link1']} - {s['link2']}): {s['stiffness']:.4g} N/m, "
            f"free length {s['rest_length']:.4g} m, tension at home {s['tension']:.4g} N"
        )
    return "".join(rows)


def _cmd_urdf(args: argparse.Namespace) -> None:
    from pkdyn import library

    output_path("-o", args.output)
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
        del pkdyn
    if args.output:
        from pkdyn.files import atomic_write

        try:
            with atomic_write(args.output) as fh:
                fh.write(text)
        except OSError as err:
            raise OutputError(args.output, err.strerror or str(err)) from None
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
    payload = {
        "position": res.position.tolist(),
        "rpy": res.rpy.tolist(),
        "q": res.q.tolist(),
        "qa": res.qa.tolist(),
        "residual": res.residual,
    }
    text = f"position [m]: {fmt(res.position)}\nrpy [rad]:    {fmt(res.rpy)}"
    g = gains_of(robot)
    if np.any(g != 1.0):  # a calibrated robot: readings differ from joint coordinates
        payload["readings"] = (res.qa / g).tolist()
    emit(args, payload, text)


def _cmd_ik(args: argparse.Namespace) -> None:
    import pkdyn

    robot = load(args)
    res = pkdyn.inverse_geometry(robot, args.pose)
    names = robot.actuator_names
    payload = {
        "qa": res.qa.tolist(),
        "q": res.q.tolist(),
        "actuators": names,
        "residual": res.residual,
    }
    text = "\n".join(
        f"{n}: {v:.9f} {u[0]}" for n, v, u in zip(names, res.qa, units(robot), strict=True)
    )
    g = gains_of(robot)
    if np.any(g != 1.0):  # a calibrated robot: what its encoders will read there
        readings = res.qa / g
        payload["readings"] = readings.tolist()
        text += "\nencoder readings (joint coordinate / <pkdyn:encoder gain>):\n" + "\n".join(
            f"{n}: {v:.9f} {u[0]}" for n, v, u in zip(names, readings, units(robot), strict=True)
        )
    emit(args, payload, text)


def _cmd_mobility(args: argparse.Namespace) -> None:
    from pkdyn.analysis.mobility import format_mobility, mobility

    result = mobility(load(args))
    emit(args, result.as_json(), format_mobility(result))


def _cmd_jacobian(args: argparse.Namespace) -> None:
    from pkdyn.analysis.kinematics import jacobian_json

    robot, q = configuration(args)
    out = jacobian_json(robot, q)
    text = "\n".join(f"{k} =\n{np.array2string(np.array(out[k]), precision=5)}" for k in "ABJ")
    emit(args, out, text)


def _cmd_singularity(args: argparse.Namespace) -> None:
    from pkdyn.analysis.singularity import singularity_json

    robot, q = configuration(args)
    out = singularity_json(robot, q)
    text = (
        f"{out['kind']}: margin = {out['margin']:.4g} (scale-aware, 0: singular), "
        f"cond(A) = {out['cond_A']:.4g}, cond(B) = {out['cond_B']:.4g}"
    )
    emit(args, out, text)


def _cmd_statics(args: argparse.Namespace) -> None:
    from pkdyn.analysis.statics import statics_json

    robot, q = configuration(args)
    out = statics_json(robot, q, args.wrench, gravity=args.gravity)
    lines = [
        f"{n}: {t:.6g} {u[2]}"
        for n, t, u in zip(out["actuators"], out["tau"], units(robot), strict=True)
    ]
    for name, r in out["reactions"].items():
        lines.append(
            f"closure {name}: force {_vector(r['force'])} N, moment {_vector(r['moment'])} N m "
            f"about {_vector(r['point'])} m (on its first body, world axes)"
        )
    for name, f in out["couplings"].items():
        lines.append(f"coupling {name}: {f + 0.0:.6g} (N m or N, on its driven joint)")
    emit(args, out, "\n".join(lines))


def _vector(v: list[float]) -> str:
    return "[" + " ".join(f"{x + 0.0:.4g}" for x in v) + "]"  # (+ 0.0: no negative zero)


def register(sub: Any) -> None:
    """Add this module's sub-commands to the ``pkdyn`` parser."""
    sp = robot_command(sub, "info", "model summary")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_info)
    sp = robot_command(sub, "urdf", "write the description")
    sp.add_argument("-o", "--output", help="output file (default: stdout)")
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
        "--pose", nargs="+", type=float, required=True, help="X Y Z [ROLL PITCH YAW] (m, rad)"
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
        type=float,
        default=[0.0] * 6,
        metavar=("FX", "FY", "FZ", "MX", "MY", "MZ"),
    )
    sp.add_argument("--gravity", action="store_true", help="include the robot's weight")
    sp.set_defaults(func=_cmd_statics)
