"""Planar 3-RRR: Pasqui's closed-form inverse model against geometry and the numeric path."""

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.closed_form import planar_3rrr as cf


@pytest.fixture(scope="module")
def robot() -> pkdyn.Robot:
    return pkdyn.load("planar_3rrr")


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _poses(p, n, rng, radius=0.10, dphi=0.4):
    """Random poses in a disc around the home pose, all reachable within the actuator limits."""
    out = []
    while len(out) < n:
        r = radius * np.sqrt(rng.uniform())
        t = rng.uniform(0, 2 * np.pi)
        X = np.array(
            [
                p.home_pose[0] + r * np.cos(t),
                p.home_pose[1] + r * np.sin(t),
                p.phi_home + rng.uniform(-dphi, dphi),
            ]
        )
        q, ok = cf.inverse(p, X, p.elbow)
        if ok[0] and np.all((q > p.q_min) & (q < p.q_max)):
            out.append(X)
    return np.array(out)


def _geometry(p, X, q1):
    """Base points, elbows and platform joints computed here from the seed's definitions."""
    ang = np.asarray(p.base_angles)
    O1 = p.base_radius * np.stack([np.cos(ang), np.sin(ang)], axis=-1)  # (3, 2)
    O2 = O1 + p.l1 * np.stack([np.cos(q1), np.sin(q1)], axis=-1)  # (N, 3, 2)
    g = X[:, 2:3] + np.asarray(p.platform_angles)
    B = X[:, None, :2] + p.h * np.stack([np.cos(g), np.sin(g)], axis=-1)
    return O1, O2, B


def _pose6(X):
    return [X[0], X[1], 0.0, 0.0, 0.0, X[2]]


def test_loads_with_three_dof_at_home(robot):
    p = robot.params
    assert robot.mobility() == 3
    assert robot.nv == 9  # planar joint (3) + 3 x (actuated + elbow)
    assert robot.actuated_joint_names == ["proximal1", "proximal2", "proximal3"]
    assert robot.actuator_names == ["motor1", "motor2", "motor3"]
    assert [c.kind for c in robot.closures] == ["hinge"] * 3
    # the home configuration is the neutral one except for the actuated (absolute) angles
    q = robot.q_home.copy()
    q[robot.actuated_q] = 0.0
    np.testing.assert_allclose(q, pin.neutral(robot.model), atol=1e-9)
    M = robot.platform_placement(robot.q_home)
    np.testing.assert_allclose(M.translation, [p.home_pose[0], p.home_pose[1], 0.0], atol=1e-9)
    np.testing.assert_allclose(M.rotation, pin.rpy.rpyToMatrix(0, 0, p.phi_home), atol=1e-9)
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-10


def test_closed_form_ik_closes_every_chain():
    """|O_2^i B_i| = l2 with the computed q_1^i, elbows on the requested side."""
    rng = np.random.default_rng(10)
    for elbow in (1, -1):
        p = pkdyn.library.FAMILIES["planar_3rrr"].make_params({"elbow": elbow})
        X = _poses(p, 1000, rng)
        q1, ok = cf.inverse(p, X, elbow)
        assert ok.all()
        _, O2, B = _geometry(p, X, q1)
        np.testing.assert_allclose(np.linalg.norm(B - O2, axis=-1), p.l2, atol=1e-12)
        u1 = np.stack([np.cos(q1), np.sin(q1)], axis=-1)
        u2 = B - O2
        cross = u1[..., 0] * u2[..., 1] - u1[..., 1] * u2[..., 0]
        assert np.all(np.sign(cross) == elbow)


