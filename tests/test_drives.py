"""The drive model: rotor inertia as armature, gearbox efficiency, motor friction.

Physics checks: the armature equals the rotor modelled as a body spinning at N times the joint
speed (kinetic energy and torques); inverse and forward dynamics invert each other through the
drives; the motor's work equals the change of mechanical energy plus the losses.
"""

import re

import numpy as np
import pinocchio as pin
import pytest
from conftest import simpson_work

import pkdyn
from pkdyn.dynamics import inverse_dynamics, mechanical_energy, simulate
from pkdyn.dynamics.actuation import actuation, drives, motor_efforts, with_drives
from pkdyn.dynamics.trajectory import JointTrajectory, named_trajectory
from pkdyn.exceptions import DescriptionError, InvalidInputError, ParameterError
from pkdyn.library import delta as delta_lib
from pkdyn.model.formats.mjcf import to_mjcf
from pkdyn.model.loader import load_string
from solvers import Drives, ForwardDynamics

J_ROTOR = 5e-5  # kg m^2, a 400 W servo with its gearbox input
N = 20.0


@pytest.fixture(scope="module")
def plain() -> pkdyn.Robot:
    return pkdyn.load("delta", geometry=False)


@pytest.fixture(scope="module")
def cycle(plain) -> JointTrajectory:
    return named_trajectory(plain, "adept", cycle_time=0.5, dt=5e-3)


# --------------------------------------------------------------------------- the drive law


def test_drive_law_inverts_and_balances_power():
    rng = np.random.default_rng(0)
    d = Drives(
        [20.0, -15.0, 50.0],
        rotor_inertia=[1e-5, 2e-5, 0.0],
        efficiency=[0.9, 0.8, 0.95],
        backdrive_efficiency=[0.85, 0.7, 0.95],
        viscous=[1e-4, 0.0, 2e-4],
        coulomb=[0.01, 0.02, 0.0],
        smoothing=0.1,
    )
    tau_m = rng.normal(0.0, 1.0, (200, 3))
    qd = rng.normal(0.0, 1.0, (200, 3)) * rng.choice([1.0, 1e-4, 0.0], (200, 3))
    tau_j = d.joint_effort(tau_m, qd)
    assert np.allclose(d.motor_effort(tau_j, qd), tau_m, rtol=0, atol=1e-12)
    assert np.allclose(d.armature, [4e-3, 4.5e-3, 0.0])
    # motor power = friction loss + gearbox loss + power to the joint (an identity)
    p_f, p_g = d.losses(tau_m, qd)
    omega = d.motor_speed(qd)
    assert np.allclose(tau_m * omega, p_f + p_g + tau_j * qd, atol=1e-12)
    fast = np.abs(omega) > 10 * d.smoothing
    assert np.all(p_f >= 0.0) and np.all(p_g[fast] >= 0.0)
    # driving: the joint gets eta N tau_in; back-driven: N tau_in / eta_b
    one = Drives([10.0], efficiency=0.8, backdrive_efficiency=0.5)
    assert one.joint_effort(np.array([1.0]), np.array([1.0]))[0] == pytest.approx(8.0)
    assert one.joint_effort(np.array([1.0]), np.array([-1.0]))[0] == pytest.approx(20.0)
    assert one.lossless is False and Drives([3.0]).lossless
    with pytest.raises(ValueError, match="efficiencies"):
        Drives([1.0], efficiency=1.2)
    with pytest.raises(ValueError, match="non-zero"):
        Drives([0.0])


# --------------------------------------------------------------------------- armature = rotor


