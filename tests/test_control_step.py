"""The control-loop step (solvers/control_step.py): closures kept, the same dynamics as raw."""

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from solvers.forward_dynamics import Actuation, ForwardDynamics, PassiveForces
from solvers.inverse_dynamics import InverseDynamics

H = 1e-3
TOL = 1e-9


@pytest.fixture(scope="module")
def robots() -> dict[str, pkdyn.Robot]:
    return {n: pkdyn.load(n, geometry=False) for n in ("delta", "gough_stewart", "tripod")}


def _pd(robot: pkdyn.Robot, amp: float = 0.05, w: float = 40.0):
    """PD tracking of a 1 Hz sine on every actuator around home, with the holding efforts.

    Gains: ``w`` [rad/s], critically damped, on the actuators' effective inertia (the inverse
    of an actuator's acceleration under a unit effort, the closures included).
    """
    qa, va, q0 = robot.actuated_q, robot.actuated_v, robot.q_home.copy()
    act = Actuation(va)
    fd = ForwardDynamics(robot.model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    z = np.zeros(robot.nv)
    a0 = fd.acceleration(q0, z, z)[va]
    unit = np.eye(len(va))
    m = np.array(
        [1.0 / (fd.acceleration(q0, z, act.generalized(unit[i], robot.nv))[va[i]] - a0[i])
         for i in range(len(va))]
    )  # fmt: skip
    hold = InverseDynamics(robot.model, robot.constraint_models, act).solve(q0, z, z).tau
    kp, kd = w * w * m, 2 * w * m

    def tau(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        s, c = np.sin(2 * np.pi * t), np.cos(2 * np.pi * t)
        return hold + kp * (q0[qa] + amp * s - q[qa]) + kd * (amp * 2 * np.pi * c - v[va])

    return tau


def _fd(robot: pkdyn.Robot, **kw) -> ForwardDynamics:
    act = Actuation(robot.actuated_v, names=robot.actuator_names)
    return ForwardDynamics(robot.model, robot.constraint_models, act, integrator="euler", **kw)


def _residual(robot: pkdyn.Robot, q: np.ndarray) -> float:
    return float(np.max(np.abs(robot.closure_set.residual(robot.model.createData(), q))))


def _raw_step(fd: ForwardDynamics, q, v, f):
    """The raw semi-implicit Euler step (same gains, proximal settings): no drift control."""
    fd._euler_gains(H)
    data = fd.model.createData()
    cds = pin.StdVec_RigidConstraintData()
    for cm in fd.constraint_models:
        cds.append(cm.createData())
    pin.initConstraintDynamics(fd.model, data, fd.constraint_models, cds)
    a = pin.constraintDynamics(fd.model, data, q, v, f, fd.constraint_models, cds, fd.prox)
    v1 = v + H * a
    return pin.integrate(fd.model, q, H * v1), v1


@pytest.mark.parametrize(
    "name, passive",
    [("delta", True), ("gough_stewart", False)],
    ids=["falling delta", "gough-stewart tracking"],
)
def test_ten_second_loop_keeps_closures(robots, name, passive):
    """10 s at 1 ms: every returned state within 1e-9 of the closures (raw Euler: 1e-4 m).

    The falling Delta swings its free arms through dead centres at up to 25 rad/s, where a
    step leaves 2e-4 m; the tracking Gough-Stewart moves its legs at 0.3 m/s.
    """
    robot = robots[name]
    fd = _fd(robot)
    tau = None if passive else _pd(robot)
    q, v = fd.project_state(robot.q_home, np.zeros(robot.nv))
    kin, cs = robot.model.createData(), robot.closure_set
    worst = 0.0
    for k in range(10_000):
        q, v = fd.step(k * H, q, v, H, tau)
        worst = max(worst, float(np.max(np.abs(cs.residual(kin, q)))))
    c = fd._control
    assert worst <= TOL
    assert c is not None and c.steps == 10_000 and c.projections <= 10
    # the tracking loop: one correction a step, measured once in 64 steps; the falling Delta
    # (through dead centres at 25 rad/s) needs measuring in 3 steps out of 4
    assert c.corrections < 1.2 * c.steps
    assert c.measured < (0.9 if passive else 0.05) * c.steps


def test_step_is_the_raw_euler_step_on_the_closures(robots):
    """Same velocity as the raw Euler step; configuration = raw one + a correction ~ residual."""
    robot = robots["delta"]
    fd, tau = _fd(robot), _pd(robot)
    q, v = fd.project_state(robot.q_home, np.zeros(robot.nv))
    for k in range(50):  # a moving state
        q, v = fd.step(k * H, q, v, H, tau)
    for k in (50, 51):  # 50: the evaluation reused from the last step; 51: the same again
        f = fd.actuation.generalized(tau(k * H, q, v), robot.nv)
        q_raw, v_raw = _raw_step(fd, q, v, f)
        q1, v1 = fd.step(k * H, q, v, H, tau)
        # the reused evaluation was made before the correction (~1e-6 away): first order in it
        assert np.max(np.abs(v1 - v_raw)) <= 1e-7 * max(1.0, np.max(np.abs(v_raw)))
        gap = _residual(robot, q_raw)
        assert 1e-9 < gap < 1e-5  # what the raw step leaves
        assert np.max(np.abs(pin.difference(robot.model, q_raw, q1))) < 20 * gap
        assert _residual(robot, q1) <= TOL
        q, v = q1, v1


def test_a_state_not_returned_by_the_step_is_evaluated_afresh(robots):
    robot = robots["gough_stewart"]
    fd, tau = _fd(robot), _pd(robot)
    q, v = fd.project_state(robot.q_home, np.zeros(robot.nv))
    q, v = fd.step(0.0, q, v, H, tau)
    # the caller changes the state in place (e.g. a reset): the cached evaluation is stale
    v *= 0.5
    f = fd.actuation.generalized(tau(H, q, v), robot.nv)
    _, v_raw = _raw_step(fd, q, v, f)
    _, v1 = fd.step(H, q, v, H, tau)
    assert np.max(np.abs(v1 - v_raw)) <= 1e-12 * max(1.0, np.max(np.abs(v_raw)))


def test_far_from_the_closures_the_step_projects(robots):
    robot = robots["gough_stewart"]
    fd = _fd(robot)
    q = pin.integrate(robot.model, robot.q_home, 0.05 * np.ones(robot.nv))
    assert _residual(robot, q) > 1e-2
    q1, _ = fd.step(0.0, q, np.zeros(robot.nv), H)
    assert _residual(robot, q1) <= TOL
    assert fd._control is not None and fd._control.projections == 1


def test_welds_and_passive_forces(robots):
    """The tripod's feet are welds (6D closures, log6 residual); damping acts as an applied
    force that changes every step (reused evaluations: its change is solved for)."""
    robot = robots["tripod"]
    passive = PassiveForces(robot.model, damping=np.full(robot.nv, 0.5))
    fd, tau = _fd(robot, passive=passive), _pd(robot, amp=0.02)
    q, v = fd.project_state(robot.q_home, np.zeros(robot.nv))
    worst = 0.0
    for k in range(300):
        q, v = fd.step(k * H, q, v, H, tau)
        worst = max(worst, _residual(robot, q))
    assert worst <= TOL
    f = fd.actuation.generalized(tau(0.3, q, v), robot.nv) + passive.force(q, v)
    _, v_raw = _raw_step(fd, q, v, f)
    _, v1 = fd.step(0.3, q, v, H, tau)
    assert np.max(np.abs(v1 - v_raw)) <= 1e-8 * max(1.0, np.max(np.abs(v_raw)))


def test_energy_of_a_free_mechanism(robots):
    """A free Delta from rest keeps its energy as well as with the full projection.

    Both are semi-implicit Euler at 1 ms (energy error O(h), 1 % of the swing's energy here);
    the full projection also takes the velocity's normal part away (an inelastic impulse),
    which this step leaves to the Baumgarte gains: within 1.5x of each other (1.2x recorded).
    """
    robot = robots["delta"]
    model, data = robot.model, robot.model.createData()

    def energy(q, v):
        return pin.computeKineticEnergy(model, data, q, v) + pin.computePotentialEnergy(
            model, data, q
        )

    drifts = []
    for full in (False, True):
        fd = _fd(robot)
        q, v = fd.project_state(robot.q_home, np.zeros(robot.nv))
        e0, worst = energy(q, v), 0.0
        for k in range(300):
            if full:
                fd.project = False
                q, v = fd.project_state(*fd.step(k * H, q, v, H))
            else:
                q, v = fd.step(k * H, q, v, H)
            worst = max(worst, abs(energy(q, v) - e0))
        drifts.append(worst)
    assert drifts[0] <= 1.5 * drifts[1]


def test_a_coupled_robot_steps_on_its_closures_and_couplings():
    """The xArm7 gripper (two closures, one coupling): the control step keeps both."""
    import warnings
    from pathlib import Path

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its tendon actuator is left out
        robot = pkdyn.load(
            Path(__file__).parent / "data/public/menagerie_xarm7_hand/hand.xml", geometry=False
        )
    fd = ForwardDynamics(
        robot.model,
        robot.constraint_models,
        Actuation(robot.actuated_v),
        couplings=robot.closure_set.couplings,
        integrator="euler",
    )
    q, v = fd.project_state(robot.q_home, np.zeros(robot.nv))
    q0 = q.copy()
    for k in range(300):  # falling under gravity, 1 ms steps
        q, v = fd.step(k * 1e-3, q, v, 1e-3)
    assert robot.closure_set.couplings and not np.allclose(q, q0)
    assert np.max(np.abs(robot.closure_set.residual(robot.model.createData(), q))) < 1e-9


def _coupled(which: str) -> pkdyn.Robot:
    import warnings
    from pathlib import Path

    if which == "leg":  # a coupling alone: the knee plus the ankle drives a rotor
        from test_sum_coupling import leg_urdf

        return pkdyn.load_string(leg_urdf(), "leg")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its tendon actuator is left out
        return pkdyn.load(
            Path(__file__).parent / "data/public/menagerie_xarm7_hand/hand.xml", geometry=False
        )


@pytest.mark.parametrize("which", ["xarm7 gripper", "leg"])
def test_coupled_steps_end_on_closures_and_couplings(which):
    """With couplings the step corrects them with the closures, with the factorization of its
    one dynamics evaluation: every returned state within 1e-9 of both, no full projection, and
    the velocity of the raw Euler step (one general evaluation) at each state."""
    robot = _coupled(which)
    act = Actuation(robot.actuated_v, names=robot.actuator_names)
    fd = ForwardDynamics(robot.model, robot.constraints, act, integrator="euler")
    ref = ForwardDynamics(robot.model, robot.constraints, act, integrator="euler", project=False)
    ref._euler_gains(H)
    amp = 0.5 * np.ones(act.n)

    def tau(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return amp * np.sin(2 * np.pi * 3 * t)

    q, v = fd.project_state(robot.q_home, np.zeros(robot.nv))
    cs, data = robot.constraints, robot.model.createData()
    worst = 0.0
    for k in range(300):
        f = act.generalized(tau(k * H, q, v), robot.nv)
        v_raw = v + H * ref.acceleration(q, v, f)
        q, v = fd.step(k * H, q, v, H, tau)
        assert np.max(np.abs(v - v_raw)) <= 1e-7 * max(1.0, np.max(np.abs(v_raw)))
        worst = max(worst, float(np.max(np.abs(cs.residual(data, q)))))
    assert worst <= TOL
    assert cs.nk and fd._control is not None and fd._control.projections == 0
    assert float(np.abs(v).max()) > 1e-2  # it moves
