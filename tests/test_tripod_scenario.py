"""The tripod's machining-and-walking scenario and its checks (issue 8, items 4-5), CLI and plot.

Each check of the report is recomputed here from the sampled configurations by other means:
joint coordinates for the locks, forward kinematics for the feet and the nacelle, the
parameters' strokes, analytic segment distances for the legs.
"""

import json
import math

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.collisions import segment_distance
from pkdyn.cli import main
from pkdyn.library import tripod
from pkdyn.tripod import BRANCHES, foot_placement
from pkdyn.tripod.analysis import LEGS, run_scenario
from pkdyn.tripod.machining import MachiningPlan
from pkdyn.tripod.scenario import WalkPlan

P = tripod.Params()
STEP = (0.08, 0.02)
PLAN = WalkPlan(
    step=STEP,
    cycles=1,
    dt=0.1,
    machining=MachiningPlan(move_time=0.6, plunge_time=0.4, contour_time=1.2),
)


@pytest.fixture(scope="module")
def robot() -> pkdyn.Robot:
    return pkdyn.load("tripod")


@pytest.fixture(scope="module")
def report(robot):
    return run_scenario(robot, PLAN, stride=2, progress=False)


def test_phase_sequence_and_one_branch_detached_at_most(report):
    names = [(r.name, r.mode, r.branch) for r in report.reports]
    assert names == [
        ("machining", "PP", None),
        ("reconfiguration", "PP", None),
        ("swing", "BE", 1),
        ("reconfiguration", "PP", None),
        ("swing", "BE", 2),
        ("reconfiguration", "PP", None),
        ("swing", "BE", 3),
        ("reconfiguration", "PP", None),
    ]
    for ph in report.phases:
        clamped = [o for o in ph.robot.constraint_owner if o.endswith("_foothold")]
        assert len(clamped) == (2 if ph.mode.kind == "BE" else 3)
        assert (len(ph.mode.locks) > 0) == (ph.mode.kind == "BE")
    # phases join at rest
    for a, b in zip(report.phases, report.phases[1:], strict=False):
        assert np.allclose(a.trajectory.q[-1], b.trajectory.q[0], atol=1e-12)
        assert np.allclose(a.trajectory.v[-1], 0.0, atol=1e-12)
        assert b.t0 == pytest.approx(a.t0 + a.trajectory.t[-1])


def test_the_robot_walks_by_the_step(robot, report):
    q0, q1 = report.q[0], report.q[-1]
    d = np.array([STEP[0], STEP[1], 0.0])
    for b in BRANCHES:
        assert np.allclose(
            foot_placement(robot, q1, b).translation,
            foot_placement(robot, q0, b).translation + d,
            atol=1e-9,
        )
    # the nacelle ends level above the new centroid, as it started above the old one
    assert np.allclose(report.nacelle[-1], report.nacelle[0] + d, atol=1e-9)
    for ph in report.phases:
        if ph.name == "swing":
            foot = foot_placement(robot, ph.trajectory.q[-1], ph.branch)
            assert np.linalg.norm(foot.translation - ph.landing.translation) < 1e-10


def test_locked_joints_constant_while_locked(robot, report):
    for ph in report.phases:
        if not ph.mode.locks:
            continue
        for lk in ph.mode.locks:
            jm = robot.model.joints[robot.model.getJointId(lk.joint)]
            for c, v in zip(lk.coordinates, lk.values, strict=True):
                values = ph.trajectory.q[:, jm.idx_q + c]
                assert np.max(np.abs(values - v)) < 1e-10
                assert np.max(np.abs(values - values[0])) < 1e-10
    assert max(r.max_lock_drift for r in report.reports) < 1e-10
    # the locks engaged at B_iIKMX's b_i, and the swing ended at the planned nacelle pose
    for r in report.reports:
        if r.name == "swing":
            assert r.lock_plan_error < 1e-9
        if r.end_error is not None:
            assert r.end_error < 1e-9


def test_support_feet_fixed_and_closures_kept(robot, report):
    for ph in report.phases:
        for b in BRANCHES:
            if b == ph.branch:
                continue
            F = ph.stance.footholds[b - 1]
            for q in ph.trajectory.q[::3]:
                M = foot_placement(robot, q, b)
                assert np.linalg.norm(M.translation - F.translation) < 1e-10
                assert np.linalg.norm(pin.log3(M.rotation.T @ F.rotation)) < 1e-10
    for r in report.reports:
        assert r.max_closure_residual < 1e-10
        assert r.max_support_drift < 1e-10


def test_stroke_margins_from_the_parameters(report):
    k = 0
    for ph, r in zip(report.phases, report.reports, strict=True):
        qa = ph.trajectory.qa
        margin = np.minimum(qa - P.stroke_min, P.stroke_max - qa).min(axis=1)
        assert r.min_stroke_margin == pytest.approx(margin.min(), abs=1e-9)
        assert np.allclose(report.stroke_margin[k : k + margin.size], margin, atol=1e-9)
        k += margin.size
    assert min(r.min_stroke_margin for r in report.reports) > 0.05


