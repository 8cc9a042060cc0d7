"""Identification that says what the motion cannot show (issue 35 item 2).

- positions beyond the joints' limits (the five-bar's actuators given in degrees: its home is at
  147.6 deg) are refused before any fit, naming the line, the column and the likely unit;
- readings the robot cannot be assembled at (a Gough-Stewart driven to leg lengths that do not
  close) are refused, naming the line;
- an actuator that moves 1 urad leaves what only it excites unseen: those base parameters are
  flagged (``excited: false``, held at their nominal values), not given the small relative
  standard deviation of a wild estimate, and the written description keeps plausible values
  (the issue: a viscous friction of 7.5e7);
- the samples shared by two worker processes (:func:`pkdyn.workers.fork_map`) give the
  estimate one process gives.

The efforts are those of the robot's own closed-loop regressor (the MuJoCo cross-check of that
model is tests/test_identification_truth.py) with noise.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from support.dynamics_truth import multisine

import pkdyn
from pkdyn.cli import main
from pkdyn.dynamics.actuation import with_drives
from pkdyn.exceptions import InvalidInputError
from pkdyn.identification import Measurements, identify, parameter_set, predict_efforts
from pkdyn.tables import write_table


def _multisine(robot, samples, amp, seed):
    """A 4-harmonic multi-sine around home (per-actuator amplitudes) at 200 Hz."""
    return multisine(robot, samples, 5e-3, np.asarray(amp, dtype=float), seed, harmonics=4)


def _recorded(robot, t, qa, qd, qdd, noise=1e-3, seed=2):
    ps = parameter_set(robot)
    tau = predict_efforts(robot, ps, ps.nominal, t, qa, qd, qdd)
    rng = np.random.default_rng(seed)
    return Measurements(t, qa, qd, qdd, tau + noise * rng.standard_normal(tau.shape)), tau


@pytest.fixture(scope="module")
def five_bar():
    return pkdyn.load("five_bar", geometry=False)


def test_positions_in_degrees_are_refused_naming_the_line(five_bar, tmp_path, capsys):
    t, qa, qd, qdd = _multisine(five_bar, 200, 0.2, 1)
    data, tau = _recorded(five_bar, t, qa, qd, qdd)
    deg = Measurements(t, np.rad2deg(qa), np.rad2deg(qd), np.rad2deg(qdd), data.tau)
    with pytest.raises(InvalidInputError, match=r"sample 0, column qa_motor1: 14\d.\d+ rad lies"):
        identify(five_bar, deg)
    names = five_bar.actuator_names
    cols = ["t", *(f"qa_{n}" for n in names), *(f"tau_{n}" for n in names)]
    path = tmp_path / "deg.csv"
    write_table(path, cols, np.column_stack([t, np.rad2deg(qa), tau]))
    assert (
        main(["identify", "five_bar", "--measurements", str(path), "-o", str(tmp_path / "x")]) == 1
    )
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "line 2, column qa_motor1" in err
    assert (
        "beyond the limits [-3.14159, 3.14159] rad of joint" in err and "look like degrees" in err
    )


def test_readings_that_do_not_close_are_refused_naming_the_line():
    robot = pkdyn.load("gough_stewart", geometry=False)
    home = robot.q_home[robot.actuated_q]
    far = np.array([0.53, 0.53, 0.53, 0.73, 0.73, 0.73])  # within the strokes; no pose
    s = np.linspace(0.0, 1.0, 400)[:, None]
    qa = home + s * (far - home)
    t = s[:, 0] * 4.0
    data = Measurements(t, qa, None, None, np.zeros_like(qa))
    with pytest.raises(InvalidInputError, match=r"sample \d+ \(t = .* s\): the readings .* cannot"):
        identify(robot, data)


def test_an_actuator_that_barely_moves_leaves_its_parameters_flagged(tmp_path):
    robot = with_drives(
        pkdyn.load("delta", geometry=False),
        rotor_inertia=np.full(3, 1e-5),
        viscous=np.full(3, 3e-4),
        coulomb=np.full(3, 0.02),
    )
    t, qa, qd, qdd = _multisine(robot, 1200, [0.3, 0.3, 1e-6], 5)  # motor3: 1 urad
    data, _ = _recorded(robot, t, qa, qd, qdd)
    res = identify(robot, data)
    formulas = res.base.formulas()
    flagged = [formulas[k] for k in np.flatnonzero(~res.excited)]
    assert "motor3.viscous" in flagged  # only motor3's speed shows it: 1 urad/s
    k = formulas.index("motor3.viscous")
    assert res.relative_std[k] > 10.0  # its std is not small: beyond ten times its size
    assert res.estimate.theta[k] == pytest.approx(3e-4)  # held at its nominal value
    assert res.drives()["motor3"]["viscous"] == pytest.approx(3e-4, rel=0.1)  # not 7.5e7
    for name in ("motor1.viscous", "motor2.viscous"):  # the moving motors': seen
        assert res.excited[formulas.index(name)]
    got = res.to_json()
    json.dumps(got, allow_nan=False)
    row = next(b for b in got["base_parameters"] if b["formula"] == "motor3.viscous")
    assert row["excited"] is False and row["excitation"] < 0.1 and row["unit"] == "N m s/rad"
    assert "motor3.viscous" in got["unexcited"]
    assert "not excited" in res.table()


def test_a_rich_motion_excites_every_base_parameter_and_the_fit_is_drawn(five_bar, tmp_path):
    t, qa, qd, qdd = _multisine(five_bar, 1200, 0.3, 5)
    data, _ = _recorded(five_bar, t, qa, qd, qdd)
    res = identify(five_bar, data)
    assert np.all(res.excited) and np.all(res.estimate.excitation > 1.0)
    assert " N m" in res.table()
    fig = res.plot(tmp_path / "fit.png")
    assert (tmp_path / "fit.png").stat().st_size > 1000 and len(fig.axes) == 4
    assert res.fit is not None and res.fit.t.size == t.size  # (under FIT_SAMPLES: all kept)
    rms = np.sqrt(np.mean((res.fit.measured - res.fit.physical) ** 2))
    assert rms == pytest.approx(1e-3, rel=0.1)  # the residual is the noise
    with pytest.warns(DeprecationWarning, match="to_json"):
        assert res.as_json()["samples"] == t.size


def test_two_worker_processes_give_the_one_process_estimate(five_bar):
    from pkdyn.identification.motion import BATCH

    t, qa, qd, qdd = _multisine(five_bar, 8 * BATCH + 17, 0.3, 9)
    data, _ = _recorded(five_bar, t, qa, qd, qdd)
    one = identify(five_bar, data, workers=1)
    two = identify(five_bar, data, workers=2)
    scale = np.abs(one.estimate.theta).max()
    np.testing.assert_allclose(two.estimate.theta, one.estimate.theta, atol=1e-9 * scale)
    np.testing.assert_array_equal(two.excited, one.excited)


def _square(shared, job):
    if job == "boom":
        raise InvalidInputError("job", "refused in the worker")
    if job == "die":
        os._exit(3)
    return shared * job


def test_fork_map_orders_results_and_raises_what_a_worker_raised():
    from pkdyn.workers import can_fork, fork_map

    if not can_fork():
        pytest.skip("no fork here")
    assert fork_map(_square, 3, [1, 2, 5]) == [3, 6, 15]
    with pytest.raises(InvalidInputError, match="refused in the worker"):
        fork_map(_square, 3, [1, "boom"])
    with pytest.raises(RuntimeError, match="ended without a result"):
        fork_map(_square, 3, ["die"])


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_the_motion_is_assembled_relative_to_the_robots_size(scale):
    """The closures of the recorded motion are solved to 1e-10 of the robot's size, whatever it.

    A five-bar of millimetres, of decimetres and of a hundred metres follows the same actuator
    motion; its closure residual, divided by ``min(1 m, its size)``, stays below 1e-10 (an
    absolute 1e-10 m left the millimetre robot assembled to 2e-8 of its size).
    """
    from pkdyn.identification.motion import ASSEMBLY_RTOL, MotionSampler

    sizes = {"d": 0.2, "l1": 0.2, "l2": 0.3, "link_radius": 0.01}
    robot = pkdyn.load("five_bar", geometry=False, **{k: v * scale for k, v in sizes.items()})
    t = np.linspace(0.0, 1.0, 101)
    wave = np.column_stack([np.sin(2 * np.pi * t), np.sin(4 * np.pi * t)])
    qa = robot.q_home[robot.actuated_q] + 0.2 * wave
    Q, _ = MotionSampler(robot).configurations(qa, t, qd=np.gradient(qa, t, axis=0))
    gap = max(float(np.abs(robot.constraints.residual(robot.data, q)).max()) for q in Q)
    assert gap <= ASSEMBLY_RTOL * min(1.0, robot.length_scale)
    # the same angles at every size (the mechanism is similar): the motion does not depend on it
    reference = MotionSampler(pkdyn.load("five_bar", geometry=False)).configurations(qa, t)[0]
    np.testing.assert_allclose(Q, reference, rtol=0.0, atol=1e-8)
