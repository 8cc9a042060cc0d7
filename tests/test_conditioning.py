"""Singular passages of a simulation: the conditioning figure, its events, the forces there.

Checked against what does not come from the code under test: the conditioning against a
numpy SVD of the closure Jacobian in the mass metric (and its invariance when the robot is
scaled), the crossing of a parallelogram four-bar through its flat configuration against the
closed-form motion (uniform rotation: the crossing time is ``(pi / 2) / omega``), the Delta's
crossings against the coplanarity of its parallelograms' normals, the forces near a crossing
against a dense KKT solve, the estimated bottom of a passage against synthetic samples.
"""

import math
import warnings

import numpy as np
import pinocchio as pin
import pytest
from conftest import null_space, parallelogram_normals_det

import pkdyn
from pkdyn.analysis.kinematics import NEAR_SINGULAR_TOL, SINGULAR_TOL
from pkdyn.dynamics import ForwardDynamics, simulate
from pkdyn.exceptions import InvalidInputError, SimulationError
from solvers import ForwardDynamics as SolverDynamics
from solvers import forward_dynamics as fd_module
from solvers.conditioning import (
    LEAVE,
    NEAR_SINGULAR,
    SINGULAR,
    THROUGH,
    Passages,
    SingularityEvent,
)

L, D = 0.2, 0.4  # the parallelogram's cranks and coupler [m]


def _rod(name: str, length: float, mass: float = 0.5) -> str:
    i = mass * length**2 / 12
    return (
        f'<link name="{name}"><inertial><origin xyz="{length / 2} 0 0"/>'
        f'<mass value="{mass}"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="{i}" iyz="0" '
        f'izz="{i}"/></inertial></link>'
    )


PARALLELOGRAM = f"""<?xml version="1.0"?>
<robot name="parallelogram" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="base"/>
  {_rod("crank1", L)}{_rod("coupler", D)}{_rod("crank2", L)}
  <joint name="a" type="continuous"><parent link="base"/><child link="crank1"/>
    <origin xyz="0 0 0" rpy="0 0 {math.pi / 2}"/><axis xyz="0 0 1"/></joint>
  <joint name="b" type="continuous"><parent link="crank1"/><child link="coupler"/>
    <origin xyz="{L} 0 0" rpy="0 0 {-math.pi / 2}"/><axis xyz="0 0 1"/></joint>
  <joint name="c" type="continuous"><parent link="base"/><child link="crank2"/>
    <origin xyz="{D} 0 0" rpy="0 0 {math.pi / 2}"/><axis xyz="0 0 1"/></joint>
  <pkdyn:closure name="pin" type="point">
    <pkdyn:frame link="coupler" xyz="{D} 0 0"/><pkdyn:frame link="crank2" xyz="{L} 0 0"/>
  </pkdyn:closure>
</robot>"""
"""A parallelogram four-bar in the horizontal plane (gravity does no work), square at q = 0.

Its cranks turn together, the coupler translates: the kinetic energy is
``(I_crank1 + I_crank2 + m_coupler L^2) omega^2 / 2`` at any crank angle, so a free motion is a
uniform rotation. At crank angles of +-pi/2 from the square every link lies on the base line:
the point closure loses a rank (the flat configuration, where the parallelogram may continue
as an anti-parallelogram), and the motion crosses it needing no force along the lost
direction."""


@pytest.fixture(scope="module")
def parallelogram() -> pkdyn.Robot:
    return pkdyn.load_string(PARALLELOGRAM, "parallelogram.urdf", geometry=False)


@pytest.fixture(scope="module")
def robots() -> dict[str, pkdyn.Robot]:
    return {
        name: pkdyn.load(name, geometry=False)
        for name in ("delta", "gough_stewart", "five_bar", "tripod")
    }


