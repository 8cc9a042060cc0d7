"""Timing helpers shared by the benchmark modules: medians of repeated batches, paired ratios.

The machine is shared, so its load changes between runs: a ratio is the median of ratios
measured on alternating batches of the two callables, not a ratio of two separate medians, and
batches are timed in CPU time of the process (not wall time, which counts the waits for a core).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import pinocchio as pin

import pkdyn
from solvers.numerics import null_space

Row = tuple[str, str, str]
"""One table row: benchmark, figure, target or comment."""

ROBOTS = ("delta", "gough_stewart", "planar_3rrr", "five_bar", "tripod")


def batch_us(fn: Callable[[], object], n: int) -> float:
    """Mean CPU time of ``n`` calls of ``fn`` [us].

    CPU time of this process (``time.process_time``): on a shared machine the wall time also
    counts the waits for a core, which other processes' load varies; both sides of a ratio are
    timed alike.
    """
    t0 = time.process_time()
    for _ in range(n):
        fn()
    return 1e6 * (time.process_time() - t0) / n


def median_us(fn: Callable[[], object], n: int, repeats: int = 7) -> float:
    """Median over ``repeats`` batches of the mean time of ``n`` calls [us]."""
    fn()
    return float(np.median([batch_us(fn, n) for _ in range(repeats)]))


def paired(
    fn: Callable[[], object],
    ref: Callable[[], object],
    n: int,
    n_ref: int | None = None,
    repeats: int = 9,
) -> tuple[float, float, float]:
    """Median times of ``fn`` and ``ref`` [us] and the median of their ratio, timed alternately."""
    fn()
    ref()
    pairs = [(batch_us(fn, n), batch_us(ref, n_ref or n)) for _ in range(repeats)]
    a = np.array(pairs)
    return float(np.median(a[:, 0])), float(np.median(a[:, 1])), float(np.median(a[:, 0] / a[:, 1]))


def consistent_state(
    robot: pkdyn.Robot, seed: int = 0, spread: float = 0.05, speed: float = 0.3
) -> tuple[np.ndarray, np.ndarray]:
    """An assembled configuration near home and a velocity in the closures' null space."""
    rng = np.random.default_rng(seed)
    q = pkdyn.project(
        robot, pin.integrate(robot.model, robot.q_home, spread * rng.standard_normal(robot.nv))
    )
    _, J = robot.closure_set.residual_and_jacobian(robot.model.createData(), q)
    Z = null_space(J, 1e-9)
    v = Z @ rng.standard_normal(Z.shape[1])
    return q, speed * v / np.max(np.abs(v))


def us(x: float) -> str:
    """A time in microseconds, 3 significant figures."""
    return f"{x:.3g} us" if x < 1e3 else f"{x / 1e3:.3g} ms"


def print_table(rows: list[Row]) -> None:
    """Print benchmark rows as a markdown table (a module run on its own)."""
    print("| benchmark | figure | target |\n|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")
