"""Dynamics of loaded robots along trajectories: physics checks, sizing, typed errors, CLI."""

import csv
import json
import subprocess
import sys
import warnings

import numpy as np
import pinocchio as pin
import pytest
from conftest import simpson_work

import pkdyn
from pkdyn.analysis.statics import static_equilibrium
from pkdyn.cli import main
from pkdyn.dynamics import (
    actuation,
    inverse_dynamics,
    mechanical_energy,
    simulate,
    with_payload,
)
from pkdyn.dynamics.sizing import size
from pkdyn.dynamics.trajectory import JointTrajectory, named_trajectory
from pkdyn.exceptions import InfeasibleEffortError, InvalidInputError, TrajectoryError
from solvers import ForwardDynamics

CASES = {
    "delta": ("adept", {"cycle_time": 0.6, "dt": 2e-3}),
    "gough_stewart": ("sine", {"dt": 2e-3}),
    "tripod": ("p2p", {"duration": 0.8, "dt": 4e-3}),
    "planar_3rrr": ("p2p", {"duration": 0.5, "dt": 2e-3}),
}


@pytest.fixture(scope="module")
def mapped() -> dict[str, tuple[pkdyn.Robot, JointTrajectory]]:
    out = {}
    for name, (traj, opts) in CASES.items():
        robot = pkdyn.load(name, geometry=False)
        out[name] = (robot, named_trajectory(robot, traj, **opts))
    return out


