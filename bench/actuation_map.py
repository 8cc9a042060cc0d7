"""Actuation-map and importer benchmarks.

- ``pkdyn.actuation_map``, ``from_actuators`` along a smooth path (warm-started), per sample:
  position solve, Jacobians both ways, reflected inertias and the singularity test, as a ratio
  to one raw Pinocchio constraint solve from the same warm start (Gauss-Newton with
  ``getConstraintsJacobian``, ``raw_pinocchio.py``): the map costs a few constraint solves.
- The parallel ankle's closed forms (:mod:`pkdyn.closed_form.parallel_ankle`), vectorised.
- Loading public models (MJCF, SDFormat, Gepetto URDF + YAML), geometry off.

Run ``python bench/actuation_map.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from raw_pinocchio import RawClosures, gauss_newton
from timing import Row, print_table, us

import pkdyn
from pkdyn.closed_form import parallel_ankle as ankle_cf

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "public"
N_PATH = 80


def map_rows(name: str, joints: list[str]) -> list[Row]:
    robot = pkdyn.load(name, geometry=False)
    m = pkdyn.actuation_map(robot, joints)
    t = np.linspace(0, 2 * np.pi, N_PATH)
    qa0 = robot.q_home[m.act_q]
    qa = qa0 + 0.1 * np.sin(t[:, None] + np.arange(m.n))
    path = m.from_actuators(qa).q
    model, data = robot.model, robot.model.createData()
    raw = RawClosures(model, robot.constraint_models)
    free = robot.passive_v

    def pkdyn_maps() -> None:
        m.from_actuators(qa)

    def raw_solves() -> None:
        q = path[0]
        for k in range(N_PATH):
            q = q.copy()
            q[robot.actuated_q] = qa[k]
            q, _ = gauss_newton(model, q, lambda y: raw.residual_and_jacobian(data, y), free)

    ratios, t_map, t_raw = [], [], []
    for _ in range(5):  # alternate batches: the machine load changes
        t0 = time.perf_counter()
        pkdyn_maps()
        a = (time.perf_counter() - t0) / N_PATH
        t0 = time.perf_counter()
        raw_solves()
        b = (time.perf_counter() - t0) / N_PATH
        t_map.append(a)
        t_raw.append(b)
        ratios.append(a / b)
    per = float(np.median(t_map))
    return [
        (
            f"{name}: actuation map from actuators ({', '.join(joints)}), warm-started path, "
            "per sample",
            f"{1 / per:.0f} maps/s ({us(1e6 * per)}) vs one raw Pinocchio constraint solve "
            f"{us(1e6 * float(np.median(t_raw)))}: {np.median(ratios):.1f}x",
            "-",
        )
    ]


def ankle_closed_form(n: int = 100_000) -> list[Row]:
    p = pkdyn.library.FAMILIES["parallel_ankle"].params()
    rng = np.random.default_rng(0)
    X = np.column_stack([rng.uniform(-0.4, 0.4, n), rng.uniform(-0.3, 0.3, n)])
    theta, _ = ankle_cf.inverse(p, X)
    out = []
    for label, fn in (
        ("inverse (motors from pitch, roll)", lambda: ankle_cf.inverse(p, X)),
        ("forward (Newton, 30 iterations)", lambda: ankle_cf.forward(p, theta)),
        ("Jacobian", lambda: ankle_cf.jacobian(p, X, theta)),
    ):
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t0)
        out.append(
            (
                f"parallel ankle closed form, {label}, vectorised",
                f"{n / np.median(times):.3g}/s",
                "-",
            )
        )
    return out


def load_rows() -> list[Row]:
    out = []
    for label, path in (
        ("MuJoCo Menagerie Cassie (MJCF)", DATA / "menagerie_cassie" / "cassie.xml"),
        ("example-robot-data Cassie (SDFormat)", DATA / "erd_cassie_sdf" / "cassie_v2.sdf"),
        ("Gepetto Battobot (URDF + YAML)", DATA / "gepetto_battobot" / "robot.urdf"),
        ("Reachy Mini (onshape-to-robot URDF)", DATA / "reachy_mini" / "robot.urdf"),
    ):
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                pkdyn.load(path, geometry=False)
            times.append(time.perf_counter() - t0)
        out.append(
            (f"load {label}, assembled, geometry off", us(1e6 * float(np.median(times))), "-")
        )
    return out


def rows() -> list[Row]:
    out = map_rows("parallel_ankle", ["ankle_pitch", "ankle_roll"])
    out += map_rows("four_bar_knee", ["knee"])
    out += ankle_closed_form()
    out += load_rows()
    return out


if __name__ == "__main__":
    print_table(rows())
