"""The four-branch walker of seed 003's conclusion (issue 19): model, modes, redundancy, checks.

Every check is made by other means than the code under test: forward kinematics of the joint
trajectories for the feet, the nacelle and the locks; coal for the distances the closed forms
compute; pkdyn's general singularity analysis for the closed-form conditioning; the constrained
forward dynamics and the energy for the inverse dynamics; a linear program over the full
dynamics equation for the least largest force.
"""

import json
import math
import warnings

import numpy as np
import pinocchio as pin
import pytest
from conftest import simpson_work
from scipy.optimize import linprog

import pkdyn
from pkdyn.analysis.collisions import CollisionChecker
from pkdyn.analysis.singularity import classify
from pkdyn.cli import main
from pkdyn.closed_form import tripod as tripod_cf
from pkdyn.dynamics import actuation, inverse_dynamics
from pkdyn.library import tripod
from pkdyn.tripod import (
    Stance,
    be_mode,
    branch_numbers,
    foot_placement,
    locked_names,
    mode_robot,
    pp_mode,
)
from pkdyn.tripod.analysis import leg_pairs, run_scenario
from pkdyn.tripod.clearance import clearances
from pkdyn.tripod.compare import compare_walkers, default_cases
from pkdyn.tripod.locked_branch import foot_frames
from pkdyn.tripod.machining import MachiningPlan
from pkdyn.tripod.redundancy import bumps
from pkdyn.tripod.scenario import WalkPlan, station_home
from solvers import ForwardDynamics

P4 = tripod.Params(branches=4)
TOOL = pin.SE3(np.eye(3), np.array([0.0, 0.0, -P4.tool_offset]))
STEP = (0.08, 0.02)
PLAN = WalkPlan(
    step=STEP,
    cycles=1,
    dt=0.25,
    machining=MachiningPlan(move_time=1.0, plunge_time=0.8, contour_time=2.0),
)


@pytest.fixture(scope="module")
def walker() -> pkdyn.Robot:
    return pkdyn.load("tripod", branches=4)


@pytest.fixture(scope="module")
def report(walker):
    return run_scenario(walker, PLAN, stride=2, progress=False)


def _nacelle(robot, q):
    pin.forwardKinematics(robot.model, robot.data, q)
    return pin.SE3(robot.data.oMi[robot.model.getJointId("nacelle")])


# --- the model ---------------------------------------------------------------------------------


def test_walker_repeats_the_tripod_branch_evenly(walker):
    tri = pkdyn.load("tripod", geometry=False)
    assert walker.name == "walker" and len(walker.actuators) == 8
    assert [a.name for a in walker.actuators][-2:] == ["L4", "R4"]
    # same home lengths, same passive angles at home: every branch is a tripod branch
    assert np.allclose(tripod.home(P4), tripod.home(tripod.Params())[0], atol=1e-12)
    s3 = tripod_cf.virtual_joints(tripod.Params(), station_home(tripod.Params(), _default(3)))
    s4 = tripod_cf.virtual_joints(P4, station_home(P4, _default(4)))
    assert np.allclose(s4, s3[0], atol=1e-12)
    # attachments spread by 90 degrees, footholds too
    for i in range(4):
        P_L, P_R = tripod_cf.attachments(P4, i)
        mid = math.atan2(P_L[1] + P_R[1], P_L[0] + P_R[0])
        assert math.isclose(math.remainder(mid - i * math.pi / 2, 2 * math.pi), 0, abs_tol=1e-12)
        f = tripod_cf.foothold_frames(P4)[i].translation
        assert np.allclose(
            f[:2], 0.7 * np.array([math.cos(i * math.pi / 2), math.sin(i * math.pi / 2)])
        )
    # the tripod's URDF is unchanged by the new parameter (the committed file is checked
    # elsewhere); the walker adds one branch of the same mass
    m3 = sum(tri.model.inertias[j].mass for j in range(tri.model.njoints))
    m4 = sum(walker.model.inertias[j].mass for j in range(walker.model.njoints))
    assert m4 - m3 == pytest.approx((m3 - 14.0) / 3, rel=1e-12)


def _default(n: int) -> Stance:
    return Stance.default(tripod.Params(branches=n))


