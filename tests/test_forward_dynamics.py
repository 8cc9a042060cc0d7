"""Constrained forward dynamics: energy, closures, power balance, drift control, friction."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import null_space, parallelogram_normals_det, simpson_work

import pkdyn
from solvers.conditioning import NEAR_SINGULAR, THROUGH
from solvers.forward_dynamics import (
    Actuation,
    ForwardDynamics,
    IntegrationError,
    PassiveForces,
    simulate,
)

ROBOTS = ("delta", "five_bar", "gough_stewart")


@pytest.fixture(scope="module")
def robots() -> dict[str, pkdyn.Robot]:
    return {name: pkdyn.load(name, geometry=False) for name in ROBOTS}


def _tangent_velocity(robot: pkdyn.Robot, q: np.ndarray, vmax: float, seed: int = 0):
    """A velocity in the null space of the closure Jacobian, largest component ``vmax``.

    A seeded random velocity projected onto the null space (``N N^T r``): the projector is
    unique, where a basis ``N`` is not (the SVD's choice of basis vectors in a repeated or
    near-repeated singular subspace depends on the BLAS kernel, and combining its columns with
    random coefficients gave each kernel another initial velocity).
    """
    J = robot.closure_set.jacobian(robot.model.createData(), q)
    N = null_space(J)
    v = N @ (N.T @ np.random.default_rng(seed).standard_normal(robot.nv))
    return vmax * v / np.max(np.abs(v))


def _actuation(robot: pkdyn.Robot, gains: bool = False) -> Actuation:
    g = [a.reduction for a in robot.actuators] if gains else None
    return Actuation(robot.actuated_v, g, robot.actuator_names)


# --------------------------------------------------------------------------- passive runs


@pytest.mark.parametrize("name", ROBOTS)
def test_passive_run_keeps_energy_and_closures(robots, name):
    """Free fall under gravity from home with a small velocity tangent to the closures.

    Nothing but gravity works: the mechanical energy is constant. The claims hold up to the
    first passage through a singularity (``valid_until``; the whole run when there is none):
    the falling Delta crosses the singularity of its closures where the normals of its three
    parallelograms become coplanar (``test_free_delta_crossings_are_reported``) after 0.4 s;
    the five-bar (horizontal: gravity does no work on it) and the hexapod cross none. The
    README's "passive 10 s simulations: drift < 1e-7, closures < 1e-9 m" is this test's bound.
    """
    robot = robots[name]
    v0 = _tangent_velocity(robot, robot.q_home, 0.5)
    res = simulate(robot.model, robot.constraint_models, robot.q_home, v0, 2.0, 1e-3)
    assert res.t[-1] == pytest.approx(2.0)
    until = res.valid_until
    n = int(np.searchsorted(res.t, until, side="right"))
    assert until > 0.3  # long enough for gravity to do work
    # closures: projected back at every output step above 1e-9 m, whatever the passages
    assert np.max(res.closure_residual) <= 1e-9
    # recorded: drift 1.8e-10 (Delta, up to 0.407 s), 6e-15 (five-bar), 2e-11 (hexapod)
    drift = np.max(np.abs(res.energy[:n] - res.energy[0])) / np.max(res.kinetic[:n])
    assert drift < 1e-7
    assert res.energy_drift(until) == pytest.approx(drift)
    if name != "five_bar":  # gravity did work: potential energy turned into kinetic energy
        assert np.max(res.kinetic[:n]) > 20 * res.kinetic[0]
        assert np.ptp(res.potential[:n]) > 0.5 * np.max(res.kinetic[:n])
    if until < res.t[-1]:  # the event that ends the claims went through a singularity
        first = next(ev for ev in res.events if ev.through)
        assert first.start == until and first.conditioning < THROUGH


@pytest.mark.parametrize("name", ("delta", "gough_stewart"))
def test_baumgarte_alone_holds_the_closures(robots, name):
    """Without projection, the Baumgarte terms keep the drift of the closures below 1e-9 m up
    to the first passage through a singularity (recorded: 5e-12 m, Delta; 2e-11 m, hexapod),
    and within 1e-8 m through the Delta's crossings (recorded: 5e-11 m)."""
    robot = robots[name]
    v0 = _tangent_velocity(robot, robot.q_home, 0.5)
    res = simulate(robot.model, robot.constraint_models, robot.q_home, v0, 1.0, 1e-3, project=False)
    assert res.projections == 0
    n = int(np.searchsorted(res.t, res.valid_until, side="right"))
    assert np.max(res.closure_residual[:n]) < 1e-9
    assert np.max(res.closure_residual) < 1e-8
    assert res.energy_drift(res.valid_until) < 1e-7


