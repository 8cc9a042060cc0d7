r"""The modal method in closed form on the library Delta: its arms' motion, efforts and modes.

For a library Delta (three arms, ball-jointed bars:
:func:`pkdyn.dynamics.delta.has_delta_dynamics`) without springs of its own, the actuators'
motion along a platform trajectory and the rigid robot's efforts are Clavel's closed forms
(:class:`pkdyn.dynamics.delta.DeltaDynamics`, equal to the general mapping and the constrained
inverse dynamics to 1e-9), vectorised over the samples: no pose is solved. With rigid links
and finite servo stiffnesses, the elastic model's deformation is the arms' deviation from their
command, ``e = q_a - q_a,cmd`` (3,) (the passive joints follow the closures, the bars without
spin momentum), and the modal method's equation (:mod:`pkdyn.precision.vibration_modal`) reads

.. math::

    M_a(q_c)\, \ddot e + C_a \dot e + K_a e = \tau_{ff} - \tau_{rigid}(t)

with ``M_a = J^T M_x J`` the arms' mass matrix (``M_x`` the nacelle-space mass of
:mod:`pkdyn.precision.vectorised`: arms with their rotors, bars without spin, nacelle and
payload; ``J = J_inv^-1`` the nacelle's velocity per arm rate), ``K_a`` and ``C_a`` the servos'
stiffness and damping (diagonal), and ``tau_rigid`` the rigid inverse dynamics of the command:
the unbalanced generalized force of :func:`~pkdyn.precision.vibration_modal.loads` seen by the
arms (by virtual power, the closures' reactions do no work on the motions they allow). The
modes at each pose solve ``K_a phi = omega^2 M_a phi`` (3 x 3, batched: Cholesky whitening of
``M_x`` and ``eigh``); the nacelle translates, so every point of it moves by ``J phi``. These
are the general method's equations in three coordinates instead of the tree's, so the modes
are computed at every command sample (no interpolation between poses). The tests check the
frequencies against :func:`pkdyn.precision.modes.modes`, and the response against the general
path and the multibody simulation.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from pkdyn.dynamics.delta import DeltaDynamics
from pkdyn.dynamics.trajectory import TaskTrajectory
from pkdyn.exceptions import SingularConfigurationError
from pkdyn.model.robot import Robot
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.vectorised import _delta_jacobian, _delta_mass, vectorised
from pkdyn.precision.vibration_modal import PathModes

__all__ = [
    "ActuatorMotion",
    "DeltaModes",
    "DeltaPoses",
    "applies",
    "arm_motion",
    "closed_form",
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
