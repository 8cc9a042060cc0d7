"""Motor x gearbox selection: the figures of a pair equal pkdyn's dynamics with that drive."""

import json
import math

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.dynamics import inverse_dynamics, with_payload
from pkdyn.dynamics.actuation import motor_efforts, with_drives
from pkdyn.dynamics.motors import Catalog, Gearbox, Motor, example_catalog
from pkdyn.dynamics.selection import actuator_inertia, select_drives
from pkdyn.dynamics.sizing import size
from pkdyn.dynamics.trajectory import named_trajectory
from pkdyn.exceptions import InvalidInputError, NoFeasibleDriveError


@pytest.fixture(scope="module")
def case():
    robot = pkdyn.load("delta", geometry=False)
    traj = named_trajectory(robot, "adept", cycle_time=0.5, dt=4e-3)
    sel = select_drives(robot, traj, example_catalog(), payload=1.0)
    return robot, traj, sel


def test_a_pair_is_the_dynamics_with_that_drive(case):
    """The motor torque of a pair (load efforts + reflected inertia through the drive model)
    equals pkdyn's inverse dynamics of the robot fitted with that motor and gearbox."""
    robot, traj, sel = case
    cand = sel.actuators[0].feasible[0]
    m, g = cand.motor, cand.gearbox
    fitted = with_drives(
        robot,
        reduction=g.ratio,
        rotor_inertia=m.rotor_inertia + g.inertia,
        efficiency=g.efficiency,
    )
    ef = inverse_dynamics(with_payload(fitted, 1.0), traj)
    tau_m = motor_efforts(fitted, ef.tau, traj.qa_dot)
    assert np.allclose(tau_m[:, 0], cand.torque, rtol=0, atol=1e-9 * np.max(np.abs(tau_m)))
    assert cand.motor_peak == pytest.approx(np.max(np.abs(tau_m[:, 0])), rel=1e-9)
    sizing = size(fitted, traj, payload=1.0)
    assert cand.motor_rms == pytest.approx(sizing.actuators[0].motor_rms, rel=1e-9)
    assert np.allclose(cand.speed, g.ratio * traj.qa_dot[:, 0])


def test_feasible_pairs_pass_every_check_and_are_ranked(case):
    _, traj, sel = case
    for a in sel.actuators:
        assert a.feasible and a.rejected
        assert all(c.feasible and c.utilisation <= 1.0 for c in a.feasible)
        scores = [c.motor.rated_torque for c in a.feasible]
        assert scores == sorted(scores)
        for c in a.feasible:
            pk = next(x for x in c.checks if x.name == "peak torque")
            env = c.motor.peak_torque_at(c.speed)
            assert np.all(np.abs(c.torque) <= env * (1 + 1e-12))
            assert pk.demand <= pk.capacity
            assert {x.name for x in c.checks} >= {"gearbox peak torque", "gearbox input speed"}
        for c in a.rejected:
            assert c.failures and "> " in c.why() and "%" in c.why()
            assert c.utilisation > 1.0
        # closest first
        assert [c.utilisation for c in a.rejected] == sorted(c.utilisation for c in a.rejected)
    assert sel.feasible and len(sel.choice()) == 3
    text = sel.table()
    assert "feasible of 126 pairs" in text and "optimal ratio" in text
    js = json.loads(json.dumps(sel.to_json()))
    assert js["actuators"][0]["rejected"][0]["why"]


def test_load_inertia_gives_the_kinetic_energy(case):
    """0.5 qa_dot^T M_a qa_dot equals the mechanism's kinetic energy along the trajectory
    (the internal mobilities carry no momentum there)."""
    robot, traj, _ = case
    loaded = with_payload(robot, 1.0)
    for k in range(5, traj.t.size, 17):
        Ma = actuator_inertia(loaded, traj.q[k])
        qd = traj.qa_dot[k]
        ke = pin.computeKineticEnergy(loaded.model, loaded.data, traj.q[k], traj.v[k])
        assert 0.5 * qd @ Ma @ qd == pytest.approx(ke, rel=1e-9)
        assert np.allclose(Ma, Ma.T) and np.all(np.linalg.eigvalsh(Ma) > 0)
    geared = with_drives(loaded, rotor_inertia=5e-5)
    diff = actuator_inertia(geared, traj.q[0], armature=True) - actuator_inertia(geared, traj.q[0])
    assert np.allclose(diff, np.diag([0.02] * 3))


def test_optimal_ratio_minimises_the_rms_torque(case):
    """Brute force over lossless, inertia-free gearboxes: the RMS-optimal ratio is the one
    reported (up to the grid)."""
    robot, traj, sel = case
    ratio = next(r for r in sel.actuators[0].ratios if r.motor == "EX-S400")
    m = next(m for m in example_catalog().motors if m.name == "EX-S400")
    grid = np.linspace(0.5, 1.5, 41) * ratio.optimal
    gears = tuple(Gearbox(f"g{r:.4f}", r, 1.0, 1e5, 1e5, 1e4, 0.0) for r in grid)
    brute = select_drives(robot, traj, Catalog((m,), gears), payload=1.0)
    a = brute.actuators[0]
    by_ratio = sorted(a.feasible + a.rejected, key=lambda c: c.reduction)
    rms = np.array([c.motor_rms for c in by_ratio])
    best = by_ratio[int(np.argmin(rms))].reduction
    assert abs(best - ratio.optimal) <= (grid[1] - grid[0]) * 1.01
    assert float(np.min(rms)) == pytest.approx(ratio.rms_at_optimal, rel=1e-3)
    assert ratio.speed_limited == pytest.approx(m.max_speed / np.max(np.abs(traj.qa_dot[:, 0])))