def test_free_delta_crossings_are_reported(robots):
    """The falling Delta crosses the singularity of its closures twice in 0.7 s: each crossing
    is one event, through the singularity, at the time the parallelograms' normals become
    coplanar (a sign change of their determinant along the recorded motion), within the
    sampling interval of that closed form; and no event is reported elsewhere."""
    robot = robots["delta"]
    v0 = _tangent_velocity(robot, robot.q_home, 0.5)
    dt = 1e-3
    res = simulate(robot.model, robot.constraint_models, robot.q_home, v0, 0.7, dt)
    det = np.array([parallelogram_normals_det(robot, q) for q in res.q])
    k = np.flatnonzero(np.sign(det[1:]) != np.sign(det[:-1]))
    crossings = res.t[k] + dt * det[k] / (det[k] - det[k + 1])  # linear interpolation
    assert len(crossings) == 2
    assert [ev.through for ev in res.events] == [True, True]
    for ev, t_cross, lo in zip(res.events, crossings, res.t[k], strict=True):
        assert ev.kind == "parallel_singularity"
        assert lo <= ev.time <= lo + dt  # the same sampling interval as the sign change
        assert abs(ev.time - t_cross) < dt
        assert ev.start <= t_cross <= ev.end
    # the conditioning recorded at the samples scales with the distance to the crossing:
    # below the near threshold only within a few samples of it
    near = res.t[res.conditioning < NEAR_SINGULAR]
    assert all(np.min(np.abs(crossings - t)) < 3 * dt for t in near)


def test_rk4_chart_is_fourth_order_on_lie_groups(robots):
    """Halving the step divides the RK4 error by ~16 (free-flyer platform, universal joints).

    The stage velocities are mapped to the exponential chart with ``dDifference``; adding them
    as if the configuration space were flat would make the scheme second order.
    """
    robot = robots["gough_stewart"]
    model = robot.model
    v0 = _tangent_velocity(robot, robot.q_home, 1.0, seed=3)
    ref = ForwardDynamics(
        model,
        robot.constraint_models,
        baumgarte=(0.0, 0.0),
        project=False,
        rtol=1e-12,
        atol=1e-13,
    ).simulate(robot.q_home, v0, 0.1, 1e-3, record_every=100)
    ff = next(j for j in model.joints if j.shortname() == "JointModelFreeFlyer")
    turn = pin.log3(pin.Quaternion(ref.q[-1, ff.idx_q + 3 : ff.idx_q + 7]).matrix())
    assert np.linalg.norm(turn) > 0.01  # the platform turns [rad] (it starts level)

    def error(integrator, dt):
        fd = ForwardDynamics(
            model,
            robot.constraint_models,
            integrator=integrator,
            baumgarte=(0.0, 0.0),
            project=False,
        )
        out = fd.simulate(robot.q_home, v0, 0.1, dt, record_every=10_000)
        return np.linalg.norm(pin.difference(model, ref.q[-1], out.q[-1])) + np.linalg.norm(
            out.v[-1] - ref.v[-1]
        )

    rk4 = error("rk4", 0.01) / error("rk4", 0.005)
    euler = error("euler", 0.002) / error("euler", 0.001)
    assert 11 < rk4 < 22
    assert 1.6 < euler < 2.5


