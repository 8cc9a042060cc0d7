"""Constrained forward dynamics: energy, closures, power balance, drift control, friction."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import null_space, simpson_work

import pkdyn
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
    """A velocity in the null space of the closure Jacobian, largest component ``vmax``."""
    J = robot.closure_set.jacobian(robot.model.createData(), q)
    v = null_space(J) @ np.random.default_rng(seed).standard_normal(robot.mobility(q))
    return vmax * v / np.max(np.abs(v))


def _actuation(robot: pkdyn.Robot, gains: bool = False) -> Actuation:
    g = [a.reduction for a in robot.actuators] if gains else None
    return Actuation(robot.actuated_v, g, robot.actuator_names)


# --------------------------------------------------------------------------- passive runs


@pytest.mark.parametrize("name", ROBOTS)
def test_passive_run_keeps_energy_and_closures(robots, name):
    """Free fall under gravity from home with a small velocity tangent to the closures.

    Nothing but gravity works: the mechanical energy is constant. The Delta swings through a
    parallel singularity (all six bars parallel) at 0.38 s, where the closure forces peak at
    3e4 N: the adaptive integrator shortens its steps there (a fixed-step RK4 loses 0.4 % of
    the energy). The five-bar moves in the horizontal plane: gravity does no work on it.
    """
    robot = robots[name]
    v0 = _tangent_velocity(robot, robot.q_home, 0.5)
    res = simulate(robot.model, robot.constraint_models, robot.q_home, v0, 2.0, 1e-3)
    assert res.t[-1] == pytest.approx(2.0)
    # recorded: closures up to 9e-10 m, energy drift 1.8e-6 (Delta), 7e-15 (five-bar), 9e-12
    # (hexapod)
    assert np.max(res.closure_residual) < 1e-8
    drift = np.max(np.abs(res.energy - res.energy[0])) / np.max(res.kinetic)
    assert drift < 1e-5
    assert res.energy_drift() == pytest.approx(drift)
    if name != "five_bar":  # gravity did work: potential energy turned into kinetic energy
        assert np.max(res.kinetic) > 20 * res.kinetic[0]
        assert np.ptp(res.potential) > 0.5 * np.max(res.kinetic)


@pytest.mark.parametrize("name", ("delta", "gough_stewart"))
def test_baumgarte_alone_holds_the_closures(robots, name):
    """Without projection, the Baumgarte terms keep the drift of the closures below 1e-8."""
    robot = robots[name]
    v0 = _tangent_velocity(robot, robot.q_home, 0.5)
    res = simulate(robot.model, robot.constraint_models, robot.q_home, v0, 1.0, 1e-3, project=False)
    assert res.projections == 0
    assert np.max(res.closure_residual) < 1e-8
    assert res.energy_drift() < 1e-3


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
