"""Vibration along a motion (:mod:`pkdyn.precision.vibration`), against physics.

- a one-mode system (a carriage on a servo-driven rail) against the closed-form response of a
  spring-mass to the same acceleration profile (Duhamel's integral, by adaptive quadrature), to
  1e-6 of its peak, both methods;
- the modal method against the multibody simulation of the elastic model on the DELTA 580's
  Adept cycle (realistic stiffness: 2e4 N m/rad servos, rigid links: 187 to 200 Hz at home,
  91 to 157 Hz with the 0.5 kg payload at the pick points), within 2 % in peak deviation,
  residual amplitude and settling time (the same motion in MuJoCo: ``test_vibration_mjcf.py``);
- the Delta's closed forms (the nacelle's coordinates) against the general path: the same
  modes along the path (1e-9), the same response as the general path at 101 poses (within
  its interpolation: 0.5 %, 1 %, 0.2 %), the display's deformation closure-consistent and
  moving the platform by the deviation;
- the free vibration after a stop (undamped multibody run) against the frequency
  :func:`pkdyn.precision.modes` gives about the loaded equilibrium (FFT peak, 1e-4), and the
  run's energy balance;
- the static deflection against :func:`pkdyn.precision.stiffness` (loaded, under gravity);
- the rigid feedforward cancels the vibration of rigid links exactly;
- shaping: the residual vibration at the frequency a ZV or ZVD shaper targets is removed.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from support.slider import slider as load_slider

import pkdyn
from pkdyn.precision import elastic_model, modes, stiffness
from pkdyn.precision.vibration import vibration

MASS = 1.0
F_SLIDER = 20.0  # Hz
K_SLIDER = MASS * (2 * np.pi * F_SLIDER) ** 2
D_MOVE = 0.05  # p2p: 5 cm along x
T_MOVE = 0.2


@pytest.fixture(scope="module")
def slider(tmp_path_factory):
    return load_slider(tmp_path_factory.mktemp("slider"), MASS)


def duhamel(t: float, zeta: float, T: float = T_MOVE, delay: float = 0.0) -> float:
    """Deviation of a spring-mass driven through its spring by a quintic move (closed form).

    ``e'' + 2 zeta w e' + w^2 e = -a(t)``: Duhamel's integral of the commanded acceleration
    against the impulse response ``exp(-zeta w t) sin(w_d t) / w_d``.
    """
    w = 2 * np.pi * F_SLIDER
    wd = w * np.sqrt(1 - zeta * zeta)

    def a(tau: float) -> float:
        u = (tau - delay) / T
        return D_MOVE / T**2 * (60 * u - 180 * u**2 + 120 * u**3) if 0 <= u <= 1 else 0.0

    def f(tau: float) -> float:
        return -a(tau) * np.exp(-zeta * w * (t - tau)) * np.sin(wd * (t - tau)) / wd

    lo, hi = delay, min(t, delay + T)
    if hi <= lo:
        return 0.0
    return quad(f, lo, hi, epsabs=1e-16, epsrel=1e-13, limit=500)[0]


@pytest.mark.parametrize("method", ["modal", "multibody"])
def test_one_mode_system_is_duhamels_integral(slider, method):
    zeta = 0.05
    r = vibration(
        slider, "p2p", cycle_time=T_MOVE, actuator_stiffness=K_SLIDER, damping_ratio=zeta,
        method=method, dwell=0.3, band=1e-5,
    )  # fmt: skip
    assert r.frequencies_end == pytest.approx([F_SLIDER], rel=1e-12)
    assert r.damping.actuator == pytest.approx([2 * zeta * np.sqrt(K_SLIDER * MASS)], rel=1e-12)
    idx = np.linspace(0, r.t.size - 1, 80).astype(int)
    ref = np.array([duhamel(t, zeta) for t in r.t[idx]])
    scale = np.max(np.abs(ref))
    assert np.max(np.abs(r.deviation[idx, 0] - ref)) < 1e-6 * scale
    # the figures from the dense output, against the closed form's own extremum
    assert r.peak_deviation == pytest.approx(
        max(abs(duhamel(r.peak_time, zeta)), r.peak_deviation), rel=1e-6
    )


def test_shaping_removes_the_residual_vibration_it_targets(slider):
    opts = dict(cycle_time=0.1, actuator_stiffness=K_SLIDER, damping_ratio=0.02, dwell=0.3)
    plain = vibration(slider, "p2p", **opts)
    for kind, left in (("zv", 2e-3), ("zvd", 2e-3)):
        shaped = vibration(slider, "p2p", shaper=kind, **opts)
        assert shaped.shaper["kind"] == kind
        assert shaped.shaper["frequencies_end"] == pytest.approx([F_SLIDER], rel=1e-9)
        # the shaped move lasts longer by the shaper's delays (half a damped period per step)
        wd = 2 * np.pi * F_SLIDER * np.sqrt(1 - 0.02**2)
        steps = 1 if kind == "zv" else 2
        assert shaped.duration == pytest.approx(0.1 + steps * np.pi / wd, abs=1.01e-3)
        assert shaped.residual_amplitude < left * plain.residual_amplitude, kind


def test_shaping_on_the_delta_removes_the_targeted_mode():
    robot = pkdyn.load("delta")
    opts = dict(cycle_time=0.5, payload=0.5, actuator_stiffness=2e4, dwell=0.3, poses=17)
    plain = vibration(robot, "adept", **opts)
    shaped = vibration(robot, "adept", shaper="zvd", **opts)

    def amplitude(r, mode):
        return next(m.amplitude for m in r.dominant_modes if m.mode == mode)

    # mode 1 (91 Hz at the pick point, the one tracked) dominates the unshaped residual ...
    assert plain.dominant_modes[0].mode == 1
    # ... and the ZVD shaper removes 97 % of it
    assert amplitude(shaped, 1) < 0.03 * amplitude(plain, 1)
    assert shaped.residual_amplitude < 0.3 * plain.residual_amplitude


@pytest.fixture(scope="module")
def delta_adept():
    robot = pkdyn.load("delta")
    opts = dict(cycle_time=0.5, payload=0.5, actuator_stiffness=2e4, band=2e-5, dwell=0.2)
    return robot, opts, vibration(robot, "adept", **opts)


def test_modal_agrees_with_the_multibody_simulation(delta_adept):
    robot, opts, modal = delta_adept
    mb = vibration(robot, "adept", method="multibody", **opts)
    assert mb.energy_drift < 1e-6
    assert modal.peak_deviation == pytest.approx(mb.peak_deviation, rel=0.02)
    assert modal.residual_amplitude == pytest.approx(mb.residual_amplitude, rel=0.02)
    assert mb.settling_time is not None and modal.settling_time is not None
    assert modal.settling_time == pytest.approx(mb.settling_time, rel=0.02)
    assert modal.static_deflection == pytest.approx(mb.static_deflection, rel=1e-3, abs=1e-9)
    assert [m.mode for m in modal.dominant_modes[:2]] == [m.mode for m in mb.dominant_modes[:2]]


def test_closed_form_is_the_general_modal_method():
    """The Delta's closed forms: the same modes as the general path, the same response."""
    import dataclasses

    from pkdyn.dynamics.trajectory import map_task_trajectory, named_task
    from pkdyn.precision.condensation import constraint_rows
    from pkdyn.precision.vibration import analyse, prepare
    from pkdyn.precision.vibration_command import command
    from pkdyn.precision.vibration_modal import path_modes

    robot = pkdyn.load("delta")
    em = elastic_model(robot, [2e4, 3e4, 2.5e4])
    p = np.zeros(3)
    cmd = command(em, named_task(robot, "adept", cycle_time=0.5), 0.5, p)
    st = prepare(robot, em, cmd, p, 0.5, "none", None, None, 2e-5, 0.3, None, None)
    closed = analyse(st, cmd, "modal")
    assert st.arms is not None and cmd.mapped is None  # (no pose solved)
    cmd.mapped = map_task_trajectory(robot, cmd.task, check_speeds=False)  # (the general path)
    # its modes at poses along the path are the general ones (frequencies, platform motions)
    samples = np.array([0, 77, 250, 401, 500])
    poses = st.arms.poses(cmd.task.pose[samples, :3])
    pm = st.arms.path_modes(poses, samples)
    general = path_modes(st.elastic, cmd.joint.q, samples, p)
    assert pm.frequencies == pytest.approx(general.frequencies, rel=1e-9)
    for a, b in zip(pm.platform, general.platform, strict=True):  # (a mode's sign is arbitrary)
        gap = np.minimum(np.abs(a - b).max(axis=1), np.abs(a + b).max(axis=1))
        assert gap.max() <= 1e-9 * np.abs(a).max()
    # the response: the general path's at many poses (in the tree's coordinates)
    general = analyse(dataclasses.replace(st, arms=None, poses=101), cmd, "modal")
    assert closed.peak_deviation == pytest.approx(general.peak_deviation, rel=5e-3)
    assert closed.residual_amplitude == pytest.approx(general.residual_amplitude, rel=1e-2)
    assert closed.settling_time == pytest.approx(general.settling_time, rel=2e-3)
    assert closed.static_deflection == pytest.approx(general.static_deflection, rel=1e-9, abs=1e-15)
    assert closed.internal == general.internal == 6
    # the display's deformation, mapped on demand: closure-consistent, it moves the platform
    # by the deviation
    from pkdyn.model.platform_jacobian import platform_jacobian

    t_c, Q, U = closed.animation()
    for k in (0, 150, 300, 450, 700):
        assert np.abs(constraint_rows(st.elastic, Q[k]) @ U[k]).max() <= 1e-9 * np.abs(U[k]).max()
        d = platform_jacobian(st.elastic.robot, Q[k], point=p)[:3] @ U[k]
        i = int(np.argmin(np.abs(closed.t - t_c[k])))
        assert d == pytest.approx(closed.deviation[i], rel=1e-6, abs=1e-6 * closed.peak_deviation)


