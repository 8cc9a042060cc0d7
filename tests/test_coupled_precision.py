"""Calibration, stiffness and modes of a coupled closed-loop robot (issue 27 item 1, issue 25).

The robot: the library five-bar with its second motor replaced by a gear between the two base
joints (``<pkdyn:coupling joint="proximal2" source="proximal1" multiplier="-0.7">``): one
actuator, one loop, one coupling row in the constraint layer. Checks against an independent truth:

- the identification Jacobian (pose sensitivity to the placements) against finite differences
  of the perturbed robot's forward geometry, which solves the loop *and* the coupling;
- calibration of a robot whose description is edited within +-2 mm, +-0.5 deg in the plane,
  measured by its own forward geometry plus 10 um noise: identifiable errors recovered within
  their standard deviations, held-out poses predicted to the noise, the out-of-plane errors the
  planar loop cannot absorb and the unidentifiable ones reported;
- stiffness against ``K = k / (dx/dqa)^2`` (the actuator alone, the gear rigid) from finite
  differences of the forward geometry, the loaded deflection against ``F / K``, and the natural
  frequency against ``sqrt(k / m_eff) / 2 pi`` with ``m_eff = v^T M v`` along the motion ``v``
  the forward geometry gives.
"""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest
from support.urdf_edit import family_xml, load_like, where_of, with_twists

import pkdyn
from pkdyn.calibration import Measurements, calibrate
from pkdyn.cli import main
from pkdyn.precision import modes, stiffness
from pkdyn.precision.parameters import placement_parameters
from pkdyn.precision.perturbation import perturbed
from pkdyn.precision.sensitivity import pose_sensitivity

SIGMA = 1e-5
IN_PLANE = (".tx", ".ty", ".rz", ".offset")


def geared_xml() -> str:
    five = pkdyn.load("five_bar", geometry=False)
    xml = family_xml(five)
    xml = re.sub(
        r'<transmission name="proximal2_transmission">.*?</transmission>', "", xml, flags=re.S
    )
    q1, q2 = float(five.q_home[0]), float(five.q_home[2])
    gear = (
        f'<pkdyn:coupling name="gear" joint="proximal2" source="proximal1" multiplier="-0.7" '
        f'joint_ref="{q2!r}" source_ref="{q1!r}"/>'
    )
    return xml.replace('task="x y"/>', 'task="x"/>' + gear)


@pytest.fixture(scope="module")
def geared(tmp_path_factory):
    xml = geared_xml()
    path = tmp_path_factory.mktemp("geared") / "geared.urdf"
    path.write_text(xml)
    robot = pkdyn.load(path, geometry=False)
    assert robot.actuator_names == ["motor1"] and robot.closure_set.nc == 7  # hinge + gear
    return robot, xml, path


def test_identification_jacobian_includes_the_coupling(geared):
    robot, _, _ = geared
    pm = placement_parameters(robot)
    qa = robot.q_home[robot.actuated_q] + 0.3
    q = pkdyn.forward_geometry(robot, qa).q
    K = pose_sensitivity(robot, q, pm).K
    x0 = pkdyn.forward_geometry(robot, qa, q_init=q).placement
    cols = [j for j, n in enumerate(pm.names) if n.endswith(IN_PLANE)]
    eps = 1e-7
    for j in cols:
        dp = np.zeros(pm.size)
        dp[j] = eps
        P = perturbed(robot, pm, dp)
        x1 = pkdyn.forward_geometry(
            P.robot, P.joint_coordinates(qa), q_init=q, check_limits=False
        ).placement
        fd = np.concatenate(
            [(x1.translation - x0.translation) / eps, pin.log3(x1.rotation @ x0.rotation.T) / eps]
        )
        np.testing.assert_allclose(K[:, j], fd, atol=2e-5 * max(1.0, np.abs(K).max()))


