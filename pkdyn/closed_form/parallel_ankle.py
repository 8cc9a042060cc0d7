r"""Closed forms of the humanoid-style parallel ankle (:mod:`pkdyn.library.parallel_ankle`).

Shank frame: ankle centre at the origin, ``x`` forward, ``z`` up. The foot turns by
``R = R_y(pitch) R_x(roll)`` (pitch about the shank's y axis, then roll about the foot's x
axis). Motor ``i`` (``i = 0`` left, ``y > 0``; ``i = 1`` right) turns about the y axis through
``M_i = (x_m, +-d, h)``; its crank end is ``C_i = M_i + c (-cos theta_i, 0, sin theta_i)``
(``theta_i = 0``: crank pointing backwards, positive ``theta_i`` lifts the crank end). A rod of
length ``L`` joins ``C_i`` to the foot point ``P_i = R p_i``, ``p_i = (x_p, +-e, z_p)`` in the
foot frame. Closure: ``|C_i - P_i| = L``.

- :func:`inverse` (vectorised): with ``D = M_i - P_i``, the closure is
  ``a cos theta + b sin theta = k`` with ``a = -2 c D_x``, ``b = 2 c D_z``,
  ``k = L^2 - |D|^2 - c^2``, hence ``theta = atan2(b, a) - acos(k / sqrt(a^2 + b^2))`` (the branch
  with the crank end below the motor axis side that contains ``theta = 0`` for the default
  geometry).
- :func:`forward` (vectorised Newton on the two rod-length equations).
- :func:`jacobian`: ``d (pitch, roll) / d theta`` by implicit differentiation of the closures.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["crank_points", "foot_points", "forward", "inverse", "jacobian"]


def _R(pitch: np.ndarray, roll: np.ndarray) -> np.ndarray:
    """``R_y(pitch) R_x(roll)`` (N, 3, 3)."""
    cp, sp, cr, sr = np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    z, o = np.zeros_like(pitch), np.ones_like(pitch)
    Ry = np.stack(
        [np.stack([cp, z, sp], -1), np.stack([z, o, z], -1), np.stack([-sp, z, cp], -1)], -2
    )
    Rx = np.stack(
        [np.stack([o, z, z], -1), np.stack([z, cr, -sr], -1), np.stack([z, sr, cr], -1)], -2
    )
    return Ry @ Rx


def _motors(p: Any) -> np.ndarray:
    return np.array([[p.x_motor, p.d, p.h], [p.x_motor, -p.d, p.h]])


def _foot_local(p: Any) -> np.ndarray:
    return np.array([[p.x_foot, p.e, p.z_foot], [p.x_foot, -p.e, p.z_foot]])


def foot_points(p: Any, angles: np.ndarray) -> np.ndarray:
    """Rod attachment points on the foot in the shank frame.

    Args:
        p: Parameters (:class:`pkdyn.library.parallel_ankle.Params`).
        angles: ``(pitch, roll)`` (N, 2) or (2,) [rad].

    Returns:
        Points (N, 2, 3) [m].

    """
    a = np.atleast_2d(np.asarray(angles, dtype=float))
    R = _R(a[:, 0], a[:, 1])
    return np.einsum("nij,kj->nki", R, _foot_local(p))


def crank_points(p: Any, theta: np.ndarray) -> np.ndarray:
    """Crank ends in the shank frame.

    Args:
        p: Parameters.
        theta: Motor angles (N, 2) or (2,) [rad].

    Returns:
        Points (N, 2, 3) [m].

    """
    t = np.atleast_2d(np.asarray(theta, dtype=float))
    u = np.stack([-np.cos(t), np.zeros_like(t), np.sin(t)], -1)
    return _motors(p)[None] + p.crank * u


def inverse(p: Any, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Motor angles from ankle pitch and roll.

    Args:
        p: Parameters.
        angles: ``(pitch, roll)`` (N, 2) or (2,) [rad].

    Returns:
        ``(theta, ok)``: motor angles (N, 2) [rad] and reachability (N,) (NaN where not).

    """
    P = foot_points(p, angles)
    D = _motors(p)[None] - P
    a = -2.0 * p.crank * D[..., 0]
    b = 2.0 * p.crank * D[..., 2]
    k = p.rod**2 - np.sum(D * D, axis=-1) - p.crank**2
    r = np.hypot(a, b)
    c = k / r
    ok = np.all(np.abs(c) <= 1.0, axis=-1)
    with np.errstate(invalid="ignore"):
        theta = np.arctan2(b, a) - np.arccos(c)
    theta = (theta + np.pi) % (2.0 * np.pi) - np.pi
    theta[~ok] = np.nan
    return theta, ok


