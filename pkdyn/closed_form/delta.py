"""Clavel's closed-form geometric models of the Delta (seed 000, section 1.4.1).

Notation: ``ra, rb, la, lb`` and ``R = ra - rb``; arm ``i`` lies in the vertical plane at
``theta_i = 0, 120, 240 deg``; ``alpha_i`` is the arm angle (0 = horizontal, positive towards the
platform, below the base). The nacelle reduced to its centre ``P`` lies on a sphere of radius
``lb`` around each point ``C'_i = [(R + la cos a_i) cos t_i, (R + la cos a_i) sin t_i,
-la sin a_i]`` (eq. 1).

Both functions take ``(N, 3)`` arrays and return a validity mask instead of raising, so sweeps
stay vectorised; invalid rows are NaN.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

__all__ = ["THETA", "DeltaGeometry", "arm_angles", "elbow_points", "forward", "inverse"]

THETA = np.deg2rad([0.0, 120.0, 240.0])
"""Arm plane angles theta_i [rad] of the three-armed Delta."""


def arm_angles(g: object) -> np.ndarray:
    """Arm plane angles of a geometry: its ``theta`` attribute if it has one, else :data:`THETA`.

    Args:
        g: Geometry (e.g. :class:`pkdyn.library.delta.Params`, whose ``arms`` may be 4).

    Returns:
        Angles (n_arms,) [rad].

    """
    return np.asarray(getattr(g, "theta", THETA), dtype=float)


class DeltaGeometry(Protocol):
    """Anything with Clavel's four lengths [m]."""

    @property
    def ra(self) -> float: ...  # noqa: D102
    @property
    def rb(self) -> float: ...  # noqa: D102
    @property
    def la(self) -> float: ...  # noqa: D102
    @property
    def lb(self) -> float: ...  # noqa: D102


def inverse(g: DeltaGeometry, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse geometric model: arm angles from nacelle positions.

    Per arm, eq. 1 reads ``A cos a + B sin a = C``; the working branch (elbow outwards,
    ``alpha + beta < 180 deg``) is ``a = atan2(B, A) + acos(C / hypot(A, B))``.

    Args:
        g: Geometry (ra, rb, la, lb) [m].
        P: Nacelle centre positions (N, 3) or (3,) [m].

    Returns:
        ``(qa, valid)``: actuator coordinates, the arm angles ``alpha`` (N, n_arms) [rad] (NaN
        where unreachable), and mask (N,).

    """
    P = np.atleast_2d(np.asarray(P, dtype=float))
    R = g.ra - g.rb
    theta = arm_angles(g)
    c, s = np.cos(theta), np.sin(theta)
    xr = P[:, :1] * c + P[:, 1:2] * s - R
    yt = -P[:, :1] * s + P[:, 1:2] * c
    z = P[:, 2:3]
    A = -2.0 * g.la * xr
    B = 2.0 * g.la * z
    C = g.lb**2 - g.la**2 - xr**2 - yt**2 - z**2
    rho = np.hypot(A, B)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = C / rho
    ok = np.abs(ratio) <= 1.0
    alpha = np.arctan2(B, A) + np.arccos(np.clip(ratio, -1.0, 1.0))
    alpha = (alpha + np.pi) % (2 * np.pi) - np.pi
    alpha[~ok] = np.nan
    return alpha, ok.all(axis=1)


def elbow_points(g: DeltaGeometry, qa: np.ndarray) -> np.ndarray:
    """Points ``C'_i`` (N, n_arms, 3) [m] of eq. 1 for arm angles ``qa`` (N, n_arms) [rad]."""
    alpha = np.atleast_2d(np.asarray(qa, dtype=float))
    R = g.ra - g.rb
    rad = R + g.la * np.cos(alpha)
    theta = arm_angles(g)
    return np.stack([rad * np.cos(theta), rad * np.sin(theta), -g.la * np.sin(alpha)], axis=-1)


def forward(g: DeltaGeometry, qa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Direct geometric model: nacelle position from arm angles (Clavel, eqs. 2-4).

    Subtracting eq. 1 pairwise gives ``x`` and ``y`` linear in ``z`` (coefficients ``H1..H5``);
    eq. 1 for arm 1 then gives ``L z^2 + M z + N = 0``. The lower root (nacelle below the
    base) is the working assembly mode. With more than three arms, the first three are used
    (the others must agree with them for the input to be assemblable).

    Args:
        g: Geometry (ra, rb, la, lb) [m].
        qa: Actuator coordinates, the arm angles ``alpha`` (N, n_arms) or (n_arms,) [rad].

    Returns:
        ``(P, valid)``: nacelle positions (N, 3) [m] (NaN where not assemblable) and mask (N,).

    """
    alpha = np.atleast_2d(np.asarray(qa, dtype=float))[:, :3]
    theta = arm_angles(g)[:3]
    R, la, lb = g.ra - g.rb, g.la, g.lb
    ca = np.cos(alpha)
    D = -(lb**2) + la**2 + R**2 + 2 * R * la * ca
    E = 2 * (R + la * ca) * np.cos(theta)
    F = 2 * (R + la * ca) * np.sin(theta)
    G = -2 * la * np.sin(alpha)
    E1, E2, E3 = E.T
    F1, F2, F3 = F.T
    G1, G2, G3 = G.T
    D1, D2, D3 = D.T
    H1 = E1 * G2 - E1 * G3 - E2 * G1 + E2 * G3 + E3 * G1 - E3 * G2
    H2 = -E1 * F2 + E1 * F3 + E2 * F1 - E2 * F3 - E3 * F1 + E3 * F2
    H3 = -E1 * D2 + E1 * D3 + E2 * D1 - E2 * D3 - E3 * D1 + E3 * D2
    H4 = F1 * D2 - F1 * D3 - F2 * D1 + F2 * D3 + F3 * D1 - F3 * D2
    H5 = -F1 * G2 + F1 * G3 + F2 * G1 - F2 * G3 - F3 * G1 + F3 * G2
    with np.errstate(invalid="ignore", divide="ignore"):
        L = (H5**2 + H1**2) / H2**2 + 1.0
        M = 2 * (H5 * H4 + H1 * H3) / H2**2 - (H5 * E1 + H1 * F1) / H2 - G1
        N = (H4**2 + H3**2) / H2**2 - (H4 * E1 + H3 * F1) / H2 + D1
        disc = M**2 - 4 * L * N
        z = (-M - np.sqrt(disc)) / (2 * L)
        x = z * H5 / H2 + H4 / H2
        y = z * H1 / H2 + H3 / H2
    P = np.stack([x, y, z], axis=1)
    ok = np.isfinite(P).all(axis=1) & (disc >= 0)
    P[~ok] = np.nan
    return P, ok
