"""Trajectories: motion laws, the Adept cycle, the closure drift, and the joint-space mapping."""

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.dynamics.profiles import motion_law
from pkdyn.dynamics.trajectory import (
    TaskTrajectory,
    adept_cycle,
    concatenate,
    map_task_trajectory,
    named_task,
    named_trajectory,
    point_to_point,
    sinusoid,
)
from pkdyn.exceptions import InvalidInputError, TrajectoryError

LIBRARY = ("delta", "gough_stewart", "planar_3rrr", "five_bar", "tripod")


@pytest.fixture(scope="module")
def robots() -> dict[str, pkdyn.Robot]:
    return {name: pkdyn.load(name, geometry=False) for name in LIBRARY}


# --------------------------------------------------------------------------- motion laws


@pytest.mark.parametrize("name", ["quintic", "jerk"])
def test_motion_law_is_rest_to_rest_and_differentiates(name):
    T = 0.7
    law = motion_law(name, T)
    t = np.linspace(0.0, T, 14001)
    s, sd, sdd = law(t)
    assert s[0] == 0.0 and s[-1] == pytest.approx(1.0, abs=1e-14)
    assert abs(sd[0]) + abs(sd[-1]) + abs(sdd[0]) + abs(sdd[-1]) < 1e-12
    h = t[1] - t[0]
    # central differences: s' and s'' are the derivatives (interior samples)
    assert np.max(np.abs(np.gradient(s, h) - sd)[1:-1]) < 1e-6 * np.max(sd)
    assert np.max(np.abs(np.gradient(sd, h) - sdd)[1:-1]) < 2e-3 * np.max(np.abs(sdd))
    assert np.all(np.diff(s) >= -1e-15)  # monotonic


@pytest.mark.parametrize(
    "fa, fj, v_max, a_max, j_max",
    [
        # closed forms of the double S (unit distance, duration T, symmetric acceleration
        # phase of length fa T with jerk ramps of fj fa T): v_max = 1 / (T - fa T),
        # a_max = v_max / (fa T - fj fa T), j = a_max / (fj fa T)
        (0.25, 0.5, 4.0 / 3.0, 32.0 / 3.0, 256.0 / 3.0),  # triangular acceleration
        (1.0 / 3.0, 1.0 / 3.0, 1.5, 27.0 / 4.0, 243.0 / 4.0),  # the default law
    ],
)
def test_quintic_peaks_and_jerk_law_closed_forms(fa, fj, v_max, a_max, j_max):
    T = 0.5
    t = np.linspace(0.0, T, 100001)
    _, sd, sdd = motion_law("quintic", T)(t)
    assert np.max(sd) == pytest.approx(1.875 / T, rel=1e-8)
    assert np.max(sdd) == pytest.approx(10.0 / np.sqrt(3.0) / T**2, rel=1e-6)
    _, sd, sdd = motion_law("jerk", T, accel_fraction=fa, jerk_fraction=fj)(t)
    assert np.max(sd) == pytest.approx(v_max / T, rel=1e-12)
    assert np.max(sdd) == pytest.approx(a_max / T**2, rel=1e-8)
    # the jerk (differences of s'') is +j, 0 or -j away from the breakpoints
    jerk = np.diff(sdd) / np.diff(t)
    tm = 0.5 * (t[1:] + t[:-1])
    knots = T * np.array([0.0, fj * fa, fa - fj * fa, fa, 1 - fa, 1 - fa + fj * fa, 1 - fj * fa, 1])
    away = np.min(np.abs(tm[:, None] - knots[None]), axis=1) > 2 * (t[1] - t[0])
    level = np.array([1, 0, -1, 0, -1, 0, 1])[np.searchsorted(knots, tm[away]) - 1]
    np.testing.assert_allclose(jerk[away], level * j_max / T**3, atol=1e-6 * j_max / T**3)
    assert np.max(np.abs(jerk)) <= j_max / T**3 * (1 + 1e-6)
    # constant velocity between the acceleration phases
    mid = (t > fa * T) & (t < (1 - fa) * T)
    assert np.ptp(sd[mid]) < 1e-9 and np.max(np.abs(sdd[mid])) < 1e-9


def test_motion_law_rejects_bad_values():
    with pytest.raises(InvalidInputError, match="profile"):
        motion_law("cubic", 1.0)
    with pytest.raises(InvalidInputError, match="duration"):
        motion_law("quintic", 0.0)
    with pytest.raises(InvalidInputError, match="accel_fraction"):
        motion_law("jerk", 1.0, accel_fraction=0.7)


# --------------------------------------------------------------------------- task trajectories


