"""``pkdyn demo`` (``make demo``): the main job on built-in defaults.

Delta motor sizing on the Adept cycle, its fastest cycle (with and without the motors' rotor
inertia), then every library robot's geometric models.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

__all__ = ["register", "run_demo", "run_fastest_demo", "run_geometry_demo", "run_sizing_demo"]

CYCLE_TIMES = (0.4, 0.5, 0.6, 0.8)
PAYLOADS = (0.0, 0.5, 1.0, 2.0)
FASTEST_PAYLOADS = (0.0, 1.0, 2.0)
ROTOR_INERTIA = 5e-5
"""Rotor plus gearbox-input inertia of the demo's motors [kg m^2] (a 400 W servo class)."""


def run_demo() -> None:
    """The main job on built-in defaults: Delta sizing, fastest cycle, geometric models."""
    run_sizing_demo()
    print()
    run_fastest_demo()
    print()
    run_geometry_demo(samples=50)


def run_fastest_demo(
    payloads: tuple[float, ...] = FASTEST_PAYLOADS,
    rotor_inertia: float = ROTOR_INERTIA,
    samples: int = 501,
) -> dict[tuple[float, float], Any]:
    """Print the DELTA 580's fastest Adept cycle per payload, without and with rotor inertia.

    The Adept path is traversed as fast as the joint-side limits allow (toppra on pkdyn's
    closed-loop inverse dynamics), once with the mechanism alone and once with motors whose
    rotor inertia ``rotor_inertia`` the arms see multiplied by the reduction squared; each
    result is checked by an independent inverse-dynamics pass along it
    (:class:`pkdyn.dynamics.fastest_grid.FastestGrid`'s table).

    Args:
        payloads: Payloads [kg].
        rotor_inertia: Motor-side rotor inertia [kg m^2].
        samples: Samples of the path (the toppra grid).

    Returns:
        ``{(payload, rotor_inertia): FastestResult}``.

    """
    from pkdyn.dynamics.fastest_grid import fastest_grid
    from pkdyn.dynamics.trajectory import named_task
    from pkdyn.model.loader import load

    robot = load("delta", geometry=False)
    p = robot.params
    path = named_task(robot, "adept", cycle_time=1.0, dt=1.0 / max(2, samples - 1))
    print(
        f"Fastest Adept cycle of the DELTA 580 (toppra on the closed-loop inverse dynamics, "
        f"{path.t.size} path samples; limits {p.effort:g} N m and {p.velocity:g} rad/s per arm; "
        f"rotor {rotor_inertia:g} kg m^2: {p.reduction**2 * rotor_inertia:.3g} kg m^2 at the arm):"
    )
    grid = fastest_grid(robot, path, payloads, (0.0, rotor_inertia))
    print(grid.table())
    return {(m, float(J or 0.0)): res for (m, J), res in grid.results.items()}


