"""Dynamics commands: ``simulate`` (passive dynamics), ``size`` (sizing, motors, fastest cycle)."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from pkdyn.cli._common import emit, integer, load, number, robot_command
from pkdyn.cli._paths import input_option, output_option
from pkdyn.cli._spelling import spelled_option
from pkdyn.exceptions import InvalidInputError, LimitsExceededError
from pkdyn.inputs import non_negative

__all__ = ["register"]


def _initial_velocity(robot: Any, v0: list[float] | None) -> np.ndarray | None:
    """``--v0``: the actuators' rates (n_a values) or every velocity coordinate (nv values)."""
    if v0 is None:
        return None
    from pkdyn.inputs import vector

    n_a, nv = len(robot.actuators), robot.nv
    v = vector("--v0", v0, (n_a, nv), "rad/s or m/s")
    if v.size == nv and nv != n_a:
        return v
    from pkdyn.analysis.kinematics import joint_velocities

    return joint_velocities(robot, robot.q_home, v)  # passive rates from the closures


def _constant_effort(robot: Any, torque: list[float] | None) -> Any:
    """``--torque``: constant joint-side efforts of the actuators [N m or N]."""
    if torque is None:
        return None
    from pkdyn.inputs import vector

    tau = vector("--torque", torque, len(robot.actuators), "N m or N")
    return lambda t, q, v: tau


def _cmd_simulate(args: argparse.Namespace) -> None:
    from pkdyn.dynamics import simulate

    robot = load(args, geometry=args.html is not None)
    res = simulate(
        robot,
        args.duration,
        args.dt,
        v0=_initial_velocity(robot, args.v0),
        torque=_constant_effort(robot, args.torque),
        integrator=args.integrator,
        step=args.step,
    )
    if args.csv:
        from pkdyn.dynamics.simulation_output import write_simulation_csv

        write_simulation_csv(robot, res, args.csv)
    if args.plot:
        res.plot(args.plot)
    if args.html:
        from pkdyn.viewer import Scene

        scene = Scene(robot, res.q[0])
        try:
            scene.animate(res.t, res.q)
            scene.save_html(args.html)
        finally:
            scene.close()
    emit(args, res)


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


def _check_settle(args: argparse.Namespace) -> None:
    """The settling options of ``size --fastest --band``, refused where they do not apply."""
    if args.band is None:
        for option, given in (
            ("--dwell", args.dwell is not None),
            ("--actuator-stiffness", args.actuator_stiffness is not None),
            ("--damping-ratio", args.damping_ratio is not None),
            ("--material", args.material is not None),
            ("--shaper", args.shaper is not None),
        ):
            if given:
                raise InvalidInputError(option, "applies with --fastest --band BAND")
        return
    if not args.fastest:
        raise InvalidInputError("--band", "needs --fastest (the fastest cycle that settles)")
    if not args.band > 0.0:
        raise InvalidInputError("--band", f"a band must be > 0 m, got {args.band:g}")
    if args.dwell is not None and not args.dwell > 0.0:
        raise InvalidInputError("--dwell", f"must be > 0 s, got {args.dwell:g}")


def _cmd_size(args: argparse.Namespace) -> None:
    from pkdyn.dynamics.sizing import size, sizing_from_efforts
    from pkdyn.dynamics.trajectory import named_task, named_trajectory

    catalog = None
    if args.catalog:  # read (and refused) before any work
        from pkdyn.dynamics.motors import load_catalog

        catalog = load_catalog(args.catalog)
        if args.gearboxes:
            catalog = catalog + load_catalog(args.gearboxes)
    elif args.gearboxes:
        raise InvalidInputError("--gearboxes", "needs --catalog (the motors to pair them with)")
    _check_settle(args)
    robot = load(args, geometry=args.material is not None)
    non_negative("--payload", args.payload, "kg")
    if args.top < 0:
        raise InvalidInputError("--top", f"must be >= 0, got {args.top}")
    if args.operating_points and not args.catalog:
        raise InvalidInputError("--operating-points", "needs --catalog (the motors to plot)")
    fast = None
    settled = None
    from_file = _trajectory_file(args, robot)
    if args.fastest:
        from pkdyn.dynamics.fastest import fastest_trajectory

        task = from_file or named_task(robot, args.trajectory, **_fastest_options(args))
        fast = fastest_trajectory(robot, task, payload=args.payload)
        traj = fast.trajectory
        result = sizing_from_efforts(robot, fast.efforts, args.payload)
        if args.band is not None:
            from pkdyn.precision.vibration_fastest import fastest_settling

            settled = fastest_settling(
                robot,
                task,
                args.band,
                0.5 if args.dwell is None else args.dwell,
                payload=args.payload,
                actuator_stiffness=args.actuator_stiffness,
                material=args.material,
                damping_ratio=args.damping_ratio,
                shaper={None: "zv", "none": None}.get(args.shaper, args.shaper),
                fast=fast,
            )
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
        selection.plot(args.operating_points)
    if args.csv:
        result.write_csv(args.csv)
    if args.plot:
        result.plot(args.plot)
    payload = result.to_json()
    text = [result.table()]
    if args.no_passive:  # the same without the springs, dampers and friction
        bare = size(robot, traj, payload=args.payload, passive=False)
        payload["without_passive"] = bare.to_json()
        what = "without" if robot.passive is not None else "(the robot has none) without"
        text = [
            "with passive elements:",
            result.table(),
            f"{what} passive elements:",
            bare.table(),
        ]
    if fast is not None:
        payload["fastest"] = fast.to_json()
        text.insert(0, fast.table())
    if settled is not None:
        payload["settling"] = settled.to_json()
        text.insert(1, settled.table())
    if selection is not None:
        payload["selection"] = selection.to_json()
        text.append(selection.table(top=args.top))
    emit(args, payload, "\n".join(text))
    if not result.feasible:  # the report stands; the exit status and one line say no
        raise LimitsExceededError(
            f"{robot.name} on {result.trajectory} with {args.payload:g} kg",
            result.exceeded,
            "see the margins above (a longer cycle or a lighter payload)",
        )


