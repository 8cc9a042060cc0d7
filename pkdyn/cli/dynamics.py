"""Dynamics commands: ``simulate`` (passive dynamics), ``size`` (sizing, motors, fastest cycle)."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from pkdyn.cli._common import emit, load, output_path, robot_command
from pkdyn.exceptions import InvalidInputError, LimitsExceededError
from pkdyn.inputs import non_negative

__all__ = ["register"]


def _cmd_simulate(args: argparse.Namespace) -> None:
    from pkdyn.dynamics import simulate

    output_path("--csv", args.csv)
    output_path("--plot", args.plot, figure=True)
    output_path("--html", args.html)
    robot = load(args, geometry=args.html is not None)
    res = simulate(robot, args.duration, args.dt, integrator=args.integrator, step=args.step)
    if args.csv:
        from pkdyn.dynamics.simulation_output import write_simulation_csv

        write_simulation_csv(robot, res, args.csv)
    if args.plot:
        from pkdyn.plotting.dynamics import plot_simulation

        plot_simulation(robot, res, path=args.plot)
    if args.html:
        from pkdyn.viewer import Scene

        scene = Scene(robot, res.q[0])
        try:
            scene.animate(res.t, res.q)
            scene.save_html(args.html)
        finally:
            scene.close()
    payload = {
        "robot": robot.name,
        "duration": float(res.t[-1] - res.t[0]),
        "dt": args.dt,
        "integrator": args.integrator,
        "steps": int(res.t.size - 1),
        "substeps": int(res.extras.get("substeps", res.t.size - 1)),
        "max_closure_residual": float(np.max(res.closure_residual)),
        "energy_drift_rel": res.energy_drift(),
        "max_kinetic_energy": float(np.max(res.kinetic)),
        "projections": int(res.projections),
        "singular_passages": [ev.to_json() for ev in res.events],
        "valid_until": float(res.valid_until),
        "energy_drift_rel_valid": res.energy_drift(res.valid_until),
    }
    text = (
        f"{robot.name}: {payload['duration']:g} s passive under gravity, {payload['steps']} steps "
        f"of {args.dt:g} s ({args.integrator}, {payload['substeps']} substeps)\n"
        f"max closure residual: {payload['max_closure_residual']:.3g} m\n"
        f"energy drift:         {payload['energy_drift_rel']:.3g} (relative to the largest "
        f"kinetic energy, {payload['max_kinetic_energy']:.4g} J)"
    )
    for ev in res.events:
        text += f"\nsingular passage:     {ev.describe()}"
    if res.events and res.valid_until < res.t[-1]:
        text += (
            f"\nexact rigid motion up to t = {res.valid_until:.6g} s (the first passage "
            "through a singularity); energy drift up to there: "
            f"{payload['energy_drift_rel_valid']:.3g}"
        )
    emit(args, payload, text)


def _trajectory_options(args: argparse.Namespace) -> dict[str, Any]:
    if args.cycle_time is not None and args.cycle_time <= 0.0:
        raise InvalidInputError("--cycle-time", f"must be > 0 s, got {args.cycle_time}")
    if args.cycles < 1:
        raise InvalidInputError("--cycles", f"must be a whole number >= 1, got {args.cycles}")
    opts: dict[str, Any] = {"dt": args.dt}
    if args.trajectory == "adept":
        opts["cycle_time"] = 0.5 if args.cycle_time is None else args.cycle_time
        opts["profile"] = args.profile
        opts["cycles"] = args.cycles
    elif args.trajectory == "sine":
        if args.cycle_time is not None:
            opts["frequency"] = 1.0 / args.cycle_time
            opts["duration"] = args.cycle_time * args.cycles
    else:  # p2p
        opts["profile"] = args.profile
        if args.cycle_time is not None:
            opts["duration"] = args.cycle_time
    return opts


def _trajectory_file(args: argparse.Namespace, robot: Any) -> Any:
    """The task trajectory of ``--trajectory FILE.csv``, or ``None`` for a named one."""
    from pkdyn.dynamics.trajectory import TRAJECTORIES

    if args.trajectory in TRAJECTORIES:
        return None
    if not args.trajectory.lower().endswith(".csv"):
        from pkdyn.exceptions import close_match

        raise InvalidInputError(
            "--trajectory",
            f"'{args.trajectory}': one of {', '.join(TRAJECTORIES)} or a .csv file"
            + close_match(args.trajectory, list(TRAJECTORIES)),
        )
    for option, given in (
        ("--cycle-time", args.cycle_time is not None),
        ("--cycles", args.cycles != 1),
    ):
        if given:
            raise InvalidInputError(option, "does not apply to a trajectory read from a file")
    from pkdyn.dynamics.trajectory_file import read_task_csv

    return read_task_csv(robot, args.trajectory)


def _fastest_options(args: argparse.Namespace) -> dict[str, Any]:
    """The path's nominal parametrisation: ``cycle_time / dt`` samples (default 1 s)."""
    if args.cycles != 1:
        raise InvalidInputError(
            "--cycles", "--fastest traverses the path once (its time is the path parameter)"
        )
    opts = _trajectory_options(args)
    if args.trajectory == "adept":
        opts["cycle_time"] = 1.0 if args.cycle_time is None else args.cycle_time
        opts["cycles"] = 1
    from pkdyn.dynamics.fastest import MAX_PATH_SAMPLES

    length = args.cycle_time if args.cycle_time is not None else 1.0
    if args.dt > 0.0 and length / args.dt > MAX_PATH_SAMPLES:  # before building the path
        raise InvalidInputError(
            "--dt",
            f"{length:g} s of path every {args.dt:g} s is {length / args.dt:.3g} samples, more "
            f"than the {MAX_PATH_SAMPLES:,} --fastest accepts (each is mapped, then solved "
            "by toppra); a longer --dt",
        )
    return opts


