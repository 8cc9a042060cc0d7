"""Geometric-model benchmarks: Delta closed forms; assembly (FK) and IK of every library robot
against raw-Pinocchio Gauss-Newton (``raw_pinocchio.py``), warm-started along a smooth path.

Run ``python bench/geometry.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
from raw_pinocchio import RawClosures, RawPoseTask, gauss_newton
from timing import ROBOTS, Row, print_table, us

import pkdyn
from pkdyn.closed_form import delta as cf_delta
from pkdyn.closed_form import gough_stewart as cf_gs

N_PATH = 60
REPEATS = 5


def _rate(fn, n_items: int, repeats: int = 7) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return n_items / float(np.median(times))


def delta_closed_form(n: int = 200_000) -> list[Row]:
    robot = pkdyn.load("delta", geometry=False)
    p = robot.params
    rng = np.random.default_rng(0)
    P = np.column_stack(
        [rng.uniform(-0.1, 0.1, n), rng.uniform(-0.1, 0.1, n), rng.uniform(-0.42, -0.3, n)]
    )
    alpha, _ = cf_delta.inverse(p, P)
    ik = _rate(lambda: cf_delta.inverse(p, P), n)
    fk = _rate(lambda: cf_delta.forward(p, alpha), n)
    m = 300
    q = robot.q_home
    t0 = time.perf_counter()
    for k in range(m):
        q = pkdyn.inverse_geometry(robot, P[k], q_init=q).q
    numeric = m / (time.perf_counter() - t0)
    return [
        ("Delta closed-form IK (Clavel), vectorised", f"{ik:.3g} poses/s", ">= 1e5/s"),
        ("Delta closed-form FK (Clavel), vectorised", f"{fk:.3g} poses/s", ">= 1e5/s"),
        (
            "Delta numeric IK (general path), warm-started, random poses",
            f"{numeric:.3g} poses/s (closed form {ik / numeric:.0f}x faster)",
            "-",
        ),
    ]


def gs_leg_path(robot: pkdyn.Robot, n: int) -> np.ndarray:
    """Leg lengths (n, 6) [m] along a smooth closed platform path about the Gough-Stewart's home.

    Small translations (2 cm) and rotations (0.05-0.08 rad) at several frequencies; the lengths
    from the closed-form inverse model.
    """
    p = robot.params
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
    return np.asarray(cf_gs.leg_lengths_rpy(p.a, p.b, poses))


def gs_assembly(n: int = 2000) -> list[Row]:
    """Gough-Stewart FK along a smooth platform trajectory (leg lengths from the closed form)."""
    robot = pkdyn.load("gough_stewart", geometry=False)
    rho = gs_leg_path(robot, n)
    q = pkdyn.forward_geometry(robot, rho[0]).q
    times = np.empty(n)
    iters = np.empty(n)
    for k in range(n):
        t0 = time.perf_counter()
        res = pkdyn.forward_geometry(robot, rho[k], q_init=q)
        times[k] = time.perf_counter() - t0
        iters[k] = res.iterations
        q = res.q
    return [
        (
            "Gough-Stewart numeric assembly (FK), warm-started along a smooth pose trajectory "
            f"({n} samples)",
            f"median {us(1e6 * float(np.median(times)))}, p90 "
            f"{us(1e6 * float(np.percentile(times, 90)))}, {iters.mean():.1f} iterations",
            "median <= 200 us",
        )
    ]


def _path(robot: pkdyn.Robot) -> np.ndarray:
    """Full configurations along a smooth actuator path around home (N_PATH, nq)."""
    t = np.linspace(0.0, 2.0 * np.pi, N_PATH)
    na = len(robot.actuators)
    qa0 = robot.q_home[robot.actuated_q]
    qa = qa0 + 0.02 * np.sin(t[:, None] + np.arange(na) * 2.0 * np.pi / na)
    out = np.empty((N_PATH, robot.nq))
    q = robot.q_home
    for k in range(N_PATH):
        q = pkdyn.forward_geometry(robot, qa[k], q_init=q, check_limits=False).q
        out[k] = q
    return out


def _walk(solve, starts: np.ndarray, targets: list) -> tuple[float, float]:
    """Median time per solve [us] and mean iterations along the path (warm-started)."""
    times, iters = [], []
    for _ in range(REPEATS):
        q = starts[0]
        t0 = time.perf_counter()
        for x in targets:
            q, it = solve(q, x)
            iters.append(it)
        times.append((time.perf_counter() - t0) / len(targets))
    return 1e6 * float(np.median(times)), float(np.mean(iters))


def robot_rows(name: str) -> list[Row]:
    robot = pkdyn.load(name, geometry=False)
    model = robot.model
    data = model.createData()
    Q = _path(robot)
    qa = Q[:, robot.actuated_q]
    raw = RawClosures(model, robot.constraint_models)

    def fk_pkdyn(q, x):
        res = pkdyn.forward_geometry(robot, x, q_init=q, check_limits=False)
        return res.q, res.iterations

    def fk_raw(q, x):
        q = q.copy()
        q[robot.actuated_q] = x
        return gauss_newton(model, q, lambda y: raw.residual_and_jacobian(data, y), robot.passive_v)

    poses = [robot.platform_placement(q) for q in Q]

    def ik_pkdyn(q, M):
        res = pkdyn.inverse_geometry(robot, M, q_init=q, check_limits=False)
        return res.q, res.iterations

    task = RawPoseTask(model, robot.platform_frame, robot.task_rows, pin.SE3.Identity())
    free = np.arange(model.nv)

    def ik_raw(q, M):
        task.target = M

        def rj(y):
            r1, J1 = raw.residual_and_jacobian(data, y)
            r2, J2 = task.residual_and_jacobian(data)
            return np.r_[r1, r2], np.vstack([J1, J2])

        return gauss_newton(model, q, rj, free)

    rows: list[Row] = []
    for label, a, b, targets in (
        ("assembly / FK", fk_pkdyn, fk_raw, list(qa)),
        ("IK", ik_pkdyn, ik_raw, poses),
    ):
        ratios, t_pk, t_raw = [], [], []
        for _ in range(3):  # alternate whole-path runs (the machine load changes)
            tp, ip = _walk(a, Q, targets)
            tr, ir = _walk(b, Q, targets)
            t_pk.append(tp)
            t_raw.append(tr)
            ratios.append(tp / tr)
        rows.append(
            (
                f"{name}: {label}, warm-started along a path, per solve",
                f"pkdyn {us(float(np.median(t_pk)))} ({ip:.1f} it.) vs raw Pinocchio "
                f"{us(float(np.median(t_raw)))} ({ir:.1f} it.): {np.median(ratios):.2f}x",
                "-",
            )
        )
    return rows


def rows() -> list[Row]:
    out = delta_closed_form() + gs_assembly()
    for name in ROBOTS:
        out += robot_rows(name)
    return out


if __name__ == "__main__":
    print_table(rows())