def _independent_kappa(robot: pkdyn.Robot, q: np.ndarray, rank: int, length: float) -> float:
    """sigma_r / sigma_1 of ``S J M^-1/2``, numpy only (``M = C C^T``: ``J C^-T``)."""
    model, data = robot.model, robot.model.createData()
    J = robot.closure_set.jacobian(data, q)[: robot.closure_set.n_rigid]
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    s = np.concatenate(
        [[1.0] * 3 if cm.type == pin.ContactType.CONTACT_3D else [1.0] * 3 + [length] * 3
         for cm in robot.constraint_models]
    )  # fmt: skip
    C = np.linalg.cholesky(M)
    sigma = np.linalg.svd(np.linalg.solve(C, (s[:, None] * J).T).T, compute_uv=False)
    return float(sigma[rank - 1] / sigma[0])


def _nearby(robot: pkdyn.Robot, seed: int, spread: float = 0.05) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q = pin.integrate(robot.model, robot.q_home, spread * rng.standard_normal(robot.nv))
    return pkdyn.project(robot, q, tol=1e-12)


# --------------------------------------------------------------------------- the figure


def test_thresholds_are_the_kinematic_analysis_ones():
    """One rule: near and singular mean the same in the dynamics as in the kinematics."""
    assert NEAR_SINGULAR == NEAR_SINGULAR_TOL
    assert SINGULAR == SINGULAR_TOL
    assert SINGULAR < THROUGH < NEAR_SINGULAR


@pytest.mark.parametrize("name", ["delta", "gough_stewart", "five_bar", "tripod"])
def test_kappa_is_the_closures_singular_value_ratio_in_the_mass_metric(robots, name):
    """At home and at assembled configurations around it: kappa from the factorization of the
    dynamics equals sigma_r / sigma_1 of the scaled closure Jacobian in the mass metric (numpy
    SVD), r the generic rank (the five-bar's planar loop: 2 of 6 rows; the tripod: 24 of 36,
    with welds whose angular rows weigh by the robot's length)."""
    robot = robots[name]
    fd = SolverDynamics(robot.model, robot.constraint_models, length_scale=robot.length_scale)
    rank = fd.reference_rank(robot.q_home)
    nrows = robot.closure_set.n_rigid
    assert rank == nrows - (nrows - robot.nv + robot.mobility())  # the closures' rank at home
    zero = np.zeros(robot.nv)
    for k, q in enumerate([robot.q_home, _nearby(robot, 1), _nearby(robot, 2)]):
        fd.acceleration(q, zero, zero)
        kappa = fd._kappa()
        ref = _independent_kappa(robot, q, rank, robot.length_scale)
        assert 0.0 < kappa <= 1.0
        assert kappa == pytest.approx(ref, rel=1e-8), k


def test_kappa_is_the_same_for_the_robot_at_any_size(robots):
    """The tripod (prismatic legs, a free-flying nacelle, welded feet) scaled by 3 in every
    length, with the same masses, has the same conditioning at the corresponding
    configuration: translations and moments are weighed by the robot's own length."""
    robot = robots["tripod"]
    k = 3.0
    model = pin.Model(robot.model)
    for j in range(model.njoints):
        M = model.jointPlacements[j]
        model.jointPlacements[j] = pin.SE3(M.rotation, k * M.translation)
        I = model.inertias[j]
        model.inertias[j] = pin.Inertia(I.mass, k * I.lever, k * k * I.inertia)
    q = _nearby(robot, 3)
    qk = q.copy()
    armature = model.armature.copy()
    for j in range(1, model.njoints):
        jm = model.joints[j]
        kind = jm.shortname()
        if kind == "JointModelFreeFlyer":
            qk[jm.idx_q : jm.idx_q + 3] *= k
            armature[jm.idx_v + 3 : jm.idx_v + 6] *= k * k
        elif kind.startswith("JointModelP"):
            qk[jm.idx_q] *= k
        else:
            armature[jm.idx_v : jm.idx_v + jm.nv] *= k * k
    model.armature = armature
    constraints = []
    for cm in robot.constraint_models:
        c = pin.RigidConstraintModel(cm)
        c.joint1_placement = pin.SE3(
            cm.joint1_placement.rotation, k * cm.joint1_placement.translation
        )
        c.joint2_placement = pin.SE3(
            cm.joint2_placement.rotation, k * cm.joint2_placement.translation
        )
        constraints.append(c)
    zero = np.zeros(robot.nv)
    kappas = []
    for mdl, cms, qq, length in (
        (robot.model, robot.constraint_models, q, robot.length_scale),
        (model, constraints, qk, k * robot.length_scale),
    ):
        fd = SolverDynamics(mdl, cms, length_scale=length)
        fd.acceleration(qq, zero, zero)
        kappas.append(fd._kappa())
    assert kappas[1] == pytest.approx(kappas[0], rel=1e-9)
    # with the moments weighed in metres whatever the size, the figure would change
    fd = SolverDynamics(model, constraints, length_scale=robot.length_scale)
    fd.acceleration(qk, zero, zero)
    assert abs(fd._kappa() / kappas[0] - 1.0) > 1e-3


