"""Calibrate, then identify, then predict: one readings rule from the measurements to the efforts.

Truth: a Delta whose description is edited as text (Clavel's dimensions within +-2 mm and
+-0.5 deg) and whose encoders read 2-3 % off (joint coordinate = gain x reading), with its
masses and inertias scaled by 10-30 % and drives added; its efforts along a multi-sine come from
MuJoCo (:mod:`support.dynamics_truth`), with 0.1 % noise; everything it records is *readings*.

1. ``calibrate`` (position measurements at readings, 10 um noise, gains identified) writes a
   calibrated description with ``<pkdyn:encoder gain>``;
2. ``identify`` on that description, from the motion recorded on the true robot (readings,
   their rates and accelerations, and the efforts);
3. the identified model predicts another recorded motion: its efforts within the noise.

The same chain with the readings taken as joint coordinates (the encoder gains ignored, as
``identify`` did before the readings rule) predicts three to five times the noise: the test
would fail on that code.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from support.calibration_truth import readings
from support.dynamics_truth import mujoco_efforts, multisine, perturbed
from support.urdf_edit import family_xml, load_like, where_of, with_twists

import pkdyn
from pkdyn.calibration import Measurements as Poses
from pkdyn.calibration import calibrate
from pkdyn.identification import Measurements, identify
from pkdyn.precision.parameters import family_shortcuts

pytest.importorskip("mujoco")

GAIN = np.array([1.03, 0.975, 1.02])  # the true joint coordinate per unit of reading
NOISE = 1e-3  # of the RMS effort


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    nominal = pkdyn.load("delta", geometry=False)
    model = family_shortcuts(nominal)
    rng = np.random.default_rng(5)
    p = rng.uniform(-1, 1, model.size) * model.tolerances(2e-3, np.deg2rad(0.5))
    xi = model.twists(p)
    twists = {where_of(pl): x for pl, x in zip(model.placements, xi, strict=True) if np.any(x)}
    geometry = load_like(with_twists(family_xml(nominal), twists), nominal)
    # 1. calibration: positions measured at readings
    R = readings(nominal, 50, seed=1) / GAIN
    P = np.array(
        [
            pkdyn.forward_geometry(
                geometry, GAIN * r, q_init=geometry.q_home, check_limits=False
            ).placement.translation
            for r in R
        ]
    )
    P += rng.normal(0.0, 1e-5, P.shape)
    cal = calibrate(nominal, Poses("position", R, P), family_shortcuts(nominal, gains=True), 1e-5)
    path = tmp_path_factory.mktemp("chain") / "calibrated.urdf"
    cal.write_urdf(path)
    calibrated = pkdyn.load(path, geometry=False)
    # 2. the motion recorded on the true robot: readings and efforts
    truth = perturbed(geometry, np.random.default_rng(7))
    t, q, qd, qdd = multisine(geometry, 1000, 5e-3, 0.3, 1)
    tau = mujoco_efforts(truth, t, q, qd, qdd)
    noise = NOISE * np.sqrt(np.mean(tau**2, axis=0))
    recorded = Measurements(
        t, q / GAIN, qd / GAIN, qdd / GAIN, tau + noise * rng.standard_normal(tau.shape)
    )
    t2, q2, qd2, qdd2 = multisine(geometry, 333, 5e-3, 0.3, 2)
    other = (t2, q2 / GAIN, qd2 / GAIN, qdd2 / GAIN)
    return cal, calibrated, recorded, other, mujoco_efforts(truth, t2, q2, qd2, qdd2), noise


def test_the_calibration_is_trusted_and_writes_the_gains(chain):
    cal, calibrated, *_ = chain
    assert cal.trusted and cal.validation_after.position_rms < 3e-5
    np.testing.assert_allclose(calibrated.encoder_gains, 1.0 + cal.gains)
    assert np.all(np.abs(calibrated.encoder_gains - GAIN) < 0.01)  # 2-3 % found to < 1 %


def test_identify_on_the_calibrated_description_predicts_within_the_noise(chain):
    cal, calibrated, recorded, other, tau2, noise = chain
    res = identify(calibrated, recorded)
    err = np.sqrt(np.mean((res.predict(*other) - tau2) ** 2, axis=0))
    assert np.all(err < noise), err / noise  # observed 0.3-0.6
    # the readings taken as joint coordinates (the gains ignored): several times the noise
    acts = tuple(dataclasses.replace(a, encoder_gain=1.0) for a in calibrated.actuators)
    desc = dataclasses.replace(calibrated.description, actuators=acts)
    ignored = dataclasses.replace(calibrated, actuators=acts, description=desc)
    res0 = identify(ignored, recorded)
    err0 = np.sqrt(np.mean((res0.predict(*other) - tau2) ** 2, axis=0))
    assert np.all(err0 > 2 * noise), err0 / noise  # observed 3.1-4.7
