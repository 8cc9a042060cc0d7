"""Singularities: Clavel's four Delta families, Pasqui's 3-RRR cases, maps, dexterity.

Every singular configuration is constructed from geometry (not found by the code under test)
and its geometric condition (bars parallel, chain stretched, lines concurrent...) is checked on
the loaded model's joint frames before it is classified.
"""

import warnings

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis import dexterity, kinematics
from pkdyn.analysis import maps as singularity_map
from pkdyn.analysis.singularity import classify, singularity_json
from pkdyn.analysis.statics import actuator_efforts
from pkdyn.closed_form import delta as dcf
from pkdyn.closed_form import planar_3rrr as rcf
from solvers import solve_lm


def quiet_classify(robot, q):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a regular or exactly singular case must not warn
        return classify(robot, q)


# --------------------------------------------------------------------------------------------
# Delta: configurations built from arm angles and a nacelle position


def delta_config(robot, alpha, P):
    """Assembled q with arm angles ``alpha``, nacelle at ``P`` (orientation kept level).

    The bars' ball joints are set from geometry (shortest rotation of the bar axis onto the
    bar direction), then polished by the closure solver on the bar joints only. The residual
    is ~1e-11, the precision of the lengths written in the URDF (10 digits).
    """
    m, data = robot.model, robot.data
    q = robot.q_home.copy()
    q[robot.actuated_q] = alpha
    j = m.getJointId("nacelle")
    jm = m.joints[j]
    M = m.jointPlacements[j].actInv(pin.SE3(np.eye(3), np.asarray(P, dtype=float)))
    q[jm.idx_q : jm.idx_q + 7] = pin.SE3ToXYZQUAT(M)
    pin.forwardKinematics(m, data, q)
    for cm in robot.constraint_models:
        jb = cm.joint1_id
        oM = data.oMi[m.parents[jb]] * m.jointPlacements[jb]
        d = oM.rotation.T @ (np.asarray(P) + cm.joint2_placement.translation - oM.translation)
        quat = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), d / np.linalg.norm(d))
        q[m.joints[jb].idx_q : m.joints[jb].idx_q + 4] = quat.coeffs()
    free = np.setdiff1d(robot.passive_v, np.arange(jm.idx_v, jm.idx_v + 6))
    cs = robot.closure_set
    sol = solve_lm(
        m, q, lambda x: cs.residual(data, x), lambda x: cs.jacobian(data, x), free, tol=1e-10
    )
    assert sol.error < 1e-10
    return sol.q


def bar_directions(robot, q):
    """Unit directions (6, 3) of the six bars, upper joint to nacelle joint, from the model."""
    pin.forwardKinematics(robot.model, robot.data, q)
    out = []
    for cm in robot.constraint_models:
        top = robot.data.oMi[cm.joint1_id].translation
        low = robot.data.oMi[cm.joint2_id].act(cm.joint2_placement.translation)
        out.append((low - top) / np.linalg.norm(low - top))
    return np.array(out)


def parallel(u, v):
    return np.linalg.norm(np.cross(u, v)) < 1e-8


@pytest.fixture(scope="module")
def g(delta):
    return delta.params


def alpha_star(g):
    """Arm angle putting the reduced elbow C'_i on the base axis: R + la cos(alpha) = 0."""
    return float(np.arccos(-(g.ra - g.rb) / g.la))


def test_delta_family_a_all_bars_parallel(delta, g):
    """a) all six bars parallel: the three C'_i coincide (alpha_i = alpha*); the nacelle keeps
    2 translations (sphere) and the rotation about the bar direction."""
    a = alpha_star(g)
    C = dcf.elbow_points(g, [a, a, a])[0]
    np.testing.assert_allclose(C - C[0], 0.0, atol=1e-15)
    d = np.array([0.1, 0.05, -1.0]) / np.linalg.norm([0.1, 0.05, -1.0])
    q = delta_config(delta, [a, a, a], C[0] + g.lb * d)
    bars = bar_directions(delta, q)
    assert all(parallel(bars[0], b) for b in bars)
    rep = quiet_classify(delta, q)
    assert rep.kind == "parallel"
    assert rep.parallel_directions.shape[0] == 2  # 2 uncontrolled translations
    np.testing.assert_allclose(rep.parallel_directions @ d, 0.0, atol=1e-6)  # tangent to sphere
    assert rep.platform_directions.shape[0] == 3  # + rotation about the bars
    rot = [t for t in rep.platform_directions if np.linalg.norm(t[3:]) > 0.5]
    assert len(rot) == 1 and parallel(rot[0][3:], d)
    assert rep.cond_A > 1e8 and np.isfinite(rep.cond_A)