def test_walker_modes_leave_two_degrees_of_freedom_to_the_nacelle(walker):
    st = Stance.default(P4)
    q0 = walker.q_home
    pp = mode_robot(walker, st, pp_mode())
    assert pp.mobility(q0) == 6  # eight actuators on a 6-DOF nacelle: redundant actuation
    for b in branch_numbers(walker):
        mode = be_mode(walker, q0, b)
        assert (
            list(mode.locked)
            == locked_names(b, 4)
            == [
                f"branch{b}_q1",
                f"branch{b}_q2",
                f"branch{b}_q3",
                f"branch{b}_q6",
            ]
        )
        be = mode_robot(walker, st, mode, q0)
        assert be.mobility(q0) == 8  # the foot takes 6, two are left to the nacelle
        clamped = [o for o in be.constraint_owner if o.endswith("_foothold")]
        assert len(clamped) == 3 and f"branch{b}_foothold" not in clamped
        # with the supports' q1 locked as the tripod's, the foot could not follow a 6D path
        from pkdyn.tripod.locks import Lock
        from pkdyn.tripod.modes import Mode

        extra = tuple(
            Lock(f"branch{s}_q2q1", (1,), (float(q0[_q1(walker, s)]),), f"branch{s}_q1")
            for s in branch_numbers(walker)
            if s != b
        )
        over = Mode("BE", b, mode.locks + extra)
        assert mode_robot(walker, st, over, q0).mobility(q0) == 5


def _q1(robot, b):
    return robot.model.joints[robot.model.getJointId(f"branch{b}_q2q1")].idx_q + 1


def test_walker_geometric_models_and_stances(walker):
    from pkdyn.tripod.analysis import redundant_singularity_distance
    from pkdyn.tripod.xfkmb import actuator_lengths, bikmx, xfkmb

    st = Stance.default(P4)
    x = station_home(P4, st)
    q = walker.q_home
    b = bikmx(P4, x, st, 2)  # the walker locks four joints of the swinging branch
    assert np.allclose(b, be_mode(walker, q, 2).lock_targets()[[1, 0, 2, 3]], atol=1e-12)
    assert np.allclose(actuator_lengths(P4, x, st), q[walker.actuated_q], atol=1e-12)
    with pytest.raises(pkdyn.InvalidInputError, match="XFKMB"):
        xfkmb(P4, np.zeros(6), st, 1, x)
    with pytest.raises(pkdyn.InvalidInputError, match="4 branches"):
        mode_robot(walker, Stance.default(tripod.Params()), pp_mode())
    with pytest.raises(pkdyn.InvalidInputError, match="branch"):
        be_mode(walker, q, 5)
    # the singularity margin of redundant actuation: classify's for a square robot
    tri = pkdyn.load("tripod", geometry=False)
    pp3 = mode_robot(tri, Stance.default(tri.params), pp_mode())
    assert redundant_singularity_distance(pp3, tri.q_home) == pytest.approx(
        classify(pp3, tri.q_home).distance, abs=1e-9
    )
    pp4 = mode_robot(walker, st, pp_mode())
    assert 0.1 < redundant_singularity_distance(pp4, q) < 1.0


@pytest.mark.parametrize(("name", "value"), [("branches", 5), ("branches", 2), ("theta", 0.8)])
def test_walker_bad_parameters(name, value):
    params = {"branches": 4, name: value}
    with pytest.raises(pkdyn.ParameterError, match=name):
        pkdyn.load("tripod", geometry=False, **params)


# --- closed forms against the general machinery -----------------------------------------------


def test_closed_form_clearances_and_conditioning_against_coal_and_classify(walker):
    st = Stance.default(P4)
    pp = mode_robot(walker, st, pp_mode())
    leg_leg, leg_nacelle = leg_pairs(4)
    c_ll, c_ln = CollisionChecker(walker, leg_leg), CollisionChecker(walker, leg_nacelle)
    A = np.array([f.translation for f in st.footholds])
    rng = np.random.default_rng(3)
    q = walker.q_home
    for _ in range(4):
        M = pin.SE3(
            pin.exp3(rng.uniform(-0.12, 0.12, 3)), np.r_[0, 0, 0.6] + rng.uniform(-0.05, 0.05, 3)
        )
        q = pkdyn.inverse_geometry(pp, M * TOOL, q_init=q, check_limits=False).q
        coal_ll, coal_ln = c_ll.distances(q).min(), c_ln.distances(q).min()
        c = clearances(P4, M.rotation[None], M.translation[None], A[None])
        # leg to nacelle: distances of points of the legs, within the rim sampling
        assert coal_ln - 1e-9 <= c.leg_to_nacelle[0] <= coal_ln + 5e-4
        # legs as capsules: never farther apart than the cylinders, by less than two radii
        assert coal_ll - 2 * P4.cylinder_radius <= c.leg_to_leg[0] <= coal_ll + 1e-9
        assert np.allclose(c.lengths[0], q[walker.actuated_q], atol=1e-12)
        for b in (1, 4):
            be = mode_robot(walker, st, be_mode(walker, q, b), q)
            sing = clearances(P4, M.rotation[None], M.translation[None], A[None], b).singularity
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                assert sing[0] == pytest.approx(classify(be, q).distance, abs=1e-9)


