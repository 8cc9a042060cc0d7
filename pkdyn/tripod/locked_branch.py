"""The walker's swinging branch with its locks engaged: a foot-to-nacelle chain of two actuators.

With the walker's locks (:func:`pkdyn.tripod.modes.be_mode`: ``q1, q2, q3, q6`` of the swinging
branch ``i``) the foot is rigid to rod ``L`` and the edge ``P_L P_R`` rigid to the nacelle, so the
swinging branch is one rigid chain from its foot to the nacelle whose only mobilities are its
triangle's, set by its two actuator lengths ``r = (q_Li, q_Ri)``. With ``F`` the foot frame
``R_A``, ``C`` the frame of rod ``L`` (origin ``A``, x along ``P_L A``, z normal to the triangle)
in ``F`` and ``D`` the edge frame (origin ``P_L``, x along ``P_L P_R``, same z) in the nacelle
frame, both frozen when the locks engage::

    X = F  C  Tx(-q_L)  Rz(-beta)  D^-1,    cos(beta) = (q_L^2 + e^2 - q_R^2) / (2 e q_L)

(``e = |P_L P_R|``, ``beta`` the triangle's angle at ``P_L``): the nacelle pose ``X`` follows
from the foot and ``r`` in closed form, vectorised over samples. The tests compare it with the
nacelle of the joint trajectories the constraint solver maps (1e-9).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.optimize import least_squares

from pkdyn.closed_form import tripod as tripod_cf
from pkdyn.dynamics.trajectory import TaskTrajectory

__all__ = ["LockedBranch", "foot_frames"]

_TURN = pin.rpy.rpyToMatrix(0.0, 0.0, np.pi)
"""The foot link frame is ``R_A`` turned half a turn about ``w_a``."""


def _se3_arrays(M: pin.SE3) -> tuple[np.ndarray, np.ndarray]:
    return np.array(M.rotation), np.array(M.translation)


@dataclass(frozen=True)
class LockedBranch:
    """The swinging branch with its locks engaged: foot-to-nacelle chain of two actuators.

    Attributes:
        branch: Branch number ``i``.
        edge: ``e = |P_L P_R|`` [m].
        C: Frame of rod ``L`` in the foot frame ``R_A`` (origin ``A``).
        D: Edge frame in the nacelle frame (origin ``P_L``).
        r0: Actuator lengths ``(q_L, q_R)`` when the locks engaged [m].

    """

    branch: int
    edge: float
    C: pin.SE3
    D: pin.SE3
    r0: np.ndarray

    @classmethod
    def engage(cls, p: Any, nacelle: pin.SE3, foot: pin.SE3, branch: int) -> LockedBranch:
        """Freeze the branch where it stands: nacelle at ``nacelle``, foot frame at ``foot``.

        Args:
            p: Walker parameters.
            nacelle: Nacelle placement ``R_P`` in ``R_B``.
            foot: Foot frame ``R_A`` of the branch in ``R_B``.
            branch: Branch number.

        Returns:
            The locked branch.

        """
        P_L, P_R = (nacelle.act(P) for P in tripod_cf.attachments(p, branch - 1))
        A = np.array(foot.translation)
        u = tripod_cf.unit_vector(P_R - P_L)
        y = tripod_cf.perpendicular(A - P_L, u)
        z = np.cross(u, y)
        e = tripod_cf.unit_vector(A - P_L)
        edge = pin.SE3(np.column_stack([u, y, z]), P_L)
        rod = pin.SE3(np.column_stack([e, np.cross(z, e), z]), A)
        r0 = np.array([np.linalg.norm(A - P_L), np.linalg.norm(A - P_R)])
        return cls(
            branch,
            float(np.linalg.norm(P_R - P_L)),
            foot.inverse() * rod,
            nacelle.inverse() * edge,
            r0,
        )

    def nacelle(
        self, R_F: np.ndarray, p_F: np.ndarray, qL: np.ndarray, qR: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Nacelle placements from foot frames and the branch's actuator lengths.

        Args:
            R_F: Foot frame orientations (N, 3, 3).
            p_F: Foot frame origins ``A`` (N, 3) [m].
            qL: Lengths ``q_L`` (N,) [m].
            qR: Lengths ``q_R`` (N,) [m].

        Returns:
            ``(R, P_O)``: nacelle orientations (N, 3, 3) and origins (N, 3) [m].

        """
        R_C, p_C = _se3_arrays(self.C)
        Dinv = self.D.inverse()
        R_Di, p_Di = _se3_arrays(Dinv)
        e = self.edge
        cb = np.clip((qL**2 + e**2 - qR**2) / (2.0 * e * qL), -1.0, 1.0)
        sb = np.sqrt(1.0 - cb**2)
        Rz = np.zeros((qL.size, 3, 3))  # Rz(-beta)
        Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = cb, sb, -sb, cb, 1.0
        R_rod = R_F @ R_C
        p_cyl = p_F + R_F @ p_C - qL[:, None] * R_rod[:, :, 0]
        R_E = R_rod @ Rz
        return R_E @ R_Di, p_cyl + R_E @ p_Di

    def lengths_near(
        self, p: Any, foot: pin.SE3, target: pin.SE3, start: np.ndarray | None = None
    ) -> np.ndarray:
        """Lengths ``(q_L, q_R)`` that put the nacelle nearest ``target`` with the foot at ``foot``.

        Least squares on the nacelle's position error and ``r_p`` times its rotation error,
        within the strokes.

        Args:
            p: Walker parameters.
            foot: Foot frame ``R_A``.
            target: Wanted nacelle placement.
            start: Initial lengths (default: those when the locks engaged).

        Returns:
            The lengths (2,) [m].

        """
        R_F, p_F = _se3_arrays(foot)

        def residual(r: np.ndarray) -> np.ndarray:
            R, P = self.nacelle(R_F[None], p_F[None], r[:1], r[1:])
            rot = pin.log3(target.rotation.T @ R[0])
            return np.concatenate([P[0] - target.translation, p.r_p * rot])

        x0 = self.r0 if start is None else start
        lo, hi = p.stroke_min, p.stroke_max
        sol = least_squares(residual, np.clip(x0, lo, hi), bounds=(lo, hi), xtol=1e-12)
        return np.asarray(sol.x, dtype=float)


def foot_frames(task: TaskTrajectory) -> tuple[np.ndarray, np.ndarray]:
    """Foot frames ``R_A`` along a swing (the task of the foot *link* frame, turned back).

    Args:
        task: The swinging foot's task (:func:`pkdyn.tripod.scenario.swing_task`).

    Returns:
        Orientations (N, 3, 3) and origins (N, 3) [m].

    """
    R = np.array([pin.rpy.rpyToMatrix(x[3:]) @ _TURN for x in task.pose])
    return R, np.array(task.pose[:, :3])
