"""Pasqui's closed-form inverse geometric model of the planar 3-RRR (seed 001, "3R Plan").

Notation of the seed: chain ``i`` (i = 1, 2, 3) has its actuated revolute at
``O_1^i = (a_i, b_i)``, its passive elbow at ``O_2^i = O_1^i + l1 (cos q_1^i, sin q_1^i)`` and
its platform revolute at ``O_3^i = O_2^i + l2 (cos(q_1^i + q_2^i), sin(q_1^i + q_2^i))``; the
platform point is ``P = O_3^i + h (cos psi_i, sin psi_i)`` with ``psi_i = q_1^i + q_2^i + q_3^i``.
All angles are absolute (from the base x axis) or relative as in the seed.

Generalisation used by :mod:`pkdyn.library.planar_3rrr`: the platform pose is ``(x, y, phi)``
and the platform joints are ``B_i = P + h (cos(phi + gamma_i), sin(phi + gamma_i))``
(``gamma_i``: platform attachment angles), so ``O_3^i = B_i`` and
``psi_i = phi + gamma_i + pi`` (direction from ``O_3^i`` to ``P``).

Inverse geometric model, per chain (seed)::

    K1 = x - (a_i + h cos psi_i)          (= B_ix - a_i)
    K2 = y - (b_i + h sin psi_i)          (= B_iy - b_i)
    K1 cos q1 + K2 sin q1 = K3 = (K1^2 + K2^2 + l1^2 - l2^2) / (2 l1)
    T^2 (K1 + K3) - 2 K2 T + K3 - K1 = 0,  T = tan(q1 / 2)
    q1 = 2 atan((K2 +/- sqrt(K1^2 + K2^2 - K3^2)) / (K1 + K3)),  if K1^2 + K2^2 >= K3^2

(The seed prints the root as ``K2 (1 +/- sqrt(K3^2 - K1^2)) / (K1 + K3)``, a transcription
slip: the roots of its own quadratic are the ones above.)

Elbow (working) mode: ``elbow = +1`` means ``sin q_2^i > 0`` (link 2 turns counter-clockwise
from link 1), which is the ``-`` sign of the root; ``elbow = -1`` is the ``+`` sign.

All functions take ``(N, 3)`` poses ``(x, y, phi)`` [m, m, rad] (or one ``(3,)`` pose) and
return a validity mask instead of raising; invalid rows are NaN. Angles are wrapped to
``(-pi, pi]``.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = [
    "Planar3RRRGeometry",
    "platform_joints",
    "inverse",
    "chain_angles",
    "elbow_points",
]


class Planar3RRRGeometry(Protocol):
    """Anything with the 3-RRR lengths [m], base points [m] and attachment angles [rad]."""

    @property
    def l1(self) -> float:
        """Proximal (actuated) link length [m]."""
        ...

    @property
    def l2(self) -> float:
        """Distal link length [m]."""
        ...

    @property
    def h(self) -> float:
        """Platform centre to platform joint [m]."""
        ...

    @property
    def base_xy(self) -> np.ndarray:
        """Base points ``(a_i, b_i)``, shape (3, 2) [m]."""
        ...

    @property
    def platform_angles(self) -> tuple[float, ...]:
        """Platform attachment angles ``gamma_i`` [rad]."""
        ...


def _wrap(a: np.ndarray) -> np.ndarray:
    return np.pi - (np.pi - a) % (2.0 * np.pi)


def _poses(pose: np.ndarray) -> np.ndarray:
    arr = np.atleast_2d(np.asarray(pose, dtype=float))
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InvalidInputError("pose", f"expected shape (N, 3) (x, y, phi), got {arr.shape}")
    return arr


def platform_joints(g: Planar3RRRGeometry, pose: np.ndarray) -> np.ndarray:
    """Platform joint centres ``B_i = O_3^i`` of poses.

    Args:
        g: Geometry.
        pose: Platform poses ``(x, y, phi)``, shape (N, 3) or (3,) [m, m, rad].

    Returns:
        ``B`` of shape (N, 3, 2) [m]: ``B[n, i]`` is chain ``i``'s platform joint.

    """
    X = _poses(pose)
    ang = X[:, 2:3] + np.asarray(g.platform_angles, dtype=float)
    return np.stack([X[:, :1] + g.h * np.cos(ang), X[:, 1:2] + g.h * np.sin(ang)], axis=-1)


def inverse(
    g: Planar3RRRGeometry, pose: np.ndarray, elbow: int | np.ndarray = 1
) -> tuple[np.ndarray, np.ndarray]:
    """Inverse geometric model: actuated angles ``q_1^i`` from platform poses (Pasqui).

    Args:
        g: Geometry.
        pose: Platform poses ``(x, y, phi)``, shape (N, 3) or (3,) [m, m, rad].
        elbow: ``+1`` (``sin q_2^i > 0``) or ``-1`` per chain: a scalar or shape (3,).

    Returns:
        ``(qa, valid)``: actuator coordinates, the angles ``q_1^i`` (N, 3) [rad] in
        ``(-pi, pi]`` (NaN where a chain cannot reach its platform joint), and mask (N,) of the
        poses every chain reaches.

    """
    B = platform_joints(g, pose)
    base = np.asarray(g.base_xy, dtype=float)
    K1 = B[..., 0] - base[:, 0]
    K2 = B[..., 1] - base[:, 1]
    K3 = (K1**2 + K2**2 + g.l1**2 - g.l2**2) / (2.0 * g.l1)
    disc = K1**2 + K2**2 - K3**2
    ok = disc >= 0.0
    s = -np.broadcast_to(np.asarray(elbow, dtype=float), (3,))
    root = np.sqrt(np.where(ok, disc, 0.0))
    # tan(q1/2) = (K2 + s root) / (K1 + K3) = (K3 - K1) / (K2 - s root) (product of the roots);
    # use the form whose numerator and denominator are not both (near) zero.
    n1, d1 = K2 + s * root, K1 + K3
    n2, d2 = K3 - K1, K2 - s * root
    first = np.abs(n1) + np.abs(d1) >= np.abs(n2) + np.abs(d2)
    q1 = 2.0 * np.where(first, np.arctan2(n1, d1), np.arctan2(n2, d2))
    q1 = _wrap(q1)
    q1[~ok] = np.nan
    return q1, ok.all(axis=1)


def elbow_points(g: Planar3RRRGeometry, qa: np.ndarray) -> np.ndarray:
    """Elbow centres ``O_2^i = (a_i + l1 cos q_1^i, b_i + l1 sin q_1^i)``.

    Args:
        g: Geometry.
        qa: Actuator coordinates, the angles ``q_1^i`` (N, 3) or (3,) [rad].

    Returns:
        Elbow points, shape (N, 3, 2) [m].

    """
    q = np.atleast_2d(np.asarray(qa, dtype=float))
    base = np.asarray(g.base_xy, dtype=float)
    return np.stack([base[:, 0] + g.l1 * np.cos(q), base[:, 1] + g.l1 * np.sin(q)], axis=-1)


def chain_angles(
    g: Planar3RRRGeometry, pose: np.ndarray, elbow: int | np.ndarray = 1
) -> tuple[np.ndarray, np.ndarray]:
    """All joint angles ``(q_1^i, q_2^i, q_3^i)`` of the three chains (seed notation).

    ``q_2^i`` is link 2's angle relative to link 1 and ``q_3^i = psi_i - q_1^i - q_2^i`` the
    platform's relative to link 2, with ``psi_i = phi + gamma_i + pi``.

    Args:
        g: Geometry.
        pose: Platform poses ``(x, y, phi)``, shape (N, 3) or (3,) [m, m, rad].
        elbow: ``+1`` or ``-1`` per chain (scalar or (3,)), see :func:`inverse`.

    Returns:
        ``(q, valid)``: angles (N, 3, 3) [rad] with ``q[n, i] = (q_1^i, q_2^i, q_3^i)`` (NaN
        where unreachable) and mask (N,).

    """
    X = _poses(pose)
    q1, ok = inverse(g, X, elbow)
    B = platform_joints(g, X)
    O2 = elbow_points(g, q1)
    t2 = np.arctan2(B[..., 1] - O2[..., 1], B[..., 0] - O2[..., 0])
    psi = X[:, 2:3] + np.asarray(g.platform_angles, dtype=float) + np.pi
    q2 = _wrap(t2 - q1)
    q3 = _wrap(psi - t2)
    return np.stack([q1, q2, q3], axis=-1), ok
