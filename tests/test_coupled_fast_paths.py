"""The fast paths of the coupled dynamics and of the inverse dynamics give the general answers.

- :func:`solvers.numerics.lstsq_spd_factor`: the Cholesky solve equals :func:`lstsq` where it is
  certified, and declines (``None``) on singular or too ill-conditioned matrices;
- the forward dynamics of a robot with couplings and no closure (Mini Cheetah: 12 rotors tied
  to its knees) against a closed form, the dense KKT system of ``crba``, ``nle`` and the
  couplings' constant rows, with the couplings' Baumgarte terms; redundant couplings (one
  given twice) fall back to the minimum-norm forces and leave the motion unchanged;
- the residual of constant rows (``A_q q - b``) against the general batched evaluation,
  a locked joint included;
- inverse dynamics without constraint rows (Tello: a floating base) solved in batches: the
  same efforts as the general path sample by sample, the same errors.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.dynamics import actuation
from solvers import ForwardDynamics, InverseDynamics, numerics
from solvers.coupling import CouplingRows, JointCoupling, LinearCoupling
from solvers.inverse_dynamics import InfeasibleError

DATA = Path(__file__).resolve().parent / "data/public/generalized_rbda/robot-models"


def _load(name: str) -> pkdyn.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pkdyn.load(DATA / name, geometry=False)


@pytest.fixture(scope="module")
def cheetah() -> pkdyn.Robot:
    return _load("mini_cheetah.urdf")


def test_spd_factor_solves_like_lstsq_and_declines_singular_matrices() -> None:
    rng = np.random.default_rng(3)
    B = rng.normal(size=(6, 9))
    A = B @ B.T
    b = rng.normal(size=6)
    Li = numerics.lstsq_spd_factor(A, 1e-12)
    assert Li is not None
    x = Li.T @ (Li @ b)
    ref = numerics.lstsq(A, b, 1e-12)
    assert np.allclose(x, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())
    assert np.allclose(A @ x, b, atol=1e-10 * np.abs(b).max())
    # rank deficient (a row given twice): lstsq's minimum norm is needed
    B2 = np.vstack([B[:5], B[:1]])
    assert numerics.lstsq_spd_factor(B2 @ B2.T, 1e-12) is None
    # positive definite but beyond the cut-off: lstsq would drop a singular value
    U = np.linalg.qr(rng.normal(size=(6, 6)))[0]
    s = np.array([1.0, 0.5, 0.1, 1e-2, 1e-3, 1e-13])
    assert numerics.lstsq_spd_factor(U @ np.diag(s) @ U.T, 1e-12) is None
    # the same within the cut-off, with the margin: certified
    s[-1] = 1e-9
    assert numerics.lstsq_spd_factor(U @ np.diag(s) @ U.T, 1e-12) is not None


def _rows(robot: pkdyn.Robot) -> CouplingRows:
    rows = robot.constraints.coupling_rows
    assert rows is not None
    return rows


def _kkt(model: pin.Model, C: np.ndarray, q, v, tau, rhs_c) -> tuple[np.ndarray, np.ndarray]:
    """``M a + h = tau + C^T mu``, ``C a = rhs_c``: the dense solve."""
    data = model.createData()
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    h = pin.nle(model, data, q, v)
    k = C.shape[0]
    K = np.block([[M, -C.T], [C, np.zeros((k, k))]])
    x = np.linalg.solve(K, np.concatenate([tau - h, rhs_c]))
    return x[: model.nv], x[model.nv :]


def test_coupled_acceleration_is_the_kkt_solution(cheetah: pkdyn.Robot) -> None:
    model = cheetah.model
    rows = _rows(cheetah)
    fd = ForwardDynamics(model, cheetah.constraints, actuation(cheetah), integrator="euler")
    assert rows.constant and fd.n_pin == 0  # couplings only: G = M^-1 C^T
    rng = np.random.default_rng(7)
    kp, kd = fd._pd
    for _ in range(3):
        # off the couplings (position and velocity): the Baumgarte terms act
        q = pin.integrate(model, cheetah.q_home, 0.2 * rng.normal(size=model.nv))
        v = rng.normal(size=model.nv)
        tau = 5.0 * rng.normal(size=model.nv)
        C = rows.jacobian(q)
        a = fd.acceleration(q, v, tau)
        a_ref, mu_ref = _kkt(model, C, q, v, tau, -kd * C @ v - kp * rows.residual(q))
        assert fd._schur is not None
        assert np.allclose(a, a_ref, rtol=0.0, atol=1e-9 * np.abs(a_ref).max())
        assert np.allclose(fd._schur.mu, mu_ref, rtol=0.0, atol=1e-9 * np.abs(mu_ref).max())
        assert fd._schur._Li is not None  # the Cholesky path was taken


def test_redundant_couplings_give_the_same_motion_and_shared_forces(
    cheetah: pkdyn.Robot,
) -> None:
    model = cheetah.model
    couplings = list(_rows(cheetah).couplings)
    twice = [*couplings, LinearCoupling("again", couplings[0].terms, couplings[0].offset)]
    one = ForwardDynamics(model, [], couplings=couplings, integrator="euler")
    two = ForwardDynamics(model, [], couplings=twice, integrator="euler")
    rng = np.random.default_rng(11)
    q = pin.integrate(model, cheetah.q_home, 0.1 * rng.normal(size=model.nv))
    v = rng.normal(size=model.nv)
    tau = rng.normal(size=model.nv)
    a1 = one.acceleration(q, v, tau)
    a2 = two.acceleration(q, v, tau)
    assert two._schur is not None and one._schur is not None
    assert two._schur._Li is None  # singular C M^-1 C^T: lstsq's minimum norm
    assert np.allclose(a2, a1, rtol=0.0, atol=1e-9 * np.abs(a1).max())
    mu1, mu2 = one._schur.mu, two._schur.mu
    scale = np.abs(mu1).max()
    assert np.allclose(mu2[1:-1], mu1[1:], rtol=0.0, atol=1e-8 * scale)
    assert np.allclose([mu2[0], mu2[-1]], 0.5 * mu1[0], rtol=0.0, atol=1e-8 * scale)


def test_constant_rows_residual_matches_the_general_evaluation(cheetah: pkdyn.Robot) -> None:
    model = cheetah.model
    base = list(_rows(cheetah).couplings)
    jid = base[0].terms[0][0]
    locked = JointCoupling("locked", joint=jid, source=None, coefficients=(0.3,), joint_ref=0.1)
    rows = CouplingRows(model, [*base[1:], locked])
    assert rows.constant and rows._Aq is not None
    rng = np.random.default_rng(5)
    Q = np.array(
        [pin.integrate(model, cheetah.q_home, rng.normal(size=model.nv)) for _ in range(4)]
    )
    batch = rows.residual(Q)
    for q, r in zip(Q, batch, strict=True):
        assert np.allclose(rows.residual(q), r, rtol=0.0, atol=1e-12)
        assert np.allclose(rows._one(q, 0), r, rtol=0.0, atol=1e-12)
    assert rows.drift(Q, np.ones((4, model.nv))).shape == (4, rows.n)
    assert not rows.drift(Q[0], np.ones(model.nv)).any()


@pytest.fixture(scope="module")
def tello() -> pkdyn.Robot:
    return _load("tello_humanoid.urdf")


def _consistent_states(robot: pkdyn.Robot, n: int) -> tuple[np.ndarray, ...]:
    """States and accelerations a forward simulation makes (the base's equation holds)."""
    model = robot.model
    act = actuation(robot)
    fd = ForwardDynamics(model, robot.constraints, act, integrator="euler")
    rng = np.random.default_rng(2)
    q = robot.q_home
    v = np.zeros(model.nv)
    Q, V, A = [], [], []
    for _ in range(n):
        tau = np.zeros(model.nv)
        tau[act.v_index] = act.gains * rng.normal(size=act.n)
        a = fd.acceleration(q, v, tau)
        Q.append(q), V.append(v), A.append(a)
        v = v + 1e-3 * a
        q = pin.integrate(model, q, 1e-3 * v)
    return np.array(Q), np.array(V), np.array(A)


def test_tree_inverse_dynamics_in_batches_matches_the_general_path(tello: pkdyn.Robot) -> None:
    model = tello.model
    act = actuation(tello)
    assert tello.constraints.n == 0 and act.n < model.nv  # a floating base: passive rows
    Q, V, A = _consistent_states(tello, 12)
    solver = InverseDynamics(model, tello.constraints, act)
    out = solver.trajectory(Q, V, A)
    for i in range(Q.shape[0]):
        ref = solver.solve(Q[i], V[i], A[i])  # (no rows: the SVD path)
        b = pin.rnea(model, model.createData(), Q[i], V[i], A[i])
        scale = np.abs(b).max()
        assert np.allclose(out.tau[i], ref.tau, rtol=0.0, atol=1e-10 * scale)
        assert np.allclose(out.tau[i], b[act.v_index] / act.gains, rtol=0.0, atol=1e-10 * scale)
        assert out.residual[i] <= 1e-7 * max(1.0, scale)
    # an acceleration of the floating base no actuator can produce: refused at that sample
    A_bad = A.copy()
    A_bad[5, 2] += 1.0
    with pytest.raises(InfeasibleError) as err:
        solver.trajectory(Q, V, A_bad)
    assert err.value.sample == 5 and err.value.actuator is None
    # a bound: the first sample beyond it, naming the actuator
    k = int(np.argmax(np.abs(out.tau).max(axis=0)))
    upper = np.full(act.n, 1e9)
    upper[k] = 0.5 * np.abs(out.tau[:, k]).max()
    lower = -upper
    bounded = InverseDynamics(model, tello.constraints, act, lower=lower, upper=upper)
    with pytest.raises(InfeasibleError) as err:
        bounded.trajectory(Q, V, A)
    first = int(np.flatnonzero(np.abs(out.tau[:, k]) > upper[k])[0])
    assert err.value.sample == first and err.value.actuator == k
