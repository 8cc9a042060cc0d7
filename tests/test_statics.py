"""Statics: actuator efforts and closure reactions against the principle of virtual work."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import random_configs

import pkdyn
from pkdyn.analysis import kinematics, statics

ROBOTS = ["delta", "gough_stewart", "planar_3rrr", "five_bar"]
SPREAD = {"delta": (0.06, 0.0), "gough_stewart": (0.03, 0.08), "planar_3rrr": (0.05, 0.3)}


@pytest.fixture(scope="module")
def robots(delta, gough_stewart):
    out = {"delta": delta, "gough_stewart": gough_stewart}
    for name in ("planar_3rrr", "five_bar"):
        out[name] = pkdyn.load(name, geometry=False)
    return out


def _configs(robot, n, seed):
    return random_configs(robot, n, seed, SPREAD.get(robot.name, (0.05, 0.0)))


def small_motion(robot, q, dqa):
    """Configurations at q_a -/+ dq_a (direct geometric model, warm started)."""
    qa = q[robot.actuated_q]
    return [
        pkdyn.forward_geometry(robot, qa + s * dqa, q_init=q, check_limits=False).q
        for s in (-1.0, 1.0)
    ]


def platform_displacement(robot, q, q_minus, q_plus):
    """Task components of the platform displacement between q- and q+ (central)."""
    M0 = robot.platform_placement(q)
    e = []
    for qq in (q_minus, q_plus):
        M = robot.platform_placement(qq)
        e.append(
            np.concatenate([M.translation - M0.translation, pin.log3(M0.rotation.T @ M.rotation)])
        )
    return ((e[1] - e[0]) / 2.0)[robot.task_rows]


@pytest.mark.parametrize("name", ROBOTS)
def test_efforts_satisfy_virtual_work(robots, name):
    """tau . dq_a + F . dx = 0 on small motions compatible with the closures."""
    robot = robots[name]
    rng = np.random.default_rng(21)
    for q in _configs(robot, 3, 22):
        m = robot.task_rows.size
        F = rng.normal(scale=50.0, size=m)
        tau = statics.actuator_efforts(robot, q, F)
        for _ in range(2):
            dqa = 1e-5 * rng.normal(size=len(robot.actuators))
            dx = platform_displacement(robot, q, *small_motion(robot, q, dqa))
            work = tau @ dqa + F @ dx
            assert abs(work) < 1e-8 * np.linalg.norm(tau) * np.linalg.norm(dqa) + 1e-14


@pytest.mark.parametrize("name", ROBOTS)
def test_full_equilibrium_matches_jacobian_transpose(robots, name):
    robot = robots[name]
    (q,) = _configs(robot, 1, 23)
    F = np.linspace(10.0, -20.0, robot.task_rows.size)
    res = statics.static_equilibrium(robot, q, F)
    np.testing.assert_allclose(res.tau, statics.actuator_efforts(robot, q, F), atol=1e-8)
    assert res.residual < 1e-8
    assert list(res.reactions) == list(dict.fromkeys(robot.constraint_owner))  # one per closure


@pytest.mark.parametrize("name", ["delta", "gough_stewart"])
def test_gravity_efforts_satisfy_virtual_work(robots, name):
    """With gravity: tau . dq_a = dU (actuators supply the potential energy change)."""
    robot = robots[name]
    rng = np.random.default_rng(24)
    model, data = robot.model, robot.data
    for q in _configs(robot, 2, 25):
        tau = statics.static_equilibrium(robot, q, gravity=True).tau
        dqa = 1e-5 * rng.normal(size=len(robot.actuators))
        qm, qp = small_motion(robot, q, dqa)
        dU = (
            pin.computePotentialEnergy(model, data, qp)
            - pin.computePotentialEnergy(model, data, qm)
        ) / 2
        assert abs(tau @ dqa - dU) < 1e-8 * np.linalg.norm(tau) * np.linalg.norm(dqa)


def test_gough_stewart_legs_are_two_force_members(robots):
    """Without gravity each leg only carries its actuator force along its axis."""
    robot = robots["gough_stewart"]
    (q,) = _configs(robot, 1, 26)
    F = np.array([30.0, -20.0, 400.0, 5.0, -8.0, 3.0])
    res = statics.static_equilibrium(robot, q, F)
    pin.forwardKinematics(robot.model, robot.data, q)
    for i, cm in enumerate(robot.constraint_models):
        B = robot.data.oMi[cm.joint2_id].act(cm.joint2_placement.translation)
        A = np.asarray(robot.params.a[i])
        u = (B - A) / np.linalg.norm(B - A)
        # force of the platform on the rod: minus the actuator force along the leg
        np.testing.assert_allclose(res.reactions[cm.name].force, -res.tau[i] * u, atol=1e-8)
        np.testing.assert_allclose(res.reactions[cm.name].moment, 0.0, atol=1e-12)


def test_delta_arms_do_not_feel_moments_on_the_nacelle(robots):
    """The parallelograms take any moment on the nacelle: the arm torques are unchanged."""
    robot = robots["delta"]
    (q,) = _configs(robot, 1, 27)
    force = np.array([3.0, -4.0, 20.0])
    t_force = statics.static_equilibrium(robot, q, force).tau
    res = statics.static_equilibrium(robot, q, np.concatenate([force, [0.5, -0.7, 0.3]]))
    np.testing.assert_allclose(res.tau, t_force, atol=1e-9)
    assert res.residual < 1e-8


@pytest.mark.parametrize("name", ROBOTS)
def test_platform_wrench_inverts_efforts(robots, name):
    robot = robots[name]
    (q,) = _configs(robot, 1, 28)
    F = np.linspace(-5.0, 7.0, robot.task_rows.size)
    tau = statics.actuator_efforts(robot, q, F)
    np.testing.assert_allclose(statics.platform_wrench(robot, q, tau), -F, atol=1e-8)


def test_statics_at_parallel_singularity_raises():
    robot = pkdyn.load("planar_3rrr", geometry=False)
    phi = float(np.arccos(0.8))  # distal lines concurrent at the platform centre
    q = robot.q_home
    for t in np.linspace(0.0, 1.0, 7)[1:]:
        q = pkdyn.inverse_geometry(robot, [0, 0, 0, 0, 0, t * phi], q_init=q).q
    with pytest.raises(pkdyn.SingularConfigurationError, match="no static equilibrium"):
        statics.static_equilibrium(robot, q, [0.0, 0.0, 1.0])  # a torque on the platform
    with pytest.raises(pkdyn.SingularConfigurationError):
        statics.actuator_efforts(robot, q, [1.0, 0.0, 0.0])
    # a force through the centre is held by the concurrent links alone; tau is not unique
    with pytest.raises(pkdyn.SingularConfigurationError, match="not unique"):
        statics.static_equilibrium(robot, q, [1.0, 0.0, 0.0])


def test_statics_json_and_input_checks(robots):
    robot = robots["delta"]
    F = np.array([0.0, 0.0, -9.81])
    out = statics.statics_json(robot, robot.q_home, F, gravity=True)
    # virtual work with gravity: tau . dqa = dV - F . dx on a small motion along each actuator
    data = robot.model.createData()
    q = robot.q_home
    for j in range(3):
        dqa = np.zeros(3)
        dqa[j] = 1e-5
        q_minus, q_plus = small_motion(robot, q, dqa)
        dV = pin.computePotentialEnergy(robot.model, data, q_plus) - pin.computePotentialEnergy(
            robot.model, data, q_minus
        )
        dx = platform_displacement(robot, q, q_minus, q_plus)
        assert out["tau"][j] * 2e-5 == pytest.approx(dV - 2.0 * F @ dx, rel=1e-6)
    assert out["actuators"] == robot.actuator_names
    with pytest.raises(pkdyn.InvalidInputError):
        statics.static_equilibrium(robot, robot.q_home, [1.0, 2.0])
    with pytest.raises(pkdyn.InvalidInputError):
        statics.actuator_efforts(robot, robot.q_home, [np.nan, 0.0, 0.0])


def test_efforts_from_seed_screws_gough_stewart(robots):
    """Merlet's statics: tau_i is the leg force, F balanced by sum of tau_i along the legs."""
    robot = robots["gough_stewart"]
    (q,) = _configs(robot, 1, 29)
    F = np.array([10.0, 20.0, -300.0, 1.0, 2.0, -3.0])
    tau = statics.actuator_efforts(robot, q, F)
    km = kinematics.kinematic_models(robot, q)
    # J_inv^T tau is the wrench applied by the legs on the platform (A^T tau with B = I)
    from pkdyn.analysis.screws import reciprocal_screws

    A, _ = reciprocal_screws(robot, q)
    np.testing.assert_allclose(A.T @ tau, -F, atol=1e-8)
    assert km.cond_A < 1e3


