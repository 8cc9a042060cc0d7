"""One platform Jacobian, one elimination of the passive joints (issue 34, item 2).

- the platform Jacobian in both axes conventions and at a reference point against finite
  differences of the platform placement;
- the passive elimination against numpy's pseudo-inverse, its rule (redundant rows dropped,
  structural rank, singular margin), and the batched solve of identification against it;
- the placement sensitivities from Pinocchio's kinematic regressors against the construction
  they replace (one action matrix per supporting placement, written out here) and against finite
  differences of the perturbed robots' forward geometry.
"""

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.kinematics import kinematic_models, passive_map, platform_jacobian
from pkdyn.exceptions import InvalidInputError
from pkdyn.precision.parameters import placement_frames, placement_parameters
from pkdyn.precision.perturbation import perturbed
from pkdyn.precision.sensitivity import _rigid_jacobians, pose_sensitivity
from solvers import numerics

ROBOTS = ("delta", "gough_stewart", "five_bar", "tripod")


@pytest.fixture(scope="module")
def robots():
    return {name: pkdyn.load(name, geometry=False) for name in ROBOTS}


def _moved(robot, shift=0.02):
    qa = robot.q_home[robot.actuated_q] + shift * robot.actuator_scale * np.linspace(
        -1, 1, len(robot.actuators)
    )
    return pkdyn.forward_geometry(robot, qa, check_limits=False).q


@pytest.mark.parametrize("name", ROBOTS)
def test_platform_jacobian_against_finite_differences(robots, name):
    robot = robots[name]
    q = _moved(robot)
    point = np.array([0.03, -0.02, 0.05])
    M0 = robot.platform_placement(q)
    h = 1e-7
    Jw = platform_jacobian(robot, q, point=point, angular="world")
    Jp = platform_jacobian(robot, q, angular="platform")
    for k in range(robot.nv):
        dv = np.zeros(robot.nv)
        dv[k] = h
        Mp = robot.platform_placement(pin.integrate(robot.model, q, dv))
        Mm = robot.platform_placement(pin.integrate(robot.model, q, -dv))
        lin = (Mp.act(point) - Mm.act(point)) / (2 * h)
        w_world = pin.log3(Mp.rotation @ M0.rotation.T) - pin.log3(Mm.rotation @ M0.rotation.T)
        w_plat = pin.log3(M0.rotation.T @ Mp.rotation) - pin.log3(M0.rotation.T @ Mm.rotation)
        np.testing.assert_allclose(Jw[:3, k], lin, atol=1e-7)
        np.testing.assert_allclose(Jw[3:, k], w_world / (2 * h), atol=1e-7)
        np.testing.assert_allclose(Jp[3:, k], w_plat / (2 * h), atol=1e-7)
    # the kinematic models' rows are these (task convention)
    km = kinematic_models(robot, q)
    np.testing.assert_array_equal(km.J6, Jp)
    with pytest.raises(InvalidInputError, match="angular"):
        platform_jacobian(robot, q, angular="tool")


def test_elimination_rule_and_pseudo_inverse():
    rng = np.random.default_rng(4)
    A = rng.normal(size=(7, 5))
    A[6] = A[0] - 2 * A[3]  # a redundant closure row
    A[:, 4] = A[:, 1]  # an internal mobility (two columns alike)
    b = rng.normal(size=(7, 3))
    el = numerics.passive_elimination(A)
    assert el.rank == 4 and not el.singular
    np.testing.assert_allclose(el.solve(b), np.linalg.pinv(A, rcond=1e-12) @ b, atol=1e-12)
    np.testing.assert_allclose(el.gap(A @ b[:5]), 0.0, atol=1e-12)
    g = el.gap(b)
    np.testing.assert_allclose(A.T @ g, 0.0, atol=1e-12)  # orthogonal to the range
    # the structural rank: a fifth direction asked for, its margin is round-off: singular
    forced = numerics.passive_elimination(A, rank=5)
    assert forced.singular and forced.margin < 1e-14
    # judged against 1 (SI closure Jacobians): an all-tiny matrix has nothing to invert
    assert numerics.passive_elimination(1e-12 * A).rank == 0
    # stacks: per matrix, and the batched solve of identification gives the same
    stack = np.stack([A, 2.0 * A, A + 1e-3 * rng.normal(size=A.shape)])
    rhs = stack @ rng.normal(size=(3, 5, 2))  # right-hand sides in the range
    ref = np.stack(
        [numerics.passive_elimination(m).solve(r) for m, r in zip(stack, rhs, strict=True)]
    )
    np.testing.assert_allclose(numerics.passive_elimination(stack).solve(rhs), ref, atol=1e-12)
    np.testing.assert_allclose(numerics.passive_solve(stack[:2], rhs[:2]), ref[:2], atol=1e-9)
    tall = rng.normal(size=(4, 9, 5))  # full column rank: least squares
    y = rng.normal(size=(4, 9))
    np.testing.assert_allclose(
        numerics.passive_solve(tall, y), (np.linalg.pinv(tall) @ y[..., None])[..., 0], atol=1e-10
    )


@pytest.mark.parametrize("name", ROBOTS)
def test_passive_map_keeps_the_loops_closed(robots, name):
    robot = robots[name]
    q = _moved(robot)
    pm = passive_map(robot, q)
    if pm.Jc.shape[0]:
        np.testing.assert_allclose(pm.Jc @ pm.V, 0.0, atol=1e-10)
    np.testing.assert_allclose(pm.J, pm.Jx @ pm.V, atol=1e-12)
    np.testing.assert_allclose(pm.V, kinematic_models(robot, q).V, atol=1e-12)


