"""Stiffness and lowest frequency of the library Gough-Stewart and Delta, vectorised over poses.

With the actuators' stiffness alone (rigid links, no other spring) the virtual-joint model
reduces to Gosselin's ``K = J^T K_a J``; where the inverse kinematic Jacobian ``J`` has a closed
form, whole maps follow at once (numpy), without solving any pose:

- Gough-Stewart (Merlet): leg ``i`` from ``A_i`` to ``B_i`` (unit vector ``u_i``) moves at
  ``rho_dot_i = u_i . v_c + ((B_i - c) x u_i) . omega`` for the reference point ``c``: ``J`` has
  rows ``[u_i, (B_i - c) x u_i]`` (world axes: the precision convention) and
  ``K = sum_i k_i J_i^T J_i`` (6 x 6);
- Delta (Clavel's reduced model, :func:`pkdyn.analysis.screws.delta_AB`): ``J`` has rows
  ``d_i / (d_i . dC'_i/dalpha_i)`` (3 x 3, the nacelle translates), and the nacelle's reduced mass
  matrix ``M_x`` is the inertial part of :class:`pkdyn.dynamics.delta.DeltaDynamics` (arms about
  their axes with the rotor inertia, bars with no spin momentum, nacelle), so the natural
  frequencies solve ``K x = omega^2 M_x x`` per pose.

The tests check both against the general path (:func:`pkdyn.precision.stiffness`,
:func:`pkdyn.precision.modes.modes`) to round-off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkdyn.analysis.kinematics import NEAR_SERIAL_TOL, SINGULAR_TOL
from pkdyn.closed_form import delta as delta_cf
from pkdyn.dynamics.delta import DeltaDynamics, has_delta_dynamics
from pkdyn.model.robot import Robot
from solvers.vec3 import cross

__all__ = [
    "VectorisedFigures",
    "delta_figures",
    "gough_stewart_figures",
    "gough_stewart_stiffness",
    "inv3",
    "sym3_min_eig",
    "vectorised",
]

_FREE = 1e-12
"""Eigenvalues of ``K`` below this fraction of the largest: a parallel singularity."""


@dataclass(eq=False)  # numpy fields
class VectorisedFigures:
    """Per pose figures of a vectorised evaluation (NaN where not valid).

    Attributes:
        valid: Pose reached and not singular (N,).
        stiffness_min: Smallest principal translational stiffness (N,) [N/m].
        deflection: Translation of the reference point under the wrench (N,) [m] (NaN without).
        f1: Lowest natural frequency (N,) [Hz] (NaN when not computed).
        reached: Pose reached (N,) (``reached & ~valid``: singular).
        near: Valid pose near a serial singularity (N,) (the margin of
            :data:`pkdyn.analysis.kinematics.NEAR_SERIAL_TOL`).

    """

    valid: np.ndarray
    stiffness_min: np.ndarray
    deflection: np.ndarray
    f1: np.ndarray
    reached: np.ndarray | None = None
    near: np.ndarray | None = None


def sym3_min_eig(A: np.ndarray) -> np.ndarray:
    """Smallest eigenvalue of symmetric 3x3 matrices (N, 3, 3), closed form (trigonometric).

    Smith's method (1961): ``A = q I + p B`` with ``det(B) / 2 = cos(3 phi)``.
    """
    a00, a11, a22 = A[:, 0, 0], A[:, 1, 1], A[:, 2, 2]
    a01, a02, a12 = A[:, 0, 1], A[:, 0, 2], A[:, 1, 2]
    q = (a00 + a11 + a22) / 3.0
    p1 = a01**2 + a02**2 + a12**2
    b00, b11, b22 = a00 - q, a11 - q, a22 - q
    p = np.sqrt(np.maximum((b00**2 + b11**2 + b22**2 + 2.0 * p1) / 6.0, 0.0))
    safe = np.where(p > 0.0, p, 1.0)
    det = (
        b00 * (b11 * b22 - a12 * a12)
        - a01 * (a01 * b22 - a12 * a02)
        + a02 * (a01 * a12 - b11 * a02)
    ) / safe**3
    phi = np.arccos(np.clip(0.5 * det, -1.0, 1.0)) / 3.0
    return np.where(p > 0.0, q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0), q)


def inv3(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverses (N, 3, 3) and determinants (N,) of 3x3 matrices, by the adjugate."""
    a, b, c = A[:, 0, 0], A[:, 0, 1], A[:, 0, 2]
    d, e, f = A[:, 1, 0], A[:, 1, 1], A[:, 1, 2]
    g, h, i = A[:, 2, 0], A[:, 2, 1], A[:, 2, 2]
    co = np.empty(A.shape[:1] + (3, 3))  # (the adjugate, entry by entry)
    co[:, 0, 0], co[:, 0, 1], co[:, 0, 2] = e * i - f * h, c * h - b * i, b * f - c * e
    co[:, 1, 0], co[:, 1, 1], co[:, 1, 2] = f * g - d * i, a * i - c * g, c * d - a * f
    co[:, 2, 0], co[:, 2, 1], co[:, 2, 2] = d * h - e * g, b * g - a * h, a * e - b * d
    det = a * co[:, 0, 0] + b * co[:, 1, 0] + c * co[:, 2, 0]
    safe = np.where(det != 0.0, det, 1.0)
    return co / safe[:, None, None], det


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.matmul(A, x[..., None])[..., 0]


