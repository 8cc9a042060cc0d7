"""Modes PP and BE of the tripod, B_iIKMX and XFKMB_i against the general constraint machinery.

The general machinery is :func:`pkdyn.inverse_geometry` on the mode robots (closures, clamps and
locks as constraints, solved by Levenberg-Marquardt on the whole configuration); the paper's
models are the vector projections (1)-(8) and an optimisation over the nacelle pose. Expected
actuator lengths are distances computed here from the attachment points and footholds.
"""

import math
import warnings

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.singularity import classify
from pkdyn.closed_form import tripod as tripod_cf
from pkdyn.library import tripod
from pkdyn.tripod import (
    BRANCHES,
    Stance,
    be_mode,
    foot_frame,
    foot_placement,
    locked_names,
    mode_robot,
    pp_mode,
    support_branches,
)
from pkdyn.tripod.xfkmb import actuator_lengths, bikmx, bikmx_virtual, xfkmb

P = tripod.Params()
TOOL = pin.SE3(np.eye(3), np.array([0.0, 0.0, -P.tool_offset]))


@pytest.fixture(scope="module")
def robot() -> pkdyn.Robot:
    return pkdyn.load("tripod", geometry=False)


def random_stance(rng: np.random.Generator, tilt: float = 0.0) -> Stance:
    """Footholds moved on the support (and tilted by up to ``tilt``)."""
    feet = []
    for f in tripod_cf.foothold_frames(P):
        R = f.rotation @ pin.exp3(np.array([0.0, 0.0, rng.uniform(-0.2, 0.2)]))
        if tilt:
            R = pin.exp3(np.r_[rng.uniform(-tilt, tilt, 2), 0.0]) @ R
        feet.append(pin.SE3(R, f.translation + np.r_[rng.uniform(-0.05, 0.05, 2), 0.0]))
    return Stance(tuple(feet))


def nacelle_pose(rng: np.random.Generator, stance: Stance) -> pin.SE3:
    c = stance.centroid()
    R = pin.exp3(rng.uniform(-0.12, 0.12, 3))
    return pin.SE3(R, np.array([c[0], c[1], P.nacelle_height]) + rng.uniform(-0.03, 0.03, 3))


def attachments(M: pin.SE3, i: int) -> tuple[np.ndarray, np.ndarray]:
    a = 2.0 * math.pi * i / 3.0
    return tuple(
        M.act(P.r_p * np.array([math.cos(a + s * P.theta), math.sin(a + s * P.theta), 0.0]))
        for s in (1.0, -1.0)
    )


def coordinate(robot: pkdyn.Robot, q: np.ndarray, joint: str, k: int = 0) -> float:
    return float(q[robot.model.joints[robot.model.getJointId(joint)].idx_q + k])


def lockable_from_q(robot: pkdyn.Robot, q: np.ndarray, b: int) -> np.ndarray:
    """Model coordinates of q1, q2, q3, q6 of branch b, read from the configuration."""
    n = f"branch{b}"
    return np.array(
        [
            coordinate(robot, q, f"{n}_q2q1", 1),
            coordinate(robot, q, f"{n}_q2q1", 0),
            coordinate(robot, q, f"{n}_a"),
            coordinate(robot, q, f"{n}_q6"),
        ]
    )


def nacelle(robot: pkdyn.Robot, q: np.ndarray) -> pin.SE3:
    pin.forwardKinematics(robot.model, robot.data, q)
    return pin.SE3(robot.data.oMi[robot.model.getJointId("nacelle")])


def pp_configuration(robot, stance, M, q0=None):
    r = mode_robot(robot, stance, pp_mode())
    return pkdyn.inverse_geometry(r, M * TOOL, q_init=q0, check_limits=False).q


def tilted(stance: Stance, b: int, tilt: float = 0.1) -> pin.SE3:
    phi = tripod_cf.PHI[b - 1]
    c = stance.centroid()
    return pin.SE3(
        pin.exp3(tilt * np.array([-math.sin(phi), math.cos(phi), 0.0])),
        np.array([c[0], c[1], P.nacelle_height]),
    )


# --- modes ------------------------------------------------------------------------------------


def test_paper_lock_sets():
    assert support_branches(1) == (2, 3)
    assert support_branches(2) == (1, 3)
    assert support_branches(3) == (1, 2)
    assert locked_names(2) == [
        "branch2_q1",
        "branch2_q2",
        "branch2_q3",
        "branch2_q6",
        "branch1_q1",
        "branch3_q1",
    ]
    with pytest.raises(pkdyn.InvalidInputError):
        support_branches(4)