def test_bumps_vanish_with_two_derivatives_at_the_ends():
    tau = np.linspace(0.0, 1.0, 2001)
    b, bd, bdd = bumps(tau, 3)
    for arr in (b, bd, bdd):
        assert np.allclose(arr[[0, -1]], 0.0, atol=1e-12)
    h = tau[1] - tau[0]
    assert np.allclose(np.gradient(b, h, axis=0)[5:-5], bd[5:-5], atol=1e-4)
    assert np.allclose(np.gradient(bd, h, axis=0)[5:-5], bdd[5:-5], atol=1e-3)


# --- the walk ------------------------------------------------------------------------------------


def test_walker_phase_sequence(report):
    names = [(r.name, r.mode, r.branch) for r in report.reports]
    assert names == [("machining", "PP", None)] + [
        x for b in (1, 2, 3, 4) for x in (("reconfiguration", "PP", None), ("swing", "BE", b))
    ] + [("reconfiguration", "PP", None)]
    for a, b in zip(report.phases, report.phases[1:], strict=False):
        assert np.allclose(a.trajectory.q[-1], b.trajectory.q[0], atol=1e-12)
        assert np.allclose(a.trajectory.v[-1], 0.0, atol=1e-12)


def test_locks_held_and_clamped_feet_fixed(walker, report):
    for ph in report.phases:
        for lk in ph.mode.locks:
            jm = walker.model.joints[walker.model.getJointId(lk.joint)]
            for c, v in zip(lk.coordinates, lk.values, strict=True):
                assert np.max(np.abs(ph.trajectory.q[:, jm.idx_q + c] - v)) < 1e-12
        for b in branch_numbers(walker):
            if b == ph.branch:
                continue
            F = ph.stance.footholds[b - 1]
            for q in ph.trajectory.q:
                M = foot_placement(walker, q, b)
                assert np.linalg.norm(M.translation - F.translation) < 1e-12
                assert np.linalg.norm(pin.log3(M.rotation.T @ F.rotation)) < 1e-12
    for r in report.reports:
        assert r.max_closure_residual < 1e-12
        assert r.max_support_drift < 1e-12 and r.max_lock_drift < 1e-12
        if r.name == "swing":
            assert r.lock_plan_error < 1e-9  # B_iIKMX gives the engaged locks


def test_the_walker_walks_by_the_step(walker, report):
    q0, q1 = report.q[0], report.q[-1]
    d = np.array([STEP[0], STEP[1], 0.0])
    for b in branch_numbers(walker):
        assert np.allclose(
            foot_placement(walker, q1, b).translation,
            foot_placement(walker, q0, b).translation + d,
            atol=1e-9,
        )
    assert np.allclose(report.nacelle[-1], report.nacelle[0] + d, atol=1e-9)


def test_swinging_foot_follows_its_path_and_the_nacelle_its_chosen_one(walker, report):
    for ph in report.phases:
        if ph.name != "swing":
            continue
        sol = ph.redundancy
        task = ph.trajectory.task
        R_F, p_F = foot_frames(task)
        for k, q in enumerate(ph.trajectory.q):
            M = foot_placement(walker, q, ph.branch)
            assert np.linalg.norm(M.translation - p_F[k]) < 1e-9
            assert np.linalg.norm(pin.log3(M.rotation.T @ R_F[k])) < 1e-9
            # the closed-form nacelle (locked branch) is where the constraint solver put it
            X = _nacelle(walker, q)
            assert np.linalg.norm(X.translation - sol.nacelle_p[k]) < 1e-9
            assert np.linalg.norm(pin.log3(X.rotation.T @ sol.nacelle_R[k])) < 1e-9
            # the redundant coordinates are the swinging branch's actuator lengths
            i = 2 * (ph.branch - 1)
            assert np.allclose(q[walker.actuated_q[i : i + 2]], sol.r[k], atol=1e-12)
        # rest to rest; r_dot and r_ddot are the derivatives of r
        assert np.allclose(sol.r_d[[0, -1]], 0.0, atol=1e-12)
        assert np.allclose(ph.trajectory.v[-1], 0.0, atol=1e-12)


