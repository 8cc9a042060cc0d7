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
  the forward geometry gives;
- with compliant links (the gear a rigid row of the condensation, beside the closure): the
  deflection against the nonlinear equilibrium under a small load, the first frequency against
  the FFT of a simulated free vibration.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pinocchio as pin
import pytest
from support.urdf_edit import family_xml, load_like, where_of, with_twists

import pkdyn
from pkdyn.calibration import Measurements, calibrate
from pkdyn.cli import main
from pkdyn.dynamics.forward import simulate
from pkdyn.precision import Material, elastic_model, modes, stiffness
from pkdyn.precision.parameters import placement_parameters
from pkdyn.precision.perturbation import perturbed
from pkdyn.precision.sensitivity import pose_sensitivity
from solvers import PassiveForces

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
    assert robot.actuator_names == ["motor1"] and robot.constraints.kinds == ["hinge", "coupling"]
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


def _equilibrium(em, q0, k, F):
    """Nonlinear equilibrium of the virtual-joint robot under a dead force ``F`` at the platform.

    Independent of the stiffness analysis: the springs' generalized force (actuator, link and
    joint springs, :class:`solvers.PassiveForces`), the load's (Pinocchio's frame Jacobian) and
    the constraint rows' (closure and gear) balance, and the constraints hold: a root of
    ``f(q) + Jc^T lambda = 0, c(q) = 0`` in ``(dq, lambda)`` (Levenberg-Marquardt).
    """
    import scipy.optimize

    ext, P = em.robot, em.robot.passive
    stiff, rest = P.stiffness.copy(), P.rest.copy()
    stiff[ext.actuated_v] += k
    rest[ext.actuated_q] = q0[ext.actuated_q]
    springs = PassiveForces(ext.model, stiffness=stiff, rest=rest)
    cs, data, nv = ext.constraints, ext.data, ext.nv

    def residual(x):
        q = pin.integrate(ext.model, q0, x[:nv])
        f = springs.conservative_force(q)
        pin.computeJointJacobians(ext.model, data, q)
        pin.updateFramePlacements(ext.model, data)
        J = pin.getFrameJacobian(
            ext.model, data, ext.platform_frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        f += J[:3].T @ F
        r, Jc = cs.residual_and_jacobian(data, q)
        return np.concatenate([(f + Jc.T @ x[nv:]) / np.abs(F).max(), r])

    sol = scipy.optimize.least_squares(
        residual, np.zeros(nv + cs.n), xtol=1e-15, ftol=1e-15, gtol=1e-15
    )
    assert np.abs(sol.fun).max() < 1e-9  # unbalanced force, relative to the load
    return pin.integrate(ext.model, q0, sol.x[:nv])


def test_compliant_links_of_the_geared_five_bar(geared, capsys):
    """Compliant links and the gear together: the gear is a rigid row of the condensation.

    Stiffness against the nonlinear equilibrium under a small load (the deflection by finite
    load: linear to first order), the first frequency against the FFT of a free vibration
    simulated with the gear and the closures (constrained forward dynamics), and the command.
    """
    _, _, path = geared
    robot = pkdyn.load(path)  # with its geometry: the links' cylinders are the beams
    k = 2e3
    em = elastic_model(robot, k, material=Material("polymer", 5e9, 1.9e9, 1200.0))
    assert em.links and em.robot.constraints.kinds == ["hinge", "coupling"]
    q0 = em.embed(robot.q_home)
    F = np.array([0.4, -0.3, 0.2])
    S = stiffness(em, robot.q_home, wrench=np.concatenate([F, np.zeros(3)]))
    for scale in (1e-2, 1e-1):
        q = _equilibrium(em, q0, k, scale * F)
        ext = em.robot
        d_nl = ext.platform_placement(q).translation - ext.platform_placement(q0).translation
        err = np.linalg.norm(scale * S.deflection[:3] - d_nl) / np.linalg.norm(d_nl)
        assert err < 2e-2 * scale, err  # second order: error proportional to the load
        gear = ext.constraints.couplings.residual(ext.data, q)
        assert np.abs(gear).max() < 1e-12  # the equilibrium keeps the gear
    rigid = stiffness(robot, robot.q_home, k, links=False)
    assert S.K[0, 0] < rigid.K[0, 0]  # the links' bending softens it along x
    # the first mode rings in a simulation of the constrained dynamics (gear included)
    result = modes(em, robot.q_home)
    assert result.f1 < modes(robot, robot.q_home, k).f1
    f = _ring(em, result, 0, periods=8, integrator="rk4", step=1.0 / (6 * result.frequencies[-1]))
    assert f == pytest.approx(result.f1, rel=1e-4)
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
    assert main(argv) == 0
    assert "K" in capsys.readouterr().out


def _ring(em, result, index, periods, **options):
    """Release the virtual-joint robot along a mode; the frequency its platform rings at (FFT
    peak of the platform's motion along the mode: Hann window, zero padding, parabolic
    interpolation), the actuator a spring ``-k (qa - qa0)``, no gravity."""
    model = pin.Model(em.robot.model)
    model.gravity = pin.Motion.Zero()
    robot = dataclasses.replace(em.robot, model=model, data=model.createData())
    qa0 = robot.q_home[robot.actuated_q].copy()
    k = em.actuator_stiffness

    def torque(t, q, v):
        return -k * (q[robot.actuated_q] - qa0)

    f = result.frequencies[index]
    shape = result.platform[index][:3]
    v0 = 1e-4 * 2 * np.pi * f * result.shapes[index] / np.abs(shape).max()
    dt = 1.0 / (24 * f)
    run = simulate(robot, periods / f, dt, q0=robot.q_home, v0=v0, torque=torque, **options)
    assert np.abs(run.coupling_residual).max() < 1e-9
    P = np.array([robot.platform_placement(q).translation for q in run.q])
    x = (P - P[0]) @ (shape / np.linalg.norm(shape))
    x = x - x.mean()
    n = x.size
    X = np.abs(np.fft.rfft(x * np.hanning(n), 16 * n))
    i = int(np.argmax(X[1:])) + 1
    a, b, c = np.log(X[i - 1 : i + 2])
    return (i + 0.5 * (a - c) / (a - 2 * b + c)) / (16 * n * dt)
