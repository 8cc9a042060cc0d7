"""The public functions as users call them, beside the core and the floor, in one run (issue 14).

The *floor* is the plainest loop of raw Pinocchio calls doing the same work, written here
(``raw_pinocchio.py``); ratios are medians of ratios timed on alternating runs.

- Inverse dynamics, per sample: ``pkdyn.dynamics.inverse_dynamics(robot, trajectory)`` (closure
  check, energies and error reporting included) on the Delta's Adept cycle and the
  Gough-Stewart platform's sine; the core ``InverseDynamics.trajectory`` without the check; the
  floor (``rnea``, the C++ constraint Jacobian, the normal equations of the passive rows, per
  sample); MuJoCo's ``mj_inverse`` plus the projection on the actuators, per sample.
- Forward simulation of a passive run from home, per simulated second:
  ``simulate(integrator="euler", step=1e-5)`` and ``simulate()`` (``dopri5``, 1 ms output)
  against the raw Euler loop (``constraintDynamics`` + ``integrate``, the same Baumgarte gains
  and step); the accuracy of the 10 s runs (largest closure residual, energy drift); MuJoCo's
  ``mj_step`` on the exported model (contacts off, its 1 ms step, soft closures) for scale.
- Assembly: ``pkdyn.forward_geometry`` of the Gough-Stewart platform along a path against the
  lean Newton loop (one C++ Jacobian call per iteration).
- Numeric workspace throughput on the default boxes (``method="numeric"``, default limits).

Run ``python bench/public.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import resource
import time

import mujoco
import numpy as np
import pinocchio as pin
import raw_pinocchio
from geometry import gs_leg_path
from timing import Row, paired, print_table, us

import pkdyn
from pkdyn.dynamics import actuation, inverse_dynamics, simulate
from pkdyn.dynamics.trajectory import named_trajectory
from pkdyn.model.formats.mjcf import MjcfOptions, StateMap, actuator_efforts, mujoco_model
from pkdyn.workspace.numeric import PARALLEL_SAMPLES
from pkdyn.workspace.translation import translation_workspace
from solvers import InverseDynamics

EULER_STEP = 1e-5  # the Euler step at which a passive Delta keeps its energy to 0.1 % over 10 s
CASES = {"delta": ("adept", {}), "gough_stewart": ("sine", {})}


# --------------------------------------------------------------------------- inverse dynamics


def inverse_rows(name: str) -> list[Row]:
    robot = pkdyn.load(name, geometry=False)
    model = robot.model
    traj, opts = CASES[name]
    jt = named_trajectory(robot, traj, **opts)
    n = jt.t.size
    closures = raw_pinocchio.RawClosures(model, robot.constraint_models)
    data = model.createData()
    vp = np.setdiff1d(np.arange(model.nv), robot.actuated_v)

    def floor() -> np.ndarray:
        return raw_pinocchio.inverse_dynamics_floor(
            model, data, closures, robot.actuated_v, vp, jt.q, jt.v, jt.a
        )

    def public() -> object:
        return inverse_dynamics(robot, jt)

    core_solver = InverseDynamics(model, list(robot.constraint_models), actuation(robot))

    def core() -> object:
        return core_solver.trajectory(jt.q, jt.v, jt.a)

    err = float(np.max(np.abs(public().tau - floor())))  # type: ignore[attr-defined]
    t_pub, t_floor, r_pub = paired(public, floor, 1, repeats=7)
    t_core, _, r_core = paired(core, floor, 1, repeats=7)
    # MuJoCo: mj_inverse and the projection on the actuators, per sample
    smap = StateMap(robot)
    mj = mujoco_model(robot, MjcfOptions(contacts=False))
    mj.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    mjd = mujoco.MjData(mj)
    states = [
        (smap.qpos(q), smap.qvel(q, v), smap.qacc(q, v, a))
        for q, v, a in zip(jt.q, jt.v, jt.a, strict=True)
    ]

    def mj_inverse() -> None:
        for qpos, qvel, qacc in states:
            mjd.qpos[:], mjd.qvel[:], mjd.qacc[:] = qpos, qvel, qacc
            mujoco.mj_inverse(mj, mjd)
            actuator_efforts(mj, mjd)

    _, t_mj, r_mj = paired(public, mj_inverse, 1, repeats=5)
    return [
        (
            f"{name}: `inverse_dynamics()` per sample ({traj}, {n} samples, closure check "
            "included) / floor (rnea + C++ constraint Jacobian + normal equations)",
            f"{us(t_pub / n)} vs {us(t_floor / n)}: **{r_pub:.2f}x** (efforts agree to {err:.1e})",
            "<= 1.5x",
        ),
        (
            f"{name}: ... core `InverseDynamics.trajectory` (no check) / floor",
            f"{us(t_core / n)}: {r_core:.2f}x",
            "-",
        ),
        (
            f"{name}: ... MuJoCo `mj_inverse` + projection on the actuators, per sample",
            f"{us(t_mj / n)}: `inverse_dynamics()` takes {r_mj:.2f}x its time",
            "-",
        ),
    ]


# --------------------------------------------------------------------------- simulation


def raw_euler(robot: pkdyn.Robot, duration: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """The raw Euler loop from home at rest: ``constraintDynamics`` + ``integrate``, the gains
    ``simulate`` uses for this step (critically damped at 0.5 / h), its proximal settings."""
    model = robot.model
    data = model.createData()
    w = 0.5 / h
    corrector = pin.BaumgarteCorrectorParameters(w * w, 2.0 * w)
    cms = pin.StdVec_RigidConstraintModel()
    cds = pin.StdVec_RigidConstraintData()
    for cm in robot.constraint_models:
        c = pin.RigidConstraintModel(cm)
        c.setBaumgarteCorrectorParameters(corrector)
        cms.append(c)
        cds.append(c.createData())
    pin.initConstraintDynamics(model, data, cms, cds)
    prox = pin.ProximalSettings(1e-12, 1e-12, 1e-6, 30)
    q, v, zero = robot.q_home.copy(), np.zeros(model.nv), np.zeros(model.nv)
    for _ in range(int(round(duration / h))):
        v = v + h * pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)
        q = pin.integrate(model, q, h * v)
    return q, v


def simulation_rows(name: str, long_euler: bool = True) -> list[Row]:
    """Timed 0.2 s runs (median of alternating runs); the accuracy of 10 s runs (the Euler one
    only with ``long_euler``: a million steps)."""
    robot = pkdyn.load(name, geometry=False)
    T = 0.2

    def euler() -> object:
        return simulate(robot, T, 1e-3, integrator="euler", step=EULER_STEP)

    def floor() -> object:
        return raw_euler(robot, T, EULER_STEP)

    def default() -> object:
        return simulate(robot, 5 * T, 1e-3)

    def acc(res: object) -> str:
        return (
            f"closures {np.max(res.closure_residual):.1e} m, energy drift "  # type: ignore[attr-defined]
            f"{res.energy_drift():.1e}, {res.projections} projections"  # type: ignore[attr-defined]
        )

    t_e, t_f, r_e = paired(euler, floor, 1, repeats=5)
    t_d, _, r_d = paired(default, floor, 1, repeats=5)
    per_s = {"euler": 1e-6 * t_e / T, "floor": 1e-6 * t_f / T, "dopri5": 1e-6 * t_d / (5 * T)}
    euler_10s = "no 10 s run"
    if long_euler:
        t0 = time.perf_counter()
        long_e = simulate(robot, 10.0, 1e-3, integrator="euler", step=EULER_STEP)
        euler_10s = f"10 s run: {time.perf_counter() - t0:.1f} s, {acc(long_e)}"
    t0 = time.perf_counter()
    long_d = simulate(robot, 10.0, 1e-3)
    wall_d = time.perf_counter() - t0
    # MuJoCo, exported model without contacts, its own 1 ms step
    mj = mujoco_model(robot, MjcfOptions(contacts=False))
    mjd = mujoco.MjData(mj)
    smap = StateMap(robot)
    steps = int(round(1.0 / mj.opt.timestep))
    mjd.qpos[:] = smap.qpos(robot.q_home)
    mujoco.mj_step(mj, mjd)
    t0 = time.process_time()
    for _ in range(steps):
        mujoco.mj_step(mj, mjd)
    t_mj = time.process_time() - t0
    return [
        (
            f'{name}: `simulate(integrator="euler", step=1e-5)` / raw Euler loop (same gains, '
            "step), per simulated second",
            f"{per_s['euler']:.2f} s vs {per_s['floor']:.2f} s: **{r_e:.2f}x**; {euler_10s}",
            "<= 1.5x, closures < 1e-8 m, drift < 0.1 %",
        ),
        (
            f"{name}: `simulate()` (dopri5, 1 ms output) / the same raw Euler loop, per simulated "
            "second",
            f"{per_s['dopri5']:.3f} s: **{r_d / 5:.2f}x**; 10 s run: {wall_d:.1f} s, {acc(long_d)}",
            "<= 3x",
        ),
        (
            f"{name}: MuJoCo `mj_step` on the exported model (contacts off, 1 ms, soft closures)",
            f"{steps / t_mj:.3g} steps/s: {t_mj:.3f} s per simulated second",
            "scale",
        ),
    ]


# --------------------------------------------------------------------------- assembly


def assembly_rows(n: int = 400) -> list[Row]:
    robot = pkdyn.load("gough_stewart", geometry=False)
    rho = gs_leg_path(robot, n)
    lean = raw_pinocchio.LeanNewton(
        robot.model, robot.constraint_models, robot.actuated_q, robot.passive_v
    )
    q0 = pkdyn.forward_geometry(robot, rho[0]).q
    iters = {"pkdyn": 0, "lean": 0}

    def public() -> None:
        q = q0
        for k in range(n):
            res = pkdyn.forward_geometry(robot, rho[k], q_init=q)
            q = res.q
            iters["pkdyn"] += res.iterations

    def floor() -> None:
        q = q0
        for k in range(n):
            q, it = lean.solve(q, rho[k])
            iters["lean"] += it

    q_pk = pkdyn.forward_geometry(robot, rho[n // 3], q_init=q0).q
    q_raw, _ = lean.solve(q0, rho[n // 3])
    agree = float(np.max(np.abs(pin.difference(robot.model, q_pk, q_raw))))
    t_pub, t_floor, ratio = paired(public, floor, 1, repeats=7)
    calls = 8 * n  # paired: a first call plus 7 timed ones
    return [
        (
            "gough_stewart: `forward_geometry()` along a path (warm-started) / lean Newton loop "
            "(one C++ Jacobian call per iteration)",
            f"{us(t_pub / n)} vs {us(t_floor / n)} per solve: **{ratio:.2f}x** "
            f"({iters['pkdyn'] / calls:.1f} vs {iters['lean'] / calls:.1f} iterations, same "
            f"configuration to {agree:.0e})",
            "<= 1.5x",
        )
    ]


# --------------------------------------------------------------------------- workspace


def _cpu_seconds() -> float:
    """CPU time of this process and of its finished children [s]."""
    own, kids = (
        resource.getrusage(resource.RUSAGE_SELF),
        resource.getrusage(resource.RUSAGE_CHILDREN),
    )
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def workspace_rows() -> list[Row]:
    out: list[Row] = []
    for name, target in (("gough_stewart", 2000), ("planar_3rrr", 1000), ("tripod", 1000)):
        robot = pkdyn.load(name)
        c0, t0 = _cpu_seconds(), time.perf_counter()
        ws = translation_workspace(robot, method="numeric", progress=False)
        el, cpu = time.perf_counter() - t0, _cpu_seconds() - c0
        out.append(
            (
                f"{name}: numeric translation workspace, default box, samples and limits",
                f"**{ws.samples / el:.3g} poses/s** ({ws.samples} poses in {el:.1f} s on "
                f"{'two processes' if ws.samples >= PARALLEL_SAMPLES else 'one process'}; "
                f"{ws.samples / cpu:.3g} poses per CPU second; {int(ws.reachable.sum())} "
                "reachable)",
                f">= {target}/s",
            )
        )
    return out


def rows() -> list[Row]:
    out: list[Row] = []
    for name in CASES:
        out += inverse_rows(name)
    for name in CASES:  # the Gough-Stewart platform's passive run is a free fall (legs unlimited)
        out += simulation_rows(name, long_euler=name == "delta")
    out += assembly_rows()
    out += workspace_rows()
    return out


if __name__ == "__main__":
    print_table(rows())
