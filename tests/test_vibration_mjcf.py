"""The elastic model exported to MJCF (:mod:`pkdyn.precision.vibration_mjcf`), against MuJoCo.

- the exported model's static compliance at the reference point, from MuJoCo's own joint
  stiffnesses, servo gains, equality-constraint Jacobian and site Jacobian, against
  :func:`pkdyn.precision.stiffness` to 1e-9, and its natural frequencies from MuJoCo's own mass
  matrix against :func:`pkdyn.precision.modes.modes` to 1e-6: rigid links, the Delta with carbon
  links (each virtual spring six joints at the beam's mid-span), the planar 3-RRR with steel
  links (hinge closures); a link whose part past its spring has no mass (the Gough-Stewart's
  steel rods) is refused, naming it, as bad servo dampings and integrators;
- the Delta's vibration on the Adept cycle (0.5 s, 0.5 kg payload, 2e4 N m/rad servos)
  simulated by MuJoCo on that export, with rigid and with carbon links, against the modal
  method: within 2 % in peak deviation, residual amplitude and settling time.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import pkdyn
from pkdyn.model.formats.mjcf_state import StateMap
from pkdyn.precision import elastic_model, modes, stiffness
from pkdyn.precision.vibration_mjcf import (
    POINT_SITE,
    elastic_mjcf,
    six_joint_q,
    six_joint_robot,
)

mujoco = pytest.importorskip("mujoco")


def _mujoco_linear(em, q, point):
    """MuJoCo's stiffness (nv,), equality rows, site Jacobian (6, nv) and mass at ``q``."""
    m = mujoco.MjModel.from_xml_string(elastic_mjcf(em, np.zeros(len(em.base.actuators)), point))
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    d = mujoco.MjData(m)
    q6 = six_joint_q(em, em.embed(q))
    d.qpos[:] = StateMap(six_joint_robot(em)).qpos(q6)
    mujoco.mj_forward(m, d)
    K = np.zeros(m.nv)
    for j in range(m.njnt):
        K[m.jnt_dofadr[j]] += m.jnt_stiffness[j]
    for a in range(m.nu):  # a position servo: force kp (ctrl - q), bias [0, -kp, 0]
        if m.actuator_biasprm[a, 1] < 0.0:
            K[m.jnt_dofadr[m.actuator_trnid[a, 0]]] -= m.actuator_biasprm[a, 1]
    rows = d.efc_J.reshape(-1, m.nv)[d.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY]
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacSite(m, d, jp, jr, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, POINT_SITE))
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    return K, rows, np.vstack([jp, jr]), M


def _stiff(K, rows):
    """The allowed motions and their stiffness's eigen-decomposition, springless ones dropped."""
    _, s, Vt = np.linalg.svd(rows)
    N = Vt[int(np.sum(s > 1e-9 * s[0])) :].T
    w, V = np.linalg.eigh(N.T @ (K[:, None] * N))
    keep = w > 1e-12 * w.max()
    return N, w[keep], V[:, keep]


