"""Dynamic identification: the closed-loop regressor against the inverse dynamics on every
library family, the parameter maps against Pinocchio and finite differences, the base
parameters, filtering, the written description, the CLI and its refusals of bad input.

Recovery from an independent truth (MuJoCo) is tests/test_identification_truth.py.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from support.dynamics_truth import multisine

import pkdyn
from pkdyn.cli import main
from pkdyn.dynamics.actuation import actuation, motor_efforts, with_drives
from pkdyn.exceptions import InvalidInputError
from pkdyn.identification import Measurements, identify, parameter_set, predict_efforts
from pkdyn.identification.filtering import derivatives
from pkdyn.identification.motion import MotionSampler
from pkdyn.identification.parameters import placement_map
from pkdyn.identification.physical import (
    from_log_cholesky,
    log_cholesky_jacobian,
    pseudo_inertia,
    to_log_cholesky,
)
from pkdyn.identification.regressor import ClosedLoopRegressor
from solvers import InverseDynamics, numerics

FAMILIES = [
    ("delta", {}),
    ("delta", {"bar_joint": "universal"}),
    ("gough_stewart", {}),
    ("five_bar", {}),
    ("tripod", {}),
    ("planar_3rrr", {}),
    ("four_bar_knee", {}),
    ("parallel_ankle", {}),
]


def _multisine(robot, T, dt, amp, seed, harmonics=4, f0=0.25):
    return multisine(robot, len(np.arange(0.0, T, dt)), dt, amp, seed, harmonics, f0)


def _amplitude(name):
    return {"gough_stewart": 0.01, "tripod": 0.005}.get(name, 0.2)


@pytest.mark.parametrize(
    ("name", "kw"), FAMILIES, ids=[f"{n}{'-u' if k else ''}" for n, k in FAMILIES]
)
def test_regressor_matches_inverse_dynamics(name, kw):
    """Y theta + known = N tau_motor of pkdyn's inverse dynamics and drive model, to 1e-9."""
    robot = with_drives(
        pkdyn.load(name, geometry=False, **kw), rotor_inertia=2e-5, viscous=3e-4, coulomb=0.02
    )
    n_a = len(robot.actuators)
    t, qa, qd, qdd = _multisine(robot, 0.4, 1e-2, _amplitude(name), 3)
    b = MotionSampler(robot).batch(t, qa, qd, qdd)
    m, d = robot.model, robot.model.createData()
    S = actuation(robot).matrix(robot.nv)
    for i in range(t.size):  # internal mobilities (bar spin) follow the dynamics, for the ID
        Nm = numerics.null_space(np.vstack([b.J[i], S]), 1e-9, 1.0)
        if Nm.shape[1]:
            M = pin.crba(m, d, b.q[i])
            M = np.triu(M) + np.triu(M, 1).T
            h = pin.rnea(m, d, b.q[i], b.v[i], b.a[i])
            b.a[i] -= Nm @ np.linalg.solve(Nm.T @ M @ Nm, Nm.T @ h)
    ps = parameter_set(robot)
    W, known = ClosedLoopRegressor(robot, ps).full(b)
    tau = W @ ps.nominal + known
    inv = InverseDynamics(m, list(robot.constraint_models), actuation(robot))
    ref = inv.trajectory(b.q, b.v, b.a, check_tol=1e-7).tau
    N = np.array([a.reduction for a in robot.actuators])
    ref = N * motor_efforts(robot, ref, b.v[:, robot.actuated_v])
    assert W.shape == (t.size, n_a, ps.p)
    # observed 5e-16 .. 3e-12
    assert np.abs(tau - ref).max() <= 1e-9 * np.abs(ref).max()


def test_placement_map_is_pinocchio_action():
    rng = np.random.default_rng(0)
    for _ in range(5):
        I = pin.Inertia.Random()
        M = pin.SE3.Random()
        mine = placement_map(M) @ I.toDynamicParameters()
        np.testing.assert_allclose(mine, M.act(I).toDynamicParameters(), atol=1e-12, rtol=0)
    assert rng is not None


def test_log_cholesky_round_trip_and_jacobian():
    rng = np.random.default_rng(1)
    for _ in range(5):
        box = pin.Inertia.FromBox(*rng.uniform(0.1, 2.0, 4))
        pi = pin.SE3.Random().act(box).toDynamicParameters()  # a physical body
        np.testing.assert_allclose(from_log_cholesky(to_log_cholesky(pi, 1.0)), pi, atol=1e-8)
        x = 0.3 * rng.standard_normal(10)
        assert np.all(np.linalg.eigvalsh(pseudo_inertia(from_log_cholesky(x))) > 0.0)
        h = 1e-6
        fd = np.column_stack(
            [
                (from_log_cholesky(x + h * e) - from_log_cholesky(x - h * e)) / (2 * h)
                for e in np.eye(10)
            ]
        )
        np.testing.assert_allclose(log_cholesky_jacobian(x), fd, atol=1e-7)


