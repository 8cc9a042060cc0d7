"""Gough-Stewart (MEL prototype): leg-length closed form against the numeric path."""

import numpy as np
import pytest

import pkdyn
from pkdyn.closed_form import gough_stewart as cf
from pkdyn.library import gough_stewart as gs


def _poses(robot, n, rng, dp=0.03, da=0.08):
    p = robot.params
    out = []
    while len(out) < n:
        pose = np.concatenate(
            [rng.uniform(-dp, dp, 3) + [0, 0, p.home_height()], rng.uniform(-da, da, 3)]
        )
        rho = cf.leg_lengths_rpy(p.a, p.b, pose)[0]
        if np.all((rho > p.rho_min) & (rho < p.rho_max)):
            out.append(pose)
    return np.array(out)


def test_mel_geometry_from_seed():
    p = gs.Params()
    # Table 3.1: base joints 25 mm and platform joints 20 mm below their plates
    assert np.allclose(p.a[:, 2], -0.025) and np.allclose(p.b[:, 2], -0.020)
    assert p.rho_min == (0.528,) * 3 + (0.491,) * 3
    assert p.rho_max == (0.757,) * 3 + (0.733,) * 3


def test_mobility_six(gough_stewart):
    assert gough_stewart.mobility() == 6
    assert gough_stewart.loops == 5


def test_actuated_coordinates_are_leg_lengths(gough_stewart):
    """Independent check: the prismatic coordinate equals |A_i B_i| in the assembled model."""
    rng = np.random.default_rng(0)
    p = gough_stewart.params
    for pose in _poses(gough_stewart, 20, rng):
        ik = pkdyn.inverse_geometry(gough_stewart, pose)
        M = ik.placement
        B_world = (M.rotation @ p.b.T).T + M.translation
        np.testing.assert_allclose(ik.qa, np.linalg.norm(B_world - p.a, axis=1), atol=1e-10)


def test_closed_form_matches_numeric_ik(gough_stewart):
    rng = np.random.default_rng(1)
    p = gough_stewart.params
    poses = _poses(gough_stewart, 50, rng)
    rho = cf.leg_lengths_rpy(p.a, p.b, poses)
    for k, pose in enumerate(poses):
        np.testing.assert_allclose(
            pkdyn.inverse_geometry(gough_stewart, pose).qa, rho[k], atol=1e-9
        )


def test_fk_ik_round_trip_1000_poses(gough_stewart):
    rng = np.random.default_rng(2)
    p = gough_stewart.params
    poses = _poses(gough_stewart, 1000, rng)
    rho = cf.leg_lengths_rpy(p.a, p.b, poses)
    q = gough_stewart.q_home
    worst = 0.0
    for k, pose in enumerate(poses):
        fk = pkdyn.forward_geometry(gough_stewart, rho[k], q_init=q)
        worst = max(worst, float(np.linalg.norm(fk.position - pose[:3])))
        worst = max(worst, float(np.abs(fk.rpy - pose[3:]).max()))
        q = fk.q
    assert worst < 1e-9


def test_assembly_from_random_actuator_inputs(gough_stewart):
    rng = np.random.default_rng(3)
    p = gough_stewart.params
    # random leg lengths near the image of random poses (arbitrary length sets need not close)
    lengths = cf.leg_lengths_rpy(p.a, p.b, _poses(gough_stewart, 100, rng, 0.02, 0.05))
    for rho in lengths + rng.uniform(-0.003, 0.003, lengths.shape):
        fk = pkdyn.forward_geometry(gough_stewart, rho)
        assert pkdyn.closure_residual(gough_stewart, fk.q) < 1e-10
        np.testing.assert_allclose(
            cf.leg_lengths(p.a, p.b, fk.position, fk.placement.rotation)[0], rho, atol=1e-10
        )


def test_stroke_limit_is_reported_with_the_leg(gough_stewart):
    with pytest.raises(pkdyn.JointLimitError, match="leg"):
        pkdyn.inverse_geometry(gough_stewart, [0, 0, 0.9, 0, 0, 0])
    with pytest.raises(pkdyn.JointLimitError, match="leg1"):
        pkdyn.forward_geometry(gough_stewart, [0.4] * 6)


def test_bad_geometry_parameter():
    with pytest.raises(pkdyn.ParameterError, match="'A'"):
        pkdyn.load("gough_stewart", A=((0, 0, 0),) * 5)