@pytest.mark.parametrize("name", list(CASES))
def test_inverse_then_forward_dynamics_reproduces_the_accelerations(mapped, name):
    """The efforts found, fed to pin.constraintDynamics (no Baumgarte), give back the
    trajectory's accelerations (1e-8, relative to the largest acceleration)."""
    robot, jt = mapped[name]
    loaded = with_payload(robot, 0.5)
    ef = inverse_dynamics(loaded, jt)
    act = actuation(loaded)
    fd = ForwardDynamics(loaded.model, list(loaded.constraint_models), act, baumgarte=(0.0, 0.0))
    for k in range(0, jt.t.size, max(1, jt.t.size // 12)):
        a = fd.acceleration(jt.q[k], jt.v[k], act.generalized(ef.tau[k], robot.nv))
        scale = max(1.0, float(np.max(np.abs(jt.a[k]))))
        assert np.max(np.abs(a - jt.a[k])) < 1e-8 * scale


@pytest.mark.parametrize("name", list(CASES))
def test_power_balance_along_the_trajectory(mapped, name):
    """integral of sum(tau qd) dt = change of kinetic + potential energy (0.5 %; Simpson)."""
    robot, jt = mapped[name]
    loaded = with_payload(robot, 1.0)
    ef = inverse_dynamics(loaded, jt)
    work, idx = simpson_work(jt.t, np.sum(ef.tau * jt.qa_dot, axis=1))
    dE = ef.energy[idx] - ef.energy[0]
    exchanged = max(float(np.max(np.abs(work))), float(np.max(ef.kinetic)))
    assert exchanged > 1e-3  # something moves
    assert np.max(np.abs(work - dE)) < 5e-3 * exchanged
    # the energies are the robot's own (Pinocchio's, independently evaluated)
    k = jt.t.size // 3
    kin, pot = mechanical_energy(loaded, jt.q[k], jt.v[k])
    M = pin.crba(loaded.model, loaded.model.createData(), jt.q[k])
    M = np.triu(M) + np.triu(M, 1).T
    assert kin == pytest.approx(0.5 * jt.v[k] @ M @ jt.v[k], rel=1e-12)
    assert ef.kinetic[k] == pytest.approx(kin) and ef.potential[k] == pytest.approx(pot)


@pytest.mark.parametrize("name", ["delta", "gough_stewart", "tripod"])
def test_static_case_equals_the_statics(mapped, name):
    """At rest (v = a = 0), the inverse dynamics with gravity and a platform wrench gives the
    efforts of the statics (issue 4), and a payload acts as its weight on the platform."""
    robot, jt = mapped[name]
    rng = np.random.default_rng(7)
    for k in (0, jt.t.size // 2):
        q = jt.q[k]
        F = rng.normal(size=6) * np.array([20.0, 20.0, 20.0, 1.0, 1.0, 1.0])
        F[[i for i in range(6) if i not in robot.task_rows]] = 0.0
        rest = JointTrajectory(
            jt.t[:2],
            np.array([q, q]),
            np.zeros((2, robot.nv)),
            np.zeros((2, robot.nv)),
            robot.actuated_q,
            robot.actuated_v,
        )
        ef = inverse_dynamics(robot, rest, wrench=F)
        ref = static_equilibrium(robot, q, F, gravity=True).tau
        np.testing.assert_allclose(ef.tau[0], ref, atol=1e-9 * max(1.0, np.max(np.abs(ref))))
        m = 2.0
        pay = inverse_dynamics(with_payload(robot, m), rest).tau[0]
        g = robot.model.gravity.linear
        weight = np.concatenate([m * g, np.zeros(3)])  # at the platform frame origin
        ref = static_equilibrium(robot, q, weight, gravity=True).tau
        np.testing.assert_allclose(pay, ref, atol=1e-9 * max(1.0, np.max(np.abs(ref))))


def test_payload_adds_its_mass_and_leaves_the_robot_alone(mapped):
    robot, _ = mapped["delta"]
    before = sum(i.mass for i in robot.model.inertias)
    loaded = with_payload(robot, 1.5, offset=(0.0, 0.0, -0.02))
    assert sum(i.mass for i in loaded.model.inertias) == pytest.approx(before + 1.5)
    assert sum(i.mass for i in robot.model.inertias) == pytest.approx(before)
    with pytest.raises(InvalidInputError, match="payload"):
        with_payload(robot, -1.0)


def test_wrench_does_the_work_it_should(mapped):
    """A constant platform force along a trajectory: the actuators supply the energy change
    minus the work of the force (0.5 %)."""
    robot, jt = mapped["gough_stewart"]
    F = np.array([15.0, -10.0, 40.0, 0.0, 0.0, 0.0])
    ef = inverse_dynamics(robot, jt, wrench=F)
    work, idx = simpson_work(jt.t, np.sum(ef.tau * jt.qa_dot, axis=1))
    pos = np.array([robot.platform_placement(q).translation for q in jt.q])
    w_force = (pos[idx] - pos[0]) @ F[:3]
    dE = ef.energy[idx] - ef.energy[0]
    exchanged = max(float(np.max(np.abs(work))), float(np.max(np.abs(w_force))))
    assert np.max(np.abs(work + w_force - dE)) < 5e-3 * exchanged
    # and its share of the efforts is -J^T F, with J the derivative of the direct geometric
    # model by central differences (force in world axes, moment in platform axes)
    F6 = np.array([15.0, -10.0, 40.0, 2.0, -1.5, 3.0])
    share = inverse_dynamics(robot, jt, wrench=F6).tau - inverse_dynamics(robot, jt).tau
    h = 1e-5
    for k in (0, jt.t.size // 3, 2 * jt.t.size // 3):
        q = jt.q[k]
        M0 = robot.platform_placement(q)
        n_a = len(robot.actuators)
        J = np.zeros((6, n_a))
        for j in range(n_a):
            dq = np.zeros(n_a)
            dq[j] = h
            Mp, Mm = (
                pkdyn.forward_geometry(robot, jt.qa[k] + s * dq, q_init=q).placement
                for s in (1.0, -1.0)
            )
            J[:3, j] = (Mp.translation - Mm.translation) / (2 * h)
            J[3:, j] = (
                pin.log3(M0.rotation.T @ Mp.rotation) - pin.log3(M0.rotation.T @ Mm.rotation)
            ) / (2 * h)
        np.testing.assert_allclose(share[k], -J.T @ F6, atol=1e-7 * np.max(np.abs(J.T @ F6)))


# --------------------------------------------------------------------------- sizing


def test_sizing_figures_from_the_efforts(mapped):
    robot, jt = mapped["delta"]
    res = size(robot, jt, payload=1.0)
    tau, qd, t = res.efforts.tau, jt.qa_dot, jt.t
    fine = np.linspace(t[0], t[-1], 20001)  # RMS by an independent (interpolated) quadrature
    for i, a in enumerate(res.actuators):
        assert a.peak == pytest.approx(np.max(np.abs(tau[:, i])))
        rms = np.sqrt(np.mean(np.interp(fine, t, tau[:, i]) ** 2))
        assert a.rms == pytest.approx(rms, rel=5e-3)
        assert a.peak_speed == pytest.approx(np.max(np.abs(qd[:, i])))
        assert a.peak_power == pytest.approx(np.max(np.abs(tau[:, i] * qd[:, i])))
        act = robot.actuators[i]
        assert a.limit == act.effort and a.margin == pytest.approx(1 - a.peak / act.effort)
        assert a.motor_peak == pytest.approx(a.peak / act.reduction)
        assert a.motor_peak_speed == pytest.approx(a.peak_speed * act.reduction)
    # a heavier payload needs more torque
    assert max(a.peak for a in size(robot, jt, payload=2.0).actuators) > max(
        a.peak for a in res.actuators
    )


def test_infeasible_effort_limits_name_the_sample_and_the_actuator():
    robot = pkdyn.load("delta", geometry=False, effort=3.0)
    jt = named_trajectory(robot, "adept", cycle_time=0.6, dt=5e-3)
    with pytest.raises(InfeasibleEffortError) as info:
        inverse_dynamics(robot, jt, limits=True)
    err = info.value
    assert err.sample is not None and err.actuator in robot.actuator_names
    assert f"sample {err.sample}" in str(err) and err.actuator in str(err)
    # without the bounds the same motion is computed, and exceeds 3 N m at that sample
    ef = inverse_dynamics(robot, jt)
    k = robot.actuator_names.index(err.actuator)
    assert abs(ef.tau[err.sample, k]) > 3.0


def test_non_finite_trajectory_is_refused(mapped):
    robot, jt = mapped["delta"]
    a = jt.a.copy()
    a[5, 3] = np.nan
    bad = JointTrajectory(jt.t, jt.q, jt.v, a, jt.actuated_q, jt.actuated_v)
    with pytest.raises(TrajectoryError, match="sample 5"):
        inverse_dynamics(robot, bad)


def test_inconsistent_acceleration_is_reported(mapped):
    robot, jt = mapped["gough_stewart"]
    a = jt.a.copy()
    a[4] += 1.0  # violates the closures
    bad = JointTrajectory(jt.t, jt.q, jt.v, a, jt.actuated_q, jt.actuated_v)
    with pytest.raises(TrajectoryError, match="sample 4.*acceleration does not satisfy closure"):
        inverse_dynamics(robot, bad)
    v = jt.v.copy()
    v[2] += 0.01
    bad = JointTrajectory(jt.t, jt.q, v, jt.a, jt.actuated_q, jt.actuated_v)
    with pytest.raises(TrajectoryError, match="sample 2.*velocity does not satisfy closure"):
        inverse_dynamics(robot, bad)


# --------------------------------------------------------------------------- simulation


def test_simulate_wraps_errors(mapped):
    robot, _ = mapped["delta"]
    with pytest.raises(InvalidInputError, match="dt"):
        simulate(robot, 1.0, 0.0)
    with pytest.raises(InvalidInputError, match="integrator"):
        simulate(robot, 1.0, 1e-3, integrator="leapfrog")
    with pytest.raises(pkdyn.PkdynError, match="torque function"):
        simulate(robot, 0.01, 1e-3, torque=lambda t, q, v: np.array([np.nan, 0.0, 0.0]))


@pytest.mark.parametrize("name", ["delta", "gough_stewart"])
def test_cli_simulate_ten_seconds_keeps_energy_and_closures(capsys, name):
    """Passive run under gravity, 10 s at 1 kHz: closures < 1e-9 m over the run, energy drift
    < 1e-7 up to the first passage through a singularity (``valid_until``: the falling Delta
    crosses the one of its parallelograms after 0.26 s, and past it the motion, the
    minimum-norm continuation, depends on the BLAS kernel's rounding: its drift over the 10 s
    was 9.6e-9 on one kernel, 3.4e-4 on another; the hexapod crosses none). Recorded: drift
    4e-11 (Delta, to 0.26 s), 1.2e-9 (hexapod, 10 s); closures 2.4e-11 m and 2.5e-10 m."""
    assert main(["simulate", name, "--duration", "10", "--dt", "1e-3", "--json"]) == 0
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert out["steps"] == 10000
    assert out["max_closure_residual"] < 1e-9
    assert out["energy_drift_rel_valid"] < 1e-7
    assert out["max_kinetic_energy"] > 0.1  # it did fall
    passages = out["singular_passages"]
    if out["valid_until"] < 10.0:
        first = next(p for p in passages if p["through"])
        assert first["start"] == out["valid_until"] and first["conditioning"] < 1e-5
    assert all(p["kind"] == "parallel_singularity" for p in passages)
    # one warning line for the passages, none without
    assert captured.err.count("parallel singularity") == (1 if passages else 0)


# --------------------------------------------------------------------------- CLI size


def test_cli_size_json_csv_plot(tmp_path, capsys):
    csv_path, png = tmp_path / "adept.csv", tmp_path / "adept.png"
    args = ["size", "delta", "--trajectory", "adept", "--payload", "1", "--cycle-time", "0.6"]
    args += ["--dt", "2e-3", "--csv", str(csv_path), "--plot", str(png), "--json"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    acts = out["actuators"]
    assert [a["name"] for a in acts] == ["motor1", "motor2", "motor3"]
    for a in acts:
        assert {"name", "peak", "rms", "peak_speed", "peak_power", "limit", "margin"} <= set(a)
        assert 0 < a["rms"] < a["peak"] < a["limit"]
    with open(csv_path) as fh:
        rows = list(csv.reader(fh))
    names = ["motor1", "motor2", "motor3"]
    prefixes = ("qa", "qa_dot", "tau")
    assert rows[0] == ["t"] + [f"{p}_{n}" for p in prefixes for n in names] + ["energy"]
    assert len(rows) == 302 and float(rows[-1][0]) == pytest.approx(0.6)
    tau1 = np.array([float(r[7]) for r in rows[1:]])
    assert np.max(np.abs(tau1)) == pytest.approx(acts[0]["peak"], rel=1e-8)
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["size", "delta", "--cycle-time", "0"], "--cycle-time"),
        (["size", "delta", "--cycle-time", "0.2"], "limits exceeded: motor1 speed by"),
        (["size", "delta", "--payload", "-2"], "payload"),
        (["size", "delta", "--param", "effort=nan"], "effort"),
        (["simulate", "delta", "--dt", "-1"], "dt"),
    ],
)
def test_cli_dynamics_errors_are_one_line(capsys, args, needle):
    assert main(args) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("pkdyn: error:") and needle in err


def test_demo_prints_the_sizing_table():
    proc = subprocess.run(
        [
            sys.executable,
            "-c",
            "from pkdyn.cli.demo import run_sizing_demo as r; "
            "r(cycle_times=(0.5,), payloads=(0.0, 1.0))",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    out = proc.stdout
    assert "DELTA 580" in out and "motor1" in out and "power balance" in out
    assert "\n0.5 " in out and "peak effort [N m]" in out  # (the grid's row of 0.5 s)


# --------------------------------------------------------------------------- redundant actuation


@pytest.fixture(scope="module")
def quattro():
    robot = pkdyn.load("delta", geometry=False, arms=4, bar_joint="universal")
    return robot, named_trajectory(robot, "adept", cycle_time=0.6, dt=4e-3)


def test_four_armed_delta_is_redundantly_actuated(quattro):
    robot, jt = quattro
    assert len(robot.actuators) == 4 and robot.mobility() == 3
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-12


def test_redundant_efforts_are_the_least_weighted_norm_and_reproduce_the_motion(quattro):
    """Four actuators for three DOF: the efforts realise the accelerations (forward dynamics)
    and minimise sum(w tau^2) over all efforts that do (no weighted gradient along the
    effort directions that move nothing)."""
    robot, jt = quattro
    ef = inverse_dynamics(robot, jt)
    act = actuation(robot)
    fd = ForwardDynamics(robot.model, list(robot.constraint_models), act, baumgarte=(0.0, 0.0))
    w = 1.0 / np.array([a.effort for a in robot.actuators]) ** 2
    data = robot.model.createData()
    for k in range(0, jt.t.size, 15):
        q, v = jt.q[k], jt.v[k]
        a = fd.acceleration(q, v, act.generalized(ef.tau[k], robot.nv))
        assert np.max(np.abs(a - jt.a[k])) < 1e-8 * max(1.0, np.max(np.abs(jt.a[k])))
        # efforts that move nothing: S^T d in the range of Jc^T, i.e. Z^T S^T d = 0
        J = robot.closure_set.jacobian(data, q)
        _, s, Vt = np.linalg.svd(J)
        Z = Vt[int(np.sum(s > 1e-9 * s[0])) :].T
        G = Z.T @ act.matrix(robot.nv).T
        _, sg, Vg = np.linalg.svd(G)
        free = Vg[int(np.sum(sg > 1e-9 * sg[0])) :]
        assert free.shape[0] == 1
        assert abs(free @ (w * ef.tau[k])) < 1e-8 * max(1.0, np.max(np.abs(w * ef.tau[k])))


def test_redundant_limits_are_respected_or_named(quattro):
    robot, jt = quattro
    free = inverse_dynamics(robot, jt)
    peak = np.max(np.abs(free.tau))
    # a limit below the least-norm peak but reachable by sharing: the QP keeps every effort in
    limited = pkdyn.load("delta", geometry=False, arms=4, bar_joint="universal", effort=0.95 * peak)
    ef = inverse_dynamics(limited, jt, limits=True)
    assert np.max(np.abs(ef.tau)) <= 0.95 * peak + 1e-8
    # far too low: named sample and actuator
    weak = pkdyn.load("delta", geometry=False, arms=4, bar_joint="universal", effort=0.2 * peak)
    with pytest.raises(InfeasibleEffortError) as info:
        inverse_dynamics(weak, jt, limits=True)
    assert info.value.sample is not None and info.value.actuator in weak.actuator_names


@pytest.mark.parametrize("params", [{"parallelogram": "hinge"}, {"arms": 4}])
def test_overconstrained_closures_simulate(params):
    """Hinge parallelograms (redundant hinge equations, hyperstatic) and a fourth arm (the
    closures over-determine the nacelle): the proximal solver copes; energy kept up to the
    first passage through a singularity, closures throughout. With hinges the parallelograms
    hold the nacelle's orientation whatever their normals do: the fall crosses no singularity
    (the ball-jointed arms cross one where the normals become coplanar, 0.22 s for four arms)."""
    robot = pkdyn.load("delta", geometry=False, **params)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (the singular passages of the four arms)
        res = simulate(robot, 1.0, 1e-3)
    n = int(np.searchsorted(res.t, res.valid_until, side="right"))
    assert np.max(res.closure_residual) < 1e-8
    assert res.energy_drift(res.valid_until) < 1e-7
    assert np.max(res.kinetic[:n]) > 0.1
    if "parallelogram" in params:
        assert res.events == [] and res.valid_until == res.t[-1]