def test_delta_family_b_two_pairs_parallel(delta, g):
    """b) bars of arms 1 and 2 parallel (C'_1 = C'_2): one translation left (arc of circle)."""
    a = alpha_star(g)
    C = dcf.elbow_points(g, [a, a, a])[0, 0]
    d = np.array([0.15, -0.1, -1.0]) / np.linalg.norm([0.15, -0.1, -1.0])
    P = C + g.lb * d
    alpha3, ok = dcf.inverse(g, P)
    assert ok[0]
    q = delta_config(delta, [a, a, alpha3[0, 2]], P)
    bars = bar_directions(delta, q)
    assert all(parallel(bars[0], b) for b in bars[:4]) and not parallel(bars[0], bars[4])
    rep = quiet_classify(delta, q)
    assert rep.kind == "parallel" and not rep.constraint
    (t,) = rep.parallel_directions
    # the free motion is tangent to both spheres: normal to both bar directions
    assert abs(t @ bars[0]) < 1e-6 and abs(t @ bars[4]) < 1e-6


def test_delta_family_c_two_parallelograms_in_one_plane(delta, g):
    """c) parallelograms 1 and 2 in one (horizontal) plane with the nacelle: the nacelle may
    turn about the line through the nacelle joints of pair 3 (its centre then moves normal to
    the nacelle plane, to first order).

    Construction: arms 1, 2 at alpha = 1.2 rad, nacelle at their elbows' height, on the
    bisector of arms 1 and 2, lb away (horizontally) from both elbows; arm 3 from chain 3's
    inverse model.
    """
    R, la, lb = g.ra - g.rb, g.la, g.lb
    a = 1.2
    rho = R + la * np.cos(a)
    s = (rho - np.sqrt(4 * lb**2 - 3 * rho**2)) / 2  # |s e_60 - rho e_0| = lb
    P = np.array([s / 2, s * np.sqrt(3) / 2, -la * np.sin(a)])
    alpha, ok = dcf.inverse(g, P)
    assert ok[0]
    q = delta_config(delta, [a, a, alpha[0, 2]], P)
    bars = bar_directions(delta, q)
    np.testing.assert_allclose(bars[:4, 2], 0.0, atol=1e-9)  # 4 bars in the nacelle plane
    rep = quiet_classify(delta, q)
    assert rep.kind == "parallel" and not rep.constraint
    (tc,) = rep.parallel_directions
    np.testing.assert_allclose(np.abs(tc), [0, 0, 1], atol=1e-6)  # the centre moves vertically
    (t,) = rep.platform_directions
    t3 = np.array([-np.sin(dcf.THETA[2]), np.cos(dcf.THETA[2]), 0.0])  # pair-3 joint line
    assert parallel(t[3:], t3) and np.linalg.norm(t[3:]) > 0.99
    # the rotation axis passes through the pair-3 nacelle joints: v = -omega x r_3
    r3 = g.rb * np.array([np.cos(dcf.THETA[2]), np.sin(dcf.THETA[2]), 0.0])
    np.testing.assert_allclose(t[:3], -np.cross(t[3:], r3), atol=1e-7)


def test_delta_family_d_parallelograms_in_one_plane():
    """d) all three parallelograms in the nacelle plane (lb = R + la cos(alpha), nacelle at the
    elbows' height): vertical translation and two tilts are uncontrolled."""
    robot = pkdyn.load("delta", lb=0.2, geometry=False)
    g = robot.params
    R = g.ra - g.rb
    a = float(np.arccos((g.lb - R) / g.la))
    q = delta_config(robot, [a, a, a], [0.0, 0.0, -g.la * np.sin(a)])
    np.testing.assert_allclose(bar_directions(robot, q)[:, 2], 0.0, atol=1e-9)
    rep = quiet_classify(robot, q)
    assert rep.kind == "parallel"
    (t,) = rep.parallel_directions
    assert abs(abs(t[2]) - 1.0) < 1e-9  # vertical translation
    assert rep.platform_directions.shape[0] == 3
    span = rep.platform_directions
    # the free twists are vz and rotations about horizontal axes: no vx, vy, wz component
    np.testing.assert_allclose(span[:, [0, 1, 5]], 0.0, atol=1e-7)


