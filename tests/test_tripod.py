"""The walking tripod (seed 003): model, geometric models and the virtual U-P-S joints (1)-(8).

Expected values come from geometry written out here (attachment circle, footholds, spindle
offset, triangle formulas), not from the module under test.
"""

import math

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.closed_form import tripod as tripod_cf
from pkdyn.library import tripod

P = tripod.Params()
E = 2.0 * P.r_p * math.sin(P.theta)  # edge length |P_L P_R|
TOOL_HOME = np.array([0.0, 0.0, P.nacelle_height - P.tool_offset, 0.0, 0.0, 0.0])
# leg tilt from the vertical at home: horizontal and vertical offsets of P_C from A
DX = P.foothold_radius - P.r_p * math.cos(P.theta)
DZ = P.nacelle_height - P.foot_height
Q6_HOME = math.atan2(DX, DZ)


@pytest.fixture(scope="module")
def robot() -> pkdyn.Robot:
    return pkdyn.load("tripod")


# --- independent geometry ---------------------------------------------------------------------


def attachment(i: int, side: str) -> np.ndarray:
    """P_L (side 'L', at phi_i + theta) or P_R of branch i (0-based) in the nacelle frame."""
    a = 2.0 * math.pi * i / 3.0 + (P.theta if side == "L" else -P.theta)
    return P.r_p * np.array([math.cos(a), math.sin(a), 0.0])


def foot_point(i: int) -> np.ndarray:
    """Universal-joint centre A_i: foot_height above the foothold on the circle."""
    a = 2.0 * math.pi * i / 3.0
    return np.array(
        [P.foothold_radius * math.cos(a), P.foothold_radius * math.sin(a), P.foot_height]
    )


def nacelle_of_tool(M_tool: pin.SE3) -> pin.SE3:
    """The spindle tip is tool_offset below P_O along the nacelle normal."""
    return M_tool * pin.SE3(np.eye(3), np.array([0.0, 0.0, P.tool_offset]))


def pose_se3(pose: np.ndarray) -> pin.SE3:
    return pin.SE3(pin.rpy.rpyToMatrix(pose[3:]), pose[:3])


def angle_about(v1: np.ndarray, v2: np.ndarray, n: np.ndarray) -> float:
    return math.atan2(float(n @ np.cross(v1, v2)), float(v1 @ v2))


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def random_tool_poses(rng: np.random.Generator, n: int, dp: float, da: float) -> np.ndarray:
    return TOOL_HOME + np.hstack([rng.uniform(-dp, dp, (n, 3)), rng.uniform(-da, da, (n, 3))])


def joint_q(robot: pkdyn.Robot, q: np.ndarray, name: str, k: int = 0) -> float:
    """Coordinate k of joint name."""
    return float(q[robot.model.joints[robot.model.getJointId(name)].idx_q + k])


def joint_placement(robot: pkdyn.Robot, name: str) -> pin.SE3:
    return robot.data.oMi[robot.model.getJointId(name)]


# --- model ------------------------------------------------------------------------------------


def test_loads_with_six_dof_and_actuator_order(robot):
    assert robot.nv == 6 + 3 * 8
    assert robot.mobility() == 6
    assert robot.actuated_joint_names == [f"branch{i}_q{s}" for i in (1, 2, 3) for s in "LR"]
    assert robot.actuator_names == [f"{s}{i}" for i in (1, 2, 3) for s in "LR"]
    assert [a.name for a in robot.actuators] == ["L1", "R1", "L2", "R2", "L3", "R3"]
    for i in (1, 2, 3):
        jm = robot.model.joints[robot.model.getJointId(f"branch{i}_q2q1")]
        assert jm.shortname() == "JointModelUniversal"
    kinds = sorted(c.kind for c in robot.closures)
    assert kinds == ["hinge"] * 3 + ["weld"] * 3
    for a in robot.actuators:
        assert a.reduction == pytest.approx(2.0 * math.pi / P.screw_lead)
    lo, hi = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    assert np.allclose(lo[robot.actuated_q], P.stroke_min)
    assert np.allclose(hi[robot.actuated_q], P.stroke_max)