# --------------------------------------------------------------------------- passages


def _samples(kappa0: float, t_star: float, rate: float, times: np.ndarray) -> list[float]:
    return [math.sqrt(kappa0**2 + (rate * (t - t_star)) ** 2) for t in times]


@pytest.mark.parametrize(("kappa0", "through"), [(0.0, True), (3e-6, True), (3e-5, False)])
def test_the_bottom_between_samples_is_estimated(kappa0, through):
    """Samples every 1 ms of a passage whose bottom falls between two of them (a singular
    value passing ``kappa0`` from zero at 1.5 /s, the falling Delta's rate): the event is
    reported, at the bottom's time and value (kappa^2 is a parabola in time), through the
    singularity or near it as the bottom is below THROUGH or not."""
    t_star, rate = 0.2624, 1.5
    times = np.arange(0.0, 0.5, 1e-3)
    log = Passages()
    for t, k in zip(times, _samples(kappa0, t_star, rate, times), strict=True):
        log.observe(float(t), k)
    assert len(log.events) == 1
    ev = log.events[0]
    assert ev.through is through
    assert ev.time == pytest.approx(t_star, abs=1e-9)
    assert ev.conditioning == pytest.approx(kappa0, abs=1e-9)
    assert ev.start <= t_star <= ev.end
    # the passage is over when kappa is back above LEAVE * NEAR_SINGULAR
    assert _samples(kappa0, t_star, rate, [ev.end])[0] > LEAVE * NEAR_SINGULAR


def test_far_passages_and_projections_are_not_events():
    """A minimum well above the near threshold is no event, nor is the small change of
    kappa at a state projected back onto the closures (a jump at one time, not a motion)."""
    times = np.arange(0.0, 0.5, 1e-3)
    log = Passages()
    for t, k in zip(times, _samples(5e-3, 0.25, 1.5, times), strict=True):
        log.observe(float(t), k)
        log.observe(float(t) + 1e-17, 0.999 * k)  # (the same output time, reached again)
    assert log.events == []
    assert SingularityEvent(0.1, 0.0, True, 0.1).to_json()["end"] is None