@pytest.fixture(scope="module")
def five_bar_run():
    """A five-bar with drives, its efforts from the regressor (exact) plus noise."""
    robot = with_drives(
        pkdyn.load("five_bar", geometry=False), rotor_inertia=1e-5, viscous=1e-4, coulomb=0.02
    )
    ps = parameter_set(robot)
    t, qa, qd, qdd = _multisine(robot, 6.0, 5e-3, 0.3, 5)
    tau = predict_efforts(robot, ps, ps.nominal, t, qa, qd, qdd)
    noise = 1e-3
    rng = np.random.default_rng(2)
    meas = tau + noise * rng.standard_normal(tau.shape)
    return robot, ps, (t, qa, qd, qdd), tau, meas, noise


def test_base_parameters_of_the_five_bar(five_bar_run):
    robot, ps, (t, qa, qd, qdd), tau, meas, noise = five_bar_run
    res = identify(robot, Measurements(t, qa, qd, qdd, meas))
    formulas = res.base.formulas()
    # a motor's rotor inertia only moves with its proximal link: grouped into its Izz
    assert any(f.startswith("proximal1.Izz") and "motor1.rotor_inertia" in f for f in formulas)
    # the mass of a link turning about a fixed vertical axis has no effect (planar, z gravity)
    assert "proximal1.m" in res.base.no_effect
    assert "motor1.rotor_inertia" in res.base.grouped
    true_b = res.base.K @ ps.nominal[ps.identified]
    z = (res.estimate.theta - true_b) / res.estimate.std
    assert np.sqrt(np.mean(z**2)) < 2.5 and np.abs(z).max() < 5.0
    np.testing.assert_allclose(res.estimate.sigma, noise, rtol=0.1)


def test_filtered_rates_identify_as_well(five_bar_run):
    robot, ps, (t, qa, qd, qdd), tau, meas, noise = five_bar_run
    qf, qd_f, qdd_f = derivatives(t, qa + 1e-6 * np.random.default_rng(4).standard_normal(qa.shape))
    inner = slice(40, -40)  # away from the filter's end effects
    assert np.abs(qd_f - qd)[inner].max() < 1e-2 * np.abs(qd).max()
    assert np.abs(qdd_f - qdd)[inner].max() < 3e-2 * np.abs(qdd).max()
    res = identify(robot, Measurements(t, qa, None, None, meas))
    assert res.filtered
    pred = res.predict(t, qa, qd, qdd)
    assert np.sqrt(np.mean((pred - tau)[inner] ** 2)) < 0.5 * noise


def _csv(path, t, robot, qa, qd=None, qdd=None, tau=None, extra=None):
    names = robot.actuator_names
    cols, data = ["t"], [t]
    for label, arr in (("qa", qa), ("qa_dot", qd), ("qa_ddot", qdd), ("tau", tau)):
        if arr is not None:
            cols += [f"{label}_{n}" for n in names]
            data += list(arr.T)
    if extra:
        cols.append(extra)
        data.append(np.zeros_like(t))
    np.savetxt(path, np.column_stack(data), delimiter=",", header=",".join(cols), comments="")
    return path