def test_home_is_assembled_neutral_and_symmetric(robot):
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-10
    length = math.sqrt(DX**2 + (P.r_p * math.sin(P.theta)) ** 2 + DZ**2)
    assert np.allclose(robot.q_home[robot.actuated_q], length, atol=1e-12)
    assert np.allclose(tripod.home(P), length, atol=1e-12)
    # neutral = home: free-flyer at its origin, passive revolute joints at 0
    passive = np.setdiff1d(np.arange(robot.nq), robot.actuated_q)
    assert np.allclose(robot.q_home[passive], pin.neutral(robot.model)[passive], atol=1e-9)
    M = robot.platform_placement(robot.q_home)
    assert np.allclose(M.translation, TOOL_HOME[:3], atol=1e-10)
    assert np.allclose(M.rotation, np.eye(3), atol=1e-10)


def test_tree_geometry_at_home(robot):
    pin.forwardKinematics(robot.model, robot.data, robot.q_home)
    for i in range(3):
        b = f"branch{i + 1}"
        lift = np.array([0.0, 0.0, P.nacelle_height])
        assert np.allclose(joint_placement(robot, f"{b}_b").translation, attachment(i, "L") + lift)
        assert np.allclose(joint_placement(robot, f"{b}_c").translation, attachment(i, "R") + lift)
        assert np.allclose(joint_placement(robot, f"{b}_a").translation, foot_point(i))
        # q6 axis along u = P_L P_R
        u = unit(attachment(i, "R") - attachment(i, "L"))
        assert np.allclose(joint_placement(robot, f"{b}_q6").rotation[:, 0], u)


def test_forward_geometry_near_home(robot):
    rng = np.random.default_rng(1)
    home = robot.q_home[robot.actuated_q]
    for _ in range(30):
        qa = home + rng.uniform(-0.03, 0.03, 6)
        res = pkdyn.forward_geometry(robot, qa)
        assert res.residual < 1e-10
        assert np.allclose(res.qa, qa, atol=1e-14)
        # parallel axes a, b, c stay parallel; both rods meet at A
        pin.forwardKinematics(robot.model, robot.data, res.q)
        for i in range(1, 4):
            b = f"branch{i}"
            n = joint_placement(robot, f"{b}_q6").rotation[:, 2]
            for j in ("b", "c"):
                assert np.allclose(joint_placement(robot, f"{b}_{j}").rotation[:, 2], n, atol=1e-9)
            assert np.allclose(joint_placement(robot, f"{b}_a").rotation[:, 0], n, atol=1e-9)
            rod_l = joint_placement(robot, f"{b}_qL").translation
            rod_r = joint_placement(robot, f"{b}_qR").translation
            assert np.linalg.norm(rod_l - rod_r) < 1e-10


def test_fk_of_ik_round_trip(robot):
    rng = np.random.default_rng(2)
    q = robot.q_home
    for pose in random_tool_poses(rng, 1000, 0.03, 0.05):
        target = pose_se3(pose)
        ig = pkdyn.inverse_geometry(robot, pose, q_init=q)
        fg = pkdyn.forward_geometry(robot, ig.qa)  # from the home guess, not from ig.q
        q = ig.q
        assert fg.residual < 1e-10
        assert np.linalg.norm(fg.placement.translation - target.translation) < 1e-9
        assert np.linalg.norm(pin.log3(fg.placement.rotation.T @ target.rotation)) < 1e-9


def test_actuator_lengths_are_geometric_distances(robot):
    rng = np.random.default_rng(3)
    for pose in random_tool_poses(rng, 40, 0.04, 0.08):
        ig = pkdyn.inverse_geometry(robot, pose)
        M = nacelle_of_tool(pose_se3(pose))
        expected = [
            np.linalg.norm(foot_point(i) - M.act(attachment(i, s))) for i in range(3) for s in "LR"
        ]
        assert np.allclose(ig.qa, expected, atol=1e-9, rtol=0.0)