@pytest.mark.parametrize("overlap", [0.0, 0.5])
def test_adept_cycle_geometry(overlap):
    bottom = np.array([0.01, -0.02, -0.4])
    cyc = adept_cycle(bottom, cycle_time=0.6, overlap=overlap, dt=1e-4)
    p = cyc.pose[:, :3]
    assert cyc.duration == pytest.approx(0.6)
    np.testing.assert_allclose(p[0], bottom - [0.1525, 0, 0], atol=1e-15)
    np.testing.assert_allclose(p[-1], p[0], atol=1e-12)
    assert np.ptp(p[:, 0]) == pytest.approx(0.305, abs=1e-12)
    assert np.max(p[:, 2]) == pytest.approx(bottom[2] + 0.025, abs=1e-12)
    assert np.ptp(p[:, 1]) == 0.0 and np.all(cyc.pose[:, 3:] == 0.0)
    # at rest at both ends and at the far end of the line
    half = cyc.t.size // 2
    for k in (0, half, -1):
        assert np.max(np.abs(cyc.pose_d[k])) < 1e-12 and np.max(np.abs(cyc.pose_dd[k])) < 1e-9
    # velocities and accelerations are the derivatives of the path
    h = cyc.t[1] - cyc.t[0]
    assert np.max(np.abs(np.gradient(p, h, axis=0) - cyc.pose_d[:, :3])[1:-1]) < 1e-4
    dv = np.gradient(cyc.pose_d[:, :3], h, axis=0)
    assert np.max(np.abs(dv - cyc.pose_dd[:, :3])[1:-1]) < 1e-2 * np.max(np.abs(cyc.pose_dd))
    vertical = np.abs(cyc.pose_d[:, 2]) > 1e-9
    horizontal = np.abs(cyc.pose_d[:, 0]) > 1e-9
    if overlap == 0.0:  # straight segments: never both at once
        assert not np.any(vertical & horizontal)
    else:  # rounded corners
        assert np.any(vertical & horizontal)


def test_sinusoid_and_concatenate():
    s = sinusoid([0, 0, 0.5], [0.01, 0, 0, 0, 0, 0.02], 2.0, 1.0, dt=1e-3)
    assert np.max(s.pose[:, 0]) == pytest.approx(0.01, rel=1e-6)
    np.testing.assert_allclose(s.pose_dd[:, 5], -((4 * np.pi) ** 2) * (s.pose[:, 5]), atol=1e-12)
    a = point_to_point([0, 0, 0], [0.1, 0, 0], 0.5)
    b = point_to_point([0.1, 0, 0], [0.1, 0.1, 0], 0.5)
    c = concatenate([a, b])
    assert c.duration == pytest.approx(1.0) and c.t.size == a.t.size + b.t.size - 1
    assert np.all(np.diff(c.t) > 0)
    with pytest.raises(InvalidInputError, match="part 1 starts"):
        concatenate([a, a])


def test_task_trajectory_rejects_nan():
    t = np.linspace(0, 1, 5)
    pose = np.zeros((5, 6))
    pose[3, 2] = np.nan
    with pytest.raises(TrajectoryError, match="sample 3"):
        TaskTrajectory(t, pose, np.zeros((5, 6)), np.zeros((5, 6)))


# --------------------------------------------------------------------------- closure drift


@pytest.mark.parametrize("name", LIBRARY)
def test_closure_drift_is_the_second_derivative(robots, name):
    """d^2 r/dt^2 = J a + gamma along q(t) = integrate(q, t v + t^2 a / 2), central differences."""
    robot = robots[name]
    cs, model = robot.closure_set, robot.model
    data = model.createData()
    rng = np.random.default_rng(3)
    q = robot.q_home
    J = cs.jacobian(data, q)
    _, s, Vt = np.linalg.svd(J)
    Z = Vt[int(np.sum(s > 1e-9 * s[0])) :].T
    v = Z @ rng.normal(size=Z.shape[1])  # consistent velocity (welds need it)
    a = rng.normal(size=model.nv)
    gamma = cs.drift(data, q, v)
    h = 1e-4

    def r(t):
        return cs.residual(data, pin.integrate(model, q, t * v + 0.5 * t * t * a))

    fd = (r(h) - 2 * r(0.0) + r(-h)) / h**2
    J = cs.jacobian(data, q)
    assert np.max(np.abs(fd - (J @ a + gamma))) < 1e-6 * max(1.0, np.max(np.abs(fd)))
    assert np.max(np.abs(gamma)) > 1e-3  # the drift is not trivially zero


# --------------------------------------------------------------------------- joint-space mapping


def _fd_errors(robot, jt):
    """Largest mismatch of the trapezoidal rule between samples: q against v, v against a.

    (``q_k+1`` against ``integrate(q_k, h (v_k + v_k+1) / 2)``; the other order,
    ``difference(q_k, q_k+1)``, is unreliable here: Pinocchio 4.1 returns a zero angle for the
    planar joint when the relative rotation is ~1e-7 rad.)
    """
    h = jt.t[1] - jt.t[0]
    model = robot.model
    vm = 0.5 * (jt.v[1:] + jt.v[:-1])
    ev = (
        max(
            np.max(
                np.abs(pin.difference(model, pin.integrate(model, jt.q[k], h * vm[k]), jt.q[k + 1]))
            )
            for k in range(jt.t.size - 1)
        )
        / h
    )
    ea = np.max(np.abs(np.diff(jt.v, axis=0) / h - 0.5 * (jt.a[1:] + jt.a[:-1])))
    return ev, ea


