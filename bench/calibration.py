"""Calibration and accuracy benchmarks (issues 26 and 27).

- ``calibrate`` of a Gough-Stewart platform (MEL) from 100 measured poses (full pose, 10 um /
  20 urad noise), family shortcuts (42 parameters) and every placement (156), against the
  floor of one Gauss-Newton iteration (forward geometry and identification Jacobian at the 100
  poses, which every iteration needs): target < 2 s (issue 27);
- a DELTA 580 from 40 measured positions (family shortcuts);
- ``pose_sensitivity`` (actuator and 156 placement sensitivities through the loops) against
  ``kinematic_models`` (the actuator Jacobian alone) at one configuration.

Times are CPU time of the process (the machine is shared; see ``timing.py``), medians of 3 runs;
the wall time of one run is given beside it.

Run ``python bench/calibration.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable

import numpy as np
from timing import Row, paired, print_table

import pkdyn
from pkdyn.analysis.kinematics import kinematic_models
from pkdyn.calibration import Measurements, calibrate
from pkdyn.precision.parameters import family_shortcuts, placement_parameters
from pkdyn.precision.perturbation import perturbed
from pkdyn.precision.sensitivity import pose_sensitivity


def _cpu_s(fn: Callable[[], object], repeats: int = 3) -> tuple[float, float]:
    """Median CPU time and the wall time of the last run [s]."""
    cpu, wall = [], 0.0
    for _ in range(repeats):
        t0, w0 = time.process_time(), time.perf_counter()
        fn()
        cpu.append(time.process_time() - t0)
        wall = time.perf_counter() - w0
    return statistics.median(cpu), wall


def _case(name: str, n: int, kind: str, spread: float, seed: int = 0):
    robot = pkdyn.load(name, geometry=False)
    model = family_shortcuts(robot)
    rng = np.random.default_rng(seed)
    p = rng.uniform(-1, 1, model.size) * model.tolerances(2e-3, np.deg2rad(0.5))
    truth = perturbed(robot, model, p).robot
    home = robot.q_home[robot.actuated_q]
    readings, poses = [], []
    while len(readings) < n:
        qa = home + spread * robot.actuator_scale * rng.uniform(-1, 1, home.size)
        try:
            pkdyn.forward_geometry(robot, qa)
            g = pkdyn.forward_geometry(truth, qa, q_init=truth.q_home)
        except pkdyn.PkdynError:
            continue
        readings.append(qa)
        poses.append(g.placement)
    m = Measurements.from_placements(np.array(readings), poses, kind)
    m.position += rng.normal(0, 1e-5, m.position.shape)
    if kind == "pose":
        m.rpy += rng.normal(0, 2e-5, m.rpy.shape)
    return robot, model, m


def _iteration_floor(robot, model, m) -> Callable[[], object]:
    """One Gauss-Newton iteration's evaluations: forward geometry and Jacobian at every pose."""
    qs = [pkdyn.forward_geometry(robot, r).q for r in m.qa]

    def run() -> None:
        for q, r in zip(qs, m.qa, strict=True):
            g = pkdyn.forward_geometry(robot, r, q_init=q, check_limits=False)
            pose_sensitivity(robot, g.q, model)

    return run


def rows() -> list[Row]:
    out: list[Row] = []
    robot, model, m = _case("gough_stewart", 100, "pose", 0.05)
    for label, pm in (
        ("family shortcuts", model),
        ("every placement", placement_parameters(robot)),
    ):
        res = calibrate(robot, m, pm, noise=(1e-5, 2e-5), holdout=0.0)
        cpu, wall = _cpu_s(lambda pm=pm: calibrate(robot, m, pm, noise=(1e-5, 2e-5), holdout=0.0))
        floor, _ = _cpu_s(_iteration_floor(robot, pm, m))
        before, after = res.before.position_rms * 1e3, res.after.position_rms * 1e6
        out.append(
            (
                f"gough_stewart: `calibrate`, 100 poses (full pose), {label}: {pm.size} "
                f"parameters, {res.identifiability.rank} identified, {res.iterations} iterations, "
                f"RMS {before:.2f} mm -> {after:.1f} um",
                f"{cpu:.2f} s CPU ({wall:.2f} s wall); {cpu / floor:.1f}x one Gauss-Newton "
                f"evaluation ({floor:.2f} s)",
                "< 2 s (issue 27)",
            )
        )
    robot, model, m = _case("delta", 40, "position", 0.3, seed=1)
    res = calibrate(robot, m, model, noise=1e-5, holdout=0.0)
    cpu, wall = _cpu_s(lambda: calibrate(robot, m, model, noise=1e-5, holdout=0.0))
    out.append(
        (
            f"delta: `calibrate`, 40 positions, family shortcuts ({model.size} parameters, "
            f"{res.identifiability.rank} identified)",
            f"{cpu:.2f} s CPU ({wall:.2f} s wall)",
            "-",
        )
    )
    robot = pkdyn.load("gough_stewart", geometry=False)
    pm = placement_parameters(robot)
    q = robot.q_home
    t_s, t_k, ratio = paired(
        lambda: pose_sensitivity(robot, q, pm), lambda: kinematic_models(robot, q), 50
    )
    out.append(
        (
            f"gough_stewart: `pose_sensitivity`, 6 actuator + {pm.size} placement sensitivities "
            "through the loops",
            f"{t_s:.0f} us vs `kinematic_models` {t_k:.0f} us: {ratio:.2f}x",
            "-",
        )
    )
    return out


if __name__ == "__main__":
    print_table(rows())
