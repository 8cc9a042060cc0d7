"""Passive elements: joint springs, dampers, Coulomb friction, two-frame springs.

Proved by physics and independent references, not by re-running pkdyn:

- forces are the negative gradient of the springs' potential energy (finite differences on the
  configuration manifold, spherical and universal joints included);
- a single-joint spring-mass against its closed form (damped period and logarithmic decrement;
  Coulomb friction: linear decay of 4 F0 / k per period);
- energy: an undamped closed-loop run with springs conserves kinetic + gravity + elastic energy
  (< 0.1 % over 10 s); with dampers, the mechanical energy lost is the dissipated work; along a
  trajectory the actuators' power balances d(energy)/dt + dissipation;
- statics with springs = virtual work (finite differences of the total potential along the
  closures);
- MuJoCo (an independent engine) on the export: hinge / ball stiffness and springref, joint
  damping, spatial tendons for the two-frame springs: pkdyn's actuator efforts against
  ``mj_inverse`` projected onto the actuators.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from conftest import null_space, simpson_work

import pkdyn
from pkdyn.analysis.statics import static_equilibrium
from pkdyn.cli import main
from pkdyn.dynamics import inverse_dynamics, simulate
from pkdyn.dynamics.trajectory import named_trajectory
from pkdyn.model.description import FrameRef, PassiveSpec, SpringSpec
from pkdyn.model.passive import with_passive
from solvers import FrameSpring, PassiveForces

G = 9.81
DATA = Path(__file__).parent / "data" / "public"


def _slider_urdf(kind: str, mass: float, extra: str, limit: str = "-1 1") -> str:
    """One body on one joint along / about x (gravity along -z does no work on it)."""
    lo, hi = limit.split()
    return f"""<robot name="slider" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="ground"/>
  <link name="body">
    <inertial><origin xyz="0 0 0"/><mass value="{mass}"/>
      <inertia ixx="{mass}" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="slide" type="{kind}">
    <parent link="ground"/><child link="body"/><axis xyz="1 0 0"/>
    <limit lower="{lo}" upper="{hi}" effort="10" velocity="10"/>
    {extra}
  </joint>
</robot>"""


def _crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Times of the upward zero crossings of ``x`` (linear interpolation)."""
    k = np.flatnonzero((x[:-1] < 0.0) & (x[1:] >= 0.0))
    return t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])


# ------------------------------------------------------------------------------ closed forms


@pytest.mark.parametrize("kind", ["prismatic", "revolute"])
def test_damped_spring_mass_matches_its_closed_form(kind):
    """m x'' + c x' + k (x - r) = 0: period 2 pi / w_d, log decrement 2 pi zeta / sqrt(1 - z^2).

    Prismatic: a 2 kg slider; revolute: a rotor of inertia 2 kg m^2 about x (ixx = mass).
    """
    m, k, c, r = 2.0, 200.0, 2.0, 0.05
    urdf = _slider_urdf(kind, m, f'<dynamics damping="{c}"/>').replace(
        "</robot>", f'<pkdyn:passive joint="slide" stiffness="{k}" rest="{r}"/></robot>'
    )
    robot = pkdyn.load_string(urdf, "slider")
    x0 = 0.15
    res = simulate(robot, 3.0, 1e-3, q0=np.array([x0]), v0=np.zeros(1))
    wn = np.sqrt(k / m)
    zeta = c / (2.0 * np.sqrt(k * m))
    wd = wn * np.sqrt(1.0 - zeta**2)
    t = res.t
    closed = r + (x0 - r) * np.exp(-zeta * wn * t) * (
        np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t)
    )
    assert np.max(np.abs(res.q[:, 0] - closed)) < 1e-10  # observed 6e-14 [m or rad]
    # period from the zero crossings, decay from successive peaks
    period = np.diff(_crossings(t, res.q[:, 0] - r))
    np.testing.assert_allclose(period, 2 * np.pi / wd, rtol=1e-6)  # observed 7e-8
    Td = 2 * np.pi / wd
    peaks = [np.max(res.q[np.abs(t - n * Td) < 0.25 * Td, 0] - r) for n in (0, 4)]
    decrement = np.log(peaks[0] / peaks[1]) / 4  # per period
    # observed 7e-6 (the peaks are read at the 1 ms samples)
    assert decrement == pytest.approx(2 * np.pi * zeta / np.sqrt(1 - zeta**2), rel=1e-4)
    # energy: what the mechanism lost is what the damper dissipated
    assert res.energy_drift() < 1e-7
    assert res.elastic[0] == pytest.approx(0.5 * k * (x0 - r) ** 2)


