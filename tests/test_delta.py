"""Delta: Clavel's closed forms against the general numeric path, assembly, round trips."""

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.closed_form import delta as cf


def _workspace_points(robot, n, rng):
    """Random nacelle positions in a cylinder around the home position, all reachable."""
    p = robot.params
    pts = []
    while len(pts) < n:
        r = 0.12 * np.sqrt(rng.uniform())
        t = rng.uniform(0, 2 * np.pi)
        P = np.array([r * np.cos(t), r * np.sin(t), p.home_height() + rng.uniform(-0.08, 0.08)])
        alpha, ok = cf.inverse(p, P)
        if ok[0] and np.all((alpha > p.alpha_min) & (alpha < p.alpha_max)):
            pts.append(P)
    return np.array(pts)


def test_mobility_counts_match_clavel(delta):
    # 12 ball joints: 9 = 3 + 6 internal (bar spin); universal at one bar end: 3 (seed 000)
    assert delta.mobility() == 9 and delta.mobility_split() == (3, 6)
    assert delta.dof() == 3  # one meaning of dof: what the platform can do, as pkdyn info says
    assert delta.loops == 5
    assert pkdyn.load("delta", bar_joint="universal", geometry=False).mobility() == 3


def test_closed_form_ik_solves_eq1(delta):
    """The arm angles put every C'_i at distance lb from P (Clavel's sphere, eq. 1)."""
    rng = np.random.default_rng(1)
    P = _workspace_points(delta, 200, rng)
    alpha, ok = cf.inverse(delta.params, P)
    assert ok.all()
    C = cf.elbow_points(delta.params, alpha)
    dist = np.linalg.norm(C - P[:, None, :], axis=2)
    np.testing.assert_allclose(dist, delta.params.lb, atol=1e-12)


def test_closed_form_fk_inverts_ik(delta):
    rng = np.random.default_rng(2)
    P = _workspace_points(delta, 500, rng)
    alpha, _ = cf.inverse(delta.params, P)
    P2, ok = cf.forward(delta.params, alpha)
    assert ok.all()
    np.testing.assert_allclose(P2, P, atol=1e-10)


def test_closed_forms_match_numeric_path(delta):
    rng = np.random.default_rng(3)
    P = _workspace_points(delta, 50, rng)
    alpha, _ = cf.inverse(delta.params, P)
    for k in range(len(P)):
        ik = pkdyn.inverse_geometry(delta, P[k])
        np.testing.assert_allclose(ik.qa, alpha[k], atol=1e-9)
        fk = pkdyn.forward_geometry(delta, alpha[k])
        np.testing.assert_allclose(fk.position, P[k], atol=1e-9)
        # the nacelle keeps its orientation (spatial parallelogram)
        assert np.abs(fk.placement.rotation - np.eye(3)).max() < 1e-9


def test_assembly_from_random_actuator_inputs(delta):
    rng = np.random.default_rng(4)
    P = _workspace_points(delta, 100, rng)
    alpha, _ = cf.inverse(delta.params, P)
    alpha += rng.uniform(-0.02, 0.02, alpha.shape)  # arbitrary inputs near the workspace
    P_cf, ok = cf.forward(delta.params, alpha)  # Clavel's direct model (three spheres)
    assert ok.all()
    for a, p_cf in zip(alpha, P_cf, strict=True):
        fk = pkdyn.forward_geometry(delta, a)
        assert pkdyn.closure_residual(delta, fk.q) < 1e-10
        # the solver moved only the passive coordinates: the actuated ones are the inputs
        np.testing.assert_allclose(fk.q[delta.actuated_q], a, rtol=0, atol=1e-15)
        np.testing.assert_allclose(fk.position, p_cf, atol=1e-9)


def test_fk_ik_round_trip_1000_poses(delta):
    rng = np.random.default_rng(5)
    P = _workspace_points(delta, 1000, rng)
    q = delta.q_home
    worst = 0.0
    for target in P:
        ik = pkdyn.inverse_geometry(delta, target, q_init=q)
        fk = pkdyn.forward_geometry(delta, ik.qa, q_init=ik.q)
        worst = max(worst, float(np.linalg.norm(fk.position - target)))
        q = ik.q
    assert worst < 1e-9


def test_two_assembly_modes_found(delta):
    alpha = np.array([0.5, 0.6, 0.7])
    modes = pkdyn.assembly_modes(delta, alpha, starts=48)
    z = sorted(m.position[2] for m in modes)
    P_low, _ = cf.forward(delta.params, alpha)
    assert any(abs(zz - P_low[0, 2]) < 1e-8 for zz in z)
    assert len(modes) >= 2  # the mirror nacelle position above the elbows exists too


def test_out_of_reach_pose_raises_naming_a_closure(delta):
    with pytest.raises(pkdyn.UnreachablePoseError, match="out of reach"):
        pkdyn.inverse_geometry(delta, [0.6, 0.0, -0.3])


def test_vectorised_closed_form_flags_unreachable(delta):
    P = np.array([[0.0, 0.0, delta.params.home_height()], [2.0, 0.0, -0.3]])
    alpha, ok = cf.inverse(delta.params, P)
    assert ok.tolist() == [True, False] and np.isnan(alpha[1]).all()
    Pf, okf = cf.forward(delta.params, np.array([[0.2, 0.2, 0.2], [3.0, -3.0, 3.0]]))
    assert okf[0]  # and the inverse model gives the arm angles back
    np.testing.assert_allclose(cf.inverse(delta.params, Pf[:1])[0][0], [0.2, 0.2, 0.2], atol=1e-12)


def test_home_is_assembled_and_centred(delta):
    assert pkdyn.closure_residual(delta, delta.q_home) < 1e-12
    M = delta.platform_placement(delta.q_home)
    np.testing.assert_allclose(M.translation, [0, 0, delta.params.home_height()], atol=1e-9)


def test_bar_lengths_in_assembled_model(delta):
    """Independent geometric check: every bar spans lb between arm tip and nacelle."""
    fk = pkdyn.forward_geometry(delta, [0.3, 0.9, 0.5])
    pin.framesForwardKinematics(delta.model, delta.data, fk.q)
    for cm in delta.constraint_models:
        bar_top = delta.data.oMi[cm.joint1_id].translation
        lower = delta.data.oMi[cm.joint2_id].act(cm.joint2_placement.translation)
        assert abs(np.linalg.norm(lower - bar_top) - delta.params.lb) < 1e-10