def test_no_feasible_pair_names_the_closest_and_what_they_lack(case, capsys):
    robot, traj, _ = case
    cat = example_catalog()
    small = Catalog(cat.motors[:2], cat.gearboxes[:3], "small")
    sel = select_drives(robot, traj, small, payload=1.0)
    assert not sel.feasible
    with pytest.raises(NoFeasibleDriveError, match="motor1") as err:
        sel.choice()
    assert len(err.value.closest) == 3 and all(" > " in c for c in err.value.closest)
    assert "NO FEASIBLE PAIR" in sel.table()


def test_criteria_and_own_transmission(case):
    robot, traj, _ = case
    cat = example_catalog()
    by_mass = select_drives(robot, traj, cat, payload=1.0, criterion="mass")
    masses = [c.mass for c in by_mass.actuators[1].feasible]
    assert masses == sorted(masses)
    by_price = select_drives(robot, traj, cat, payload=1.0, criterion="price")
    prices = [c.score for c in by_price.actuators[1].feasible]
    assert prices == sorted(prices) and all(math.isfinite(p) for p in prices)
    motors_only = Catalog(cat.motors, (), "motors")
    own = select_drives(robot, traj, motors_only, payload=1.0)
    assert all(c.reduction == 20.0 and c.gearbox is None for c in own.actuators[0].rejected)
    assert {c.name for c in own.actuators[0].feasible} <= {m.name for m in cat.motors}
    no_price = Catalog((Motor("M", 1.0, 3.0, 300.0, 600.0, 4e-5, 1.0),), (), "x")
    with pytest.raises(InvalidInputError, match="price missing for M"):
        select_drives(robot, traj, no_price, criterion="price")
    with pytest.raises(InvalidInputError, match="criterion"):
        select_drives(robot, traj, cat, criterion="colour")


def test_thermal_window_of_a_short_time_constant(case):
    robot, traj, _ = case
    m = Motor("hot", 1.3, 3.8, 314.0, 628.0, 4e-5, 1.5, thermal_time_constant=1.0)
    cold = Motor("cold", 1.3, 3.8, 314.0, 628.0, 4e-5, 1.5)
    gears = example_catalog().gearboxes[3:4]
    long = named_trajectory(robot, "adept", cycle_time=0.8, cycles=3, dt=4e-3)
    sel = select_drives(robot, long, Catalog((m, cold), gears), payload=2.0)
    a = sel.actuators[0]
    by = {c.motor.name: c for c in a.feasible + a.rejected}
    assert by["hot"].motor_rms > by["cold"].motor_rms  # the worst 1 s window, not the mean


def test_cli_catalog_and_operating_points(tmp_path, capsys):
    png = tmp_path / "op.png"
    args = ["size", "delta", "--cycle-time", "0.5", "--dt", "4e-3", "--payload", "1"]
    args += ["--catalog", "example", "--operating-points", str(png), "--json"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    sel = out["selection"]
    assert sel["feasible"] and sel["actuators"][0]["best"]
    assert png.read_bytes()[:4] == b"\x89PNG"
    bad = tmp_path / "bad.yaml"
    bad.write_text("motors:\n  - {name: X1, rated_torque: 1, peak_torque: 3}\n")
    assert main(["size", "delta", "--dt", "4e-3", "--catalog", str(bad)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("pkdyn: error:") and len(err.splitlines()) == 1
    assert "motor 'X1': field 'rated_speed': missing" in err
    assert main(["size", "delta", "--operating-points", str(png)]) == 1
    assert "--catalog" in capsys.readouterr().err


def test_a_screw_keeps_its_reduction_and_may_go_without_gearbox():
    hexapod = pkdyn.load("gough_stewart", geometry=False)
    traj = named_trajectory(hexapod, "sine", dt=1e-2)
    sel = select_drives(hexapod, traj, example_catalog())
    screw = hexapod.actuators[0].reduction  # rad/m
    a = sel.actuators[0]
    every = a.feasible + a.rejected
    direct = [c for c in every if c.gearbox is None]
    assert len(direct) == 7 and all(c.reduction == pytest.approx(screw) for c in direct)
    assert all(c.reduction == pytest.approx(c.gearbox.ratio * screw) for c in every if c.gearbox)
    assert a.feasible and a.best.gearbox is None  # this gentle motion needs no gearbox


def test_redundant_actuation_selects_and_has_a_load_inertia():
    quattro = pkdyn.load("delta", geometry=False, arms=4, bar_joint="universal")
    traj = named_trajectory(quattro, "adept", cycle_time=0.6, dt=1e-2)
    sel = select_drives(quattro, traj, example_catalog(), payload=1.0)
    assert len(sel.actuators) == 4 and sel.feasible
    k = traj.t.size // 3
    Ma = actuator_inertia(quattro, traj.q[k])  # pseudo-inverse: 4 rates, 3 dof
    ke = pin.computeKineticEnergy(quattro.model, quattro.data, traj.q[k], traj.v[k])
    assert 0.5 * traj.qa_dot[k] @ Ma @ traj.qa_dot[k] == pytest.approx(ke, rel=1e-8)