def run_sizing_demo(
    cycle_time: float = 0.5,
    payload: float = 1.0,
    cycle_times: tuple[float, ...] = CYCLE_TIMES,
    payloads: tuple[float, ...] = PAYLOADS,
) -> dict[str, object]:
    """Print the motor sizing of the default DELTA 580 on the Adept cycle.

    One detailed table (``cycle_time``, ``payload``), a peak-torque / margin grid over
    ``cycle_times`` x ``payloads`` (:class:`pkdyn.dynamics.sizing_grid.SizingGrid`), and the
    physical checks of the computation (closure residual along the trajectory, power balance
    of the efforts against the energy).

    Args:
        cycle_time: Cycle time of the detailed table [s].
        payload: Payload of the detailed table [kg].
        cycle_times: Cycle times of the grid [s].
        payloads: Payloads of the grid [kg].

    Returns:
        ``{"detail": SizingResult, "grid": {(cycle_time, payload): SizingResult}}``.

    """
    from pkdyn.dynamics.sizing import size
    from pkdyn.dynamics.sizing_grid import sizing_grid
    from pkdyn.dynamics.trajectory import named_trajectory
    from pkdyn.model.assembly import closure_residual
    from pkdyn.model.loader import load

    robot = load("delta", geometry=False)
    p = robot.params
    print(
        f"DELTA 580 (Bouri & Clavel): ra = {p.ra} m, rb = {p.rb} m, la = {p.la} m, "
        f"lb = {p.lb} m, reduction {p.reduction:g}, effort limit {p.effort:g} N m, "
        f"speed limit {p.velocity:g} rad/s (joint side)"
    )
    traj = named_trajectory(robot, "adept", cycle_time=cycle_time)
    detail = size(robot, traj, payload=payload)
    print(f"Adept cycle 25/305/25 mm, quintic moves, {cycle_time:g} s, payload {payload:g} kg:")
    print(detail.table())
    # physical checks of that computation
    ef = detail.efforts
    P = np.sum(ef.tau * traj.qa_dot, axis=1)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (P[1:] + P[:-1]) * np.diff(traj.t))])
    balance = float(np.max(np.abs(work - (ef.energy - ef.energy[0]))))
    scale = max(float(np.max(np.abs(work))), float(np.max(ef.kinetic)))
    worst = max(closure_residual(robot, q) for q in traj.q[:: max(1, traj.t.size // 50)])
    print(
        f"checks: closure residual along the cycle <= {worst:.1e} m; power balance "
        f"|integral(tau.qd) - dE| = {balance / scale:.1e} of the energy exchanged"
    )
    print()
    grid = sizing_grid(robot, cycle_times, payloads)
    print(grid.table())
    return {"detail": detail, "grid": grid.results}


def run_geometry_demo(samples: int = 200, seed: int = 0) -> list[dict[str, float]]:
    """Print, for every library robot, its size, mobility and geometric-model accuracy.

    For each robot: ``samples`` random platform poses near home are solved by the inverse
    geometric model, then the direct geometric model is solved from the actuated coordinates
    found, and the pose error of the round trip and the closure residuals are reported.

    Args:
        samples: Number of random poses per robot.
        seed: Random seed.

    Returns:
        One row per robot (the printed figures).

    """
    import pinocchio as pin

    from pkdyn import library
    from pkdyn.model.assembly import closure_residual, forward_geometry, inverse_geometry
    from pkdyn.model.loader import load
    from pkdyn.units import columns

    rng = np.random.default_rng(seed)
    rows = []
    table = [
        [
            "robot",
            "nq",
            "nv",
            "dof",
            "loops",
            "act",
            "max closure [m or rad]",
            "max FK(IK) err [m or rad]",
            "ms/solve",
        ]
    ]
    for name in library.FAMILIES:
        robot = load(name, geometry=False)
        home = robot.platform_placement(robot.q_home)
        worst_c = closure_residual(robot, robot.q_home)
        worst_p = 0.0
        q = robot.q_home
        t0 = time.perf_counter()
        for _ in range(samples):
            d = np.zeros(6)
            d[robot.task_rows] = rng.uniform(-1, 1, robot.task_rows.size)
            d[:3] *= 0.02
            d[3:] *= 0.05
            target = (
                home * pin.exp6(d)
                if robot.task_rows.size == 6
                else pin.SE3(home.rotation, home.translation + d[:3])
                * pin.SE3(pin.exp3(d[3:]), np.zeros(3))
            )
            ik = inverse_geometry(robot, target, q_init=q)
            fk = forward_geometry(robot, ik.qa, q_init=ik.q)
            assert fk.placement is not None
            err = np.concatenate(
                [
                    fk.placement.translation - target.translation,
                    pin.log3(target.rotation.T @ fk.placement.rotation),
                ]
            )[robot.task_rows]
            worst_p = max(worst_p, float(np.max(np.abs(err))))
            worst_c = max(worst_c, fk.residual, ik.residual)
            q = ik.q
        ms = (time.perf_counter() - t0) / (2 * samples) * 1e3
        row = {
            "nq": robot.nq,
            "nv": robot.nv,
            "dof": robot.dof(),
            "loops": robot.loops,
            "actuators": len(robot.actuators),
            "closure": worst_c,
            "roundtrip": worst_p,
            "ms": ms,
        }
        rows.append(row)
        table.append(
            [
                name,
                *(str(row[k]) for k in ("nq", "nv", "dof", "loops", "actuators")),
                f"{worst_c:.2e}",
                f"{worst_p:.2e}",
                f"{ms:.2f}",
            ]
        )
    print(columns(table))
    print(f"\n{samples} random poses per robot: inverse then direct geometric model.")
    return rows


def _cmd_demo(args: argparse.Namespace) -> None:
    run_demo()


def register(sub: Any) -> None:
    """Add ``demo`` to the ``pkdyn`` parser."""
    sp = sub.add_parser("demo", help="run the demonstration on built-in defaults")
    sp.set_defaults(func=_cmd_demo)
