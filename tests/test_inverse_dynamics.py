"""Inverse dynamics: round trips with the forward dynamics, redundancy, bounds, power balance.

Consistent states are built without the forward dynamics: ``v`` in the null space of the
closure Jacobian ``J``, and ``a = -J^+ (Jdot v) + Z eta`` where ``Jdot v`` is the central
finite difference of ``J`` along ``v`` (``(J(q (+) h v) - J(q (-) h v)) v / 2h``), so that
``J a + Jdot v = 0``, and ``Z eta`` is any acceleration the closures allow.
"""

import numpy as np
import pinocchio as pin
import pytest
import scipy.linalg
from conftest import simpson_work

import pkdyn
from solvers.forward_dynamics import Actuation, ForwardDynamics
from solvers.inverse_dynamics import InfeasibleError, InverseDynamics


@pytest.fixture(scope="module")
def robots() -> dict[str, pkdyn.Robot]:
    return {
        "five_bar": pkdyn.load("five_bar", geometry=False),
        "gough_stewart": pkdyn.load("gough_stewart", geometry=False),
        "delta": pkdyn.load("delta", geometry=False),
        # universal-jointed bars: no spinning bar, the 3 actuators drive every mobility
        "delta_u": pkdyn.load("delta", geometry=False, bar_joint="universal"),
    }


def _actuation(robot: pkdyn.Robot) -> Actuation:
    return Actuation(robot.actuated_v, names=robot.actuator_names)


def _consistent_state(robot: pkdyn.Robot, seed: int, v_scale=0.5, a_scale=2.0):
    rng = np.random.default_rng(seed)
    model, cs = robot.model, robot.closure_set
    data = model.createData()
    qa = robot.q_home[robot.actuated_q] + 0.02 * rng.standard_normal(len(robot.actuators))
    q = pkdyn.forward_geometry(robot, qa).q
    J = cs.jacobian(data, q)
    Z = scipy.linalg.null_space(J, rcond=1e-9)
    v = v_scale * Z @ rng.standard_normal(Z.shape[1])
    h = 1e-5
    Jdv = (
        (
            cs.jacobian(data, pin.integrate(model, q, h * v))
            - cs.jacobian(data, pin.integrate(model, q, -h * v))
        )
        @ v
        / (2 * h)
    )
    a = a_scale * Z @ rng.standard_normal(Z.shape[1]) - np.linalg.pinv(J, rcond=1e-9) @ Jdv
    return q, v, a


def _closure_error(robot, q, dq):
    return np.max(np.abs(robot.closure_set.residual(robot.data, pin.integrate(robot.model, q, dq))))