def test_optimised_path_never_worse_than_the_baseline(walker, report):
    swings = [ph for ph in report.phases if ph.name == "swing"]
    gains = []
    for ph in swings:
        sol = ph.redundancy
        # the objective recomputed from the joint trajectory's nacelle and feet (FK)
        n = len(ph.stance.footholds)
        X = [_nacelle(walker, q) for q in ph.trajectory.q]
        A = np.array(
            [
                [foot_placement(walker, q, b).translation for b in range(1, n + 1)]
                for q in ph.trajectory.q
            ]
        )
        c = clearances(
            P4,
            np.array([x.rotation for x in X]),
            np.array([x.translation for x in X]),
            A,
            ph.branch,
        )
        phi = sol.settings.objective(c)
        assert phi == pytest.approx(sol.objective, abs=1e-9)
        assert phi >= sol.objective_baseline - 1e-12
        assert (
            c.singularity.min()
            >= min(sol.settings.singularity_keep, sol.baseline.singularity.min()) - 1e-9
        )
        gains.append(sol.objective - sol.objective_baseline)
        # the baseline: the branch's lengths at the foot's pace from engagement to landing
        s = (sol.t - sol.t[0]) / (sol.t[-1] - sol.t[0])
        law = s**3 * (10 - 15 * s + 6 * s**2)
        if not sol.optimised:
            assert np.allclose(sol.r, sol.r[0] + np.outer(law, sol.r[-1] - sol.r[0]), atol=1e-12)
    assert max(gains) > 1e-3  # the redundancy is used: a millimetre at least somewhere
    assert all(r.redundancy is not None for r in report.reports if r.name == "swing")


def test_forces_feasible_and_min_max_allocation(walker, report):
    effort = P4.effort
    for r in report.reports:
        assert 10.0 < r.max_actuator_force <= effort
        assert r.max_dynamics_residual < 1e-7
        assert r.min_stroke_margin > 0.05 and r.min_leg_distance > 0.0
    assert report.violations() == []
    assert report.tau.shape == (report.t.size, 8)
    # mode PP with the machining wrench: least largest force against a linear program over the
    # whole dynamics equation (efforts and closure forces free), independent of the solver's
    # null-space reduction
    ph = report.phases[0]
    pp = ph.robot
    W = ph.wrench
    k = int(np.argmax(np.abs(W).sum(axis=1)))
    jt = ph.trajectory
    one = pkdyn.dynamics.trajectory.JointTrajectory(
        jt.t[k : k + 1],
        jt.q[k : k + 1],
        jt.v[k : k + 1],
        jt.a[k : k + 1],
        pp.actuated_q,
        pp.actuated_v,
    )
    norm = inverse_dynamics(pp, one, wrench=W[k], progress=False).tau[0]
    mm = inverse_dynamics(pp, one, wrench=W[k], progress=False, allocation="max").tau[0]
    q, v, a = one.q[0], one.v[0], one.a[0]
    b = (
        pin.rnea(pp.model, pp.data, q, v, a)
        - pkdyn.analysis.kinematics.platform_jacobian(pp, q).T @ W[k]
    )
    J = pp.closure_set.jacobian(pp.data, q)
    S = actuation(pp).matrix(pp.nv)
    n_a, nc = S.shape[0], J.shape[0]
    # variables (tau, lambda, t): min t, S^T tau + J^T lambda = b, |tau_i| <= t
    A_eq = np.hstack([S.T, J.T, np.zeros((pp.nv, 1))])
    A_ub = np.vstack(
        [
            np.hstack([np.eye(n_a), np.zeros((n_a, nc)), -np.ones((n_a, 1))]),
            np.hstack([-np.eye(n_a), np.zeros((n_a, nc)), -np.ones((n_a, 1))]),
        ]
    )
    c = np.zeros(n_a + nc + 1)
    c[-1] = 1.0
    lp = linprog(
        c,
        A_ub=A_ub,
        b_ub=np.zeros(2 * n_a),
        A_eq=A_eq,
        b_eq=b,
        bounds=[(None, None)] * (n_a + nc + 1),
    )
    assert lp.status == 0
    assert np.max(np.abs(mm)) == pytest.approx(lp.fun, rel=1e-6, abs=1e-6)
    assert np.max(np.abs(mm)) <= np.max(np.abs(norm)) + 1e-9
    # both satisfy the equation: S^T tau - b in the range of J^T
    for tau in (norm, mm):
        y = b - S.T @ tau
        lam = np.linalg.lstsq(J.T, y, rcond=None)[0]
        assert np.max(np.abs(J.T @ lam - y)) < 1e-7