@pytest.mark.parametrize(
    "name, k, material, where",
    [
        ("delta", 2e4, None, [0.05, -0.03, -0.45]),
        ("delta", 2e4, "carbon", [0.05, -0.03, -0.45]),
        ("planar_3rrr", 2e4, "steel", None),
    ],
)
def test_exported_compliance_and_frequencies_are_pkdyns(name, k, material, where):
    robot = pkdyn.load(name)
    q = robot.q_home if where is None else pkdyn.inverse_geometry(robot, where).q
    em = elastic_model(robot, k, material=material)
    point = np.array([0.01, 0.02, -0.03])
    K, rows, Jp, M = _mujoco_linear(em, q, point)
    # every spring (servos, the links' six per virtual spring) on its own MuJoCo joint
    assert K.size == em.robot.nv and np.count_nonzero(K) == np.count_nonzero(em.spring_stiffness())
    N, w, V = _stiff(K, rows)
    JV = Jp @ N @ V
    C = (JV / w) @ JV.T  # MuJoCo's compliance at the point (world axes)
    task = np.asarray(robot.task_rows)
    C_pk = stiffness(em, q, point=point).compliance
    C_mj = C[np.ix_(task, task)]
    for a in (task < 3, task >= 3):
        for b in (task < 3, task >= 3):
            if a.any() and b.any():
                scale = np.sqrt(np.abs(C_pk[np.ix_(a, a)]).max() * np.abs(C_pk[np.ix_(b, b)]).max())
                assert np.abs(C_mj[np.ix_(a, b)] - C_pk[np.ix_(a, b)]).max() <= 1e-9 * scale
    # natural frequencies from MuJoCo's mass matrix
    lam = scipy.linalg.eigh(N.T @ (K[:, None] * N), N.T @ M @ N, eigvals_only=True)
    lam = lam[lam > 1e-10 * lam.max()]
    f = modes(em, q).frequencies
    assert lam.size == f.size
    assert np.sqrt(lam) / (2 * np.pi) == pytest.approx(f, rel=1e-6)


def _modal_and_mujoco(material, timestep, integrator):
    """The Delta's Adept cycle (0.5 s, 0.5 kg, 2e4 N m/rad) by the modal method and MuJoCo."""
    from pkdyn.dynamics.trajectory import named_task
    from pkdyn.precision.vibration import analyse, prepare
    from pkdyn.precision.vibration_command import command
    from pkdyn.precision.vibration_mjcf import mujoco_figures

    robot = pkdyn.load("delta")
    em = elastic_model(robot, 2e4, material=material)
    p = np.zeros(3)
    cmd = command(em, named_task(robot, "adept", cycle_time=0.5), 0.5, p)
    st = prepare(robot, em, cmd, p, 0.5, "none", None, None, 2e-5, 0.3, None, None)
    modal = analyse(st, cmd, "modal")  # (as vibration(robot, "adept", ...))
    _, fig = mujoco_figures(st, cmd, modal, timestep, integrator)
    return modal, fig


@pytest.mark.parametrize(
    "material, timestep, integrator",
    [
        (None, 5e-5, "RK4"),  # rigid links: three modes, 91 to 157 Hz with the payload
        # carbon arms and bars: 57 modes up to 7.1 kHz, the stiffest overdamped by the links'
        # Rayleigh damping; implicit in the dampers, explicit in the springs: stable below
        # 2 / omega_max (45 us)
        ("carbon", 4e-5, "implicitfast"),
    ],
)
def test_mujoco_runs_the_exported_model_as_the_modal_method(material, timestep, integrator):
    modal, fig = _modal_and_mujoco(material, timestep, integrator)
    if material is not None:
        assert modal.links and modal.modes > 20  # (57 modes, 33 integrated)
    assert fig.peak_deviation == pytest.approx(modal.peak_deviation, rel=0.02)
    assert fig.residual_amplitude == pytest.approx(modal.residual_amplitude, rel=0.02)
    assert fig.settling_time == pytest.approx(modal.settling_time, rel=0.02)


def test_refusals_name_the_culprit():
    from pkdyn.exceptions import InvalidInputError
    from pkdyn.precision.vibration_mjcf import mujoco_figures

    em = elastic_model(pkdyn.load("gough_stewart"), 2e6, material="steel")
    with pytest.raises(InvalidInputError, match="leg1_rod"):  # (MuJoCo: a mass per body)
        elastic_mjcf(em, np.zeros(6))
    delta = elastic_model(pkdyn.load("delta"), 2e4, material="carbon")
    with pytest.raises(InvalidInputError, match="servo_damping"):
        elastic_mjcf(delta, np.zeros(2))
    with pytest.raises(InvalidInputError, match="damping"):
        elastic_mjcf(delta, np.zeros(3), damping=np.zeros(5))
    with pytest.raises(InvalidInputError, match="integrator"):
        mujoco_figures(None, None, None, integrator="leapfrog")