# --------------------------------------------------------------------------- actuated runs


def _pd(robot, act: Actuation, kp: float, kd: float, amplitude: float, freq: float):
    """Joint-side PD tracking of a sinusoid about home, returned as actuator-side efforts."""
    qa0 = robot.q_home[robot.actuated_q]
    phase = np.arange(act.n) * 2 * np.pi / act.n
    idx = robot.actuated_v

    def tau(t, q, v):
        ref = qa0 + amplitude * np.sin(2 * np.pi * freq * t + phase)
        joint = kp * (ref - q[robot.actuated_q]) - kd * v[idx]
        return joint / act.gains

    return tau


@pytest.mark.parametrize(
    ("name", "kp", "kd", "amplitude"),
    [("delta", 60.0, 1.0, 0.3), ("gough_stewart", 3e4, 300.0, 0.02)],
)
def test_actuator_work_equals_energy_change(robots, name, kp, kd, amplitude):
    """Power balance: int tau . (S qdot) dt = change of mechanical energy (no friction).

    Efforts are motor-side (actuation gains = reductions), so the conjugate velocity is the
    motor velocity ``reduction * qdot``. The work is integrated here by Simpson's rule on the
    recorded samples (1 kHz), independently of the integrator.
    """
    robot = robots[name]
    act = _actuation(robot, gains=True)
    fd = ForwardDynamics(robot.model, robot.constraint_models, act)
    res = fd.simulate(
        robot.q_home, np.zeros(robot.nv), 1.0, 1e-3, _pd(robot, act, kp, kd, amplitude, 2.0)
    )
    power = np.sum(res.tau * act.gains * res.v[:, act.v_index], axis=1)
    work, _ = simpson_work(res.t, power)
    dE = (res.energy - res.energy[0])[::2]
    scale = np.max(np.abs(work))
    assert scale > 0.05  # the actuators did work [J]
    assert np.max(np.abs(dE - work)) < 5e-3 * scale
    assert np.max(np.abs(res.work[::2] - work)) < 5e-3 * scale
    assert res.energy_drift() < 1e-6  # the integrator's own quadrature of the work
    assert np.max(res.closure_residual) < 1e-8
    # the motion stayed near home (the PD tracked it): no singular collapse
    assert np.max(np.abs(res.q[:, robot.actuated_q] - robot.q_home[robot.actuated_q])) < 0.5


def test_friction_only_dissipates(robots):
    robot = robots["five_bar"]
    friction = PassiveForces(robot.model, damping=0.02, friction=0.01, smoothing=0.01)
    v0 = _tangent_velocity(robot, robot.q_home, 2.0)
    fd = ForwardDynamics(robot.model, robot.constraint_models, passive=friction)
    res = fd.simulate(robot.q_home, v0, 1.0, 1e-3)
    assert np.all(np.diff(res.energy) <= 1e-12)
    assert np.all(np.diff(res.dissipated) >= 0.0)
    assert res.kinetic[-1] < 1e-6 * res.kinetic[0]  # brought to rest (dry friction holds it)
    # energy balance: what the mechanism lost is what friction dissipated
    assert res.energy_drift() < 1e-6
    # the friction law: opposes the velocity, tanh-saturated Coulomb part
    v = np.array([-1.0, -1e-4, 0.0, 1.0])
    f = friction.dissipative_force(v)
    assert np.all(f * v <= 0.0)
    assert f[-1] == pytest.approx(-(0.02 + 0.01 * np.tanh(100.0)))


# --------------------------------------------------------------------------- drift control