def test_cli_identify_writes_a_description_that_loads_and_sizes(five_bar_run, tmp_path, capsys):
    robot, ps, (t, qa, qd, qdd), tau, meas, noise = five_bar_run
    data = _csv(tmp_path / "run.csv", t, robot, qa, qd, qdd, meas)
    t2, qa2, qd2, qdd2 = _multisine(robot, 2.0, 5e-3, 0.25, 9)
    tau2 = predict_efforts(robot, ps, ps.nominal, t2, qa2, qd2, qdd2)
    other = _csv(tmp_path / "other.csv", t2, robot, qa2, qd2, qdd2, tau2)
    out, pred = tmp_path / "identified.urdf", tmp_path / "pred.csv"
    args = ["identify", "five_bar", "--measurements", str(data), "-o", str(out), "--json"]
    assert main([*args, "--predict", str(other), "--csv", str(pred)]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["prediction"]["samples"] == t2.size
    assert max(payload["prediction"]["rms_error"].values()) < noise
    rows = np.loadtxt(pred, delimiter=",", skiprows=1)
    header = pred.read_text().splitlines()[0].split(",")
    assert header == ["t", "tau_motor1", "tau_motor2"] and rows.shape == (t2.size, 3)
    np.testing.assert_allclose(rows[:, 0], t2, atol=1e-9)
    loaded = pkdyn.load(str(out), geometry=False)
    acts = {a.name: a for a in loaded.actuators}
    assert acts["motor1"].coulomb == pytest.approx(0.02, rel=0.02)
    # the written description reproduces the identified model's efforts
    ps2 = parameter_set(loaded)
    tau_file = predict_efforts(loaded, ps2, ps2.nominal, t2, qa2, qd2, qdd2)
    np.testing.assert_allclose(tau_file, rows[:, 1:], atol=1e-6 * np.abs(tau2).max())
    assert main(["size", str(out), "--trajectory", "sine", "--json"]) == 0


def _error(capsys, argv):
    code = main(argv)
    err = capsys.readouterr().err.strip()
    assert code == 1 and err.startswith("pkdyn: error:") and "\n" not in err, err
    return err


def test_cli_refuses_bad_input(five_bar_run, tmp_path, capsys):
    robot, ps, (t, qa, qd, qdd), tau, meas, noise = five_bar_run
    out = str(tmp_path / "x.urdf")
    run = ["identify", "five_bar", "-o", out, "--measurements"]
    f = _csv(tmp_path / "a.csv", t, robot, qa, qd, qdd)
    assert "missing columns tau_motor1, tau_motor2" in _error(capsys, [*run, str(f)])
    f = _csv(tmp_path / "b.csv", t, robot, qa, qd, qdd, meas, extra="tau_motor3")
    assert "unknown column tau_motor3" in _error(capsys, [*run, str(f)])
    bad = meas.copy()
    bad[17, 1] = np.nan
    f = _csv(tmp_path / "c.csv", t, robot, qa, qd, qdd, bad)
    assert "line 19, column tau_motor2" in _error(capsys, [*run, str(f)])
    still = np.tile(qa[0], (t.size, 1))  # no motion: nothing excited
    f = _csv(tmp_path / "d.csv", t, robot, still, 0 * qd, 0 * qdd, meas)
    assert "does not excite" in _error(capsys, [*run, str(f)])
    f = _csv(tmp_path / "e.csv", t[:4], robot, qa[:4], qd[:4], qdd[:4], meas[:4])
    assert "base parameters" in _error(capsys, [*run, str(f)])
    assert not (tmp_path / "x.urdf").exists()


def test_refuses_redundant_actuation():
    robot = pkdyn.load("tripod", geometry=False, branches=4)
    t = np.zeros(3)
    qa = np.tile(robot.q_home[robot.actuated_q], (3, 1))
    with pytest.raises(InvalidInputError, match="redundantly actuated"):
        identify(robot, Measurements(t, qa, qa * 0, qa * 0, qa * 0))


def test_excitation_lowers_the_condition_within_the_limits():
    from pkdyn.identification.excitation import excitation_trajectory

    robot = pkdyn.load("five_bar", geometry=False)
    kw = dict(period=4.0, harmonics=3, samples=20, amplitude=0.3, seed=3)
    start = excitation_trajectory(robot, max_iter=0, **kw)
    best = excitation_trajectory(robot, max_iter=6, **kw)
    assert best.condition < 0.5 * start.condition  # observed 42 -> 4 (30 samples, 8 iter.)
    q, qd, qdd = best.evaluate(np.array([0.0]))
    np.testing.assert_allclose(q[0], robot.q_home[robot.actuated_q], atol=1e-12)
    np.testing.assert_allclose(np.r_[qd[0], qdd[0]], 0.0, atol=1e-12)  # starts at rest
    t, qa, qd, qdd = best.sample(rate=200.0)
    lo = robot.model.lowerPositionLimit[robot.actuated_q]
    hi = robot.model.upperPositionLimit[robot.actuated_q]
    assert np.all((qa >= lo - 1e-6) & (qa <= hi + 1e-6))
    lim = np.array([a.velocity for a in robot.actuators])
    assert np.all(np.abs(qd) <= lim * (1 + 1e-6))
    h = t[1] - t[0]  # the rates are the positions' derivatives
    np.testing.assert_allclose(np.gradient(qa, h, axis=0)[1:-1], qd[1:-1], atol=1e-3)