def test_chain_angles_satisfy_the_seed_chain_equations(robot):
    """x = a + l1 cos q1 + l2 cos(q1+q2) + h cos(q1+q2+q3) (and y), psi = phi + gamma + pi."""
    p = robot.params
    X = _poses(p, 500, np.random.default_rng(11))
    q, ok = cf.chain_angles(p, X, p.elbow)
    assert ok.all()
    q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2]
    O1, _, _ = _geometry(p, X, q1)
    x = O1[:, 0] + p.l1 * np.cos(q1) + p.l2 * np.cos(q1 + q2) + p.h * np.cos(q1 + q2 + q3)
    y = O1[:, 1] + p.l1 * np.sin(q1) + p.l2 * np.sin(q1 + q2) + p.h * np.sin(q1 + q2 + q3)
    np.testing.assert_allclose(x, np.repeat(X[:, :1], 3, axis=1), atol=1e-12)
    np.testing.assert_allclose(y, np.repeat(X[:, 1:2], 3, axis=1), atol=1e-12)
    psi = X[:, 2:3] + np.asarray(p.platform_angles) + np.pi
    np.testing.assert_allclose(_wrap(q1 + q2 + q3 - psi), 0.0, atol=1e-12)
    assert np.all(q2 > 0)  # elbow = +1


def test_closed_form_matches_inverse_geometry(robot):
    p = robot.params
    X = _poses(p, 40, np.random.default_rng(12))
    q1, _ = cf.inverse(p, X, p.elbow)
    for k in range(len(X)):
        ik = pkdyn.inverse_geometry(robot, _pose6(X[k]))
        np.testing.assert_allclose(_wrap(ik.qa - q1[k]), 0.0, atol=1e-9)
        assert pkdyn.closure_residual(robot, ik.q) < 1e-10


def test_model_coordinates_follow_the_documented_conventions(robot):
    """Passive elbow coordinate = q_2^i - q_2^i(home); planar joint frame at the home pose."""
    p = robot.params
    X = _poses(p, 20, np.random.default_rng(13))
    q, _ = cf.chain_angles(p, X, p.elbow)
    q_home, _ = cf.chain_angles(p, p.home_pose, p.elbow)
    elbows = [robot.model.joints[robot.model.getJointId(f"distal{i}")].idx_q for i in (1, 2, 3)]
    for k in range(len(X)):
        fk = pkdyn.forward_geometry(robot, q[k, :, 0])
        np.testing.assert_allclose(_wrap(fk.q[elbows] + q_home[0, :, 1] - q[k, :, 1]), 0, atol=1e-9)