def test_both_modes_have_six_degrees_of_freedom(robot):
    st = Stance.default(P)
    q = pp_configuration(robot, st, tilted(st, 1))
    pp = mode_robot(robot, st, pp_mode(), q)
    assert pp.mobility(q) == 6
    for b in BRANCHES:
        be = mode_robot(robot, st, be_mode(robot, q, b), q)
        assert pkdyn.closure_residual(be, q) < 1e-12
        assert be.mobility(q) == 6  # 30 - (6 hinges + 12 clamps + 2 + 1 + 1 + 2 locks)
        assert f"branch{b}_foothold" not in be.constraint_owner
        assert be.platform_frame == robot.model.getFrameId(f"branch{b}_foot")
    # without the locks the released branch would add 6 DOF
    m = be_mode(robot, q, 1)
    free = mode_robot(robot, st, type(m)("BE", 1), q)
    assert free.mobility(q) == 12


def test_be_foot_moves_with_locks_and_supports_held(robot):
    """BE IGM by the general machinery: locked coordinates and support feet do not move."""
    rng = np.random.default_rng(0)
    st = Stance.default(P)
    q = pp_configuration(robot, st, tilted(st, 2))
    for b in BRANCHES:
        mode = be_mode(robot, q, b)
        be = mode_robot(robot, st, mode, q)
        target0 = st.footholds[b - 1]
        for _ in range(5):
            target = pin.SE3(target0.rotation, target0.translation + rng.uniform(-0.04, 0.04, 3))
            qb = pkdyn.inverse_geometry(be, foot_frame(target), q_init=q, check_limits=False).q
            foot = foot_placement(robot, qb, b)
            assert np.linalg.norm(foot.translation - target.translation) < 1e-10
            assert np.linalg.norm(pin.log3(foot.rotation.T @ target.rotation)) < 1e-10
            assert np.max(np.abs(mode.lock_vector(robot, qb) - mode.lock_targets())) < 1e-10
            for s in support_branches(b):
                held = foot_placement(robot, qb, s)
                assert np.linalg.norm(held.translation - st.footholds[s - 1].translation) < 1e-9


def test_stance_and_mode_robot_errors(robot):
    with pytest.raises(pkdyn.InvalidInputError):
        Stance((pin.SE3.Identity(),) * 2)  # type: ignore[arg-type]
    other = pkdyn.load("five_bar", geometry=False)
    with pytest.raises(pkdyn.PkdynError, match="library tripod"):
        mode_robot(other, Stance.default(P), pp_mode())
    with pytest.raises(pkdyn.InvalidInputError):
        be_mode(robot, robot.q_home, 1, values=[0.0] * 5)


# --- B_iIKMX against the general machinery -----------------------------------------------------


def test_bikmx_matches_pp_inverse_geometry_on_moved_footholds(robot):
    rng = np.random.default_rng(1)
    q = robot.q_home
    for k in range(30):
        st = random_stance(rng, tilt=0.15 if k % 2 else 0.0)
        M = nacelle_pose(rng, st)
        q = pp_configuration(robot, st, M, robot.q_home)
        assert np.linalg.norm(nacelle(robot, q).translation - M.translation) < 1e-10
        # actuator lengths: distances from the footholds to the attachment points
        expected = [
            np.linalg.norm(st.footholds[i].translation - P_)
            for i in range(3)
            for P_ in attachments(M, i)
        ]
        assert np.allclose(q[robot.actuated_q], expected, atol=1e-9)
        assert np.allclose(actuator_lengths(P, M, st), expected, atol=1e-12)
        for b in BRANCHES:
            j, kk = support_branches(b)
            got = bikmx(P, M, st, b)
            want = np.r_[
                lockable_from_q(robot, q, b),
                lockable_from_q(robot, q, j)[0],
                lockable_from_q(robot, q, kk)[0],
            ]
            assert np.allclose(got, want, atol=1e-9), (k, b, got - want)


def test_bikmx_virtual_q3_differs_by_the_triangle_angle(robot):
    """The paper's q3 is measured from the median A P_C, the model's lock from rod L."""
    rng = np.random.default_rng(2)
    st = random_stance(rng)
    M = nacelle_pose(rng, st)
    q = pp_configuration(robot, st, M)
    e = 2 * P.r_p * math.sin(P.theta)
    s0 = tripod_cf.virtual_joints(P, tripod_cf.home_nacelle_placement(P))[0]
    gamma_home = math.atan2(0.5 * e, s0[3])
    for b in BRANCHES:
        v = bikmx_virtual(P, M, st, b)
        m = bikmx(P, M, st, b)
        q_l = coordinate(robot, q, f"branch{b}_qL")
        q4 = tripod_cf.virtual_joints(P, M, st.footholds)[b - 1, 3]
        gamma = math.acos((q_l**2 + q4**2 - 0.25 * e**2) / (2 * q_l * q4))
        assert m[2] == pytest.approx(v[2] - gamma_home + gamma, abs=1e-10)
        assert m[0] == pytest.approx(v[0] - s0[0], abs=1e-12)
        assert m[3] == pytest.approx(v[3] - s0[5], abs=1e-12)


# --- XFKMB_i against the general machinery -----------------------------------------------------


