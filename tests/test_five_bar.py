"""Five-bar: closed forms against geometry and the numeric path, assembly, round trips."""

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.closed_form import five_bar as fb_cf
from pkdyn.library import five_bar as fb


@pytest.fixture(scope="module")
def robot() -> pkdyn.Robot:
    return pkdyn.load("five_bar")


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _points(p, n, rng, radius=0.08):
    """Random end-effector points in a disc around home, reachable within the actuator limits."""
    out = []
    while len(out) < n:
        r = radius * np.sqrt(rng.uniform())
        t = rng.uniform(0, 2 * np.pi)
        E = np.array([p.x_home + r * np.cos(t), p.home_height() + r * np.sin(t)])
        q, ok = fb_cf.inverse(p, E)
        if ok[0] and np.all((q > p.q_min) & (q < p.q_max)):
            out.append(E)
    return np.array(out)


def _elbows(p, theta):
    """Elbows C_j = A_j + l1 (cos theta_j, sin theta_j), computed here."""
    A = np.array([[-p.d / 2, 0.0], [p.d / 2, 0.0]])
    return A + p.l1 * np.stack([np.cos(theta), np.sin(theta)], axis=-1)


def test_loads_with_two_dof_at_home(robot):
    p = robot.params
    assert robot.mobility() == 2
    assert robot.nv == 4
    assert robot.actuated_joint_names == ["proximal1", "proximal2"]
    assert robot.actuator_names == ["motor1", "motor2"]
    assert [c.kind for c in robot.closures] == ["hinge"]
    np.testing.assert_allclose(
        robot.platform_placement(robot.q_home).translation,
        [p.x_home, p.home_height(), 0.0],
        atol=1e-9,
    )
    q = robot.q_home.copy()
    q[robot.actuated_q] = 0.0
    np.testing.assert_allclose(q, pin.neutral(robot.model), atol=1e-9)  # passive neutral = home
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-10
    # default working mode: both elbows outward, symmetric about the y axis
    th = robot.q_home[robot.actuated_q]
    C = _elbows(p, th)
    assert C[0, 0] < -p.d / 2 and C[1, 0] > p.d / 2
    np.testing.assert_allclose(th[0], np.pi - th[1], atol=1e-9)


@pytest.mark.parametrize("mode", ["+-", "-+", "++", "--"])
def test_closed_form_ik_closes_the_loop(mode):
    """|C_j E| = l2 for both chains; the elbow side matches the working mode."""
    p = fb.Params(working_mode=mode)
    E = _points(fb.Params(), 1000, np.random.default_rng(20))
    theta, ok = fb_cf.inverse(p, E)
    assert ok.all()
    C = _elbows(p, theta)
    np.testing.assert_allclose(np.linalg.norm(E[:, None] - C, axis=-1), p.l2, atol=1e-12)
    A = np.array([[-p.d / 2, 0.0], [p.d / 2, 0.0]])
    u = E[:, None] - A  # A_j -> E
    v = C - A  # A_j -> C_j
    side = np.sign(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0])  # + : C_j left of A_j -> E
    np.testing.assert_array_equal(side, np.broadcast_to(fb_cf.mode_signs(mode), side.shape))


def test_closed_form_fk_inverts_ik(robot):
    p = robot.params
    E = _points(p, 1000, np.random.default_rng(21))
    theta, _ = fb_cf.inverse(p, E)
    E2, ok = fb_cf.forward(p, theta)
    assert ok.all()
    np.testing.assert_allclose(E2, E, atol=1e-12)


def test_closed_form_matches_inverse_geometry(robot):
    p = robot.params
    E = _points(p, 50, np.random.default_rng(22))
    theta, _ = fb_cf.inverse(p, E)
    for k in range(len(E)):
        ik = pkdyn.inverse_geometry(robot, [E[k, 0], E[k, 1], 0.0])
        np.testing.assert_allclose(_wrap(ik.qa - theta[k]), 0.0, atol=1e-9)
        assert pkdyn.closure_residual(robot, ik.q) < 1e-10