def _with_rotor_bodies(p: delta_lib.Params, J: float) -> str:
    """The Delta's URDF plus, per arm, a rotor body on the base spinning about the arm axis.

    The rotor is off the arm axis (a motor beside its gearbox) and has transverse inertia and
    mass: none of it matters for a rotor whose axis is fixed, only J about the axis does.
    """
    xml = delta_lib.build_urdf(p)
    extra = []
    for i, th in enumerate(p.theta, start=1):
        c, s = np.cos(th), np.sin(th)
        xyz = f"{(p.ra + 0.06) * c} {(p.ra + 0.06) * s} 0.08"
        extra.append(
            f'<link name="rotor{i}"><inertial><origin xyz="0 0 0"/><mass value="0.7"/>'
            f'<inertia ixx="3e-4" ixy="0" ixz="0" iyy="{J}" iyz="0" izz="3e-4"/></inertial>'
            "</link>"
            f'<joint name="rotor{i}" type="revolute"><parent link="base"/>'
            f'<child link="rotor{i}"/><origin xyz="{xyz}" rpy="0 0 {th}"/><axis xyz="0 1 0"/>'
            '<limit lower="-1e4" upper="1e4" effort="1e3" velocity="1e4"/></joint>'
            f'<transmission name="rotor{i}_t"><type>SimpleTransmission</type>'
            f'<joint name="rotor{i}"/><actuator name="rotor_motor{i}"/></transmission>'
        )
    return xml.replace("</robot>", "\n".join(extra) + "\n</robot>")


def _augment(robot: pkdyn.Robot, big: pkdyn.Robot, jt: JointTrajectory, n: float):
    """The trajectory of ``robot`` on the rotor model: same joints, rotors at n x the arms."""
    Q = np.zeros((jt.t.size, big.nq))
    V = np.zeros((jt.t.size, big.nv))
    A = np.zeros((jt.t.size, big.nv))
    m, M = robot.model, big.model
    for j in range(1, M.njoints):
        name = M.names[j]
        jm = M.joints[j]
        if name.startswith("rotor"):
            src = m.joints[m.getJointId("arm" + name[len("rotor") :])]
            Q[:, jm.idx_q] = n * jt.q[:, src.idx_q]
            V[:, jm.idx_v] = n * jt.v[:, src.idx_v]
            A[:, jm.idx_v] = n * jt.a[:, src.idx_v]
            continue
        src = m.joints[m.getJointId(name)]
        Q[:, jm.idx_q : jm.idx_q + jm.nq] = jt.q[:, src.idx_q : src.idx_q + src.nq]
        V[:, jm.idx_v : jm.idx_v + jm.nv] = jt.v[:, src.idx_v : src.idx_v + src.nv]
        A[:, jm.idx_v : jm.idx_v + jm.nv] = jt.a[:, src.idx_v : src.idx_v + src.nv]
    return JointTrajectory(jt.t, Q, V, A, big.actuated_q, big.actuated_v, name="augmented")


def test_armature_equals_the_rotor_as_a_body(plain, cycle):
    """Kinetic energy and arm torques of the armature model equal those of the mechanism with
    the rotors as bodies spinning at N times the arm speed (torque N tau_rotor on the arm)."""
    p = delta_lib.Params()  # no armature: the rotors are bodies
    geared = pkdyn.load("delta", geometry=False, rotor_inertia=J_ROTOR)
    assert np.allclose(geared.model.armature[geared.actuated_v], N**2 * J_ROTOR)
    big = load_string(_with_rotor_bodies(p, J_ROTOR), "delta+rotors", geometry=False)
    aug = _augment(geared, big, cycle, N)
    ef = inverse_dynamics(geared, cycle)
    ef_big = inverse_dynamics(big, aug)
    names = big.actuated_joint_names
    arms = [names.index(f"arm{i}") for i in (1, 2, 3)]
    rotors = [names.index(f"rotor{i}") for i in (1, 2, 3)]
    combined = ef_big.tau[:, arms] + N * ef_big.tau[:, rotors]
    scale = float(np.max(np.abs(ef.tau)))
    assert np.max(np.abs(combined - ef.tau)) < 1e-9 * scale
    # the rotors' share is large on this fast cycle (reflected 0.02 kg m^2 per arm)
    ef0 = inverse_dynamics(plain, cycle)
    assert np.max(np.abs(ef.tau - ef0.tau)) > 0.2 * float(np.max(np.abs(ef0.tau)))
    # kinetic energy: the armature's 0.5 N^2 J qd^2 is the rotor's 0.5 J (N qd)^2
    kin = np.array(
        [mechanical_energy(geared, q, v)[0] for q, v in zip(cycle.q, cycle.v, strict=True)]
    )
    kin_big = np.array([mechanical_energy(big, q, v)[0] for q, v in zip(aug.q, aug.v, strict=True)])
    assert np.max(np.abs(kin - kin_big)) < 1e-10 * float(np.max(kin))
    assert np.allclose(ef.kinetic, kin, rtol=1e-12)


