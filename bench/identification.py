"""Identification benchmark: a Delta and a Gough-Stewart from 1e5 samples (issue 27: < 10 s).

Each robot, with rotor inertias and motor friction, follows a 5-harmonic multi-sine at 1 kHz
(100 s; 0.3 rad of the Delta's arms, 3 cm of the Gough-Stewart's legs); its efforts come from
the closed-loop regressor with the true parameters plus 1 % noise (computed once, not timed).
Timed: :func:`pkdyn.identification.identify` as a user calls it (base parameters from random
motions, joint motions, regressor, weighted least squares, physical parameters; two worker
processes from 20,000 samples on). ``PKDYN_BENCH_ID_SAMPLES`` sets the number of samples
(default 100000), ``PKDYN_BENCH_ID_ROBOTS`` the robots (default ``delta,gough_stewart``).

Run ``python bench/identification.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import os
import resource
import time

import numpy as np
from timing import Row, print_table

import pkdyn
from pkdyn.dynamics.actuation import with_drives
from pkdyn.identification import Measurements, identify, parameter_set, predict_efforts

AMPLITUDE = {"delta": 0.3, "gough_stewart": 0.03}  # [rad or m]


def _motion(robot, n: int, dt: float = 1e-3, amp: float = 0.3):
    rng = np.random.default_rng(1)
    t = np.arange(n) * dt
    k = len(robot.actuators)
    qa = np.tile(robot.q_home[robot.actuated_q], (n, 1))
    qd, qdd = np.zeros_like(qa), np.zeros_like(qa)
    for h in range(1, 6):
        w = 2 * np.pi * 0.2 * h
        A, B = amp * rng.uniform(-1, 1, k) / h, amp * rng.uniform(-1, 1, k) / h
        s, c = np.sin(w * t[:, None]), np.cos(w * t[:, None])
        qa += A * s + B * (c - 1)
        qd += w * (A * c - B * s)
        qdd += -w * w * (A * s + B * c)
    return t, qa, qd, qdd


def _row(name: str, n: int) -> Row:
    robot = with_drives(
        pkdyn.load(name, geometry=False), rotor_inertia=1e-5, viscous=1e-4, coulomb=0.02
    )
    ps = parameter_set(robot)
    t, qa, qd, qdd = _motion(robot, n, amp=AMPLITUDE.get(name, 0.1))
    tau = predict_efforts(robot, ps, ps.nominal, t, qa, qd, qdd)
    noise = 0.01 * np.sqrt(np.mean(tau**2, axis=0))
    meas = tau + noise * np.random.default_rng(2).standard_normal(tau.shape)

    def cpu_s() -> float:  # this process and its (joined) worker processes
        own, kids = (
            resource.getrusage(w) for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)
        )
        return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime

    t0 = time.perf_counter()
    c0 = cpu_s()
    res = identify(robot, Measurements(t, qa, qd, qdd, meas))
    wall, cpu = time.perf_counter() - t0, cpu_s() - c0
    z = (res.estimate.theta - res.base.K @ ps.nominal[ps.identified]) / res.estimate.std
    return (
        f"{name}: `identify` from {n} samples ({len(robot.actuators)} actuators, "
        f"{res.base.size} base parameters)",
        f"{wall:.1f} s wall, {cpu:.1f} s CPU on 2 processes ({1e6 * cpu / n:.0f} us CPU per "
        f"sample, load {os.getloadavg()[0]:.1f}); recovery max {np.abs(z).max():.2f} std",
        "< 10 s for 1e5 samples",
    )


def rows() -> list[Row]:
    n = int(os.environ.get("PKDYN_BENCH_ID_SAMPLES", "100000"))
    names = os.environ.get("PKDYN_BENCH_ID_ROBOTS", "delta,gough_stewart").split(",")
    return [_row(name.strip(), n) for name in names if name.strip()]


if __name__ == "__main__":
    print_table(rows())
