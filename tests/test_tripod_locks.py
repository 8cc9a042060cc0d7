"""Lockable passive joints as rigid constraint models (pkdyn.tripod.locks).

The residual of each kind of lock is compared with the closed form of its geometry: a point at
``arm`` from a rotation axis moves by the chord ``2 arm |sin(dq / 2)|``; a point on the first
axis of a universal joint does not move with the first angle.
"""

import math

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.tripod.locks import LOCK_ARM, Lock, lock_constraint, lock_values
from solvers import ClosureSet


@pytest.fixture(scope="module")
def robot() -> pkdyn.Robot:
    return pkdyn.load("tripod", geometry=False)


def _set(robot: pkdyn.Robot, q: np.ndarray, joint: str, k: int, value: float) -> np.ndarray:
    q = q.copy()
    q[robot.model.joints[robot.model.getJointId(joint)].idx_q + k] = value
    return q


def _random_q(robot: pkdyn.Robot, rng: np.random.Generator) -> np.ndarray:
    return pin.integrate(robot.model, robot.q_home, rng.uniform(-0.3, 0.3, robot.nv))


@pytest.mark.parametrize("joint", ["branch1_q6", "branch2_a", "branch3_b"])
def test_revolute_lock_residual_is_the_chord_of_the_angle_error(robot, joint):
    rng = np.random.default_rng(0)
    cm = lock_constraint(robot.model, Lock(joint, (0,), (0.2,)))
    assert cm.type == pin.ContactType.CONTACT_3D
    cs = ClosureSet(robot.model, [cm])
    data = robot.model.createData()
    for _ in range(20):
        q = _random_q(robot, rng)  # every other joint anywhere
        dq = rng.uniform(-1.0, 1.0)
        r = cs.residual(data, _set(robot, q, joint, 0, 0.2 + dq))
        assert np.linalg.norm(r) == pytest.approx(2.0 * LOCK_ARM * abs(math.sin(dq / 2)), abs=1e-12)


def test_prismatic_lock_residual_is_the_length_error(robot):
    cs = ClosureSet(robot.model, [lock_constraint(robot.model, Lock("branch1_qL", (0,), (0.7,)))])
    data = robot.model.createData()
    q = _random_q(robot, np.random.default_rng(1))
    for d in (-0.05, 0.0, 0.03):
        r = cs.residual(data, _set(robot, q, "branch1_qL", 0, 0.7 + d))
        assert np.linalg.norm(r) == pytest.approx(abs(d), abs=1e-12)


def test_universal_second_coordinate_lock_ignores_the_first(robot):
    """Support branches lock q1 (coordinate 1) and keep q2 (coordinate 0) free."""
    rng = np.random.default_rng(2)
    cs = ClosureSet(
        robot.model, [lock_constraint(robot.model, Lock("branch2_q2q1", (1,), (0.15,)))]
    )
    data = robot.model.createData()
    q = _random_q(robot, rng)
    for _ in range(20):
        q0, dq1 = rng.uniform(-1.0, 1.0, 2)
        qq = _set(robot, _set(robot, q, "branch2_q2q1", 0, q0), "branch2_q2q1", 1, 0.15 + dq1)
        r = cs.residual(data, qq)
        assert np.linalg.norm(r) == pytest.approx(2 * LOCK_ARM * abs(math.sin(dq1 / 2)), abs=1e-12)


def test_whole_universal_lock_is_a_weld_of_rank_two(robot):
    rng = np.random.default_rng(3)
    values = (0.1, -0.2)
    cm = lock_constraint(robot.model, Lock("branch1_q2q1", (0, 1), values))
    assert cm.type == pin.ContactType.CONTACT_6D
    cs = ClosureSet(robot.model, [cm])
    data = robot.model.createData()
    q = _random_q(robot, rng)
    q = _set(robot, _set(robot, q, "branch1_q2q1", 0, values[0]), "branch1_q2q1", 1, values[1])
    r, J = cs.residual_and_jacobian(data, q)
    assert np.max(np.abs(r)) < 1e-12
    s = np.linalg.svd(J, compute_uv=False)
    assert int(np.sum(s > 1e-9 * s[0])) == 2
    # the rotation error is the relative rotation of the universal joint: R1(q0) R2(q1)
    a1, a2 = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, -1.0])
    d0, d1 = 0.3, -0.25
    q2 = _set(
        robot, _set(robot, q, "branch1_q2q1", 0, values[0] + d0), "branch1_q2q1", 1, values[1] + d1
    )
    R_lock = pin.exp3(a1 * values[0]) @ pin.exp3(a2 * values[1])
    R = pin.exp3(a1 * (values[0] + d0)) @ pin.exp3(a2 * (values[1] + d1))
    angle = np.linalg.norm(pin.log3(R_lock.T @ R))
    assert np.linalg.norm(cs.residual(data, q2)[3:]) == pytest.approx(angle, abs=1e-12)


def test_lock_jacobians_match_finite_differences(robot):
    rng = np.random.default_rng(4)
    locks = [
        Lock("branch1_q2q1", (0, 1), (0.05, 0.1)),
        Lock("branch1_a", (0,), (0.02,)),
        Lock("branch2_q2q1", (1,), (-0.1,)),
        Lock("branch3_q6", (0,), (0.3,)),
    ]
    cs = ClosureSet(robot.model, [lock_constraint(robot.model, lk) for lk in locks])
    data = robot.model.createData()
    q = _random_q(robot, rng)
    _, J = cs.residual_and_jacobian(data, q)
    h = 1e-6
    Jfd = np.column_stack(
        [
            (
                cs.residual(data, pin.integrate(robot.model, q, h * e))
                - cs.residual(data, pin.integrate(robot.model, q, -h * e))
            )
            / (2 * h)
            for e in np.eye(robot.nv)
        ]
    )
    assert np.max(np.abs(J - Jfd)) < 1e-8


def test_lock_values_reads_the_coordinates(robot):
    q = _set(robot, robot.q_home, "branch3_q2q1", 1, 0.42)
    assert lock_values(robot.model, q, "branch3_q2q1", [1]) == (0.42,)


@pytest.mark.parametrize(
    ("lock", "what"),
    [
        (Lock("nope", (0,), (0.0,)), "no joint"),
        (Lock("nacelle", (0,), (0.0,)), "cannot be locked"),
        (Lock("branch1_q2q1", (0,), (0.0,)), "first coordinate"),
        (Lock("branch1_q6", (1,), (0.0,)), "coordinates"),
    ],
)
def test_bad_locks_name_the_culprit(robot, lock, what):
    with pytest.raises(pkdyn.InvalidInputError, match=what):
        lock_constraint(robot.model, lock)


def test_lock_values_must_match_coordinates():
    with pytest.raises(pkdyn.InvalidInputError):
        Lock("branch1_q6", (0,), (0.0, 1.0))
    with pytest.raises(pkdyn.InvalidInputError):
        Lock("branch1_q6", (0,), (float("nan"),))
