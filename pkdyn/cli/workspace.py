"""Workspace and collision commands: ``workspace`` and ``collisions``."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
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
    shown = rep.pairs[: args.top] if args.top else rep.pairs
    lines = [
        f"min distance {rep.min_distance * 1e3:.3f} mm "
        f"({'IN COLLISION' if rep.in_collision else 'clear'}, margin {args.margin * 1e3:g} mm)"
    ]
    lines += [f"  {p.a:>22s} - {p.b:<22s} {p.distance * 1e3:9.3f} mm" for p in shown]
    emit(args, rep.as_json(), "\n".join(lines))


def _cmd_clavel(args: argparse.Namespace, robot: Any) -> None:
    from pkdyn.exceptions import PkdynError
    from pkdyn.workspace.clavel import clavel_closed_form, clavel_numeric

    if robot.family != "delta":
        raise PkdynError(
            f"--clavel applies to the delta family (ra, rb, la, lb); {robot.name} is not one"
        )
    p = robot.params
    cf = clavel_closed_form(p, args.gamma_max, args.ab_min)
    nu, v_ws = clavel_numeric(
        p, args.gamma_max, args.ab_min, rays=args.rays, progress=False if args.json else None
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


def _sampled(
    args: argparse.Namespace,
    robot: Any,
    compute: Callable[..., Any],
    options: dict[str, Any],
    plot: Callable[..., Any],
    to_json: Callable[[Any], dict[str, Any]],
    title: Callable[[Any], str] | None = None,
) -> tuple[dict[str, Any], str]:
    """Run one sampled workspace, plot it if asked: its JSON and text (every ``--kind``)."""
    result = compute(robot, **options, progress=False if args.json else None)
    if args.plot:
        extra = {} if title is None else {"title": title(result)}
        plot(result, path=args.plot, **extra)
    out = to_json(result)
    return out, _text(out)


def _translation(args: argparse.Namespace, robot: Any) -> tuple[dict[str, Any], str]:
    from pkdyn.plotting.workspace import plot_translation_workspace
    from pkdyn.workspace.translation import translation_workspace

    options = dict(
        rpy=args.rpy,
        bounds=_box(args.bounds),
        step=args.step,
        samples=args.samples,
        limits=args.limits,
        margin=args.margin,
        method=args.method,
    )
    return _sampled(
        args, robot, translation_workspace, options, plot_translation_workspace, _as_json
    )


def _orientation(args: argparse.Namespace, robot: Any) -> tuple[dict[str, Any], str]:
    from pkdyn.plotting.workspace import plot_orientation_workspace
    from pkdyn.workspace.orientation import mel_study, orientation_workspace

    if args.mel:
        study = mel_study(
            robot,
            args.center,
            args.vector,
            n1=args.n1,
            n2=args.n2,
            progress=False if args.json else None,
        )
        cases = {name: ow.as_json() for name, ow in study.items()}
        payload = dict(list(cases.values())[-1])
        payload["cases"] = cases
        if args.plot:
            from pkdyn.plotting.workspace import plot_mel_study

            plot_mel_study(study, path=args.plot)
        lines = [
            f"{name:28s} {c['volume']:.4f} sr  (full circles {c['full_circles']})"
            for name, c in cases.items()
        ]
        return payload, "\n".join(
            ["MEL prototype study (Merlet ch. 3), allowed solid angle:", *lines]
        )
    options = dict(
        center=args.center,
        N=args.vector,
        X1=args.x1,
        X2=args.x2,
        rpy0=args.rpy,
        n1=args.n1,
        n2=args.n2,
        limits=args.limits,
        margin=args.margin,
    )
    return _sampled(
        args, robot, orientation_workspace, options, plot_orientation_workspace, _as_json
    )


def _dextrous(args: argparse.Namespace, robot: Any) -> tuple[dict[str, Any], str]:
    from pkdyn.plotting.workspace import plot_translation_workspace
    from pkdyn.workspace.dextrous import dextrous_json, dextrous_workspace

    options = dict(
        bounds=_box(args.bounds),
        step=args.step,
        samples=args.samples,
        joint_limits=args.joint_limits,
    )
    return _sampled(
        args,
        robot,
        dextrous_workspace,
        options,
        plot_translation_workspace,
        dextrous_json,
        title=lambda ws: f"{ws.robot}: dextrous workspace, {ws.volume:.4g} m^3",
    )


def _as_json(result: Any) -> dict[str, Any]:
    return dict(result.as_json())


def _box(values: list[float] | None) -> Any:
    return None if values is None else [values[0:2], values[2:4], values[4:6]]


def _text(out: dict[str, Any]) -> str:
    unit = out.get("volume_unit", "m^3")
    lines = [f"{out['kind']} workspace: volume {out['volume']:.6g} {unit}"]
    if out["bounds"] is not None:
        lines.append("bounds: " + ", ".join(f"[{a:.4f}, {b:.4f}]" for a, b in out["bounds"]))
    lines.append(
        f"samples: {out['samples']}, rejected by: "
        + ", ".join(f"{k} {v}" for k, v in out["limits_hit"].items())
    )
    if out.get("touches_box"):
        lines.append("note: reachable samples touch the sampled box; widen --bounds")
    return "\n".join(lines)


def _cmd_workspace(args: argparse.Namespace) -> None:
    robot = load(args, geometry=True)
    if args.clavel:
        _cmd_clavel(args, robot)
        return
    run = {"translation": _translation, "orientation": _orientation, "dextrous": _dextrous}
    payload, text = run[args.kind](args, robot)
    emit(args, payload, text)


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