# --- virtual joints, equations (1)-(8) ---------------------------------------------------------


def test_virtual_joints_at_home():
    s = tripod_cf.virtual_joints(P, pin.SE3(np.eye(3), np.array([0.0, 0.0, P.nacelle_height])))
    assert s.shape == (3, 6)
    for row in s:
        q1, q2, q3, q4, q5, q6 = row
        assert abs(q1) < 1e-12 and abs(q3) < 1e-12 and abs(q5) < 1e-12
        assert q4 == pytest.approx(math.hypot(DX, DZ), abs=1e-12)
        assert q6 == pytest.approx(Q6_HOME, abs=1e-12)
        # level nacelle, level feet: the foot tilts back by the angle the triangle leans out
        assert q2 == pytest.approx(-Q6_HOME, abs=1e-12)


def _virtual_chain(foot: pin.SE3, s: np.ndarray, i: int) -> pin.SE3:
    """Nacelle placement rebuilt from foot frame R_A and the virtual coordinates of branch i."""
    q1, q2, q3, q4, q5, q6 = s
    R = foot.rotation @ pin.exp3(np.array([0.0, 0.0, q1])) @ pin.exp3(np.array([0.0, q2, 0.0]))
    R = R @ pin.exp3(np.array([-q3, 0.0, 0.0]))  # z axis now along l_c = A P_C
    x3, y3, z3 = R[:, 0], R[:, 1], R[:, 2]
    P_C = foot.translation + q4 * z3
    u = math.sin(q5) * z3 - math.cos(q5) * y3
    y_t = unit(-z3 - (-z3 @ u) * u)  # from the edge towards A, in the triangle plane
    w_p = -pin.exp3(-q6 * u) @ y_t
    v_out = np.cross(w_p, u)  # P_O P_C direction
    r = np.array([math.cos(2 * math.pi * i / 3), math.sin(2 * math.pi * i / 3), 0.0])
    z = np.array([0.0, 0.0, 1.0])
    R_P = (
        np.column_stack([v_out, np.cross(w_p, v_out), w_p])
        @ np.column_stack([r, np.cross(z, r), z]).T
    )
    assert np.allclose(x3, np.cross(u, y_t), atol=1e-9)  # v3 is normal to the triangle
    return pin.SE3(R_P, P_C - P.r_p * math.cos(P.theta) * v_out)


def test_virtual_chain_reproduces_nacelle_pose():
    rng = np.random.default_rng(4)
    default = tripod_cf.foothold_frames(P)
    for k in range(100):
        M = pose_se3(
            np.r_[0.0, 0.0, P.nacelle_height, 0, 0, 0]
            + np.r_[rng.uniform(-0.1, 0.1, 3), rng.uniform(-0.25, 0.25, 3)]
        )
        if k % 2:  # moved and tilted feet (mode BE: the footholds change)
            feet = [
                pin.SE3(
                    f.rotation @ pin.exp3(rng.uniform(-0.3, 0.3, 3)),
                    f.translation + rng.uniform(-0.05, 0.05, 3),
                )
                for f in default
            ]
        else:
            feet = default
        s = tripod_cf.virtual_joints(P, M, feet)
        for i in range(3):
            Mi = _virtual_chain(feet[i], s[i], i)
            assert np.linalg.norm(Mi.translation - M.translation) < 1e-9
            assert np.linalg.norm(pin.log3(Mi.rotation.T @ M.rotation)) < 1e-9
            # (5) and the nacelle-side points
            P_C = M.act(0.5 * (attachment(i, "L") + attachment(i, "R")))
            assert s[i, 3] == pytest.approx(np.linalg.norm(P_C - feet[i].translation), abs=1e-12)