def test_inverse_and_forward_dynamics_invert_each_other_through_the_drives():
    robot = pkdyn.load("delta", geometry=False, rotor_inertia=J_ROTOR)
    robot = with_drives(robot, efficiency=0.85, backdrive_efficiency=0.7, viscous=1e-4)
    robot = with_drives(robot, coulomb=0.02)
    d = drives(robot)
    act = actuation(robot)
    fd = ForwardDynamics(robot.model, list(robot.constraint_models), act, baumgarte=(0.0, 0.0))
    rng = np.random.default_rng(3)
    traj = named_trajectory(robot, "adept", cycle_time=0.6, dt=0.02)
    for k in range(0, traj.t.size, 5):
        q, v = traj.q[k], traj.v[k]
        tau_m = rng.normal(0.0, 0.5, 3)
        tau_j = d.joint_effort(tau_m, v[robot.actuated_v])
        a = fd.acceleration(q, v, act.generalized(tau_j, robot.nv))
        one = JointTrajectory(
            np.array([0.0, 1.0]),
            np.array([q, q]),
            np.array([v, v]),
            np.array([a, a]),
            robot.actuated_q,
            robot.actuated_v,
        )
        back = inverse_dynamics(robot, one).tau[0]
        assert np.allclose(motor_efforts(robot, back, v[robot.actuated_v]), tau_m, atol=1e-8)


def _simpson(t: np.ndarray, p: np.ndarray) -> float:
    """Integral of ``p`` over ``t`` (an odd number of uniform samples)."""
    assert t.size % 2 == 1
    return float(simpson_work(t, p)[0][-1])


