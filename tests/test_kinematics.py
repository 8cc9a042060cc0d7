"""Kinematic models (issue 4): A, B, J, J_inv against finite differences of the geometric models."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import random_configs

import pkdyn
from pkdyn.analysis import kinematics as kin
from pkdyn.analysis import screws

ROBOTS = ["delta", "gough_stewart", "planar_3rrr", "five_bar"]
# pose perturbation amplitudes (translation [m], rotation [rad]) for random reachable poses
SPREAD = {
    "delta": (0.06, 0.0),
    "gough_stewart": (0.03, 0.08),
    "planar_3rrr": (0.05, 0.3),
    "five_bar": (0.05, 0.0),
    "tripod": (0.03, 0.05),
}


@pytest.fixture(scope="module")
def robots(delta, gough_stewart):
    out = {"delta": delta, "gough_stewart": gough_stewart}
    for name in ("planar_3rrr", "five_bar", "tripod"):
        out[name] = pkdyn.load(name, geometry=False)
    return out


def _configs(robot, n, seed):
    return random_configs(robot, n, seed, SPREAD[robot.name])


def pose_error(robot, M0, M):
    """Task components of the pose change: world position, platform-frame rotation vector."""
    e = np.concatenate([M.translation - M0.translation, pin.log3(M0.rotation.T @ M.rotation)])
    return e[robot.task_rows]


def fd_jacobian(robot, q, h=1e-6):
    """x_dot / qa_dot by central differences of the direct geometric model (warm started)."""
    qa0 = q[robot.actuated_q]
    M0 = robot.platform_placement(q)
    cols = []
    for j in range(qa0.size):
        e = []
        for s in (1.0, -1.0):
            qa = qa0.copy()
            qa[j] += s * h
            fk = pkdyn.forward_geometry(robot, qa, q_init=q, check_limits=False)
            e.append(pose_error(robot, M0, fk.placement))
        cols.append((e[0] - e[1]) / (2 * h))
    return np.column_stack(cols)


def fd_inverse_jacobian(robot, q, h=1e-6):
    """qa_dot / x_dot by central differences of the inverse geometric model."""
    M0 = robot.platform_placement(q)
    cols = []
    for k in robot.task_rows:
        qa = []
        for s in (1.0, -1.0):
            d = np.zeros(6)
            d[k] = s * h
            target = pin.SE3(M0.rotation @ pin.exp3(d[3:]), M0.translation + d[:3])
            qa.append(pkdyn.inverse_geometry(robot, target, q_init=q, check_limits=False).qa)
        cols.append((qa[0] - qa[1]) / (2 * h))
    return np.column_stack(cols)


@pytest.mark.parametrize("name", ROBOTS)
def test_direct_jacobian_matches_fk_differences(robots, name):
    robot = robots[name]
    for q in _configs(robot, 3, 11):
        km = kin.kinematic_models(robot, q)
        J_fd = fd_jacobian(robot, q)
        np.testing.assert_allclose(km.J, J_fd, atol=1e-7 * max(1.0, np.abs(J_fd).max()))


@pytest.mark.parametrize("name", ROBOTS)
def test_inverse_jacobian_matches_ik_differences(robots, name):
    robot = robots[name]
    for q in _configs(robot, 3, 12):
        km = kin.kinematic_models(robot, q)
        Ji_fd = fd_inverse_jacobian(robot, q)
        np.testing.assert_allclose(km.J_inv, Ji_fd, atol=1e-7 * max(1.0, np.abs(Ji_fd).max()))
        np.testing.assert_allclose(km.J_inv @ km.J, np.eye(km.n_a), atol=1e-9)


def test_tripod_jacobian_matches_fk_differences(robots):
    """A 6-DOF robot with 6D weld closures and hinges: rotation rows included."""
    robot = robots["tripod"]
    (q,) = _configs(robot, 1, 13)
    J_fd = fd_jacobian(robot, q)
    np.testing.assert_allclose(kin.kinematic_models(robot, q).J, J_fd, atol=1e-7 * 10)


@pytest.mark.parametrize("name", ROBOTS)
def test_normalisation_and_relation(robots, name):
    """[B, -A] has orthonormal rows, and A x_dot = B qa_dot holds for FK differences."""
    robot = robots[name]
    (q,) = _configs(robot, 1, 14)
    km = kin.kinematic_models(robot, q)
    R = np.hstack([km.B, -km.A])
    np.testing.assert_allclose(R @ R.T, np.eye(km.m), atol=1e-12)
    J_fd = fd_jacobian(robot, q)
    np.testing.assert_allclose(km.A @ J_fd, km.B, atol=1e-7)
    assert np.all(np.isfinite([km.cond_A, km.cond_B]))


@pytest.mark.parametrize("name", ROBOTS)
def test_joint_velocities_respect_closures(robots, name):
    robot = robots[name]
    (q,) = _configs(robot, 1, 15)
    km = kin.kinematic_models(robot, q)
    qa_dot = np.linspace(0.5, -0.3, km.n_a)
    v = kin.joint_velocities(robot, q, qa_dot)
    np.testing.assert_allclose(v[robot.actuated_v], qa_dot, atol=0)
    if robot.closure_set.nc:
        np.testing.assert_allclose(km.Jc @ v, 0.0, atol=1e-10)
    # the platform velocity of these joint velocities is J qa_dot
    np.testing.assert_allclose(km.Jx @ v, kin.platform_twist(robot, q, qa_dot), atol=1e-10)
    # integrating them keeps the mechanism assembled to second order
    dt = 1e-4
    q2 = pin.integrate(robot.model, q, v * dt)
    assert pkdyn.closure_residual(robot, q2) < 50 * dt**2


@pytest.mark.parametrize("name", ROBOTS)
def test_twist_and_rates_round_trip(robots, name):
    robot = robots[name]
    (q,) = _configs(robot, 1, 16)
    qa_dot = np.random.default_rng(0).normal(size=len(robot.actuators))
    x_dot = kin.platform_twist(robot, q, qa_dot)
    np.testing.assert_allclose(kin.actuator_rates(robot, q, x_dot), qa_dot, atol=1e-9)


@pytest.mark.parametrize("name", ROBOTS)
def test_reciprocal_screws_match_general_path(robots, name):
    """Pasqui's reciprocal-screw A, B (seed 001) give the J of the general elimination."""
    robot = robots[name]
    for q in _configs(robot, 3, 17):
        km = kin.kinematic_models(robot, q)
        A, B = screws.reciprocal_screws(robot, q)
        np.testing.assert_allclose(np.linalg.solve(A, B), km.J, atol=1e-8)
        # same relations: the orthonormal forms share their singular values
        An, Bn = screws.normalise(A, B)
        np.testing.assert_allclose(np.linalg.svd(An, compute_uv=False), km.sigma_A, atol=1e-8)
        np.testing.assert_allclose(np.linalg.svd(Bn, compute_uv=False), km.sigma_B, atol=1e-8)


