"""Closed-form geometric models of the planar five-bar (:mod:`pkdyn.library.five_bar`).

With ``K = E - A_j`` and ``K_3 = (|K|^2 + l1^2 - l2^2) / (2 l1)``, the inverse model is
``theta_j = atan2(K_y, K_x) + s_j acos(K_3 / |K|)`` (``s_j = +1``: elbow ``C_j`` on the left of
``A_j -> E``); the direct model intersects the circles of radius ``l2`` about the elbows.
Vectorised over points; parameters duck-typed (``d``, ``l1``, ``l2``, ``base_xy``,
``working_mode``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError

__all__ = ["MODES", "elbow_points", "forward", "inverse", "mode_signs"]

MODES = ("+-", "-+", "++", "--")
"""Working modes: the elbow signs ``(s_1, s_2)``."""


def mode_signs(working_mode: str) -> np.ndarray:
    """Elbow signs ``(s_1, s_2)`` of a working mode string such as ``"+-"``.

    Args:
        working_mode: Two characters among ``+`` and ``-``.

    Returns:
        Array (2,) of +1 / -1.

    Raises:
        InvalidInputError: Not one of :data:`MODES`.

    """
    if working_mode not in MODES:
        raise InvalidInputError(
            "working_mode", f"must be one of {', '.join(MODES)}, got {working_mode!r}"
        )
    return np.array([1.0 if c == "+" else -1.0 for c in working_mode])


def _wrap(a: np.ndarray) -> np.ndarray:
    return np.pi - (np.pi - a) % (2.0 * np.pi)


def inverse(
    p: Any, E: np.ndarray, working_mode: str | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Inverse geometric model: actuated angles from end-effector points.

    Per chain, ``K = E - A_j`` and ``K_3 = (|K|^2 + l1^2 - l2^2) / (2 l1)``; then
    ``theta_j = atan2(K_y, K_x) + s_j acos(K_3 / |K|)`` when ``|K_3| <= |K|``.

    Args:
        p: Parameters (``d``, ``l1``, ``l2``; ``working_mode`` unless given).
        E: End-effector points, shape (N, 2) or (2,) [m].
        working_mode: Overrides ``p.working_mode``.

    Returns:
        ``(qa, valid)``: actuator coordinates, the angles ``theta`` (N, 2) [rad] in
        ``(-pi, pi]`` (NaN where a chain cannot reach), and mask (N,).

    """
    P = np.atleast_2d(np.asarray(E, dtype=float))
    s = mode_signs(p.working_mode if working_mode is None else working_mode)
    A = p.base_xy
    Kx = P[:, :1] - A[:, 0]
    Ky = P[:, 1:2] - A[:, 1]
    rho = np.hypot(Kx, Ky)
    K3 = (rho**2 + p.l1**2 - p.l2**2) / (2.0 * p.l1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = K3 / rho
    ok = (np.abs(ratio) <= 1.0) & (rho > 0.0)
    theta = np.arctan2(Ky, Kx) + s * np.arccos(np.clip(np.where(ok, ratio, 0.0), -1.0, 1.0))
    theta = _wrap(theta)
    theta[~ok] = np.nan
    return theta, ok.all(axis=1)


def elbow_points(p: Any, qa: np.ndarray) -> np.ndarray:
    """Elbows ``C_j = A_j + l1 (cos theta_j, sin theta_j)``.

    Args:
        p: Parameters.
        qa: Actuator coordinates, the angles ``theta`` (N, 2) or (2,) [rad].

    Returns:
        Elbow points, shape (N, 2, 2) [m].

    """
    t = np.atleast_2d(np.asarray(qa, dtype=float))
    A = p.base_xy
    return np.stack([A[:, 0] + p.l1 * np.cos(t), A[:, 1] + p.l1 * np.sin(t)], axis=-1)


def forward(p: Any, qa: np.ndarray, assembly: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Direct geometric model: end-effector points from actuated angles.

    ``E = M + s n sqrt(l2^2 - |C_1 C_2|^2 / 4)`` with ``M`` the midpoint of ``C_1 C_2`` and
    ``n`` the unit normal on the left of ``C_1 -> C_2``.

    Args:
        p: Parameters.
        qa: Actuator coordinates, the angles ``theta`` (N, 2) or (2,) [rad].
        assembly: ``s = +1`` (E on the left of ``C_1 -> C_2``; above the base for the default
            robot) or ``-1``.

    Returns:
        ``(E, valid)``: points (N, 2) [m] (NaN where not assemblable) and mask (N,).

    """
    C = elbow_points(p, qa)
    u = C[:, 1] - C[:, 0]
    c = np.linalg.norm(u, axis=1)
    h2 = p.l2**2 - 0.25 * c**2
    ok = (h2 >= 0.0) & (c > 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.stack([-u[:, 1], u[:, 0]], axis=1) / c[:, None]
    E = 0.5 * (C[:, 0] + C[:, 1]) + assembly * n * np.sqrt(np.where(ok, h2, 0.0))[:, None]
    E[~ok] = np.nan
    return E, ok