@pytest.mark.parametrize("name", ["five_bar", "planar_3rrr", "tripod"])
def test_closure_reactions_balance_the_cut_tree(name):
    """One force and one moment per closure (hinges: not two half-forces), checked on the tree
    cut open at the closures: the actuator efforts, the load, gravity and each reaction applied
    to the closure's first body (and its opposite to the second) balance every joint."""
    robot = pkdyn.load(name, geometry=False)
    model = robot.model
    (q,) = _configs(robot, 1, 31)
    F = np.linspace(15.0, -10.0, robot.task_rows.size)
    res = statics.static_equilibrium(robot, q, F, gravity=True)
    kinds = {c.name: c.kind for c in robot.description.closures}
    data = model.createData()
    pin.computeJointJacobians(model, data, q)
    gen = np.zeros(robot.nv)
    LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    done = set()
    for k, (_, j1, M1, j2, _) in enumerate(robot.closure_set.items):
        owner = robot.constraint_owner[k]
        if owner in done:
            continue
        done.add(owner)
        r = res.reactions[owner]
        np.testing.assert_allclose(r.point, (data.oMi[j1] * M1).translation, atol=1e-12)
        wrench = np.concatenate([r.force, r.moment])
        for j, sign in ((j1, 1.0), (j2, -1.0)):
            if j == 0:
                continue
            at = pin.SE3(np.eye(3), data.oMi[j].actInv(r.point))  # the point on that body
            J = pin.getFrameJacobian(model, data, j, at, LWA)
            gen += sign * J.T @ wrench
        if kinds[owner] == "hinge":  # no moment about the hinge's own axis
            c = next(c for c in robot.description.closures if c.name == owner)
            axis = (data.oMi[j1] * M1).rotation @ np.asarray(c.axis)
            assert abs(r.moment @ axis) < 1e-9 * max(1.0, np.linalg.norm(r.moment))
    km = kinematics.kinematic_models(robot, q)
    F6 = np.zeros(6)
    F6[robot.task_rows] = F
    S_T = np.zeros((robot.nv, len(robot.actuators)))
    S_T[robot.actuated_v, np.arange(len(robot.actuators))] = 1.0
    g = pin.computeGeneralizedGravity(model, data, q)
    total = S_T @ res.tau + gen + km.J6.T @ F6 - g
    assert np.max(np.abs(total)) < 1e-8 * max(1.0, np.max(np.abs(g)), np.max(np.abs(F)))
