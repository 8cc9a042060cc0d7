"""Vectorised kinematics of sampled states and the batched inverse dynamics, against slow paths.

- :class:`solvers.SampledKinematics`: closure residuals, velocity and acceleration errors of many
  states at once equal :class:`solvers.ClosureSet`'s residual, ``J v`` and ``J a + drift`` state
  by state (points), and the time derivative of the velocity error along the motion (central
  finite differences, welds included); frame wrenches equal ``platform_jacobian^T W``.
- :meth:`solvers.InverseDynamics.trajectory` (batched) equals :meth:`~solvers.InverseDynamics.solve`
  sample by sample (the reference path), refuses inconsistent samples at the right sample and
  closure, and reports an infeasible sample before a later inconsistent one.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.kinematics import platform_jacobian
from pkdyn.dynamics import actuation, inverse_dynamics
from pkdyn.dynamics.trajectory import JointTrajectory, named_trajectory
from pkdyn.exceptions import InfeasibleEffortError, TrajectoryError
from solvers import (
    ForwardDynamics,
    InconsistentMotionError,
    InfeasibleError,
    InverseDynamics,
    SampledKinematics,
)

CLOSURES = Path(__file__).parent / "data" / "closures"
ROBOTS = ["delta", "gough_stewart", "planar_3rrr", "five_bar", "tripod"]


def _capture(robot, sk, states):
    data = robot.model.createData()
    for k, (q, v, a) in enumerate(states):
        pin.rnea(robot.model, data, q, v, a)
        pin.computeJointJacobians(robot.model, data, q)
        sk.capture(k, data)


@pytest.mark.parametrize("name", [*ROBOTS, "rssr_point", "four_bar_hinge", "weld_universal"])
def test_closure_errors_equal_the_closure_set_state_by_state(name):
    """Random, unassembled states: residuals exact; point rows of the velocity and acceleration
    errors equal J v and J a + drift; weld rows equal Jlog6^-1 J v (the relative twist)."""
    path = CLOSURES / f"{name}.urdf"
    robot = pkdyn.load(str(path) if path.exists() else name, geometry=False)
    model, cs = robot.model, robot.closure_set
    rng = np.random.default_rng(3)
    states = [
        (
            pin.integrate(model, robot.q_home, 0.3 * rng.standard_normal(model.nv)),
            rng.standard_normal(model.nv),
            rng.standard_normal(model.nv),
        )
        for _ in range(4)
    ]
    sk = SampledKinematics(model, cs, size=8)
    _capture(robot, sk, states)
    V = np.array([s[1] for s in states])
    r, ev, ea = sk.closure_errors(len(states), V)
    data = model.createData()
    for k, (q, v, a) in enumerate(states):
        r0, J = cs.residual_and_jacobian(data, q)
        gamma = cs.drift(data, q, v)
        np.testing.assert_allclose(r[k], r0, rtol=0, atol=1e-14)
        for i, kind in enumerate(cs.kinds):  # point-like rows: every kind but a full weld
            rows = slice(cs.offsets[i], cs.offsets[i + 1])
            if kind != "weld" or cs.sizes[i] != 6:
                np.testing.assert_allclose(ev[k, rows], (J @ v)[rows], rtol=0, atol=1e-12)
                np.testing.assert_allclose(ea[k, rows], (J @ a + gamma)[rows], rtol=0, atol=1e-11)
            else:
                twist = np.linalg.solve(pin.Jlog6(pin.exp6(r0[rows])), (J @ v)[rows])
                np.testing.assert_allclose(ev[k, rows], twist, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("name", "kw"),
    [
        *[(n, {}) for n in ROBOTS],
        ("delta", {"bar_joint": "universal"}),
        ("rssr_point", {}),
        ("four_bar_hinge", {}),
        ("weld_universal", {}),
    ],
)
def test_batched_residuals_jacobians_and_drift_equal_the_closure_set(name, kw):
    """The fast captures (one Pinocchio call per sample): residuals and Jacobians of random,
    unassembled states equal ClosureSet's (points and welds); the drift from the time variation
    of the world Jacobian (universal joints split in two revolute joints) equals the drift from
    rnea's accelerations (:meth:`capture`) and, on point rows, ClosureSet's ``gamma``."""
    path = CLOSURES / f"{name}.urdf"
    robot = pkdyn.load(str(path) if path.exists() else name, geometry=False, **kw)
    model, cs = robot.model, robot.closure_set
    rng = np.random.default_rng(4)
    qs = [pin.integrate(model, robot.q_home, 0.3 * rng.standard_normal(model.nv)) for _ in range(5)]
    V = rng.standard_normal((5, model.nv))
    sk = SampledKinematics(model, cs, size=8)
    for k, q in enumerate(qs):
        sk.capture_configuration(k, q)
    r, J = sk.residuals_and_jacobians(np.arange(5))
    data = model.createData()
    for k, q in enumerate(qs):
        r0, J0 = cs.residual_and_jacobian(data, q)
        np.testing.assert_allclose(r[k], r0, rtol=0, atol=1e-14)
        np.testing.assert_allclose(J[k], J0, rtol=0, atol=1e-12)
    for k, q in enumerate(qs):
        sk.capture_drift(k, q, V[k])
    fast = sk.acceleration_errors(5, V)
    ref = SampledKinematics(model, cs, size=8)  # rnea's accelerations
    _capture(robot, ref, [(q, V[k], np.zeros(model.nv)) for k, q in enumerate(qs)])
    np.testing.assert_allclose(fast, ref.acceleration_errors(5, V), rtol=0, atol=1e-11)
    for k, q in enumerate(qs):
        gamma = cs.drift(data, q, V[k])
        for i, kind in enumerate(cs.kinds):  # point-like rows: every kind but a full weld
            rows = slice(cs.offsets[i], cs.offsets[i + 1])
            if kind != "weld" or cs.sizes[i] != 6:
                np.testing.assert_allclose(fast[k, rows], gamma[rows], rtol=0, atol=1e-11)


@pytest.mark.parametrize("name", ["gough_stewart", "weld_universal"])
def test_acceleration_error_is_the_rate_of_the_velocity_error(name):
    """Along q(t) = q (+) (t v + t^2/2 a), v(t) = v + t a from a closure-consistent velocity, the
    acceleration error is d/dt of the velocity error (central differences, h = 1e-6): the
    joint bias accelerations (universal joints) and the weld rows included."""
    path = CLOSURES / f"{name}.urdf"
    robot = pkdyn.load(str(path) if path.exists() else name, geometry=False)
    model, cs = robot.model, robot.closure_set
    rng = np.random.default_rng(5)
    q = pkdyn.project(
        robot, pin.integrate(model, robot.q_home, 0.1 * rng.standard_normal(model.nv))
    )
    J = cs.jacobian(model.createData(), q)
    _, s, Vt = np.linalg.svd(J)
    Z = Vt[int(np.sum(s > 1e-9 * s[0])) :].T
    v = Z @ rng.standard_normal(Z.shape[1])
    a = rng.standard_normal(model.nv)
    h = 1e-6
    states = [
        (pin.integrate(model, q, t * v + 0.5 * t * t * a), v + t * a, a) for t in (-h, 0.0, h)
    ]
    sk = SampledKinematics(model, cs, size=3)
    _capture(robot, sk, states)
    _, ev, ea = sk.closure_errors(3, np.array([x[1] for x in states]))
    rate = (ev[2] - ev[0]) / (2 * h)
    assert np.max(np.abs(ea[1] - rate)) < 1e-6 * max(1.0, np.max(np.abs(ea[1])))


def test_frame_force_is_the_platform_jacobian_transpose_times_the_wrench():
    robot = pkdyn.load("gough_stewart", geometry=False)
    model = robot.model
    rng = np.random.default_rng(2)
    qs = [pin.integrate(model, robot.q_home, 0.2 * rng.standard_normal(model.nv)) for _ in range(3)]
    W = rng.standard_normal((3, 6))
    sk = SampledKinematics(model, robot.closure_set, frames=(robot.platform_frame,), size=3)
    _capture(robot, sk, [(q, np.zeros(model.nv), np.zeros(model.nv)) for q in qs])
    g = sk.frame_force(3, robot.platform_frame, W)
    for k, q in enumerate(qs):
        np.testing.assert_allclose(g[k], platform_jacobian(robot, q).T @ W[k], atol=1e-12)


# --------------------------------------------------------------------------- batched solve


@pytest.fixture(scope="module")
def delta_cycle():
    robot = pkdyn.load("delta", geometry=False)
    return robot, named_trajectory(robot, "adept", cycle_time=0.6, dt=2e-3)


@pytest.mark.parametrize("name", ROBOTS)
def test_batched_trajectory_equals_the_state_by_state_solve(name):
    """Efforts, closure forces, residuals and energies of the batched path equal ``solve`` and
    ``computeKineticEnergy`` / ``computePotentialEnergy`` sample by sample (motor-side gains)."""
    robot = pkdyn.load(name, geometry=False)
    model = robot.model
    act = actuation(robot)
    act.gains = np.array([1.0 + 0.5 * k for k in range(act.n)])
    fd = ForwardDynamics(model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    rng = np.random.default_rng(7)
    Q, V, A = [], [], []
    data = model.createData()
    for _ in range(6):
        q = pkdyn.project(
            robot, pin.integrate(model, robot.q_home, 0.05 * rng.standard_normal(model.nv))
        )
        J = robot.closure_set.jacobian(data, q)
        _, s, Vt = np.linalg.svd(J)
        v = Vt[int(np.sum(s > 1e-9 * s[0])) :].T @ rng.standard_normal(
            model.nv - int(np.sum(s > 1e-9 * s[0]))
        )
        Q.append(q)
        V.append(v)
        A.append(fd.acceleration(q, v, act.generalized(rng.standard_normal(act.n), model.nv)))
    Q, V, A = np.array(Q), np.array(V), np.array(A)
    inv = InverseDynamics(model, robot.constraint_models, act)
    out = inv.trajectory(Q, V, A, check_tol=1e-7)
    ref = InverseDynamics(model, robot.constraint_models, act)
    for k in range(len(Q)):
        x = ref.solve(Q[k], V[k], A[k])
        scale = np.max(np.abs(x.tau))
        np.testing.assert_allclose(out.tau[k], x.tau, rtol=0, atol=1e-11 * scale)
        lam = np.max(np.abs(x.constraint_forces))
        np.testing.assert_allclose(out.constraint_forces[k], x.constraint_forces, atol=1e-11 * lam)
        assert out.residual[k] < 1e-9 * max(1.0, scale)
        assert out.kinetic[k] == pytest.approx(pin.computeKineticEnergy(model, data, Q[k], V[k]))
        assert out.potential[k] == pytest.approx(pin.computePotentialEnergy(model, data, Q[k]))


def test_public_inverse_dynamics_refuses_inconsistent_samples_in_any_batch(delta_cycle):
    """Sample 280 (second batch of the solver) broken in position, velocity or acceleration:
    refused with the sample, the time and the closure named, nothing else computed."""
    robot, jt = delta_cycle
    k = 280
    for what, field, delta in (
        ("configuration", "q", 1e-4),
        ("velocity", "v", 1e-3),
        ("acceleration", "a", 1e-2),
    ):
        arrays = {"q": jt.q.copy(), "v": jt.v.copy(), "a": jt.a.copy()}
        arrays[field][k, robot.passive_v[0] if field != "q" else robot.passive_v[0] + 1] += delta
        bad = JointTrajectory(
            jt.t, arrays["q"], arrays["v"], arrays["a"], jt.actuated_q, jt.actuated_v
        )
        with pytest.raises(
            TrajectoryError, match=rf"sample {k} .*{what} does not satisfy closure '"
        ):
            inverse_dynamics(robot, bad)


def test_an_earlier_infeasible_sample_is_reported_before_an_inconsistent_one(delta_cycle):
    robot, jt = delta_cycle
    free = inverse_dynamics(robot, jt)
    limit = 0.9 * float(np.max(np.abs(free.tau)))
    first = int(np.flatnonzero(np.max(np.abs(free.tau), axis=1) > limit)[0])
    assert first > 3
    weak = pkdyn.load("delta", geometry=False, effort=limit)
    a = jt.a.copy()
    a[first + 2, robot.passive_v[0]] += 1.0
    bad = JointTrajectory(jt.t, jt.q, jt.v, a, jt.actuated_q, jt.actuated_v)
    with pytest.raises(InfeasibleEffortError) as info:
        inverse_dynamics(weak, bad, limits=True)
    assert info.value.sample == first
    a[first - 3, robot.passive_v[0]] += 1.0  # now an inconsistent sample comes first
    bad = JointTrajectory(jt.t, jt.q, jt.v, a, jt.actuated_q, jt.actuated_v)
    with pytest.raises(TrajectoryError, match=f"sample {first - 3} "):
        inverse_dynamics(weak, bad, limits=True)


def test_solver_check_raises_its_own_error_with_the_closure():
    robot = pkdyn.load("five_bar", geometry=False)
    jt = named_trajectory(robot, "sine", dt=1e-2)
    inv = InverseDynamics(robot.model, robot.constraint_models, actuation(robot))
    V = jt.v.copy()
    V[3, robot.passive_v[0]] += 0.1
    with pytest.raises(InconsistentMotionError) as err:
        inv.trajectory(jt.q, V, jt.a, check_tol=1e-7, first_sample=100)
    e = err.value
    assert (e.sample, e.what) == (103, "velocity") and e.closure in robot.closure_set.names
    assert e.error > 1e-3
    # without the check the sample is solved (by the one-by-one path when needed)
    assert np.all(np.isfinite(inv.trajectory(jt.q, V, jt.a).tau))


def test_bounds_fall_back_to_the_general_path_and_name_the_sample():
    """Effort bounds hit inside a batch: the batched elimination steps aside and the general
    path raises at the first sample out of bounds, as the state-by-state loop does."""
    robot = pkdyn.load("five_bar", geometry=False)
    jt = named_trajectory(robot, "sine", dt=2e-3)
    act = actuation(robot)
    free = InverseDynamics(robot.model, robot.constraint_models, act).trajectory(jt.q, jt.v, jt.a)
    lim = 0.7 * np.max(np.abs(free.tau), axis=0)
    first = int(np.flatnonzero(np.any(np.abs(free.tau) > lim, axis=1))[0])
    inv = InverseDynamics(robot.model, robot.constraint_models, act, -lim, lim)
    with pytest.raises(InfeasibleError) as err:
        inv.trajectory(jt.q, jt.v, jt.a)
    assert err.value.sample == first
