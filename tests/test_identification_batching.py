"""The fast identification path against a per-sample reference built from other code.

:class:`~pkdyn.identification.motion.MotionSampler` solves most samples together (batched
Newton from Hermite guesses between sequentially solved anchors), evaluates the closures of a
batch with :class:`solvers.SampledKinematics` (placements read from one Jacobian call, drift
from the time variation of the world Jacobian) and the regressor multiplies the elimination
maps before gathering columns. The reference here works sample by sample with
:class:`solvers.ClosureSet` (Jacobian and drift, :func:`numpy.linalg.pinv`) and Pinocchio's
joint-torque regressor, mapped by ``T = [I; -(J_p^+ J_a)^T]`` in plain numpy. A dense 1 kHz
motion over two batches (anchors, batched samples, the batch boundary) must give

- configurations on the closures (residual <= 1e-10) with the measured actuators, equal to the
  sample-by-sample Newton solutions where the actuators determine every joint;
- regressor rows equal to the reference's within 1e-10 of their largest entry.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from support.dynamics_truth import multisine

import pkdyn
from pkdyn.dynamics.actuation import with_drives
from pkdyn.identification import parameter_set
from pkdyn.identification.motion import ASSEMBLY_TOL, MotionBatch, MotionSampler
from pkdyn.identification.regressor import ClosedLoopRegressor


def _motion(robot, n, amp, dt=1e-3):
    return multisine(robot, n, dt, amp, 11, harmonics=3, f0=1.5)


def _reference_rows(robot, ps, Q, qd, qdd):
    """Rows (n, n_a, p_id) sample by sample: ClosureSet, pinv, Pinocchio's regressor."""
    model, cs = robot.model, robot.closure_set
    data = model.createData()
    va = np.asarray(robot.actuated_v)
    vp = np.setdiff1d(np.arange(model.nv), va)
    reg = ClosedLoopRegressor(robot, ps)
    rows, body = [], []
    for i, q in enumerate(Q):
        J = cs.jacobian(data, q)
        X = np.linalg.pinv(J[:, vp], rcond=1e-12) @ J[:, va]
        v, a = np.zeros(model.nv), np.zeros(model.nv)
        v[va], a[va] = qd[i], qdd[i]
        v[vp] = -X @ qd[i]
        gamma = cs.drift(data, q, v)
        a[vp] = -np.linalg.pinv(J[:, vp], rcond=1e-12) @ (J[:, va] @ qdd[i] + gamma)
        T = np.zeros((va.size, model.nv))
        T[np.arange(va.size), va] = 1.0
        T[:, vp] = -X.T
        body.append(T @ pin.computeJointTorqueRegressor(model, data, q, v, a))
        b = MotionBatch(q[None], v[None], a[None], J[None])
        rows.append(reg.rows(b)[0][0])
    return np.array(rows), np.array(body)


@pytest.mark.parametrize(
    ("name", "amp"), [("delta", 0.2), ("gough_stewart", 0.02), ("tripod", 0.004)]
)
def test_batched_rows_equal_the_per_sample_reference(name, amp):
    robot = with_drives(
        pkdyn.load(name, geometry=False), rotor_inertia=1e-5, viscous=1e-4, coulomb=0.02
    )
    ps = parameter_set(robot)
    t, qa, qd, qdd = _motion(robot, 400, amp)
    sampler = MotionSampler(robot)
    batches = [
        sampler.batch(t[s : s + 256], qa[s : s + 256], qd[s : s + 256], qdd[s : s + 256], s)
        for s in (0, 256)
    ]
    Q = np.concatenate([b.q for b in batches])
    reg = ClosedLoopRegressor(robot, ps)
    Y = np.concatenate([reg.rows(b)[0] for b in batches])
    data = robot.model.createData()
    for q, a in zip(Q, qa, strict=True):
        assert np.abs(robot.closure_set.residual(data, q)).max() <= ASSEMBLY_TOL
        np.testing.assert_array_equal(q[robot.actuated_q], a)
    Y_ref, body = _reference_rows(robot, ps, Q, qd, qdd)
    scale = np.abs(Y_ref).max()
    assert np.abs(Y - Y_ref).max() <= 1e-10 * scale
    W = reg.full(batches[0])[0][:, :, : body.shape[2]]  # every body identified here
    np.testing.assert_allclose(W, body[:256], rtol=0, atol=1e-10 * scale)
    if name != "delta":  # no internal mobility: the assembly is unique near the motion
        one = MotionSampler(robot)
        Q1 = np.concatenate(
            [one.configurations(qa[s : s + 256], t[s : s + 256], s)[0] for s in (0, 256)]
        )
        np.testing.assert_allclose(Q, Q1, rtol=0, atol=1e-9)
