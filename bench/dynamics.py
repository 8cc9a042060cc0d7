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

import time
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
    loop = ControlLoop(robot)
    t_pk, t_rw, r_loop = paired(loop.pkdyn_batch, loop.raw_batch, 1, repeats=11)
    rows.append(
        (
            f"{name}: control-loop step, `ForwardDynamics.step` (`euler`, default `project=True`: "
            "ends each 1 ms step on the closures) vs a raw Euler step, PD tracking loop",
            f"{us(t_pk / loop.batch)} vs {us(t_rw / loop.batch)}: **{r_loop:.2f}x**",
            "<= 2x (Delta, Gough-Stewart)",
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


class ControlLoop:
    """A 1 ms control loop: PD tracking of a 1 Hz sine (0.05 rad or m) on every actuator.

    Gains: a 40 rad/s critically damped loop on each actuator's effective inertia at home
    (closures included), plus the efforts holding home (at 20 rad/s the Gough-Stewart's
    platform yaw is too weakly held: it drifts into large motions after 4 s). The pkdyn side
    calls ``ForwardDynamics.step(t, q, v, 1e-3, tau)`` (``euler`` with the default projection:
    the control-loop step of ``solvers/control_step.py``); the raw side the same controller,
    ``pin.constraintDynamics`` with the same gains and proximal settings, and the update
    ``v + h a``, ``integrate(q, h v)`` (no drift control: its closures open). Each side
    continues its own state from batch to batch.
    """

    batch = 100
    h = 1e-3

    def __init__(self, robot: pkdyn.Robot, passive: bool = False) -> None:
        model = robot.model
        self.model = model
        self.robot = robot
        qa, va = robot.actuated_q, robot.actuated_v
        q0 = robot.q_home.copy()
        act = Actuation(va, names=robot.actuator_names)
        # effective inertia of each actuator (closures included) and the efforts holding home
        fd0 = ForwardDynamics(model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
        z = np.zeros(model.nv)
        a0 = fd0.acceleration(q0, z, z)[va]
        unit = np.eye(act.n)
        m_a = np.array(
            [1.0 / (fd0.acceleration(q0, z, act.generalized(unit[i], model.nv))[va[i]] - a0[i])
             for i in range(act.n)]
        )  # fmt: skip
        hold = InverseDynamics(model, robot.constraint_models, act).solve(q0, z, z).tau
        w = 40.0
        kp, kd = w * w * m_a, 2.0 * w * m_a
        amp, f = 0.05, 1.0

        def tau(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
            s, c = np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)
            ref = q0[qa] + amp * s
            return hold + kp * (ref - q[qa]) + kd * (amp * 2 * np.pi * f * c - v[va])

        def free(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
            return np.zeros(len(va))

        self.tau = free if passive else tau
        self.fd = ForwardDynamics(model, robot.constraint_models, act, integrator="euler")
        self.raw = ForwardDynamics(model, robot.constraint_models, act, integrator="euler")
        self.raw._euler_gains(self.h)
        q, v = self.fd.project_state(q0, np.zeros(model.nv))
        self.pk_state = (q, v, 0.0)
        self.raw_state = (q, v, 0.0)

    def pkdyn_batch(self, n: int | None = None) -> None:
        q, v, t = self.pk_state
        step, tau, h = self.fd.step, self.tau, self.h
        for _ in range(n or self.batch):
            q, v = step(t, q, v, h, tau)
            t += h
        self.pk_state = (q, v, t)

    def raw_batch(self, n: int | None = None) -> None:
        q, v, t = self.raw_state
        model, h, tau, va, fd = self.model, self.h, self.tau, self.robot.actuated_v, self.raw
        data, cms, cds, prox = fd.data, fd.constraint_models, fd.constraint_datas, fd.prox
        for _ in range(n or self.batch):
            g = np.zeros(model.nv)
            g[va] = tau(t, q, v)
            a = pin.constraintDynamics(model, data, q, v, g, cms, cds, prox)
            v = v + h * a
            q = pin.integrate(model, q, h * v)
            t += h
        self.raw_state = (q, v, t)

    def run(self, seconds: float) -> tuple[float, float, float]:
        """Both loops over ``seconds`` from their states: worst closure residuals [m], CPU ratio."""
        steps = int(round(seconds / self.h))
        cs, kin = self.robot.closure_set, self.model.createData()
        worst = [0.0, 0.0]
        times = [0.0, 0.0]
        for k, batch in enumerate((self.pkdyn_batch, self.raw_batch)):
            for _ in range(steps):
                t0 = time.process_time()
                batch(1)
                times[k] += time.process_time() - t0
                q = (self.pk_state, self.raw_state)[k][0]
                worst[k] = max(worst[k], float(np.max(np.abs(cs.residual(kin, q)))))
        return worst[0], worst[1], times[0] / times[1]


def control_loop_rows(seconds: float = 10.0) -> list[Row]:
    """The 10 s control loops of the Delta and the Gough-Stewart: closures kept, cost."""
    out: list[Row] = []
    robots = {name: pkdyn.load(name, geometry=False) for name in ("delta", "gough_stewart")}
    # (the passive Gough-Stewart falls through a singularity: not a control loop)
    for name, passive in (("delta", False), ("delta", True), ("gough_stewart", False)):
        loop = ControlLoop(robots[name], passive)
        pk, raw, ratio = loop.run(seconds)
        c = loop.fd._control
        assert c is not None
        what = "falling (actuators free)" if passive else "PD tracking"
        out.append(
            (
                f"{name}: {seconds:g} s control loop at 1 ms, {what}: closure residual after "
                "each step, `ForwardDynamics.step` vs the raw Euler loop",
                f"{pk:.1e} m vs {raw:.1e} m; {ratio:.2f}x its CPU time; {c.measured} extra "
                f"residual checks, {c.projections} projections in {c.steps} steps",
                "<= 1e-9 m, <= 2x",
            )
        )
    return out


XARM_HAND = Path(__file__).resolve().parents[1] / "tests/data/public/menagerie_xarm7_hand/hand.xml"


def coupled_rows(n: int = 1000) -> list[Row]:
    """A robot with a joint coupling: Pinocchio's call on the closures plus the couplings' forces.

    The UFACTORY xArm7 gripper (two point closures and the drivers' coupling): one evaluation
    (one ``pin.constraintDynamics`` call and the couplings' response from its factorization, see
    :mod:`solvers.coupled_dynamics`) against the raw call on its two closures alone (the same
    robot without the coupling, which Pinocchio cannot take).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its tendon actuator is left out
        robot = pkdyn.load(XARM_HAND, geometry=False)
    model = robot.model
    q, v = consistent_state(robot)
    zero = np.zeros(model.nv)
    fd = ForwardDynamics(model, robot.constraints)
    rigid = ForwardDynamics(model, robot.constraint_models)
    data, cms, cds, prox = rigid.data, rigid.constraint_models, rigid.constraint_datas, rigid.prox

    def raw() -> None:
        pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)

    t, t_raw, r = paired(lambda: fd._accel(q, v, zero), raw, n)
    return [
        (
            "xArm7 gripper (2 closures + 1 coupling, nv = 6): forward evaluation (one call and "
            "the coupling's response from its factorization) vs one raw `pin.constraintDynamics` "
            "call on the 2 closures without the coupling",
            f"{us(t)} vs {us(t_raw)}: {r:.2f}x",
            "- (robots without couplings keep the raw call)",
        )
    ]


def rows() -> list[Row]:
    out: list[Row] = []
    for name in ROBOTS:
        out += robot_rows(name)
    return out + control_loop_rows() + coupled_rows()


if __name__ == "__main__":
    print_table(rows())