def test_min_max_allocation_along_the_machining(report):
    ph = report.phases[0]
    norm = inverse_dynamics(ph.robot, ph.trajectory, wrench=ph.wrench, progress=False)
    mm = inverse_dynamics(
        ph.robot, ph.trajectory, wrench=ph.wrench, progress=False, allocation="max"
    )
    assert np.max(mm.residual) < 1e-7
    peak_norm, peak_mm = np.max(np.abs(norm.tau), axis=1), np.max(np.abs(mm.tau), axis=1)
    assert np.all(peak_mm <= peak_norm + 1e-7)
    assert np.mean(peak_norm - peak_mm) > 0.1  # [N]: the least norm is not the least maximum
    with pytest.raises(pkdyn.InvalidInputError, match="allocation"):
        inverse_dynamics(ph.robot, ph.trajectory, progress=False, allocation="minmax")


def test_inverse_then_forward_dynamics_reproduces_the_swing(walker, report):
    ph = next(p for p in report.phases if p.name == "swing" and p.branch == 3)
    be, jt = ph.robot, ph.trajectory
    eff = inverse_dynamics(be, jt, progress=False)
    fd = ForwardDynamics(walker.model, list(be.constraint_models), actuation(be), project=False)
    for k in range(0, jt.t.size, 2):
        a = fd.acceleration(jt.q[k], jt.v[k], fd.actuation.generalized(eff.tau[k], walker.nv))
        assert np.max(np.abs(a - jt.a[k])) < 1e-6 * max(1.0, np.max(np.abs(jt.a)))


def test_power_balance_along_the_walk(report):
    """Actuator work = change of mechanical energy, phase by phase (locks and clamps do no work).

    Simpson's rule on the 0.25 s samples leaves ~0.3 % (1e-4 at 0.1 s: the error falls as
    h^4); a wrong force or a lock doing work would be of order one.
    """
    for ph in report.phases[1:]:  # the machining phase has its wrench switched on and off
        eff = inverse_dynamics(ph.robot, ph.trajectory, progress=False)
        power = np.sum(eff.tau * ph.trajectory.qa_dot, axis=1)
        work, idx = simpson_work(ph.trajectory.t, power)
        dE = eff.energy[idx] - eff.energy[0]
        scale = max(1.0, float(np.max(np.abs(dE))))
        assert np.max(np.abs(work - dE)) < 5e-3 * scale


# --- bad input ---------------------------------------------------------------------------------


def test_foothold_out_of_reach_names_phase_branch_and_stroke(walker):
    from pkdyn.tripod.scenario import plan_scenario

    with pytest.raises(pkdyn.TrajectoryError) as err:
        plan_scenario(walker, WalkPlan(step=(0.8, 0.0), cycles=1, dt=0.5, machining=None))
    msg = str(err.value)
    assert "phase 1" in msg and "swing of branch 1" in msg and "out of reach" in msg
    assert f"[{P4.stroke_min}, {P4.stroke_max}] m" in msg


def test_unavoidable_collision_names_phase_branch_and_bodies():
    from pkdyn.tripod.scenario import plan_scenario

    robot = pkdyn.load("tripod", branches=4, theta=0.74)
    with pytest.raises(pkdyn.TrajectoryError) as err:
        plan_scenario(robot, WalkPlan(cycles=1, dt=0.5, machining=None))
    msg = str(err.value)
    assert "swing of branch" in msg and "would interfere" in msg and "< 0" in msg
    assert "phase" in msg and "nacelle" in msg


# --- CLI, comparison ------------------------------------------------------------------------------


