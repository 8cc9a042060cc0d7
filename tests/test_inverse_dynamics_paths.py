"""The inverse dynamics' fast path gives the general path's solution, and steps aside where it must.

``InverseDynamics.solve`` first tries a passive-row elimination (semi-normal equations) with
rank margins, then falls back on the SVD null-space reduction. Both are compared here on random
consistent states of every library robot (the SVD path forced, and fed ClosureSet's own
Jacobian), and the fallback is checked at a singular configuration and with violated bounds.
"""

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from solvers import Actuation, ForwardDynamics, InfeasibleError, InverseDynamics

ROBOTS = ["delta", "gough_stewart", "planar_3rrr", "five_bar", "tripod"]


def _state(robot, rng, act, fd):
    model = robot.model
    q = pkdyn.project(
        robot, pin.integrate(model, robot.q_home, 0.05 * rng.standard_normal(model.nv))
    )
    _, J = robot.closure_set.residual_and_jacobian(model.createData(), q)
    _, s, Vt = np.linalg.svd(J)
    Z = Vt[int(np.sum(s > 1e-9 * s[0])) :].T
    v = Z @ rng.standard_normal(Z.shape[1])
    a = fd.acceleration(q, v, act.generalized(rng.standard_normal(act.n), model.nv))
    return q, v, a


@pytest.mark.parametrize("name", ROBOTS)
def test_fast_path_equals_general_path(name):
    robot = pkdyn.load(name, geometry=False)
    model = robot.model
    red = np.array([a.reduction for a in robot.actuators])
    act = Actuation(robot.actuated_v, gains=red, names=robot.actuator_names)
    fd = ForwardDynamics(model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    fast = InverseDynamics(model, robot.constraint_models, act)
    general = InverseDynamics(model, robot.constraint_models, act)
    general._solve_unique = lambda b, J: None
    kin = model.createData()
    general._jacobian = lambda q: robot.closure_set.residual_and_jacobian(kin, q)[1]
    rng = np.random.default_rng(11)
    for _ in range(5):
        q, v, a = _state(robot, rng, act, fd)
        np.testing.assert_allclose(
            fast._jacobian(q), general._jacobian(q), rtol=0, atol=1e-13
        )  # Pinocchio's constraint Jacobian in the ClosureSet convention
        b = pin.rnea(model, model.createData(), q, v, a)
        assert fast._solve_unique(b, fast._jacobian(q)) is not None  # the fast path applies
        x, y = fast.solve(q, v, a), general.solve(q, v, a)
        np.testing.assert_allclose(x.tau, y.tau, rtol=0, atol=1e-12 * np.max(np.abs(y.tau)))
        lam = y.constraint_forces
        np.testing.assert_allclose(
            x.constraint_forces, lam, rtol=0, atol=1e-12 * np.max(np.abs(lam))
        )
        assert x.redundancy == y.redundancy == 0
        assert x.residual < 1e-9 * max(1.0, np.max(np.abs(b)))


def test_fast_path_steps_aside_at_a_singularity_and_on_violated_bounds():
    robot = pkdyn.load("five_bar", geometry=False)
    model = robot.model
    act = Actuation(robot.actuated_v, names=robot.actuator_names)
    fd = ForwardDynamics(model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    inv = InverseDynamics(
        model, robot.constraint_models, act, lower=[-1e-3, -1e-3], upper=[1e-3, 1e-3]
    )
    rng = np.random.default_rng(0)
    q, v, a = _state(robot, rng, act, fd)
    b = pin.rnea(model, model.createData(), q, v, a)
    assert inv._solve_unique(b, inv._jacobian(q)) is None  # bounds violated: general path
    with pytest.raises(InfeasibleError) as err:
        inv.solve(q, v, a)
    assert err.value.actuator is not None
    # a passive column of J set to zero (J_p loses rank): the fast path must not answer
    J = inv._jacobian(q)
    J[:, inv._vp[0]] = 0.0
    assert inv._solve_unique(b, J) is None
