"""``make demo``: load every library robot, assemble it, and run its geometric models."""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin

from pkdyn import library
from pkdyn.assembly import closure_residual, forward_geometry, inverse_geometry
from pkdyn.loader import load

__all__ = ["run_demo"]


def run_demo(samples: int = 200, seed: int = 0) -> list[dict[str, float]]:
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
    rng = np.random.default_rng(seed)
    rows = []
    header = f"{'robot':<14}{'nq':>4}{'nv':>4}{'dof':>5}{'loops':>6}{'act':>5}"
    header += f"{'max closure':>14}{'max FK(IK) err':>16}{'ms/solve':>10}"
    print(header)
    print("-" * len(header))
    for name in library.MODULES:
        if name not in library.FAMILIES:
            continue
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
        print(
            f"{name:<14}{robot.nq:>4}{robot.nv:>4}{row['dof']:>5}{row['loops']:>6}"
            f"{row['actuators']:>5}{worst_c:>14.2e}{worst_p:>16.2e}{ms:>10.2f}"
        )
    print(f"\n{samples} random poses per robot: inverse then direct geometric model.")
    return rows
