"""Geometric models of a Gough-Stewart platform (Merlet's notation): inverse and batched direct.

Leg ``i`` joins the base joint centre ``A_i`` (base frame) to the platform joint centre ``B_i``
(platform frame); for a platform placement ``(p, R)`` its length is
``rho_i = | p + R B_i - A_i |``. :func:`forward` solves the direct model of many platforms at
once by Newton's method (the Monte Carlo of the family's joint centres).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from solvers.vec3 import cross

__all__ = ["forward", "leg_lengths", "leg_rows", "leg_lengths_rpy", "rotation_log"]


def leg_lengths(A: np.ndarray, B: np.ndarray, p: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Leg lengths for a batch of platform placements.

    Args:
        A: Base joint centres (6, 3) [m], base frame, or one set per placement (N, 6, 3).
        B: Platform joint centres (6, 3) [m], platform frame, or one set per placement
            (N, 6, 3).
        p: Platform positions (N, 3) or (3,) [m].
        R: Platform rotations (N, 3, 3) or (3, 3).

    Returns:
        Leg lengths rho (N, 6) [m].

    """
    p = np.atleast_2d(np.asarray(p, dtype=float))
    R = np.asarray(R, dtype=float)
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    if R.ndim == 2:
        R = np.broadcast_to(R, (p.shape[0], 3, 3))
    if B.ndim == 3:  # a platform each
        return _legs(A, B, p, R)[1]
    legs = p[:, None, :] + np.einsum("nij,kj->nki", R, B) - A
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