def test_calibration_of_the_geared_five_bar_recovers_the_errors(geared):
    robot, xml, _ = geared
    pm = placement_parameters(robot)
    rng = np.random.default_rng(1)
    p_true = rng.uniform(-1, 1, pm.size) * pm.tolerances(2e-3, np.deg2rad(0.5), 0.0)
    p_true = np.where([n.endswith(IN_PLANE) for n in pm.names], p_true, 0.0)
    xi = pm.twists(p_true)
    twists = {where_of(pl): x for pl, x in zip(pm.placements, xi, strict=True) if np.any(x)}
    truth = load_like(with_twists(xml, twists), robot)
    qa = robot.q_home[robot.actuated_q] + np.linspace(-0.6, 0.6, 40)[:, None]
    poses = [
        pkdyn.forward_geometry(truth, a, q_init=truth.q_home, check_limits=False).placement
        for a in qa
    ]
    m = Measurements.from_placements(qa, poses, "position")
    m.position = m.position + rng.normal(0.0, SIGMA, m.position.shape)
    res = calibrate(robot, m, pm, noise=SIGMA, holdout=0.25)
    # the planar loop cannot absorb out-of-plane errors: reported, not estimated
    assert "distal2.rx" in res.not_assembling and "proximal1.tx" not in res.not_assembling
    ident = res.identifiability
    assert 0 < ident.rank < pm.size - len(res.not_assembling)  # some are not identifiable
    assert res.before.position_rms > 100 * SIGMA
    assert res.validation_after.position_rms < 1.5 * np.sqrt(2) * SIGMA
    # identifiable errors: truth plus what the unidentifiable ones add to them, within 4.5 std
    exp = p_true[ident.identifiable].copy()
    for j, c in ident.combinations.items():
        if j < pm.size:
            exp += c * p_true[j]
    est = ident.identifiable
    z = np.abs(res.p[est] - exp) / res.std[est]
    assert z.max() < 4.5, (z.max(), pm.names[est[int(np.argmax(z))]])
    assert np.all(res.p[np.setdiff1d(np.arange(pm.size), est)] == 0.0)


def _motion(robot, q, qa, eps=1e-6):
    qp = pkdyn.forward_geometry(robot, qa + eps, q_init=q).q
    qm = pkdyn.forward_geometry(robot, qa - eps, q_init=q).q
    dx = (robot.platform_placement(qp).translation - robot.platform_placement(qm).translation) / (
        2 * eps
    )
    return pin.difference(robot.model, qm, qp) / (2 * eps), dx


def test_stiffness_and_frequency_of_the_geared_five_bar(geared):
    robot, _, _ = geared
    q = robot.q_home
    qa = q[robot.actuated_q]
    k = 1e3
    v, dx = _motion(robot, q, qa)
    K_expected = k / dx[0] ** 2  # the gear is rigid: one spring, seen through dx/dqa
    S = stiffness(robot, q, k)
    assert S.task == ("x",)
    np.testing.assert_allclose(S.K[0, 0], K_expected, rtol=1e-6)
    loaded = stiffness(robot, q, k, wrench=[1.0], loaded=True)
    assert loaded.deflection[0] == pytest.approx(1.0 / K_expected, rel=2e-2)
    M = pin.crba(robot.model, robot.data, q)
    M = np.triu(M) + np.triu(M, 1).T
    f = np.sqrt(k / (v @ M @ v)) / (2 * np.pi)
    np.testing.assert_allclose(modes(robot, q, k).frequencies, [f], rtol=1e-6)


def test_compliant_links_of_a_coupled_robot_are_refused_in_one_line(geared, capsys):
    robot, _, path = geared
    qa = repr(float(robot.q_home[robot.actuated_q][0]))
    argv = [
        "stiffness",
        str(path),
        "--qa",
        qa,
        "--actuator-stiffness",
        "1e3",
        "--material",
        "steel",
    ]
    code = main(argv)
    err = capsys.readouterr().err.strip()
    assert code == 1 and err.startswith("pkdyn: error:") and "\n" not in err, err
    assert "rigid links" in err
