"""Dynamics benchmarks against raw Pinocchio, per library robot.

- Forward dynamics, per dynamics evaluation: pkdyn's step against the raw
  ``pin.constraintDynamics`` call on the same model, constraint models (Baumgarte gains) and
  proximal settings. Euler makes one evaluation per step; ``rk4`` four; ``dopri5`` six per
  accepted or rejected substep, counted from the integrator. The adaptive step also needs the
  Lie-group maps of its Runge-Kutta-Munthe-Kaas stages (``pin.integrate``, ``pin.dDifference``):
  its cost is given against the raw call alone and against raw call + those maps.
- Inverse dynamics per sample: ``InverseDynamics.solve`` against a raw-Pinocchio solve
  (``rnea``, ``getConstraintsJacobian``, one least-squares solve of ``[S^T J^T] x = b``).

Run ``python bench/dynamics.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import raw_pinocchio
from timing import ROBOTS, Row, consistent_state, median_us, paired, print_table, us

import pkdyn
from solvers import Actuation, ForwardDynamics, InverseDynamics

_ARG1 = pin.ArgumentPosition.ARG1
STEPS = 100


def robot_rows(name: str, n: int = 1000) -> list[Row]:
    robot = pkdyn.load(name, geometry=False)
    model = robot.model
    q, v = consistent_state(robot)
    red = np.array([a.reduction for a in robot.actuators])
    act = Actuation(robot.actuated_v, gains=red, names=robot.actuator_names)
    tau0 = np.zeros(act.n)

    def torque(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return tau0

    dt = 1e-3
    fd = ForwardDynamics(model, robot.constraint_models, act, integrator="euler", project=False)
    data, cms, cds, prox = fd.data, fd.constraint_models, fd.constraint_datas, fd.prox
    zero = np.zeros(model.nv)

    def raw() -> None:
        pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)

    def raw_step() -> None:  # the same semi-implicit Euler step, raw
        a = pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)
        v1 = v + dt * a
        pin.integrate(model, q, dt * v1)

    rows: list[Row] = []
    t_euler, t_raw, r_euler = paired(lambda: fd.step(0.0, q, v, dt, torque), raw, n)
    _, t_rs, r_step = paired(lambda: fd.step(0.0, q, v, dt, torque), raw_step, n)
    rows.append(
        (
            f"{name}: forward step, `euler` (1 evaluation) vs raw `pin.constraintDynamics`",
            f"{us(t_euler)} vs {us(t_raw)}: {r_euler:.2f}x ({r_step:.2f}x a raw Euler step: "
            f"the call + state update, {us(t_rs)})",
            "<= 1.3x",
        )
    )
    fdp = ForwardDynamics(model, robot.constraint_models, act, integrator="euler")
    t_p, _, r_p = paired(lambda: fdp.step(0.0, q, v, dt, torque), raw, n)
    rows.append(
        (
            f"{name}: ... `ForwardDynamics.step` with the default `project=True` (a control "
            "loop's step checks the closures after each 1 ms step and projects above 1e-9; "
            "`simulate` checks once per output step)",
            f"{us(t_p)}: {r_p:.2f}x",
            "-",
        )
    )
    fd5 = ForwardDynamics(model, robot.constraint_models, act, integrator="dopri5")
    q2 = pin.integrate(model, q, 1e-3 * v)

    def raw_rkmk() -> None:  # what one RKMK stage needs from Pinocchio
        pin.integrate(model, q, v)
        pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)
        pin.dDifference(model, q, q2, _ARG1).dot(v)

    def run() -> None:
        fd5.simulate(q, v, STEPS * dt, dt, torque, record_every=STEPS)

    run()
    evals = 6 * (fd5.steps + fd5.rejected) + 1
    t5, _, r5 = paired(run, raw, 1, n, repeats=7)
    _, _, r_rk = paired(run, raw_rkmk, 1, n, repeats=7)
    rows.append(
        (
            f"{name}: forward step, `dopri5` in `simulate` (with closure checks), per evaluation",
            f"{us(t5 / evals)} ({evals / STEPS:.1f} eval./output step): {r5 / evals:.2f}x the "
            f"raw call, {r_rk / evals:.2f}x raw call + `integrate` + `dDifference`",
            "<= 1.3x, see notes",
        )
    )
    fd4 = ForwardDynamics(model, robot.constraint_models, act, integrator="rk4", project=False)
    t4, _, r4 = paired(lambda: fd4.step(0.0, q, v, dt, torque), raw, max(1, n // 4), n)
    rows.append(
        (
            f"{name}: forward step, `rk4` (4 evaluations), per evaluation",
            f"{us(t4 / 4)}: {r4 / 4:.2f}x",
            "-",
        )
    )
    check = median_us(lambda: fd5.closure_set.residual(fd5._kin, q), n)
    rows.append((f"{name}: closure check (residual) after an output step", us(check), "-"))
    # inverse dynamics on a consistent state
    fd0 = ForwardDynamics(model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    a = fd0.acceleration(q, v, act.generalized(np.ones(act.n), model.nv))
    inv = InverseDynamics(model, robot.constraint_models, act)
    closures = raw_pinocchio.RawClosures(model, robot.constraint_models)
    S = act.matrix(model.nv)
    kin = model.createData()
    tau_raw = raw_pinocchio.inverse_dynamics(model, kin, closures, S, q, v, a)
    assert np.allclose(inv.solve(q, v, a).tau, tau_raw, rtol=1e-8, atol=1e-9)
    t_id, t_idr, r_id = paired(
        lambda: inv.solve(q, v, a),
        lambda: raw_pinocchio.inverse_dynamics(model, kin, closures, S, q, v, a),
        max(1, n // 2),
    )
    rows.append(
        (
            f"{name}: inverse dynamics, one sample, vs raw Pinocchio (rnea + J + lstsq)",
            f"{us(t_id)} vs {us(t_idr)}: {r_id:.2f}x",
            "-",
        )
    )
    return rows


XARM_HAND = Path(__file__).resolve().parents[1] / "tests/data/public/menagerie_xarm7_hand/hand.xml"


def coupled_rows(n: int = 1000) -> list[Row]:
    """A robot with a joint coupling: Pinocchio's call on the closures plus the couplings' forces.

    The UFACTORY xArm7 gripper (two point closures and the drivers' coupling): one evaluation
    (three ``pin.constraintDynamics`` calls, see :mod:`solvers.forward_dynamics`) against the raw
    call on its two closures alone (the same robot without the coupling, which Pinocchio cannot
    take).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its tendon actuator is left out
        robot = pkdyn.load(XARM_HAND, geometry=False)
    model = robot.model
    q, v = consistent_state(robot)
    zero = np.zeros(model.nv)
    fd = ForwardDynamics(model, robot.constraint_models, couplings=robot.closure_set.couplings)
    rigid = ForwardDynamics(model, robot.constraint_models)
    data, cms, cds, prox = rigid.data, rigid.constraint_models, rigid.constraint_datas, rigid.prox

    def raw() -> None:
        pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)

    t, t_raw, r = paired(lambda: fd._accel(q, v, zero), raw, n)
    return [
        (
            "xArm7 gripper (2 closures + 1 coupling, nv = 6): forward evaluation (3 calls: "
            "closures, probe, coupling force) vs one raw `pin.constraintDynamics` call on the 2 "
            "closures without the coupling",
            f"{us(t)} vs {us(t_raw)}: {r:.2f}x",
            "- (robots without couplings keep the raw call)",
        )
    ]


def rows() -> list[Row]:
    out: list[Row] = []
    for name in ROBOTS:
        out += robot_rows(name)
    return out + coupled_rows()


if __name__ == "__main__":
    print_table(rows())