def test_cli_walker_json_has_the_phase_keys_and_the_objective(capsys):
    args = ["tripod", "scenario", "--branches", "4", "--cycles", "1", "--dt", "0.5"]
    assert main([*args, "--no-machining", "--stride", "4", "--allocation", "max", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    keys = {
        "mode",
        "branch",
        "locked",
        "max_closure_residual",
        "max_actuator_force",
        "min_leg_distance",
        "min_stroke_margin",
        "redundancy",
    }
    assert [p["branch"] for p in out["phases"]] == [None, 1, None, 2, None, 3, None, 4, None]
    for ph in out["phases"]:
        assert keys <= set(ph)
        if ph["mode"] == "BE":
            red = ph["redundancy"]
            assert len(ph["locked"]) == 4
            assert red["objective"] >= red["objective_baseline"]
            assert {"baseline", "chosen"} <= set(red)
        else:
            assert ph["redundancy"] is None
    assert out["summary"]["branches"] == 4 and out["summary"]["violations"] == []
    assert main([*args, "--no-machining", "--stride", "4", "--allocation", "max"]) == 0
    text = capsys.readouterr().out
    assert "objective: baseline -> chosen" in text and " mm -> " in text


def test_cli_walker_error_is_one_line(capsys):
    args = ["tripod", "scenario", "--branches", "4", "--cycles", "1", "--no-machining"]
    assert main([*args, "--step", "0.8", "0", "--dt", "0.5"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "swing of branch 1" in err[0] and "stroke" in err[0]


def test_comparison_table_json_and_plot(tmp_path):
    from pkdyn.plotting.tripod import plot_comparison

    cases = default_cases(WalkPlan(cycles=1, dt=0.5, machining=None))
    comp = compare_walkers(cases, stride=4, progress=False)
    assert [(r.robot, r.case) for r in comp.rows] == [
        ("tripod", "plane"),
        ("walker", "plane"),
        ("tripod", "cylinder R = 3 m"),
        ("walker", "cylinder R = 3 m"),
    ]
    rows = json.loads(json.dumps(comp.to_json()))["rows"]
    assert all(r["error"] is None and r["phases_with_violation"] == 0 for r in rows)
    tri, walk = comp.row("tripod", "plane").values(), comp.row("walker", "plane").values()
    assert walk["mass"] - tri["mass"] == pytest.approx(tri["swing_mass"], rel=1e-9)
    # the walker's neighbouring legs are 90 degrees apart instead of 120
    assert walk["min_leg_to_leg"] < tri["min_leg_to_leg"]
    assert "| plane | walker |" in comp.table()
    fig = plot_comparison(comp, path=tmp_path / "cmp.png")
    assert (tmp_path / "cmp.png").stat().st_size > 10_000 and len(fig.axes) == 6


def test_pp_kinematic_models_have_one_relation_per_actuator(walker):
    """Eight actuators for the nacelle's six coordinates: ``A`` 8 x 6, ``B`` 8 x 8.

    ``J_inv`` against central differences of the inverse geometric model (rates in the task
    convention: linear in world axes, angular in the nacelle frame). With only six relations
    kept, ``J_inv`` was off by 0.34 m/rad and the stance looked near-singular (margin 3e-4).
    """
    from pkdyn.analysis.kinematics import kinematic_models

    pp = mode_robot(walker, Stance.default(P4), pp_mode())
    M = pin.SE3(pin.exp3(np.array([0.05, -0.03, 0.02])), np.r_[0.01, 0.02, 0.6])
    q = pkdyn.inverse_geometry(pp, M * TOOL, q_init=walker.q_home, check_limits=False).q
    km = kinematic_models(pp, q)
    assert km.A.shape == (8, 6) and km.B.shape == (8, 8)
    x0 = pp.platform_placement(q)
    h = 1e-6
    J_fd = np.zeros((8, 6))
    for i in range(6):
        d = np.zeros(6)
        d[i] = h
        qa = [
            pkdyn.inverse_geometry(
                pp,
                pin.SE3(x0.rotation @ pin.exp3(s * d[3:]), x0.translation + s * d[:3]),
                q_init=q,
                check_limits=False,
            ).qa
            for s in (1.0, -1.0)
        ]
        J_fd[:, i] = (qa[0] - qa[1]) / (2 * h)
    assert np.max(np.abs(km.J_inv - J_fd)) < 1e-7
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = classify(pp, q)
    assert report.kind == "regular" and report.margin > 0.05