def test_virtual_joints_accept_a_pose_vector():
    pose = np.array([0.02, -0.01, 0.63, 0.05, -0.03, 0.1])
    assert np.allclose(
        tripod_cf.virtual_joints(P, pose), tripod_cf.virtual_joints(P, pose_se3(pose)), atol=1e-15
    )
    with pytest.raises(pkdyn.InvalidInputError):
        tripod_cf.virtual_joints(P, pose, tripod_cf.foothold_frames(P)[:2])


def test_virtual_joints_match_the_assembled_model(robot):
    """q1..q6 from equations (1)-(8) against joint values and frames of the assembled model.

    The assembly is solved to 1e-12; 1e-9 leaves room for the amplification through the thin
    triangle.
    """
    tol = 1e-9
    rng = np.random.default_rng(5)
    model, data = robot.model, robot.data
    for pose in random_tool_poses(rng, 40, 0.04, 0.08):
        q = pkdyn.inverse_geometry(robot, pose).q
        pin.forwardKinematics(model, data, q)
        M = joint_placement(robot, "nacelle")
        s = tripod_cf.virtual_joints(P, pin.SE3(M))
        w_p = M.rotation[:, 2]
        for i in range(3):
            b = f"branch{i + 1}"
            q1, q2, q3, q4, q5, q6 = s[i]
            q_l, q_r = joint_q(robot, q, f"{b}_qL"), joint_q(robot, q, f"{b}_qR")
            A = joint_placement(robot, f"{b}_a").translation
            P_L = joint_placement(robot, f"{b}_b").translation
            P_R = joint_placement(robot, f"{b}_c").translation
            assert np.allclose(A, foot_point(i), atol=tol)
            # q4: |A P_C| measured on the model, and the triangle's median formula
            assert q4 == pytest.approx(np.linalg.norm(A - 0.5 * (P_L + P_R)), abs=tol)
            assert q4**2 == pytest.approx(0.5 * (q_l**2 + q_r**2) - 0.25 * E**2, abs=tol)
            # q5: from the two actuator lengths
            assert math.sin(q5) == pytest.approx((q_r**2 - q_l**2) / (2 * E * q4), abs=tol)
            # q6: hinge joint about u, and the dihedral between nacelle and triangle planes
            edge = joint_placement(robot, f"{b}_q6").rotation
            assert q6 == pytest.approx(Q6_HOME + joint_q(robot, q, f"{b}_q6"), abs=tol)
            assert q6 == pytest.approx(angle_about(-w_p, edge[:, 1], edge[:, 0]), abs=tol)
            # q1, q2: the universal joint at A (home values 0 and -q6_home)
            assert q1 == pytest.approx(joint_q(robot, q, f"{b}_q2q1", 1), abs=tol)
            assert q2 == pytest.approx(-Q6_HOME + joint_q(robot, q, f"{b}_q2q1", 0), abs=tol)
            # q3: knuckle joint about a, minus the triangle's angle at A between A P_C and A P_L
            gamma = math.acos((q_l**2 + q4**2 - 0.25 * E**2) / (2 * q_l * q4))
            gamma_home = math.atan2(0.5 * E, math.hypot(DX, DZ))
            assert q3 == pytest.approx(joint_q(robot, q, f"{b}_a") + gamma_home - gamma, abs=tol)


# --- parameters -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("r_p", -0.3),
        ("theta", 1.2),
        ("stroke_min", 0.95),
        ("nacelle_height", 1.5),
        ("nacelle_height", 0.05),
        ("rod_mass", 0.0),
        ("tool_offset", float("nan")),
    ],
)
def test_bad_parameter_names_it(name, value):
    with pytest.raises(pkdyn.ParameterError) as err:
        pkdyn.load("tripod", **{name: value})
    assert err.value.name == name
    assert f"'{name}'" in str(err.value)


def test_other_parameters_build_and_assemble():
    r = pkdyn.load("tripod", geometry=False, r_p=0.25, theta=0.25, nacelle_height=0.65)
    assert r.mobility() == 6
    assert pkdyn.closure_residual(r, r.q_home) < 1e-10
    assert r.platform_placement(r.q_home).translation[2] == pytest.approx(0.65 - P.tool_offset)