def test_planar_3rrr_seed_matrices(robots):
    """Seed 001's B_ii = l1 l2 sin q_2^i, with q_2^i read from the model's joint frames."""
    robot = robots["planar_3rrr"]
    p = robot.params
    (q,) = _configs(robot, 1, 18)
    _, B = screws.reciprocal_screws(robot, q)
    pin.framesForwardKinematics(robot.model, robot.data, q)
    for i in range(3):
        prox = robot.data.oMi[robot.model.getJointId(f"proximal{i + 1}")]
        dist = robot.data.oMi[robot.model.getJointId(f"distal{i + 1}")]
        u1, u2 = prox.rotation[:2, 0], dist.rotation[:2, 0]
        sin_q2 = u1[0] * u2[1] - u1[1] * u2[0]
        assert B[i, i] == pytest.approx(p.l1 * p.l2 * sin_q2, abs=1e-10)


def test_gough_stewart_reciprocal_screws_are_leg_lines(robots):
    """A rows: unit leg directions and their moments about the platform origin; B = I."""
    robot = robots["gough_stewart"]
    (q,) = _configs(robot, 1, 19)
    A, B = screws.reciprocal_screws(robot, q)
    np.testing.assert_allclose(np.linalg.norm(A[:, :3], axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(B, np.eye(6), atol=0)
    # a leg line's twist-reciprocal: a pure rotation about the leg line changes no leg length
    M = robot.platform_placement(q)
    for i, cm in enumerate(robot.constraint_models):
        Bw = M.act(cm.joint2_placement.translation)
        u = A[i, :3]
        twist = np.concatenate([np.cross(u, M.translation - Bw), M.rotation.T @ u])
        assert abs(A[i] @ twist) < 1e-12


def test_unassembled_or_malformed_q_is_rejected(robots):
    robot = robots["delta"]
    q = robot.q_home.copy()
    q[robot.actuated_q[0]] += 0.1
    with pytest.raises(pkdyn.InvalidInputError, match="not an assembled"):
        kin.kinematic_models(robot, q)
    with pytest.raises(pkdyn.InvalidInputError):
        kin.kinematic_models(robot, q[:-1])
    with pytest.raises(pkdyn.InvalidInputError):
        kin.platform_twist(robot, robot.q_home, [1.0, 2.0])


def test_jacobian_json(robots):
    robot = robots["gough_stewart"]
    out = kin.jacobian_json(robot, robot.q_home)
    for key in ("A", "B", "J"):
        assert np.asarray(out[key]).shape == (6, 6)
    # J is the derivative of the direct geometric model, and A J = B
    np.testing.assert_allclose(out["J"], fd_jacobian(robot, robot.q_home), atol=1e-7)
    np.testing.assert_allclose(np.asarray(out["A"]) @ out["J"], out["B"], atol=1e-10)
    assert out["task"] == ["x", "y", "z", "rx", "ry", "rz"]