@pytest.mark.parametrize("integrator", ["dopri5", "rk4", "euler"])
def test_parallelogram_crosses_its_flat_configuration_when_the_closed_form_says(
    parallelogram, integrator
):
    """Uniform rotation at 2 rad/s from the square: the cranks lie on the base line at
    t* = (pi / 2) / 2 s. One event, through the singularity, at t* within the time kappa takes
    to pass THROUGH at its own rate (the adaptive integrator samples it there; the fixed-step
    ones estimate the bottom from their 1 ms samples); the crossing needs no force along the
    lost direction, so the energy is kept through it."""
    robot = parallelogram
    w = 2.0
    fd = SolverDynamics(robot.model, robot.constraint_models, integrator=integrator)
    step = 1e-4 if integrator == "euler" else None
    res = fd.simulate(robot.q_home, np.array([w, -w, w]), 1.2, 1e-3, step=step)
    t_star = (math.pi / 2) / w
    assert len(res.events) == 1
    ev = res.events[0]
    assert ev.through and ev.kind == "parallel_singularity"
    # the rate of kappa on the way in, from the recorded samples 20 and 10 ms before
    k1, k2 = np.interp([t_star - 0.02, t_star - 0.01], res.t, res.conditioning)
    rate = (k1 - k2) / 0.01
    assert rate > 0.0
    assert abs(ev.time - t_star) < 2.0 * THROUGH / rate
    assert res.valid_until == ev.start < t_star
    assert res.energy_drift() < 1e-8
    inertia = 2 * 0.5 * L**2 / 3 + 0.5 * L**2  # two cranks about their ends, the coupler
    assert res.kinetic[0] == pytest.approx(0.5 * inertia * w * w, rel=1e-12)


def test_refined_forces_are_the_exact_constrained_dynamics(robots):
    """Near the Delta's crossing (conditioning 2e-5 .. 5e-5) the proximal iterations stop
    short; the refined acceleration is the solution of the dense KKT system (numpy) within
    the filter's (THROUGH / kappa)^4, and much closer to it than the iterations left it."""
    robot = robots["delta"]
    model = robot.model
    J0 = robot.closure_set.jacobian(model.createData(), robot.q_home)
    N = null_space(J0)
    v0 = N @ (N.T @ np.random.default_rng(0).standard_normal(robot.nv))
    v0 *= 0.5 / np.max(np.abs(v0))
    path = SolverDynamics(model, robot.constraint_models).simulate(
        robot.q_home, v0, 0.41, 1e-4, record_every=1
    )
    pick = np.flatnonzero((path.conditioning > 2e-5) & (path.conditioning < 5e-5))
    assert pick.size
    q, v = path.q[pick[0]], path.v[pick[0]]
    zero = np.zeros(robot.nv)
    fd = SolverDynamics(model, robot.constraint_models, baumgarte=(0.0, 0.0))
    a = fd.acceleration(q, v, zero)
    kappa = fd._kappa()
    assert fd.prox.iter >= fd.prox.max_iter  # the iterations hit their cap here
    raw = SolverDynamics(model, robot.constraint_models, baumgarte=(0.0, 0.0))
    raw._refine = lambda a: a  # type: ignore[method-assign]
    a_prox = raw.acceleration(q, v, zero)
    data = model.createData()
    J = robot.closure_set.jacobian(data, q)
    gamma = robot.closure_set.drift(data, q, v)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    h = pin.rnea(model, data, q, v, zero)
    nc = J.shape[0]
    K = np.block([[M, -J.T], [J, np.zeros((nc, nc))]])
    exact = np.linalg.solve(K, np.concatenate([-h, -gamma]))[: robot.nv]
    err, err_prox = np.max(np.abs(a - exact)), np.max(np.abs(a_prox - exact))
    assert err < (THROUGH / kappa) ** 4 * np.max(np.abs(exact))
    assert err < 1e-2 * err_prox
    assert np.max(np.abs(J @ a + gamma)) < 1e-2 * np.max(np.abs(J @ a_prox + gamma))