def _forward(robot, act, q, v, tau):
    fd = ForwardDynamics(robot.model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    return fd.acceleration(q, v, act.generalized(tau, robot.nv))


# --------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("name", ("five_bar", "gough_stewart", "delta_u"))
def test_inverse_then_forward_reproduces_the_acceleration(robots, name):
    robot = robots[name]
    act = _actuation(robot)
    inv = InverseDynamics(robot.model, robot.constraint_models, act)
    for seed in range(3):
        q, v, a = _consistent_state(robot, seed)
        # consistent: along q (+) (t v + t^2 a / 2) the closure residual is O(t^3) (O(t^2) if
        # J a + Jdot v were not 0): halving t divides it by 8
        r1, r2 = (_closure_error(robot, q, t * v + 0.5 * t * t * a) for t in (1e-2, 5e-3))
        assert 6.0 < r1 / r2 < 10.0
        out = inv.solve(q, v, a)
        assert out.redundancy == 0 and out.iterations == 0
        assert out.residual < 1e-9
        assert np.max(np.abs(_forward(robot, act, q, v, out.tau) - a)) < 1e-8
        # unique efforts: the least-squares solution of [S^T J^T] [tau; lambda] = M a + h
        J = robot.closure_set.jacobian(robot.data, q)
        b = pin.rnea(robot.model, robot.data, q, v, a)
        x = np.linalg.lstsq(np.hstack([act.matrix(robot.nv).T, J.T]), b, rcond=1e-10)[0]
        assert np.max(np.abs(out.tau - x[: act.n])) < 1e-8 * max(1.0, np.max(np.abs(x)))
        # the multipliers balance the rest of the dynamics equation (independent M and h)
        M = pin.crba(robot.model, robot.data, q)
        M = np.triu(M) + np.triu(M, 1).T
        nle = pin.nonLinearEffects(robot.model, robot.data, q, v)
        lhs = M @ a + nle - act.generalized(out.tau, robot.nv) - J.T @ out.constraint_forces
        assert np.max(np.abs(lhs)) < 1e-9 * max(1.0, np.max(np.abs(b)))


def test_delta_with_spinning_bars_needs_consistent_bar_accelerations(robots):
    """Ball-ended bars spin freely (6 unactuated mobilities): only the accelerations of a real
    motion can be produced. Those of a forward-dynamics solve are; a random one is not."""
    robot = robots["delta"]
    act = _actuation(robot)
    assert robot.mobility() == 9
    inv = InverseDynamics(robot.model, robot.constraint_models, act)
    rng = np.random.default_rng(4)
    q, v, _ = _consistent_state(robot, 4)
    tau0 = rng.uniform(-2.0, 2.0, act.n)
    a = _forward(robot, act, q, v, tau0)
    out = inv.solve(q, v, a)
    assert np.max(np.abs(out.tau - tau0)) < 1e-9
    # an acceleration the closures allow but the actuators cannot produce: the bars' spin
    # accelerations are off (the bars' axial inertia is tiny, hence the large acceleration)
    J = robot.closure_set.jacobian(robot.data, q)
    delta = scipy.linalg.null_space(J, rcond=1e-9) @ rng.standard_normal(robot.mobility(q))
    with pytest.raises(InfeasibleError) as err:
        inv.solve(q, v, a + 1e3 * delta, sample=7)
    assert err.value.actuator is None and err.value.sample == 7
    assert "sample 7" in str(err.value) and "not consistent" in str(err.value)


# --------------------------------------------------------------------------- redundancy


def _redundant_five_bar(robot):
    """The five-bar with its passive distal joints also driven: 4 actuators for 2 dof."""
    joints = range(1, robot.model.njoints)
    return Actuation(
        [robot.model.joints[j].idx_v for j in joints],
        names=[robot.model.names[j] for j in joints],
    )


def _min_norm(robot, act, q, v, a, w):
    """Minimum ``sum w tau^2`` efforts, from scipy's null space and a pseudo-inverse."""
    J = robot.closure_set.jacobian(robot.data, q)
    Z = scipy.linalg.null_space(J, rcond=1e-9)
    b = pin.rnea(robot.model, robot.data, q, v, a)
    G = Z.T @ act.matrix(robot.nv).T
    Wh = np.diag(1.0 / np.sqrt(w))
    return Wh @ np.linalg.pinv(G @ Wh) @ (Z.T @ b), G, Z.T @ b


@pytest.mark.parametrize("weights", (None, [1.0, 4.0, 1.0, 0.25]))
def test_redundant_actuation_minimises_the_effort_norm(robots, weights):
    robot = robots["five_bar"]
    act = _redundant_five_bar(robot)
    w = np.ones(4) if weights is None else np.asarray(weights)
    inv = InverseDynamics(robot.model, robot.constraint_models, act, weights=weights)
    for seed in range(4):  # a sequence of samples: the QP is warm-started
        q, v, a = _consistent_state(robot, seed)
        out = inv.solve(q, v, a)
        assert out.redundancy == 2
        assert np.max(np.abs(_forward(robot, act, q, v, out.tau) - a)) < 1e-8
        tau_mn, G, _ = _min_norm(robot, act, q, v, a, w)
        assert np.max(np.abs(out.tau - tau_mn)) < 1e-8 * max(1.0, np.max(np.abs(tau_mn)))
        # optimality: the weighted gradient has no component along the free effort directions
        N = scipy.linalg.null_space(G)
        assert np.max(np.abs(N.T @ (w * out.tau))) < 1e-8 * max(1.0, np.max(np.abs(tau_mn)))


def test_redundant_actuation_with_an_active_bound(robots):
    robot = robots["five_bar"]
    act = _redundant_five_bar(robot)
    q, v, a = _consistent_state(robot, 5)
    tau_mn, G, f = _min_norm(robot, act, q, v, a, np.ones(4))
    k = int(np.argmax(np.abs(tau_mn)))
    bound = 0.5 * abs(tau_mn[k])
    lower, upper = np.full(4, -np.inf), np.full(4, np.inf)
    lower[k], upper[k] = -bound, bound
    inv = InverseDynamics(robot.model, robot.constraint_models, act, lower, upper)
    out = inv.solve(q, v, a)
    assert out.tau[k] == pytest.approx(np.sign(tau_mn[k]) * bound, abs=1e-8)
    assert np.max(np.abs(_forward(robot, act, q, v, out.tau) - a)) < 1e-8
    # the same problem with the bound as an equality, solved by least squares (KKT system)
    e = np.eye(4)[k]
    A = np.vstack([G, e])
    rhs = np.concatenate([f, [np.sign(tau_mn[k]) * bound]])
    K = np.block([[np.eye(4), A.T], [A, np.zeros((A.shape[0], A.shape[0]))]])
    ref = np.linalg.lstsq(K, np.concatenate([np.zeros(4), rhs]), rcond=1e-12)[0][:4]
    assert np.max(np.abs(out.tau - ref)) < 1e-7
    assert out.tau @ out.tau >= tau_mn @ tau_mn


# --------------------------------------------------------------------------- infeasibility


def test_infeasible_bounds_name_the_sample_and_the_actuator(robots):
    robot = robots["gough_stewart"]
    act = _actuation(robot)
    # one configuration, a growing motion: sample 3 asks for 8 times the acceleration
    states = [_consistent_state(robot, 10, v_scale=0.1 * s, a_scale=s) for s in (1, 2, 3, 8, 1)]
    Q, V, A = (np.array(x) for x in zip(*states, strict=True))
    free = InverseDynamics(robot.model, robot.constraint_models, act).trajectory(Q, V, A)
    lim = 1.2 * np.max(np.abs(free.tau[:3]), axis=0)  # samples 0-2 are within the bounds
    assert np.any(np.abs(free.tau[3]) > lim)
    expected = int(np.argmax(np.abs(free.tau[3]) / lim))
    inv = InverseDynamics(robot.model, robot.constraint_models, act, -lim, lim)
    with pytest.raises(InfeasibleError) as err:
        inv.trajectory(Q, V, A)
    e = err.value
    assert e.sample == 3 and e.actuator == expected and e.name == f"motor{expected + 1}"
    assert e.required == pytest.approx(free.tau[3, expected])
    assert f"sample 3: actuator 'motor{expected + 1}'" in str(e)


def test_infeasible_redundant_actuation_names_the_most_loaded_actuator(robots):
    robot = robots["five_bar"]
    act = _redundant_five_bar(robot)
    q, v, a = _consistent_state(robot, 6)
    tau_mn, _, _ = _min_norm(robot, act, q, v, a, np.ones(4))
    lim = 0.5 * np.max(np.abs(tau_mn))  # below what the least-loaded solution needs
    inv = InverseDynamics(
        robot.model, robot.constraint_models, act, -np.full(4, lim), np.full(4, lim)
    )
    with pytest.raises(InfeasibleError) as err:
        inv.solve(q, v, a, sample=0)
    assert err.value.actuator == int(np.argmax(np.abs(tau_mn)))
    assert err.value.name == robot.model.names[1 + err.value.actuator]


# --------------------------------------------------------------------------- trajectories


@pytest.mark.parametrize(
    ("name", "kp", "kd"), [("delta", 60.0, 1.0), ("gough_stewart", 3e4, 300.0)]
)
def test_power_balance_along_a_simulated_trajectory(robots, name, kp, kd):
    """Forward-simulate a PD-driven motion, then run the inverse dynamics on the recorded
    samples: it recovers the applied efforts, and int tau . qdot_a dt = change of energy."""
    robot = robots[name]
    act = _actuation(robot)
    qa0 = robot.q_home[robot.actuated_q]
    amp = 0.3 if name == "delta" else 0.02
    phase = np.arange(act.n) * 2 * np.pi / act.n

    def tau_fn(t, q, v):
        ref = qa0 + amp * np.sin(4 * np.pi * t + phase)
        return kp * (ref - q[robot.actuated_q]) - kd * v[act.v_index]

    fd = ForwardDynamics(robot.model, robot.constraint_models, act)
    sim = fd.simulate(robot.q_home, np.zeros(robot.nv), 0.5, 1e-3, tau_fn)
    lim = np.array([x.effort for x in robot.actuators])
    out = InverseDynamics(robot.model, robot.constraint_models, act, -lim, lim).trajectory(
        sim.q, sim.v, sim.a
    )
    assert np.max(out.residual) < 1e-8
    assert np.max(np.abs(out.tau - sim.tau)) < 1e-6 * np.max(np.abs(sim.tau))
    # the closures of both robots are independent equations: the closure forces are unique too,
    # and Pinocchio's (converted to this convention by the forward dynamics) are the same
    lam_scale = np.max(np.abs(sim.constraint_forces))
    assert np.max(np.abs(out.constraint_forces - sim.constraint_forces)) < 1e-6 * lam_scale
    power = np.sum(out.tau * sim.v[:, act.v_index], axis=1)
    work, _ = simpson_work(sim.t, power)
    dE = (sim.energy - sim.energy[0])[::2]
    assert np.max(np.abs(work)) > 0.05
    assert np.max(np.abs(dE - work)) < 5e-3 * np.max(np.abs(work))