@pytest.mark.parametrize("mode", ["stretched", "folded"])
def test_delta_serial_arm_and_bars_aligned(delta, g, mode):
    """Serial: arm 1 and its bars aligned (stretched or folded back): arm 1 loses control."""
    a1 = 1.9 if mode == "stretched" else -1.2
    C1 = dcf.elbow_points(g, [a1, 0.0, 0.0])[0, 0]
    arm = np.array([np.cos(a1), 0.0, -np.sin(a1)])
    P = C1 + (1.0 if mode == "stretched" else -1.0) * g.lb * arm
    alpha, ok = dcf.inverse(g, P)
    assert ok[0]
    q = delta_config(delta, [a1, alpha[0, 1], alpha[0, 2]], P)
    assert parallel(bar_directions(delta, q)[0], arm)
    rep = quiet_classify(delta, q)
    assert rep.kind == "serial"
    (d,) = rep.serial_directions
    np.testing.assert_allclose(np.abs(d), [1.0, 0.0, 0.0], atol=1e-6)
    with pytest.raises(pkdyn.SingularConfigurationError):
        _ = kinematics.kinematic_models(delta, q).J_inv
    # J exists at a serial singularity, and the platform cannot move along arm 1's bars
    J = kinematics.kinematic_models(delta, q).J
    assert abs(arm @ J[:, 0]) < 1e-6


# --------------------------------------------------------------------------------------------
# Planar 3-RRR (seed 001)


@pytest.fixture(scope="module")
def rrr():
    return pkdyn.load("planar_3rrr", geometry=False)


def rrr_ik(robot, X, steps=6, until=1.0):
    """IK continuation from the home pose towards ``X`` = (x, y, phi)."""
    q = robot.q_home
    X0 = robot.params.home_pose
    for t in np.linspace(0.0, until, steps + 1)[1:]:
        Y = X0 + t * (np.asarray(X) - X0)
        q = pkdyn.inverse_geometry(robot, [Y[0], Y[1], 0, 0, 0, Y[2]], q_init=q).q
    return q


def rrr_points(robot, q):
    """O_1, O_2, O_3 (3, 3, 2) of the three chains and the platform centre, from the model."""
    m, d = robot.model, robot.data
    pin.framesForwardKinematics(m, d, q)
    pts = []
    for i in range(3):
        O1 = d.oMi[m.getJointId(f"proximal{i + 1}")].translation[:2]
        O2 = d.oMi[m.getJointId(f"distal{i + 1}")].translation[:2]
        cm = robot.constraint_models[2 * i]
        O3 = d.oMi[cm.joint1_id].act(cm.joint1_placement.translation)[:2]
        pts.append([O1, O2, O3])
    return np.array(pts), robot.platform_placement(q).translation[:2]


def cross2(u, v):
    return u[0] * v[1] - u[1] * v[0]


def test_3rrr_serial_chain_stretched(rrr):
    """Chain 1 fully stretched (|O_1 O_3| = l1 + l2, sin q_2 = 0): serial, chain 1's actuator."""
    u = np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    X = np.array([*(0.2 * u), 0.0])  # B_1 - O_1 = (0.4 + 0.2) u for the default geometry
    qa, ok = rcf.inverse(rrr.params, X)
    assert ok[0]
    q = pkdyn.forward_geometry(rrr, qa[0], q_init=rrr_ik(rrr, X, until=0.95)).q
    pts, _ = rrr_points(rrr, q)
    O1, O2, O3 = pts[0]
    assert abs(cross2(O2 - O1, O3 - O2)) < 1e-9 and (O2 - O1) @ (O3 - O2) > 0
    rep = quiet_classify(rrr, q)
    assert rep.kind == "serial"
    np.testing.assert_allclose(np.abs(rep.serial_directions[0]), [1, 0, 0], atol=1e-6)


def test_3rrr_serial_chain_folded():
    """Chain 1 folded back (|O_1 O_3| = l1 - l2, q_2 = pi), other chains in elbow -1 mode."""
    robot = pkdyn.load("planar_3rrr", l1=0.4, l2=0.3, elbow=-1, geometry=False)
    p = robot.params
    ang, phi = 0.5, 0.05
    B1 = p.base_xy[0] + (p.l1 - p.l2) * np.array([np.cos(ang), np.sin(ang)])
    g1 = phi + p.platform_angles[0]
    X = np.array([*(B1 - p.h * np.array([np.cos(g1), np.sin(g1)])), phi])
    qa, ok = rcf.inverse(p, X, -1)
    assert ok[0]
    qa[0, 0] = ang
    q = pkdyn.forward_geometry(robot, qa[0], q_init=rrr_ik(robot, X, until=0.98)).q
    O1, O2, O3 = rrr_points(robot, q)[0][0]
    assert abs(cross2(O2 - O1, O3 - O2)) < 1e-9 and (O2 - O1) @ (O3 - O2) < 0
    rep = quiet_classify(robot, q)
    assert rep.kind == "serial"
    np.testing.assert_allclose(np.abs(rep.serial_directions[0]), [1, 0, 0], atol=1e-6)