def _legs(
    A: np.ndarray, B: np.ndarray, P: np.ndarray, R: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Leg vectors ``p + R B_i - A_i`` (N, 6, 3), their lengths (N, 6) and ``R B_i`` (N, 6, 3)."""
    Bw = np.matmul(R[:, None], B[..., None])[..., 0]
    v = P[:, None, :] + Bw - A
    return v, np.sqrt(np.sum(v * v, axis=-1)), Bw


def leg_rows(A: np.ndarray, B: np.ndarray, P: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Rows ``[u_i, (R B_i) x u_i]`` (N, 6, 6): the leg lengths' derivatives, each its platform.

    ``d rho = rows [dp; w]`` for a platform displacement ``dp`` and a rotation ``w`` (world
    axes, ``R <- exp([w]x) R``): the inverse kinematic Jacobian about the platform origin.

    Args:
        A: Base joint centres (N, 6, 3) [m], base frame.
        B: Platform joint centres (N, 6, 3) [m], platform frame.
        P: Platform positions (N, 3) [m].
        R: Platform rotations (N, 3, 3).

    Returns:
        The rows [-, m].

    """
    v, length, Bw = _legs(A, B, P, R)
    u = v / length[..., None]
    return np.concatenate([u, cross(Bw, u)], axis=-1)


def _exp3(w: np.ndarray) -> np.ndarray:
    """Rotation matrices ``exp([w]x)`` (N, 3, 3) of rotation vectors (N, 3) (Rodrigues)."""
    t2 = np.sum(w * w, axis=-1)
    t = np.sqrt(t2)
    small = t < 1e-4
    ts = np.where(small, 1.0, t)
    a = np.where(small, 1.0 - t2 / 6.0, np.sin(ts) / ts)  # sin t / t
    b = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(ts)) / (ts * ts))  # (1 - cos t) / t^2
    K = np.zeros((w.shape[0], 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
    return np.eye(3) + a[:, None, None] * K + b[:, None, None] * np.matmul(K, K)


def rotation_log(R: np.ndarray) -> np.ndarray:
    """Rotation vectors ``log3(R)`` (N, 3) of rotations (N, 3, 3) of less than pi - 0.1 rad.

    From the skew part ``sin(t) u`` and the trace ``1 + 2 cos(t)`` by ``atan2``: accurate to
    the rounding of ``R`` at small angles too (where ``arccos`` of the trace is not). Rotations
    closer to a half turn than 0.1 rad are computed by :func:`pinocchio.log3` one by one.

    Args:
        R: Rotation matrices (N, 3, 3).

    Returns:
        Rotation vectors (N, 3) [rad].

    """
    R = np.asarray(R, dtype=float)
    w = 0.5 * np.stack(
        [R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], axis=-1
    )
    s = np.sqrt(np.sum(w * w, axis=-1))
    c = 0.5 * (R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2] - 1.0)
    t = np.arctan2(s, c)
    factor = np.where(s > 1e-8, t / np.where(s > 1e-8, s, 1.0), 1.0 + s * s / 6.0)
    out = factor[:, None] * w
    for k in np.flatnonzero(t > np.pi - 0.1):
        out[k] = pin.log3(R[k])
    return out


def forward(
    A: np.ndarray,
    B: np.ndarray,
    rho: np.ndarray,
    p0: np.ndarray,
    R0: np.ndarray,
    tol: float,
    max_iterations: int = 20,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Direct geometric model of a batch of Gough-Stewart platforms: Newton from one start.

    Each platform ``n`` (its own joint centres and leg lengths) is solved for the placement
    ``(p, R)`` with ``| p + R B_i - A_i | = rho_i`` by Newton's method on the six lengths,
    all platforms at once (batched 6 x 6 solves), from the start ``(p0, R0)``; the rotation is
    updated as ``R <- exp([w]x) R`` (``w`` in world axes). The solution is the one Newton's
    method reaches from the start: the start's assembly mode for platforms near it.

    Args:
        A: Base joint centres (N, 6, 3) [m], base frame.
        B: Platform joint centres (N, 6, 3) [m], platform frame.
        rho: Leg lengths (N, 6) [m].
        p0: Start position (3,) [m].
        R0: Start rotation (3, 3).
        tol: Largest leg-length residual of a converged platform [m] (relative to the
            robot's size: e.g. ``1e-13`` times it).
        max_iterations: Most Newton steps.

    Returns:
        Positions (N, 3) [m], rotations (N, 3, 3) and which platforms converged (N,); the
        others hold their last iterate.

    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    rho = np.asarray(rho, dtype=float)
    n = rho.shape[0]
    P = np.broadcast_to(np.asarray(p0, dtype=float), (n, 3)).copy()
    R = np.broadcast_to(np.asarray(R0, dtype=float), (n, 3, 3)).copy()
    done = np.zeros(n, dtype=bool)
    active = np.arange(n)
    for iteration in range(max_iterations + 1):
        Ra, Pa = R[active], P[active]
        v, length, Bw = _legs(A[active], B[active], Pa, Ra)
        f = length - rho[active]
        ok = np.all(np.abs(f) <= tol, axis=1) & np.all(np.isfinite(f), axis=1)
        done[active[ok]] = True
        keep = ~ok & np.all(np.isfinite(f), axis=1)
        active, Ra, Pa = active[keep], Ra[keep], Pa[keep]
        if not active.size or iteration == max_iterations:
            break
        u = v[keep] / length[keep][..., None]
        J = np.concatenate([u, cross(Bw[keep], u)], axis=-1)  # d length = J [dp; w]
        try:
            step = np.linalg.solve(J, -f[keep][..., None])[..., 0]
        except np.linalg.LinAlgError:  # a singular platform: solve one by one, drop it
            step = np.full((active.size, 6), np.nan)
            for k in range(active.size):
                try:
                    step[k] = np.linalg.solve(J[k], -f[keep][k])
                except np.linalg.LinAlgError:
                    pass
        finite = np.all(np.isfinite(step), axis=1)
        active, Ra, Pa, step = active[finite], Ra[finite], Pa[finite], step[finite]
        P[active] = Pa + step[:, :3]
        R[active] = np.matmul(_exp3(step[:, 3:]), Ra)
    return P, R, done
