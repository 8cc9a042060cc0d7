r"""Closed forms of the four-bar knee (:mod:`pkdyn.library.four_bar_knee`).

Sagittal plane ``(x, z)`` of the thigh frame, knee axis at the origin, angles about ``+y`` (a
rotation by ``a`` takes ``(1, 0)`` to ``(cos a, -sin a)``). Crank end
``C(phi) = M + r1 (cos phi, -sin phi)`` with the motor axis ``M = (x_motor, a)``; lever end on
the shank ``K(theta) = r3 (cos theta, -sin theta)``; coupler ``|C - K| = r2``.

- :func:`knee_from_motor`: ``C_x cos theta - C_z sin theta = k``,
  ``k = (|C|^2 + r3^2 - r2^2) / (2 r3)``, hence
  ``theta = atan2(-C_z, C_x) + acos(k / |C|)`` (the assembly mode of the home configuration);
- :func:`motor_from_knee`: with ``D = M - K``, ``D_x cos phi - D_z sin phi = k'``,
  ``k' = (r2^2 - |D|^2 - r1^2) / (2 r1)``, hence ``phi = atan2(-D_z, D_x) + acos(k' / |D|)``;
- :func:`ratio`: ``d theta / d phi`` by implicit differentiation of ``|C - K|^2 = r2^2``
  (infinite at the dead points, where the coupler and the lever are aligned).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["coupler_length", "knee_from_motor", "motor_from_knee", "ratio"]


def coupler_length(p: Any) -> float:
    """Coupler length ``r2`` [m]: crank and lever both along ``+x`` at zero."""
    return float(np.hypot(p.x_motor + p.r1 - p.r3, p.a))


def _C(p: Any, phi: np.ndarray) -> np.ndarray:
    return np.stack([p.x_motor + p.r1 * np.cos(phi), p.a - p.r1 * np.sin(phi)], -1)


def _K(p: Any, theta: np.ndarray) -> np.ndarray:
    return np.stack([p.r3 * np.cos(theta), -p.r3 * np.sin(theta)], -1)


def knee_from_motor(p: Any, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Knee angle from the motor (crank) angle.

    Args:
        p: Parameters (:class:`pkdyn.library.four_bar_knee.Params`).
        phi: Crank angles (N,) [rad].

    Returns:
        ``(theta, ok)`` (N,): knee angles [rad] (NaN where the loop cannot close) and
        reachability.

    """
    C = _C(p, np.asarray(phi, dtype=float))
    r2 = coupler_length(p)
    n = np.hypot(C[..., 0], C[..., 1])
    c = (n**2 + p.r3**2 - r2**2) / (2.0 * p.r3 * n)
    ok = np.abs(c) <= 1.0
    with np.errstate(invalid="ignore"):
        theta = np.arctan2(-C[..., 1], C[..., 0]) + np.arccos(c)
    return np.where(ok, theta, np.nan), ok


def motor_from_knee(p: Any, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Motor (crank) angle from the knee angle.

    Args:
        p: Parameters.
        theta: Knee angles (N,) [rad].

    Returns:
        ``(phi, ok)`` (N,).

    """
    K = _K(p, np.asarray(theta, dtype=float))
    D = np.array([p.x_motor, p.a]) - K
    r2 = coupler_length(p)
    n = np.hypot(D[..., 0], D[..., 1])
    c = (r2**2 - n**2 - p.r1**2) / (2.0 * p.r1 * n)
    ok = np.abs(c) <= 1.0
    with np.errstate(invalid="ignore"):
        phi = np.arctan2(-D[..., 1], D[..., 0]) + np.arccos(c)
    phi = (phi + np.pi) % (2.0 * np.pi) - np.pi
    return np.where(ok, phi, np.nan), ok


def ratio(p: Any, phi: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``d theta / d phi`` at assembled ``(phi, theta)`` (N,)."""
    phi = np.asarray(phi, dtype=float)
    theta = np.asarray(theta, dtype=float)
    E = _C(p, phi) - _K(p, theta)
    dC = p.r1 * np.stack([-np.sin(phi), -np.cos(phi)], -1)
    dK = p.r3 * np.stack([-np.sin(theta), -np.cos(theta)], -1)
    with np.errstate(divide="ignore"):
        return np.sum(E * dC, -1) / np.sum(E * dK, -1)
