"""A coupling of a sum: a leg whose ankle rotor turns with the knee plus the ankle.

A planar leg (hip, knee and ankle about ``y``) with a geared rotor on the thigh (an unbounded
joint: its angle is its cos / sin pair's) tied to the sum of the knee and ankle angles,
``knee + ankle - rotor / 12 = 0``: the coupling published legged robots use (a belt or a linkage
that makes the ankle drive's rotor turn with the foot's pitch relative to the thigh).
Actuators on the hip, the knee and the ankle; the rotor's inertia is reflected through the
coupling. Checks against physics and a second engine:

- mobility 3 (4 joints, 1 coupling), the description read and written back;
- a passive fall under gravity: the energy balance, the coupling kept;
- statics by virtual work: the holding efforts are the derivatives of the potential energy
  along the coordinates the actuators drive (finite differences of the forward geometry);
- inverse dynamics against MuJoCo: the export writes the coupling as a fixed tendon held by a
  tendon equality; MuJoCo's own equality residual vanishes at pkdyn's configurations and its
  inverse dynamics, explained through its equality Jacobian, gives pkdyn's efforts;
- bad descriptions: one line naming the coupling.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.mobility import mobility
from pkdyn.analysis.statics import static_equilibrium
from pkdyn.cli import main
from pkdyn.dynamics.forward import simulate
from pkdyn.dynamics.inverse import inverse_dynamics
from pkdyn.dynamics.trajectory import JointTrajectory
from pkdyn.exceptions import DescriptionError
from pkdyn.model.description import LinearCouplingSpec, parse_description
from pkdyn.model.formats.urdf_writer import UrdfWriter

RATIO = 12.0
COUPLING = (
    '<pkdyn:coupling name="ankle_rotor" offset="0">'
    '<pkdyn:term joint="knee" coefficient="1"/><pkdyn:term joint="ankle" coefficient="1"/>'
    f'<pkdyn:term joint="rotor" coefficient="{-1 / RATIO!r}"/></pkdyn:coupling>'
)


def _link(name: str, mass: float, com: str, i: float) -> str:
    return (
        f'<link name="{name}"><inertial><origin xyz="{com}"/><mass value="{mass}"/>'
        f'<inertia ixx="{i}" iyy="{i}" izz="{0.5 * i}" ixy="0" ixz="0" iyz="0"/></inertial>'
        "</link>"
    )


def _joint(name: str, kind: str, parent: str, child: str, xyz: str) -> str:
    limit = (
        '<limit lower="-3" upper="3" effort="50" velocity="20"/>' if kind != "continuous" else ""
    )
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}"/><axis xyz="0 1 0"/>{limit}</joint>'
    )


def _transmission(joint: str) -> str:
    return (
        f'<transmission name="t_{joint}"><type>SimpleTransmission</type><joint name="{joint}"/>'
        f'<actuator name="m_{joint}"><mechanicalReduction>1</mechanicalReduction></actuator>'
        "</transmission>"
    )


def leg_urdf(coupling: str = COUPLING) -> str:
    return f"""<robot name="leg" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="base"/>
  {_link("thigh", 2.0, "0.02 0 -0.15", 0.02)}
  {_link("shank", 1.0, "0 0 -0.15", 0.01)}
  {_link("foot", 0.5, "0.05 0 -0.02", 0.002)}
  {_link("rotor", 0.3, "0 0 0", 4e-4)}
  {_joint("hip", "revolute", "base", "thigh", "0 0 0")}
  {_joint("knee", "revolute", "thigh", "shank", "0 0 -0.3")}
  {_joint("ankle", "revolute", "shank", "foot", "0 0 -0.3")}
  {_joint("rotor", "continuous", "thigh", "rotor", "0 0 -0.05")}
  {_transmission("hip")}{_transmission("knee")}{_transmission("ankle")}
  {coupling}
  <pkdyn:platform link="foot" xyz="0.1 0 -0.05" task="x z ry"/>
