"""Sizing benchmarks: the fastest cycle and the motor selection, timed as a user calls them.

- ``fastest_trajectory`` on the DELTA 580's Adept path (501 samples, 1 kg), against the four
  inverse-dynamics passes it is made of (three for the coefficients, one for the check): the
  ratio is the cost of toppra and of the bookkeeping.
- ``select_drives`` with the example catalog (7 motors x 18 gearboxes per arm) on the 0.5 s Adept
  cycle, against the one inverse-dynamics pass it needs.

Run ``python bench/sizing.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable

from timing import Row, print_table

import pkdyn
from pkdyn.dynamics import inverse_dynamics, with_payload
from pkdyn.dynamics.fastest import fastest_trajectory, joint_path
from pkdyn.dynamics.motors import example_catalog
from pkdyn.dynamics.selection import select_drives
from pkdyn.dynamics.trajectory import named_task, named_trajectory


def _median_s(fn: Callable[[], object], repeats: int = 3) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def rows() -> list[Row]:
    robot = pkdyn.load("delta", geometry=False)
    loaded = with_payload(robot, 1.0)
    path = joint_path(robot, named_task(robot, "adept", cycle_time=1.0, dt=2e-3))
    fast = fastest_trajectory(robot, path, payload=1.0)
    t_fast = _median_s(lambda: fastest_trajectory(robot, path, payload=1.0))
    t_id = _median_s(lambda: inverse_dynamics(loaded, fast.trajectory))
    traj = named_trajectory(robot, "adept", cycle_time=0.5)
    cat = example_catalog()
    t_sel = _median_s(lambda: select_drives(robot, traj, cat, payload=1.0))
    t_id2 = _median_s(lambda: inverse_dynamics(loaded, traj))
    n = path.t.size
    return [
        (
            f"delta: `fastest_trajectory`, Adept path of {n} samples, 1 kg "
            f"(cycle {fast.cycle_time:.4f} s)",
            f"{t_fast:.2f} s vs 4 inverse-dynamics passes {4 * t_id:.2f} s: "
            f"{t_fast / (4 * t_id):.2f}x",
            "-",
        ),
        (
            f"delta: `select_drives`, example catalog ({len(cat.motors)} x {len(cat.gearboxes)} "
            f"pairs x 3 arms), 0.5 s Adept cycle ({traj.t.size} samples)",
            f"{t_sel:.2f} s vs 1 inverse-dynamics pass {t_id2:.2f} s: {t_sel / t_id2:.2f}x",
            "-",
        ),
    ]


if __name__ == "__main__":
    print_table(rows())