def _leg_segments(robot: pkdyn.Robot, q: np.ndarray) -> dict[str, tuple]:
    """Axis end points and radius of every leg cylinder, from the geometry placements."""
    gm = robot.collision_model
    gd = pin.GeometryData(gm)
    pin.updateGeometryPlacements(robot.model, robot.data, gm, gd, q)
    out = {}
    for k, g in enumerate(gm.geometryObjects):
        link = robot.model.frames[g.parentFrame].name
        if any(link.endswith(n) for n in LEGS):
            M = gd.oMg[k]
            half = 0.5 * g.geometry.halfLength * 2.0
            ends = [M.act(np.array([0.0, 0.0, s * half])) for s in (-1.0, 1.0)]
            out[link] = (ends[0], ends[1], g.geometry.radius)
    return out


def test_leg_distances_agree_with_segment_bounds(robot, report):
    """For cylinders of radius r1, r2 around segments at distance d: d - r1 - r2 <= dist <= d;
    for the nearly parallel legs of neighbouring branches the lower bound is attained."""
    for ph in report.phases[::2]:
        q = ph.trajectory.q[ph.trajectory.t.size // 2]
        seg = _leg_segments(robot, q)
        rep = pkdyn.analysis.collisions.distance_report(
            robot, q, pairs=[(a, b) for a in seg for b in seg if a[:7] < b[:7]]
        )
        for pair in rep.pairs:
            a = robot.model.frames[
                robot.collision_model.geometryObjects[
                    robot.collision_model.getGeometryId(pair.a)
                ].parentFrame
            ].name
            b = robot.model.frames[
                robot.collision_model.geometryObjects[
                    robot.collision_model.getGeometryId(pair.b)
                ].parentFrame
            ].name
            p1, q1, r1 = seg[a]
            p2, q2, r2 = seg[b]
            d = float(segment_distance(p1[None], q1[None], p2[None], q2[None])[0][0])
            assert d - r1 - r2 - 1e-9 <= pair.distance <= d + 1e-9
        closest = rep.pairs[0]
        assert closest.distance > 0.3  # legs of different branches stay far apart
    assert min(r.min_leg_to_leg for r in report.reports) > 0.3
    assert 0.0 < min(r.min_leg_to_nacelle for r in report.reports) < 0.05


def test_singularity_margins_and_efforts(report):
    for r in report.reports:
        assert r.min_singularity_distance > 0.05
        assert r.max_dynamics_residual < 1e-8
    # recorded figures of this plan [N] (largest |force| per phase; the limit is 3000 N)
    recorded = [307.3, 93.45, 344.08, 93.76, 358.48, 82.46, 370.71, 72.84]
    assert [r.max_actuator_force for r in report.reports] == pytest.approx(recorded, rel=1e-3)
    # the released branch hangs on the supports: the swings load the actuators most
    swing = max(r.max_actuator_force for r in report.reports if r.mode == "BE")
    reconf = max(r.max_actuator_force for r in report.reports if r.name == "reconfiguration")
    assert swing > reconf
    assert report.violations() == []
    assert report.tau.shape == (report.t.size, 6)
    assert np.isfinite(report.singularity_distance).sum() >= report.t.size // 2


def test_forces_at_rest_are_the_gradient_of_the_potential_energy(report):
    """Virtual work: each phase starts at rest without machining wrench, where the actuator
    forces must be dV/dqa, V the potential energy of the mechanism assembled by the direct
    geometric model of the phase's robot (central differences)."""
    h = 1e-5
    for i, ph in enumerate(report.phases):
        jt, r = ph.trajectory, ph.robot
        assert np.max(np.abs(jt.v[0])) == 0.0 and np.max(np.abs(jt.a[0])) == 0.0
        assert ph.wrench is None or np.max(np.abs(ph.wrench[0])) == 0.0
        tau = report.tau[np.flatnonzero(report.phase == i)[0]]
        q = jt.q[0]
        qa = q[r.actuated_q]
        data = r.model.createData()
        grad = np.zeros(qa.size)
        for j in range(qa.size):
            dq = np.zeros(qa.size)
            dq[j] = h
            V = [
                pin.computePotentialEnergy(
                    r.model, data, pkdyn.forward_geometry(r, qa + s * dq, q_init=q).q
                )
                for s in (1.0, -1.0)
            ]
            grad[j] = (V[0] - V[1]) / (2 * h)
        np.testing.assert_allclose(tau, grad, atol=1e-7 * np.max(np.abs(grad)))


def test_report_json_has_the_phase_keys(report):
    out = json.loads(json.dumps(report.to_json()))
    keys = {
        "mode",
        "branch",
        "locked",
        "max_closure_residual",
        "max_actuator_force",
        "min_leg_distance",
        "min_stroke_margin",
    }
    for ph in out["phases"]:
        assert keys <= set(ph)
        assert ph["mode"] in ("PP", "BE")
        assert (ph["branch"] is None) == (ph["mode"] == "PP")
        assert (len(ph["locked"]) == 6) == (ph["mode"] == "BE")
    assert out["phases"][2]["locked"] == [
        "branch1_q1",
        "branch1_q2",
        "branch1_q3",
        "branch1_q6",
        "branch2_q1",
        "branch3_q1",
    ]
    assert out["summary"]["violations"] == []


def test_plot(report, tmp_path):
    from pkdyn.plotting.tripod import plot_scenario

    path = tmp_path / "scenario.png"
    fig = plot_scenario(report, path=path)
    assert path.stat().st_size > 10_000
    assert len(fig.axes) == 4


def test_cli_scenario_json_and_plot(tmp_path, capsys):
    png = tmp_path / "walk.png"
    args = ["tripod", "scenario", "--cycles", "1", "--dt", "0.25", "--no-machining"]
    assert main([*args, "--stride", "4", "--json", "--plot", str(png)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [p["mode"] for p in out["phases"]] == ["PP", "BE"] * 3 + ["PP"]
    assert [p["branch"] for p in out["phases"]] == [None, 1, None, 2, None, 3, None]
    assert png.stat().st_size > 10_000
    assert main(args) == 0
    assert "swing" in capsys.readouterr().out


def test_cli_html_animation(tmp_path):
    pytest.importorskip("pkdyn.viewer")
    html = tmp_path / "walk.html"
    args = ["tripod", "scenario", "--cycles", "1", "--dt", "0.5", "--no-machining"]
    assert main([*args, "--stride", "8", "--html", str(html)]) == 0
    text = html.read_text()
    assert text.lstrip().lower().startswith("<!doctype html") or "<html" in text[:500].lower()
    assert len(text) > 10_000


@pytest.mark.parametrize(
    ("args", "what"),
    [
        (["--dt", "0"], "dt"),
        (["--cycles", "0"], "cycles"),
        (["--param", "r_p=-1"], "r_p"),
        (["--stride", "0"], "stride"),
        (["--lift", "0.25", "--dt", "0.5"], "not feasible"),
        (["--step", "0.8", "0", "--dt", "0.5"], "shorten the step"),
    ],
)
def test_cli_errors_are_one_line(args, what, capsys):
    base = ["tripod", "scenario", "--cycles", "1", "--no-machining"]
    assert main([*base, *args]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and what in err[0]


def test_walk_across_a_curved_support(robot):
    """Cylinder of radius 3 m (axis y) crossed along x: the feet land with new attitudes."""
    radius = 3.0
    plan = WalkPlan(step=(0.1, 0.0), cycles=1, dt=0.25, machining=None, surface_radius=radius)
    rep = run_scenario(robot, plan, stride=4, progress=False)
    assert rep.violations() == []
    for ph, r in zip(rep.phases, rep.reports, strict=True):
        assert r.max_closure_residual < 1e-10 and r.max_support_drift < 1e-10
        assert r.max_lock_drift < 1e-10
        if ph.name == "swing":
            foot = foot_placement(robot, ph.trajectory.q[-1], ph.branch)
            # on the cylinder: the sole normal points away from the axis, A is foot_height out
            axis_point = np.array([0.0, foot.translation[1], -radius])
            n = foot.translation - axis_point
            assert np.linalg.norm(n) == pytest.approx(radius + P.foot_height, abs=1e-9)
            assert np.allclose(foot.rotation[:, 2], n / np.linalg.norm(n), atol=1e-9)
            start = ph.stance.footholds[ph.branch - 1]
            turn = np.linalg.norm(pin.log3(start.rotation.T @ foot.rotation))
            assert turn == pytest.approx(0.1 / radius, abs=1e-9)  # arc step / radius


def test_swing_task_turns_the_foot_with_consistent_rates():
    from pkdyn.tripod.scenario import foothold, swing_task

    a = foothold(P, 0.7, 0.0, 0.0, 2.0)
    b = foothold(P, 0.8, 0.02, 0.1, 2.0)
    task = swing_task(a, b, 0.03, 1.0, 0.002)
    R = [pin.rpy.rpyToMatrix(x[3:]) for x in task.pose]
    dt = task.t[1] - task.t[0]
    for k in range(1, task.t.size - 1, 50):
        w_fd = pin.log3(R[k - 1].T @ R[k + 1]) / (2 * dt)  # local angular velocity
        E = pin.rpy.computeRpyJacobian(task.pose[k, 3:], pin.ReferenceFrame.LOCAL)
        assert np.allclose(E @ task.pose_d[k, 3:], w_fd, atol=1e-5)
        rd_fd = (task.pose_d[k + 1] - task.pose_d[k - 1]) / (2 * dt)
        assert np.allclose(task.pose_dd[k], rd_fd, atol=1e-3)
    assert np.allclose(task.pose[0, :3], a.translation) and np.allclose(
        task.pose[-1, :3], b.translation
    )


def test_wrong_robot_and_plan_values():
    five = pkdyn.load("five_bar", geometry=False)
    with pytest.raises(pkdyn.PkdynError, match="library tripod"):
        run_scenario(five, PLAN)
    with pytest.raises(pkdyn.InvalidInputError):
        WalkPlan(step=(math.nan, 0.0))
    with pytest.raises(pkdyn.InvalidInputError):
        WalkPlan(tilt=-0.1)
    with pytest.raises(pkdyn.InvalidInputError):
        WalkPlan(surface_radius=0.5)
