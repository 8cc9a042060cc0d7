"""Actuation maps: finite differences, virtual work, kinetic energy, full inverse dynamics.

- ``J`` against central finite differences of the position maps (both ways);
- torque maps by virtual work (``tau_a . qa_dot = tau_j . qj_dot`` along random motions);
- the reflected inertia against the kinetic energy of the whole mechanism moving with
  ``qj_dot`` (``1/2 v^T M v`` with ``v`` from the closures);
- static agreement with full constrained inverse dynamics (:class:`solvers.InverseDynamics`,
  no gravity): the actuator efforts that hold a joint-space load equal ``J^T tau_j``;
- the closed forms of the two leg families; the four-bar's dead point is flagged singular.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.closed_form import four_bar_knee as knee_cf
from pkdyn.closed_form import parallel_ankle as ankle_cf
from pkdyn.dynamics.actuation import actuation
from solvers import InverseDynamics

H = 1e-6


@pytest.fixture(scope="module")
def ankle():
    return pkdyn.load("parallel_ankle")


@pytest.fixture(scope="module")
def knee():
    return pkdyn.load("four_bar_knee")


@pytest.fixture(scope="module")
def five_bar():
    return pkdyn.load("five_bar")


CASES = {
    "ankle": ("ankle", ["ankle_pitch", "ankle_roll"]),
    "knee": ("knee", ["knee"]),
    "five_bar": ("five_bar", ["distal1", "distal2"]),
}


@pytest.fixture(params=list(CASES))
def case(request):
    name, joints = CASES[request.param]
    robot = request.getfixturevalue(name)
    return robot, pkdyn.actuation_map(robot, joints)


def _samples(robot, m, n=6, seed=0):
    rng = np.random.default_rng(seed)
    qa0 = robot.q_home[m.act_q]
    return qa0 + 0.15 * rng.uniform(-1, 1, (n, m.n))


def test_jacobian_against_finite_differences(case):
    robot, m = case
    s = m.from_actuators(_samples(robot, m))
    assert s.reached.all() and not s.singular.any()
    for k in range(len(s.qa)):
        for i in range(m.n):
            d = np.zeros(m.n)
            d[i] = H
            plus = m.from_actuators(s.qa[k] + d, q_init=s.q[k])
            minus = m.from_actuators(s.qa[k] - d, q_init=s.q[k])
            fd = (plus.qj[0] - minus.qj[0]) / (2 * H)
            np.testing.assert_allclose(s.J[k][:, i], fd, rtol=1e-6, atol=1e-8)
    back = m.from_joints(s.qj, q_init=s.q[0])
    np.testing.assert_allclose(back.qa, s.qa, atol=1e-10)
    for k in range(len(s.qa)):
        np.testing.assert_allclose(back.J_inv[k] @ s.J[k], np.eye(m.n), atol=1e-9)


def test_torque_maps_by_virtual_work(case):
    robot, m = case
    s = m.from_actuators(_samples(robot, m, seed=1))
    rng = np.random.default_rng(2)
    tau_j = rng.standard_normal((len(s.qa), m.n))
    tau_a = s.actuator_torques(tau_j)
    np.testing.assert_allclose(s.joint_torques(tau_a), tau_j, atol=1e-9)
    for k in range(len(s.qa)):
        qa_dot = rng.standard_normal(m.n)
        qj_dot = s.J[k] @ qa_dot
        # the same rates, measured on the mechanism: a closure-consistent velocity
        Jc = robot.closure_set.jacobian(robot.model.createData(), s.q[k])
        S = np.zeros((2 * m.n, robot.nv))
        S[np.arange(m.n), m.act_v] = 1.0
        S[m.n + np.arange(m.n), m.joint_v] = 1.0
        v = np.linalg.lstsq(np.vstack([Jc, S[: m.n]]), np.r_[np.zeros(len(Jc)), qa_dot], None)[0]
        np.testing.assert_allclose(v[m.joint_v], qj_dot, atol=1e-9)
        assert tau_a[k] @ qa_dot == pytest.approx(tau_j[k] @ qj_dot, abs=1e-9)


def test_reflected_inertia_is_the_kinetic_energy(case):
    robot, m = case
    s = m.from_joints(m.from_actuators(_samples(robot, m, seed=3)).qj)
    rng = np.random.default_rng(4)
    data = robot.model.createData()
    for k in range(len(s.qa)):
        qj_dot = rng.standard_normal(m.n)
        Jc = robot.closure_set.jacobian(data, s.q[k])
        # least kinetic energy among the motions with these joint rates (internal motions free)
        M = pin.crba(robot.model, data, s.q[k])
        M = np.triu(M) + np.triu(M, 1).T
        nv, nc = robot.nv, Jc.shape[0]
        S = np.zeros((m.n, nv))
        S[np.arange(m.n), m.joint_v] = 1.0
        KKT = np.block(
            [[M, Jc.T, S.T], [Jc, np.zeros((nc, nc + m.n))], [S, np.zeros((m.n, nc + m.n))]]
        )
        sol = np.linalg.lstsq(KKT, np.r_[np.zeros(nv + nc), qj_dot], None)[0]
        v = sol[:nv]
        assert 0.5 * qj_dot @ s.M_joint[k] @ qj_dot == pytest.approx(0.5 * v @ M @ v, rel=1e-9)
        qa_dot = v[m.act_v]
        assert qa_dot @ s.M_act[k] @ qa_dot == pytest.approx(v @ M @ v, rel=1e-9)


def test_static_agreement_with_full_inverse_dynamics(case):
    """Hold a joint-space load: full constrained inverse dynamics gives ``J^T tau_j``."""
    robot, m = case
    model = robot.model.copy()
    model.gravity = pin.Motion.Zero()
    solver = InverseDynamics(model, list(robot.constraint_models), actuation(robot))
    s = m.from_actuators(_samples(robot, m, n=4, seed=5))
    rng = np.random.default_rng(6)
    for k in range(len(s.qa)):
        tau_j = rng.standard_normal(m.n)
        f_ext = np.zeros(robot.nv)
        f_ext[m.joint_v] = -tau_j  # the load on the joints; the mechanism delivers tau_j
        out = solver.solve(s.q[k], np.zeros(robot.nv), np.zeros(robot.nv), f_ext=f_ext)
        np.testing.assert_allclose(out.tau, s.actuator_torques(tau_j)[k], atol=1e-9)


def test_ankle_closed_forms(ankle):
    m = pkdyn.actuation_map(ankle, ["ankle_pitch", "ankle_roll"])
    rng = np.random.default_rng(7)
    X = np.column_stack([rng.uniform(-0.4, 0.4, 40), rng.uniform(-0.3, 0.3, 40)])
    X = X[np.argsort(X[:, 0])]
    theta, ok = ankle_cf.inverse(ankle.params, X)
    assert ok.all()
    s = m.from_joints(X)
    np.testing.assert_allclose(s.qa, theta, atol=1e-9)
    x, ok = ankle_cf.forward(ankle.params, theta)
    assert ok.all()
    np.testing.assert_allclose(x, X, atol=1e-12)
    np.testing.assert_allclose(ankle_cf.jacobian(ankle.params, X, theta), s.J, atol=1e-9)


def test_knee_closed_forms_and_dead_point(knee):
    m = pkdyn.actuation_map(knee, ["knee"])
    theta = np.linspace(-0.15, 1.55, 30)
    phi, ok = knee_cf.motor_from_knee(knee.params, theta)
    assert ok.all()
    s = m.from_joints(theta[:, None])
    np.testing.assert_allclose(s.qa[:, 0], phi, atol=1e-9)
    back, ok = knee_cf.knee_from_motor(knee.params, phi)
    np.testing.assert_allclose(back, theta, atol=1e-12)
    np.testing.assert_allclose(s.J[:, 0, 0], knee_cf.ratio(knee.params, phi, theta), rtol=1e-9)
    # the dead point: coupler folded on the lever (|C| = r2 - r3), where the motor's branch of
    # knee angles ends: d knee / d motor grows without bound, and the motor cannot go further
    p = knee.params
    r2 = knee_cf.coupler_length(p)
    lo, hi = 0.5, 1.2  # |C(phi)| decreases through r2 - r3 once on this interval
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        C = np.array([p.x_motor + p.r1 * np.cos(mid), p.a - p.r1 * np.sin(mid)])
        lo, hi = (mid, hi) if np.linalg.norm(C) > r2 - p.r3 else (lo, mid)
    phi_dead = lo
    near = m.from_actuators([[phi_dead - 1e-3], [phi_dead - 1e-6]], q_init=s.q[-1])
    assert abs(near.J[1, 0, 0]) > 100 * abs(s.J[0, 0, 0])
    assert abs(near.J[1, 0, 0]) > 20 * abs(near.J[0, 0, 0])
    beyond = m.from_actuators([[phi_dead + 1e-3]], q_init=near.q[1], strict=False)
    assert not beyond.reached[0]


def test_unreached_samples(knee):
    m = pkdyn.actuation_map(knee, ["knee"])
    phi = knee.q_home[m.act_q][0]
    with pytest.raises(pkdyn.AssemblyError, match="sample 1 .*strict=False"):
        m.from_actuators([[phi], [phi + 1.5]])
    s = m.from_actuators([[phi], [phi + 1.5]], strict=False)
    assert list(s.reached) == [True, False]
    assert np.isnan(s.qa[1]).all() and s.singular[1]


@pytest.mark.parametrize(
    "kwargs,message",
    [
        ({"joints": ["nope"]}, "'nope' is not a joint"),
        ({"joints": ["ankle_pitch"]}, "1 joint coordinates for 2 actuators"),
        ({"joints": []}, "at least one joint"),
        ({"joints": ["ankle_pitch", "ankle_pitch"]}, "named twice"),
        ({"joints": ["ankle_pitch", "ankle_roll"], "actuators": ["motor_x"]}, "'motor_x'"),
    ],
)
def test_bad_maps(ankle, kwargs, message):
    with pytest.raises(pkdyn.InvalidInputError, match=message):
        pkdyn.actuation_map(ankle, **kwargs)


def test_bad_samples(ankle):
    m = pkdyn.actuation_map(ankle, ["ankle_pitch", "ankle_roll"])
    for bad in ([0.1], [[0.1, np.nan]], np.zeros((2, 3))):
        with pytest.raises(pkdyn.InvalidInputError):
            m.from_joints(bad)
    s = m.from_joints([0.1, 0.0])
    with pytest.raises(pkdyn.InvalidInputError, match="tau_joint"):
        s.actuator_torques([1.0, 2.0, 3.0])


def test_actuation_map_on_a_leg_of_a_floating_robot():
    """Menagerie Cassie: the left foot motor and its foot joint, everything else held."""
    robot = pkdyn.load(pkdyn.__path__[0] + "/../tests/data/public/menagerie_cassie/cassie.xml")
    m = pkdyn.actuation_map(robot, ["left-foot-crank"], actuators=["left-foot"])
    assert 0 not in m.moving_v  # the floating base is held
    s = m.from_actuators(robot.q_home[m.act_q] + np.array([[0.0], [0.02], [0.04]]))
    assert s.reached.all() and not s.singular.any()
    d = np.diff(s.qj[:, 0])
    assert np.all(d != 0)  # the plantar rod turns the crank with the foot
    np.testing.assert_allclose(s.q[:, :7], np.tile(robot.q_home[:7], (3, 1)), atol=1e-15)
