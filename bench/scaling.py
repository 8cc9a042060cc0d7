"""Cost that grows like the robot (issue 36 item 5): the URDF+ ladder and legged robots.

The models are the public URDF+ files of ``tests/data/public/generalized_rbda/``: the ladder of
parallel chains (``implicit``: two chains of depth D joined by a connecting rod, one planar
loop, nv = 2D + 1; ``explicit``: the same chains tied by a coupling of the sums of L/2 joints
of each, nv = 2D), depths 5 to 40, loop sizes 3 to 41, and the legged robots (couplings of
rotors to sums of joints, floating bases). Per model, as users call them:

- **set-up per call**: the fixed cost of a public call, measured as the call on one sample or
  one step (the median of repeated calls on one robot: what every call after the robot's first
  costs): ``pkdyn.dynamics.inverse_dynamics`` (a trajectory of one sample; its solver and
  sampled kinematics are kept by the robot, :mod:`pkdyn.model.reuse`), a forward simulation
  ``simulate(..., integrator="euler")`` of one step. Target: <= 2 ms at every size;
- **inverse dynamics per sample**: the marginal cost of ``inverse_dynamics`` over a 200-sample
  trajectory (made by a forward simulation under sinusoidal efforts, so that every model,
  floating bases included, has a consistent one) against the floor, the plainest per-sample
  loop (``rnea``, the C++ constraint Jacobian and the coupling rows, the normal equations of the
  passive rows);
- **forward dynamics per step**: ``solvers.ForwardDynamics.step`` (``euler``) against the
  floor, one ``pin.constraintDynamics`` call (closures only) or one dense KKT solve of
  ``crba``, ``nle`` and the constant coupling rows (couplings only; linear couplings have no
  drift); also against a raw Euler step (that floor and the state update ``v + h a``,
  ``pin.integrate``, which every step makes: on the smallest models they cost about as much
  as the floor itself).

Targets: set-up <= 2 ms, per-sample ratios <= 1.5x, per-sample cost linear in nv (the columns
``us/nv``). Times are CPU times of this process (``bench/timing.py``).

Run ``python bench/scaling.py``; prints the rows as a markdown table.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import raw_pinocchio
from timing import Row, paired, print_table, us

import pkdyn
from pkdyn.dynamics import actuation, inverse_dynamics, simulate
from pkdyn.dynamics.joint_motion import actuator_trajectory
from pkdyn.dynamics.trajectory import JointTrajectory
from pkdyn.model.description import LinearCouplingSpec
from solvers import ForwardDynamics

DATA = Path(__file__).resolve().parent.parent / "tests/data/public/generalized_rbda"

LADDER = (
    "parallel_chains/implicit_depth5_loop_size3.urdf",
    "parallel_chains/implicit_depth5_loop_size11.urdf",
    "parallel_chains/implicit_depth10_loop_size13.urdf",
    "parallel_chains/implicit_depth20_loop_size21.urdf",
    "parallel_chains/implicit_depth40_loop_size41.urdf",
    "parallel_chains/explicit_depth5_loop_size2.urdf",
    "parallel_chains/explicit_depth5_loop_size10.urdf",
    "parallel_chains/explicit_depth10_loop_size12.urdf",
    "parallel_chains/explicit_depth20_loop_size20.urdf",
    "parallel_chains/explicit_depth40_loop_size40.urdf",
)
LEGGED = (
    "robot-models/mini_cheetah.urdf",
    "robot-models/mit_humanoid.urdf",
    "robot-models/jvrc1_humanoid.urdf",
    "robot-models/tello_humanoid.urdf",
)
SET_UP_TARGET_MS = 2.0
RATIO_TARGET = 1.5
SAMPLES = 200


def _cpu_ms(fn, repeats: int = 9) -> float:
    """Median CPU time of one call [ms], after a first call (the robot's first is apart)."""
    fn()
    out = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        out.append(time.process_time() - t0)
    return 1e3 * float(np.median(out))


def _coupling_rows(robot: pkdyn.Robot) -> np.ndarray:
    """The constant rows of the linear couplings (sum_i c_i q_i = b), hand-written."""
    model = robot.model
    rows = []
    for c in robot.couplings:
        if not isinstance(c, LinearCouplingSpec):
            raise NotImplementedError("polynomial couplings")
        row = np.zeros(model.nv)
        for joint, coef in c.terms:
            row[model.joints[model.getJointId(joint)].idx_v] += float(coef)
        rows.append(row)
    return np.array(rows).reshape(-1, model.nv)


def _trajectory(robot: pkdyn.Robot, n: int) -> JointTrajectory:
    """A consistent trajectory of ``n`` samples.

    With loops: the actuators moved along sines (:func:`actuator_trajectory`, the passive
    joints assembled); without (a floating base, couplings): a forward simulation under sine
    efforts (its accelerations are the dynamics' own).
    """
    n_a = len(robot.actuators)
    if robot.constraints.nc:
        t = np.arange(n) * 1e-3
        w = 2 * np.pi
        s = np.sin(w * t)[:, None] * np.ones(n_a)
        qa = robot.q_home[robot.actuated_q] + 0.05 * s
        qd = 0.05 * w * np.cos(w * t)[:, None] * np.ones(n_a)
        return actuator_trajectory(robot, t, qa, qd, -(w**2) * 0.05 * s)
    amp = 0.2 * np.ones(n_a)

    def torque(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return amp * np.sin(2 * np.pi * t)

    dt = 1e-3
    res = simulate(robot, n * dt, dt, torque=torque, integrator="euler", step=dt / 4)
    k = slice(1, n + 1)
    return JointTrajectory(
        res.t[k], res.q[k], res.v[k], res.a[k], robot.actuated_q, robot.actuated_v
    )


def model_rows(path: str) -> list[Row]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = pkdyn.load(DATA / path, geometry=False)
    model = robot.model
    nv = robot.nv
    name = Path(path).stem
    rows: list[Row] = []
    act = actuation(robot) if robot.actuators else None
    # ------------------------------------------------------------- set-up per call
    setups = []
    if robot.actuators:
        traj = _trajectory(robot, SAMPLES)
        one = JointTrajectory(
            traj.t[:1], traj.q[:1], traj.v[:1], traj.a[:1], robot.actuated_q, robot.actuated_v
        )
        setups.append(("inverse_dynamics", _cpu_ms(lambda: inverse_dynamics(robot, one))))
    setups.append(("simulate", _cpu_ms(lambda: simulate(robot, 1e-3, 1e-3, integrator="euler"))))
    worst = max(t for _, t in setups)
    rows.append(
        (
            f"{name} (nv {nv}): set-up per call",
            ", ".join(f"{k} {t:.2f} ms" for k, t in setups),
            f"<= {SET_UP_TARGET_MS:g} ms: {'yes' if worst <= SET_UP_TARGET_MS else '**no**'}",
        )
    )
    # ------------------------------------------------------------- inverse dynamics
    if robot.actuators:
        closures = raw_pinocchio.RawClosures(model, robot.constraint_models)
        C = _coupling_rows(robot)
        data = model.createData()
        va = robot.actuated_v
        vp = np.setdiff1d(np.arange(nv), va)

        def floor() -> None:
            for k in range(traj.t.size):
                b = pin.rnea(model, data, traj.q[k], traj.v[k], traj.a[k])
                J = closures.jacobian(data, traj.q[k]) if closures.nc else np.zeros((0, nv))
                J = np.vstack([J, C])
                Jp = J[:, vp]
                lam = np.linalg.lstsq(Jp @ Jp.T, Jp @ b[vp], rcond=None)[0]
                b[va] - J[:, va].T @ lam

        def public() -> None:
            inverse_dynamics(robot, traj)

        t_pub, t_floor, ratio = paired(public, floor, 1, repeats=5)
        t_all, t_one, _ = paired(public, lambda: inverse_dynamics(robot, one), 1, repeats=5)
        per = (t_all - t_one) / (traj.t.size - 1)  # the call's marginal cost per sample
        rows.append(
            (
                f"... inverse dynamics per sample ({traj.t.size} samples)",
                f"{us(per)} ({per / nv:.2f} us/nv) vs floor {us(t_floor / traj.t.size)}: "
                f"{per / (t_floor / traj.t.size):.2f}x",
                f"<= {RATIO_TARGET:g}x (the whole call: {ratio:.2f}x)",
            )
        )
    # ------------------------------------------------------------- forward dynamics
    fd = ForwardDynamics(model, robot.constraints, act, integrator="euler", project=False)
    q = robot.q_home
    v = np.zeros(nv)
    tau = np.zeros(len(robot.actuators))

    def torque(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return tau

    step = (lambda: fd.step(0.0, q, v, 1e-3, torque)) if act is not None else None
    if step is None:
        step = lambda: fd.step(0.0, q, v, 1e-3)  # noqa: E731
    C = _coupling_rows(robot)
    if robot.constraints.nc and C.shape[0]:
        rows.append(("... forward dynamics per step", "(closures and couplings: no floor)", "-"))
        return rows
    data = model.createData()
    zero = np.zeros(nv)
    if robot.constraints.nc:
        cms, prox = fd.constraint_models, fd.prox
        cds = pin.StdVec_RigidConstraintData()
        for cm in cms:
            cds.append(cm.createData())
        pin.initConstraintDynamics(model, data, cms, cds)

        def floor_fd() -> np.ndarray:
            return pin.constraintDynamics(model, data, q, v, zero, cms, cds, prox)

        what = "pin.constraintDynamics"
    else:
        m = C.shape[0]

        def floor_fd() -> np.ndarray:
            M = pin.crba(model, data, q)
            M = np.triu(M) + np.triu(M, 1).T
            h = pin.nle(model, data, q, v)
            K = np.block([[M, C.T], [C, np.zeros((m, m))]])
            return np.linalg.solve(K, np.concatenate([-h, np.zeros(m)]))[:nv]

        what = "a dense KKT solve"

    def raw_step() -> None:  # the floor and the state update any Euler step makes
        v1 = v + 1e-3 * floor_fd()
        pin.integrate(model, q, 1e-3 * v1)

    t_fd, t_ff, r_fd = paired(step, floor_fd, 200, repeats=5)
    _, t_raw, r_raw = paired(step, raw_step, 200, repeats=5)
    rows.append(
        (
            "... forward dynamics per step (`euler`)",
            f"{us(t_fd)} ({t_fd / nv:.2f} us/nv) vs {what} {us(t_ff)}: {r_fd:.2f}x "
            f"(vs that and the state update, a raw Euler step {us(t_raw)}: {r_raw:.2f}x)",
            f"<= {RATIO_TARGET:g}x",
        )
    )
    return rows


def rows() -> list[Row]:
    out: list[Row] = []
    for path in (*LADDER, *LEGGED):
        try:
            out += model_rows(path)
        except Exception as err:  # noqa: BLE001 - one model's failure must not hide the others
            out.append((Path(path).stem, f"failed: {type(err).__name__}: {err}"[:200], "-"))
    return out


if __name__ == "__main__":
    import sys

    if len(sys.argv) > 1:
        LADDER = tuple(a for a in sys.argv[1:] if "parallel" in a)  # noqa: F811
        LEGGED = tuple(a for a in sys.argv[1:] if "parallel" not in a)  # noqa: F811
    print_table(rows())