def test_xfkmb_matches_be_inverse_geometry(robot):
    rng = np.random.default_rng(3)
    st = Stance.default(P)
    for b in BRANCHES:
        M0 = tilted(st, b)
        q0 = pp_configuration(robot, st, M0)
        b_i = bikmx(P, M0, st, b)
        mode = be_mode(robot, q0, b)
        # the URDF stores 10 significant digits: the model matches the parameters to ~1e-10
        assert np.allclose(mode.lock_targets(), b_i[[1, 0, 2, 3, 4, 5]], atol=1e-9)
        be = mode_robot(robot, st, mode, q0)
        for _ in range(4):
            f = st.footholds[b - 1]
            target = pin.SE3(f.rotation, f.translation + rng.uniform(-0.05, 0.05, 3))
            res = xfkmb(P, b_i, st.moved(b, target), b, M0)
            qb = pkdyn.inverse_geometry(be, foot_frame(target), q_init=q0, check_limits=False).q
            Mb = nacelle(robot, qb)
            assert res.residual < 1e-11
            assert np.linalg.norm(Mb.translation - res.placement.translation) < 1e-9
            assert np.linalg.norm(pin.log3(Mb.rotation.T @ res.placement.rotation)) < 1e-9
            assert np.allclose(qb[robot.actuated_q], res.lengths, atol=1e-9)


def test_xfkmb_converges_from_a_distant_guess_and_checks_strokes():
    st = Stance.default(P)
    M0 = tilted(st, 1)
    b_i = bikmx(P, M0, st, 1)
    guess = pin.SE3(pin.exp3(np.array([0.05, -0.05, 0.05])) @ M0.rotation, M0.translation + 0.02)
    res = xfkmb(P, b_i, st, 1, guess)
    assert np.linalg.norm(res.placement.translation - M0.translation) < 1e-10
    assert np.linalg.norm(pin.log3(res.placement.rotation.T @ M0.rotation)) < 1e-10
    far = pin.SE3(np.eye(3), np.array([1.5, 0.0, 0.06]))
    with pytest.raises(pkdyn.JointLimitError) as err:
        xfkmb(P, b_i, st.moved(1, far), 1, M0)
    assert err.value.value > P.stroke_max
    # without the stroke check the optimisation still keeps the locks
    res = xfkmb(P, b_i, st.moved(1, far), 1, M0, check_limits=False)
    assert np.allclose(bikmx(P, res.placement, st.moved(1, far), 1), b_i, atol=1e-11)


def test_virtual_xfkmb_keeps_the_papers_values():
    st = Stance.default(P)
    M0 = tilted(st, 3)
    b_v = bikmx_virtual(P, M0, st, 3)
    f = st.footholds[2]
    moved = st.moved(3, pin.SE3(f.rotation, f.translation + np.array([0.03, 0.02, 0.02])))
    res = xfkmb(P, b_v, moved, 3, M0, virtual=True)
    assert np.allclose(bikmx_virtual(P, res.placement, moved, 3), b_v, atol=1e-11)
    # with rod L locked instead, the nacelle ends elsewhere: the two readings of q3 differ
    other = xfkmb(P, bikmx(P, M0, st, 3), moved, 3, M0)
    assert np.linalg.norm(other.placement.translation - res.placement.translation) > 1e-4


# --- why the scenario tilts the nacelle ---------------------------------------------------------


def test_be_is_serially_singular_with_a_level_nacelle(robot):
    """With every edge P_L P_R parallel to the support, the locked q1 of the supports do not
    react to translations: the nacelle slides along rod L of the swinging branch, foot at rest."""
    st = Stance.default(P)
    q = robot.q_home
    be = mode_robot(robot, st, be_mode(robot, q, 1), q)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = classify(be, q)
        assert rep.kind == "serial"
        # the motion: nacelle translating along A_1 P_L1, no rotation, keeps all constraints
        Jc = be.closure_set.jacobian(be.data, q)
        J6 = pkdyn.analysis.kinematics.platform_jacobian(be, q)
        A = st.footholds[0].translation
        P_L, _ = attachments(tripod_cf.home_nacelle_placement(P), 0)
        d = (P_L - A) / np.linalg.norm(P_L - A)
        nacelle_v = np.zeros(robot.nv)
        nacelle_v[:3] = d  # free-flyer: local linear velocity (nacelle level: world axes)
        K = np.vstack([Jc, J6])
        free = np.arange(6, robot.nv)
        x = np.linalg.lstsq(K[:, free], -K @ nacelle_v, rcond=None)[0]
        v = nacelle_v.copy()
        v[free] = x
        assert np.max(np.abs(K @ v)) < 1e-9  # foot at rest, closures and locks kept
        assert np.linalg.norm(v[robot.actuated_v]) > 0.1  # driven by the actuators
        # tilted by 0.1 rad about the axis normal to branch 1: regular, cond(B) ~ 10
        qt = pp_configuration(robot, st, tilted(st, 1))
        bt = mode_robot(robot, st, be_mode(robot, qt, 1), qt)
        rep = classify(bt, qt)
        assert rep.kind == "regular"
        assert rep.cond_B < 20.0
