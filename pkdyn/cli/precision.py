"""The precision commands: ``stiffness`` and ``modes`` (:mod:`pkdyn.precision`)."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from pkdyn.cli._common import configuration, emit, integer, load, number, posed_command
from pkdyn.cli._paths import output_option
from pkdyn.exceptions import InvalidInputError

__all__ = ["register"]


def _options(sp: argparse.ArgumentParser) -> None:
    sp.add_argument(
        "--actuator-stiffness",
        nargs="+",
        type=number,
        metavar="K",
        help="joint-side actuator stiffness, one or one per actuator [N m/rad or N/m] "
        "(default: the description's <pkdyn:stiffness>)",
    )
    sp.add_argument(
        "--material",
        help="model the slender links as beams of this material (steel, aluminium, carbon)",
    )
    sp.add_argument(
        "--rigid-links", action="store_true", help="ignore the links' described compliance"
    )
    sp.add_argument(
        "--point",
        nargs=3,
        type=number,
        metavar=("X", "Y", "Z"),
        help="reference point in the platform frame [m] (default: its origin)",
    )


def _elastic(args: argparse.Namespace) -> tuple[Any, Any, np.ndarray]:
    from pkdyn.precision import elastic_model

    robot, q = _posed(args)
    em = elastic_model(robot, args.actuator_stiffness, args.material, not args.rigid_links)
    return robot, em, q


def _posed(args: argparse.Namespace) -> tuple[Any, np.ndarray]:
    if args.material is None and getattr(args, "html", None) is None:
        return configuration(args)
    import pkdyn

    robot = load(args, geometry=True)  # beams are read from the links' cylinders; the view
    if args.qa is not None:
        return robot, pkdyn.forward_geometry(robot, args.qa, check_limits=False).q
    return robot, pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q


def _cmd_stiffness(args: argparse.Namespace) -> None:
    from pkdyn.precision import stiffness

    robot, em, q = _elastic(args)
    S = stiffness(em, q, point=args.point, wrench=args.wrench, loaded=args.loaded)
    out = S.to_json()
    out["actuators"] = robot.actuator_names
    out["actuator_stiffness"] = [float(k) for k in em.actuator_stiffness]
    out["links"] = [lc.link for lc in em.links]
    lines = [f"K ({' '.join(S.task)}) =", np.array2string(S.K, precision=5)]
    if S.translation is not None:
        k = ", ".join(f"{x:.5g}" for x in S.translation.stiffness)
        lines.append(f"principal translational stiffness [N/m]: {k}")
    if S.rotation is not None:
        k = ", ".join(f"{x:.5g}" for x in S.rotation.stiffness)
        lines.append(f"principal rotational stiffness [N m/rad]: {k}")
    if S.internal:
        lines.append(f"internal mobilities without stiffness: {S.internal}")
    if S.deflection is not None:
        d = S.deflection
        lines.append(
            f"deflection: {np.array2string(d[:3] * 1e6, precision=3)} um, "
            f"{np.array2string(d[3:] * 1e6, precision=3)} urad"
        )
    emit(args, out, "\n".join(lines))


def _cmd_modes(args: argparse.Namespace) -> None:
    from pkdyn.precision.modes import modes

    if args.count is not None and args.count < 1:
        raise InvalidInputError("--count", f"{args.count}: give 1 or more")
    robot, em, q = _elastic(args)
    result = modes(em, q, point=args.point, gravity=args.gravity)
    out = result.to_json(args.count)
    out["links"] = [lc.link for lc in em.links]
    f = result.frequencies[: args.count]
    lines = [f"natural frequencies [Hz]: {', '.join(f'{x:.5g}' for x in f)}"]
    if result.internal:
        lines.append(f"internal mobilities without stiffness (not modes): {result.internal}")
    if args.html is not None:
        from pkdyn.viewer import animate_mode

        scene = animate_mode(em, result, args.mode - 1)
        try:
            path = scene.save_html(args.html)
        finally:
            scene.close()
        lines.append(f"wrote {path}: mode {args.mode} ({result.frequencies[args.mode - 1]:.5g} Hz)")
        out["html"] = str(path)
    emit(args, out, "\n".join(lines))


def register(sub: Any) -> None:
    """Add ``stiffness`` and ``modes`` to the ``pkdyn`` parser."""
    sp = posed_command(
        sub, "stiffness", "stiffness, compliance and deflection at a configuration (VJM)"
    )
    _options(sp)
    sp.add_argument(
        "--wrench",
        nargs="+",
        type=number,
        metavar="F",
        help="tool wrench: fx fy fz mx my mz [N, N m] (world axes, moment about the point) or "
        "the task components; its deflection is reported",
    )
    sp.add_argument(
        "--loaded",
        action="store_true",
        help="solve the equilibrium under the wrench and add its geometric stiffness",
    )
    sp.set_defaults(func=_cmd_stiffness)
    sp = posed_command(sub, "modes", "natural frequencies and mode shapes at a configuration")
    _options(sp)
    sp.add_argument("--count", type=integer, default=None, help="report the lowest COUNT modes")
    sp.add_argument("--gravity", action="store_true", help="about the equilibrium under gravity")
    output_option(sp, "--html", metavar="FILE", help="write an animation of a mode (meshcat HTML)")
    sp.add_argument("--mode", type=integer, default=1, help="mode to animate, 1 = lowest (--html)")
    sp.set_defaults(func=_cmd_modes)
