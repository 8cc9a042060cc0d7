"""Natural frequencies against free-vibration simulations and closed forms (issue 26, item 2).

The simulations are pkdyn's constrained forward dynamics of the virtual-joint robot (its link
springs are passive elements) with the actuators replaced by springs (a joint torque
``-k_a (qa - qa_0)``), released along one mode without gravity; the FFT peak of the platform's
motion (Hann window, zero padding, parabolic interpolation) is the frequency it rings at.
"""

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.dynamics.forward import simulate
from pkdyn.exceptions import InvalidInputError
from pkdyn.precision import Material, elastic_model
from pkdyn.precision.modes import mode_trajectory, modes


def parallelogram(l=0.3, d=0.4, mc=0.5, m=2.0, r=0.01):
    """A 1-DOF parallelogram four-bar (cranks ``l``, coupler ``d``) and its effective inertia.

    The coupler translates on a circle: ``T = (2 I_crank + m l^2) qd^2 / 2`` about the crank
    pivots, so with an actuator of stiffness ``k`` on a crank ``f = sqrt(k / m_eff) / (2 pi)``.
    """
    Ic = mc * (3 * r**2 + l**2) / 12.0

    def crank(name):
        return (
            f'<link name="{name}"><inertial><origin xyz="0 0 {l / 2}"/><mass value="{mc}"/>'
            f'<inertia ixx="{Ic}" iyy="{Ic}" izz="{mc * r**2 / 2}" ixy="0" ixz="0" iyz="0"/>'
            f'</inertial><collision><origin xyz="0 0 {l / 2}"/><geometry><cylinder '
            f'radius="{r}" length="{l}"/></geometry></collision></link>'
        )

    limit = '<limit lower="-1.5" upper="1.5" effort="100" velocity="10"/>'
    xml = f"""<robot name="parallelogram" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="base"/>{crank("crank1")}{crank("crank2")}
  <link name="coupler"><inertial><origin xyz="{d / 2} 0 0"/><mass value="{m}"/>
    <inertia ixx="0.01" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="a1" type="revolute"><parent link="base"/><child link="crank1"/>
    <axis xyz="0 1 0"/>{limit}</joint>
  <joint name="c" type="revolute"><parent link="crank1"/><child link="coupler"/>
    <origin xyz="0 0 {l}"/><axis xyz="0 1 0"/>{limit}</joint>
  <joint name="a2" type="revolute"><parent link="base"/><child link="crank2"/>
    <origin xyz="{d} 0 0"/><axis xyz="0 1 0"/>{limit}</joint>
  <transmission name="t1"><type>transmission_interface/SimpleTransmission</type>
    <joint name="a1"/><actuator name="motor"><mechanicalReduction>1</mechanicalReduction>
    </actuator></transmission>
  <pkdyn:closure name="loop" type="point">
    <pkdyn:frame link="coupler" xyz="{d} 0 0"/><pkdyn:frame link="crank2" xyz="0 0 {l}"/>
  </pkdyn:closure>
  <pkdyn:platform link="coupler" xyz="{d / 2} 0 0" task="x"/>
</robot>"""
    return xml, 2 * (Ic + mc * (l / 2) ** 2) + m * l**2


@pytest.fixture(scope="module")
def four_bar(tmp_path_factory):
    xml, m_eff = parallelogram()
    path = tmp_path_factory.mktemp("parallelogram") / "parallelogram.urdf"
    path.write_text(xml)
    return pkdyn.load(str(path)), m_eff


def test_one_dof_linkage_rings_at_sqrt_k_over_m(four_bar):
    robot, m_eff = four_bar
    k = 5e3
    for qa in (0.0, 0.4, -0.7):
        q = pkdyn.forward_geometry(robot, [qa]).q
        result = modes(robot, q, k)
        assert result.frequencies.size == 1 and result.internal == 0
        assert result.f1 == pytest.approx(np.sqrt(k / m_eff) / (2 * np.pi), rel=1e-12)


def _without_gravity(robot):
    model = pin.Model(robot.model)
    model.gravity = pin.Motion.Zero()
    return dataclasses.replace(robot, model=model, data=model.createData())


def _fft_peak(x, dt):
    x = x - x.mean()
    n = x.size
    X = np.abs(np.fft.rfft(x * np.hanning(n), 16 * n))
    i = int(np.argmax(X[1:])) + 1
    a, b, c = np.log(X[i - 1 : i + 2])
    return (i + 0.5 * (a - c) / (a - 2 * b + c)) / (16 * n * dt)