def test_coulomb_friction_decays_linearly():
    """Dry friction F0 on a spring-mass: amplitude falls by 4 F0 / k per period 2 pi / w_n."""
    m, k, f0 = 1.0, 100.0, 0.5
    robot = pkdyn.load_string(
        _slider_urdf("prismatic", m, f'<dynamics friction="{f0}"/>').replace(
            "</robot>", f'<pkdyn:passive joint="slide" stiffness="{k}"/></robot>'
        ),
        "slider",
    )
    x0 = 0.2
    res = simulate(robot, 1.5, 1e-3, q0=np.array([x0]), v0=np.zeros(1))
    T = 2 * np.pi / np.sqrt(k / m)
    t, x = res.t, res.q[:, 0]
    peaks = [np.max(x[(t >= (n - 0.25) * T) & (t < (n + 0.25) * T)]) for n in (1, 2)]
    drop = 4 * f0 / k
    # the tanh smoothing (1 cm/s against peak speeds of 2 m/s): observed 3e-5
    assert x0 - peaks[0] == pytest.approx(drop, rel=1e-3)
    assert peaks[0] - peaks[1] == pytest.approx(drop, rel=1e-3)
    assert res.energy_drift() < 1e-6
    assert np.all(np.diff(res.dissipated) >= -1e-15)


# ------------------------------------------------------------------------------ gradients