def test_baumgarte_pulls_a_drifted_state_back(robots):
    """Critically damped closure error: e(t) = e0 (1 + w t) exp(-w t), w = 50 rad/s."""
    robot = robots["five_bar"]
    rng = np.random.default_rng(1)
    q0 = pin.integrate(robot.model, robot.q_home, 1e-4 * rng.standard_normal(robot.nv))
    e0 = np.max(np.abs(robot.closure_set.residual(robot.data, q0)))
    kw = dict(project=False, record_every=100)
    res = simulate(robot.model, robot.constraint_models, q0, np.zeros(robot.nv), 0.2, 1e-3, **kw)
    assert res.closure_residual[0] == pytest.approx(e0)
    assert res.closure_residual[-1] < 1e-3 * e0  # (1 + 10) exp(-10) = 5e-4
    free = simulate(
        robot.model,
        robot.constraint_models,
        q0,
        np.zeros(robot.nv),
        0.2,
        1e-3,
        baumgarte=(0.0, 0.0),
        **kw,
    )
    assert free.closure_residual[-1] > 0.5 * e0


@pytest.mark.parametrize("name", ("delta", "five_bar"))
def test_projection_restores_closures_without_adding_energy(robots, name):
    robot = robots[name]
    model = robot.model
    rng = np.random.default_rng(2)
    q = pin.integrate(model, robot.q_home, 1e-3 * rng.standard_normal(robot.nv))
    v = rng.standard_normal(robot.nv)
    fd = ForwardDynamics(model, robot.constraint_models)
    qp, vp = fd.project_state(q, v)
    data = model.createData()
    r, J = robot.closure_set.residual_and_jacobian(data, qp)
    assert np.max(np.abs(r)) < 1e-11
    assert np.max(np.abs(J @ vp)) < 1e-10
    # kinetic-energy metric: the removed velocity is M-orthogonal to the allowed motions
    M = pin.crba(model, data, qp)
    M = np.triu(M) + np.triu(M, 1).T
    Z = null_space(J)
    assert np.max(np.abs(Z.T @ M @ (v - vp))) < 1e-9 * np.max(np.abs(M @ v))
    assert vp @ M @ vp <= v @ M @ v


# --------------------------------------------------------------------------- interface


def test_recording_and_api_errors(robots):
    robot = robots["five_bar"]
    act = _actuation(robot)
    fd = ForwardDynamics(robot.model, robot.constraint_models, act, integrator="rk4")
    res = fd.simulate(robot.q_home, np.zeros(robot.nv), 0.011, 1e-3, record_every=4)
    assert res.t.tolist() == pytest.approx([0.0, 0.004, 0.008, 0.011], abs=1e-12)
    assert res.q.shape == (4, robot.nq) and res.tau.shape == (4, 2)
    assert res.constraint_forces.shape == (4, robot.closure_set.nc)
    with pytest.raises(ValueError, match="returned 3 values for 2 actuators"):
        fd.simulate(robot.q_home, np.zeros(robot.nv), 0.01, 1e-3, lambda t, q, v: np.ones(3))
    with pytest.raises(ValueError, match="unknown integrator"):
        ForwardDynamics(robot.model, robot.constraint_models, integrator="leapfrog")
    with pytest.raises(ValueError, match="distinct"):
        Actuation([0, 0])
    with pytest.raises(IntegrationError) as err:
        fd.simulate(
            robot.q_home, np.zeros(robot.nv), 0.01, 1e-3, lambda t, q, v: np.full(2, np.nan)
        )
    assert err.value.time == 0.0


def test_step_matches_simulate(robots):
    robot = robots["gough_stewart"]
    act = _actuation(robot)
    v0 = _tangent_velocity(robot, robot.q_home, 0.2)
    kw = dict(integrator="rk4", project=False)
    res = ForwardDynamics(robot.model, robot.constraint_models, act, **kw).simulate(
        robot.q_home, v0, 0.005, 1e-3
    )
    fd = ForwardDynamics(robot.model, robot.constraint_models, act, **kw)
    q, v = robot.q_home, v0
    for k in range(5):
        q, v = fd.step(k * 1e-3, q, v, 1e-3)
    assert np.max(np.abs(q - res.q[-1])) < 1e-14
    assert np.max(np.abs(v - res.v[-1])) < 1e-12