CONCURRENT_PHI = float(np.arccos(0.8))
"""Default 3-RRR: at (0, 0, phi) the distal links are radial (O_2, O_3, P aligned) when
|0.5 - 0.4 e^{i phi}| = l1 = 0.3, i.e. cos(phi) = 0.8."""


def test_3rrr_parallel_distal_lines_concurrent(rrr):
    q = rrr_ik(rrr, [0.0, 0.0, CONCURRENT_PHI])
    pts, P = rrr_points(rrr, q)
    for _, O2, O3 in pts:
        assert abs(cross2(O3 - O2, P - O3)) < 1e-9  # distal line through the centre
    rep = quiet_classify(rrr, q)
    assert rep.kind == "parallel"
    (t,) = rep.parallel_directions
    np.testing.assert_allclose(np.abs(t), [0, 0, 1], atol=1e-6)  # uncontrolled rotation
    with pytest.raises(pkdyn.SingularConfigurationError) as err:
        _ = kinematics.kinematic_models(rrr, q).J
    assert err.value.kind == "parallel"
    with pytest.raises(pkdyn.SingularConfigurationError):
        kinematics.platform_twist(rrr, q, [1.0, 0.0, 0.0])
    with pytest.raises(pkdyn.SingularConfigurationError):
        actuator_efforts(rrr, q, [1.0, 0.0, 0.0])
    # J_inv still exists (no serial singularity): the derivative of Pasqui's inverse model
    J_inv = kinematics.kinematic_models(rrr, q).J_inv
    X = np.array([0.0, 0.0, CONCURRENT_PHI])
    p = rrr.params
    np.testing.assert_allclose(rcf.inverse(p, X, p.elbow)[0][0], q[rrr.actuated_q], atol=1e-9)
    h = 1e-6
    fd = [
        (rcf.inverse(p, X + e, p.elbow)[0] - rcf.inverse(p, X - e, p.elbow)[0])[0] / (2 * h)
        for e in h * np.eye(3)
    ]
    fd = np.column_stack(fd)
    np.testing.assert_allclose(J_inv, fd, atol=1e-6)
    out = singularity_json(rrr, q)
    assert out["kind"] == "parallel" and np.isfinite(out["cond_A"]) and out["cond_A"] > 1e8
    assert len(out["directions"]["parallel"]) == 1


def test_3rrr_parallel_distal_lines_parallel():
    """Distal links all vertical at pose (0, 0, 0): base points chosen to make it so."""
    p0 = pkdyn.load("planar_3rrr", geometry=False).params
    gam = np.asarray(p0.platform_angles)
    O2 = p0.h * np.column_stack([np.cos(gam), np.sin(gam)]) - [0.0, p0.l2]
    beta = np.deg2rad([200.0, 160.0, 185.0])  # cos(beta) < 0: elbow mode +1
    O1 = O2 + p0.l1 * np.column_stack([np.cos(beta), np.sin(beta)])
    base = tuple((float(a), float(b)) for a, b in O1)
    robot = pkdyn.load(
        "planar_3rrr", base_points=base, x_home=0.03, y_home=0.02, phi_home=0.1, geometry=False
    )
    q = rrr_ik(robot, [0.0, 0.0, 0.0])
    pts, _ = rrr_points(robot, q)
    for _, a, b in pts:
        assert abs((b - a)[0]) < 1e-9  # vertical distal links
    rep = quiet_classify(robot, q)
    assert rep.kind == "parallel"
    (t,) = rep.parallel_directions
    np.testing.assert_allclose(np.abs(t), [1, 0, 0], atol=1e-6)  # translation across the links


def test_near_singular_warns_with_finite_condition_number(rrr):
    q = rrr_ik(rrr, [0.0, 0.0, CONCURRENT_PHI - 1e-6])
    with pytest.warns(kinematics.NearSingularityWarning, match="near a parallel"):
        rep = classify(rrr, q)
    assert rep.kind == "regular" and rep.near
    assert 1e4 < rep.cond_A < 1e8 and np.isfinite(rep.distance)
    assert rep.parallel_directions.shape == (1, 3)  # the near-singular direction is reported
    km = kinematics.kinematic_models(rrr, q)
    with pytest.warns(kinematics.NearSingularityWarning):
        J = km.J
    np.testing.assert_allclose(km.A @ J, km.B, atol=1e-9 * np.max(np.abs(J)))


