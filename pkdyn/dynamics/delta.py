"""Inverse dynamics of the library Delta along a platform trajectory, vectorised (closed form).

The general path (:func:`pkdyn.dynamics.trajectory.map_task_trajectory` then
:func:`pkdyn.dynamics.inverse_dynamics`) solves every sample with the numeric geometric models
and the constrained inverse dynamics: about 3 ms per sample. For Clavel's Delta with ball-jointed
parallelograms the same efforts follow in closed form for all samples at once (numpy), about a
thousand times faster; design studies (:mod:`pkdyn.design`) size thousands of Deltas with it.

Kinematics (seed 000, eq. 1): arm ``k`` turns by ``alpha_k`` about the fixed axis ``a_k``
through ``O_k``; its two bars run from the elbow points ``E_b`` to the nacelle points
``A_b = P + delta_b``, and both bars of arm ``k`` share the vector ``d_k = A_b - E_b`` with
``|d_k| = lb``. With ``E'_k = a_k x (E_k - O_k)`` (``dE/d alpha``) and ``E''_k = a_k x E'_k``::

    alpha_dot_k  = d_k . P_dot / (d_k . E'_k)
    alpha_ddot_k = (d_k . P_ddot - alpha_dot_k^2 d_k . E''_k + |d_dot_k|^2) / (d_k . E'_k)

with ``d_dot_k = P_dot - E'_k alpha_dot_k``. The nacelle translates; each bar, a solid of
revolution about its axis ``u = d / lb`` with zero spin momentum (as the general mapping makes
it, see :mod:`pkdyn.dynamics.trajectory`), turns at ``omega = u x u_dot`` and
``omega_dot = u x u_ddot``, so its moment about its centre of mass is ``I_t omega_dot``.

Efforts by virtual power: every body velocity is linear in ``P_dot`` (``alpha_dot = J_inv
P_dot``, ``J_inv`` with rows ``d_k^T / (d_k . E'_k)``); with ``w`` the generalized force of the
bars and the nacelle in ``P`` coordinates (inertia minus gravity) and ``Q_k`` that of arm ``k``
about its axis, ``tau = Q + J_inv^-T w``. Masses, centres of mass, inertias, armatures, gravity
and joint placements are read from the loaded model (so :func:`pkdyn.dynamics.with_payload`
and edited masses count); the tests check the efforts against the general path to 1e-9.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.analysis.kinematics import SINGULAR_TOL
from pkdyn.closed_form.delta import inverse
from pkdyn.dynamics.series import series_table
from pkdyn.dynamics.trajectory import TaskTrajectory
from pkdyn.exceptions import PkdynError, TrajectoryError
from pkdyn.model.robot import Robot
from pkdyn.results import Result, jsonable
from solvers.vec3 import cross

__all__ = [
    "DET_BOUND",
    "ActuatorTrajectory",
    "DeltaDynamics",
    "delta_closed_form_params",
    "delta_inverse_dynamics",
    "has_delta_dynamics",
    "unit_dets",
]


@dataclass(frozen=True)
class ActuatorTrajectory(Result):
    """Actuator motion and efforts along a trajectory.

    Attributes:
        t: Sample times (N,) [s].
        actuators: Actuator (joint) names (n_a).
        qa: Actuator positions (N, n_a) [rad].
        qa_dot: Actuator rates (N, n_a) [rad/s].
        qa_ddot: Actuator accelerations (N, n_a) [rad/s^2].
        tau: Joint-side efforts (N, n_a) [N m].

    """

    t: np.ndarray
    actuators: list[str]
    qa: np.ndarray
    qa_dot: np.ndarray
    qa_ddot: np.ndarray
    tau: np.ndarray

    @property
    def power(self) -> np.ndarray:
        """Actuator powers ``tau * qa_dot`` (N, n_a) [W]."""
        return self.tau * self.qa_dot

    def to_json(self) -> dict[str, Any]:
        """The series: ``t`` [s], ``actuators``, ``qa`` [rad], ``qa_dot``, ``qa_ddot``, ``tau``."""
        return jsonable(
            {
                "t": self.t,
                "actuators": list(self.actuators),
                "qa": self.qa,
                "qa_dot": self.qa_dot,
                "qa_ddot": self.qa_ddot,
                "tau": self.tau,
            }
        )

    def table(self) -> str:
        """Per actuator: the range of its angle, rate and effort."""
        n = list(self.actuators)
        return series_table(
            "actuator trajectory",
            self.t,
            [
                ("qa", self.qa, n, ["rad"] * len(n)),
                ("qa_dot", self.qa_dot, n, ["rad/s"] * len(n)),
                ("tau", self.tau, n, ["N m"] * len(n)),
            ],
        )


def delta_closed_form_params(p: Any) -> bool:
    """Whether Delta parameters give 3 arms of ball-jointed bars (Clavel's closed forms apply).

    Args:
        p: The family's parameters (or any object with ``arms``, ``parallelogram``,
            ``bar_joint``; a missing one takes the library's default).

    """
    return (
        getattr(p, "arms", 3) == 3
        and getattr(p, "parallelogram", "ball") == "ball"
        and getattr(p, "bar_joint", "spherical") == "spherical"
    )


def has_delta_dynamics(robot: Robot) -> bool:
    """Whether :func:`delta_inverse_dynamics` applies: a library Delta, 3 arms, ball bars."""
    return (
        robot.family == "delta"
        and delta_closed_form_params(robot.params)
        and len(robot.actuators) == 3
        and robot.platform_frame is not None
    )


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of two 3-vectors: its products and differences, without its overhead."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", a, b)


@dataclass(frozen=True)
class _Bar:
    arm: int
    elbow: np.ndarray  # ball centre in the arm frame [m]
    nacelle: np.ndarray  # closure point on the nacelle, minus the platform frame offset [m]
    mass: float
    fraction: float  # centre of mass along the bar, from the elbow (0..1)
    length: float  # ball centre to ball centre [m]
    inertia_t: float  # transverse inertia about the centre of mass [kg m^2]


def _solid(
    p_bar: np.ndarray, lever: np.ndarray, Ic: np.ndarray
) -> tuple[float, float, float, bool]:
    """A bar's axial figures, and whether it is not a solid of revolution about its axis.

    Returns ``(length [m], transverse inertia [kg m^2], centre-of-mass fraction, not one)``.

    Args:
        p_bar: Lower ball centre in the bar frame (3,) [m] (the upper one at its origin).
        lever: Centre of mass in the bar frame (3,) [m].
        Ic: Inertia about the centre of mass, bar frame (3, 3) [kg m^2].

    """
    length = float(np.linalg.norm(p_bar))
    z = p_bar / length
    It = float(Ic.trace() - z @ Ic @ z) / 2.0
    Ia = float(z @ Ic @ z)
    sym = It * (np.eye(3) - np.outer(z, z)) + Ia * np.outer(z, z)
    bad = bool(
        np.linalg.norm(_cross3(lever, z)) > 1e-12
        or np.max(np.abs(Ic - sym)) > 1e-12 * (1.0 + abs(It))
    )
    return length, It, float(lever @ z) / length, bad


class DeltaDynamics:
    """The Delta's kinematic and inertial data read from a loaded model, for many trajectories.

    Args:
        robot: A library Delta with three arms and ball-jointed bars (:func:`has_delta_dynamics`),
            possibly with a payload (:func:`pkdyn.dynamics.with_payload`).
        payload: A point mass added to the nacelle [kg] (the nacelle only translates: where it
            sits does not matter; the same as ``with_payload(robot, payload)``).

    Raises:
        PkdynError: Not such a Delta, or a bar that is not a solid of revolution about its axis.

    """

    def __init__(self, robot: Robot, payload: float = 0.0) -> None:
        if not has_delta_dynamics(robot):
            raise PkdynError(
                f"{robot.name}: the closed-form Delta dynamics needs a library Delta with three "
                "arms and ball-jointed bars; use pkdyn.dynamics.inverse_dynamics"
            )
        model = robot.model
        self.robot = robot
        self.params = robot.params
        arms = [int(j) for j in robot.actuated_joints]
        self.arms = arms
        self.O = np.array([model.jointPlacements[j].translation for j in arms])
        self.R0 = np.array([model.jointPlacements[j].rotation for j in arms])
        self.axis = self.R0[:, :, 1]  # arm axes a_k (world): joint y axes
        iv = robot.actuated_v
        arm_I = [model.inertias[j] for j in arms]
        self.arm_mass = np.array([float(i.mass) for i in arm_I])
        self.arm_lever = np.array([np.array(i.lever) for i in arm_I])  # arm frame
        y = np.array([0.0, 1.0, 0.0])
        axial: dict[bytes, float] = {}  # (the arms of a library Delta share it: computed once)
        keys = []
        for i in arm_I:
            lever, inertia = np.asarray(i.lever), np.asarray(i.inertia)
            key = float(i.mass).hex().encode() + lever.tobytes() + inertia.tobytes()
            keys.append(key)
            if key not in axial:
                axial[key] = float(inertia[1, 1]) + float(i.mass) * float(
                    np.sum(_cross3(y, lever) ** 2)
                )
        self.arm_axial = np.array([axial[k] for k in keys]) + np.asarray(model.armature)[iv]
        self.gravity = np.array(model.gravity.linear)
        frame = model.frames[robot.platform_frame]
        nac = int(frame.parentJoint)
        pin.framesForwardKinematics(model, robot.data, robot.q_home)
        self.R_nacelle = np.array(robot.data.oMi[nac].rotation)
        f_off = self.R_nacelle @ np.array(frame.placement.translation)
        self.f_off = f_off  # platform frame origin minus nacelle centre, world axes [m]
        if not (np.isfinite(payload) and payload >= 0.0):
            raise PkdynError(f"payload must be >= 0 kg, got {payload}")
        self.nacelle_mass = float(model.inertias[nac].mass) + float(payload)
        bars = []
        # a bar's axial figures are a function of its lower ball and its inertia alone: the
        # bars of a library Delta share them, computed once (the same numbers, bit for bit)
        solids: dict[bytes, tuple[float, float, float, float]] = {}
        for cm in robot.constraint_models:
            j1, j2 = int(cm.joint1_id), int(cm.joint2_id)
            if j2 != nac or int(model.parents[j1]) not in arms:
                raise PkdynError(f"{robot.name}: closure on joint {model.names[j1]} is not a bar")
            p_bar = np.array(cm.joint1_placement.translation)  # lower ball, bar frame
            inert = model.inertias[j1]
            lever = np.array(inert.lever)
            Ic = np.array(inert.inertia)
            key = p_bar.tobytes() + lever.tobytes() + Ic.tobytes()
            solid = solids.get(key)
            if solid is None:
                solid = solids[key] = _solid(p_bar, lever, Ic)
            length, It, fraction, bad = solid
            if bad:
                raise PkdynError(
                    f"{robot.name}: bar '{model.names[j1]}' is not a solid of revolution about "
                    "its axis; use pkdyn.dynamics.inverse_dynamics"
                )
            bars.append(
                _Bar(
                    arm=arms.index(int(model.parents[j1])),
                    elbow=np.array(model.jointPlacements[j1].translation),
                    nacelle=self.R_nacelle @ np.array(cm.joint2_placement.translation) - f_off,
                    mass=float(inert.mass),
                    fraction=fraction,
                    length=length,
                    inertia_t=It,
                )
            )
        self.bars = bars
        # per arm: elbow and nacelle points of its first bar (the bars of an arm share d, E',
        # E'', u and their length), and the sums over its bars of the mass moments that the
        # bars' generalized forces need (see solve)
        first = [next(b for b in bars if b.arm == k) for k in range(3)]
        for b in bars:
            if abs(b.length - first[b.arm].length) > 1e-12:
                raise PkdynError(f"{robot.name}: the bars of arm {b.arm + 1} differ in length")
        self.elbow = np.array([b.elbow for b in first])
        self.attach = np.array([b.nacelle for b in first])
        self.length = np.array([b.length for b in first])

        def per_arm(fn: Callable[[_Bar], float]) -> np.ndarray:
            return np.array([sum(fn(b) for b in bars if b.arm == k) for k in range(3)])

        self.m_ee = per_arm(lambda b: b.mass * (1.0 - b.fraction) ** 2)
        self.m_ep = per_arm(lambda b: b.mass * b.fraction * (1.0 - b.fraction))
        self.m_pp = per_arm(lambda b: b.mass * b.fraction**2)
        self.m_e = per_arm(lambda b: b.mass * (1.0 - b.fraction))
        self.m_p = per_arm(lambda b: b.mass * b.fraction)
        self.inertia_t = per_arm(lambda b: b.inertia_t)
        self.lo = np.array(model.lowerPositionLimit[robot.actuated_q])
        self.hi = np.array(model.upperPositionLimit[robot.actuated_q])
        self.vmax = np.array([a.velocity for a in robot.actuators])
        self.names = robot.actuator_names

    def _in_world(self, c: np.ndarray, s: np.ndarray, e: np.ndarray) -> np.ndarray:
        """Arm-frame vectors ``e`` (3 arms, 3) in world axes (N, 3, 3), elementwise.

        ``R0_k Ry(alpha_k) e_k`` for arm angles of cosines ``c`` and sines ``s`` (N, 3).
        """
        x = c * e[:, 0] + s * e[:, 2]
        z = c * e[:, 2] - s * e[:, 0]
        R0 = self.R0
        return x[..., None] * R0[:, :, 0] + e[:, 1, None] * R0[:, :, 1] + z[..., None] * R0[:, :, 2]

    def solve(
        self, task: TaskTrajectory, check_limits: bool = True, check_speeds: bool = True
    ) -> ActuatorTrajectory:
        """Actuator motion and efforts along a platform trajectory (see the module docstring).

        Args:
            task: Platform trajectory (positions, rates and accelerations of the platform
                frame; the orientation columns are ignored: the nacelle keeps its own).
            check_limits: Raise if an arm leaves its angle or speed limits (as
                :func:`pkdyn.dynamics.trajectory.map_task_trajectory` does).
            check_speeds: With ``check_limits``, also raise beyond a speed limit (``False``:
                the angle limits only, as ``map_task_trajectory(..., check_speeds=False)``).

        Returns:
            Arm angles, rates, accelerations and joint-side torques.

        Raises:
            TrajectoryError: A sample is out of reach, at or across a singularity, or outside
                the arm limits (the message names the sample).

        """
        t = task.t
        P, Pd, Pdd = task.pose[:, :3], task.pose_d[:, :3], task.pose_dd[:, :3]
        alpha, ok = inverse(self.params, P - self.f_off)
        if not ok.all():
            k = int(np.flatnonzero(~ok)[0])
            raise TrajectoryError("pose out of reach of the arms", sample=k, time=float(t[k]))
        if check_limits:
            self._check_angles(t, alpha)
        c, s = np.cos(alpha), np.sin(alpha)
        a = self.axis[None]  # (1, 3 arms, 3): arm axes
        E = self.O[None] + self._in_world(c, s, self.elbow)  # elbow ball centres (N, 3, 3)
        d = P[:, None, :] + self.attach[None] - E  # bar vectors, |d| = length
        E1 = cross(a, E - self.O[None])  # dE/d alpha
        E2 = cross(a, E1)  # d2E/d alpha2
        g = _dot(d, E1)  # (N, 3)
        self._check_singular(t, d, E1, g)
        alpha_d = _dot(d, Pd[:, None, :]) / g
        dd = Pd[:, None, :] - E1 * alpha_d[..., None]
        alpha_dd = (_dot(d, Pdd[:, None, :]) - alpha_d**2 * _dot(d, E2) + _dot(dd, dd)) / g
        if check_limits and check_speeds:
            self._check_speeds(t, alpha_d)
        Edd = E1 * alpha_dd[..., None] + E2 * (alpha_d**2)[..., None]  # elbow accelerations
        Jinv = d / g[..., None]  # (N, 3 arms, 3)
        grav = self.gravity
        # arms: Q_k = I_axis alpha_dd - m g . (a x r)
        r_arm = self._in_world(c, s, self.arm_lever)
        Q = self.arm_axial * alpha_dd - self.arm_mass * _dot(cross(a, r_arm), grav[None, None])
        # nacelle (translating): w = m (P_ddot - g)
        w = self.nacelle_mass * (Pdd - grav)
        # bars, summed per arm: centre c = E + f d; F = m (c_ddot - g) with
        # c_ddot = (1 - f) E_ddot + f P_ddot; V = (1 - f) E' (x) Jinv_k + f I, so that
        # sum V^T F = Jinv_k (E' . sum (1 - f) F) + sum f F; M = I_t u x u_ddot about c and
        # Omega = [u]x (I - E' (x) Jinv_k) / L
        Pdd3, g3 = Pdd[:, None, :], grav[None, None, :]
        F_e = self.m_ee[:, None] * Edd + self.m_ep[:, None] * Pdd3 - self.m_e[:, None] * g3
        F_p = self.m_ep[:, None] * Edd + self.m_pp[:, None] * Pdd3 - self.m_p[:, None] * g3
        w += np.sum(Jinv * _dot(E1, F_e)[..., None] + F_p, axis=1)
        L = self.length[None, :, None]
        u = d / L
        d2 = Pdd3 - Edd
        M = self.inertia_t[None, :, None] * cross(u, d2 / L)
        uxM = cross(M, u) / L  # [u]x^T M / L
        w += np.sum(uxM - Jinv * _dot(E1, uxM)[..., None], axis=1)
        tau = Q + np.linalg.solve(np.swapaxes(Jinv, 1, 2), w[..., None])[..., 0]
        return ActuatorTrajectory(t.copy(), list(self.names), alpha, alpha_d, alpha_dd, tau)

    def _check_angles(self, t: np.ndarray, alpha: np.ndarray) -> None:
        bad = (alpha < self.lo - 1e-12) | (alpha > self.hi + 1e-12)
        if bad.any():
            k, i = (int(x[0]) for x in np.nonzero(bad))
            raise TrajectoryError(
                f"actuator joint '{self.names[i]}' would be at {alpha[k, i]:.6g}, outside its "
                f"limits [{self.lo[i]:.6g}, {self.hi[i]:.6g}]",
                sample=k,
                time=float(t[k]),
            )

    def _check_speeds(self, t: np.ndarray, alpha_d: np.ndarray) -> None:
        bad = np.abs(alpha_d) > self.vmax * (1.0 + 1e-9)
        if bad.any():
            k, i = (int(x[0]) for x in np.nonzero(bad))
            raise TrajectoryError(
                f"actuator '{self.names[i]}' would move at {alpha_d[k, i]:.4g}, beyond its "
                f"velocity limit {self.vmax[i]:.4g} (slow the trajectory down)",
                sample=k,
                time=float(t[k]),
            )

    def _check_singular(self, t: np.ndarray, d: np.ndarray, E1: np.ndarray, g: np.ndarray) -> None:
        """Serial (bar along the elbow's path) or parallel (bars dependent) singularities."""
        nd = np.linalg.norm(d, axis=-1)
        scale = nd * np.linalg.norm(E1, axis=-1)
        serial = np.abs(g) <= SINGULAR_TOL * scale
        U = d / nd[..., None]
        # unit rows: det(U) = s1 s2 s3 with s1 in [1, sqrt 3]; a vanishing det is a vanishing
        # smallest singular value (parallel singularity: the bars cannot hold the nacelle)
        detU = unit_dets(U, nd, SINGULAR_TOL)
        parallel = np.abs(detU) <= SINGULAR_TOL
        det = detU * np.prod(np.sign(g), axis=1)
        crossed = np.zeros(t.size, dtype=bool)
        crossed[1:] = det[1:] * det[:-1] < 0.0
        for what, mask in (("serial", serial), ("parallel", parallel), ("crossed", crossed)):
            if mask.any():
                k = int(np.flatnonzero(mask)[0])
                msg = (
                    f"the trajectory crosses a singularity after t = {t[k - 1]:.6g} s "
                    "(det J_inv changes sign)"
                    if what == "crossed"
                    else f"{what} singularity: the arms cannot control the nacelle here"
                )
                raise TrajectoryError(msg, sample=k, time=float(t[k]))


DET_BOUND = 1e-11
"""Bound on ``|u0 . (u1 x u2) - det(U)|`` (LAPACK's, by LU) for unit rows ``u_i``.

Both are within 5e-13 of the exact determinant of the rows as stored: the triple product within
about 21 eps (six products of components of at most 1 in magnitude, a few roundings each), LU
with partial pivoting within about 460 eps (backward error ``3 gamma_3 |L||U|``, growth at most
4 on a 3 x 3, cofactors of unit rows at most 1, the product and ``exp(log)`` of the diagonal);
1e-11 leaves a factor of 20.
"""


def unit_dets(U: np.ndarray, norms: np.ndarray, tol: float) -> np.ndarray:
    """Determinants of 3 x 3 matrices of unit rows that decide ``|det| <= tol`` and signs exactly.

    The triple products ``u0 . (u1 x u2)`` (a few array operations) when every one is farther
    than :data:`DET_BOUND` above ``tol`` in magnitude (then every ``|det| > tol``, each sign is
    that of LAPACK's ``np.linalg.det`` and a product of two of them cannot underflow), else
    ``np.linalg.det(U)`` itself: the same decisions as ``np.linalg.det``, by a rigorous bound.

    Args:
        U: Matrices (N, 3, 3) whose rows are unit vectors (directions divided by their norms).
        norms: The rows' norms before the division (N, 3) [any unit]: rows made of norms out of
            [1e-100, 1e100] (rounded in the division beyond the bound) take LAPACK's path.
        tol: The threshold the caller compares ``|det|`` with (``>= 0``, below 1).

    Returns:
        (N,) values with the signs of ``np.linalg.det(U)`` and on the same side of ``tol`` in
        magnitude.

    """
    u0, u1, u2 = U[:, 0], U[:, 1], U[:, 2]
    x = u1[:, 1] * u2[:, 2] - u1[:, 2] * u2[:, 1]
    y = u1[:, 2] * u2[:, 0] - u1[:, 0] * u2[:, 2]
    z = u1[:, 0] * u2[:, 1] - u1[:, 1] * u2[:, 0]
    T = u0[:, 0] * x + u0[:, 1] * y + u0[:, 2] * z
    sure = np.abs(T) > tol + DET_BOUND  # (NaN: not sure)
    if bool(np.all(sure)) and bool(np.all((norms > 1e-100) & (norms < 1e100))):
        return T
    return np.asarray(np.linalg.det(U))


def delta_inverse_dynamics(
    robot: Robot, task: TaskTrajectory, check_limits: bool = True, payload: float = 0.0
) -> ActuatorTrajectory:
    """Arm angles, rates, accelerations and torques of a library Delta along a platform path.

    The closed-form, vectorised equivalent of ``inverse_dynamics(robot,
    map_task_trajectory(robot, task))`` (see the module docstring).

    Args:
        robot: A library Delta, three arms, ball-jointed bars (payload included if any).
        task: Platform trajectory (positions [m] and their derivatives).
        check_limits: Raise if an arm leaves its angle or speed limits.
        payload: Point mass carried by the nacelle [kg] (as :func:`with_payload`, without the
            copy of the model).

    Returns:
        The actuator trajectory with joint-side torques [N m].

    Raises:
        PkdynError: Not such a Delta.
        TrajectoryError: Out of reach, singular, or outside the arm limits.

    """
    return DeltaDynamics(robot, payload).solve(task, check_limits)