def test_capped_iterations_report_the_closures_acceleration_residual(robots):
    """An evaluation whose proximal iterations hit their cap is left as it is only when
    ``mu * relative_residual`` (what Pinocchio reports, an infinity norm in its contact
    frames) is within the solver's accuracy (``ForwardDynamics._capped``): that figure is the
    closures' acceleration residual ``J a + gamma`` of the acceleration returned, here measured
    on the same points with the closure rows' own world-frame Jacobian and drift (no Baumgarte
    gains): its largest point norm lies between the figure and sqrt(3) times it, to
    round-off, near the Delta's crossing, where both are far above round-off, and where they
    are not."""
    robot = robots["delta"]
    model = robot.model
    J0 = robot.closure_set.jacobian(model.createData(), robot.q_home)
    N = null_space(J0)
    v0 = N @ (N.T @ np.random.default_rng(0).standard_normal(robot.nv))
    v0 *= 0.5 / np.max(np.abs(v0))
    path = SolverDynamics(model, robot.constraint_models).simulate(
        robot.q_home, v0, 0.41, 1e-4, record_every=1
    )
    raw = SolverDynamics(model, robot.constraint_models, baumgarte=(0.0, 0.0))
    rows = raw._pin_rows  # the points of Pinocchio's constraint models, world frame
    assert all(cm.type == pin.ContactType.CONTACT_3D for cm in raw.constraint_models)
    prox, data = raw.prox, model.createData()
    zero = np.zeros(robot.nv)
    seen = {"above": 0, "within": 0}
    for q, v in zip(path.q[-60:], path.v[-60:], strict=True):
        a = pin.constraintDynamics(
            model, raw.data, q, v, zero, raw.constraint_models, raw.constraint_datas, prox
        )
        if prox.iter < prox.max_iter:
            continue
        pin.forwardKinematics(model, data, q, v, zero)
        pin.computeJointJacobians(model, data, q)
        rows.calc(data)
        gamma = rows.drift(data)
        r = (rows.jacobian(data) @ a + gamma).reshape(-1, 3)
        largest = float(np.max(np.linalg.norm(r, axis=1)))
        reported = prox.mu * prox.relative_residual
        noise = 1e-12 * float(np.max(np.abs(gamma)))  # round-off of the solve
        assert reported * (1 - 1e-3) - noise <= largest <= math.sqrt(3) * reported * 1.001 + noise
        seen["above" if reported > prox.absolute_accuracy else "within"] += 1
    assert seen["above"] and seen["within"]


# --------------------------------------------------------------------------- public boundary


def test_control_loop_reports_the_crossing_once(robots):
    """The control-loop step (1 kHz, Delta falling from home at rest) reports the crossing of
    its closures' singularity: one event, through it, in the step where the parallelograms'
    normals become coplanar along the loop's own states, and one warning."""
    robot = robots["delta"]
    fd = ForwardDynamics(robot, integrator="euler")
    q, v = fd.project_state(robot.q_home, np.zeros(robot.nv))
    h = 1e-3
    dets = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for k in range(400):
            q, v = fd.step(k * h, q, v, h)
            dets.append(parallelogram_normals_det(robot, q))
    det = np.array(dets)
    cross = np.flatnonzero(np.sign(det[1:]) != np.sign(det[:-1]))
    assert len(cross) == 1 and len(fd.events) == 1
    t_lo = (cross[0] + 1) * h  # the states are at (k + 1) h
    ev = fd.events[0]
    assert ev.through and t_lo <= ev.time <= t_lo + h
    mine = [w for w in caught if "parallel singularity" in str(w.message)]
    assert len(mine) == 1 and "ForwardDynamics.events" in str(mine[0].message)


def test_the_iteration_proxy_alone_finds_the_crossing(robots, monkeypatch):
    """Between the conditioning's checks of ``dopri5``, a rise of the proximal solver's
    iteration count calls one (``ForwardDynamics._due``): with the periodic checks switched
    off, only the one at home (where the Delta at rest has no rate of fall) and those the proxy
    calls remain, and the crossing is still reported in the 1 ms step where the
    parallelograms' normals become coplanar; without the proxy (no check after the first) it
    is not."""
    monkeypatch.setattr(fd_module, "ADAPTIVE_CHECK_PERIOD", 10**9)
    monkeypatch.setattr(fd_module, "STEP_CHECK_PERIOD", 10**9)
    robot = robots["delta"]
    h = 1e-3

    def run(proxy: bool) -> tuple[ForwardDynamics, np.ndarray]:
        fd = ForwardDynamics(robot, integrator="dopri5")
        if not proxy:
            observe = fd._observe

            def blind(t: float, kappa: float) -> None:
                observe(t, kappa)
                fd._iter_seen = 10**9  # more than any iteration count

            fd._observe = blind  # type: ignore[method-assign]
        q, v = fd.project_state(robot.q_home, np.zeros(robot.nv))
        dets = []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for k in range(400):
                q, v = fd.step(k * h, q, v, h)
                dets.append(parallelogram_normals_det(robot, q))
        return fd, np.array(dets)

    fd, det = run(proxy=True)
    cross = np.flatnonzero(np.sign(det[1:]) != np.sign(det[:-1]))
    assert len(cross) == 1 and len(fd.events) == 1
    t_lo = (cross[0] + 1) * h
    assert fd.events[0].through and t_lo <= fd.events[0].time <= t_lo + h
    blind, _ = run(proxy=False)
    assert not blind.events