</robot>"""


@pytest.fixture(scope="module")
def leg():
    return pkdyn.load_string(leg_urdf(), "leg")


def _q(robot: pkdyn.Robot, hip: float, knee: float, ankle: float) -> np.ndarray:
    """The configuration of three angles, the rotor on the coupling."""
    q = pin.neutral(robot.model)
    idx = {n: robot.model.joints[robot.model.getJointId(n)].idx_q for n in ("hip", "knee", "ankle")}
    q[idx["hip"]], q[idx["knee"]], q[idx["ankle"]] = hip, knee, ankle
    i = robot.model.joints[robot.model.getJointId("rotor")].idx_q
    rotor = RATIO * (knee + ankle)
    q[i : i + 2] = math.cos(rotor), math.sin(rotor)
    return q


def test_description_mobility_and_round_trip(leg, tmp_path, capsys):
    c = leg.couplings[0]
    assert isinstance(c, LinearCouplingSpec)
    assert c.terms == (("knee", 1.0), ("ankle", 1.0), ("rotor", -1 / RATIO)) and c.offset == 0.0
    assert leg.constraints.kinds == ["coupling"] and leg.nv == 4 and leg.nq == 5
    assert mobility(leg).mobility == 3 and leg.dof(_q(leg, 0.3, -0.5, 0.2)) == 3
    w = UrdfWriter("leg")
    w.linear_coupling("ankle_rotor", c.terms, c.offset)
    text = w.to_string()
    again = parse_description(text, "written").couplings
    assert again == (c,)
    path = tmp_path / "leg.urdf"
    path.write_text(leg_urdf())
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "ankle_rotor (knee + ankle - 0.0833333 rotor = 0)" in out, out


def test_passive_fall_keeps_energy_and_the_coupling(leg):
    q0 = _q(leg, 0.4, -0.6, 0.3)
    out = simulate(leg, 1.0, 0.01, q0=q0)
    assert out.energy_drift() < 1e-8
    assert float(np.max(out.coupling_residual)) < 1e-9
    # the rotor turned many times (its angle wraps; the coupling holds through)
    i = leg.model.joints[leg.model.getJointId("rotor")].idx_v
    assert float(np.ptp(np.cumsum(out.v[:, i]) * 0.01)) > 2 * math.pi


def test_statics_by_virtual_work(leg):
    """Holding efforts: ``tau_k = dV/dqa_k`` along the coordinates the actuators drive (the
    forward geometry keeps the coupling), central differences of the potential energy."""
    q = _q(leg, 0.3, -0.5, 0.2)
    st = static_equilibrium(leg, q, gravity=True)
    qa = q[leg.actuated_q].copy()
    data = leg.model.createData()

    def V(a: np.ndarray) -> float:
        x = pkdyn.forward_geometry(leg, a, q_init=q, check_limits=False).q
        return float(pin.computePotentialEnergy(leg.model, data, x))

    h = 1e-6
    grad = [(V(qa + h * e) - V(qa - h * e)) / (2 * h) for e in np.eye(3)]
    np.testing.assert_allclose(st.tau, grad, rtol=1e-7, atol=1e-9)
    # the coupling's generalized force (joint i receives coefficient_i times it) balances the
    # rotor's equation: nothing loads the balanced rotor at rest
    assert abs(st.couplings["ankle_rotor"]) < 1e-12 * np.abs(st.tau).max()
    # under a moment on the foot the same, and the efforts are -J^T F (virtual work)
    F = np.array([0.0, 0.0, 0.0, 0.0, 2.0, 0.0])
    J = np.array(
        [
            pin.log3(
                leg.platform_placement(pkdyn.forward_geometry(leg, qa + h * e, q_init=q).q).rotation
                @ leg.platform_placement(
                    pkdyn.forward_geometry(leg, qa - h * e, q_init=q).q
                ).rotation.T
            )[1]
            / (2 * h)
            for e in np.eye(3)
        ]
    )
    st_f = static_equilibrium(leg, q, F)
    np.testing.assert_allclose(st_f.tau, -2.0 * J, rtol=1e-7, atol=1e-9)


mujoco = pytest.importorskip("mujoco")


def test_inverse_dynamics_against_mujoco(leg):
    from pkdyn.model.formats.mjcf import to_mjcf
    from pkdyn.model.formats.mjcf_mujoco import actuator_efforts
    from pkdyn.model.formats.mjcf_state import StateMap

    xml = to_mjcf(leg)
    assert '<fixed name="ankle_rotor/sum">' in xml
    mj = mujoco.MjModel.from_xml_string(xml)
    smap = StateMap(leg)
    # a motion on the coupling: hip, knee, ankle sinusoids, the rotor their geared sum (its angle
    # kept within half a turn, as MuJoCo's qpos and pkdyn's cos / sin pair then agree)
    t = np.linspace(0.0, 0.5, 11)
    amp = np.array([0.3, 0.1, 0.08])
    w = np.array([2.0, 3.0, 5.0])
    ang = amp * np.sin(np.outer(t, w))
    d_ang = amp * w * np.cos(np.outer(t, w))
    dd_ang = -amp * w**2 * np.sin(np.outer(t, w))
    rot = RATIO * (ang[:, 1] + ang[:, 2])
    assert np.abs(rot).max() < math.pi
    q = np.array([_q(leg, *a) for a in ang])
    v = np.column_stack([d_ang, RATIO * (d_ang[:, 1] + d_ang[:, 2])])
    a = np.column_stack([dd_ang, RATIO * (dd_ang[:, 1] + dd_ang[:, 2])])
    order = [
        leg.model.joints[leg.model.getJointId(n)].idx_v for n in ("hip", "knee", "ankle", "rotor")
    ]
    V = np.zeros_like(v)
    A = np.zeros_like(a)
    V[:, order], A[:, order] = v, a
    res = inverse_dynamics(
        leg, JointTrajectory(t, q, V, A, leg.actuated_q, leg.actuated_v), progress=False
    )
    data = mujoco.MjData(mj)
    for k in range(t.size):
        data.qpos[:] = smap.qpos(q[k])
        data.qvel[:] = smap.qvel(q[k], V[k])
        data.qacc[:] = smap.qacc(q[k], V[k], A[k])
        mujoco.mj_inverse(mj, data)
        eq = np.asarray(data.efc_type[: data.nefc]) == mujoco.mjtConstraint.mjCNSTR_EQUALITY
        assert np.abs(np.asarray(data.efc_pos[: data.nefc])[eq]).max() < 1e-12
        tau_mj = actuator_efforts(mj, data)
        np.testing.assert_allclose(res.tau[k], tau_mj, rtol=1e-9, atol=1e-9 * np.abs(tau_mj).max())


@pytest.mark.parametrize(
    ("coupling", "message"),
    [
        ('<pkdyn:coupling name="c"><pkdyn:term joint="knee" coefficient="1"/>'
         '<pkdyn:term joint="knee" coefficient="2"/></pkdyn:coupling>', "two terms"),
        ('<pkdyn:coupling name="c"><pkdyn:term joint="knee" coefficient="0"/></pkdyn:coupling>',
         "zero"),
        ('<pkdyn:coupling name="c"><pkdyn:term joint="knee" coefficient="nan"/>'
         "</pkdyn:coupling>", "finite"),
        ('<pkdyn:coupling name="c"><pkdyn:term joint="knee"/></pkdyn:coupling>', "coefficient"),
        ('<pkdyn:coupling name="c"><pkdyn:term joint="elbow" coefficient="1"/>'
         "</pkdyn:coupling>", "elbow"),
        ('<pkdyn:coupling name="c" offset="inf"><pkdyn:term joint="knee" coefficient="1"/>'
         "</pkdyn:coupling>", "finite"),
        ('<pkdyn:coupling name="c" joint="knee"><pkdyn:term joint="ankle" coefficient="1"/>'
         "</pkdyn:coupling>", "'joint'"),
        ('<pkdyn:coupling name="c"><pkdyn:terms joint="ankle" coefficient="1"/>'
         "</pkdyn:coupling>", "pkdyn:terms"),
        ('<pkdyn:coupling name="hip_loop"><pkdyn:term joint="hip" coefficient="1"/>'
         '</pkdyn:coupling><pkdyn:coupling name="hip_loop"><pkdyn:term joint="knee" '
         'coefficient="1"/></pkdyn:coupling>', "given twice"),
    ],
)  # fmt: skip
def test_bad_couplings_name_the_coupling(coupling, message, tmp_path, capsys):
    with pytest.raises(DescriptionError, match=message) as err:
        pkdyn.load_string(leg_urdf(coupling), "leg")
    assert "coupling" in str(err.value)
    path = tmp_path / "bad.urdf"
    path.write_text(leg_urdf(coupling))
    assert main(["info", str(path)]) == 1
    line = capsys.readouterr().err.strip()
    assert line.startswith("pkdyn: error:") and "\n" not in line and "coupling" in line


def test_simulation_reports_the_coupling_apart(tmp_path, capsys):
    """The closures' residual and the couplings' are reported apart (JSON, table, CSV)."""
    import json

    path = tmp_path / "leg.urdf"
    path.write_text(leg_urdf())
    csv = tmp_path / "run.csv"
    argv = ["simulate", str(path), "--duration", "0.1", "--dt", "0.01", "--csv", str(csv)]
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["max_closure_residual"] == 0.0  # no closure
    assert 0.0 <= out["max_coupling_residual"] < 1e-9
    assert "coupling_residual" in csv.read_text().splitlines()[0]
    assert main(argv[:-2]) == 0
    assert "max coupling residual" in capsys.readouterr().out
