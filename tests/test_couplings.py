"""Joint couplings (gears, racks, mimic joints, MuJoCo joint equalities) as a constraint.

Checks that can fail, from physics and from a second engine:

- the coupling rows (residual, Jacobian, drift) against finite differences, on revolute,
  unbounded revolute (cos/sin) and prismatic joints, and the sampled (vectorised) rows against
  them;
- a gear pair (with its polynomial variant: a cam law) and a rack and pinion against their
  closed forms: positions, velocities, statics by virtual work (the tooth force as the coupling
  reaction), accelerations from Lagrange's equations, energy and power balance in simulation,
  inverse dynamics along a trajectory;
- the UFACTORY xArm7 gripper and the Robotiq 2F-85 from MuJoCo Menagerie against MuJoCo itself:
  the equality constraints hold (MuJoCo's ``efc_pos``) along a closing motion, the same rank of
  the equality Jacobian, the mass matrix and bias forces, and the actuator effort at rest under a
  fingertip force (MuJoCo's inverse dynamics through its own constraint Jacobian and tendon);
- the sources: ``pkdyn:coupling`` (written back by the URDF writer), URDF ``<mimic>``, Gepetto
  sidecars, MJCF joint equalities (with ``ref``), the MJCF export (couplings as joint
  equalities, checked by MuJoCo);
- bad input: one line naming the coupling or the equality.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.analysis.kinematics import kinematic_models
from pkdyn.analysis.mobility import format_mobility, mobility
from pkdyn.analysis.singularity import classify
from pkdyn.analysis.statics import actuator_efforts, static_equilibrium
from pkdyn.cli import main
from pkdyn.dynamics.actuation import actuation
from pkdyn.dynamics.forward import simulate
from pkdyn.dynamics.inverse import inverse_dynamics
from pkdyn.dynamics.sizing import size
from pkdyn.dynamics.trajectory import JointTrajectory
from pkdyn.exceptions import DescriptionError, LoopClosureError
from pkdyn.model.description import parse_description
from pkdyn.model.formats.mjcf import actuator_efforts as mj_actuator_efforts
from pkdyn.model.formats.mjcf import to_mjcf
from pkdyn.model.formats.urdf_writer import UrdfWriter
from solvers import ClosureSet, InverseDynamics, SampledKinematics
from solvers.coupling import JointCoupling
from solvers.forward_dynamics import ForwardDynamics

DATA = Path(__file__).parent / "data" / "public"
XARM_HAND = DATA / "menagerie_xarm7_hand" / "hand.xml"
ROBOTIQ = DATA / "menagerie_robotiq_2f85" / "2f85.xml"

# ------------------------------------------------------------------------------ gear pair model

R1, R2 = 0.05, 0.1  # pitch radii [m]
N = R1 / R2  # |d theta2 / d theta1|
M2, L, I1, IC2, G = 2.0, 0.3, 0.004, 0.01, 9.81  # lever on gear 2 [kg, m, kg m^2, m/s^2]
J2 = IC2 + M2 * L**2  # inertia of gear 2 about its axis
POLY = (0.05, -0.5, 0.2, -0.1)  # a cam law theta2 = p(theta1 - 0.1) + 0.02 (with references)


def gear_urdf(coupling: str = 'source="wheel1" multiplier="-0.5"', extra: str = "") -> str:
    """Two gears on horizontal axes (y); gear 2 carries a lever of mass M2 at L (gravity -z).

    With ``theta2 = p(theta1)``: ``T = (I1 + p'^2 J2) theta1_dot^2 / 2``,
    ``V = -M2 g L sin(theta2)``.
    """
    return f"""<robot name="gears" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="base"/>
  <link name="gear1"><inertial><mass value="1.0"/>
    <inertia ixx="0.002" iyy="{I1}" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="gear2"><inertial><origin xyz="{L} 0 0"/><mass value="{M2}"/>
    <inertia ixx="0.01" iyy="{IC2}" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="wheel1" type="revolute"><parent link="base"/><child link="gear1"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="10"/></joint>
  <joint name="wheel2" type="revolute"><parent link="base"/><child link="gear2"/>
    <origin xyz="{R1 + R2} 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="10"/></joint>
  <transmission name="t1"><type>transmission_interface/SimpleTransmission</type>
    <joint name="wheel1"/><actuator name="motor"><mechanicalReduction>1</mechanicalReduction>
    </actuator></transmission>
  {f'<pkdyn:coupling name="mesh" joint="wheel2" {coupling}/>' if coupling else ""}
  <pkdyn:platform link="gear2" task="ry"/>{extra}
</robot>"""


def law(robot: pkdyn.Robot):
    """``p, p', p''`` of the robot's coupling, as functions of theta1 (closed form)."""
    c = robot.couplings[0]
    poly = np.polynomial.Polynomial(c.coefficients)
    d1, d2 = poly.deriv(), poly.deriv(2)

    def p(t: float) -> float:
        return c.joint_ref + poly(t - c.source_ref)

    return p, (lambda t: d1(t - c.source_ref)), (lambda t: d2(t - c.source_ref))


def closed_form_acceleration(robot, th1: float, w1: float, tau: float) -> float:
    """Lagrange: ``(I1 + p'^2 J2) a + p' p'' J2 w^2 + dV/dtheta1 = tau``."""
    p, d1, d2 = law(robot)
    dV = -M2 * G * L * math.cos(p(th1)) * d1(th1)
    return (tau - d1(th1) * d2(th1) * J2 * w1**2 - dV) / (I1 + d1(th1) ** 2 * J2)


@pytest.fixture(scope="module", params=["linear", "polynomial"])
def gears(request):
    if request.param == "linear":
        return pkdyn.load_string(gear_urdf(), "gears")
    coef = " ".join(map(str, POLY))
    c = f'source="wheel1" polycoef="{coef}" joint_ref="0.02" source_ref="0.1"'
    return pkdyn.load_string(gear_urdf(c), "cam")


# ------------------------------------------------------------------------------ coupling rows


def _three_joint_model() -> pin.Model:
    m = pin.Model()
    for k, jm in enumerate((pin.JointModelRZ(), pin.JointModelRUBY(), pin.JointModelPX())):
        j = m.addJoint(
            0 if k < 2 else 1, jm, pin.SE3(np.eye(3), np.array([0.2 * k, 0, 0])), f"j{k}"
        )
        m.appendBodyToJoint(j, pin.Inertia.Random(), pin.SE3.Identity())
    return m


def test_coupling_rows_match_finite_differences():
    """Residual, Jacobian and drift of polynomial couplings on R, unbounded R and P joints."""
    model = _three_joint_model()
    couplings = [
        JointCoupling("a", 2, 1, (0.1, -2.0, 0.3, 0.05, -0.02), 0.2, 0.05),
        JointCoupling("b", 3, 2, (0.0, 0.4, -0.1), -0.01, 0.3),
        JointCoupling("c", 1, 3, (0.3, 1.5), 0.0, 0.02),
        JointCoupling("lock", 3, None, (0.25,), 0.1),
    ]
    cs = ClosureSet(model, [], couplings)
    data = model.createData()
    rng = np.random.default_rng(3)
    eps = 1e-6
    for _ in range(4):
        q = pin.normalize(model, rng.normal(size=model.nq))
        v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)
        r, J = cs.residual_and_jacobian(data, q)
        assert np.all(np.abs(r[:1]) <= math.pi)  # the unbounded joint's residual is wrapped
        Jfd = np.column_stack(
            [
                (
                    cs.residual(data, pin.integrate(model, q, eps * e))
                    - cs.residual(data, pin.integrate(model, q, -eps * e))
                )
                / (2 * eps)
                for e in np.eye(model.nv)
            ]
        )
        np.testing.assert_allclose(J, Jfd, atol=1e-8)

        def r_of(t: float, q=q, v=v, a=a) -> np.ndarray:
            return cs.residual(data, pin.integrate(model, q, v * t + 0.5 * a * t * t))

        h = 1e-4
        second = (r_of(h) - 2 * r_of(0.0) + r_of(-h)) / h**2
        np.testing.assert_allclose(J @ a + cs.drift(data, q, v), second, atol=1e-5)
        np.testing.assert_allclose(cs.local_residual(data, q), r, atol=1e-15)
        np.testing.assert_allclose(cs.local_jacobian_after_residual(data, q), J, atol=1e-15)
    # sampled rows: the same residual, J v and J a + gamma, vectorised
    Q = np.array([pin.normalize(model, rng.normal(size=model.nq)) for _ in range(5)])
    V, A = rng.normal(size=(5, model.nv)), rng.normal(size=(5, model.nv))
    sk = SampledKinematics(model, cs, size=8)
    r, ev, ea = sk.closure_errors(5, V, Q, A)
    for k in range(5):
        rk, Jk = cs.residual_and_jacobian(data, Q[k])
        np.testing.assert_allclose(r[k], rk, atol=1e-14)
        np.testing.assert_allclose(ev[k], Jk @ V[k], atol=1e-13)
        np.testing.assert_allclose(ea[k], Jk @ A[k] + cs.drift(data, Q[k], V[k]), atol=1e-13)
    with pytest.raises(ValueError, match="couplings relate 1-DoF joints"):
        free = pin.Model()
        free.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
        ClosureSet(free, [], [JointCoupling("x", 1, None, (0.0,))])


# ------------------------------------------------------------------------------ gears: closed forms


def test_gear_positions_velocities_mobility(gears):
    p, d1, _ = law(gears)
    for th1 in (-0.6, 0.1, 0.7):
        res = pkdyn.forward_geometry(gears, [th1])
        assert res.q[1] == pytest.approx(p(th1), abs=1e-12)
        back = pkdyn.inverse_geometry(gears, res.placement)
        assert back.qa[0] == pytest.approx(th1, abs=1e-9)
        km = kinematic_models(gears, res.q)
        assert km.J[0, 0] == pytest.approx(d1(th1), rel=1e-9)  # platform ry rate per theta1 rate
    mob = mobility(gears)
    assert (mob.mobility, mob.grubler, mob.couplings, mob.hyperstatism) == (1, 1, 1, 0)
    assert "- couplings" in format_mobility(mob)


def test_gear_statics_by_virtual_work(gears):
    """Holding torque and tooth force: gravity on the lever, a moment on gear 2."""
    p, d1, _ = law(gears)
    for th1, moment in ((0.3, 0.0), (-0.5, 1.7)):
        q = pkdyn.forward_geometry(gears, [th1]).q
        th2 = p(th1)
        # virtual work: tau d1 + moment d2 - dV = 0 with d2 = p' d1, V = -M2 g L sin(theta2)
        dV2 = -M2 * G * L * math.cos(th2)
        tau = (dV2 - moment) * d1(th1)
        st = static_equilibrium(gears, q, [0, 0, 0, 0, moment, 0], gravity=True)
        assert st.tau[0] == pytest.approx(tau, rel=1e-9)
        # the coupling reaction is the generalized force on the driven joint
        assert st.couplings["mesh"] == pytest.approx(dV2 - moment, rel=1e-9)
        if moment:
            # actuator_efforts: tau = -J^T F (no gravity)
            assert actuator_efforts(gears, q, [moment])[0] == pytest.approx(
                -moment * d1(th1), rel=1e-9
            )


def test_gear_dynamics_by_lagrange_and_energy(gears):
    """Accelerations against Lagrange's equation; the simulation keeps the energy balance."""
    fd = ForwardDynamics(
        gears.model,
        [],
        couplings=gears.closure_set.couplings,
        integrator="dopri5",
    )
    p, d1, _ = law(gears)
    for th1, w1, tau in ((0.2, 1.3, 0.5), (-0.4, -2.0, -1.0)):
        q = np.array([th1, p(th1)])
        v = np.array([w1, d1(th1) * w1])
        a = fd.acceleration(q, v, np.array([tau, 0.0]))
        assert a[0] == pytest.approx(closed_form_acceleration(gears, th1, w1, tau), rel=1e-9)
        # the tooth force: joint 2's equation J2 a2 + dV/dtheta2 = lambda
        lam = fd.closure_forces(fd._kin, np.zeros(1))[0]
        assert lam == pytest.approx(J2 * a[1] - M2 * G * L * math.cos(p(th1)), rel=1e-8)
    # a driven run: work done = energy gained, closures kept
    q0 = pkdyn.forward_geometry(gears, [0.1]).q
    out = simulate(
        gears, 1.0, 0.01, q0=q0, torque=lambda t, q, v: np.array([0.4 * math.sin(3 * t)])
    )
    assert out.energy_drift() < 1e-7
    assert float(np.max(out.closure_residual)) < 1e-9
    passive = simulate(gears, 1.0, 0.01, q0=q0)  # the lever falls, swinging the gears
    assert passive.energy_drift() < 1e-8
    assert float(np.ptp(passive.q[:, 0])) > 0.5


def test_cam_dwell_is_a_singularity():
    """A cam law with ``p' = 0`` (a dwell): serial when the cam is actuated (the follower stays
    put while the actuator moves), parallel when the follower is (the cam turns freely)."""
    serial = pkdyn.load_string(
        gear_urdf('source="wheel1" polycoef="0 -0.5 0.5"'), "dwell"
    )  # wheel2 = -0.5 u + 0.5 u^2, p'(0.5) = 0
    assert classify(serial, pkdyn.forward_geometry(serial, [0.5]).q).kind == "serial"
    assert classify(serial, pkdyn.forward_geometry(serial, [0.1]).q).kind == "regular"
    parallel = pkdyn.load_string(
        gear_urdf(coupling="", extra="").replace(
            "</robot>",
            '<pkdyn:coupling name="cam" joint="wheel1" source="wheel2" polycoef="0 -0.5 0.5"/>'
            "</robot>",
        ),
        "dwell",
    )
    q = np.array([-0.125, 0.5])  # wheel1 = p(0.5)
    assert pkdyn.closure_residual(parallel, q) < 1e-15
    assert classify(parallel, q).kind == "parallel"
    assert classify(parallel, np.array([-0.045, 0.1])).kind == "regular"


def test_gear_inverse_dynamics_along_a_trajectory(gears):
    """Efforts along theta1(t) = 0.3 sin(2 t): the closed-form torque, sample by sample."""
    p, d1, d2 = law(gears)
    t = np.linspace(0.0, 1.0, 21)
    th, w, al = 0.3 * np.sin(2 * t), 0.6 * np.cos(2 * t), -1.2 * np.sin(2 * t)
    q = np.column_stack([th, [p(x) for x in th]])
    v = np.column_stack([w, [d1(x) * y for x, y in zip(th, w, strict=True)]])
    a = np.column_stack(
        [al, [d1(x) * z + d2(x) * y * y for x, y, z in zip(th, w, al, strict=True)]]
    )
    traj = JointTrajectory(t, q, v, a, gears.actuated_q, gears.actuated_v)
    res = inverse_dynamics(gears, traj, limits=False)
    expect = [
        (I1 + d1(x) ** 2 * J2) * z
        + d1(x) * d2(x) * J2 * y * y
        - M2 * G * L * math.cos(p(x)) * d1(x)
        for x, y, z in zip(th, w, al, strict=True)
    ]
    np.testing.assert_allclose(res.tau[:, 0], expect, rtol=1e-9, atol=1e-12)
    sized = size(gears, traj)  # sizing: the peak effort of the same samples
    assert sized.actuators[0].peak == pytest.approx(float(np.max(np.abs(expect))), rel=1e-9)


def test_rack_and_pinion():
    """A continuous pinion driven by an actuated rack: theta = -x / r (the pinion's angle is
    its cos / sin pair's); a moment M on the pinion is held by the force M / r."""
    r = 0.04
    urdf = f"""<robot name="rack" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="base"/>
  <link name="pinion"><inertial><mass value="0.5"/>
    <inertia ixx="1.5e-4" iyy="1.5e-4" izz="3e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="rack"><inertial><mass value="1.5"/>
    <inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="pinion_joint" type="continuous"><parent link="base"/><child link="pinion"/>
    <axis xyz="0 0 1"/></joint>
  <joint name="rack_joint" type="prismatic"><parent link="base"/><child link="rack"/>
    <origin xyz="0 {r} 0"/><axis xyz="1 0 0"/>
    <limit lower="-0.5" upper="0.5" effort="100" velocity="1"/></joint>
  <transmission name="t"><type>SimpleTransmission</type><joint name="rack_joint"/>
    <actuator name="motor"><mechanicalReduction>1</mechanicalReduction></actuator>
  </transmission>
  <pkdyn:coupling name="teeth" joint="pinion_joint" source="rack_joint" multiplier="{-1 / r}"/>
  <pkdyn:platform link="pinion" task="rz"/>
</robot>"""
    robot = pkdyn.load_string(urdf, "rack")
    assert robot.nq == 3 and robot.nv == 2  # the continuous pinion keeps its cos / sin pair
    for x in (-0.2, 0.03, 0.15):  # beyond half a turn: the angle wraps, the residual too
        q = pkdyn.forward_geometry(robot, [x]).q
        assert math.atan2(q[1], q[0]) == pytest.approx(
            math.remainder(-x / r, 2 * math.pi), abs=1e-9
        )
    q = pkdyn.inverse_geometry(robot, [0, 0, 0, 0, 0, -0.75]).q
    assert q[2] == pytest.approx(0.75 * r, abs=1e-10)
    assert actuator_efforts(robot, q, [2.0])[0] == pytest.approx(2.0 / r, rel=1e-9)
    fd = ForwardDynamics(robot.model, [], couplings=robot.closure_set.couplings)
    a = fd.acceleration(q, np.zeros(2), np.array([0.0, 3.0]))
    assert a[1] == pytest.approx(3.0 / (1.5 + 3e-4 / r**2), rel=1e-9)
    assert a[0] == pytest.approx(-a[1] / r, rel=1e-9)


# ------------------------------------------------------------------------------ MuJoCo Menagerie

mujoco = pytest.importorskip("mujoco")

LOCKS = (
    '<joint name="lock_r" joint1="right_spring_link_joint"/>'
    '<joint name="lock_l" joint1="left_spring_link_joint"/></equality>'
)
"""The 2F-85's adaptive spring links held (as on their stops): one degree of freedom left."""

GRIPPERS = {
    # name: (file, driver, pad body, platform point on the pad, extra equalities, dof)
    "xarm7_hand": (XARM_HAND, "left_driver_joint", "left_finger", (0.0, -0.024, 0.041), "", 1),
    "robotiq_2f85": (ROBOTIQ, "right_driver_joint", "right_pad", (0.0, -0.0026, 0.03), LOCKS, 1),
}


@pytest.fixture(scope="module", params=list(GRIPPERS))
def gripper(request, tmp_path_factory):
    """The published model for MuJoCo; for pkdyn, the same text with the tendon actuator
    on the driver joint (the tendon ``0.5 (right + left)`` moves as the driver does through
    the coupling) and a sidecar placing the platform on a pad (task: the closing direction)."""
    path, driver, pad, point, extra, dof = GRIPPERS[request.param]
    text = path.read_text()
    if extra:
        text = text.replace("</equality>", extra)
    mine = text.replace('tendon="split"', f'joint="{driver}"')
    d = tmp_path_factory.mktemp(request.param)
    (d / "gripper.xml").write_text(mine)
    (d / "gripper.yaml").write_text(
        f"platform: {{frame: {pad}, xyz: [{point[0]}, {point[1]}, {point[2]}], task: y}}\n"
    )
    robot = pkdyn.load(d / "gripper.xml")
    mj = mujoco.MjModel.from_xml_string(text)
    return request.param, robot, mj, dof


def _mj_data(mj, q: np.ndarray, v: np.ndarray | None = None):
    data = mujoco.MjData(mj)
    data.qpos[:] = q  # hinges only: MuJoCo's qpos is pkdyn's q
    if v is not None:
        data.qvel[:] = v
    mujoco.mj_forward(mj, data)
    return data


def _equality_rows(mj, data) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's equality residuals ``efc_pos`` and Jacobian rows (dense)."""
    n = data.nefc
    J = np.zeros((n, mj.nv))
    if mujoco.mj_isSparse(mj):
        mujoco.mju_sparse2dense(
            J, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind
        )
    else:
        J = np.asarray(data.efc_J).reshape(-1)[: n * mj.nv].reshape(n, mj.nv)
    eq = np.asarray(data.efc_type[:n]) == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    return np.asarray(data.efc_pos[:n])[eq], J[eq]


def test_gripper_loads_with_its_coupling_and_matches_mujoco_at_home(gripper):
    name, robot, mj, dof = gripper
    coupling = next(c for c in robot.couplings if c.source is not None)
    assert coupling.coefficients == (0.0, 1.0, 0.0, 0.0, 0.0)
    assert robot.dof() == dof
    q = robot.q_home
    rng = np.random.default_rng(1)
    v = rng.normal(size=robot.nv)
    data = _mj_data(mj, q, v)
    r_mj, J_mj = _equality_rows(mj, data)
    assert np.max(np.abs(r_mj)) < 1e-9
    J = robot.closure_set.jacobian(robot.data, q)
    rank = np.linalg.matrix_rank
    assert rank(J, 1e-9) == rank(J_mj, 1e-9) == robot.nv - dof
    Mj = np.zeros((mj.nv, mj.nv))
    mujoco.mj_fullM(mj, data, Mj)
    M = pin.crba(robot.model, robot.data, q)
    np.testing.assert_allclose(np.triu(M) + np.triu(M, 1).T, Mj, atol=1e-9)
    h = pin.rnea(robot.model, robot.data, q, v, np.zeros(robot.nv))
    np.testing.assert_allclose(h, data.qfrc_bias, atol=1e-9)


def test_gripper_closing_motion_keeps_mujocos_equalities(gripper):
    """pkdyn's configurations along the closing stroke satisfy MuJoCo's own constraints."""
    name, robot, mj, _ = gripper
    q = robot.q_home
    worst = 0.0
    for theta in np.linspace(0.05, 0.75, 8):
        q = pkdyn.forward_geometry(robot, [theta], q_init=q).q
        r_mj, _ = _equality_rows(mj, _mj_data(mj, q))
        worst = max(worst, float(np.max(np.abs(r_mj))))
    assert worst < 1e-9, name


def test_gripper_effort_under_a_fingertip_force_matches_mujoco(gripper):
    """Actuator effort at rest under a force on the pad: pkdyn's statics against MuJoCo's
    inverse dynamics (gravity, springs), explained by its tendon actuator and equalities."""
    name, robot, mj, _ = gripper
    q = pkdyn.forward_geometry(robot, [0.4]).q
    force = np.array([0.0, 3.0, -1.5])
    st = static_equilibrium(robot, q, [*force, 0.0, 0.0, 0.0], gravity=True)
    data = _mj_data(mj, q)
    point = robot.platform_placement(q).translation
    body = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_BODY, GRIPPERS[name][2])
    f_ext = np.zeros(mj.nv)
    mujoco.mj_applyFT(mj, data, force, np.zeros(3), point, body, f_ext)
    data.qacc[:] = 0.0
    data.qfrc_applied[:] = f_ext
    mujoco.mj_inverse(mj, data)
    data.qfrc_inverse[:] -= f_ext  # what the actuator (and the equalities) must supply
    tau_mj = mj_actuator_efforts(mj, data)
    assert st.tau[0] == pytest.approx(tau_mj[0], rel=1e-9), name


# ------------------------------------------------------------------------------ sources

CAM_MJCF = """<mujoco model="cam">
  <compiler angle="radian"/>
  <worldbody>
    <body name="a"><joint name="ja" axis="0 1 0" ref="0.2"/>
      <geom type="box" size="0.1 0.02 0.02" pos="0.1 0 0" mass="1"/></body>
    <body name="b" pos="0.3 0 0"><joint name="jb" axis="0 1 0" ref="-0.1"/>
      <geom type="capsule" size="0.02 0.1" pos="0 0 0.1" mass="0.5"/></body>
    <body name="c" pos="0 0.2 0"><joint name="jc" type="slide" axis="1 0 0" ref="0.05"/>
      <geom type="sphere" size="0.03" mass="0.3"/></body>
    <body name="d" pos="0 -0.2 0"><joint name="jd" axis="0 0 1"/>
      <geom type="sphere" size="0.03" mass="0.3" pos="0.05 0 0"/></body>
  </worldbody>
  <equality>
    <joint name="cam" joint1="jb" joint2="ja" polycoef="0.1 -0.5 0.3 0.2 -0.05"/>
    <joint joint1="jc" joint2="jb" polycoef="0.01 0.04"/>
    <joint name="stop" joint1="jd" polycoef="0.3 7 7 7 7"/>
  </equality>
  <actuator><motor joint="ja" gear="1"/></actuator>
</mujoco>"""


def test_mjcf_joint_equalities_keep_mujocos_semantics(tmp_path):
    """Polynomials about qpos0 (the joints' ref), a lock; pkdyn's assembled configurations
    satisfy MuJoCo's constraints, and the export of the coupled robot reads back the same."""
    path = tmp_path / "cam.xml"
    path.write_text(CAM_MJCF)
    robot = pkdyn.load(path)
    cam, lin, stop = robot.couplings
    assert (cam.name, cam.joint, cam.source, cam.joint_ref, cam.source_ref) == (
        "cam",
        "jb",
        "ja",
        -0.1,
        0.2,
    )
    assert (lin.name, lin.coefficients, lin.joint_ref) == ("joint2", (0.01, 0.04), 0.05)
    assert (stop.source, stop.coefficients) == (None, (0.3,))
    assert robot.dof() == 1
    mj = mujoco.MjModel.from_xml_string(CAM_MJCF)
    exported = mujoco.MjModel.from_xml_string(to_mjcf(robot))
    q = robot.q_home
    for qa in (-0.4, 0.2, 0.9):
        q = pkdyn.forward_geometry(robot, [qa], q_init=q).q
        for model in (mj, exported):
            r_mj, J_mj = _equality_rows(model, _mj_data(model, q))
            assert np.max(np.abs(r_mj)) < 1e-12
            np.testing.assert_allclose(J_mj, robot.closure_set.jacobian(robot.data, q), atol=1e-12)
    again = pkdyn.load_string(to_mjcf(robot), "again")
    for c in again.couplings:  # re-expanded about qpos0 = 0: the same relation
        r = again.closure_set.residual(again.data, q)
        assert np.max(np.abs(r)) < 1e-12, c.name


def test_urdf_mimic_is_a_coupling_on_a_tree_joint():
    """A mimic joint stays a joint of the tree (never Pinocchio's mimic) plus a coupling."""
    urdf = gear_urdf(coupling="").replace(
        '<limit lower="-3" upper="3" effort="10" velocity="10"/></joint>\n  <transmission',
        '<limit lower="-3" upper="3" effort="10" velocity="10"/>'
        '<mimic joint="wheel1" multiplier="-0.5" offset="0.1"/></joint>\n  <transmission',
    )
    robot = pkdyn.load_string(urdf, "mimic")
    assert robot.nv == 2
    (c,) = robot.couplings
    assert (c.name, c.joint, c.source, c.coefficients) == (
        "wheel2_mimic",
        "wheel2",
        "wheel1",
        (0.1, -0.5),
    )
    q = pkdyn.forward_geometry(robot, [0.4]).q
    assert q[1] == pytest.approx(0.1 - 0.2, abs=1e-12)


def test_writer_and_sidecar_give_the_same_coupling(tmp_path):
    w = UrdfWriter("w")
    w.coupling("gear", "wheel2", "wheel1", (0.0, -0.5))
    w.coupling("cam", "wheel2", "wheel1", POLY, joint_ref=0.02, source_ref=0.1)
    w.coupling("lock", "wheel2", None, (0.3,), joint_ref=0.1)
    text = w.to_string()
    assert 'multiplier="-0.5"' in text and 'polycoef="0.05 -0.5 0.2 -0.1"' in text
    specs = parse_description(text, "w").couplings
    assert [s.name for s in specs] == ["gear", "cam", "lock"]
    assert specs[1].coefficients == POLY and specs[1].source_ref == 0.1
    assert specs[2].source is None and specs[2].coefficients == (0.3,)
    # the same coupling from a Gepetto sidecar, on the plain URDF
    (tmp_path / "gears.urdf").write_text(gear_urdf(coupling=""))
    (tmp_path / "gears.yaml").write_text(
        "name_mot: [wheel1]\n"
        "couplings:\n"
        "  - {name: mesh, joint: wheel2, source: wheel1, multiplier: -0.5}\n"
    )
    from_yaml = pkdyn.load(tmp_path / "gears.urdf")
    ref = pkdyn.load_string(gear_urdf(), "gears")
    assert from_yaml.couplings == ref.couplings
    q = pkdyn.forward_geometry(from_yaml, [0.3]).q
    np.testing.assert_allclose(q, pkdyn.forward_geometry(ref, [0.3]).q, atol=1e-14)


# ------------------------------------------------------------------------------ bad input

FOUR_BAR = Path(__file__).parent / "data" / "closures" / "four_bar_hinge.urdf"

BAD_URDF = {
    "coupling 'g'": ('<pkdyn:coupling name="g" joint="wheel2" source="nope"/>', "joint 'nope'"),
    "coupling 'g' polycoef": (
        '<pkdyn:coupling name="g" joint="wheel2" source="wheel1" polycoef="0 1 0 0 0 1"/>',
        "6 coefficients",
    ),
    "coupling 'g' multiplier": (
        '<pkdyn:coupling name="g" joint="wheel2" source="wheel1" multiplier="nan"/>',
        "not a finite number",
    ),
    "joint 'wheel2' <mimic> offset": (
        "",
        "not a finite number",
    ),
}


@pytest.mark.parametrize("culprit", list(BAD_URDF))
def test_bad_couplings_name_the_element(culprit, tmp_path, capsys):
    element, why = BAD_URDF[culprit]
    urdf = gear_urdf(coupling="", extra=element)
    if "mimic" in culprit:
        urdf = urdf.replace(
            'velocity="10"/></joint>\n  <transmission',
            'velocity="10"/><mimic joint="wheel1" offset="NaN"/></joint>\n  <transmission',
        )
    path = tmp_path / "bad.urdf"
    path.write_text(urdf)
    with pytest.raises(DescriptionError, match=why) as err:
        pkdyn.load(path)
    assert culprit in str(err.value)
    assert main(["info", str(path)]) == 1
    out = capsys.readouterr().err.strip().splitlines()
    assert len(out) == 1 and out[0].startswith("pkdyn: error:") and culprit in out[0]


def test_coupling_on_a_joint_that_is_not_1dof(tmp_path):
    urdf = FOUR_BAR.read_text().replace(
        "</robot>",
        '<pkdyn:joint name="coupler_joint" type="spherical"/>'
        '<pkdyn:coupling name="k" joint="coupler_joint" source="crank_joint"/></robot>',
    )
    with pytest.raises(DescriptionError, match="coupling 'k'.*3 degrees of freedom"):
        pkdyn.load_string(urdf, "bad")


@pytest.mark.parametrize(
    "equality,why",
    [
        ('<joint joint1="ja" joint2="nope"/>', "joint2='nope' is not a joint"),
        ('<joint joint1="ja" polycoef="0 1 0 0 0 0"/>', "6 coefficients"),
        ('<joint name="n" joint1="ja" joint2="jb" polycoef="0 nan"/>', "NaN"),
        ('<joint joint2="ja"/>', "missing attribute 'joint1'"),
    ],
)
def test_bad_mjcf_joint_equalities_name_the_equality(equality, why, tmp_path):
    path = tmp_path / "bad.xml"
    path.write_text(CAM_MJCF.replace("</equality>", equality + "</equality>"))
    with pytest.raises(DescriptionError, match=why) as err:
        pkdyn.load(path)
    assert "<joint" in str(err.value) and "(line 1" in str(err.value)


def test_a_coupling_that_contradicts_a_closure_is_named(tmp_path, capsys):
    """The four-bar's rocker cannot turn half a turn: locking it there cannot be assembled."""
    path = tmp_path / "locked.urdf"
    path.write_text(
        FOUR_BAR.read_text().replace(
            "</robot>", '<pkdyn:coupling name="stop" joint="rocker_joint" offset="3.0"/></robot>'
        )
    )
    with pytest.raises(LoopClosureError, match="coupling 'stop'.*contradicts the closures") as err:
        pkdyn.load(path)
    assert err.value.culprit == "coupling 'stop'" and err.value.closure == "stop"
    assert main(["info", str(path)]) == 1
    out = capsys.readouterr().err.strip().splitlines()
    assert len(out) == 1 and "coupling 'stop'" in out[0]


def test_gripper_falls_keeping_energy_closures_and_coupling(gripper):
    """Passive fall under gravity (springs, dampers, friction left out): the rigid closures by
    Pinocchio's solver, the coupling by its forces; energy kept, every constraint held."""
    name, robot, _, _ = gripper
    out = simulate(robot, 0.1, 0.01, passive=False)
    assert out.energy_drift() < 1e-9, name
    assert float(np.max(out.closure_residual)) < 1e-10
    assert float(np.ptp(out.q[:, 0])) > 1e-4  # it moves
    # the recorded closure and coupling forces are the inverse dynamics' (another solver) at
    # the recorded state, with no actuator effort (both in the rows of robot.constraints)
    inv = InverseDynamics(robot.model, robot.constraints, actuation(robot))
    res = inv.solve(out.q[-1], out.v[-1], out.a[-1])
    assert abs(res.tau[0]) < 1e-12
    np.testing.assert_allclose(res.constraint_forces, out.constraint_forces[-1], atol=1e-9)


def test_a_coupling_off_by_cad_rounding_is_absorbed(tmp_path):
    """Crank and rocker both locked, 3e-5 rad apart from an assembly: within the assembly
    tolerance, the description is taken as rounded (one warning) and assembles exactly."""
    with pytest.warns(UserWarning):
        four_bar = pkdyn.load(FOUR_BAR)
    q = four_bar.q_home
    crank, rocker = (
        four_bar.model.joints[four_bar.model.getJointId(n)].idx_q
        for n in ("crank_joint", "rocker_joint")
    )
    a, b = float(q[crank]), float(q[rocker]) + 3e-5
    locks = (
        f'<pkdyn:coupling name="a" joint="crank_joint" offset="{a!r}"/>'
        f'<pkdyn:coupling name="b" joint="rocker_joint" offset="{b!r}"/></robot>'
    )
    path = tmp_path / "locked.urdf"
    path.write_text(FOUR_BAR.read_text().replace("</robot>", locks))
    with pytest.warns(UserWarning, match="cannot be closed exactly") as caught:
        robot = pkdyn.load(path)
    assert any("constant terms were adjusted" in str(w.message) for w in caught)
    assert robot.dof() == 0
    assert pkdyn.closure_residual(robot, robot.q_home) < 1e-9