def test_motor_work_equals_energy_change_plus_losses():
    """int tau_m omega dt = change of mechanical energy (rotors included) + friction and gearbox
    losses, on a driven 0.4 s run with efficiencies 0.8 / 0.7 and motor friction."""
    robot = pkdyn.load("delta", geometry=False, rotor_inertia=J_ROTOR)
    robot = with_drives(robot, efficiency=0.8, backdrive_efficiency=0.7, viscous=2e-4, coulomb=0.03)
    d = drives(robot)
    va = robot.actuated_v
    home = robot.q_home[robot.actuated_q]

    def motor(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        target = home + 0.3 * np.sin(2 * np.pi * 2.5 * t + np.array([0.0, 2.0, 4.0]))
        return 0.6 * (target - q[robot.actuated_q]) * 10.0 - 0.05 * v[va] + 0.2

    res = simulate(robot, 0.4, 5e-4, motor_torque=motor)
    tau_m = np.array([motor(t, q, v) for t, q, v in zip(res.t, res.q, res.v, strict=True)])
    qd = res.v[:, va]
    assert np.allclose(d.joint_effort(tau_m, qd), res.tau, atol=1e-10)  # what was applied
    p_f, p_g = d.losses(tau_m, qd)
    w_motor = _simpson(res.t, np.sum(tau_m * d.motor_speed(qd), axis=1))
    w_loss = _simpson(res.t, np.sum(p_f + p_g, axis=1))
    dE = float(res.energy[-1] - res.energy[0])
    assert w_loss > 0.1 * abs(w_motor)  # the losses matter here
    assert abs(w_motor - w_loss - dE) < 1e-3 * (abs(w_motor) + w_loss)


def test_free_motors_brake_a_falling_delta():
    """Motors free (zero torque): what the mechanism loses is what the drives dissipate."""
    robot = pkdyn.load("delta", geometry=False, rotor_inertia=J_ROTOR)
    robot = with_drives(robot, efficiency=0.9, backdrive_efficiency=0.6, viscous=1e-3, coulomb=0.02)
    d = drives(robot)
    res = simulate(robot, 0.3, 5e-4)  # lossy drives: the motors' friction acts by default
    qd = res.v[:, robot.actuated_v]
    p_f, p_g = d.losses(np.zeros_like(qd), qd)
    lost = _simpson(res.t, np.sum(p_f + p_g, axis=1))
    dE = float(res.energy[-1] - res.energy[0])
    assert dE < 0.0 and lost > 0.0
    assert abs(dE + lost) < 2e-3 * lost
    ideal = simulate(pkdyn.load("delta", geometry=False, rotor_inertia=J_ROTOR), 0.3, 5e-4)
    assert abs(ideal.energy[-1] - ideal.energy[0]) < 1e-6 * float(np.max(ideal.kinetic))


# --------------------------------------------------------------------------- descriptions


def test_description_elements_round_trip(plain):
    robot = pkdyn.load("delta", geometry=False, rotor_inertia=J_ROTOR, efficiency=0.9)
    a = robot.actuators[0]
    assert (a.rotor_inertia, a.efficiency, a.backdrive_efficiency) == (J_ROTOR, 0.9, None)
    xml = delta_lib.build_urdf(delta_lib.Params())
    assert "pkdyn:rotor_inertia" not in xml  # defaults write nothing (committed URDFs unchanged)
    drive = (
        '<pkdyn:rotor_inertia value="3e-5"/><pkdyn:efficiency value="0.9" backdrive="0.8"/>'
        '<pkdyn:motor_friction viscous="1e-4" coulomb="0.02"/>'
    )
    xml2 = re.sub(r"(</mechanicalReduction>)", r"\1" + drive, xml, count=1)
    r2 = load_string(xml2, "edited", geometry=False)
    a = r2.actuators[0]
    assert (a.rotor_inertia, a.efficiency, a.backdrive_efficiency) == (3e-5, 0.9, 0.8)
    assert (a.viscous, a.coulomb) == (1e-4, 0.02)
    assert r2.model.armature[r2.actuated_v[0]] == pytest.approx(400 * 3e-5)
    assert r2.model.armature[r2.actuated_v[1]] == 0.0
    # the MJCF export carries the armature (MuJoCo's reflected rotor inertia)
    assert 'armature="0.012"' in to_mjcf(r2)


@pytest.mark.parametrize(
    ("element", "needle"),
    [
        ('<pkdyn:efficiency value="1.2"/>', "efficiency> value='1.2': must lie in \\(0, 1\\]"),
        ('<pkdyn:efficiency value="0.9" backdrive="0"/>', "backdrive='0'"),
        ('<pkdyn:rotor_inertia value="-1e-5"/>', "rotor_inertia> value='-1e-5'"),
        ('<pkdyn:rotor_inertia value="nan"/>', "NaN"),
        ("<pkdyn:rotor_inertia/>", "missing attribute 'value'"),
        ('<pkdyn:motor_friction coulomb="-1"/>', "coulomb='-1'"),
    ],
)
def test_bad_drive_elements_name_the_transmission(element, needle):
    xml = delta_lib.build_urdf(delta_lib.Params())
    bad = re.sub(r"(</mechanicalReduction>)", r"\1" + element, xml, count=1)
    with pytest.raises(DescriptionError, match="arm1_transmission") as err:
        load_string(bad, "bad", geometry=False)
    assert re.search(needle, str(err.value))


def test_with_drives_and_parameters_are_checked(plain):
    with pytest.raises(InvalidInputError, match="rotor_inertia"):
        with_drives(plain, rotor_inertia=[1e-5, 2e-5])
    with pytest.raises(InvalidInputError, match="efficiencies"):
        with_drives(plain, efficiency=0.0)
    with pytest.raises(ParameterError, match="efficiency"):
        pkdyn.load("delta", geometry=False, efficiency=1.5)
    geared = with_drives(plain, rotor_inertia=J_ROTOR)
    assert plain.model.armature.max() == 0.0  # the original is untouched
    back = with_drives(geared, rotor_inertia=0.0)
    assert np.all(back.model.armature == 0.0)
    assert pin.computeKineticEnergy(back.model, back.data, plain.q_home, np.zeros(plain.nv)) == 0


def test_mjcf_armature_round_trip():
    """MJCF carries the reflected inertia as the joint's armature: exported and read back, it
    becomes the actuator's rotor inertia again (armature / gear^2), counted once."""
    robot = pkdyn.load("delta", geometry=False, rotor_inertia=J_ROTOR)
    back = load_string(to_mjcf(robot), "delta.xml", geometry=False)
    assert [a.rotor_inertia for a in back.actuators] == pytest.approx([J_ROTOR] * 3)
    assert np.allclose(back.model.armature[back.actuated_v], N**2 * J_ROTOR)
    assert np.allclose(drives(back).armature, N**2 * J_ROTOR)