def _gram(J: np.ndarray, k: np.ndarray, a: slice, b: slice) -> np.ndarray:
    """Block ``J[:, :, a]^T diag(k) J[:, :, b]`` (N, |a|, |b|)."""
    return np.matmul(np.swapaxes(J[:, :, a] * k[None, :, None], 1, 2), J[:, :, b])


def _gs_rows(
    A: np.ndarray, B: np.ndarray, P: np.ndarray, R: np.ndarray, point: np.ndarray | None
) -> np.ndarray:
    """Rows ``[u_i, (B_i - c) x u_i]`` (N, 6, 6) of the Gough-Stewart's inverse Jacobian."""
    P = np.atleast_2d(np.asarray(P, dtype=float))
    R = np.asarray(R, dtype=float)
    p = np.zeros(3) if point is None else np.asarray(point, dtype=float)
    if R.ndim == 2:  # one orientation (a translation map): rotate the joints once
        Bw = P[:, None, :] + (B @ R.T)[None]
        c = P + R @ p
    else:
        Bw = P[:, None, :] + np.matmul(R[:, None], B[None, :, :, None])[..., 0]
        c = P + _mv(R, np.broadcast_to(p, P.shape))
    J = np.empty((P.shape[0], B.shape[0], 6))
    u = Bw - A[None]
    u /= np.sqrt(np.sum(u * u, axis=-1, keepdims=True))
    J[..., :3] = u
    J[..., 3:] = cross(Bw - c[:, None, :], u)
    return J


def gough_stewart_stiffness(
    A: np.ndarray,
    B: np.ndarray,
    P: np.ndarray,
    R: np.ndarray,
    k: np.ndarray,
    point: np.ndarray | None = None,
) -> np.ndarray:
    """``K = J^T diag(k) J`` (N, 6, 6) of a Gough-Stewart platform (module docstring).

    Args:
        A: Base joint centres (6, 3) [m], world.
        B: Platform joint centres (6, 3) [m], platform frame.
        P: Platform frame origins (N, 3) [m].
        R: Platform rotations (N, 3, 3) or (3, 3).
        k: Leg stiffnesses (6,) [N/m].
        point: Reference point, platform frame [m] (default: the origin).

    Returns:
        Stiffness matrices [N/m, N, N m/rad], world axes, moments about the point.

    """
    J = _gs_rows(A, B, P, R, point)
    return _gram(J, np.asarray(k, dtype=float), slice(0, 6), slice(0, 6))