def test_simulate_reports_passages_and_warns_once(robots):
    robot = robots["delta"]
    with pytest.warns(UserWarning, match="parallel singularity") as caught:
        res = simulate(robot, 0.5, 1e-3)
    assert len([w for w in caught if "parallel singularity" in str(w.message)]) == 1
    assert res.events and res.events[0].through
    assert res.valid_until == res.events[0].start
    assert res.conditioning.shape == res.t.shape and np.all(res.conditioning <= 1.0)
    assert res.energy_drift(res.valid_until) < 1e-7


@pytest.mark.parametrize(
    "dt", [0.0, -1e-3, float("nan"), float("inf"), "1e-3", None, True, 1j, [1e-3]]
)
def test_step_refuses_a_bad_dt_naming_it(robots, dt):
    robot = robots["five_bar"]
    fd = ForwardDynamics(robot, integrator="euler")
    with pytest.raises(InvalidInputError, match="^dt: "):
        fd.step(0.0, robot.q_home, np.zeros(robot.nv), dt)


def test_step_names_its_other_bad_inputs(robots):
    robot = robots["five_bar"]
    fd = ForwardDynamics(robot, integrator="euler")
    q, v = robot.q_home, np.zeros(robot.nv)
    for args, name in (
        ((float("nan"), q, v, 1e-3), "t"),
        ((0.0, q[:-1], v, 1e-3), "q"),
        ((0.0, q, np.full(robot.nv, np.nan), 1e-3), "v"),
        ((0.0, q, v, 1e-3, "pd"), "tau"),
    ):
        with pytest.raises(InvalidInputError, match=f"^{name}: "):
            fd.step(*args)
    with pytest.raises(SimulationError, match="the tau function raised ZeroDivisionError"):
        fd.step(0.0, q, v, 1e-3, lambda t, q, v: 1 / 0)
    with pytest.raises(SimulationError, match="returned 3 values for 2 actuators"):
        fd.step(0.0, q, v, 1e-3, lambda t, q, v: np.ones(3))
    with pytest.raises(InvalidInputError, match="^integrator: "):
        ForwardDynamics(robot, integrator="leapfrog")
    with pytest.raises(InvalidInputError, match="^options: "):
        ForwardDynamics(robot, rtoll=1e-9)
    with pytest.raises(InvalidInputError, match="^robot: "):
        ForwardDynamics(robot.model)  # type: ignore[arg-type]
    # the solver itself refuses a step that is not a positive finite number
    with pytest.raises(ValueError, match="dt must be"):
        SolverDynamics(robot.model, robot.constraint_models).step(0.0, q, v, float("nan"))


def test_a_state_that_blows_up_is_a_simulation_error(robots):
    robot = robots["five_bar"]
    fd = ForwardDynamics(robot, integrator="euler", project=False)
    huge = lambda t, q, v: np.full(2, 1e300)  # noqa: E731
    with pytest.raises(SimulationError, match="non-finite"):
        q, v = robot.q_home, np.zeros(robot.nv)
        for k in range(5):
            q, v = fd.step(k * 1e-3, q, v, 1e-3, huge)
