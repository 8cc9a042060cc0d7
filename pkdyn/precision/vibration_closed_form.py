r"""The modal method in closed form on the library Delta: its arms, joints, efforts and modes.

For a library Delta (three arms, ball-jointed bars:
:func:`pkdyn.dynamics.delta.has_delta_dynamics`) without springs of its own, the actuators'
motion along a platform trajectory and the rigid robot's efforts are Clavel's closed forms
(:class:`pkdyn.dynamics.delta.DeltaDynamics`, equal to the general mapping and the constrained
inverse dynamics to 1e-9), vectorised over the samples: no pose is solved; so is the whole
mechanism's joint trajectory (:func:`delta_joint_trajectory`). With rigid links and finite
servo stiffnesses the elastic model moves with three coordinates, and the modal method's
equation (:mod:`pkdyn.precision.vibration_modal`) is written in the nacelle's (its translation
``x`` from the commanded position, world axes: the deviation itself):

.. math::

    M_x(q_c)\, \ddot x + J^T C_a J\, \dot x + J^T K_a J\, x
    = J^T (\tau_{ff} - \tau_{rigid}(t))

with ``M_x`` the nacelle-space mass of :mod:`pkdyn.precision.vectorised` (arms with their
rotors, bars without spin, nacelle and payload), ``J = J_inv`` the arms' rates per nacelle
velocity, ``K_a`` and ``C_a`` the servos' stiffness and damping (diagonal) and ``tau_rigid``
the rigid inverse dynamics of the command: ``J^T (tau_ff - tau_rigid)`` is the unbalanced
generalized force of :func:`~pkdyn.precision.vibration_modal.loads` seen by the nacelle (by
virtual power, the closures' reactions do no work on the motions they allow). The modes at
each pose solve ``J^T K_a J phi = omega^2 M_x phi`` (3 x 3, batched: Cholesky whitening and
``eigh``), at every command sample (no interpolation between poses); every point of the
nacelle moves by ``phi`` (it translates).

The same equations as the general method's, in other coordinates: what a linearisation
neglects (the inertial loads' geometric stiffness, the gyroscopic coupling of the deformation
rates) depends on them. In the nacelle's the neglected terms change the figures by 0.05 to 0.3
% (measured by integrating them); in the arms' coordinates (``e = q_a - q_a,cmd``, the mass
``J^-T M_x J^-1``) the residual amplitude and settling time of the Delta's Adept cycle came
out 2 % and 6 % from the multibody simulation, against 0.9 % and 0.07 % here. The tests check
the frequencies against :func:`pkdyn.precision.modes.modes`, and the response against the
general path and the multibody simulation.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.dynamics.delta import DeltaDynamics
from pkdyn.dynamics.trajectory import JointTrajectory, TaskTrajectory
from pkdyn.exceptions import SingularConfigurationError
from pkdyn.model.robot import Robot
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.vectorised import _delta_jacobian, _delta_mass, vectorised
from pkdyn.precision.vibration_modal import PathModes
from solvers.vec3 import cross

__all__ = [
    "ActuatorMotion",
    "DeltaModes",
    "DeltaPoses",
    "applies",
    "arm_motion",
    "closed_form",
    "delta_joint_trajectory",
    "gravity_efforts",
    "joint_deformation",
]


@dataclass(frozen=True)
class ActuatorMotion:
    """The actuators' commanded motion and the rigid robot's efforts along it (closed form).

    Attributes:
        qa: Actuator positions (N, n_a) [rad or m].
        qa_dot: Their rates (N, n_a).
        qa_ddot: Their accelerations (N, n_a).
        tau: Rigid inverse dynamics efforts (N, n_a) [N m or N], joint side, payload included.

    """

    qa: np.ndarray
    qa_dot: np.ndarray
    qa_ddot: np.ndarray
    tau: np.ndarray


def closed_form(robot: Robot) -> bool:
    """Whether the arms' closed forms apply: a library Delta without springs of its own."""
    return vectorised(robot, frequency=True) == "delta"


def applies(em: ElasticModel) -> bool:
    """Whether the closed-form modal method applies: that Delta, rigid links, finite servos."""
    return (
        not em.links
        and em.robot is em.base
        and closed_form(em.base)
        and bool(np.all(np.isfinite(em.actuator_stiffness)))
    )


