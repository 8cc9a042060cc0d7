"""MJCF export and cross-checks of pkdyn's dynamics against MuJoCo, an independent engine.

- Export: every library robot loads in MuJoCo; at the same (random) configuration the body
  frames, closure sites and platform agree with Pinocchio's (1e-9); masses, gears, control
  ranges and the home keyframe are those of the description; the state map between the two
  coordinate conventions (quaternion order, free-flyer velocities in world axes) is checked
  against MuJoCo's own body velocities and accelerations.
- Forward dynamics: pkdyn's constrained accelerations (``ForwardDynamics.acceleration``) against
  MuJoCo's ``mj_forward`` with nearly hard closures. MuJoCo's constraints are soft: with the
  stiffest impedance it accepts (``d = 0.9999``) the accelerations differ by O(1 - d); the soft
  solution is a smooth function of ``eps = (1 - d) / d``, so MuJoCo runs at three ``eps`` are
  extrapolated to ``eps = 0`` (quadratic Richardson). The part of the accelerations in the
  closures' null space (``Z^T M a``, which no constraint force can change) is compared
  directly.
- Inverse dynamics: pkdyn's actuator efforts (``InverseDynamics``) against MuJoCo's
  ``mj_inverse`` output projected onto the actuators through MuJoCo's own closure Jacobian: the
  least-squares solution of ``[moment^T  J_c^T] [tau; lambda] = qfrc_inverse``.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from conftest import null_space

import pkdyn
from pkdyn.cli import main
from pkdyn.exceptions import DescriptionError
from pkdyn.model.formats.mjcf import MjcfOptions, StateMap, actuator_efforts, mujoco_model, to_mjcf
from solvers import Actuation, ForwardDynamics, InverseDynamics

mujoco = pytest.importorskip("mujoco")

LIBRARY = ["delta", "gough_stewart", "planar_3rrr", "five_bar", "tripod"]
CROSS = {  # cross-checked robots: name -> builder parameters
    "delta": {},
    "delta_universal": {"bar_joint": "universal"},
    "gough_stewart": {},
    "five_bar": {},
    "planar_3rrr": {},
    "tripod": {},
}
IMPEDANCES = (0.9999, 0.9998, 0.9996)
# bounds of the table of docs/guide/evidence.md (relative accelerations): MuJoCo's stiffest soft
# closures, and extrapolated to rigid ones; the tripod's welded feet are the softest (1.8e-2,
# 2.3e-7)
SOFT = {"tripod": 3e-2}
RIGID = {"tripod": 1e-6}


@pytest.fixture(scope="module", params=LIBRARY)
def exported(request):
    robot = pkdyn.load(request.param)
    model = mujoco.MjModel.from_xml_string(to_mjcf(robot))
    return robot, model, StateMap(robot)


def _random_q(robot: pkdyn.Robot, rng: np.random.Generator, spread: float) -> np.ndarray:
    return pin.integrate(robot.model, robot.q_home, spread * rng.standard_normal(robot.nv))


def _body(model, name: str) -> int:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)


def _site(model, name: str) -> int:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, name)


# ------------------------------------------------------------------------------ export


def test_layout_matches_mujoco(exported):
    robot, model, smap = exported
    assert (model.nq, model.nv, model.nu) == (smap.nq, smap.nv, len(robot.actuators))
    for jm in smap.joints:
        for k, name in enumerate(jm.mj_joints):
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            assert jid >= 0, name
            assert model.jnt_dofadr[jid] == jm.dof + k
            if jm.kind not in ("free", "ball"):
                assert model.jnt_qposadr[jid] == jm.qpos + k
            else:
                assert model.jnt_qposadr[jid] == jm.qpos


def test_kinematics_match(exported):
    """Body frames, closure sites and the platform site agree with Pinocchio (1e-9)."""
    robot, model, smap = exported
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    for _ in range(3):
        q = _random_q(robot, rng, 0.5)
        data.qpos[:] = smap.qpos(q)
        mujoco.mj_kinematics(model, data)
        pin.framesForwardKinematics(robot.model, robot.data, q)
        for j in range(1, robot.model.njoints):
            b = _body(model, smap.body_names[j])
            oMi = robot.data.oMi[j]
            np.testing.assert_allclose(data.xpos[b], oMi.translation, rtol=0, atol=1e-9)
            np.testing.assert_allclose(data.xmat[b].reshape(3, 3), oMi.rotation, atol=1e-9)
        for cm in robot.constraint_models:
            sides = ((1, cm.joint1_id, cm.joint1_placement), (2, cm.joint2_id, cm.joint2_placement))
            for side, jid, M in sides:
                s = _site(model, f"{cm.name}_{side}")
                oMc = robot.data.oMi[jid] * M
                np.testing.assert_allclose(data.site_xpos[s], oMc.translation, atol=1e-9)
                np.testing.assert_allclose(data.site_xmat[s].reshape(3, 3), oMc.rotation, atol=1e-9)
        if robot.platform_frame is not None:
            f = robot.model.frames[robot.platform_frame]
            s = _site(model, f.name)
            np.testing.assert_allclose(
                data.site_xpos[s], robot.data.oMf[robot.platform_frame].translation, atol=1e-9
            )
        np.testing.assert_allclose(smap.q(smap.qpos(q)), q, atol=1e-12)


def test_inertia_actuators_and_home(exported):
    robot, model, smap = exported
    masses = [robot.model.inertias[j].mass for j in range(1, robot.model.njoints)]
    np.testing.assert_allclose(model.body_mass.sum(), sum(masses), rtol=1e-12)
    for k, a in enumerate(robot.actuators):
        assert model.actuator(k).name == a.name
        assert model.actuator_gear[k, 0] == pytest.approx(a.reduction)
        np.testing.assert_allclose(
            model.actuator_ctrlrange[k], [-a.effort / a.reduction, a.effort / a.reduction]
        )
    # the home keyframe is assembled: MuJoCo's own closure residuals vanish, nothing touches
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)
    eq = data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    assert eq.sum() == robot.closure_set.nc
    assert np.max(np.abs(data.efc_pos[: data.nefc][eq])) < 1e-9
    assert data.ncon == 0


def test_mujoco_simulation_holds_closures(exported):
    """The exported model runs in MuJoCo: 0.3 s from home under gravity, closures held."""
    robot, model, _ = exported
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    worst = 0.0
    for _ in range(300):
        mujoco.mj_step(model, data)
        eq = data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
        worst = max(worst, float(np.max(np.abs(data.efc_pos[: data.nefc][eq]))))
    assert np.all(np.isfinite(data.qpos))
    assert worst < 1e-3  # soft constraints: ~1e-4 m at 1 kHz


def test_state_map_against_mujoco_body_motion(exported):
    """qvel / qacc mapping: MuJoCo's body velocities and accelerations equal Pinocchio's."""
    robot, model, smap = exported
    data = mujoco.MjData(model)
    rng = np.random.default_rng(1)
    q = _random_q(robot, rng, 0.5)
    v = rng.standard_normal(robot.nv)
    a = rng.standard_normal(robot.nv)
    data.qpos[:] = smap.qpos(q)
    data.qvel[:] = smap.qvel(q, v)
    mujoco.mj_fwdPosition(model, data)
    mujoco.mj_fwdVelocity(model, data)
    data.qacc[:] = smap.qacc(q, v, a)
    mujoco.mj_rnePostConstraint(model, data)  # body accelerations from qacc
    pin.forwardKinematics(robot.model, robot.data, q, v, a)
    res = np.zeros(6)
    for j in range(1, robot.model.njoints):
        b = _body(model, smap.body_names[j])
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_XBODY, b, res, 1)
        vj = robot.data.v[j]
        np.testing.assert_allclose(res, np.r_[vj.angular, vj.linear], atol=1e-9)
        mujoco.mj_objectAcceleration(model, data, mujoco.mjtObj.mjOBJ_XBODY, b, res, 1)
        # Pinocchio's is spatial; MuJoCo's linear part is classical and counts gravity as an
        # upward acceleration of the world (as its recursive Newton-Euler does)
        aj = robot.data.a[j]
        R = robot.data.oMi[j].rotation
        classical = aj.linear + np.cross(vj.angular, vj.linear) - R.T @ robot.model.gravity.linear
        np.testing.assert_allclose(res, np.r_[aj.angular, classical], atol=1e-8)
    np.testing.assert_allclose(smap.v(q, smap.qvel(q, v)), v, atol=1e-12)
    np.testing.assert_allclose(smap.a(q, v, smap.qacc(q, v, a)), a, atol=1e-12)
    f_mj = rng.standard_normal(smap.nv)  # same power in both coordinates
    assert smap.force(q, f_mj) @ v == pytest.approx(f_mj @ smap.qvel(q, v), rel=1e-12)
    T = smap.velocity_matrix(q)
    np.testing.assert_allclose(T @ v, smap.qvel(q, v), atol=1e-12)


def _erd_urdf(rel: str) -> Path | None:
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    path = Path(str(dist.locate_file(f"cmeel.prefix/share/example-robot-data/robots/{rel}")))
    return path if path.is_file() else None


def test_plain_urdf_with_meshes_and_continuous_joints():
    """A plain URDF with STL meshes and continuous joints (Pinocchio stores cos, sin)."""
    path = _erd_urdf("double_pendulum_description/urdf/double_pendulum_continuous.urdf")
    if path is None:
        pytest.skip("example-robot-data is not installed")
    robot = pkdyn.load(path)
    model = mujoco.MjModel.from_xml_string(to_mjcf(robot))
    smap = StateMap(robot)
    assert model.nmesh > 0 and {jm.kind for jm in smap.joints} == {"hinge_unbounded"}
    data = mujoco.MjData(model)
    q = pin.integrate(robot.model, pin.neutral(robot.model), np.array([2.5, -2.0]))
    data.qpos[:] = smap.qpos(q)
    mujoco.mj_kinematics(model, data)
    pin.forwardKinematics(robot.model, robot.data, q)
    for j in range(1, robot.model.njoints):
        b = _body(model, smap.body_names[j])
        np.testing.assert_allclose(data.xpos[b], robot.data.oMi[j].translation, atol=1e-9)
    np.testing.assert_allclose(smap.q(smap.qpos(q)), q, atol=1e-12)


def test_other_joint_kinds_match_mujoco():
    """Unaligned revolute and prismatic, translation and spherical ZYX joints (a hand-built
    tree): body frames and body velocities agree with MuJoCo's."""
    robot = pkdyn.load("five_bar", geometry=False)
    model = pin.Model()
    rng = np.random.default_rng(5)
    parent = 0
    joints = (
        pin.JointModelRevoluteUnaligned(np.array([1.0, 2.0, 2.0]) / 3.0),
        pin.JointModelPrismaticUnaligned(np.array([0.0, 0.6, 0.8])),
        pin.JointModelTranslation(),
        pin.JointModelSphericalZYX(),
    )
    for k, jm in enumerate(joints):
        M = pin.SE3(pin.exp3(rng.standard_normal(3)), rng.standard_normal(3) * 0.2)
        parent = model.addJoint(parent, jm, M, f"j{k}")
        model.appendBodyToJoint(parent, pin.Inertia.FromBox(1.0, 0.1, 0.2, 0.3), pin.SE3.Identity())
        model.addFrame(pin.Frame(f"link{k}", parent, pin.SE3.Identity(), pin.FrameType.BODY))
    fake = dataclasses.replace(
        robot,
        model=model,
        data=model.createData(),
        constraint_models=pin.StdVec_RigidConstraintModel(),
        actuators=(),
        platform_frame=None,
        q_home=pin.neutral(model),
    )
    smap = StateMap(fake)
    mj = mujoco.MjModel.from_xml_string(to_mjcf(fake))
    data = mujoco.MjData(mj)
    q = pin.integrate(model, pin.neutral(model), rng.standard_normal(model.nv))
    v = rng.standard_normal(model.nv)
    data.qpos[:] = smap.qpos(q)
    data.qvel[:] = smap.qvel(q, v)
    mujoco.mj_forward(mj, data)
    d = model.createData()
    pin.forwardKinematics(model, d, q, v)
    res = np.zeros(6)
    for j in range(1, model.njoints):
        b = _body(mj, smap.body_names[j])
        np.testing.assert_allclose(data.xpos[b], d.oMi[j].translation, atol=1e-12)
        np.testing.assert_allclose(data.xmat[b].reshape(3, 3), d.oMi[j].rotation, atol=1e-12)
        mujoco.mj_objectVelocity(mj, data, mujoco.mjtObj.mjOBJ_XBODY, b, res, 1)
        np.testing.assert_allclose(res, np.r_[d.v[j].angular, d.v[j].linear], atol=1e-12)
    assert mj.nq == smap.nq == 1 + 1 + 3 + 3


