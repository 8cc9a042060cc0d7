"""Reciprocal-screw kinematic models of the library robots (seed 001, Pasqui).

For each chain ``i``, a screw ``$_perp`` reciprocal to the twists of the chain's passive joints
(``$_perp . $_k = 0``) eliminates them from the platform twist ``V = sum_j q_dot_j $_j``:
``$_perp . V = qa_dot $_perp . $_a``. Stacking one such relation per actuator gives
``A x_dot = B qa_dot`` with explicit, vectorised ``A`` (rows: the reciprocal screws, i.e. the
wrenches the chains transmit to the platform) and diagonal ``B`` (``$_perp . $_a``).

Conventions are those of :mod:`pkdyn.analysis.kinematics`: ``x_dot`` lists the robot's task
components in the order ``(x, y, z, rx, ry, rz)``, linear velocity of the platform frame origin in
world axes, angular velocity in the platform frame. ``A`` and ``B`` here keep the seed's
normalisation (lengths in m); :func:`normalise` maps them to the orthonormal form of
:func:`pkdyn.analysis.kinematics.kinematic_models` (same ``J``, same singular values up to
round-off).

- Planar 3-RRR (seed 001, "3R Plan"): ``$_perp^i`` is the force along the distal link
  ``O_2^i O_3^i`` (length ``l2``), reciprocal to the two passive revolutes at ``O_2^i`` and
  ``O_3^i``. In the seed's order ``(phi_dot, x_dot, y_dot)`` its row is
  ``[h l2 sin q_3^i, l2 cos(q_1^i + q_2^i), l2 sin(q_1^i + q_2^i)]`` and
  ``B_ii = $_perp . $_1 = l1 l2 sin q_2^i`` (the seed's printed matrices have index slips; these
  are the values its derivation gives). Reordered here to the task order ``(x, y, rz)``.
- Gough-Stewart (Merlet): the force along leg ``i`` (unit vector ``u_i`` from ``A_i`` to ``B_i``)
  is reciprocal to the universal and spherical joints; ``rho_dot_i = u_i . v +
  ((B_i - O) x u_i) . omega_world``, so ``A`` rows are ``[u_i, R^T ((B_i - O) x u_i)]`` and
  ``B = I``.
- Delta (Clavel's reduced model, nacelle reduced to its centre ``P``): the bar direction
  ``P - C'_i`` (length ``lb``) is reciprocal to the ball joints; differentiating
  ``|P - C'_i|^2 = lb^2`` gives rows ``A_i = (P - C'_i)^T`` and
  ``B_ii = (P - C'_i) . dC'_i/dalpha_i``. (The reduced model does not see the nacelle's
  orientation, hence not Clavel's family c) constraint singularity.)
- Five-bar: ``A_j = (E - C_j)^T``, ``B_jj = (E - C_j) . dC_j/dtheta_j``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from pkdyn.closed_form import delta as delta_cf
from pkdyn.closed_form import five_bar as five_bar_cf
from pkdyn.closed_form import planar_3rrr as rrr_cf
from pkdyn.exceptions import InvalidInputError
from pkdyn.library import delta, five_bar, gough_stewart, planar_3rrr
from pkdyn.model.pose import as_finite
from pkdyn.model.robot import Robot

__all__ = [
    "normalise",
    "delta_AB",
    "planar_3rrr_AB",
    "planar_3rrr_chain_angles",
    "gough_stewart_AB",
    "five_bar_AB",
    "reciprocal_screws",
    "RECIPROCAL_SCREWS",
]


def normalise(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal form of ``A x_dot = B qa_dot``: ``[B, -A]`` with orthonormal rows.

    Args:
        A: Parallel matrices (..., m, m).
        B: Serial matrices (..., m, n_a).

    Returns:
        ``(A_n, B_n)`` spanning the same relations, normalised as in
        :func:`pkdyn.analysis.kinematics.kinematic_models` (unique up to a left orthogonal factor).

    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    m, n_a = A.shape[-1], B.shape[-1]
    R = np.concatenate([B, -A], axis=-1)
    bad = ~np.isfinite(R).all(axis=(-2, -1))
    R = np.where(bad[..., None, None], 0.0, R)
    _, _, Vt = np.linalg.svd(R, full_matrices=False)
    rows = Vt[..., :m, :]
    rows = np.where(bad[..., None, None], np.nan, rows)
    return -rows[..., n_a:], rows[..., :n_a]


def delta_AB(
    g: delta_cf.DeltaGeometry, P: np.ndarray, qa: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Delta (Clavel's reduced model): ``A`` (N, 3, 3) and diagonal ``B`` (N, 3, 3).

    Args:
        g: Geometry (ra, rb, la, lb) [m].
        P: Nacelle centres (N, 3) or (3,) [m].
        qa: Actuator coordinates, the arm angles ``alpha`` (N, 3) or (3,) [rad].

    Returns:
        ``A`` rows ``(P - C'_i)`` [m] and ``B_ii = (P - C'_i) . dC'_i/dalpha_i`` [m^2/rad].

    """
    P = np.atleast_2d(np.asarray(P, dtype=float))
    alpha = np.atleast_2d(np.asarray(qa, dtype=float))
    C = delta_cf.elbow_points(g, alpha)
    d = P[:, None, :] - C
    dC = np.stack(
        [
            -g.la * np.sin(alpha) * np.cos(delta_cf.THETA),
            -g.la * np.sin(alpha) * np.sin(delta_cf.THETA),
            -g.la * np.cos(alpha),
        ],
        axis=-1,
    )
    B = np.einsum("nij,nij->ni", d, dC)
    return d, B[..., None] * np.eye(3)