def arm_motion(
    dd: DeltaDynamics, task: TaskTrajectory, check_limits: bool = True
) -> ActuatorMotion:
    """The arms' motion and the rigid robot's efforts along ``task``, in closed form.

    Args:
        dd: The Delta's closed forms, read from the robot carrying its payload
            (:func:`closed_form`).
        task: The platform trajectory.
        check_limits: Raise when an arm leaves its angle limits (not its speed limits: as the
            general mapping of a vibration analysis).

    Returns:
        Arm angles, rates, accelerations [rad, rad/s, rad/s^2] and efforts [N m].

    Raises:
        TrajectoryError: A sample out of reach, at or across a singularity, or beyond an
            arm's limits (named).

    """
    m = dd.solve(task, check_limits=check_limits, check_speeds=False)
    return ActuatorMotion(m.qa, m.qa_dot, m.qa_ddot, np.asarray(m.tau, dtype=float))


def gravity_efforts(dd: DeltaDynamics, task: TaskTrajectory) -> np.ndarray:
    """The arms' efforts holding the commanded poses at rest (N, 3) [N m]."""
    zero = np.zeros_like(task.pose_d)
    still = dataclasses.replace(task, pose_d=zero, pose_dd=zero)
    return np.asarray(dd.solve(still, check_limits=False).tau, dtype=float)


@dataclass(eq=False)  # numpy fields
class DeltaPoses:
    """The Delta's arm geometry at nacelle positions (:func:`DeltaModes.poses`).

    Attributes:
        Jinv: Arm rates per nacelle velocity (n, 3, 3) [rad/m].
        E1: Elbow velocity per arm rate (n, 3 arms, 3) [m/rad].
        d: Bar vectors, elbow to nacelle (n, 3 arms, 3) [m].

    """

    Jinv: np.ndarray
    E1: np.ndarray
    d: np.ndarray

    def take(self, samples: np.ndarray) -> DeltaPoses:
        """The poses ``samples``."""
        return DeltaPoses(self.Jinv[samples], self.E1[samples], self.d[samples])


class DeltaModes:
    """Modes of the Delta's elastic model in the nacelle's coordinates, at any positions.

    Args:
        dd: The Delta's closed forms, read from the elastic model's robot (with the payload).
        stiffness: Servo stiffness per arm (3,) [N m/rad], finite.

    """

    def __init__(self, dd: DeltaDynamics, stiffness: np.ndarray) -> None:
        self.dd = dd
        self.k = np.asarray(stiffness, dtype=float)
        self.internal = len(self.dd.bars)  # the bars' spins

    def poses(self, P: np.ndarray) -> DeltaPoses:
        """The arm geometry at platform positions ``P`` (n, 3) [m].

        Raises:
            SingularConfigurationError: A position out of reach or at a singularity.

        """
        P = np.atleast_2d(np.asarray(P, dtype=float))
        ok, Jinv, E1, d, _, _ = _delta_jacobian(self.dd, P)
        if not ok.all():
            k = int(np.flatnonzero(~ok)[0])
            raise SingularConfigurationError(
                "serial",
                f"{self.dd.robot.name}: the arms cannot control the nacelle at "
                f"{np.round(P[k], 6).tolist()} m (out of reach or singular)",
            )
        return DeltaPoses(Jinv, E1, d)

    def damping(self, poses: DeltaPoses, c: np.ndarray) -> np.ndarray:
        """The servos' damping ``J_inv^T C_a J_inv`` (n, 3, 3) [N s/m] of servo damping ``c``."""
        return np.einsum("nki,k,nkj->nij", poses.Jinv, np.asarray(c, dtype=float), poses.Jinv)

    def path_modes(self, poses: DeltaPoses, samples: np.ndarray) -> PathModes:
        """Modes at the poses ``poses`` (the command's samples ``samples``).

        Returns:
            :class:`PathModes` in the nacelle's coordinates (``platform``): shapes (n, 3, 3)
            (mass-normalised), mass ``M_x`` (n, 3, 3), platform motions (n, 3, 6).

        """
        Jinv = poses.Jinv
        Mx = _delta_mass(self.dd, Jinv, poses.E1, poses.d)
        Kx = np.einsum("nki,k,nkj->nij", Jinv, self.k, Jinv)  # J_inv^T K_a J_inv
        Li = np.linalg.inv(np.linalg.cholesky(Mx))
        A = Li @ Kx @ np.swapaxes(Li, 1, 2)
        w2, Y = np.linalg.eigh(0.5 * (A + np.swapaxes(A, 1, 2)))
        shapes = np.swapaxes(np.swapaxes(Li, 1, 2) @ Y, 1, 2)  # (n, mode, 3), M_x-normalised
        platform = np.zeros((shapes.shape[0], 3, 6))
        platform[:, :, :3] = shapes
        return PathModes(
            samples=np.asarray(samples, dtype=int),
            frequencies=np.sqrt(np.maximum(w2, 0.0)) / (2.0 * np.pi),
            shapes=shapes,
            platform=platform,
            mass=Mx,
            internal=self.internal,
            coordinates="platform",
        )