def _action_matrix_columns(robot, model, q):
    """``C`` and ``X`` the way they were built before the regressors: one ``Ad(oF)`` per
    placement that supports an entity, for the joint placements, its frame's for its own."""
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    pin.updateFramePlacements(robot.model, data)
    F = placement_frames(robot, data, model.placements)
    T = [M.toActionMatrix() for M in F]
    xi = model.E.reshape(len(model.placements), 6, -1)

    def twist(joint, own):
        S = np.zeros((6, model.size))
        support = set(int(j) for j in robot.model.supports[joint]) if joint > 0 else set()
        for k, pl in enumerate(model.placements):
            if (pl.kind == "joint" and pl.joint in support) or (pl.kind, pl.name) == own:
                S += T[k] @ xi[k]
        return S

    def skew(p):
        return pin.skew(np.asarray(p))

    full = robot.constraints.unreduced  # (the sensitivities' rows: every constraint model's)
    C = np.zeros((full.n, model.size))
    offsets = full.closure_rows.base_offsets
    owners = robot.constraint_owner
    for i, cm in enumerate(robot.constraint_models):
        S1 = twist(int(cm.joint1_id), ("closure", f"{owners[i]}/1"))
        S2 = twist(int(cm.joint2_id), ("closure", f"{owners[i]}/2"))
        oM1 = data.oMi[cm.joint1_id] * cm.joint1_placement
        oM2 = data.oMi[cm.joint2_id] * cm.joint2_placement
        o = int(offsets[i])
        if cm.type == pin.ContactType.CONTACT_3D:
            d1 = S1[:3] - skew(oM1.translation) @ S1[3:]
            d2 = S2[:3] - skew(oM2.translation) @ S2[3:]
            C[o : o + 3] = d1 - d2
        else:
            op = pin.Jlog6(oM1.actInv(oM2)) @ oM2.inverse().toActionMatrix()
            C[o : o + 6] = op @ (S2 - S1)
    X = np.zeros((6, model.size))
    if robot.platform_frame is not None:
        f = robot.model.frames[robot.platform_frame]
        Sp = twist(int(f.parentJoint), ("platform", "platform"))
        oMf = data.oMf[robot.platform_frame]
        X[:3] = Sp[:3] - skew(oMf.translation) @ Sp[3:]
        X[3:] = oMf.rotation.T @ Sp[3:]
    return C, X


@pytest.mark.parametrize("name", ROBOTS)
def test_regressor_columns_are_the_action_matrix_columns(robots, name):
    robot = robots[name]
    model = placement_parameters(robot, gains=True)
    q = _moved(robot)
    pose_sensitivity(robot, q)  # (kinematics at q in robot.data)
    C, X = _rigid_jacobians(robot, model, robot.data, None)
    C0, X0 = _action_matrix_columns(robot, model, q)
    scale = max(1.0, np.abs(C0).max(), np.abs(X0).max())
    assert np.abs(C - C0).max() <= 1e-14 * scale
    assert np.abs(X - X0).max() <= 1e-14 * scale


def test_regressor_sensitivity_of_a_perturbed_robot_by_finite_differences(robots):
    """At a perturbed robot (``at``), the columns with ``Jexp6`` against rebuilt robots."""
    robot = robots["delta"]
    model = placement_parameters(robot)
    rng = np.random.default_rng(2)
    p0 = rng.uniform(-1, 1, model.size) * model.tolerances(1e-3, 5e-3)
    P0 = perturbed(robot, model, p0)
    qa = robot.q_home[robot.actuated_q] + 0.05
    g0 = pkdyn.forward_geometry(P0.robot, qa, q_init=P0.robot.q_home)
    s = pose_sensitivity(P0.robot, g0.q, model, at=p0)
    h = 1e-6
    for k in rng.choice(model.size, 10, replace=False):
        res = []
        for sign in (1.0, -1.0):
            dp = np.zeros(model.size)
            dp[k] = sign * h
            g = pkdyn.forward_geometry(perturbed(robot, model, p0 + dp).robot, qa, q_init=g0.q)
            M0, M = g0.placement, g.placement
            res.append(
                np.concatenate(
                    [M.translation - M0.translation, pin.log3(M0.rotation.T @ M.rotation)]
                )
            )
        fd = (res[0] - res[1]) / (2 * h)
        np.testing.assert_allclose(s.K[:, k], fd, atol=1e-6 * max(1.0, np.abs(fd).max()))


def test_one_joint_robot(tmp_path):
    """nv = 1: Pinocchio hands a (6, 1) Jacobian back as a vector; the stiffness of a crank."""
    from pkdyn.precision import stiffness

    xml = """<robot name="crank" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="0.25 0 0"/><mass value="1"/>
    <inertia ixx="0.001" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="a1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <transmission name="t"><type>transmission_interface/SimpleTransmission</type>
    <joint name="a1"/><actuator name="m"><mechanicalReduction>1</mechanicalReduction></actuator>
  </transmission>
  <pkdyn:platform link="arm" xyz="0.5 0 0" task="x"/>
</robot>"""
    path = tmp_path / "crank.urdf"
    path.write_text(xml)
    robot = pkdyn.load(str(path))
    q = pkdyn.forward_geometry(robot, [0.3]).q
    assert platform_jacobian(robot, q, angular="world").shape == (6, 1)
    k = 100.0
    S = stiffness(robot, q, k)  # x = L cos(q): K = k / (L sin q)^2
    assert S.K[0, 0] == pytest.approx(k / (0.5 * np.sin(0.3)) ** 2, rel=1e-12)