def gough_stewart_figures(
    robot: Robot,
    P: np.ndarray,
    R: np.ndarray,
    k: np.ndarray,
    point: np.ndarray | None = None,
    wrench: np.ndarray | None = None,
) -> VectorisedFigures:
    """Figures of a library Gough-Stewart at poses ``(P, R)`` (no frequency: NaN).

    The translational principal stiffnesses (moments free) are the eigenvalues of the Schur
    complement ``S = K_tt - K_tr K_rr^-1 K_rt`` (the inverse of the compliance's translation
    block), the deflection ``S^-1 (F - K_tr K_rr^-1 M)``: 3 x 3 closed forms.
    """
    prm = robot.params
    J = _gs_rows(prm.a, prm.b, P, R, point)
    N = J.shape[0]
    k = np.asarray(k, dtype=float)
    t, r = slice(0, 3), slice(3, 6)
    Ktt, Ktr, Krr = _gram(J, k, t, t), _gram(J, k, t, r), _gram(J, k, r, r)
    Krr_inv, det_r = inv3(Krr)
    G = np.matmul(Ktr, Krr_inv)
    S = Ktt - np.matmul(G, np.swapaxes(Ktr, 1, 2))
    S = 0.5 * (S + np.swapaxes(S, 1, 2))
    kmin = sym3_min_eig(S)
    top = np.einsum("nii->n", Ktt)
    ok = np.isfinite(kmin) & (det_r > 0.0) & (kmin > _FREE * top)
    kmin = np.where(ok, kmin, np.nan)
    defl = np.full(N, np.nan)
    if wrench is not None:
        S_inv, _ = inv3(S)
        w = np.asarray(wrench, dtype=float)
        F = w[:3][None] - _mv(G, np.broadcast_to(w[3:], (N, 3)))
        defl = np.where(ok, np.linalg.norm(_mv(S_inv, F), axis=-1), np.nan)
    # (a Gough-Stewart has no serial singularity: each leg's rate is u_i . v, |u_i| = 1)
    return VectorisedFigures(ok, kmin, defl, np.full(N, np.nan), np.ones(N, dtype=bool))


