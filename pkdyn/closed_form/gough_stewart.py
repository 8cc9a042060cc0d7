"""Closed-form inverse geometric model of a Gough-Stewart platform (Merlet's notation).

Leg ``i`` joins the base joint centre ``A_i`` (base frame) to the platform joint centre ``B_i``
(platform frame); for a platform placement ``(p, R)`` its length is
``rho_i = | p + R B_i - A_i |``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

__all__ = ["leg_lengths", "leg_lengths_rpy"]


def leg_lengths(A: np.ndarray, B: np.ndarray, p: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Leg lengths for a batch of platform placements.

    Args:
        A: Base joint centres (6, 3) [m], base frame.
        B: Platform joint centres (6, 3) [m], platform frame.
        p: Platform positions (N, 3) or (3,) [m].
        R: Platform rotations (N, 3, 3) or (3, 3).

    Returns:
        Leg lengths rho (N, 6) [m].

    """
    p = np.atleast_2d(np.asarray(p, dtype=float))
    R = np.asarray(R, dtype=float)
    if R.ndim == 2:
        R = np.broadcast_to(R, (p.shape[0], 3, 3))
    legs = p[:, None, :] + np.einsum("nij,kj->nki", R, B) - A[None, :, :]
    return np.linalg.norm(legs, axis=2)


def leg_lengths_rpy(A: np.ndarray, B: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """Leg lengths for poses given as ``[x, y, z, roll, pitch, yaw]`` rows.

    Args:
        A: Base joint centres (6, 3) [m].
        B: Platform joint centres (6, 3) [m].
        poses: (N, 6) positions [m] and roll, pitch, yaw [rad] (R = Rz Ry Rx).

    Returns:
        Leg lengths (N, 6) [m].

    """
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    R = np.stack([pin.rpy.rpyToMatrix(r) for r in poses[:, 3:]])
    return leg_lengths(A, B, poses[:, :3], R)
