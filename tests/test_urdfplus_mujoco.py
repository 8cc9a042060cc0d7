"""The URDF+ models of generalized_rbda: their dynamics against MuJoCo on the MJCF export.

A second engine for every dynamic result: each model is loaded by pkdyn (inertias repaired where
the file's break the triangle inequality, which MuJoCo refuses), exported to MJCF
(:func:`pkdyn.model.formats.mjcf.to_mjcf`: loops as ``connect`` equalities, rotor couplings as
joint equalities, couplings of sums as fixed tendons held by tendon equalities, massless rotors
lending a mass on their axis) and compiled by MuJoCo. At a state on the constraints (the
assembled home and, where the mechanism moves, a configuration reached along it; seeded random
velocities in the null space of the constraint Jacobian), every term of the constrained
dynamics is taken from MuJoCo, in pkdyn's velocity coordinates (``qvel = T v``, ``qacc = T a +
c(q, v)``):

- mass matrix ``T^T M T`` (``mj_fullM``) and bias forces ``T^T (M c + qfrc_bias)``;
- constraint rows ``J_mj T`` (the equality rows of ``efc_J``) and their drift ``J_mj c +
  Jdot v`` (``Jdot v``: for a ``connect``, the difference of the two sites' accelerations at
  ``qacc = 0``, ``mj_objectAcceleration``; joint and tendon equalities are linear: none),

and the exact constrained dynamics solved from them (a KKT system; redundant rows of planar
loops are consistent, least squares). MuJoCo's own solver is not used: its equality
constraints are soft (``solref``/``solimp``), so its accelerations are not the rigid ones.

- **forward dynamics**: pkdyn's constrained acceleration (:class:`solvers.ForwardDynamics`) under
  seeded random generalized forces equals MuJoCo's terms' solution;
- **inverse dynamics**: for the acceleration MuJoCo's terms give under seeded random actuator
  efforts ``tau0`` (a motion the actuators can make, floating base or not), pkdyn's efforts
  (:class:`solvers.InverseDynamics`) leave a residual ``M a + b - S^T tau`` in the row space of
  MuJoCo's constraint Jacobian (the constraint forces exist), and are ``tau0`` where the
  efforts are unique,

both to 1e-9 relative (to the largest acceleration, or to ``|M a + b|``). Measured worst: forward
1.2e-10 (the nv = 81 ladder), inverse 6.2e-11 (the explicit depth-40 chain), efforts 9.3e-11.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkdyn
from pkdyn.dynamics.actuation import actuation
from pkdyn.model.assembly import project
from pkdyn.model.formats.mjcf import to_mjcf
from pkdyn.model.formats.mjcf_state import StateMap
from solvers import ForwardDynamics, InverseDynamics
from solvers.numerics import null_space

mujoco = pytest.importorskip("mujoco")

DATA = Path(__file__).parent / "data" / "public" / "generalized_rbda"
TOL = 1e-9

MODELS = [
    "robot-models/four_bar.urdf",
    "robot-models/six_bar.urdf",
    "robot-models/planar_leg_linkage.urdf",
    "robot-models/revolute_rotor_chain.urdf",
    "robot-models/mini_cheetah_fl_leg.urdf",
    "robot-models/mit_humanoid_leg.urdf",
    "robot-models/mini_cheetah.urdf",
    "robot-models/mit_humanoid.urdf",
    "robot-models/jvrc1_humanoid.urdf",
    "history/cassie_v4.urdf",
    "parallel_chains/explicit_depth5_loop_size6.urdf",
    "parallel_chains/implicit_depth5_loop_size5.urdf",
    "parallel_chains/explicit_depth40_loop_size40.urdf",
    "parallel_chains/implicit_depth40_loop_size41.urdf",
    "variable_four_bar/four_bar_branch_2_3.urdf",
]


def _load(name: str) -> pkdyn.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # repaired inertias, massless rotors: said on load
        return pkdyn.load(DATA / name, geometry=False, repair_inertias=True)


def _equality_rows(mj, data) -> tuple[np.ndarray, np.ndarray]:
    """Equality rows of ``efc_J`` (n_eq, nv_mj) and the equality id of each."""
    nefc = data.nefc
    J = np.zeros((nefc, mj.nv))
    if mujoco.mj_isSparse(mj):
        mujoco.mju_sparse2dense(
            J, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind
        )
    else:
        J[:] = np.asarray(data.efc_J).reshape(-1)[: nefc * mj.nv].reshape(nefc, mj.nv)
    eq = np.asarray(data.efc_type[:nefc]) == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    return J[eq], np.asarray(data.efc_id[:nefc])[eq]


def _site_acceleration(mj, data, site: int) -> np.ndarray:
    res = np.zeros(6)
    mujoco.mj_objectAcceleration(mj, data, mujoco.mjtObj.mjOBJ_SITE, site, res, 0)
    return res[3:]


def mujoco_terms(robot, mj, smap: StateMap, q: np.ndarray, v: np.ndarray):
    """``M, b, J, gamma`` of the constrained dynamics in pkdyn's coordinates, from MuJoCo."""
    data = mujoco.MjData(mj)
    data.qpos[:] = smap.qpos(q)
    data.qvel[:] = smap.qvel(q, v)
    mujoco.mj_forward(mj, data)
    T = smap.velocity_matrix(q)
    c = smap.qacc(q, v, np.zeros(robot.nv))
    Mj = np.zeros((mj.nv, mj.nv))
    mujoco.mj_fullM(mj, data, Mj)
    M = T.T @ Mj @ T
    b = T.T @ (Mj @ c + np.asarray(data.qfrc_bias))
    Jeq, ids = _equality_rows(mj, data)
    data.qacc[:] = 0.0  # the sites' accelerations at qacc = 0: Jdot v of a connect
    mujoco.mj_rnePostConstraint(mj, data)
    drift = np.zeros(len(ids))
    k = 0
    while k < len(ids):
        e = int(ids[k])
        rows = int(np.sum(ids == e))
        kind = int(mj.eq_type[e])
        if kind == int(mujoco.mjtEq.mjEQ_CONNECT):
            assert int(mj.eq_objtype[e]) == int(mujoco.mjtObj.mjOBJ_SITE)
            a1 = _site_acceleration(mj, data, int(mj.eq_obj1id[e]))
            a2 = _site_acceleration(mj, data, int(mj.eq_obj2id[e]))
            drift[k : k + rows] = a1 - a2
        else:  # joint and tendon equalities: linear rows, no drift
            assert kind in (int(mujoco.mjtEq.mjEQ_JOINT), int(mujoco.mjtEq.mjEQ_TENDON))
        k += rows
    J = Jeq @ T
    return M, b, J, Jeq @ c + drift