def _residual_and_jacobians(
    p: Any, angles: np.ndarray, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rod-length residuals (N, 2), d/d(pitch, roll) (N, 2, 2), d/dtheta (N, 2) (diagonal)."""
    pitch, roll = angles[:, 0], angles[:, 1]
    R = _R(pitch, roll)
    P = np.einsum("nij,kj->nki", R, _foot_local(p))
    C = crank_points(p, theta)
    E = C - P
    f = np.sum(E * E, axis=-1) - p.rod**2
    ey = np.array([0.0, 1.0, 0.0])
    cp, sp = np.cos(pitch), np.sin(pitch)
    roll_axis = np.stack([cp, np.zeros_like(cp), -sp], -1)  # R_y(pitch) e_x
    dP_pitch = np.cross(ey[None, None], P)
    dP_roll = np.cross(roll_axis[:, None], P)
    Fx = np.stack([-2.0 * np.sum(E * dP_pitch, -1), -2.0 * np.sum(E * dP_roll, -1)], -1)
    t = np.atleast_2d(theta)
    dC = p.crank * np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], -1)
    Ft = 2.0 * np.sum(E * dC, -1)
    return f, Fx, Ft


def forward(
    p: Any, theta: np.ndarray, guess: np.ndarray | None = None, iterations: int = 30
) -> tuple[np.ndarray, np.ndarray]:
    """Ankle pitch and roll from motor angles (Newton, vectorised).

    Args:
        p: Parameters.
        theta: Motor angles (N, 2) or (2,) [rad].
        guess: Starting ``(pitch, roll)`` (N, 2) (default zeros).
        iterations: Newton iterations.

    Returns:
        ``(angles, ok)``: (N, 2) [rad] and convergence (N,) (rod lengths to 1e-12 m).

    """
    t = np.atleast_2d(np.asarray(theta, dtype=float))
    x = np.zeros_like(t) if guess is None else np.array(np.atleast_2d(guess), dtype=float)
    for _ in range(iterations):
        f, Fx, _ = _residual_and_jacobians(p, x, t)
        det = Fx[:, 0, 0] * Fx[:, 1, 1] - Fx[:, 0, 1] * Fx[:, 1, 0]
        safe = np.abs(det) > 1e-300
        dx0 = np.where(
            safe, (Fx[:, 1, 1] * f[:, 0] - Fx[:, 0, 1] * f[:, 1]) / np.where(safe, det, 1), 0
        )
        dx1 = np.where(
            safe, (-Fx[:, 1, 0] * f[:, 0] + Fx[:, 0, 0] * f[:, 1]) / np.where(safe, det, 1), 0
        )
        x = x - np.stack([dx0, dx1], -1)
    f, _, _ = _residual_and_jacobians(p, x, t)
    ok = np.all(np.abs(f) <= 2.0 * p.rod * 1e-12, axis=-1)
    return x, ok


def jacobian(p: Any, angles: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``d (pitch, roll) / d theta`` at an assembled configuration.

    Args:
        p: Parameters.
        angles: ``(pitch, roll)`` (N, 2) [rad].
        theta: Motor angles (N, 2) [rad].

    Returns:
        (N, 2, 2): ``(pitch, roll)_dot = J theta_dot``.

    """
    x = np.atleast_2d(np.asarray(angles, dtype=float))
    _, Fx, Ft = _residual_and_jacobians(p, x, np.atleast_2d(theta))
    # Fx dx + diag(Ft) dtheta = 0
    return -np.linalg.solve(Fx, Ft[:, :, None] * np.eye(2)[None])
