"""Closed-form geometry of the walking tripod (:mod:`pkdyn.library.tripod`, seed 003).

Attachment points, foothold frames and the home nacelle placement the builder uses, and the
paper's vector-projection solution of the virtual U-P-S chains (equations (1)-(8), the
``B_iIKMX`` model), the triangle's actuator lengths and the model coordinates of the lockable
joints. Parameters are duck-typed (``r_p``, ``theta``, ``foothold_radius``, ``foot_height``,
``nacelle_height`` and, optionally, ``branches``: 3 for the tripod, 4 for the four-branch walker,
3 when absent); all vectorised over the branches.

Branch ``i`` (0-based here) sits at ``phi_i = 2 pi i / n`` about the nacelle axis for ``n``
branches (:func:`branch_angles`): the same branch design is repeated evenly, its attachment
points ``phi_i +- theta`` on the same circle of radius ``r_p`` and its foothold on the same circle
of radius ``foothold_radius``, so every branch of the walker sees exactly the geometry of a tripod
branch at home.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import InvalidInputError
from pkdyn.model.pose import pose_from_vector
from solvers.vec3 import cross

__all__ = [
    "PHI",
    "attachments",
    "branch_angles",
    "branch_count",
    "foothold_frames",
    "home_nacelle_placement",
    "lockable_coordinates",
    "perpendicular",
    "triangle_lengths",
    "unit_vector",
    "virtual_joints",
]

PHI = (0.0, 2.0 * np.pi / 3.0, 4.0 * np.pi / 3.0)
"""Angular position [rad] of branch ``i`` of the tripod about the nacelle axis (branch 1 along
+x); :func:`branch_angles` for any number of branches."""


def branch_count(p: Any) -> int:
    """Number of branches of a parameter set (``p.branches``, 3 when absent)."""
    return int(getattr(p, "branches", 3))


def branch_angles(p: Any) -> tuple[float, ...]:
    """Angular positions ``phi_i = 2 pi i / n`` [rad] of the ``n`` branches (branch 1 along +x).

    For the tripod they are :data:`PHI`.
    """
    n = branch_count(p)
    return PHI if n == 3 else tuple(2.0 * np.pi * i / n for i in range(n))


def unit_vector(v: np.ndarray) -> np.ndarray:
    """``v / |v|`` (3,)."""
    return v / np.linalg.norm(v)


def perpendicular(v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """Equation (2): unit vector of ``v1`` projected on the plane normal to unit ``v2``."""
    return unit_vector(v1 - (v1 @ v2) * v2)


def _units(v: np.ndarray) -> np.ndarray:
    return v / np.sqrt(np.einsum("ij,ij->i", v, v))[:, None]


def _angles(v1: np.ndarray, v2: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Equation (1), row-wise."""
    return np.arctan2(np.einsum("ij,ij->i", n, cross(v1, v2)), np.einsum("ij,ij->i", v1, v2))