def _delta_jacobian(
    dd: DeltaDynamics, P: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(ok, J_inv, E', d, reached, margin)`` with the arm data of :class:`DeltaDynamics`.

    ``margin`` is the smallest ``|d . E'| / (|d| |E'|)`` of the arms (N,): the sine of the
    angle between an arm's bars and its elbow's path, the scale-aware serial margin of the
    arm (0: stretched or folded along its bars), judged with the singularity thresholds.
    """
    alpha, ok = delta_cf.inverse(dd.params, P - dd.f_off)
    reached = np.array(ok, dtype=bool)
    alpha = np.where(np.isfinite(alpha), alpha, 0.0)
    c, s = np.cos(alpha).T, np.sin(alpha).T  # (arm, N)
    # Component-major, (arm, component, N): the products, sums and differences of
    # DeltaDynamics._in_world, solvers.vec3.cross and the sums over components (numpy's
    # sum(axis=-1): 0 + x + y + z) in their order, each a loop over the poses; the arrays
    # returned are (N, arm, component), C-ordered, as before.
    e, R0, O = dd.elbow, dd.R0, dd.O[:, :, None]
    x = c * e[:, 0, None] + s * e[:, 2, None]
    z = c * e[:, 2, None] - s * e[:, 0, None]
    mid = (e[:, 1, None] * R0[:, :, 1])[:, :, None]
    E = O + (x[:, None, :] * R0[:, :, 0, None] + mid + z[:, None, :] * R0[:, :, 2, None])
    d = P.T[None, :, :] + dd.attach[:, :, None] - E
    a0, a1, a2 = (dd.axis[:, i, None] for i in range(3))
    b = E - O
    E1 = np.stack(
        [a1 * b[:, 2] - a2 * b[:, 1], a2 * b[:, 0] - a0 * b[:, 2], a0 * b[:, 1] - a1 * b[:, 0]],
        axis=1,
    )
    p = d * E1
    g = 0.0 + p[:, 0] + p[:, 1] + p[:, 2]
    p = d * d
    dd2 = 0.0 + p[:, 0] + p[:, 1] + p[:, 2]
    p = E1 * E1
    scale = np.sqrt(dd2 * (0.0 + p[:, 0] + p[:, 1] + p[:, 2]))
    margin = np.min(np.abs(g) / np.where(scale > 0.0, scale, 1.0), axis=0)
    ok = ok & (margin > SINGULAR_TOL)
    g = np.where(ok[None, :], g, 1.0)
    Jinv = d / g[:, None, :]

    def rows(a: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(a.transpose(2, 0, 1))

    return ok, rows(Jinv), rows(E1), rows(d), reached, margin


def _outer(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[:, :, None] * b[:, None, :]


def _delta_mass(dd: DeltaDynamics, Jinv: np.ndarray, E1: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Nacelle-space mass matrix (N, 3, 3) of the kinetic energy, as a sum of outer products.

    With the arm rate ``alpha_dot_k = J_k . P_dot`` (``J_k`` row ``k`` of ``J_inv``), the elbow
    moves at ``E'_k alpha_dot_k``; per arm: the arm about its axis ``I_k J_k J_k^T``; its bars
    (centre of mass ``(1 - f) E + f P``, sums ``m_ee, m_ep, m_pp`` of
    :class:`pkdyn.dynamics.delta.DeltaDynamics`) ``m_ee |E'|^2 J J^T + m_ep (E' J^T + J E'^T) +
    m_pp I`` and, turning at ``u x (P_dot - E_dot) / L`` with no spin, ``I_t / L^2 X^T X`` with
    ``X^T X = I - u u^T - e J^T - J e^T + |u x E'|^2 J J^T`` (``e = E' - u (u . E')``); the
    nacelle ``m I``.
    """
    N = Jinv.shape[0]
    scalar = dd.nacelle_mass + float(np.sum(dd.m_pp))
    # Component-major, (arm, component, N) and (3, 3, N): the same products and sums in the same
    # order as on (N, 3) and (N, 3, 3) arrays, each a loop over the poses instead of N loops of
    # three; a sum over the three components is numpy's ``sum(axis=-1)``: 0 + x + y + z.
    Jk = np.ascontiguousarray(Jinv.transpose(1, 2, 0))
    E1k = np.ascontiguousarray(E1.transpose(1, 2, 0))
    dk = np.ascontiguousarray(d.transpose(1, 2, 0))
    Mt = np.zeros((3, 3, N))
    T, o = np.empty((3, 3, N)), np.empty((3, 3, N))
    oT = o.transpose(1, 0, 2)
    mul, add = np.multiply, np.add
    for k in range(3):
        J, e1 = Jk[k], E1k[k]
        u = dk[k] / dd.length[k]
        b = dd.inertia_t[k] / dd.length[k] ** 2
        p = u * e1
        ue = 0.0 + p[0] + p[1] + p[2]
        e = e1 - u * ue
        p = e1 * e1
        e1e1 = 0.0 + p[0] + p[1] + p[2]
        ux = e1e1 - ue**2  # |u x E'|^2
        a = dd.arm_axial[k] + dd.m_ee[k] * e1e1 + b * ux
        Jr = J[None, :, :]  # J_j, (1, 3, N)
        mul(J[:, None, :], Jr, out=T)  # a J J^T
        T *= a
        Mt += T
        # m_ep (E' J^T + J E'^T), as E' J^T plus its transpose: one outer product fewer
        mul(e1[:, None, :], Jr, out=o)
        add(o, oT, out=T)
        T *= dd.m_ep[k]
        Mt += T
        # b (u u^T + e J^T + J e^T)
        mul(e[:, None, :], Jr, out=o)
        mul(u[:, None, :], u[None, :, :], out=T)
        T += o
        T += oT
        T *= b
        Mt -= T
        scalar += b
    M = np.ascontiguousarray(Mt.transpose(2, 0, 1))
    M += scalar * np.eye(3)[None]
    return 0.5 * (M + np.swapaxes(M, 1, 2))


def _chol3(M: np.ndarray) -> np.ndarray:
    """Lower Cholesky factors (N, 3, 3) of symmetric positive definite 3x3 matrices."""
    L = np.zeros_like(M)
    L[:, 0, 0] = np.sqrt(M[:, 0, 0])
    L[:, 1, 0] = M[:, 1, 0] / L[:, 0, 0]
    L[:, 2, 0] = M[:, 2, 0] / L[:, 0, 0]
    L[:, 1, 1] = np.sqrt(M[:, 1, 1] - L[:, 1, 0] ** 2)
    L[:, 2, 1] = (M[:, 2, 1] - L[:, 2, 0] * L[:, 1, 0]) / L[:, 1, 1]
    L[:, 2, 2] = np.sqrt(M[:, 2, 2] - L[:, 2, 0] ** 2 - L[:, 2, 1] ** 2)
    return L


def delta_figures(
    robot: Robot,
    P: np.ndarray,
    k: np.ndarray,
    wrench: np.ndarray | None = None,
    frequency: bool = False,
) -> VectorisedFigures:
    """Figures of a library Delta (three arms, ball-jointed bars) at nacelle positions ``P``.

    ``K = J^T K_a J`` (3 x 3); the smallest principal stiffness is its smallest eigenvalue, the
    deflection ``|K^-1 F|``; the lowest frequency the smallest root of ``det(K - w^2 M_x) = 0``
    (``L^-1 K L^-T`` with ``M_x = L L^T``): 3 x 3 closed forms.
    """
    dd = DeltaDynamics(robot)
    P = np.atleast_2d(np.asarray(P, dtype=float))
    N = P.shape[0]
    ok, Jinv, E1, d, reached, margin = _delta_jacobian(dd, P)
    k = np.asarray(k, dtype=float)
    K = _gram(Jinv, k, slice(0, 3), slice(0, 3))
    kmin = sym3_min_eig(K)
    ok = ok & (kmin > _FREE * np.einsum("nii->n", K))
    kmin = np.where(ok, kmin, np.nan)
    defl = np.full(N, np.nan)
    if wrench is not None:
        C, _ = inv3(K)
        F = np.broadcast_to(np.asarray(wrench, dtype=float)[:3], (N, 3))
        defl = np.where(ok, np.linalg.norm(_mv(C, F), axis=-1), np.nan)
    f1 = np.full(N, np.nan)
    if frequency and ok.any():
        sel: np.ndarray | slice = slice(None) if ok.all() else ok  # (every pose: no copies)
        M = _delta_mass(dd, Jinv[sel], E1[sel], d[sel])
        L_inv, _ = inv3(_chol3(M))
        A = np.matmul(np.matmul(L_inv, K[sel]), np.swapaxes(L_inv, 1, 2))
        A = 0.5 * (A + np.swapaxes(A, 1, 2))
        f1[ok] = np.sqrt(np.maximum(sym3_min_eig(A), 0.0)) / (2.0 * np.pi)
    return VectorisedFigures(ok, kmin, defl, f1, reached, ok & (margin < NEAR_SERIAL_TOL))


def vectorised(robot: Robot, frequency: bool = False) -> str | None:
    """Which closed form applies to a robot: ``delta``, ``gough_stewart`` or ``None``.

    Library robots only, with no spring of their own (``robot.passive``); the Gough-Stewart has
    no frequency closed form here.
    """
    if robot.passive is not None or robot.params is None:
        return None
    if has_delta_dynamics(robot):
        return "delta"
    if robot.family == "gough_stewart" and not frequency:
        return "gough_stewart"
    return None
