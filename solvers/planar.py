"""Planar motion: the world-fixed plane in which a set of joints moves the bodies they carry.

The velocity of a body is ``sum_k c_k v_k`` over the world twists ``c_k`` (columns of the world
joint Jacobian ``data.J``, at the world origin: linear velocity of the origin, then angular
velocity) of the coordinates supporting it. The motion is planar with normal ``n`` when every
such twist is a rotation about an axis parallel to ``n`` or a translation normal to it:
``w x n = 0`` and ``v . n = 0``. The property holds at every configuration once it holds at one:
a rotation about ``n`` keeps the twists of the joints it carries planar about ``n``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PLANAR_TOL", "plane_normal"]

PLANAR_TOL = 1e-10
"""Relative tolerance of a planar twist: ``|w x n|`` and ``|v . n|`` over the twist's norm."""


def plane_normal(columns: np.ndarray, tol: float = PLANAR_TOL) -> np.ndarray | None:
    """Unit normal of the plane of motion of world twist columns, or ``None`` if not planar.

    Args:
        columns: World twists (6, m) (``data.J[:, cols]`` after
            ``pin.computeJointJacobians``): linear velocity of the world origin, angular
            velocity.
        tol: Relative tolerance (see :data:`PLANAR_TOL`).

    Returns:
        ``n`` (3,), or ``None`` when a twist is not planar, no twist rotates (a pure
        translation mechanism: no normal is singled out) or there are no twists.

    """
    if columns.shape[1] == 0:
        return None
    ang = columns[3:]
    norms = np.linalg.norm(columns, axis=0)
    big = np.linalg.norm(ang, axis=0) > tol * np.maximum(norms, 1e-300)
    if not big.any():
        return None
    k = int(np.argmax(big))
    n = ang[:, k] / np.linalg.norm(ang[:, k])
    a = ang.T  # (np.cross's products and differences, without its overhead)
    cross = np.stack(
        [
            a[:, 1] * n[2] - a[:, 2] * n[1],
            a[:, 2] * n[0] - a[:, 0] * n[2],
            a[:, 0] * n[1] - a[:, 1] * n[0],
        ],
        axis=1,
    )
    off_axis = np.linalg.norm(cross, axis=1)
    off_plane = np.abs(n @ columns[:3])
    if np.any(off_axis > tol * norms) or np.any(off_plane > tol * norms):
        return None
    return n