def _fd_gradient(model: pin.Model, fn, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    g = np.zeros(model.nv)
    for i in range(model.nv):
        e = np.zeros(model.nv)
        e[i] = h
        g[i] = (fn(pin.integrate(model, q, e)) - fn(pin.integrate(model, q, -e))) / (2 * h)
    return g


def test_spring_forces_are_minus_the_gradient_of_their_energy():
    """Joint springs on every kind of joint (anisotropic spherical, universal) and two-frame
    springs: f = -dV/dq on the manifold, at random configurations."""
    robot = pkdyn.load("delta", geometry=False, bar_joint="spherical")
    model = robot.model
    rng = np.random.default_rng(3)
    stiff = rng.uniform(0.5, 3.0, model.nv)
    rest = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    springs = [
        FrameSpring(0, pin.SE3(np.eye(3), np.array([0.15, 0.0, 0.1])), 1, pin.SE3.Random(), 80.0),
        FrameSpring(2, pin.SE3.Random(), model.njoints - 1, pin.SE3.Random(), 50.0, 0.05),
    ]
    passive = PassiveForces(model, stiffness=stiff, rest=rest, springs=springs)
    for _ in range(3):
        q = pin.integrate(model, robot.q_home, 0.3 * rng.standard_normal(model.nv))
        f = passive.conservative_force(q)
        g = _fd_gradient(model, passive.potential, q)
        np.testing.assert_allclose(f, -g, rtol=0, atol=1e-6 * np.max(np.abs(f)))
        np.testing.assert_allclose(passive.forces(q[None], np.zeros((1, model.nv)))[0], f)


def test_spherical_spring_is_mujocos_ball_spring():
    """Isotropic ball spring: f = -k log3(R_rest^T R) (MuJoCo's mju_subQuat law)."""
    model = pin.Model()
    model.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    rest = np.array([0.1, -0.2, 0.3, 0.9])
    rest /= np.linalg.norm(rest)
    passive = PassiveForces(model, stiffness=7.0, rest=rest)
    q = pin.randomConfiguration(model)
    R0 = pin.Quaternion(rest[3], *rest[:3]).matrix()
    R = pin.Quaternion(q[3], *q[:3]).matrix()
    np.testing.assert_allclose(passive.conservative_force(q), -7.0 * pin.log3(R0.T @ R))


def test_dissipation_is_never_negative():
    model = pin.Model()
    model.addJoint(0, pin.JointModelPX(), pin.SE3.Identity(), "x")
    passive = PassiveForces(model, damping=0.3, friction=0.2)
    v = np.linspace(-2.0, 2.0, 41)[:, None]
    assert np.all(passive.dissipations(v) >= 0.0)
    f = np.array([passive.dissipative_force(vk) for vk in v])
    assert np.all(f * v <= 0.0)


# ------------------------------------------------------------------------------ energy


def _springy_five_bar() -> pkdyn.Robot:
    robot = pkdyn.load("five_bar", geometry=False)
    return with_passive(
        robot,
        [
            PassiveSpec("distal1", stiffness=(0.4,), rest=(-1.5,)),
            PassiveSpec("proximal2", stiffness=(0.3,), rest=(2.0,)),
        ],
        [
            SpringSpec(
                "s1",
                FrameRef("base", pin.SE3(np.eye(3), np.array([0.0, 0.2, 0.0]))),
                FrameRef("distal2", pin.SE3(np.eye(3), np.array([0.15, 0.0, 0.0]))),
                20.0,
                0.1,
            )
        ],
    )


def test_undamped_run_with_springs_conserves_energy():
    """Closed loop, joint and two-frame springs, 10 s: total energy within 0.1 %."""
    robot = _springy_five_bar()
    res = simulate(robot, 10.0, 1e-2, record_every=10)
    assert np.ptp(res.elastic) > 0.05  # the springs exchanged energy with the motion [J]
    assert np.max(res.kinetic) > 0.05
    E = res.energy
    assert np.max(np.abs(E - E[0])) < 1e-3 * np.max(np.abs(E))
    assert res.energy_drift() < 1e-6  # relative to the largest kinetic energy (observed 1e-9)
    assert np.max(res.closure_residual) < 1e-8


def test_dampers_dissipate_what_the_mechanism_loses():
    robot = _springy_five_bar()
    damped = with_passive(
        robot,
        [
            PassiveSpec(
                "distal1", stiffness=(0.4,), rest=(-1.5,), damping=(0.01,), friction=(0.005,)
            )
        ],
    )
    res = simulate(damped, 2.0, 2e-3, record_every=10)
    assert res.dissipated[-1] > 0.5 * (res.energy[0] - res.energy[-1]) > 0.0
    assert res.energy_drift() < 1e-6
    # the robot's own elements can be left out: then nothing dissipates
    free = simulate(damped, 0.2, 2e-3, passive=False)
    assert np.all(free.dissipated == 0.0) and np.all(free.elastic == 0.0)


def test_inverse_dynamics_power_balance_with_springs_and_dampers():
    """Along the Adept cycle: sum tau qa_dot = d(kinetic + gravity + elastic)/dt + dissipation."""
    robot = _balanced_delta(damping=0.02)
    traj = named_trajectory(robot, "adept", cycle_time=0.6, dt=1e-3)
    ef = inverse_dynamics(robot, traj)
    P = np.sum(ef.tau * traj.qa_dot, axis=1) - ef.dissipation
    work, idx = simpson_work(traj.t, P)
    dE = (ef.energy - ef.energy[0])[idx]
    assert np.max(np.abs(ef.elastic)) > 0.1
    assert np.max(ef.dissipation) > 1e-3 * np.max(np.abs(P))
    assert np.max(np.abs(work - dE)) < 1e-4 * np.max(np.abs(dE))  # observed 2e-6
    bare = inverse_dynamics(robot, traj, passive=False)
    assert np.max(np.abs(bare.tau - ef.tau)) > 0.1 * np.max(np.abs(bare.tau))


# ------------------------------------------------------------------------------ statics


def _balanced_delta(damping: float = 0.0) -> pkdyn.Robot:
    robot = pkdyn.load("delta", geometry=False, bar_joint="universal")
    p = robot.params
    springs = []
    for i, th in enumerate(p.theta, start=1):
        u = np.array([np.cos(th), np.sin(th), 0.0])
        springs.append(
            SpringSpec(
                f"balance{i}",
                FrameRef("base", pin.SE3(np.eye(3), p.ra * u + np.array([0.0, 0.0, 0.12]))),
                FrameRef(f"arm{i}", pin.SE3(np.eye(3), np.array([0.12, 0.0, 0.0]))),
                150.0,
                0.01,
            )
        )
    joints = [
        PassiveSpec(f"arm{i}", stiffness=(1.5,), rest=(0.4,), damping=(damping,)) for i in (1, 2, 3)
    ]
    return with_passive(robot, joints, springs)


@pytest.mark.parametrize("name", ["five_bar", "delta"])
def test_statics_with_springs_is_virtual_work(name):
    """tau_i = d(V_gravity + V_springs)/d qa_i along the closures (forward geometry)."""
    robot = _springy_five_bar() if name == "five_bar" else _balanced_delta()
    rng = np.random.default_rng(5)
    qa0 = robot.q_home[robot.actuated_q] + 0.05 * rng.standard_normal(len(robot.actuators))
    q0 = pkdyn.forward_geometry(robot, qa0).q
    data = robot.model.createData()

    def energy(qa: np.ndarray) -> float:
        q = pkdyn.forward_geometry(robot, qa, q_init=q0).q
        return float(pin.computePotentialEnergy(robot.model, data, q)) + robot.passive.potential(q)

    h = 1e-5
    grad = np.array(
        [
            (energy(qa0 + h * e) - energy(qa0 - h * e)) / (2 * h)
            for e in np.eye(len(robot.actuators))
        ]
    )
    tau = static_equilibrium(robot, q0, gravity=True).tau
    np.testing.assert_allclose(tau, grad, rtol=0, atol=1e-6 * np.max(np.abs(tau)))
    without = static_equilibrium(robot, q0, gravity=True, passive=False).tau
    assert np.max(np.abs(without - tau)) > 0.1 * np.max(np.abs(tau))


# ------------------------------------------------------------------------------ MuJoCo


def test_springs_and_dampers_match_mujoco():
    """Export (stiffness / springref, ball stiffness, damping, spatial tendons) and compare
    pkdyn's actuator efforts with MuJoCo's mj_inverse projected onto the actuators."""
    mujoco = pytest.importorskip("mujoco")
    from pkdyn.model.formats.mjcf import MjcfOptions, StateMap, actuator_efforts, to_mjcf
    from solvers import Actuation, ForwardDynamics, InverseDynamics

    base = _balanced_delta(damping=0.05)
    robot = with_passive(
        pkdyn.load("delta", geometry=False),  # ball-jointed bars: ball stiffness and damping
        list(base.description.passive)
        + [PassiveSpec(f"bar{i}a_upper", stiffness=(0.2,), damping=(0.01,)) for i in (1, 2, 3)],
        list(base.description.springs),
    )
    model = mujoco.MjModel.from_xml_string(to_mjcf(robot, MjcfOptions(contacts=False)))
    assert model.ntendon == 3 and np.all(model.tendon_stiffness == 150.0)
    model.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    smap = StateMap(robot)
    red = np.array([a.reduction for a in robot.actuators])
    act = Actuation(robot.actuated_v, gains=red, names=robot.actuator_names)
    inv = InverseDynamics(robot.model, robot.constraint_models, act)
    fd = ForwardDynamics(robot.model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(11)
    kin = robot.model.createData()
    for _ in range(3):
        dq = 0.05 * rng.standard_normal(robot.nv)
        q = pkdyn.project(robot, pin.integrate(robot.model, robot.q_home, dq))
        _, J = robot.closure_set.residual_and_jacobian(kin, q)
        Z = null_space(J)
        v = Z @ rng.standard_normal(Z.shape[1])
        tau = rng.uniform(-0.5, 0.5, 3)  # motor side
        a = fd.acceleration(q, v, act.generalized(tau, robot.nv) + robot.passive.force(q, v))
        tau_pk = inv.solve(q, v, a, f_ext=robot.passive.force(q, v)).tau
        np.testing.assert_allclose(tau_pk, tau, rtol=0, atol=1e-9)  # ID inverts FD
        data.qpos[:] = smap.qpos(q)
        data.qvel[:] = smap.qvel(q, v)
        data.qacc[:] = smap.qacc(q, v, a)
        mujoco.mj_inverse(model, data)
        tau_mj = actuator_efforts(model, data)
        passive_mj = smap.force(q, data.qfrc_passive)
        np.testing.assert_allclose(passive_mj, robot.passive.force(q, v), atol=1e-9)
        np.testing.assert_allclose(tau_mj, tau_pk, rtol=0, atol=1e-8 * np.max(np.abs(tau_pk)))


# ------------------------------------------------------------------------------ description


def test_description_elements_build_the_forces():
    """<dynamics> + pkdyn:passive (per DOF on a spherical joint) + pkdyn:spring."""
    robot = pkdyn.load("delta", geometry=False)
    urdf = pkdyn.model.families.FAMILIES["delta"].build_urdf(robot.params)
    urdf = urdf.replace(
        "</robot>",
        '<pkdyn:passive joint="arm1" stiffness="2" rest="0.3" friction="0.1"/>'
        '<pkdyn:passive joint="bar1a_upper" stiffness="1 2 3" rest="0 0.1 0" damping="0.01"/>'
        '<pkdyn:spring name="balance1" stiffness="150" rest_length="0.01">'
        '<pkdyn:frame link="base" xyz="0.15 0 0.12"/><pkdyn:frame link="arm1" xyz="0.12 0 0"/>'
        "</pkdyn:spring></robot>",
    )
    robot = pkdyn.load_string(urdf, "delta+springs", geometry=False)
    model, P = robot.model, robot.passive
    arm = model.joints[model.getJointId("arm1")]
    bar = model.joints[model.getJointId("bar1a_upper")]
    iv = slice(bar.idx_v, bar.idx_v + 3)
    assert P.stiffness[arm.idx_v] == 2.0 and P.rest[arm.idx_q] == 0.3
    assert P.friction[arm.idx_v] == 0.1 and model.friction[arm.idx_v] == 0.1
    np.testing.assert_array_equal(P.stiffness[iv], [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(model.damping[iv], [0.01] * 3)
    R_rest = pin.Quaternion(P.rest[bar.idx_q + 3], *P.rest[bar.idx_q : bar.idx_q + 3]).matrix()
    np.testing.assert_allclose(pin.log3(R_rest), [0.0, 0.1, 0.0], atol=1e-15)
    (length, tension), *_ = P.spring_state(robot.q_home)
    assert tension == pytest.approx(150.0 * (length - 0.01))
    assert robot.description.springs[0].name == "balance1"


BAD = {
    "joint 'slide' stiffness": '<pkdyn:passive joint="slide" stiffness="-3"/>',
    "joint 'slide' <dynamics> damping": '<dynamics damping="-0.5"/>',
    "joint 'slide' <dynamics> friction": '<dynamics friction="nan"/>',
    "joint 'slide' rest=1.5": '<pkdyn:passive joint="slide" stiffness="3" rest="1.5"/>',
    "joint 'slide' damping": '<pkdyn:passive joint="slide" damping="1 2"/>',
    "pkdyn:passive joint 'nope'": '<pkdyn:passive joint="nope" damping="1"/>',
    "spring 's'": '<pkdyn:spring name="s" stiffness="3"><pkdyn:frame link="body"/>'
    '<pkdyn:frame link="body" xyz="0 0 1"/></pkdyn:spring>',
    "spring 's' rest_length": '<pkdyn:spring name="s" stiffness="2" rest_length="inf">'
    '<pkdyn:frame link="ground"/><pkdyn:frame link="body"/></pkdyn:spring>',
    "spring 's' stiffness": '<pkdyn:spring name="s" stiffness="-2">'
    '<pkdyn:frame link="ground"/><pkdyn:frame link="body"/></pkdyn:spring>',
}


@pytest.mark.parametrize("culprit", list(BAD))
def test_bad_passive_elements_name_joint_and_field(culprit, tmp_path, capsys):
    element = BAD[culprit]
    if element.startswith("<dynamics"):
        urdf = _slider_urdf("prismatic", 1.0, element)
    else:
        urdf = _slider_urdf("prismatic", 1.0, "").replace("</robot>", element + "</robot>")
    with pytest.raises(pkdyn.DescriptionError) as err:
        pkdyn.load_string(urdf, "robot.urdf")
    assert f"robot.urdf: {culprit}" in str(err.value)
    path = tmp_path / "robot.urdf"
    path.write_text(urdf)
    assert main(["info", str(path)]) == 1
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pkdyn: error: ") and culprit in lines[0]


@pytest.mark.parametrize("kind", ["fixed", "floating"])
def test_friction_on_a_joint_that_cannot_carry_it(kind):
    urdf = _slider_urdf(kind, 1.0, '<dynamics friction="0.2"/>')
    with pytest.raises(pkdyn.DescriptionError, match="joint 'slide' friction: a"):
        pkdyn.load_string(urdf, "robot.urdf")
    # zero values (common in exported URDFs) are accepted
    robot = pkdyn.load_string(_slider_urdf(kind, 1.0, '<dynamics friction="0" damping="0"/>'), "r")
    assert robot.passive is None


def test_rest_rotation_outside_a_cone_limit():
    robot = pkdyn.load("delta", geometry=False)
    with pytest.raises(pkdyn.DescriptionError, match="joint 'bar1a_upper' rest"):
        with_passive(robot, [PassiveSpec("bar1a_upper", stiffness=(1.0,), rest=(1.2, 0.0, 0.0))])


# ------------------------------------------------------------------------------ CLI

SPRINGS = (
    '<pkdyn:passive joint="arm1" stiffness="2" rest="0.3" friction="0.1"/>'
    '<pkdyn:passive joint="bar1a_upper" damping="0.01"/>'
    '<pkdyn:spring name="balance1" stiffness="150" rest_length="0.01">'
    '<pkdyn:frame link="base" xyz="0.15 0 0.12"/><pkdyn:frame link="arm1" xyz="0.12 0 0"/>'
    "</pkdyn:spring></robot>"
)


def test_cli_info_lists_passive_elements(tmp_path, capsys):
    robot = pkdyn.load("delta", geometry=False)
    path = tmp_path / "delta.urdf"
    path.write_text(
        pkdyn.model.families.FAMILIES["delta"].build_urdf(robot.params).replace("</robot>", SPRINGS)
    )
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "joint arm1: stiffness 2 N m/rad, rest 0.3 rad; friction 100 mN m" in out
    assert "joint bar1a_upper: damping 10 mN m s/rad, 10 mN m s/rad, 10 mN m s/rad" in out
    assert "spring balance1 (base - arm1): 150 N/m, free length 10 mm" in out
    assert main(["info", str(path), "--json"]) == 0
    passive = json.loads(capsys.readouterr().out)["passive"]
    assert passive["joints"][0] == {
        "joint": "arm1",
        "stiffness": [2.0],
        "friction": [0.1],
        "rest": [0.3],
    }
    s = passive["springs"][0]
    assert s["tension"] == pytest.approx(150.0 * (s["length"] - 0.01))
    assert main(["info", "delta"]) == 0
    assert "passive: none" in capsys.readouterr().out
    # size: with and without them
    argv = ["size", str(path), "--cycle-time", "0.6", "--dt", "0.01", "--payload", "1"]
    assert main([*argv, "--no-passive", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    with_p, without = out["actuators"], out["without_passive"]["actuators"]
    assert abs(with_p[0]["peak"] - without[0]["peak"]) > 0.5  # [N m]: the spring on arm 1
    assert with_p[1]["peak"] == pytest.approx(without[1]["peak"], rel=0.01)
    assert main([*argv, "--no-passive"]) == 0
    text = capsys.readouterr().out
    assert "with passive elements:" in text and "without passive elements:" in text


# ------------------------------------------------------------------------------ real model


def _menagerie_cassie_on_a_stand() -> str:
    """Menagerie's Cassie MJCF (vendored, text only) with its pelvis held: no free joint, and
    the ``home`` keyframe without the free joint's 7 coordinates."""
    text = (DATA / "menagerie_cassie" / "cassie.xml").read_text()
    key = re.search(r'<key name="home" qpos="([^"]*)"', text)
    assert key is not None
    home = " ".join(key.group(1).split()[7:])
    return text.replace(key.group(0), f'<key name="home" qpos="{home}"').replace("<freejoint/>", "")


def test_cassie_actuator_torques_match_mujoco_inverse():
    """Fixed-base Cassie (MuJoCo Menagerie) along a closure-consistent motion: pkdyn's actuator
    torques against MuJoCo's ``mj_inverse`` projected onto the actuators (least squares on
    [actuator moments, equality Jacobian]), leaf springs (1500 and 1250 N m/rad), joint
    damping (ball joints included), armature and ``ref`` (knee, tarsus) read from the MJCF.

    MuJoCo's joint-limit constraints are disabled: pkdyn's dynamics do not enforce joint limits.
    """
    mujoco = pytest.importorskip("mujoco")
    from pkdyn.dynamics.joint_motion import actuator_trajectory
    from pkdyn.model.formats.mjcf import StateMap, actuator_efforts

    text = _menagerie_cassie_on_a_stand()
    robot = pkdyn.load_string(text, "cassie.xml")
    model = robot.model
    shin = model.joints[model.getJointId("left-shin")]
    ball = model.joints[model.getJointId("left-achilles-rod")]
    assert robot.passive.stiffness[shin.idx_v] == 1500.0
    np.testing.assert_array_equal(robot.passive.damping[ball.idx_v : ball.idx_v + 3], [0.01] * 3)
    mj = mujoco.MjModel.from_xml_string(text)
    mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_LIMIT
    smap = StateMap.by_name(robot, mj)
    np.testing.assert_allclose(model.armature, smap.force(robot.q_home, mj.dof_armature))
    n = len(robot.actuators)
    t = np.linspace(0.0, 0.5, 11)
    w = 2 * np.pi / 0.5
    amp = 0.1 * np.linspace(0.5, 1.0, n)
    qa0 = robot.q_home[robot.actuated_q]
    traj = actuator_trajectory(
        robot,
        t,
        qa0 + np.outer(np.sin(w * t), amp),
        np.outer(w * np.cos(w * t), amp),
        np.outer(-(w**2) * np.sin(w * t), amp),
    )
    tau = inverse_dynamics(robot, traj).tau
    gear = np.array([a.reduction for a in robot.actuators])
    order = [mj.actuator(a.name).id for a in robot.actuators]
    data = mujoco.MjData(mj)
    stiff = mj.jnt_stiffness.copy()
    springless = []
    for k in range(t.size):
        q, v, a = traj.q[k], traj.v[k], traj.a[k]
        data.qpos[:], data.qvel[:], data.qacc[:] = smap.qpos(q), smap.qvel(q, v), smap.qacc(q, v, a)
        mujoco.mj_inverse(mj, data)
        assert data.nefc == 12  # the four connect equalities only
        np.testing.assert_allclose(smap.force(q, data.qfrc_passive), robot.passive.force(q, v))
        tau_mj = gear * actuator_efforts(mj, data)[order]
        # observed 1e-11 (the conditioning of the least squares)
        np.testing.assert_allclose(tau_mj, tau[k], rtol=0, atol=1e-8 * np.max(np.abs(tau[k])))
        # the same motion in MuJoCo without the leaf springs
        mj.jnt_stiffness[:] = 0.0
        mujoco.mj_inverse(mj, data)
        mj.jnt_stiffness[:] = stiff
        springless.append(gear * actuator_efforts(mj, data)[order])
    # without them the torques would be 41 % off (RMS over the motion; armature: 1.6 %,
    # ball-joint damping: 6e-5)
    assert np.linalg.norm(np.array(springless) - tau) > 0.2 * np.linalg.norm(tau)


PASSIVE_MJCF = """
<mujoco model="passive">
  <compiler angle="degree"/>
  <default><joint damping="0.2"/></default>
  <worldbody>
    <body name="a" pos="0 0 1">
      <inertial pos="0.1 0 0" mass="1" diaginertia="0.01 0.02 0.02"/>
      <joint name="hinge" type="hinge" axis="0 1 0" ref="30" stiffness="40" springref="45"
             armature="0.05" frictionloss="0.3"/>
      <body name="b" pos="0.2 0 0">
        <inertial pos="0 0 -0.1" mass="0.5" diaginertia="0.005 0.005 0.002"/>
        <joint name="ball" type="ball" stiffness="3" damping="0.05"/>
        <body name="c" pos="0 0 -0.2">
          <inertial pos="0 0 0" mass="0.3" diaginertia="0.001 0.001 0.001"/>
          <joint name="slide" type="slide" axis="1 0 0" ref="0.02" stiffness="500"
                 springref="0.05"/>
        </body>
      </body>
    </body>
    <body name="d" pos="1 0 1">
      <inertial pos="0 0 0" mass="0.3" diaginertia="0.001 0.001 0.001"/>
      <joint name="free" type="free" damping="0.4"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_mjcf_passive_attributes_on_every_joint_type_match_mujoco():
    """stiffness / springref / ref / damping / armature on hinge, ball, slide and free joints:
    pkdyn's passive forces = MuJoCo's qfrc_passive at random states (friction aside: MuJoCo's
    frictionloss is a constraint, pkdyn keeps its level as smooth Coulomb friction)."""
    mujoco = pytest.importorskip("mujoco")
    from pkdyn.model.formats.mjcf import StateMap

    robot = pkdyn.load_string(PASSIVE_MJCF, "passive.xml")
    mj = mujoco.MjModel.from_xml_string(PASSIVE_MJCF)
    smap = StateMap.by_name(robot, mj)
    hinge = robot.model.joints[robot.model.getJointId("hinge")]
    assert robot.passive.friction[hinge.idx_v] == pytest.approx(0.3)
    assert robot.passive.rest[hinge.idx_q] == pytest.approx(np.radians(45.0))
    np.testing.assert_allclose(smap.qpos(robot.q_home), mj.qpos0, atol=1e-12)  # ref
    np.testing.assert_allclose(robot.model.armature, smap.force(robot.q_home, mj.dof_armature))
    no_friction = PassiveForces(
        robot.model,
        robot.passive.stiffness,
        robot.passive.rest,
        robot.passive.damping,
    )
    data = mujoco.MjData(mj)
    rng = np.random.default_rng(2)
    for _ in range(4):
        q = pin.integrate(robot.model, robot.q_home, 0.4 * rng.standard_normal(robot.nv))
        v = rng.standard_normal(robot.nv)
        data.qpos[:], data.qvel[:] = smap.qpos(q), smap.qvel(q, v)
        mujoco.mj_fwdPosition(mj, data)
        mujoco.mj_fwdVelocity(mj, data)
        f_mj = smap.force(q, data.qfrc_passive)
        np.testing.assert_allclose(f_mj, no_friction.force(q, v), rtol=0, atol=1e-12)
    with pytest.raises(pkdyn.DescriptionError, match="MuJoCo joint 'hinge'"):
        StateMap.by_name(pkdyn.load("five_bar", geometry=False), mj)