def kkt_acceleration(M, b, J, gamma, f) -> np.ndarray:
    """Rigid constrained acceleration: ``M a + b = f + J^T l``, ``J a + gamma = 0``."""
    Minv_J = np.linalg.solve(M, J.T)
    a0 = np.linalg.solve(M, f - b)
    lam = np.linalg.lstsq(J @ Minv_J, -gamma - J @ a0, rcond=None)[0]
    return a0 + Minv_J @ lam


def _states(robot, rng):
    """Two assembled configurations with consistent velocities: home, and one along a motion."""
    q0 = robot.q_home
    out = []
    for q in (q0, None):
        if q is None:
            J = robot.constraints.jacobian(robot.model.createData(), q0)
            N = null_space(J)
            step = N @ rng.standard_normal(N.shape[1])
            step *= 0.05 / max(float(np.abs(step).max()), 1e-12)
            q = project(robot, pin.integrate(robot.model, q0, step))
        J = robot.constraints.jacobian(robot.model.createData(), q)
        N = null_space(J)
        v = N @ rng.standard_normal(N.shape[1])
        out.append((q, v))
    return out


def _solvers(robot):
    fd = ForwardDynamics(robot.model, robot.constraints, actuation(robot))
    inv = None
    if robot.actuators:
        inv = InverseDynamics(robot.model, robot.constraints, actuation(robot))
    return fd, inv


@pytest.fixture(scope="module", params=MODELS)
def engines(request):
    robot = _load(request.param)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mj = mujoco.MjModel.from_xml_string(to_mjcf(robot))
    return robot, mj, StateMap(robot)


def test_forward_dynamics_agree_with_mujoco(engines):
    robot, mj, smap = engines
    rng = np.random.default_rng(36)
    fd, _ = _solvers(robot)
    for q, v in _states(robot, rng):
        M, b, J, gamma = mujoco_terms(robot, mj, smap, q, v)
        f = rng.standard_normal(robot.nv) * max(1.0, float(np.abs(b).max()))
        a_mj = kkt_acceleration(M, b, J, gamma, f)
        a_pk = fd.acceleration(q, v, f)
        scale = max(1.0, float(np.abs(a_mj).max()))
        assert float(np.abs(a_pk - a_mj).max()) < TOL * scale, robot.name


def test_inverse_dynamics_agree_with_mujoco(engines):
    robot, mj, smap = engines
    _, inv = _solvers(robot)
    if inv is None:
        pytest.skip(f"{robot.name} declares no actuator")
    rng = np.random.default_rng(35)
    S = actuation(robot).matrix(robot.nv)
    for q, v in _states(robot, rng):
        M, b, J, gamma = mujoco_terms(robot, mj, smap, q, v)
        tau0 = rng.standard_normal(S.shape[0]) * max(1.0, float(np.abs(b).max()))
        a = kkt_acceleration(M, b, J, gamma, S.T @ tau0)  # reachable, floating base or not
        result = inv.solve(q, v, a)
        r = M @ a + b - S.T @ result.tau
        if J.size:
            r = r - J.T @ np.linalg.lstsq(J.T, r, rcond=None)[0]
        scale = max(1.0, float(np.abs(M @ a + b).max()))
        assert float(np.abs(r).max()) < TOL * scale, robot.name
        if result.redundancy == 0:  # unique efforts: those that made the motion
            effort = max(1.0, float(np.abs(tau0).max()))
            assert float(np.abs(result.tau - tau0).max()) < TOL * effort, robot.name