@pytest.mark.parametrize(
    ("name", "traj"),
    [("delta", "p2p"), ("gough_stewart", "sine"), ("planar_3rrr", "p2p"), ("tripod", "p2p")],
)
def test_mapping_is_consistent_with_closures_task_and_time(robots, name, traj):
    """Every sample closed, on the task, velocity tangent, and (q, v, a) integrate each other:
    the central-difference mismatch falls like h^2 for every coordinate, internal mobilities
    (the Delta's bar spins) included."""
    robot = robots[name]
    errs = []
    for dt in (2e-3, 1e-3):
        kw = {"duration": 0.4} if traj == "p2p" else {"duration": 0.4, "frequency": 2.5}
        jt = named_trajectory(robot, traj, dt=dt, check_limits=False, **kw)
        errs.append(_fd_errors(robot, jt))
    ev, ea = np.array(errs).T
    assert ev[1] < 0.35 * ev[0] and ea[1] < 0.35 * ea[0]  # second order
    assert ev[1] < 1e-3 * np.max(np.abs(jt.v)) and ea[1] < 1e-2 * np.max(np.abs(jt.a))
    data = robot.model.createData()
    cs = robot.closure_set
    assert jt.task is not None
    for k in range(0, jt.t.size, 20):
        q, v = jt.q[k], jt.v[k]
        assert np.max(np.abs(cs.residual(data, q))) < 1e-10
        assert np.max(np.abs(cs.jacobian(data, q) @ v)) < 1e-9
        M = robot.platform_placement(q)
        target = jt.task.pose[k]
        err = np.concatenate(
            [M.translation - target[:3], pin.log3(pin.rpy.rpyToMatrix(target[3:]).T @ M.rotation)]
        )
        assert np.max(np.abs(err[robot.task_rows])) < 1e-9


def test_out_of_reach_trajectory_names_the_sample(robots):
    robot = robots["delta"]
    task = named_task(robot, "p2p", offset=[0.0, 0.0, -0.5], duration=0.5, dt=5e-3)
    with pytest.raises(TrajectoryError, match=r"sample \d+ \(t = [\d.]+ s\): pose out of reach"):
        map_task_trajectory(robot, task, check_limits=False)


def test_too_fast_trajectory_names_the_actuator(robots):
    robot = robots["delta"]
    with pytest.raises(TrajectoryError, match=r"actuator 'motor\d' would move at .* limit"):
        named_trajectory(robot, "adept", cycle_time=0.3)
    # without the limit check it maps (the sizing then reports a negative speed margin)
    jt = named_trajectory(robot, "adept", cycle_time=0.3, check_limits=False, dt=5e-3)
    assert np.max(np.abs(jt.qa_dot)) > 15.0


def test_trajectory_through_a_parallel_singularity_is_refused():
    """Five-bar with both elbows on the left: along y = 0.3 m, the distal links align (parallel
    singularity, det J_inv changes sign) between x = 0.25 and 0.275 m."""
    robot = pkdyn.load("five_bar", geometry=False, working_mode="++")
    task = point_to_point([0.0, 0.3, 0.0], [0.29, 0.3, 0.0], 0.5, dt=5e-3)
    with pytest.raises(TrajectoryError, match=r"sample \d+ .*crosses a parallel singularity"):
        map_task_trajectory(robot, task, check_limits=False)
    # the same move stopping short of it maps
    ok = point_to_point([0.0, 0.3, 0.0], [0.24, 0.3, 0.0], 0.5, dt=5e-3)
    map_task_trajectory(robot, ok, check_limits=False)


def test_named_trajectory_rejects_unknown_names_and_options(robots):
    with pytest.raises(InvalidInputError, match="unknown trajectory"):
        named_trajectory(robots["delta"], "circle")
    with pytest.raises(InvalidInputError, match="adept"):
        named_trajectory(robots["delta"], "adept", speed=3)


@pytest.mark.parametrize(
    ("name", "options", "needle"),
    [
        ("adept", {"cycle_time": "fast"}, "cycle_time"),
        ("adept", {"cycles": 1.5}, "cycles"),
        ("sine", {"frequency": 0.0}, "frequency"),
        ("sine", {"amplitude": float("nan")}, "amplitude"),
        ("p2p", {"duration": [1.0]}, "duration"),
        ("p2p", {"profile": "bang"}, "profile"),
    ],
)
def test_named_task_validates_its_options(robots, name, options, needle):
    with pytest.raises(InvalidInputError, match=needle):
        named_task(robots["delta"], name, **options)