def register(sub: Any) -> None:
    """Add ``simulate`` and ``size`` to the ``pkdyn`` parser."""
    sp = robot_command(
        sub,
        "simulate",
        "constrained dynamics under gravity, from rest or --v0, free or under a --torque",
    )
    sp.add_argument("--duration", type=number, default=1.0, help="simulated time [s]")
    sp.add_argument("--dt", type=number, default=1e-3, help="output time step [s]")
    sp.add_argument(
        "--v0",
        nargs="+",
        type=number,
        metavar="V",
        help="initial velocity: the actuators' rates in actuator order (rad/s or m/s; the "
        "passive joints follow the closures) or every velocity coordinate (nv values); "
        "default: at rest",
    )
    sp.add_argument(
        "--torque",
        nargs="+",
        type=number,
        metavar="T",
        help="constant actuator efforts, joint side, in actuator order (N m or N); default: "
        "free actuators",
    )
    sp.add_argument("--integrator", choices=("dopri5", "rk4", "euler"), default="dopri5")
    sp.add_argument(
        "--step", type=number, default=None, help="integration step [s] (default: --dt)"
    )
    output_option(
        sp,
        "--csv",
        metavar="FILE",
        help="write the time series (t, qa_, qa_dot_, tau_, energies, closure_residual)",
    )
    output_option(
        sp,
        "--plot",
        figure=True,
        metavar="FILE.png",
        help="plot actuators, energies, closures vs time",
    )
    output_option(sp, "--html", metavar="FILE", help="save a meshcat animation (static HTML)")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_simulate)
    sp = robot_command(sub, "size", "actuator efforts, speeds and powers along a trajectory")
    input_option(
        sp,
        "--trajectory",
        or_name=True,
        default="adept",
        metavar="NAME|FILE.csv",
        help="adept, sine, p2p, or a CSV file: a column t [s] and qa_<actuator> columns "
        "(actuator space) or the controlled pose components among x y z roll pitch yaw",
    )
    sp.add_argument("--payload", type=number, default=0.0, help="payload mass [kg]")
    sp.add_argument(
        "--cycle-time",
        type=number,
        default=None,
        help="adept: cycle time; sine: period; p2p: move duration [s]",
    )
    sp.add_argument("--cycles", type=integer, default=1, help="number of cycles (adept, sine)")
    sp.add_argument("--profile", choices=("quintic", "jerk"), default="quintic")
    sp.add_argument("--dt", type=number, default=1e-3, help="sample period [s]")
    output_option(
        sp, "--csv", metavar="FILE", help="write the time series (t, qa_, qa_dot_, tau_, energy)"
    )
    output_option(
        sp, "--plot", figure=True, metavar="FILE.png", help="plot effort, speed, power vs time"
    )
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
    settle = sp.add_argument_group(
        "settling (with --fastest): the fastest cycle whose tool settles, with and without "
        "input shaping (the elastic model: pkdyn vibration)"
    )
    spelled_option(
        settle,
        "--band",
        deprecated=("--settle",),
        type=number,
        metavar="BAND",
        help="settling band on the tool's deviation [m]: the fastest cycle that settles in it",
    )
    settle.add_argument(
        "--dwell", type=number, help="time after the motion within which to settle [s] (0.5)"
    )
    settle.add_argument(
        "--actuator-stiffness",
        nargs="+",
        type=number,
        metavar="K",
        help="servo stiffness, one or one per actuator [N m/rad or N/m] (default: described)",
    )
    settle.add_argument(
        "--damping-ratio", type=number, help="damping ratio of the first mode (0.02)"
    )
    settle.add_argument("--material", help="link material (steel, aluminium, carbon)")
    settle.add_argument(
        "--shaper",
        choices=("zv", "zvd", "none"),
        help="input shaper compared with the unshaped motion (default zv)",
    )
    input_option(
        sp,
        "--catalog",
        or_name=True,
        metavar="FILE",
        help="motor (and gearbox) catalog, YAML or CSV, or 'example': select motors",
    )
    input_option(
        sp,
        "--gearboxes",
        or_name=True,
        metavar="FILE",
        help="gearbox catalog (YAML, CSV, 'example')",
    )
    sp.add_argument(
        "--criterion",
        choices=("rated_torque", "mass", "price"),
        default="rated_torque",
        help="ranking of the feasible motor x gearbox pairs (smallest first)",
    )
    spelled_option(
        sp,
        "--top",
        deprecated=("--show",),
        type=integer,
        default=5,
        help="pairs listed per actuator (5)",
    )
    output_option(
        sp,
        "--operating-points",
        figure=True,
        metavar="FILE.png",
        help="plot the chosen motors' operating points over their envelopes (with --catalog)",
    )
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_size)