def test_unsupported_joint_names_it():
    robot = pkdyn.load("five_bar", geometry=False)
    model = pin.Model()
    model.addJoint(0, pin.JointModelHZ(0.01), pin.SE3.Identity(), "screw")
    fake = dataclasses.replace(
        robot,
        model=model,
        constraint_models=pin.StdVec_RigidConstraintModel(),
        actuators=(),
        q_home=pin.neutral(model),
    )
    with pytest.raises(DescriptionError, match="screw"):
        to_mjcf(fake)


def test_cli_writes_a_loadable_file(tmp_path, capsys):
    out = tmp_path / "five_bar.xml"
    assert main(["mjcf", "five_bar", "-o", str(out), "--step", "0.0005"]) == 0
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.opt.timestep == 0.0005 and model.neq == 2
    assert main(["mjcf", "five_bar", "--no-contacts"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("<mujoco") and "<contact>" not in text
    assert main(["mjcf", "no_such_robot"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no_such_robot" in err[0]


# ------------------------------------------------------------------------------ cross-checks


@dataclasses.dataclass
class _Case:
    robot: pkdyn.Robot
    smap: StateMap
    model: object
    act: Actuation
    states: list[tuple[np.ndarray, np.ndarray, np.ndarray]]  # (q, v, motor-side tau)


@pytest.fixture(scope="module", params=list(CROSS))
def case(request):
    name = request.param
    robot = pkdyn.load(name.split("_universal")[0], geometry=False, **CROSS[name])
    model = mujoco.MjModel.from_xml_string(to_mjcf(robot, MjcfOptions(contacts=False)))
    model.opt.tolerance = 1e-15
    model.opt.ls_tolerance = 1e-12
    model.opt.iterations = 1000
    model.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    red = np.array([a.reduction for a in robot.actuators])
    eff = np.array([a.effort for a in robot.actuators])
    act = Actuation(robot.actuated_v, gains=red, names=robot.actuator_names)
    rng = np.random.default_rng(7)
    kin = robot.model.createData()
    states = []
    for _ in range(3):  # assembled q near home, v in the closures' null space, random efforts
        q = pkdyn.project(robot, _random_q(robot, rng, 0.05))
        Z = _null_space(robot, kin, q)
        v = Z @ rng.standard_normal(Z.shape[1])
        v *= 2.0 / np.max(np.abs(v))
        states.append((q, v, 0.5 * eff / red * rng.uniform(-1.0, 1.0, act.n)))
    return _Case(robot, StateMap(robot), model, act, states)


def _null_space(robot: pkdyn.Robot, kin: pin.Data, q: np.ndarray) -> np.ndarray:
    _, J = robot.closure_set.residual_and_jacobian(kin, q)
    return null_space(J)


def _mujoco_acceleration(case: _Case, q, v, tau, d_max: float) -> np.ndarray:
    model = case.model
    model.eq_solimp[:, :3] = d_max, d_max, 0.001
    data = mujoco.MjData(model)
    data.qpos[:] = case.smap.qpos(q)
    data.qvel[:] = case.smap.qvel(q, v)
    data.ctrl[:] = tau
    mujoco.mj_forward(model, data)
    return case.smap.a(q, v, data.qacc)


def test_forward_accelerations_match_mujoco(case):
    robot, act = case.robot, case.act
    fd = ForwardDynamics(robot.model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    kin = robot.model.createData()
    eps = np.array([(1.0 - d) / d for d in IMPEDANCES])
    for q, v, tau in case.states:
        a = fd.acceleration(q, v, act.generalized(tau, robot.nv))
        a_still = fd.acceleration(q, 0.0 * v, act.generalized(tau, robot.nv))
        soft = np.array([_mujoco_acceleration(case, q, v, tau, d) for d in IMPEDANCES])
        hard = np.linalg.solve(np.vander(eps, 3, increasing=True), soft)[0]  # Richardson
        scale = np.linalg.norm(a)
        # nearly hard MuJoCo closures: within O(1 - d); extrapolated: 1e-7 (observed <= 2e-9)
        name = case.robot.name
        assert np.linalg.norm(soft[0] - a) < SOFT.get(name, 5e-3) * scale
        assert np.linalg.norm(hard - a) < RIGID.get(name, 1e-7) * scale
        # the velocity terms (centripetal, closure Jdot v) matter far more than the error
        assert np.linalg.norm(hard - a) < 1e-3 * np.linalg.norm(a - a_still)
        # null-space part Z^T M a: independent of the constraint model (observed <= 1e-11)
        M = pin.crba(robot.model, kin, q)
        M = np.triu(M) + np.triu(M, 1).T
        P = _null_space(robot, kin, q).T @ M
        assert np.linalg.norm(P @ (soft[0] - a)) < 1e-9 * np.linalg.norm(P @ a)


def test_inverse_efforts_match_mujoco(case):
    robot, act, model, smap = case.robot, case.act, case.model, case.smap
    fd = ForwardDynamics(robot.model, robot.constraint_models, act, baumgarte=(0.0, 0.0))
    inv = InverseDynamics(robot.model, robot.constraint_models, act)
    data = mujoco.MjData(model)
    for q, v, tau in case.states:
        a = fd.acceleration(q, v, act.generalized(tau, robot.nv))
        tau_pk = inv.solve(q, v, a).tau
        data.qpos[:] = smap.qpos(q)
        data.qvel[:] = smap.qvel(q, v)
        data.qacc[:] = smap.qacc(q, v, a)
        mujoco.mj_inverse(model, data)
        tau_mj = actuator_efforts(model, data)  # least squares on [moment^T J_eq^T]
        # observed 1e-15 .. 3e-13
        np.testing.assert_allclose(tau_mj, tau_pk, rtol=0, atol=1e-9 * np.max(np.abs(tau_pk)))
        np.testing.assert_allclose(tau_pk, tau, rtol=0, atol=1e-9 * np.max(np.abs(tau)))


def test_actuator_efforts_with_a_sparse_jacobian():
    """The projection reads MuJoCo's sparse constraint Jacobian as well as the dense one."""
    robot = pkdyn.load("gough_stewart", geometry=False)
    smap = StateMap(robot)
    rng = np.random.default_rng(3)
    q = pkdyn.project(robot, _random_q(robot, rng, 0.05))
    v = _null_space(robot, robot.model.createData(), q) @ rng.standard_normal(6)
    qacc = rng.standard_normal(smap.nv)
    out = []
    for jac in (mujoco.mjtJacobian.mjJAC_DENSE, mujoco.mjtJacobian.mjJAC_SPARSE):
        model = mujoco_model(robot, MjcfOptions(contacts=False))
        model.opt.jacobian = jac
        data = mujoco.MjData(model)
        data.qpos[:] = smap.qpos(q)
        data.qvel[:] = smap.qvel(q, v)
        data.qacc[:] = qacc
        mujoco.mj_inverse(model, data)
        out.append(actuator_efforts(model, data))
    assert np.all(np.isfinite(out[0])) and np.any(out[0] != 0.0)
    np.testing.assert_allclose(out[0], out[1], rtol=1e-10)


def test_no_warnings_for_library_geometry():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in LIBRARY:
            to_mjcf(pkdyn.load(name))
