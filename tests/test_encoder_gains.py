"""Encoder gains from the command line (issue 27 item 1: "the calibrated description loads like
any other and its forward model reproduces the measurements").

The rule: ``--qa`` is always the actuated joint coordinates; ``--readings`` are the encoders'
readings, and the description's ``<pkdyn:encoder gain>`` turns them into joint coordinates
(coordinate = gain x reading). ``fk`` and ``ik`` report the readings beside ``qa`` when the robot
has gains, and ``--qa`` on such a robot prints a one-line note. ``calibrate`` reads readings in its
``qa_<actuator>`` columns (a robot calibrated before has its gains applied to them).

Truth: a Delta whose description is edited (dimensions within +-2 mm, +-0.5 deg) and whose encoders
read 0.3-0.5 % off; its forward geometry at (1 + gain) x reading, plus 10 um noise, is the
measurement; ``pkdyn calibrate --gains`` writes a URDF; ``pkdyn fk --readings`` on it reproduces
held-out measured positions within the noise, and ``--qa`` with the same numbers does not.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from support.calibration_truth import readings as _readings
from support.urdf_edit import family_xml, load_like, where_of, with_twists

import pkdyn
from pkdyn.calibration import Measurements, calibrate, write_csv
from pkdyn.cli import main
from pkdyn.precision.parameters import family_shortcuts

SIGMA = 1e-5


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    robot = pkdyn.load("delta", geometry=False)
    model = family_shortcuts(robot, gains=True)
    rng = np.random.default_rng(3)
    p_true = rng.uniform(-1, 1, model.size) * model.tolerances(2e-3, np.deg2rad(0.5), 0.0)
    gains = np.array([4e-3, -5e-3, 3e-3])  # the encoders read 0.3-0.5 % off
    xi = model.twists(p_true)
    twists = {where_of(pl): x for pl, x in zip(model.placements, xi, strict=True) if np.any(x)}
    truth = load_like(with_twists(family_xml(robot), twists), robot)
    readings = _readings(robot, 60, seed=4)
    exact = np.array(
        [
            pkdyn.forward_geometry(
                truth, (1.0 + gains) * r, q_init=truth.q_home, check_limits=False
            ).placement.translation
            for r in readings
        ]
    )
    measured = exact + rng.normal(0.0, SIGMA, exact.shape)
    d = tmp_path_factory.mktemp("gains")
    csv, out = d / "m.csv", d / "cal.urdf"
    write_csv(csv, robot, Measurements("position", readings[:45], measured[:45]))
    argv = ["calibrate", "delta", "--measurements", str(csv), "-o", str(out), "--gains"]
    assert main([*argv, "--noise", str(SIGMA), "--holdout", "0", "--json"]) == 0
    return robot, gains, readings, exact, measured, out


def _fk(capsys, argv):
    assert main([*argv, "--json"]) == 0
    cap = capsys.readouterr()
    return json.loads(cap.out), cap.err


def test_fk_on_readings_reproduces_held_out_measurements(calibrated, capsys):
    robot, gains, readings, exact, measured, out = calibrated
    loaded = pkdyn.load(out, geometry=False)
    g = np.array([a.encoder_gain for a in loaded.actuators])
    assert np.all(g != 1.0)  # the gains are identified and written (weakly beside the
    # offsets with position measurements: the prediction, not each gain, is what is checked)
    worst_readings = worst_qa = 0.0
    for r, x in zip(readings[45:], exact[45:], strict=True):
        got, err = _fk(capsys, ["fk", str(out), "--readings", *map(repr, r.tolist())])
        assert err == ""
        worst_readings = max(worst_readings, float(np.linalg.norm(np.array(got["position"]) - x)))
        np.testing.assert_allclose(got["readings"], r, atol=1e-12)
        np.testing.assert_allclose(got["qa"], g * r, atol=1e-12)
        wrong, note = _fk(capsys, ["fk", str(out), "--qa", *map(repr, r.tolist())])
        assert note.count("\n") == 1 and "encoder gains" in note and "--readings" in note
        worst_qa = max(worst_qa, float(np.linalg.norm(np.array(wrong["position"]) - x)))
    assert worst_readings < 5 * SIGMA  # within the noise, on poses the calibration never saw
    assert worst_qa > 30 * SIGMA  # the readings taken as coordinates: a wrong pose


def test_ik_reports_the_readings_and_fk_inverts_it(calibrated, capsys):
    robot, gains, readings, exact, measured, out = calibrated
    got, _ = _fk(capsys, ["ik", str(out), "--pose", *map(repr, exact[50].tolist())])
    back, _ = _fk(capsys, ["fk", str(out), "--readings", *map(repr, got["readings"])])
    np.testing.assert_allclose(back["position"], exact[50], atol=1e-9)
    assert main(["ik", str(out), "--pose", *map(repr, exact[50].tolist())]) == 0
    assert "encoder readings" in capsys.readouterr().out


def test_recalibrating_a_calibrated_robot_applies_its_gains(calibrated):
    """The calibrated URDF as the nominal robot: its gains turn the readings into coordinates,
    so its errors at the measurements are already at the noise level."""
    robot, gains, readings, exact, measured, out = calibrated
    loaded = pkdyn.load(out, geometry=False)
    m = Measurements("position", readings, measured)
    res = calibrate(loaded, m, "placements", noise=SIGMA, holdout=0.0, max_iter=1, accept=True)
    assert res.before.position_rms < 3 * SIGMA


def test_readings_count_and_values_are_checked(calibrated, capsys):
    out = str(calibrated[-1])
    for argv, needle in (
        (["fk", out, "--readings", "0.1", "0.2"], "expected 3 values"),
        (["fk", out, "--readings", "nan", "0", "0"], "finite"),
        (["fk", out, "--readings", "1e308", "0", "0"], "beyond any plausible"),
    ):
        assert main(argv) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert err[-1].startswith("pkdyn: error:") and needle in err[-1], err
        assert len([e for e in err if e.startswith("pkdyn: error")]) == 1
    with pytest.raises(SystemExit) as exit_:
        main(["fk", out, "--readings", "0", "0", "0", "--qa", "0", "0", "0"])
    assert exit_.value.code == 2 and "not allowed with" in capsys.readouterr().err
