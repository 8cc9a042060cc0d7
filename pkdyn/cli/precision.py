"""The precision commands: ``stiffness`` and ``modes`` (:mod:`pkdyn.precision`).

At one configuration (``--pose``, ``--qa`` or ``--readings``) or over a plane of the workspace
(``--map PLANE`` with ``--center``, ``--extent``, ``--grid``: the map convention shared with
``accuracy --map``; ``--plot FILE``, ``--csv FILE``). The commands only call the results'
``table()``, ``to_json()``, ``plot()`` and ``write_csv()``.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import numpy as np

from pkdyn.cli._common import (
    check_worker_options,
    emit,
    integer,
    load,
    number,
    qa_argument,
    robot_command,
    worker_options,
)
from pkdyn.cli._paths import output_option
from pkdyn.cli._spelling import spelled_option
from pkdyn.exceptions import InvalidInputError

__all__ = [
    "check_map_options",
    "check_worker_options",
    "map_options",
    "posed_or_map",
    "register",
    "worker_options",
    "write_map",
]


def _options(sp: argparse.ArgumentParser) -> None:
    sp.add_argument(
        "--actuator-stiffness",
        nargs="+",
        type=number,
        metavar="K",
        help="joint-side actuator stiffness, one or one per actuator [N m/rad or N/m] "
        "(inf: rigid; default: the description's <pkdyn:stiffness>)",
    )
    sp.add_argument(
        "--material",
        help="model the slender links the description leaves undescribed as beams of this "
        "material (steel, aluminium, carbon); the description's own materials apply without it",
    )
    sp.add_argument(
        "--rigid-links", action="store_true", help="ignore the links' described compliance"
    )
    sp.add_argument(
        "--shear",
        choices=("on", "off"),
        default="on",
        help="the beams' shear deflection (Timoshenko, default on; off: Euler-Bernoulli)",
    )
    sp.add_argument(
        "--point",
        nargs=3,
        type=number,
        metavar=("X", "Y", "Z"),
        help="reference point in the platform frame [m] (default: its origin)",
    )


def map_options(sp: argparse.ArgumentParser, grid: int, fields: tuple[str, ...]) -> None:
    """``--center``, ``--extent``, ``--grid``, ``--plot``, ``--csv``, ``--field`` of ``--map``.

    Args:
        sp: The sub-command's parser (it has ``--map PLANE``).
        grid: Default points per axis.
        fields: The fields ``--field`` may name (the first is plotted by default).

    """
    sp.add_argument(
        "--center",
        nargs=3,
        type=number,
        metavar=("X", "Y", "Z"),
        help="a position of the map's plane [m] (default: the home pose's)",
    )
    sp.add_argument(
        "--extent",
        type=number,
        metavar="E",
        help="half-width of the map about the centre [m] (default: the workspace's box)",
    )
    sp.add_argument("--grid", type=integer, default=grid, help=f"map points per axis ({grid})")
    output_option(
        sp, "--plot", figure=True, metavar="FILE", help="save the map's plot (png, pdf, svg...)"
    )
    output_option(sp, "--csv", metavar="FILE", help="save the map's cells as CSV")
    sp.add_argument(
        "--field",
        choices=fields,
        default=None,
        help=f"field plotted (default: {fields[0]})",
    )
    worker_options(sp, "the general path's poses and the Monte Carlo's robots")


def posed_or_map(
    sub: Any, name: str, help_: str, grid: int, fields: tuple[str, ...], what: str
) -> Any:
    """A sub-command at one configuration (``--pose``, ``--qa``, ``--readings``) or over a map.

    Args:
        sub: The sub-parsers.
        name: The command.
        help_: Its one line.
        grid: Default map points per axis.
        fields: The map's fields (``--field``).
        what: What the map shows (``--map``'s help).

    Returns:
        The parser, with ``--json`` and the map options (:func:`map_options`).

    """
    sp = robot_command(sub, name, help_)
    where = sp.add_mutually_exclusive_group(required=True)
    where.add_argument("--pose", nargs="+", type=number, help="X Y Z [ROLL PITCH YAW] (m, rad)")
    qa_argument(where)
    where.add_argument(
        "--map",
        choices=("xy", "xz", "yz"),
        help=f"map {what} over a plane of the workspace (with --center, --extent, --grid)",
    )
    sp.add_argument("--json", action="store_true")
    map_options(sp, grid, fields)
    return sp


def check_map_options(args: argparse.Namespace) -> None:
    """Options of ``--map`` checked before any work (one line each; the paths: the CLI's)."""
    check_worker_options(args)
    if args.map is None:
        for option, value in (
            ("--plot", args.plot),
            ("--csv", args.csv),
            ("--center", args.center),
            ("--extent", args.extent),
            ("--field", args.field),
        ):
            if value is not None:
                raise InvalidInputError(option, "belongs to a map: give --map xy|xz|yz")


def _shear(args: argparse.Namespace) -> bool:
    return bool(args.shear == "on")


def _needs_geometry(robot: Any, args: argparse.Namespace) -> bool:
    """Beams are read from the links' cylinders: a material given or described."""
    desc = robot.description
    return bool(
        args.material is not None
        or desc.material is not None
        or any(c.material is not None or c.inner_radius > 0.0 for c in desc.compliance)
        or getattr(args, "html", None) is not None
    )


def _robot(args: argparse.Namespace) -> Any:
    robot = load(args)
    if not args.rigid_links and _needs_geometry(robot, args):
        robot = load(args, geometry=True)  # the beams are read from the links' cylinders
    return robot


def _configuration(args: argparse.Namespace, robot: Any) -> np.ndarray:
    import pkdyn

    if args.qa is not None:
        return pkdyn.forward_geometry(robot, args.qa, check_limits=False).q
    return pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q


def _elastic(args: argparse.Namespace) -> tuple[Any, Any]:
    from pkdyn.precision import elastic_model

    robot = _robot(args)
    em = elastic_model(
        robot, args.actuator_stiffness, args.material, not args.rigid_links, _shear(args)
    )
    _material_note(args, em)
    return robot, em


def _material_note(args: argparse.Namespace, em: Any) -> None:
    """One line on stderr: which links ``--material`` turned into beams (the undescribed)."""
    if args.material is None or args.json:
        return
    links = em.material_links
    if links:
        text = f"--material {args.material} applies to the links the description leaves "
        text += f"undescribed: {', '.join(links)}"
    else:
        text = f"--material {args.material} is not used: the description gives every slender "
        text += "link its own material or compliance"
    print(f"pkdyn: note: {text}", file=sys.stderr)


def _map(args: argparse.Namespace, frequency: bool) -> None:
    from pkdyn.precision.maps import precision_map

    robot = _robot(args)
    if args.actuator_stiffness is None and any(a.stiffness is None for a in robot.actuators):
        from pkdyn.precision import actuator_stiffness

        actuator_stiffness(robot, None)  # (the one line naming the actuator)
    result = precision_map(
        robot,
        args.map,
        center=args.center,
        extent=args.extent,
        samples=args.grid,
        actuator_stiffness=args.actuator_stiffness,
        material=args.material,
        links=not args.rigid_links,
        point=args.point,
        wrench=getattr(args, "wrench", None),
        frequency=frequency,
        workers=args.workers,
        scheduler=args.scheduler,
        timeout=args.timeout,
    )
    write_map(args, result, "f1" if frequency else "stiffness_min")


def write_map(args: argparse.Namespace, result: Any, default_field: str) -> None:
    """``--csv``, ``--plot`` (when some cell was evaluated), then the table or JSON."""
    if args.csv:
        result.write_csv(args.csv)
    text = result.table()
    if args.plot:
        if result.evaluated.any():
            result.plot(args.plot, field=args.field or default_field)
            text += f"\nplot: {args.plot}"
        else:
            text += f"\nno plot written to {args.plot}: no cell was evaluated"
    if args.csv:
        text += f"\ncells: {args.csv}"
    emit(args, result.to_json(), text)


def _cmd_stiffness(args: argparse.Namespace) -> None:
    from pkdyn.precision import stiffness

    check_map_options(args)
    if args.map is not None:
        if args.loaded:
            raise InvalidInputError("--loaded", "maps give the unloaded stiffness: leave it out")
        _map(args, frequency=False)
        return
    robot, em = _elastic(args)
    q = _configuration(args, robot)
    S = stiffness(em, q, point=args.point, wrench=args.wrench, loaded=args.loaded)
    emit(args, S.to_json(), S.table())


def _cmd_modes(args: argparse.Namespace) -> None:
    from pkdyn.precision.modes import modes

    check_map_options(args)
    if args.top is not None and args.top < 1:
        raise InvalidInputError("--top", f"{args.top}: give 1 or more")
    if args.mode < 1:
        raise InvalidInputError(
            "--mode", f"{args.mode} is not a mode number: they count from 1 (the lowest)"
        )
    if args.map is not None:
        for option, value in (("--html", args.html), ("--gravity", args.gravity or None)):
            if value is not None:
                raise InvalidInputError(option, "applies at one configuration, not to --map")
        _map(args, frequency=True)
        return
    robot, em = _elastic(args)
    q = _configuration(args, robot)
    result = modes(em, q, point=args.point, gravity=args.gravity)
    result.top = args.top
    out = result.to_json()
    text = result.table()
    if args.html is not None:
        from pkdyn.viewer import animate_mode

        if result.rigid:
            raise InvalidInputError("--html", "the robot is rigid here: there is no mode to show")
        scene = animate_mode(em, result, args.mode - 1)
        try:
            path = scene.save_html(args.html)
        finally:
            scene.close()
        f = result.frequencies[args.mode - 1]
        text += f"\nwrote {path}: mode {args.mode} ({f:.5g} Hz)"
        out["html"] = str(path)
    emit(args, out, text)


def register(sub: Any) -> None:
    """Add ``stiffness`` and ``modes`` to the ``pkdyn`` parser."""
    sp = posed_or_map(
        sub,
        "stiffness",
        "stiffness, compliance and deflection at a configuration or over a map (VJM)",
        31,
        ("stiffness_min", "deflection"),
        "the smallest stiffness (and the deflection)",
    )
    _options(sp)
    sp.add_argument(
        "--wrench",
        nargs="+",
        type=number,
        metavar="F",
        help="tool wrench: fx fy fz mx my mz [N, N m] (world axes, moment about the point) or "
        "the task components; its deflection is reported (a field of --map)",
    )
    sp.add_argument(
        "--loaded",
        action="store_true",
        help="solve the equilibrium under the wrench and add its geometric stiffness",
    )
    sp.set_defaults(func=_cmd_stiffness)
    sp = posed_or_map(
        sub,
        "modes",
        "natural frequencies and mode shapes at a configuration or over a map",
        21,
        ("f1", "stiffness_min"),
        "the lowest frequency",
    )
    _options(sp)
    spelled_option(
        sp,
        "--top",
        deprecated=("--count",),
        type=integer,
        default=None,
        metavar="N",
        help="report the lowest N modes",
    )
    sp.add_argument("--gravity", action="store_true", help="about the equilibrium under gravity")
    output_option(sp, "--html", metavar="FILE", help="write an animation of a mode (meshcat HTML)")
    sp.add_argument("--mode", type=integer, default=1, help="mode to animate, 1 = lowest (--html)")
    sp.set_defaults(func=_cmd_modes)