@pytest.mark.parametrize("name", ["delta", "gough_stewart", "planar_3rrr", "five_bar"])
def test_regular_configurations_are_not_flagged(name, delta, gough_stewart):
    robot = {"delta": delta, "gough_stewart": gough_stewart}.get(name) or pkdyn.load(
        name, geometry=False
    )
    rng = np.random.default_rng(7)
    M0 = robot.platform_placement(robot.q_home)
    for _ in range(5):
        d = np.zeros(6)
        d[robot.task_rows] = rng.uniform(-0.03, 0.03, robot.task_rows.size)
        target = pin.SE3(M0.rotation @ pin.exp3(d[3:]), M0.translation + d[:3])
        q = pkdyn.inverse_geometry(robot, target, q_init=robot.q_home).q
        rep = quiet_classify(robot, q)
        assert rep.kind == "regular" and not rep.near
        assert 0.0 < rep.distance <= 1.0
        assert rep.parallel_directions.size == rep.serial_directions.size == 0


# --------------------------------------------------------------------------------------------
# Closed-form maps, dexterity and plotting


def test_3rrr_map_matches_general_path_and_finds_singularities(rrr):
    p = rrr.params
    xs = np.linspace(-0.05, 0.05, 5)
    cmap = singularity_map.planar_3rrr_map(p, xs, xs, 0.2)
    d = cmap.data
    assert d.valid.all() and (d.kind == 0).all()
    # same condition numbers as the general elimination on the full model
    q = rrr_ik(rrr, [xs[3], xs[1], 0.2])
    rep = quiet_classify(rrr, q)
    assert d.cond_A[1, 3] == pytest.approx(rep.cond_A, rel=1e-7)
    assert d.cond_B[1, 3] == pytest.approx(rep.cond_B, rel=1e-7)
    km = kinematics.kinematic_models(rrr, q)
    assert d.lci[1, 3] == pytest.approx(dexterity.local_conditioning_index(km.J), rel=1e-7)
    # constructed singular poses: concurrent distal lines (parallel), stretched chain (serial)
    u = np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    X = np.array([[0.0, 0.0, CONCURRENT_PHI], [*(0.2 * u), 0.0], [0.02, 0.01, 0.1]])
    c = singularity_map.planar_3rrr_conditioning(p, X)
    assert c.kind.tolist() == [2, 1, 0]
    assert np.isfinite(c.cond_A).all() and c.lci[0] == 0.0


def test_delta_map_matches_dexterity_of_numeric_path(delta, g):
    P = np.array([[0.02, -0.03, -0.40], [0.08, 0.05, -0.33], [-0.1, 0.04, -0.45]])
    c = singularity_map.delta_conditioning(g, P)
    num = dexterity.dexterity_map(delta, P)
    assert c.valid.all() and num.valid.all()
    np.testing.assert_allclose(c.lci, num.lci, rtol=1e-7)
    np.testing.assert_allclose(c.manipulability, num.manipulability, rtol=1e-7)
    cmap = singularity_map.delta_map(
        g, np.linspace(-0.6, 0.6, 31), np.linspace(-0.6, 0.6, 31), -0.4
    )
    assert cmap.data.lci.shape == (31, 31)
    assert (~cmap.data.valid).any() and cmap.data.valid.any()  # workspace boundary inside
    assert np.isnan(cmap.data.lci[~cmap.data.valid]).all()
    assert (cmap.data.lci[cmap.data.valid] > 0).all()


def test_dexterity_indices_of_a_known_matrix():
    J = np.diag([2.0, 0.5])
    assert dexterity.manipulability(J) == pytest.approx(1.0)
    assert dexterity.condition_number(J) == pytest.approx(4.0)
    assert dexterity.local_conditioning_index(J) == pytest.approx(0.25)
    assert dexterity.condition_number(np.diag([1.0, 0.0])) == kinematics.COND_MAX
    Jh = dexterity.homogenise(np.ones((3, 3)), ("x", "y", "rz"), 0.1)
    np.testing.assert_allclose(Jh[2], 0.1)


def test_dexterity_at_singular_configuration_is_finite(rrr):
    q = rrr_ik(rrr, [0.0, 0.0, CONCURRENT_PHI])
    dx = dexterity.dexterity(rrr, q)
    assert dx.singular and dx.lci == 0.0 and np.isfinite(dx.cond)


def test_plot_conditioning_map_writes_png(rrr, tmp_path):
    from pkdyn.plotting import plot_conditioning_map

    xs = np.linspace(-0.3, 0.3, 41)
    cmap = singularity_map.planar_3rrr_map(rrr.params, xs, xs, CONCURRENT_PHI)
    out = tmp_path / "map.png"
    fig = plot_conditioning_map(cmap, field="cond_J", path=out)
    assert out.stat().st_size > 1000 and fig.axes
