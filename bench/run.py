"""pkdyn benchmarks (``make bench``): figures as throughputs and ratios measured in one run.

Writes ``bench/results.md``. Medians of repeated runs; never a timed unit test.
"""

from __future__ import annotations

import platform
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import pkdyn
from pkdyn.closed_form import delta as cf_delta
from pkdyn.closed_form import gough_stewart as cf_gs

OUT = Path(__file__).with_name("results.md")


def _median_rate(fn, n_items: int, repeats: int = 7) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return n_items / float(np.median(times))


def bench_delta_closed_form(n: int = 200_000) -> dict[str, float]:
    robot = pkdyn.load("delta", geometry=False)
    rng = np.random.default_rng(0)
    p = robot.params
    P = np.column_stack(
        [rng.uniform(-0.1, 0.1, n), rng.uniform(-0.1, 0.1, n), rng.uniform(-0.42, -0.3, n)]
    )
    alpha, ok = cf_delta.inverse(p, P)
    ik = _median_rate(lambda: cf_delta.inverse(p, P), n)
    fk = _median_rate(lambda: cf_delta.forward(p, alpha), n)
    # the numeric path on the same robot, for the ratio
    m = 300
    q = robot.q_home
    t = time.perf_counter()
    for k in range(m):
        q = pkdyn.inverse_geometry(robot, P[k], q_init=q).q
    num_ik = m / (time.perf_counter() - t)
    return {"ik_per_s": ik, "fk_per_s": fk, "numeric_ik_per_s": num_ik, "valid": float(ok.mean())}


def bench_gs_assembly(n: int = 2000) -> dict[str, float]:
    robot = pkdyn.load("gough_stewart", geometry=False)
    p = robot.params
    # a smooth trajectory: each solve is warm-started from the previous solution
    t = np.linspace(0, 2 * np.pi, n)
    poses = np.column_stack(
        [
            0.02 * np.sin(t),
            0.02 * np.cos(2 * t),
            p.home_height() + 0.02 * np.sin(3 * t),
            0.05 * np.sin(t),
            0.05 * np.cos(t),
            0.08 * np.sin(2 * t),
        ]
    )
    rho = cf_gs.leg_lengths_rpy(p.a, p.b, poses)
    q = pkdyn.forward_geometry(robot, rho[0]).q
    times = np.empty(n)
    iters = np.empty(n)
    for k in range(n):
        t0 = time.perf_counter()
        res = pkdyn.forward_geometry(robot, rho[k], q_init=q)
        times[k] = time.perf_counter() - t0
        iters[k] = res.iterations
        q = res.q
    # raw Pinocchio reference: one kinematics + Jacobian pass (what one LM iteration needs)
    data = robot.model.createData()
    m = 5000
    t0 = time.perf_counter()
    for _ in range(m):
        pin.computeJointJacobians(robot.model, data, q)
    raw = (time.perf_counter() - t0) / m
    return {
        "median_us": float(np.median(times) * 1e6),
        "p90_us": float(np.percentile(times, 90) * 1e6),
        "mean_iterations": float(iters.mean()),
        "raw_jacobians_us": raw * 1e6,
    }


def main() -> None:
    d = bench_delta_closed_form()
    g = bench_gs_assembly()
    lines = [
        "# pkdyn benchmark results",
        "",
        f"Machine: {platform.machine()}, {platform.processor() or 'cpu'}, Python "
        f"{platform.python_version()}, Pinocchio {pin.__version__}, numpy {np.__version__}.",
        "Medians of repeated runs (`make bench`).",
        "",
        "| benchmark | figure | target |",
        "|---|---|---|",
        f"| Delta closed-form IK (Clavel), vectorised | {d['ik_per_s']:.3g} poses/s | >= 1e5/s |",
        f"| Delta closed-form FK (Clavel), vectorised | {d['fk_per_s']:.3g} poses/s | >= 1e5/s |",
        f"| Delta numeric IK (general path), warm-started | {d['numeric_ik_per_s']:.3g} poses/s "
        f"(closed form is {d['ik_per_s'] / d['numeric_ik_per_s']:.0f}x faster) | - |",
        f"| Gough-Stewart numeric assembly (FK), warm-started | median {g['median_us']:.0f} us, "
        f"p90 {g['p90_us']:.0f} us, {g['mean_iterations']:.1f} iterations | median <= 200 us |",
        f"| ... raw `pin.computeJointJacobians` on the same model | {g['raw_jacobians_us']:.1f} us "
        f"(assembly = {g['median_us'] / g['raw_jacobians_us']:.0f}x) | - |",
        "",
    ]
    OUT.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