def test_closed_form_joint_trajectory_is_the_mechanisms():
    """The Delta's joints along a motion in closed form: assembled, on the path, no bar spin."""
    import pinocchio as pin

    from pkdyn.dynamics.delta import DeltaDynamics
    from pkdyn.dynamics.inverse import inverse_dynamics
    from pkdyn.dynamics.trajectory import named_task
    from pkdyn.precision.vibration_closed_form import arm_motion, delta_joint_trajectory
    from solvers import numerics

    robot = pkdyn.load("delta", geometry=False)
    task = named_task(robot, "adept", cycle_time=0.5)
    dd = DeltaDynamics(robot)
    arms = arm_motion(dd, task)
    jt = delta_joint_trajectory(robot, dd, task, arms)
    model, data, cs, fid = robot.model, robot.data, robot.constraints, robot.platform_frame
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for k in range(0, task.t.size, 50):
        q, v, a = jt.q[k], jt.v[k], jt.a[k]
        assert np.abs(cs.residual(data, q)).max() < 1e-12  # closures [m]
        Jc = cs.jacobian(data, q)
        assert np.abs(Jc @ v).max() < 1e-12 and np.abs(Jc @ a + cs.drift(data, q, v)).max() < 1e-9
        pin.forwardKinematics(model, data, q, v, a)
        M = pin.updateFramePlacement(model, data, fid)
        assert M.translation == pytest.approx(task.pose[k, :3], abs=1e-12)
        assert pin.getFrameVelocity(model, data, fid, lwa).linear == pytest.approx(
            task.pose_d[k, :3], abs=1e-12
        )
        acc = pin.getFrameClassicalAcceleration(model, data, fid, lwa).linear
        assert acc == pytest.approx(task.pose_dd[k, :3], abs=1e-9)
        # the internal mobilities (the bars' spins): zero momentum, their dynamics satisfied
        S = np.zeros((3, model.nv))
        S[np.arange(3), robot.actuated_v] = 1.0
        N = numerics.null_space(np.vstack([Jc, S]), 1e-9, 1.0)
        assert N.shape[1] == 6
        Mq = pin.crba(model, data, q)
        Mq = np.triu(Mq) + np.triu(Mq, 1).T
        assert np.abs(N.T @ Mq @ v).max() < 1e-12
        assert np.abs(N.T @ pin.rnea(model, data, q, v, a)).max() < 1e-9
    # the rigid efforts along it are the closed form's
    assert inverse_dynamics(robot, jt).tau == pytest.approx(arms.tau, abs=1e-9)