def _cmd_size(args: argparse.Namespace) -> None:
    from pkdyn.dynamics.sizing import size, sizing_from_efforts
    from pkdyn.dynamics.trajectory import named_task, named_trajectory

    output_path("--csv", args.csv)
    output_path("--plot", args.plot, figure=True)
    output_path("--operating-points", args.operating_points, figure=True)
    catalog = None
    if args.catalog:  # read (and refused) before any work
        from pkdyn.dynamics.motors import load_catalog

        catalog = load_catalog(args.catalog)
        if args.gearboxes:
            catalog = catalog + load_catalog(args.gearboxes)
    elif args.gearboxes:
        raise InvalidInputError("--gearboxes", "needs --catalog (the motors to pair them with)")
    robot = load(args)
    non_negative("--payload", args.payload, "kg")
    if args.show < 0:
        raise InvalidInputError("--show", f"must be >= 0, got {args.show}")
    if args.operating_points and not args.catalog:
        raise InvalidInputError("--operating-points", "needs --catalog (the motors to plot)")
    fast = None
    from_file = _trajectory_file(args, robot)
    if args.fastest:
        from pkdyn.dynamics.fastest import fastest_trajectory

        task = from_file or named_task(robot, args.trajectory, **_fastest_options(args))
        fast = fastest_trajectory(robot, task, payload=args.payload)
        traj = fast.trajectory
        result = sizing_from_efforts(robot, fast.efforts, args.payload)
    else:
        # speeds are reported (their margins), not refused: a sizing answers how far off it is
        if from_file is not None:
            from pkdyn.dynamics.trajectory import map_task_trajectory

            traj = map_task_trajectory(robot, from_file, check_speeds=False)
        else:
            traj = named_trajectory(
                robot, args.trajectory, check_speeds=False, **_trajectory_options(args)
            )
        result = size(robot, traj, payload=args.payload)
    selection = None
    if catalog is not None:
        from pkdyn.dynamics.selection import select_drives

        selection = select_drives(
            robot,
            traj,
            catalog,
            payload=args.payload,
            criterion=args.criterion,
            efforts=result.efforts,
        )
    if args.operating_points and selection is not None:
        from pkdyn.plotting.motors import plot_operating_points

        plot_operating_points(selection, path=args.operating_points)
    if args.csv:
        result.write_csv(args.csv)
    if args.plot:
        from pkdyn.plotting.dynamics import plot_efforts

        plot_efforts(result, path=args.plot)
    head = (
        f"{robot.name}: {result.trajectory}, {result.duration:.4g} s, payload {args.payload:g} kg"
        + ("" if result.feasible else "  -- LIMITS EXCEEDED")
    )
    payload = result.as_json()
    text = [head, result.table()]
    if args.no_passive:  # the same without the springs, dampers and friction
        bare = size(robot, traj, payload=args.payload, passive=False)
        payload["without_passive"] = bare.as_json()
        what = "without" if robot.passive is not None else "(the robot has none) without"
        text = [
            head,
            "with passive elements:",
            result.table(),
            f"{what} passive elements:" + ("" if bare.feasible else "  -- LIMITS EXCEEDED"),
            bare.table(),
        ]
    if fast is not None:
        payload["fastest"] = fast.as_json()
        text.insert(
            0,
            f"fastest cycle: {fast.cycle_time:.4g} s (toppra on {traj.t.size} samples; a torque "
            f"or speed limit active on {100 * fast.active_fraction:.0f} % of them; inverse "
            f"dynamics along it: {100 * float(np.max(fast.torque_utilisation)):.3f} % of the "
            f"torque limit, {100 * float(np.max(fast.speed_utilisation)):.3f} % of the speed "
            "limit)",
        )
    if selection is not None:
        payload["selection"] = selection.as_json()
        text.append(selection.table(show=args.show))
    emit(args, payload, "\n".join(text))
    if not result.feasible:  # the report stands; the exit status and one line say no
        raise LimitsExceededError(
            f"{robot.name} on {result.trajectory} with {args.payload:g} kg",
            result.exceeded,
            "see the margins above (a longer cycle or a lighter payload)",
        )