def _turn(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotations (..., 3, 3) taking unit vectors ``a`` to ``b`` (..., 3)."""
    k = cross(a, b)
    c = np.einsum("...i,...i->...", a, b)
    K = np.zeros((*k.shape[:-1], 3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -k[..., 2], k[..., 1], -k[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = k[..., 2], -k[..., 1], k[..., 0]
    return np.eye(3) + K + (K @ K) / (1.0 + c)[..., None, None]


def delta_joint_trajectory(
    robot: Robot, dd: DeltaDynamics, task: TaskTrajectory, arms: ActuatorMotion
) -> JointTrajectory | None:
    """The library Delta's joint trajectory along ``task``, in closed form (no pose solved).

    The trajectory :func:`pkdyn.dynamics.trajectory.map_task_trajectory` maps, built from the
    arms' closed-form motion: arm ``k`` at ``alpha_k``; both bars of the arm along
    ``u_k = d_k / L_k`` (elbow to nacelle), turning at ``omega = u x u'`` and ``u x u''`` (no
    spin: their spin momentum stays zero, as the general mapping makes it), their spin
    carried along the samples by the smallest rotation between successive axes (parallel
    transport, from the home configuration's); the nacelle translating. Each spherical joint's
    velocity is the bar's angular velocity relative to its arm, in the bar frame, and its
    acceleration the rate of that vector; the nacelle's free joint's are its velocity and
    acceleration in its own frame.

    Args:
        robot: The Delta as loaded.
        dd: Its closed forms (:class:`~pkdyn.dynamics.delta.DeltaDynamics`).
        task: The platform trajectory (uniform samples).
        arms: The arms' motion along it (:func:`arm_motion`).

    Returns:
        The joint trajectory, or ``None`` when the model is not the library's tree (arms on
        the world, spherical bar joints on the arms, the nacelle a free joint on the world).

    """
    model = robot.model
    arm_j = [int(j) for j in robot.actuated_joints]
    fid = robot.platform_frame
    if fid is None:
        return None
    nac = int(model.frames[fid].parentJoint)
    if model.joints[nac].shortname() != "JointModelFreeFlyer" or int(model.parents[nac]) != 0:
        return None
    bars = []
    for cm in robot.constraint_models:
        j = int(cm.joint1_id)
        parent = int(model.parents[j])
        if (
            model.joints[j].shortname() != "JointModelSpherical"
            or parent not in arm_j
            or int(cm.joint2_id) != nac
        ):
            return None
        p = np.asarray(cm.joint1_placement.translation, dtype=float)
        bars.append((j, arm_j.index(parent), np.asarray(model.jointPlacements[j].rotation), p))
    if model.njoints - 1 != len(arm_j) + len(bars) + 1:
        return None
    P, Pd, Pdd = task.pose[:, :3], task.pose_d[:, :3], task.pose_dd[:, :3]
    alpha, ad, add = arms.qa, arms.qa_dot, arms.qa_ddot
    N = P.shape[0]
    c, s = np.cos(alpha), np.sin(alpha)
    a = dd.axis[None]  # (1, arm, 3)
    E = dd.O[None] + dd._in_world(c, s, dd.elbow)
    d = P[:, None, :] + dd.attach[None] - E
    L = dd.length[None, :, None]
    E1 = cross(a, E - dd.O[None])
    E2 = cross(a, E1)
    u = d / L
    ud = (Pd[:, None, :] - E1 * ad[..., None]) / L
    udd = (Pdd[:, None, :] - E1 * add[..., None] - E2 * (ad**2)[..., None]) / L
    w_bar = cross(u, ud)  # (N, arm, 3): the bars' angular velocity, world axes
    al_bar = cross(u, udd)
    w_rel = w_bar - ad[..., None] * a  # relative to the arm
    al_rel = al_bar - add[..., None] * a
    # arm frames R0 Ry(alpha) (N, arm, 3, 3)
    Ry = np.zeros((N, 3, 3, 3))
    Ry[..., 0, 0], Ry[..., 0, 2], Ry[..., 1, 1] = c, s, 1.0
    Ry[..., 2, 0], Ry[..., 2, 2] = -s, c
    R_arm = dd.R0[None] @ Ry
    Q = np.tile(robot.q_home, (N, 1))
    V = np.zeros((N, model.nv))
    A = np.zeros((N, model.nv))
    for k, j in enumerate(arm_j):
        jm = model.joints[j]
        Q[:, jm.idx_q], V[:, jm.idx_v], A[:, jm.idx_v] = alpha[:, k], ad[:, k], add[:, k]
    from scipy.spatial.transform import Rotation

    data = robot.model.createData()
    pin.forwardKinematics(model, data, robot.q_home)
    for j, k, R_pl, p in bars:
        z = p / np.linalg.norm(p)
        base = R_arm[:, k] @ R_pl  # (N, 3, 3): the bar frame at zero relative rotation
        R = np.empty((N, 3, 3))
        home = np.asarray(data.oMi[j].rotation)
        R[0] = _turn(home @ z, u[0, k]) @ home  # (the home's spin, turned onto the axis)
        steps = _turn(u[:-1, k], u[1:, k])
        for i in range(N - 1):
            R[i + 1] = steps[i] @ R[i]
        rel = np.swapaxes(base, 1, 2) @ R
        jm = model.joints[j]
        Q[:, jm.idx_q : jm.idx_q + 4] = Rotation.from_matrix(rel).as_quat()  # (x, y, z, w)
        Rt = np.swapaxes(R, 1, 2)
        v = np.einsum("nij,nj->ni", Rt, w_rel[:, k])
        V[:, jm.idx_v : jm.idx_v + 3] = v
        w_local = np.einsum("nij,nj->ni", Rt, w_bar[:, k])
        A[:, jm.idx_v : jm.idx_v + 3] = np.einsum("nij,nj->ni", Rt, al_rel[:, k]) - cross(
            w_local, v
        )
    jm = model.joints[nac]
    Mp = model.jointPlacements[nac]
    Rn = dd.R_nacelle
    Rp = np.asarray(Mp.rotation)
    Q[:, jm.idx_q : jm.idx_q + 3] = (P - dd.f_off - np.asarray(Mp.translation)) @ Rp
    Q[:, jm.idx_q + 3 : jm.idx_q + 7] = Rotation.from_matrix(Rp.T @ Rn).as_quat()
    V[:, jm.idx_v : jm.idx_v + 3] = Pd @ Rn
    A[:, jm.idx_v : jm.idx_v + 3] = Pdd @ Rn
    return JointTrajectory(
        task.t.copy(), Q, V, A, robot.actuated_q, robot.actuated_v, task=task, name=task.name
    )


def joint_deformation(em: ElasticModel, Q: np.ndarray, E: np.ndarray) -> np.ndarray:
    """Deformations of the extended tree (K, nv) whose actuators deviate by ``E`` (K, n_a).

    At each commanded configuration ``Q[k]``, the smallest joint motion that keeps the
    closures and moves the actuators by ``E[k]`` (for displays).
    """
    from pkdyn.precision.condensation import constraint_rows
    from solvers import numerics

    r = em.robot
    iv = np.asarray(r.actuated_v)
    sel = np.zeros((iv.size, r.nv))
    sel[np.arange(iv.size), iv] = 1.0
    out = np.empty((Q.shape[0], r.nv))
    for k in range(Q.shape[0]):
        A = np.vstack([constraint_rows(em, Q[k]), sel])
        b = np.concatenate([np.zeros(A.shape[0] - iv.size), E[k]])
        out[k] = numerics.lstsq(A, b, 1e-9, 1.0)
    return out
