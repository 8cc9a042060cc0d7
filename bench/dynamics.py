"""Dynamics benchmarks: forward step cost against the raw Pinocchio call, inverse dynamics.

Run ``python bench/dynamics.py``; prints a markdown table (medians of repeated runs).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import pinocchio as pin

import pkdyn
from solvers.forward_dynamics import Actuation, ForwardDynamics
from solvers.inverse_dynamics import InverseDynamics

Row = tuple[str, str, float, str]


def _time_us(fn: Callable[[], object], n: int) -> float:
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return 1e6 * (time.perf_counter() - t0) / n


def _median_us(fn: Callable[[], object], n: int, repeats: int = 7) -> float:
    return float(np.median([_time_us(fn, n) for _ in range(repeats)]))


def _ratio(
    fn: Callable[[], object], ref: Callable[[], object], n: int, n_ref: int
) -> tuple[float, float]:
    """Median time of ``fn`` [us] and median of its ratio to ``ref``, timed alternately (the
    machine load changes between runs)."""
    pairs = [(_time_us(fn, n), _time_us(ref, n_ref)) for _ in range(9)]
    return float(np.median([p[0] for p in pairs])), float(np.median([p[0] / p[1] for p in pairs]))


def _state(robot: pkdyn.Robot, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Home configuration and a velocity in the null space of the closure Jacobian."""
    q = robot.q_home
    _, J = robot.closure_set.residual_and_jacobian(robot.model.createData(), q)
    _, s, Vt = np.linalg.svd(J)
    Z = Vt[int(np.sum(s > 1e-9 * s[0])) :].T
    v = Z @ np.random.default_rng(seed).standard_normal(Z.shape[1])
    return q, 0.3 * v / np.max(np.abs(v))


def bench(name: str, n: int = 2000) -> list[Row]:
    robot = pkdyn.load(name, geometry=False)
    model = robot.model
    q, v = _state(robot)
    act = Actuation(robot.actuated_v, names=robot.actuator_names)
    zeros = np.zeros(act.n)

    def torque(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return zeros

    # raw Pinocchio call on the same model and constraints, same proximal settings
    data = model.createData()
    cms = robot.constraint_models
    cds = robot.constraint_data()
    pin.initConstraintDynamics(model, data, cms, cds)
    prox = pin.ProximalSettings(1e-12, 1e-12, 1e-6, 30)
    tau = np.zeros(model.nv)

    def raw_call() -> None:
        pin.constraintDynamics(model, data, q, v, tau, cms, cds, prox)

    raw = _median_us(raw_call, n)
    rows: list[Row] = [(name, "raw `pin.constraintDynamics`", raw, "1.00")]

    dt = 1e-3
    for integ, evals in (("euler", 1), ("rk4", 4)):
        fd = ForwardDynamics(model, cms, act, integrator=integ, project=False)
        fd.step(0.0, q, v, dt, torque)
        us, ratio = _ratio(lambda fd=fd: fd.step(0.0, q, v, dt, torque), raw_call, n // evals, n)
        rows.append((name, f"`{integ}` step, Baumgarte only", us, f"{ratio / evals:.2f}"))

    # dopri5 within simulate (first same as last: 6 evaluations per accepted substep), with
    # the closure-residual check after every step; recording decimated
    fd = ForwardDynamics(model, cms, act, integrator="dopri5")
    steps = 200
    us, ratio = _ratio(
        lambda: fd.simulate(q, v, steps * dt, dt, torque, record_every=steps), raw_call, 1, n
    )
    evals = 6.0 * (fd.steps + fd.rejected) / steps
    rows.append(
        (
            name,
            "`dopri5` output step in `simulate` + projection check",
            us / steps,
            f"{ratio / (steps * evals):.2f} ({evals:.1f} eval./step)",
        )
    )
    check = _median_us(lambda: fd.closure_set.residual(fd._kin, q), n)
    rows.append((name, "projection check (closure residual)", check, "-"))
    rng = np.random.default_rng(1)
    q_off = pin.integrate(model, q, 1e-7 * rng.standard_normal(model.nv))
    proj = _median_us(lambda: fd.project_state(q_off, v), n // 10)
    rows.append((name, "projection of q (Gauss-Newton) and v (M-metric)", proj, "-"))

    fd0 = ForwardDynamics(model, cms, act, baumgarte=(0.0, 0.0))
    a = fd0.acceleration(q, v, act.generalized(np.ones(act.n), model.nv))
    lim = np.array([x.effort for x in robot.actuators])
    inv = InverseDynamics(model, cms, act, -lim, lim)
    rows.append(
        (name, "inverse dynamics, one sample", _median_us(lambda: inv.solve(q, v, a), n // 2), "-")
    )
    return rows


def main() -> None:
    print("| robot | operation | time (us) | ratio to the raw call, per evaluation |")
    print("|---|---|---|---|")
    for name in ("delta", "gough_stewart"):
        for robot, label, us, ratio in bench(name):
            print(f"| {robot} | {label} | {us:.1f} | {ratio} |")


if __name__ == "__main__":
    main()