def register(sub: Any) -> None:
    """Add ``simulate`` and ``size`` to the ``pkdyn`` parser."""
    sp = robot_command(sub, "simulate", "passive constrained dynamics under gravity")
    sp.add_argument("--duration", type=float, default=1.0, help="simulated time [s]")
    sp.add_argument("--dt", type=float, default=1e-3, help="output time step [s]")
    sp.add_argument("--integrator", choices=("dopri5", "rk4", "euler"), default="dopri5")
    sp.add_argument("--step", type=float, default=None, help="integration step [s] (default: --dt)")
    sp.add_argument(
        "--csv",
        metavar="FILE",
        help="write the time series (t, qa_, qa_dot_, tau_, energies, closure_residual)",
    )
    sp.add_argument("--plot", metavar="FILE.png", help="plot actuators, energies, closures vs time")
    sp.add_argument("--html", metavar="FILE", help="save a meshcat animation (static HTML)")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_simulate)
    sp = robot_command(sub, "size", "actuator efforts, speeds and powers along a trajectory")
    sp.add_argument(
        "--trajectory",
        default="adept",
        metavar="NAME|FILE.csv",
        help="adept, sine, p2p, or a CSV file: a column t [s] and qa_<actuator> columns "
        "(actuator space) or the controlled pose components among x y z roll pitch yaw",
    )
    sp.add_argument("--payload", type=float, default=0.0, help="payload mass [kg]")
    sp.add_argument(
        "--cycle-time",
        type=float,
        default=None,
        help="adept: cycle time; sine: period; p2p: move duration [s]",
    )
    sp.add_argument("--cycles", type=int, default=1, help="number of cycles (adept, sine)")
    sp.add_argument("--profile", choices=("quintic", "jerk"), default="quintic")
    sp.add_argument("--dt", type=float, default=1e-3, help="sample period [s]")
    sp.add_argument(
        "--csv", metavar="FILE", help="write the time series (t, qa_, qa_dot_, tau_, energy)"
    )
    sp.add_argument("--plot", metavar="FILE.png", help="plot effort, speed, power vs time")
    sp.add_argument(
        "--no-passive",
        action="store_true",
        help="also report the efforts without the robot's springs, dampers and friction",
    )
    sp.add_argument(
        "--fastest",
        action="store_true",
        help="traverse the trajectory's path as fast as the torque and speed limits allow "
        "(toppra); --cycle-time / --dt then set the path's sampling (default 1 s / 1 ms)",
    )
    sp.add_argument(
        "--catalog",
        metavar="FILE",
        help="motor (and gearbox) catalog, YAML or CSV, or 'example': select motors",
    )
    sp.add_argument("--gearboxes", metavar="FILE", help="gearbox catalog (YAML, CSV, 'example')")
    sp.add_argument(
        "--criterion",
        choices=("rated_torque", "mass", "price"),
        default="rated_torque",
        help="ranking of the feasible motor x gearbox pairs (smallest first)",
    )
    sp.add_argument("--show", type=int, default=5, help="pairs listed per actuator")
    sp.add_argument(
        "--operating-points",
        metavar="FILE.png",
        help="plot the chosen motors' operating points over their envelopes (with --catalog)",
    )
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_size)