def test_static_deflection_is_the_loaded_stiffness_deflection(delta_adept):
    robot, opts, modal = delta_adept
    q_end = pkdyn.inverse_geometry(robot, [-0.1525, 0.0, -0.4]).q
    from pkdyn.dynamics.payload import with_payload

    S = stiffness(
        with_payload(robot, 0.5), q_end, actuator_stiffness=2e4, loaded=True, gravity=True
    )
    assert modal.static_deflection == pytest.approx(S.deflection[:3], rel=2e-3, abs=1e-10)


def test_rigid_feedforward_cancels_the_vibration_of_rigid_links(delta_adept):
    robot, opts, modal = delta_adept
    ff = vibration(robot, "adept", feedforward="rigid", **opts)
    assert ff.peak_deviation < 1e-9 * modal.peak_deviation
    gravity = vibration(robot, "adept", feedforward="gravity", **opts)
    assert np.linalg.norm(gravity.static_deflection) < 1e-9 * np.linalg.norm(
        modal.static_deflection
    )


def test_free_vibration_after_a_stop_rings_at_the_natural_frequency():
    """An undamped vertical move on the Delta's axis excites its vertical mode only."""
    from pkdyn.dynamics.trajectory import point_to_point

    robot = pkdyn.load("delta")
    home = robot.platform_placement(robot.q_home).translation
    end = home + [0.0, 0.0, -0.05]
    move = point_to_point(home, end, 0.08)
    r = vibration(
        robot, move, payload=0.3, actuator_stiffness=2e4, damping_ratio=0.0,
        method="multibody", dwell=0.5,
    )  # fmt: skip
    assert r.energy_drift < 1e-7
    free = r.t >= r.duration + 0.01
    t = r.t[free]
    y = r.deviation[free, 2] - r.static_deflection[2]
    w = np.hanning(t.size)

    def magnitude(f: float) -> float:  # the windowed signal's spectrum at any frequency
        return abs(np.sum(w * y * np.exp(-2j * np.pi * f * t)))

    dt = t[1] - t[0]
    spectrum = np.abs(np.fft.rfft(w * y, 8 * t.size))
    f0 = np.fft.rfftfreq(8 * t.size, dt)[np.argmax(spectrum)]
    from scipy.optimize import minimize_scalar

    peak = minimize_scalar(lambda f: -magnitude(f), bounds=(f0 - 1.0, f0 + 1.0), method="bounded",
                           options={"xatol": 1e-6}).x  # fmt: skip
    em = elastic_model(pkdyn.dynamics.with_payload(robot, 0.3), 2e4)
    q_end = pkdyn.inverse_geometry(robot, end).q
    m = modes(em, q_end, gravity=True)
    vertical = int(np.argmax(np.abs(m.platform[:, 2])))
    assert peak == pytest.approx(m.frequencies[vertical], rel=1e-4)


@pytest.mark.parametrize("name, k", [("gough_stewart", 2e6), ("planar_3rrr", 2e4)])
def test_other_robots_modal_against_multibody(name, k):
    """Prismatic actuators and rotations in the task: the methods agree the same way."""
    robot = pkdyn.load(name)
    opts = dict(cycle_time=0.2, payload=0.5, actuator_stiffness=k, dwell=0.2, band=1e-6)
    modal = vibration(robot, "p2p", **opts)
    mb = vibration(robot, "p2p", method="multibody", **opts)
    assert modal.task == mb.task and len(modal.task) == len(robot.task_rows)
    assert mb.energy_drift < 1e-6
    assert modal.peak_deviation == pytest.approx(mb.peak_deviation, rel=0.02)
    assert modal.residual_amplitude == pytest.approx(mb.residual_amplitude, rel=0.02)
    rot = [i for i, c in enumerate(modal.task) if c.startswith("r")]
    if rot:  # the rotations' deviation [rad]
        a = np.max(np.abs(modal.deviation[:, rot]))
        b = np.max(np.abs(mb.deviation[:, rot]))
        assert a == pytest.approx(b, rel=0.02)