def test_closed_form_derivative_matches_model_velocities(robot):
    """Central differences of the closed form = actuated rates of the closure's kernel motions."""
    p = robot.params
    model, data = robot.model, robot.data
    X = _poses(p, 10, np.random.default_rng(14))
    eps = 1e-6
    for x in X:
        fk = pkdyn.forward_geometry(robot, cf.inverse(p, x, p.elbow)[0][0])
        _, J = robot.closure_set.residual_and_jacobian(data, fk.q)
        _, s, Vt = np.linalg.svd(J)
        N = Vt[int(np.sum(s > 1e-9 * s[0])) :].T  # (nv, 3) admissible velocities
        assert N.shape[1] == 3
        Jf = pin.computeFrameJacobian(
            model, data, fk.q, robot.platform_frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        Jx = Jf[[0, 1, 5]] @ N  # (xdot, ydot, phidot) of each kernel motion
        Jq = N[robot.actuated_v]
        model_jac = Jq @ np.linalg.inv(Jx)
        fd = np.empty((3, 3))
        for j in range(3):
            d = np.zeros(3)
            d[j] = eps
            fd[:, j] = _wrap(
                cf.inverse(p, x + d, p.elbow)[0][0] - cf.inverse(p, x - d, p.elbow)[0][0]
            )
        np.testing.assert_allclose(fd / (2 * eps), model_jac, atol=1e-6)


def test_assembly_from_random_actuator_inputs(robot):
    rng = np.random.default_rng(15)
    p = robot.params
    X = _poses(p, 200, rng)
    q1, _ = cf.inverse(p, X, p.elbow)
    q1 += rng.uniform(-0.01, 0.01, q1.shape)
    for qa in q1:
        fk = pkdyn.forward_geometry(robot, qa)
        assert pkdyn.closure_residual(robot, fk.q) < 1e-10
        # the solver moved only the passive coordinates: the actuated ones are the inputs
        np.testing.assert_allclose(fk.q[robot.actuated_q], qa, rtol=0, atol=1e-15)
        # independent check: every chain reaches its platform joint
        pose = np.array([*fk.position[:2], fk.rpy[2]])[None]
        _, O2, B = _geometry(p, pose, qa[None])
        np.testing.assert_allclose(np.linalg.norm(B - O2, axis=-1), p.l2, atol=1e-10)
        assert abs(fk.position[2]) < 1e-12 and np.abs(fk.rpy[:2]).max() < 1e-12


def test_fk_of_closed_form_ik_round_trip_1000_poses(robot):
    p = robot.params
    X = _poses(p, 1000, np.random.default_rng(16))
    q1, _ = cf.inverse(p, X, p.elbow)
    worst_pos = worst_rot = 0.0
    q_prev = robot.q_home
    for k in range(len(X)):
        fk = pkdyn.forward_geometry(robot, q1[k], q_init=q_prev if k % 2 else None)
        q_prev = fk.q
        worst_pos = max(worst_pos, float(np.abs(fk.position[:2] - X[k, :2]).max()))
        worst_rot = max(worst_rot, abs(float(_wrap(fk.rpy[2] - X[k, 2]))))
    assert worst_pos < 1e-9
    assert worst_rot < 1e-9


def test_mirror_elbow_mode():
    r = pkdyn.load("planar_3rrr", elbow=-1, geometry=False)
    p = r.params
    assert r.mobility() == 3
    q, _ = cf.chain_angles(p, p.home_pose, -1)
    assert np.all(q[0, :, 1] < 0)
    X = _poses(p, 10, np.random.default_rng(17))
    q1, _ = cf.inverse(p, X, -1)
    for k in range(len(X)):
        ik = pkdyn.inverse_geometry(r, _pose6(X[k]))
        np.testing.assert_allclose(_wrap(ik.qa - q1[k]), 0.0, atol=1e-9)


def test_explicit_base_points_equal_the_circle():
    fam = pkdyn.library.FAMILIES["planar_3rrr"]
    p = fam.params()
    explicit = fam.make_params({"base_points": tuple(map(tuple, p.base_xy))})
    assert fam.build_urdf(explicit) == fam.build_urdf(p)
    shifted = fam.make_params({"base_points": "((-0.4, -0.3), (0.45, -0.25), (0.0, 0.5))"})
    r = pkdyn.load("planar_3rrr", base_points=shifted.base_points, geometry=False)
    assert pkdyn.closure_residual(r, r.q_home) < 1e-10
    np.testing.assert_allclose(r.q_home[r.actuated_q], cf.inverse(shifted, shifted.home_pose)[0][0])


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("l1", -0.3),
        ("h", 0.0),
        ("base_radius", float("nan")),
        ("elbow", 0),
        ("x_home", 1.5),  # out of reach
        ("base_angles", (0.0, 1.0)),
        ("base_points", ((0.0, 0.0), (1.0, 0.0))),
        ("base_points", (0.0, 1.0, 2.0)),
        ("q_min", 0.0),  # home actuated angles below it
    ],
)
def test_bad_parameters_are_named(name, value):
    with pytest.raises(pkdyn.ParameterError, match=f"'{name}'"):
        pkdyn.load("planar_3rrr", **{name: value})


def test_unreachable_pose(robot):
    far = [1.0, 0.0, 0.0]
    assert not cf.inverse(robot.params, far)[1][0]
    assert np.isnan(cf.inverse(robot.params, far)[0]).any()
    with pytest.raises(pkdyn.UnreachablePoseError):
        pkdyn.inverse_geometry(robot, _pose6(far))


def test_actuator_limit_violation():
    r = pkdyn.load("planar_3rrr", q_min=-2.45, geometry=False)
    p = r.params
    X = _poses(pkdyn.library.FAMILIES["planar_3rrr"].params(), 400, np.random.default_rng(18))
    q1, _ = cf.inverse(p, X, p.elbow)
    k = int(np.argmin(q1.min(axis=1)))
    assert q1[k].min() < p.q_min
    with pytest.raises(pkdyn.JointLimitError) as err:
        pkdyn.inverse_geometry(r, _pose6(X[k]))
    assert err.value.joint == f"proximal{int(np.argmin(q1[k])) + 1}"
