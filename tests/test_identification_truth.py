"""Identification against an independent truth: MuJoCo's inverse dynamics of perturbed robots.

For the Delta, the Gough-Stewart platform, the five-bar and the walking tripod in mode PP: the
masses and rotational inertias of every body are scaled by 10-30 % (either way; centres of mass
kept), rotor inertias and motor friction are added; the truth's efforts along a multi-sine
motion come from MuJoCo (``mj_inverse`` on the exported model, projected onto the actuators
through MuJoCo's own closure Jacobian, :func:`pkdyn.model.formats.mjcf.actuator_efforts`), the
internal mobilities of the truth (the Delta's bar spin) following its own dynamics; the motor
friction is added by the drive model, and 1 % noise. The identification, from the nominal
robot, must

- recover the base parameters of the truth within the noise: every estimate within 4.5 of its
  standard deviations, their RMS within 2;
- predict a held-out motion's efforts with an RMS error below the noise (the tripod, 124 base
  parameters from 800 samples: 1.5 times; the nominal model is tens of noise levels off);
- report the parameters the efforts cannot see (not invent them): they are listed, and changing
  them changes no effort.

The same holds for a robot with a joint coupling: the UFACTORY xArm7 gripper of MuJoCo
Menagerie (two four-bar fingers, their drivers coupled by a joint equality; exported back to
MuJoCo as one), its actuator on the driver joint and its joints' ``frictionloss`` (a MuJoCo
constraint force with no counterpart in pkdyn) removed.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from support.dynamics_truth import mujoco_efforts, multisine, perturbed

import pkdyn
from pkdyn.identification import Measurements, identify, parameter_set, predict_efforts
from pkdyn.identification.motion import MotionSampler
from pkdyn.identification.regressor import ClosedLoopRegressor

mujoco = pytest.importorskip("mujoco")

CASES = {  # family: (excursion of the actuators [rad or m], samples, held-out error / noise)
    "delta": (0.3, 1000, 1.0),
    "gough_stewart": (0.03, 1000, 1.0),
    "five_bar": (0.3, 600, 1.0),
    "tripod": (0.01, 800, 1.5),  # 124 base parameters from 800 samples (observed 0.44-1.35)
}


@pytest.mark.parametrize("name", list(CASES))
def test_recovers_a_perturbed_robot_from_mujoco_efforts(name):
    amp, samples, bound = CASES[name]
    nominal = pkdyn.load(name, geometry=False)
    rng = np.random.default_rng(7)
    truth = perturbed(nominal, rng)
    t, qa, qd, qdd = multisine(nominal, samples, 5e-3, amp, 1)
    tau = mujoco_efforts(truth, t, qa, qd, qdd)
    ps_true = parameter_set(truth)
    # the other engine agrees with the closed-loop regressor of the truth (observed 4e-14 ..
    # 2e-7: the Delta's bars spin as the truth's dynamics say, the regressor least-norm)
    tau_reg = predict_efforts(truth, ps_true, ps_true.nominal, t, qa, qd, qdd)
    assert np.abs(tau - tau_reg).max() < 1e-6 * np.abs(tau).max()
    noise = 0.01 * np.sqrt(np.mean(tau**2, axis=0))
    res = identify(
        nominal, Measurements(t, qa, qd, qdd, tau + noise * rng.standard_normal(tau.shape))
    )
    sel = res.parameters.identified
    z = (res.estimate.theta - res.base.K @ ps_true.nominal[sel]) / res.estimate.std
    assert np.abs(z).max() < 4.5 and np.sqrt(np.mean(z**2)) < 2.0, z
    np.testing.assert_allclose(res.estimate.sigma, noise, rtol=0.15)
    t2, qa2, qd2, qdd2 = multisine(nominal, samples // 3, 5e-3, amp, 2)
    tau2 = mujoco_efforts(truth, t2, qa2, qd2, qdd2)
    err = np.sqrt(np.mean((res.predict(t2, qa2, qd2, qdd2) - tau2) ** 2, axis=0))
    ps0 = parameter_set(nominal)
    err0 = np.sqrt(
        np.mean(
            (predict_efforts(nominal, ps0, ps0.nominal, t2, qa2, qd2, qdd2) - tau2) ** 2, axis=0
        )
    )
    assert np.all(err < bound * noise), (err / noise, err0 / noise)
    assert np.all(err0 > 5 * noise)
    # reported, not invented: the parameters without effect are listed, and have none
    ps = res.parameters
    assert len(res.base.no_effect) >= {"five_bar": 30, "delta": 30}.get(name, 1)
    unseen = [ps.index(p) for p in res.base.no_effect]
    moved = res.theta.copy()
    moved[unseen] *= 1.5
    moved[unseen] += 0.1
    b2 = MotionSampler(nominal).batch(t2[:50], qa2[:50], qd2[:50], qdd2[:50])
    W, known = ClosedLoopRegressor(nominal, ps).full(b2)
    np.testing.assert_allclose(W @ moved, W @ res.theta, rtol=0, atol=1e-9 * np.abs(tau2).max())


XARM_HAND = Path(__file__).parent / "data" / "public" / "menagerie_xarm7_hand" / "hand.xml"


@pytest.fixture(scope="module")
def xarm_gripper(tmp_path_factory):
    text = XARM_HAND.read_text().replace('tendon="split"', 'joint="left_driver_joint"')
    d = tmp_path_factory.mktemp("xarm")
    (d / "gripper.xml").write_text(text.replace('frictionloss="1"', 'frictionloss="0"'))
    (d / "gripper.yaml").write_text(
        "platform: {frame: left_finger, xyz: [0.0, -0.024, 0.041], task: y}\n"
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the tendon's other actuator references: left out
        return pkdyn.load(d / "gripper.xml")


def test_recovers_a_perturbed_coupled_gripper_from_mujoco_efforts(xarm_gripper):
    nominal = xarm_gripper
    assert len(nominal.couplings) == 1 and nominal.closure_set.n_rigid == 6
    rng = np.random.default_rng(7)
    truth = perturbed(nominal, rng)
    mid = np.array([0.4])  # mid-stroke (0 .. 0.85 rad)
    t, qa, qd, qdd = multisine(nominal, 600, 5e-3, 0.15, 1, center=mid)
    tau = mujoco_efforts(truth, t, qa, qd, qdd)
    ps_true = parameter_set(truth)
    tau_reg = predict_efforts(truth, ps_true, ps_true.nominal, t, qa, qd, qdd)
    assert np.abs(tau - tau_reg).max() < 1e-9 * np.abs(tau).max()  # observed 1e-12
    noise = 0.01 * np.sqrt(np.mean(tau**2, axis=0))
    res = identify(
        nominal, Measurements(t, qa, qd, qdd, tau + noise * rng.standard_normal(tau.shape))
    )
    sel = res.parameters.identified
    z = (res.estimate.theta - res.base.K @ ps_true.nominal[sel]) / res.estimate.std
    assert np.abs(z).max() < 4.5 and np.sqrt(np.mean(z**2)) < 2.0, z  # observed 2.1, 1.5
    np.testing.assert_allclose(res.estimate.sigma, noise, rtol=0.15)
    # the coupling groups the two fingers: their inertia about the common axis is one base
    # parameter with the rotor inertia
    assert any(
        "left_outer_knuckle.Ixx" in f and "right_outer_knuckle.Ixx" in f and "rotor" in f
        for f in res.base.formulas()
    )
    t2, qa2, qd2, qdd2 = multisine(nominal, 200, 5e-3, 0.15, 2, center=mid)
    tau2 = mujoco_efforts(truth, t2, qa2, qd2, qdd2)
    err = np.sqrt(np.mean((res.predict(t2, qa2, qd2, qdd2) - tau2) ** 2, axis=0))
    ps0 = parameter_set(nominal)
    tau0 = predict_efforts(nominal, ps0, ps0.nominal, t2, qa2, qd2, qdd2)
    err0 = np.sqrt(np.mean((tau0 - tau2) ** 2, axis=0))
    assert np.all(err < noise) and np.all(err0 > 2 * noise), (err / noise, err0 / noise)
    unseen = [ps0.index(p) for p in res.base.no_effect]
    assert len(unseen) >= 30  # a translating finger's rotational inertia, among others
    moved = res.theta.copy()
    moved[unseen] = 1.5 * moved[unseen] + 0.1
    b2 = MotionSampler(nominal, None).batch(t2[:50], qa2[:50], qd2[:50], qdd2[:50])
    W, _ = ClosedLoopRegressor(nominal, ps0).full(b2)
    np.testing.assert_allclose(W @ moved, W @ res.theta, rtol=0, atol=1e-9 * np.abs(tau2).max())