def planar_3rrr_chain_angles(
    g: rrr_cf.Planar3RRRGeometry, pose: np.ndarray, qa: np.ndarray
) -> np.ndarray:
    """Seed angles ``(q_1^i, q_2^i, q_3^i)`` of an assembly given its pose and actuated angles.

    Unlike :func:`pkdyn.closed_form.planar_3rrr.chain_angles` this needs no working mode: the
    elbows follow from ``q_1^i``.

    Args:
        g: Geometry.
        pose: Platform poses ``(x, y, phi)`` (N, 3) or (3,) [m, m, rad].
        qa: Actuator coordinates, the angles ``q_1^i`` (N, 3) or (3,) [rad].

    Returns:
        Angles (N, 3, 3) [rad]: ``[n, i] = (q_1^i, q_2^i, q_3^i)``.

    """
    X = np.atleast_2d(np.asarray(pose, dtype=float))
    q1 = np.atleast_2d(np.asarray(qa, dtype=float))
    B = rrr_cf.platform_joints(g, X)
    O2 = rrr_cf.elbow_points(g, q1)
    t2 = np.arctan2(B[..., 1] - O2[..., 1], B[..., 0] - O2[..., 0])
    psi = X[:, 2:3] + np.asarray(g.platform_angles, dtype=float) + np.pi
    return np.stack([q1, t2 - q1, psi - t2], axis=-1)