def _ring(em, result, index, periods, **options):
    """Release the virtual-joint robot along a mode; the frequency its platform rings at."""
    robot = _without_gravity(em.robot)
    qa0 = robot.q_home[robot.actuated_q].copy()
    k = em.actuator_stiffness

    def torque(t, q, v):
        return -k * (q[robot.actuated_q] - qa0)

    f = result.frequencies[index]
    shape = result.platform[index][:3]
    v0 = 1e-4 * 2 * np.pi * f * result.shapes[index] / np.abs(shape).max()
    dt = 1.0 / (24 * f)
    run = simulate(robot, periods / f, dt, q0=robot.q_home, v0=v0, torque=torque, **options)
    P = np.array([robot.platform_placement(q).translation for q in run.q])
    return _fft_peak((P - P[0]) @ (shape / np.linalg.norm(shape)), dt)


def test_delta_frequencies_ring_in_simulation(delta):
    em = elastic_model(delta, 2e4)
    result = modes(em, delta.q_home)
    assert result.frequencies.size == 3  # the nacelle's three translations
    assert result.internal == 6  # the bars' spin: no stiffness, reported apart
    assert 120.0 < result.f1 < 250.0  # seed 000's measured range, for this stiffness
    for index in (0, 2):
        f = _ring(em, result, index, periods=12)
        assert f == pytest.approx(result.frequencies[index], rel=1e-4)


def test_compliant_links_ring_in_simulation(four_bar):
    robot, _ = four_bar
    em = elastic_model(robot, 5e3, material=Material("polymer", 5e9, 1.9e9, 1200.0))
    result = modes(em, robot.q_home)
    assert result.frequencies.size > 1 and result.condensed == 0
    rigid = modes(robot, robot.q_home, 5e3)
    assert result.f1 < rigid.f1  # the cranks' bending lowers it
    f = _ring(em, result, 0, periods=8, integrator="rk4", step=1.0 / (6 * result.frequencies[-1]))
    assert f == pytest.approx(result.f1, rel=1e-4)


def test_mode_shapes_are_mass_normalised_and_drawn_assembled(gough_stewart):
    em = elastic_model(gough_stewart, 2e6)
    result = modes(em, gough_stewart.q_home)
    assert np.all(np.diff(result.frequencies) >= 0.0) and result.frequencies.size == 6
    from pkdyn.precision.modes import mass_matrix

    M = mass_matrix(em.robot, result.q_elastic)
    G = result.shapes @ M @ result.shapes.T
    assert np.allclose(G, np.eye(6), atol=1e-9)
    t, Q = mode_trajectory(em, result, index=0, amplitude=0.01, cycles=1, samples=8)
    assert Q.shape == (9, em.robot.nq)
    res = [np.abs(em.robot.closure_set.residual(em.robot.data, q)).max() for q in Q]
    assert max(res) < 1e-9
    moved = [
        np.linalg.norm(
            em.robot.platform_placement(q).translation
            - em.robot.platform_placement(Q[0]).translation
        )
        for q in Q
    ]
    assert 0.002 < max(moved) <= 0.0101
    payload = result.to_json()
    assert len(payload["frequencies"]) == 6 and payload["internal_mobilities"] == 0
    with pytest.raises(InvalidInputError, match="7 is not a mode number"):
        mode_trajectory(em, result, index=6)


def test_vibrations_about_the_equilibrium_under_gravity(delta):
    """Modes about the weighted equilibrium (geometric terms of the weight) ring as simulated.

    The simulation starts at that equilibrium, gravity on, the actuator springs held at their
    commanded angles: the nacelle rings about it at the loaded frequency.
    """
    em = elastic_model(delta, 500.0)  # soft arms: the weight's geometric terms show
    free = modes(em, delta.q_home)
    loaded = modes(em, delta.q_home, gravity=True)
    assert loaded.q_elastic is not None
    sag = (
        delta.platform_placement(loaded.q).translation
        - delta.platform_placement(delta.q_home).translation
    )
    assert sag[2] < -2e-4  # the nacelle sinks under its weight
    assert loaded.frequencies.size == 3 and loaded.internal == 6
    assert abs(loaded.f1 / free.f1 - 1.0) > 1e-4  # and its frequencies change
    robot = em.robot
    qa0 = delta.q_home[robot.actuated_q].copy()
    k = em.actuator_stiffness

    def torque(t, q, v):
        return -k * (q[robot.actuated_q] - qa0)

    f = loaded.frequencies[2]
    shape = loaded.platform[2][:3]
    v0 = 1e-4 * 2 * np.pi * f * loaded.shapes[2] / np.abs(shape).max()
    dt = 1.0 / (24 * f)
    run = simulate(robot, 12 / f, dt, q0=loaded.q_elastic, v0=v0, torque=torque)
    P = np.array([robot.platform_placement(q).translation for q in run.q])
    rung = _fft_peak((P - P[0]) @ (shape / np.linalg.norm(shape)), dt)
    assert rung == pytest.approx(f, rel=3e-5)
    assert abs(rung - free.frequencies[2]) > 5 * abs(rung - f)  # the weight's terms are seen
