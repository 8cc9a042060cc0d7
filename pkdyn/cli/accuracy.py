"""``pkdyn accuracy``: error budget of the platform pose (actuator and geometric errors)."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from pkdyn.cli._common import emit, load, output_path, qa_argument, robot_command

__all__ = ["register"]


def _budget(b: Any) -> dict[str, Any]:
    return {
        "worst_case": [float(v) for v in b.worst],
        "rms": [float(v) for v in b.rms],
        "position_worst": b.position_worst,
        "position_rms": b.position_rms,
        "orientation_worst": b.orientation_worst,
        "orientation_rms": b.orientation_rms,
    }


def _tolerances(args: argparse.Namespace, robot: Any, model: Any) -> np.ndarray:
    length = args.tolerance[0]
    angle = args.tolerance[1] if len(args.tolerance) > 1 else length / robot.length_scale
    gain = args.tolerance[2] if len(args.tolerance) > 2 else 0.0
    return np.asarray(model.tolerances(length, angle, gain))


def _cmd_accuracy(args: argparse.Namespace) -> None:
    import pkdyn
    from pkdyn.exceptions import InvalidInputError
    from pkdyn.inputs import count, seed
    from pkdyn.precision.accuracy import (
        accuracy_map,
        actuator_errors,
        geometric_errors,
        monte_carlo,
        slice_grid,
    )
    from pkdyn.precision.parameters import parameter_model

    output_path("--plot", args.plot, figure=True)
    count("--top", args.top, 0)
    seed("--seed", args.seed)
    if args.plot and args.map is None:
        raise InvalidInputError("--plot", "plots a map: give --map xy|xz|yz")
    from pkdyn.inputs import vector

    if not 1 <= len(args.tolerance) <= 3:
        raise InvalidInputError("--tolerance", "give LENGTH [ANGLE [GAIN]] >= 0 (m, rad, -)")
    tolerance = vector("--tolerance", args.tolerance, (1, 2, 3), "m, rad, -")
    if np.any(tolerance < 0.0):
        raise InvalidInputError("--tolerance", "give LENGTH [ANGLE [GAIN]] >= 0 (m, rad, -)")
    robot = load(args)
    model = parameter_model(robot, args.model)
    tol = _tolerances(args, robot, model)
    if args.map is not None:
        centre = (
            robot.platform_placement(robot.q_home).translation
            if args.center is None
            else np.asarray(args.center, dtype=float)
        )
        extent = args.extent if args.extent is not None else 0.2 * robot.length_scale
        P, shape = slice_grid(centre, args.map, extent, args.grid)
        amap = accuracy_map(
            robot,
            P,
            args.resolution,
            args.backlash,
            model,
            tol,
            shape=shape,
            axes=(args.map[0], args.map[1]),
        )
        if args.plot:
            from pkdyn.plotting.accuracy import plot_accuracy_map

            plot_accuracy_map(amap, args.field, path=args.plot)
        grid: dict[str, Any] = {
            "axes": list(amap.axes),
            "positions": amap.P.tolist(),
            "valid": amap.valid.tolist(),
            **{
                f: [
                    None if not v else float(x)
                    for x, v in zip(getattr(amap, f), amap.valid, strict=True)
                ]
                for f in ("actuator_worst", "actuator_rms", "geometric_worst", "geometric_rms")
            },
        }
        ok = amap.valid
        a_max = float(np.nanmax(amap.actuator_worst)) if ok.any() else float("nan")
        g_max = float(np.nanmax(amap.geometric_rms)) if ok.any() else float("nan")
        text = (
            f"{int(ok.sum())} of {ok.size} positions reached; worst-case position error "
            f"(actuators) up to {a_max:.4g} m, geometric RMS up to {g_max:.4g} m"
            + (f"; plot: {args.plot}" if args.plot else "")
        )
        emit(args, grid, text)
        return
    if args.qa is not None:
        q = pkdyn.forward_geometry(robot, args.qa, check_limits=False).q
    else:
        q = pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q
    act = actuator_errors(robot, q, args.resolution, args.backlash)
    geo = geometric_errors(robot, q, model, tol, args.distribution)
    payload: dict[str, Any] = {
        "pose_components": ["x", "y", "z", "rx", "ry", "rz"],
        "actuators": {**_budget(act), "J": act.J.tolist()},
        "geometric": {
            **_budget(geo),
            "model": model.kind,
            "parameters": model.size,
            "ranking": geo.ranking(args.top),
            "not_assembling": list(geo.not_assembling),
        },
    }
    lines = [
        f"actuator errors: worst-case position {act.position_worst:.4g} m, RMS "
        f"{act.position_rms:.4g} m; rotation {act.orientation_worst:.4g} rad worst-case",
        f"geometric tolerances ({model.kind}, {model.size} parameters): worst-case position "
        f"{geo.position_worst:.4g} m, RMS {geo.position_rms:.4g} m",
        "largest contributions (share of the position variance):",
    ]
    lines += [
        f"  {r['name']}: {r['position_rms']:.3g} m RMS ({100 * r['share']:.1f} %)"
        for r in geo.ranking(args.top)
    ]
    if args.samples:
        mc = monte_carlo(robot, q, model, tol, args.samples, args.distribution, args.seed)
        payload["monte_carlo"] = {
            "samples": int(len(mc.errors)),
            "failed": mc.failed,
            "rms": [float(v) for v in mc.rms],
            "position_rms": mc.position_rms,
            "position_max": mc.position_max,
            "orientation_rms": mc.orientation_rms,
        }
        lines.append(
            f"Monte Carlo ({len(mc.errors)} robots): position RMS {mc.position_rms:.4g} m "
            f"(first order {geo.position_rms:.4g} m), largest {mc.position_max:.4g} m"
        )
    emit(args, payload, "\n".join(lines))


def register(sub: Any) -> None:
    """Add this module's sub-commands to the ``pkdyn`` parser."""
    sp = robot_command(sub, "accuracy", "error budget: actuator resolution/backlash, tolerances")
    where = sp.add_mutually_exclusive_group(required=True)
    where.add_argument("--pose", nargs="+", type=float, help="X Y Z [ROLL PITCH YAW] (m, rad)")
    qa_argument(where)
    where.add_argument(
        "--map", choices=("xy", "xz", "yz"), help="map the position errors over a square grid"
    )
    sp.add_argument(
        "--resolution",
        nargs="+",
        type=float,
        default=[0.0],
        metavar="R",
        help="actuator resolution, one or per actuator (rad or m)",
    )
    sp.add_argument(
        "--backlash",
        nargs="+",
        type=float,
        default=[0.0],
        metavar="B",
        help="actuator backlash, one or per actuator (rad or m)",
    )
    sp.add_argument(
        "--tolerance",
        nargs="+",
        type=float,
        default=[5e-5, 5e-4],
        metavar="T",
        help="geometric tolerance: LENGTH [ANGLE [GAIN]] (m, rad, -; default 5e-5 m, 5e-4 rad; "
        "ANGLE defaults to LENGTH / the robot's size)",
    )
    sp.add_argument(
        "--model",
        default="auto",
        choices=("auto", "placements", "shortcuts", "family"),
        help="geometric parameters (default: family shortcuts when the family has them)",
    )
    sp.add_argument("--distribution", default="uniform", choices=("uniform", "normal"))
    sp.add_argument("--samples", type=int, default=0, help="Monte Carlo robots (default 0: off)")
    sp.add_argument("--seed", type=int, default=0)
    sp.add_argument("--top", type=int, default=10, help="ranked tolerances shown (10)")
    sp.add_argument("--center", nargs=3, type=float, metavar=("X", "Y", "Z"), help="map centre")
    sp.add_argument("--extent", type=float, help="map half-width [m] (default 0.2 x size)")
    sp.add_argument("--grid", type=int, default=15, help="map samples per side (15)")
    sp.add_argument(
        "--field",
        default="actuator_worst",
        choices=("actuator_worst", "actuator_rms", "geometric_worst", "geometric_rms"),
        help="field plotted",
    )
    sp.add_argument("--plot", help="save the map's plot (png, pdf, svg...)")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_accuracy)
