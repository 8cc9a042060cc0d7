"""``pkdyn accuracy``: error budget of the platform pose (actuator and geometric errors).

At one configuration: :func:`pkdyn.precision.accuracy.accuracy_budget` (it names the values it
assumed when none was given); over a plane (``--map PLANE`` with ``--center``, ``--extent``,
``--grid``, the map convention of ``stiffness --map`` and ``modes --map``):
:func:`pkdyn.precision.accuracy_maps.accuracy_map`. The command only calls the results'
``table()``, ``to_json()``, ``plot()`` and ``write_csv()``.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from pkdyn.cli._common import emit, integer, load, number
from pkdyn.cli.precision import check_map_options, posed_or_map, write_map

__all__ = ["register"]

_FIELDS = ("actuator_worst", "actuator_rms", "geometric_worst", "geometric_rms")


def _tolerances(args: argparse.Namespace, robot: Any, model: Any) -> np.ndarray | None:
    """Tolerances per parameter from ``--tolerance LENGTH [ANGLE [GAIN]]`` (``None``: not given)."""
    if args.tolerance is None:
        return None
    length = args.tolerance[0]
    angle = args.tolerance[1] if len(args.tolerance) > 1 else length / robot.length_scale
    gain = args.tolerance[2] if len(args.tolerance) > 2 else 0.0
    return np.asarray(model.tolerances(length, angle, gain))


def _cmd_accuracy(args: argparse.Namespace) -> None:
    import pkdyn
    from pkdyn.exceptions import InvalidInputError
    from pkdyn.inputs import count, seed
    from pkdyn.precision.accuracy import DEFAULT_TOLERANCE, accuracy_budget, accuracy_map
    from pkdyn.precision.parameters import parameter_model

    check_map_options(args)
    count("--top", args.top, 0)
    seed("--seed", args.seed)
    if args.plot and args.map is None:
        raise InvalidInputError("--plot", "plots a map: give --map xy|xz|yz")
    if args.tolerance is not None and not 1 <= len(args.tolerance) <= 3:
        raise InvalidInputError("--tolerance", "give LENGTH [ANGLE [GAIN]] >= 0 (m, rad, -)")
    from pkdyn.inputs import vector

    tolerance = None if args.tolerance is None else vector("--tolerance", args.tolerance, (1, 2, 3))
    if tolerance is not None and np.any(tolerance < 0.0):
        raise InvalidInputError("--tolerance", "give LENGTH [ANGLE [GAIN]] >= 0 (m, rad, -)")
    robot = load(args)
    model = parameter_model(robot, args.model)
    tol = _tolerances(args, robot, model)
    if args.map is not None:
        if tol is None:
            tol = model.tolerances(*DEFAULT_TOLERANCE)
        amap = accuracy_map(
            robot,
            args.map,
            center=args.center,
            extent=args.extent,
            samples=args.grid,
            resolution=0.0 if args.resolution is None else args.resolution,
            backlash=0.0 if args.backlash is None else args.backlash,
            model=model,
            tolerance=tol,
            distribution=args.distribution,
        )
        write_map(args, amap, "actuator_worst")
        return
    if args.qa is not None:
        q = pkdyn.forward_geometry(robot, args.qa, check_limits=False).q
    else:
        q = pkdyn.inverse_geometry(robot, args.pose, check_limits=False).q
    result = accuracy_budget(
        robot,
        q,
        model,
        args.resolution,
        args.backlash,
        tol,
        args.distribution,
        args.samples,
        args.seed,
        args.top,
        workers=args.workers,
        scheduler=args.scheduler,
        timeout=args.timeout,
    )
    emit(args, result.to_json(), result.table())


def register(sub: Any) -> None:
    """Add this module's sub-commands to the ``pkdyn`` parser."""
    sp = posed_or_map(
        sub,
        "accuracy",
        "error budget: actuator resolution/backlash, tolerances",
        15,
        _FIELDS,
        "the position errors",
    )
    sp.add_argument(
        "--resolution",
        nargs="+",
        type=number,
        default=None,
        metavar="R",
        help="actuator resolution, one or per actuator (rad or m; default 0, named)",
    )
    sp.add_argument(
        "--backlash",
        nargs="+",
        type=number,
        default=None,
        metavar="B",
        help="actuator backlash, one or per actuator (rad or m; default 0, named)",
    )
    sp.add_argument(
        "--tolerance",
        nargs="+",
        type=number,
        default=None,
        metavar="T",
        help="geometric tolerance: LENGTH [ANGLE [GAIN]] (m, rad, -; default 5e-5 m, 5e-4 rad, "
        "named in the output; ANGLE defaults to LENGTH / the robot's size when only LENGTH is "
        "given)",
    )
    sp.add_argument(
        "--model",
        default="auto",
        choices=("auto", "placements", "shortcuts", "family"),
        help="geometric parameters (default: family shortcuts when the family has them)",
    )
    sp.add_argument("--distribution", default="uniform", choices=("uniform", "normal"))
    sp.add_argument(
        "--samples", type=integer, default=0, help="Monte Carlo robots (default 0: off)"
    )
    sp.add_argument("--seed", type=integer, default=0)
    sp.add_argument("--top", type=integer, default=10, help="ranked tolerances shown (10)")
    sp.set_defaults(func=_cmd_accuracy)
