"""Calibrations that say when not to trust them (issue 35 item 2), and the likely cause.

Truth: a Delta (and a Gough-Stewart for orientations) with errors within +-2 mm and +-0.5 deg
written into its text; its forward geometry at readings plus 10 um noise is the measurement.
The measurements are then spoiled the ways users spoil them: centimetres or millimetres, x and y
swapped, orientations in degrees, readings in degrees, or the measurements of another Delta
(``la`` 0.3 m and ``lb`` 0.8 m) against the default one. Each calibration must refuse (a
:class:`pkdyn.CalibrationError`, or an :class:`pkdyn.InvalidInputError` before the fit) and name
the cause; with ``accept`` it returns the result with its reasons; the command line exits 1
without writing the model unless ``--accept``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from support.calibration_truth import draw, measure, readings, truth_of

import pkdyn
from pkdyn.calibration import Measurements, calibrate, write_csv
from pkdyn.cli import main
from pkdyn.exceptions import CalibrationError, InvalidInputError
from pkdyn.precision.parameters import family_shortcuts

SIGMA = 1e-5


@pytest.fixture(scope="module")
def delta():
    robot = pkdyn.load("delta", geometry=False)
    model = family_shortcuts(robot)
    rng = np.random.default_rng(7)
    truth, _ = truth_of(robot, model, draw(model, rng))
    m, _ = measure(truth, readings(robot, 50, seed=1), "position", SIGMA, rng)
    return robot, model, m


def _spoiled(m, position=None, qa=None):
    return Measurements(
        "position", m.qa if qa is None else qa, m.position if position is None else position
    )


def _refused(robot, model, m, *needles):
    with pytest.raises(CalibrationError) as err:
        calibrate(robot, m, model, noise=SIGMA)
    text = str(err.value)
    assert "\n" not in text and "not trusted" in text, text
    for needle in needles:
        assert needle in text, text
    return err.value


def test_a_good_calibration_is_trusted(delta):
    robot, model, m = delta
    res = calibrate(robot, m, model, noise=SIGMA)
    assert res.trusted and res.reasons == () and res.cause == ""
    assert res.to_json()["trusted"] is True and "NOT TRUSTED" not in res.table()


def test_centimetres(delta):
    robot, model, m = delta
    err = _refused(
        robot, model, _spoiled(m, 100.0 * m.position), "times the stated noise", "centimetres"
    )
    assert err.result is not None and not err.result.trusted  # the calibration, to inspect
    res = calibrate(robot, _spoiled(m, 100.0 * m.position), model, noise=SIGMA, accept=True)
    assert not res.trusted and "centimetres" in res.cause
    assert res.to_json()["likely_cause"] == res.cause and "NOT TRUSTED" in res.table()


def test_millimetres_are_refused_before_the_fit(delta):
    robot, model, m = delta
    with pytest.raises(InvalidInputError, match="more than 100 times its size.*millimetres"):
        calibrate(robot, _spoiled(m, 1000.0 * m.position), model, noise=SIGMA)


def test_x_and_y_swapped(delta):
    robot, model, m = delta
    _refused(robot, model, _spoiled(m, m.position[:, [1, 0, 2]]), "read as y, x, z")


def test_readings_in_degrees_are_refused_before_the_fit(delta):
    robot, model, m = delta
    with pytest.raises(InvalidInputError, match="cannot be assembled.*look like degrees"):
        calibrate(robot, _spoiled(m, qa=np.rad2deg(m.qa)), model, noise=SIGMA)


def test_measurements_of_another_delta(delta):
    """The issue's case: a 0.3/0.8 m Delta measured, the default one calibrated: la and lb
    would grow by half and more than double."""
    robot, model, _ = delta
    big = pkdyn.load("delta", geometry=False, la=0.3, lb=0.8)
    rng = np.random.default_rng(3)
    qa = []
    while len(qa) < 40:
        q = big.q_home[big.actuated_q] + 0.3 * rng.uniform(-1, 1, 3)
        try:
            pkdyn.forward_geometry(big, q)
            pkdyn.forward_geometry(robot, q)
        except pkdyn.PkdynError:
            continue
        qa.append(q)
    m, _ = measure(big, np.array(qa), "position", SIGMA, rng)
    err = _refused(robot, model, m, "corrections beyond 10 times the tolerances", "nominal robot")
    assert any(n in " ".join(err.reasons) for n in ("lb1", "lb2", "lb3"))


def test_orientations_in_degrees():
    robot = pkdyn.load("gough_stewart", geometry=False)
    model = family_shortcuts(robot)
    rng = np.random.default_rng(11)
    truth, _ = truth_of(robot, model, draw(model, rng))
    m, _ = measure(truth, readings(robot, 40, seed=2, spread=0.05), "pose", SIGMA, rng, 2e-5)
    assert calibrate(robot, m, model, noise=(SIGMA, 2e-5)).trusted
    spoiled = Measurements("pose", m.qa, m.position, np.rad2deg(m.rpy))
    with pytest.raises(CalibrationError, match="orientations look like degrees"):
        calibrate(robot, spoiled, model, noise=(SIGMA, 2e-5))


def test_tight_tolerances_flag_the_corrections(delta):
    robot, model, m = delta
    with pytest.raises(CalibrationError, match="corrections beyond 10 times the tolerances"):
        calibrate(robot, m, model, noise=SIGMA, tolerance=(1e-5, 1e-5))
    res = calibrate(robot, m, model, noise=SIGMA, tolerance=(1e-5, 1e-5), accept=True)
    assert res.to_json()["parameters"][0]["tolerance"] == 1e-5
    with pytest.raises(InvalidInputError, match="tolerance"):
        calibrate(robot, m, model, tolerance=(1.0, -1.0))


def test_cli_refuses_writes_with_accept_and_validates_on_a_file(delta, tmp_path, capsys):
    robot, model, m = delta
    good, held, bad = tmp_path / "m.csv", tmp_path / "v.csv", tmp_path / "cm.csv"
    write_csv(good, robot, m.subset(np.arange(40)))
    write_csv(held, robot, m.subset(np.arange(40, 50)))
    write_csv(bad, robot, _spoiled(m, 100.0 * m.position))
    out = tmp_path / "cal.urdf"
    base = ["calibrate", "delta", "--noise", str(SIGMA), "-o", str(out), "--measurements"]
    assert main([*base, str(bad)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("pkdyn: error:") and "\n" not in err and "centimetres" in err
    assert not out.exists()
    assert main([*base, str(bad), "--accept"]) == 0
    text = capsys.readouterr().out
    assert "NOT TRUSTED" in text and "written although not trusted" in text and out.exists()
    png = tmp_path / "res.png"
    argv = [*base, str(good), "--validation", str(held), "--plot", str(png), "--json"]
    assert main(argv) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["trusted"] and got["poses"] == {"calibration": 40, "validation": 10}
    assert got["validation_after"]["position_rms"] < 2 * np.sqrt(3) * SIGMA
    assert png.stat().st_size > 1000
    assert main([*base, str(good), "--tolerance", "1e-6", "1e-6"]) == 1
    assert "corrections beyond" in capsys.readouterr().err


def test_the_result_protocol_and_the_old_spellings(delta, tmp_path):
    from pkdyn.calibration.writer import joint_coordinates, write_calibrated

    robot, model, m = delta
    res = calibrate(robot, m, model, noise=SIGMA)
    json.dumps(res.to_json(), allow_nan=False)
    json.dumps(res.identifiability.to_json(), allow_nan=False)
    text = res.table()
    assert " um " in text and " mm" in text and "rad" in text  # units on the figures
    assert "acts as" in res.identifiability.table()
    fig = res.plot(tmp_path / "r.svg")
    assert (tmp_path / "r.svg").exists() and len(fig.axes) == 6  # x, y, z before and after
    with pytest.warns(DeprecationWarning, match="to_json"):
        assert res.as_dict()["trusted"]
    with pytest.warns(DeprecationWarning, match="write_urdf"):
        write_calibrated(res, tmp_path / "c.urdf")
    with pytest.warns(DeprecationWarning, match="joint_coordinates"):
        joint_coordinates(robot, m.qa)
    assert (tmp_path / "c.urdf").read_text() == res.urdf()


@pytest.mark.parametrize(
    ("option", "culprit"),
    [
        ({"accept": "yes"}, "accept"),
        ({"residual_limit": float("nan")}, "residual_limit"),
        ({"correction_limit": -1.0}, "correction_limit"),
        ({"tolerance": "x"}, "tolerance"),
        ({"tolerance": (1e-3, 1e-3, 1e-3, 1e-3)}, "tolerance"),
    ],
)
def test_the_trust_options_are_checked(delta, option, culprit):
    robot, model, m = delta
    with pytest.raises(InvalidInputError) as err:
        calibrate(robot, m, model, noise=SIGMA, **option)
    assert culprit in str(err.value) and "\n" not in str(err.value)
