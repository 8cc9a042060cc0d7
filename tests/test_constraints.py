"""The constraint layer (:mod:`solvers.constraints`): every row kind against finite differences.

Rows of point, hinge (5 independent rows) and weld closures, of planar closures reduced to their
in-plane rows (point and hinge about the normal: 2, weld and a hinge across the plane: 3), of
linear couplings over revolute, prismatic and unbounded (cos/sin) joints and of polynomial
couplings, on seeded random configurations away from closure:

- the Jacobian against central differences of the residual along ``pin.integrate``;
- ``J a + gamma`` against the second difference of the residual along
  ``q(t) = q (+) (t v + t^2 a / 2)`` (at any velocity for every kind but the welds, whose drift
  is exact when their relative velocity vanishes: checked on velocities the constraints allow);
- the reduced rows span the same motions as the unreduced ones at closure (same null space), and
  the planar rows the same as the spatial ones;
- the views ``closures`` and ``couplings`` are the set's own rows; nothing depends on an earlier
  call (an evaluation at another configuration in between changes nothing).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest

from solvers import numerics
from solvers.closure import Closure
from solvers.constraints import ConstraintSet
from solvers.coupling import JointCoupling, LinearCoupling

EPS = 1e-6


def _body(model: pin.Model, jid: int, rng: np.random.Generator) -> None:
    I = pin.Inertia.Random()
    model.appendBodyToJoint(
        jid, pin.Inertia(1.0 + rng.random(), I.lever, np.eye(3) * 0.01), pin.SE3.Identity()
    )


def spatial_model() -> tuple[pin.Model, list[Closure]]:
    """A tree with revolute, unbounded, prismatic, spherical and universal joints; closures of
    every kind between its bodies, in general position."""
    rng = np.random.default_rng(5)
    m = pin.Model()

    def add(parent, jm, xyz, name, rpy=(0.0, 0.0, 0.0)):
        M = pin.SE3(pin.rpy.rpyToMatrix(np.array(rpy)), np.array(xyz, dtype=float))
        j = m.addJoint(parent, jm, M, name)
        _body(m, j, rng)
        return j

    a1 = add(0, pin.JointModelRZ(), (0, 0, 0), "a1")
    a2 = add(a1, pin.JointModelSpherical(), (0.3, 0, 0.1), "a2", (0.2, -0.1, 0.3))
    a3 = add(a2, pin.JointModelRUBY(), (0.2, 0.1, 0), "a3")
    b1 = add(0, pin.JointModelPX(), (0, 0.4, 0), "b1", (0.1, 0.2, 0))
    b2 = add(b1, pin.JointModelUniversal(np.array([1.0, 0, 0]), np.array([0, 1.0, 0])),
             (0.1, 0, 0.2), "b2")  # fmt: skip
    b3 = add(b2, pin.JointModelRX(), (0, 0.2, 0.1), "b3", (0.3, 0.0, -0.2))

    def frame(xyz, rpy):
        return pin.SE3(pin.rpy.rpyToMatrix(np.array(rpy)), np.array(xyz, dtype=float))

    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    closures = [
        Closure(
            "p", "point", a3, frame((0.1, 0, 0.05), (0, 0, 0)), b3, frame((0, 0.1, 0), (0, 0, 0))
        ),
        Closure(
            "h",
            "hinge",
            a2,
            frame((0.05, 0.1, 0), (0.4, 0.1, -0.3)),
            b2,
            frame((0.1, 0, 0.1), (-0.2, 0.3, 0.1)),
            tuple(axis),
        ),  # fmt: skip
        Closure(
            "w", "weld", a1, frame((0.2, 0, 0), (0.1, 0, 0.2)), b3, frame((0, 0, 0.1), (0, 0.3, 0))
        ),
        Closure(
            "g",
            "hinge",
            0,
            frame((0.5, 0.2, 0), (0, 0.2, 0)),
            a3,
            frame((0, 0.1, 0.1), (0.1, 0, 0)),
            (0.0, 0.0, 1.0),
        ),  # fmt: skip
    ]
    return m, closures


def planar_model() -> tuple[pin.Model, list[Closure]]:
    """A mechanism moving in the plane normal to ``z``: revolute joints about ``z`` (one of them
    unbounded), a prismatic joint along ``x``; closures in the plane (their frames turned about
    ``z`` only), one hinge about ``x`` (across the plane)."""
    rng = np.random.default_rng(6)
    m = pin.Model()

    def add(parent, jm, xyz, name, yaw=0.0):
        M = pin.SE3(pin.rpy.rpyToMatrix(np.array([0.0, 0.0, yaw])), np.array(xyz, dtype=float))
        j = m.addJoint(parent, jm, M, name)
        _body(m, j, rng)
        return j

    a1 = add(0, pin.JointModelRZ(), (0, 0, 0.1), "a1")
    a2 = add(a1, pin.JointModelRZ(), (0.3, 0, 0), "a2", 0.4)
    b1 = add(0, pin.JointModelPX(), (0.5, 0, 0.1), "b1", 0.3)
    b2 = add(b1, pin.JointModelRUBZ(), (0, 0.2, 0), "b2", -0.2)
    b3 = add(b2, pin.JointModelRZ(), (0.25, 0, 0), "b3")

    def frame(xy, yaw):
        return pin.SE3(pin.rpy.rpyToMatrix(np.array([0.0, 0.0, yaw])), np.array([*xy, 0.0]))

    closures = [
        Closure("p", "point", a2, frame((0.2, 0), 0.0), b3, frame((0.1, 0.05), 0.0)),
        Closure("h", "hinge", a2, frame((0.1, 0.1), 0.3), b2, frame((0.05, 0), -0.4)),
        Closure("w", "weld", a1, frame((0.15, 0.02), 0.1), b3, frame((0, 0.1), 0.7)),
        Closure("x", "hinge", a1, frame((0.1, 0), 0.0), b1, frame((0, 0.1), 0.2), (1.0, 0, 0)),
    ]
    return m, closures


def couplings(model: pin.Model) -> list:
    """Linear sums over revolute, prismatic and unbounded joints (wrapped with the period
    their circular joints give, or not), a polynomial law and a lock."""
    ids = {model.names[j]: j for j in range(1, model.njoints) if model.joints[j].nv == 1}
    circ = [j for j in ids.values() if model.joints[j].nq == 2]
    lin = [j for j in ids.values() if model.joints[j].nq == 1]
    out = [
        LinearCoupling("sum", ((lin[0], 1.0), (lin[1], -2.5), (circ[0], 2.0)), 0.1),
        LinearCoupling("diff", ((lin[0], 0.7), (lin[-1], 1.3)), -0.2),
        LinearCoupling("odd", ((circ[0], 0.7), (lin[1], 1.0)), 0.05),  # no wrapping
        JointCoupling("cam", lin[-1], circ[0], (0.1, -0.5, 0.3, 0.05, -0.02), 0.2, 0.05),
        JointCoupling("lock", lin[0], None, (0.25,), 0.1),
    ]
    return out


def _fd_jacobian(cs: ConstraintSet, data, q: np.ndarray) -> np.ndarray:
    model = cs.model
    return np.column_stack(
        [
            (
                cs.residual(data, pin.integrate(model, q, EPS * e))
                - cs.residual(data, pin.integrate(model, q, -EPS * e))
            )
            / (2 * EPS)
            for e in np.eye(model.nv)
        ]
    )


def _second_difference(cs, data, q, v, a, h=1e-4) -> np.ndarray:
    def r(t: float) -> np.ndarray:
        return cs.residual(data, pin.integrate(cs.model, q, v * t + 0.5 * a * t * t))

    return (r(h) - 2 * r(0.0) + r(-h)) / h**2


def _check(cs: ConstraintSet, seed: int, spread: float = 0.4) -> None:
    model = cs.model
    data = model.createData()
    rng = np.random.default_rng(seed)
    wrapped = [k for k, n in enumerate(cs.names) if n in ("sum", "diff", "cam")]
    for _ in range(4):
        q = pin.integrate(model, pin.neutral(model), spread * rng.standard_normal(model.nv))
        v, a = rng.standard_normal(model.nv), rng.standard_normal(model.nv)
        r, J = cs.residual_and_jacobian(data, q)
        if any(abs(abs(r[cs.offsets[k]]) - math.pi) < 1e-3 for k in wrapped):
            continue  # (a wrapped residual at its jump: no derivative there)
        np.testing.assert_allclose(J, _fd_jacobian(cs, data, q), rtol=0, atol=2e-8)
        # nothing remembered: the Jacobian after another residual evaluation is the same
        cs.residual(data, pin.integrate(model, q, rng.standard_normal(model.nv)))
        np.testing.assert_allclose(cs.jacobian(data, q), J, rtol=0, atol=1e-15)
        cs.residual(data, q)
        np.testing.assert_allclose(cs.jacobian_after_residual(data, q), J, rtol=0, atol=1e-15)
        r_loc = cs.local_residual(data, q)  # every row (unreduced), contact frames, for solvers
        J_loc = cs.local_jacobian_after_residual(data, q)
        assert r_loc.shape == (cs.n_local,) and J_loc.shape == (cs.n_local, model.nv)
        full = cs.unreduced
        np.testing.assert_allclose(np.abs(r_loc[full.nc :]), np.abs(r[cs.nc :]), atol=1e-15)
        for k in range(len(full.closures.names)):  # same norm per constraint model as the world
            lo, hi = full.offsets[k], full.offsets[k + 1]
            w = full.residual(data, q)[lo:hi]
            assert np.linalg.norm(r_loc[lo:hi]) == pytest.approx(np.linalg.norm(w), rel=1e-12)
        welds = [k for k, kind in enumerate(cs.kinds) if kind == "weld" and cs.sizes[k] == 6]
        if welds:  # a weld's drift is exact on motions that keep its relative velocity zero
            v = numerics.null_space(J, 1e-9) @ rng.standard_normal(model.nv - numerics.rank(J))
        np.testing.assert_allclose(
            J @ a + cs.drift(data, q, v), _second_difference(cs, data, q, v, a), rtol=0, atol=1e-5
        )


@pytest.mark.parametrize("reduce", [True, False])
def test_spatial_rows_match_finite_differences(reduce):
    model, closures = spatial_model()
    cs = ConstraintSet(model, closures, couplings(model), reduce=reduce)
    assert cs.sizes == [3, 5 if reduce else 6, 6, 5 if reduce else 6, 1, 1, 1, 1, 1]
    assert (cs.nc, cs.nk, cs.n) == (sum(cs.sizes[:4]), 5, sum(cs.sizes))
    _check(cs, 1)


@pytest.mark.parametrize("reduce", [True, False])
def test_planar_rows_match_finite_differences(reduce):
    model, closures = planar_model()
    cs = ConstraintSet(model, closures, couplings(model), reduce=reduce)
    if reduce:  # point 2, hinge about z 2, weld 3, hinge about x 3
        assert cs.sizes[:4] == [2, 2, 3, 3]
        assert all(np.allclose(n, [0, 0, 1]) for n in cs.closure_rows.normals)
    else:
        assert cs.sizes[:4] == [3, 6, 6, 6]
    _check(cs, 2, spread=0.3)


def _closed_at(model: pin.Model, closures: list[Closure], q: np.ndarray) -> list[Closure]:
    """The closures with their second frames moved onto the first ones at ``q``."""
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    out = []
    for c in closures:
        M2 = data.oMi[c.joint2].actInv(data.oMi[c.joint1] * c.placement1)
        out.append(dataclasses.replace(c, placement2=M2))
    return out


@pytest.mark.parametrize("build", [spatial_model, planar_model])
def test_reduced_rows_allow_the_same_motions(build):
    """At closure the reduced rows have the same null space as the unreduced ones (the hinge's
    two points; the planar rows against the spatial ones): only redundant rows were dropped,
    and what is left is independent."""
    model, closures = build()
    rng = np.random.default_rng(8)
    q = pin.integrate(model, pin.neutral(model), 0.5 * rng.standard_normal(model.nv))
    data = model.createData()
    for c in _closed_at(model, closures, q):
        full = ConstraintSet(model, [c], reduce=False)
        red = ConstraintSet(model, [c], reduce=True)
        assert np.abs(full.residual(data, q)).max() < 1e-14
        assert np.abs(red.residual(data, q)).max() < 1e-14
        J1, J2 = full.jacobian(data, q), red.jacobian(data, q)
        N1 = numerics.null_space(J1, 1e-9)
        N2 = numerics.null_space(J2, 1e-9)
        assert N1.shape == N2.shape, c.name
        assert np.abs(J2 @ N1).max() < 1e-12 and np.abs(J1 @ N2).max() < 1e-12
        # as many rows as independent motions they block (fewer joints between the two bodies
        # than rows: the mechanism's own redundancy)
        assert numerics.rank(J2, 1e-9) == numerics.rank(J1, 1e-9)
        free = int(np.count_nonzero(np.abs(J1).sum(axis=0)))
        if free >= red.n:
            assert numerics.rank(J2, 1e-9) == red.n, c.name
        assert red.n < full.n or c.kind in ("point", "weld") and build is spatial_model


def test_views_and_wrapping():
    model, closures = spatial_model()
    cs = ConstraintSet(model, closures, couplings(model), reduce=True)
    data = model.createData()
    q = pin.integrate(model, pin.neutral(model), np.full(model.nv, 0.3))
    r, J = cs.residual_and_jacobian(data, q)
    rc, Jc = cs.closures.residual_and_jacobian(data, q)
    rk, Jk = cs.couplings.residual_and_jacobian(data, q)
    np.testing.assert_array_equal(np.concatenate([rc, rk]), r)
    np.testing.assert_array_equal(np.vstack([Jc, Jk]), J)
    assert cs.closures.names == ["p", "h", "w", "g"]
    assert cs.couplings.names == ["sum", "diff", "odd", "cam", "lock"]
    assert cs.couplings.offsets.tolist() == [0, 1, 2, 3, 4, 5]
    # wrapping periods: 2 pi |a| of the one circular joint (a turn of it moves the row by that);
    # none without circular joint; none for a polynomial whose driven joint is not circular
    rows = cs.coupling_rows
    assert rows is not None
    np.testing.assert_allclose(rows.period, [4 * math.pi, 0.0, 1.4 * math.pi, 0.0, 0.0])
    # a circular joint's angle is its cos / sin pair's: a full turn changes nothing
    jc = next(j for j in range(1, model.njoints) if model.joints[j].nq == 2)
    i = model.joints[jc].idx_v
    dq = np.zeros(model.nv)
    dq[i] = 2 * math.pi
    np.testing.assert_allclose(cs.couplings.residual(data, pin.integrate(model, q, dq)), rk,
                               atol=1e-12)  # fmt: skip
    # batches: the same rows, state by state
    Q = np.array([pin.integrate(model, q, 0.2 * k * np.ones(model.nv)) for k in range(3)])
    batch_r = rows.residual(Q)
    batch_J = rows.jacobian(Q)
    for k in range(3):
        np.testing.assert_allclose(batch_r[k], rows.residual(Q[k]), atol=1e-14)
        np.testing.assert_allclose(batch_J[k], rows.jacobian(Q[k]), atol=1e-14)


def test_malformed_couplings_are_refused():
    model, _ = spatial_model()
    spherical = next(j for j in range(1, model.njoints) if model.joints[j].nv == 3)
    with pytest.raises(ValueError, match="'bad'.*1-DoF"):
        ConstraintSet(model, (), [LinearCoupling("bad", ((1, 1.0), (spherical, 1.0)))])
    with pytest.raises(ValueError, match="'twice'.*twice"):
        ConstraintSet(model, (), [LinearCoupling("twice", ((1, 1.0), (1, 2.0)))])
    with pytest.raises(ValueError, match="'zero'.*non-zero"):
        ConstraintSet(model, (), [LinearCoupling("zero", ((1, 0.0),))])
    with pytest.raises(ValueError, match="'nan'"):
        ConstraintSet(model, (), [LinearCoupling("nan", ((1, 1.0),), math.nan)])
    with pytest.raises(ValueError, match="'empty'"):
        ConstraintSet(model, (), [LinearCoupling("empty", ())])


@pytest.mark.parametrize("build", [spatial_model, planar_model])
def test_sampled_rows_equal_the_set_state_by_state(build):
    """The vectorised rows of many states (:class:`solvers.SampledKinematics`): residuals,
    Jacobians, ``J v`` and ``J a + gamma`` (point-like rows; a full weld's errors are its
    relative twist) and the drift at ``a = 0``, sample by sample."""
    from solvers.sampled import SampledKinematics

    model, closures = build()
    cs = ConstraintSet(model, closures, couplings(model))
    rng = np.random.default_rng(9)
    n = 5
    Q = np.array(
        [pin.integrate(model, pin.neutral(model), 0.4 * rng.standard_normal(model.nv))
         for _ in range(n)]
    )  # fmt: skip
    V, A = rng.standard_normal((n, model.nv)), rng.standard_normal((n, model.nv))
    sk = SampledKinematics(model, cs, size=8)
    data = model.createData()
    for k in range(n):
        pin.rnea(model, data, Q[k], V[k], A[k])
        pin.computeJointJacobians(model, data, Q[k])
        sk.capture(k, data)
    r, ev, ea = sk.closure_errors(n, V, Q, A)
    ref = SampledKinematics(model, cs, size=8)
    for k in range(n):
        ref.capture_configuration(k, Q[k])
    rr, JJ = ref.residuals_and_jacobians(np.arange(n))
    for k in range(n):
        ref.capture_drift(k, Q[k], V[k])
    gamma_batch = ref.acceleration_errors(n, V)
    point_like = np.concatenate(
        [np.arange(cs.offsets[i], cs.offsets[i + 1])
         for i, kind in enumerate(cs.kinds) if kind != "weld" or cs.sizes[i] != 6]
    )  # fmt: skip
    for k in range(n):
        r0, J0 = cs.residual_and_jacobian(data, Q[k])
        gamma = cs.drift(data, Q[k], V[k])
        np.testing.assert_allclose(r[k], r0, rtol=0, atol=1e-13)
        np.testing.assert_allclose(rr[k], r0, rtol=0, atol=1e-13)
        np.testing.assert_allclose(JJ[k], J0, rtol=0, atol=1e-12)
        np.testing.assert_allclose(ev[k, point_like], (J0 @ V[k])[point_like], atol=1e-12)
        np.testing.assert_allclose(ea[k, point_like], (J0 @ A[k] + gamma)[point_like], atol=1e-11)
        np.testing.assert_allclose(gamma_batch[k, point_like], gamma[point_like], atol=1e-11)