def planar_3rrr_AB(
    g: rrr_cf.Planar3RRRGeometry, angles: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Planar 3-RRR (seed 001): ``A`` (N, 3, 3) in task order ``(x, y, rz)``, diagonal ``B``.

    Args:
        g: Geometry (``l1``, ``l2``, ``h``).
        angles: Seed angles (N, 3, 3) or (3, 3): ``[n, i] = (q_1^i, q_2^i, q_3^i)`` [rad].

    Returns:
        ``A`` rows ``[l2 cos(q_1 + q_2), l2 sin(q_1 + q_2), h l2 sin q_3]`` [m, m, m^2] and
        ``B = diag(l1 l2 sin q_2^i)`` [m^2].

    """
    q = np.asarray(angles, dtype=float)
    if q.ndim == 2:
        q = q[None]
    q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2]
    a = q1 + q2
    A = np.stack([g.l2 * np.cos(a), g.l2 * np.sin(a), g.h * g.l2 * np.sin(q3)], axis=-1)
    B = (g.l1 * g.l2 * np.sin(q2))[..., None] * np.eye(3)
    return A, B


def gough_stewart_AB(
    A_pts: np.ndarray, B_world: np.ndarray, origin: np.ndarray, R: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Gough-Stewart: rows ``[u_i, R^T ((B_i - O) x u_i)]`` (N, 6, 6) and ``B = I``.

    Args:
        A_pts: Base joint centres (6, 3) [m], world.
        B_world: Platform joint centres in world coordinates (N, 6, 3) or (6, 3) [m].
        origin: Platform frame origins ``O`` (N, 3) or (3,) [m].
        R: Platform frame rotations (N, 3, 3) or (3, 3).

    Returns:
        ``(A, B)`` with ``B`` the identity (N, 6, 6).

    """
    Bw = np.asarray(B_world, dtype=float)
    Bw = Bw[None] if Bw.ndim == 2 else Bw
    O = np.atleast_2d(np.asarray(origin, dtype=float))
    Rm = np.asarray(R, dtype=float)
    Rm = np.broadcast_to(Rm, (Bw.shape[0], 3, 3)) if Rm.ndim == 2 else Rm
    leg = Bw - np.asarray(A_pts, dtype=float)[None]
    u = leg / np.linalg.norm(leg, axis=-1, keepdims=True)
    mom = np.cross(Bw - O[:, None, :], u)
    ang = np.einsum("nji,nkj->nki", Rm, mom)  # R^T m_k
    A = np.concatenate([u, ang], axis=-1)
    return A, np.broadcast_to(np.eye(6), A.shape).copy()


def five_bar_AB(p: five_bar.Params, E: np.ndarray, qa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Five-bar: rows ``(E - C_j)^T`` (N, 2, 2) and ``B_jj = (E - C_j) . dC_j/dtheta_j``.

    Args:
        p: Five-bar parameters (``l1``, ``base_xy``).
        E: End-effector points (N, 2) or (2,) [m].
        qa: Actuator coordinates, the angles ``theta`` (N, 2) or (2,) [rad].

    Returns:
        ``(A, B)`` [m, m^2].

    """
    Ep = np.atleast_2d(np.asarray(E, dtype=float))
    t = np.atleast_2d(np.asarray(qa, dtype=float))
    C = five_bar_cf.elbow_points(p, t)
    d = Ep[:, None, :] - C
    dC = p.l1 * np.stack([-np.sin(t), np.cos(t)], axis=-1)
    return d, np.einsum("nij,nij->ni", d, dC)[..., None] * np.eye(2)


def _delta_screws(robot: Robot, q: np.ndarray, M: pin.SE3) -> tuple[np.ndarray, np.ndarray] | None:
    prm: delta.Params = robot.params
    if prm.arms != 3:
        return None
    return delta_AB(prm, M.translation, q[robot.actuated_q])


def _planar_3rrr_screws(
    robot: Robot, q: np.ndarray, M: pin.SE3
) -> tuple[np.ndarray, np.ndarray] | None:
    prm: planar_3rrr.Params = robot.params
    phi = float(np.arctan2(M.rotation[1, 0], M.rotation[0, 0]))
    pose = np.array([M.translation[0], M.translation[1], phi])
    return planar_3rrr_AB(prm, planar_3rrr_chain_angles(prm, pose, q[robot.actuated_q]))


def _gough_stewart_screws(
    robot: Robot, q: np.ndarray, M: pin.SE3
) -> tuple[np.ndarray, np.ndarray] | None:
    prm: gough_stewart.Params = robot.params
    data = robot.data
    pin.forwardKinematics(robot.model, data, q)
    Bw = np.array(
        [
            data.oMi[cm.joint2_id].act(cm.joint2_placement.translation)
            for cm in robot.constraint_models
        ]
    )
    return gough_stewart_AB(prm.a, Bw, M.translation, M.rotation)


def _five_bar_screws(
    robot: Robot, q: np.ndarray, M: pin.SE3
) -> tuple[np.ndarray, np.ndarray] | None:
    prm: five_bar.Params = robot.params
    return five_bar_AB(prm, M.translation[:2], q[robot.actuated_q])


ScrewModel = Callable[[Robot, np.ndarray, pin.SE3], "tuple[np.ndarray, np.ndarray] | None"]
"""``(robot, q, platform placement) -> (A, B)`` with a leading axis of 1, or ``None`` when these
parameters of the family have no reciprocal-screw model."""

RECIPROCAL_SCREWS: dict[str, ScrewModel] = {
    "delta": _delta_screws,
    "planar_3rrr": _planar_3rrr_screws,
    "gough_stewart": _gough_stewart_screws,
    "five_bar": _five_bar_screws,
}
"""Reciprocal-screw models by family name (:attr:`pkdyn.Robot.family`)."""


def reciprocal_screws(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pasqui's ``A`` and ``B`` of a library robot at configuration ``q`` (seed normalisation).

    Args:
        robot: A library robot of a family in :data:`RECIPROCAL_SCREWS` (``delta`` with three
            arms, ``planar_3rrr``, ``gough_stewart``, ``five_bar``).
        q: Assembled configuration (nq,).

    Returns:
        ``(A, B)``: (m, m) and (m, n_a), task order of the robot.

    Raises:
        InvalidInputError: Not one of these library robots.

    """
    qq = as_finite("q", q, robot.nq)
    model = RECIPROCAL_SCREWS.get(robot.family or "")
    AB = None if model is None else model(robot, qq, robot.platform_placement(qq))
    if AB is None:
        raise InvalidInputError(
            "robot",
            f"no reciprocal-screw model for {robot.name}; use "
            "pkdyn.analysis.kinematics.kinematic_models",
        )
    A, B = AB
    return A[0], B[0]