def _perps(v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """Equation (2), row-wise."""
    return _units(v1 - np.einsum("ij,ij->i", v1, v2)[:, None] * v2)


def attachments(p: Any, i: int) -> tuple[np.ndarray, np.ndarray]:
    """``P_L`` and ``P_R`` of branch ``i`` (0-based) in the nacelle frame ``R_P`` [m]."""
    phi = branch_angles(p)[i]
    a_l, a_r = phi + p.theta, phi - p.theta
    P_L = p.r_p * np.array([math.cos(a_l), math.sin(a_l), 0.0])
    P_R = p.r_p * np.array([math.cos(a_r), math.sin(a_r), 0.0])
    return P_L, P_R


def foothold_frames(p: Any) -> list[pin.SE3]:
    """Foot frames ``R_Ai`` of the footholds of the model, in the support frame ``R_B``.

    Origin ``A_i`` (universal-joint centre) at ``foot_height`` above the foothold
    ``foothold_radius (cos phi_i, sin phi_i, 0)``; ``w_a`` = +z (normal to the support),
    ``u_a`` radial outwards, ``v_a = w_a x u_a``.

    Args:
        p: Parameters.

    Returns:
        The foot placements, one per branch.

    """
    out = []
    for phi in branch_angles(p):
        R = pin.rpy.rpyToMatrix(0.0, 0.0, phi)
        A = np.array([p.foothold_radius * math.cos(phi), p.foothold_radius * math.sin(phi), 0.0])
        A[2] = p.foot_height
        out.append(pin.SE3(R, A))
    return out


def home_nacelle_placement(p: Any) -> pin.SE3:
    """Placement of ``R_P`` in ``R_B`` at home: ``P_O`` at ``(0, 0, nacelle_height)``, level.

    Args:
        p: Parameters.

    Returns:
        The nacelle placement.

    """
    return pin.SE3(np.eye(3), np.array([0.0, 0.0, p.nacelle_height]))


def virtual_joints(
    p: Any,
    nacelle_placement: pin.SE3 | Sequence[float] | np.ndarray,
    footholds: Sequence[pin.SE3] | None = None,
) -> np.ndarray:
    """Coordinates ``s_i = [q1 .. q6]`` of the virtual U-P-S chains: the paper's ``B_iIKMX``.

    Vector-projection solution of equations (1)-(8) of seed 003, with ``Theta`` the signed angle
    of equation (1) and ``perp`` the projection of equation (2), all vectors in ``R_B``:

    - ``u`` = unit ``P_L P_R``; ``l_c`` = unit ``A P_C`` (from ``A`` to ``P_C``);
      ``v_c`` = unit ``P_C P_O`` (in the nacelle plane, normal to ``u``, towards the centre);
    - (3) ``q6 = pi/2 - Theta(perp(l_c, u), v_c, u)``: 0 when the triangle plane is normal to the
      nacelle plane, positive when the foot is outboard of the edge;
    - (4) ``q5 = pi/2 - Theta(u, l_c, u x l_c)`` in ``[-pi/2, pi/2]``, positive when ``A`` is
      nearer ``P_L`` (``q_L < q_R``); (5) ``q4 = |A P_C|``;
    - ``v3`` = unit ``l_c x u`` (axis ``a``, normal to the triangle, pointing outboard and up
      at home); ``w'`` = ``perp(w_a, v3)``; (6) ``q3 = Theta(l_c, w', v3)``;
    - ``x1 = perp(v3, w_a)``; (7) ``q2 = Theta(w', w_a, x1 x w_a)``; (8)
      ``q1 = Theta(u_a, x1, w_a)``.

    Two readings differ from the paper's text: in (3) the paper names ``v_c`` "B_O P_C", which is
    not normal to ``u`` as the paper itself requires; we use the in-plane direction ``P_C P_O``.
    In (7) the paper takes ``u`` as the normal; the true rotation axis of ``q2`` is
    ``x1 x w_a``, which equals ``u`` when ``u`` is parallel to the support (e.g. at home) and
    gives the right magnitude elsewhere. With these definitions (and ``|q2| < pi/2``) the
    virtual chain from the foot frame ``R_A`` is, with ``Rx, Ry, Rz`` rotations about the
    current axes::

        R_A Rz(q1) Ry(q2)         has x = v3 and z = w'
        R_A Rz(q1) Ry(q2) Rx(-q3) has z = l_c, and P_C = A + q4 l_c
        u = sin(q5) l_c - cos(q5) (l_c x v3)
        w_p = -Rot(u, -q6) perp(-l_c, u)      (w_p: the nacelle normal)

    At home (level nacelle, default footholds) ``q1 = q3 = q5 = 0`` and ``q2 = -q6``.

    Args:
        p: Parameters.
        nacelle_placement: Placement of ``R_P`` in ``R_B`` (``pin.SE3``), or
            ``[x, y, z, roll, pitch, yaw]`` [m, rad] with ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (the
            paper's ``x = (x_P, y_P, z_P, alpha_P, beta_P, gamma_P)``).
        footholds: Foot frames ``R_Ai`` (origin ``A_i``) in ``R_B``, one per branch; default
            :func:`foothold_frames`.

    Returns:
        (n, 6) array: row ``i`` holds ``q1, q2, q3 [rad], q4 [m], q5, q6 [rad]`` of branch
        ``i + 1``.

    Raises:
        InvalidInputError: Malformed placement or not one foothold per branch.

    """
    M = pose_from_vector(nacelle_placement)
    n = branch_count(p)
    feet = foothold_frames(p) if footholds is None else list(footholds)
    if len(feet) != n or not all(isinstance(f, pin.SE3) for f in feet):
        raise InvalidInputError(
            "footholds", f"expected {n} pin.SE3 foot frames (one per branch), got {footholds!r}"
        )
    # all branches at once: rows of (n, 3) arrays
    R, P_O = np.array(M.rotation), np.array(M.translation)
    P_L = np.array([attachments(p, i)[0] for i in range(n)]) @ R.T + P_O
    P_R = np.array([attachments(p, i)[1] for i in range(n)]) @ R.T + P_O
    A = np.array([f.translation for f in feet])
    u_a = np.array([f.rotation[:, 0] for f in feet])
    w_a = np.array([f.rotation[:, 2] for f in feet])
    P_C = 0.5 * (P_L + P_R)
    u = _units(P_R - P_L)
    l_c = _units(P_C - A)
    v_c = _units(P_O - P_C)
    q6 = 0.5 * np.pi - _angles(_perps(l_c, u), v_c, u)
    q5 = 0.5 * np.pi - _angles(u, l_c, _units(cross(u, l_c)))
    q4 = np.linalg.norm(P_C - A, axis=1)
    v3 = _units(cross(l_c, u))
    w_p = _perps(w_a, v3)
    q3 = _angles(l_c, w_p, v3)
    x1 = _perps(v3, w_a)
    q2 = _angles(w_p, w_a, _units(cross(x1, w_a)))
    q1 = _angles(u_a, x1, w_a)
    return np.column_stack([q1, q2, q3, q4, q5, q6])


def triangle_lengths(p: Any, s: np.ndarray) -> np.ndarray:
    """Actuator lengths ``q_L = |A P_L|`` and ``q_R = |A P_R|`` from the virtual ``q4``, ``q5``.

    With ``e = |P_L P_R|``: ``q_L^2 = q4^2 + e^2/4 - e q4 sin q5`` and
    ``q_R^2 = q4^2 + e^2/4 + e q4 sin q5`` (the median ``A P_C`` makes the angle
    ``pi/2 - q5`` with ``P_L P_R``).

    Args:
        p: Parameters.
        s: Virtual coordinates (n, 6) or (6,) from :func:`virtual_joints`.

    Returns:
        ``(..., 2)`` array ``[q_L, q_R]`` [m].

    """
    s = np.asarray(s, dtype=float)
    e = 2.0 * p.r_p * math.sin(p.theta)
    q4, q5 = s[..., 3], s[..., 4]
    base = q4**2 + 0.25 * e**2
    return np.stack(
        [np.sqrt(base - e * q4 * np.sin(q5)), np.sqrt(base + e * q4 * np.sin(q5))], axis=-1
    )


def _gamma_l(p: Any, s: np.ndarray) -> np.ndarray:
    """Angle [rad] of the triangle at ``A`` between ``A P_C`` and ``A P_L``."""
    e = 2.0 * p.r_p * math.sin(p.theta)
    q4, q5 = s[..., 3], s[..., 4]
    return np.arctan2(0.5 * e * np.cos(q5), q4 - 0.5 * e * np.sin(q5))


@functools.lru_cache(maxsize=16)
def _home_virtual(p: Any) -> tuple[np.ndarray, float]:
    """Virtual coordinates of branch 1 at home and the triangle's angle ``gamma_L`` there."""
    s0 = virtual_joints(p, home_nacelle_placement(p))[0]
    s0.setflags(write=False)
    return s0, float(_gamma_l(p, s0))


def lockable_coordinates(p: Any, s: np.ndarray) -> np.ndarray:
    """Model coordinates of the lockable passive joints from the virtual ``q1 .. q6``.

    The model's passive joints are zero at home (default footholds, level nacelle), so the
    paper's angles map to them with the home values ``s0`` of :func:`virtual_joints` as offsets:

    - ``q1``: coordinate 1 of ``branch{i}_q2q1``, ``q1 - q1_home``;
    - ``q2``: coordinate 0 of ``branch{i}_q2q1``, ``q2 - q2_home``;
    - ``q3``: joint ``branch{i}_a`` (knuckle on rod ``L``), ``q3 - gamma_L(home) + gamma_L``:
      the paper's ``q3`` is measured from the median ``A P_C``, which no body carries, the
      model's joint from the rod ``A P_L``; ``gamma_L`` is the triangle's angle at ``A``
      between them (a function of ``q4``, ``q5``);
    - ``q6``: joint ``branch{i}_q6``, ``q6 - q6_home``.

    Args:
        p: Parameters.
        s: Virtual coordinates (n, 6) (or (6,) for one branch, then branch 1's offsets
            apply: all branches have the same home values).

    Returns:
        ``(..., 4)`` array: model coordinates of ``q1, q2, q3, q6`` [rad].

    """
    s = np.asarray(s, dtype=float)
    s0, g0 = _home_virtual(p)
    return np.stack(
        [
            s[..., 0] - s0[0],
            s[..., 1] - s0[1],
            s[..., 2] - g0 + _gamma_l(p, s),
            s[..., 5] - s0[5],
        ],
        axis=-1,
    )