def test_closed_form_derivative_matches_model_velocities(robot):
    """Central differences of the closed form = actuated rates of the closure's kernel motions."""
    p = robot.params
    model, data = robot.model, robot.data
    eps = 1e-6
    for E in _points(p, 10, np.random.default_rng(23)):
        fk = pkdyn.forward_geometry(robot, fb_cf.inverse(p, E)[0][0])
        _, J = robot.closure_set.residual_and_jacobian(data, fk.q)
        _, s, Vt = np.linalg.svd(J)
        N = Vt[int(np.sum(s > 1e-9 * s[0])) :].T
        assert N.shape[1] == 2
        Jf = pin.computeFrameJacobian(
            model, data, fk.q, robot.platform_frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        model_jac = N[robot.actuated_v] @ np.linalg.inv(Jf[:2] @ N)
        fd = np.column_stack(
            [
                _wrap(fb_cf.inverse(p, E + d)[0][0] - fb_cf.inverse(p, E - d)[0][0]) / (2 * eps)
                for d in np.eye(2) * eps
            ]
        )
        np.testing.assert_allclose(fd, model_jac, atol=1e-6)


def test_assembly_from_random_actuator_inputs(robot):
    rng = np.random.default_rng(24)
    p = robot.params
    theta, _ = fb_cf.inverse(p, _points(p, 200, rng))
    theta += rng.uniform(-0.02, 0.02, theta.shape)
    for qa in theta:
        fk = pkdyn.forward_geometry(robot, qa)
        assert pkdyn.closure_residual(robot, fk.q) < 1e-10
        # the solver moved only the passive coordinates: the actuated ones are the inputs
        np.testing.assert_allclose(fk.q[robot.actuated_q], qa, rtol=0, atol=1e-15)
        # independent check: the end-effector is at distance l2 from both elbows
        C = _elbows(p, qa)
        np.testing.assert_allclose(np.linalg.norm(fk.position[:2] - C, axis=1), p.l2, atol=1e-10)
        assert abs(fk.position[2]) < 1e-12


def test_fk_of_closed_form_ik_round_trip_1000_points(robot):
    p = robot.params
    E = _points(p, 1000, np.random.default_rng(25))
    theta, _ = fb_cf.inverse(p, E)
    worst = 0.0
    q_prev = robot.q_home
    for k in range(len(E)):
        fk = pkdyn.forward_geometry(robot, theta[k], q_init=q_prev if k % 2 else None)
        q_prev = fk.q
        worst = max(worst, float(np.abs(fk.position[:2] - E[k]).max()))
    assert worst < 1e-9


def test_assembly_modes_are_the_two_circle_intersections(robot):
    p = robot.params
    qa = robot.q_home[robot.actuated_q]
    modes = pkdyn.assembly_modes(robot, qa, starts=32, spread=2.5)
    found = np.array(sorted((m.position[:2] for m in modes), key=lambda e: e[1]))
    expected = np.array(
        sorted((fb_cf.forward(p, qa, s)[0][0] for s in (1, -1)), key=lambda e: e[1])
    )
    assert found.shape == (2, 2)
    np.testing.assert_allclose(found, expected, atol=1e-9)


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("l1", -0.2),
        ("d", 0.0),
        ("l2", float("inf")),
        ("working_mode", "+"),
        ("y_home", 0.6),  # out of reach
        ("q_max", -3.0),  # no home within [q_min, q_max]: named by the derived y_home
    ],
)
def test_bad_parameters_are_named(name, value):
    culprit = "y_home" if name == "q_max" else name
    with pytest.raises(pkdyn.ParameterError, match=f"'{culprit}'"):
        pkdyn.load("five_bar", **{name: value})


def test_explicit_home_outside_the_actuator_limits_names_the_limit():
    with pytest.raises(pkdyn.ParameterError, match="'q_max'"):
        pkdyn.load("five_bar", y_home=0.3, q_max=2.0)  # theta_1 at (0, 0.3) is 2.41 rad


def test_derived_home_respects_the_actuator_limits():
    r = pkdyn.load("five_bar", q_max=2.0, geometry=False)
    assert np.all(r.q_home[r.actuated_q] <= 2.0)


def test_unreachable_points(robot):
    p = robot.params
    for E in ([0.0, 0.6], [-0.1, 0.02]):  # beyond l1 + l2, inside |l1 - l2| of A_1
        assert not fb_cf.inverse(p, E)[1][0]
        with pytest.raises(pkdyn.UnreachablePoseError):
            pkdyn.inverse_geometry(robot, [E[0], E[1], 0.0])


def test_actuator_limit_violation():
    r = pkdyn.load("five_bar", q_max=2.5, geometry=False)
    p = r.params
    E = np.array([-0.05, 0.28])
    theta, ok = fb_cf.inverse(p, E)
    assert ok[0] and theta[0, 0] > p.q_max
    with pytest.raises(pkdyn.JointLimitError) as err:
        pkdyn.inverse_geometry(r, [E[0], E[1], 0.0])
    assert err.value.joint == "proximal1"
