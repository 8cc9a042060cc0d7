r"""The modal method: pose-dependent modes of the elastic model along the path, superposed.

Linearised about the commanded (rigid) motion ``q_c(t)``, the elastic model's deformation ``u``
(extended velocity coordinates, within the motions the closures allow) obeys

.. math::

    M(q_c) \ddot u + C \dot u + K(q_c) u = F(t), \qquad
    F = P_c \left[-\mathrm{RNEA}(q_c, v_c, a_c) + S^T \tau_{ff} + f_{passive}(q_c, v_c)\right]

``F`` the generalized force the commanded motion leaves unbalanced (its inertial and gravity
loads, payload included, less the actuators' feedforward, plus the robot's own springs and
dampers), projected by ``P_c`` on the motions the closures allow at that sample (the part their
reactions balance does no work on the deformation). Method:

- **modes at poses**: :func:`pkdyn.precision.modes.modes` (the same ``M`` and ``K``;
  mass-normalised shapes ``U_i``, platform motions ``P_i``, undamped ``omega_i``) at ``poses``
  commanded configurations spread evenly in time, first and last included;
- **interpolation between two poses** ``j`` and ``j + 1``: in the coordinates of pose ``j``'s
  integrated modes ``B = U_j``, the mass and stiffness are ``I`` and ``Omega_j^2`` at pose
  ``j``, and ``T^T T`` and ``T^T Omega_{j+1}^2 T`` at pose ``j + 1``, whose integrated modes
  ``U_{j+1}`` are seen through ``T = U_{j+1} M_{j+1} B^T`` (the platform motions alike,
  ``T^T P_{j+1}``); both are interpolated linearly in time to the middle of each sample
  interval, where their own modes (``omega``, shapes, ``P``) are taken; the damping
  ``B C B^T`` is that of the constant joint-space ``C`` (its modal off-diagonal terms
  neglected: exact for the damping-ratio model, which is proportional to the stiffness);
- **modal coordinates carried across** from one interval's modes to the next one's by the
  projection ``y' = V'^T M' V y`` (through the segment basis; and from basis ``U_j`` to
  ``U_{j+1}`` by ``T`` where the segment changes), the rates alike;
- **exact integration** on each interval of

  .. math::

      \ddot y_i + 2 \zeta_i \omega_i \dot y_i + \omega_i^2 y_i = V_i^T B F(t)

  for a forcing that is the cubic Hermite interpolant of its end values and rates (``F``'s rate
  from a cubic spline through the samples): particular polynomial plus free damped
  oscillation, evaluated in closed form anywhere in the interval (the dense output);
- the motion starts in the static equilibrium of the first interval (``y = V^T B F / omega^2``);
  after it the command rests at the end pose (its own modes) and the response is the closed
  form of constant coefficients;
- only the lowest ``count`` modes are integrated; the others respond quasi-statically
  (``U_i^T F / omega_i^2``, interpolated between poses: the static correction, so that the
  static deflection stays exact).

The platform deviation is ``d = sum_i P_i y_i`` (plus the quasi-static part).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.interpolate import CubicSpline

from pkdyn.exceptions import PkdynError
from pkdyn.precision.condensation import RANK_TOL, constraint_rows
from pkdyn.precision.elastic import ElasticModel
from pkdyn.precision.modes import mass_matrix, modes
from pkdyn.progress import progress as progress_bar
from solvers import numerics

__all__ = [
    "DEFAULT_POSES",
    "DEFAULT_POSES_LINKS",
    "ModalResponse",
    "PathModes",
    "loads",
    "modal_response",
    "path_modes",
]

DEFAULT_POSES = 33
"""Poses along the motion where the modes are computed (start and end included), rigid links."""

DEFAULT_POSES_LINKS = 65
"""The same with compliant links (their many modes change faster along the path)."""


@dataclass(eq=False)  # numpy fields
class PathModes:
    """Modes of the elastic model at poses along a motion.

    Attributes:
        samples: Command sample index of each pose (P,), increasing, first and last included.
        frequencies: Undamped natural frequencies (P, n) [Hz], ascending per pose.
        shapes: Mass-normalised mode shapes (P, n, nv_ext).
        platform: Platform motion per mode (P, n, 6): reference point [m], rotation [rad].
        mass: Mass matrix of the elastic model at each pose (P, nv_ext, nv_ext).
        internal: Internal mobilities without stiffness (not modes).
        coordinates: ``extended`` (the extended tree's velocity coordinates) or ``platform``
            (the platform's translation, world axes: the Delta's closed form,
            :mod:`pkdyn.precision.vibration_closed_form`); the shapes, mass, forces and damping
            of a response share them.

    """

    samples: np.ndarray
    frequencies: np.ndarray
    shapes: np.ndarray
    platform: np.ndarray
    mass: np.ndarray
    internal: int
    coordinates: str = "extended"

    @property
    def count(self) -> int:
        """Number of modes per pose."""
        return int(self.frequencies.shape[1])


def pose_samples(n: int, poses: int) -> np.ndarray:
    """``poses`` sample indices spread evenly over ``n`` samples (both ends included)."""
    return np.unique(np.round(np.linspace(0, n - 1, max(2, min(poses, n)))).astype(int))


def path_modes(
    em: ElasticModel,
    Q: np.ndarray,
    samples: np.ndarray,
    point: np.ndarray,
    progress: bool | None = None,
) -> PathModes:
    """Modes at the configurations ``Q[samples]`` of the robot as loaded (see the module).

    Args:
        em: The elastic model (its robot carries the payload).
        Q: Commanded configurations of the robot as loaded (N, nq).
        samples: Indices of the poses (P,).
        point: Reference point, platform frame [m].
        progress: Progress bar.

    Returns:
        The modes along the motion.

    Raises:
        PkdynError: The number of modes changes along the motion (a mobility appears or
            disappears: a singularity is near).
        SingularConfigurationError: A pose where the platform moves without stiffness.

    """
    found = []
    for k in progress_bar(list(samples), "modes along the motion", "pose", progress, min_items=50):
        found.append(modes(em, Q[int(k)], point=point))
    counts = {m.frequencies.size for m in found}
    if len(counts) > 1:
        k = next(
            int(s)
            for s, m in zip(samples, found, strict=True)
            if m.frequencies.size != found[0].frequencies.size
        )
        raise PkdynError(
            f"{em.base.name}: the number of elastic modes changes along the motion (at sample "
            f"{k}: {found[0].frequencies.size} -> {sorted(counts)}): a mobility appears, the "
            "motion passes near a singularity"
        )
    r = em.robot
    mass = np.array([mass_matrix(r, m.q_elastic) for m in found])
    return PathModes(
        samples=np.asarray(samples, dtype=int),
        frequencies=np.array([m.frequencies for m in found]),
        shapes=np.array([m.shapes for m in found]),
        platform=np.array([m.platform for m in found]),
        mass=mass,
        internal=int(found[0].internal),
    )


def loads(
    em: ElasticModel, Q: np.ndarray, V: np.ndarray, A: np.ndarray, tau_ff: np.ndarray
) -> np.ndarray:
    """Generalized force the commanded motion leaves unbalanced (N, nv_ext) [N m or N].

    ``-RNEA(q, v, a) + S^T tau_ff + f_passive(q, v)`` on the elastic model's robot (whose
    inertias carry the payload) at each commanded sample (module docstring), projected on the
    motions the closures (and the rigid actuators) allow there: the part the closures' reactions
    balance does no work on the deformation, and is removed so that a basis of neighbouring
    poses does not pick it up.
    """
    r = em.robot
    model, data = r.model, r.model.createData()
    iv = np.asarray(r.actuated_v)
    P = r.passive
    n = Q.shape[0]
    F = np.empty((n, r.nv))
    rows = []
    rnea = pin.rnea
    for k in range(n):
        f = -rnea(model, data, Q[k], V[k], A[k])
        if P is not None:
            f = f + P.force(Q[k], V[k])
        f[iv] += tau_ff[k]
        F[k] = f
        rows.append(constraint_rows(em, Q[k]))
    if not rows or rows[0].shape[0] == 0:
        return F
    J = np.array(rows)  # (N, r, nv)
    _, sv, Vt = np.linalg.svd(J)  # (batched)
    ranks = [numerics.rank_of(sv[k], RANK_TOL, 1.0) for k in range(n)]
    for rank in set(ranks):
        ks = np.flatnonzero(np.asarray(ranks) == rank)
        Vr = Vt[ks, :rank, :]  # the rows' range: the reactions' directions
        F[ks] -= np.einsum("krv,kr->kv", Vr, np.einsum("krv,kv->kr", Vr, F[ks]))
    return F


def _free(omega: np.ndarray, zeta: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(E C, E S)`` of a damped oscillator: ``e(tau) = EC e0 + ES (e0' + zeta omega e0)``.

    ``E = exp(-zeta omega tau)``, ``C = cos(omega_d tau)``, ``S = sin(omega_d tau) / omega_d``
    (their hyperbolic forms when over-damped), stable for any ``tau >= 0``.
    """
    sigma = zeta * omega
    disc = 1.0 - zeta * zeta
    under = disc >= 0.0
    wd = omega * np.sqrt(np.abs(disc))
    x = wd * tau
    E = np.exp(-sigma * tau)
    EC_u = E * np.cos(x)
    ES_u = E * tau * np.sinc(x / np.pi)
    # over-damped: exp(-(sigma -/+ a) tau) without overflow (only where over-damped)
    rate = np.where(under, sigma, sigma - wd)
    slow = np.exp(-rate * tau)
    fast_ratio = np.exp(-2.0 * np.where(under, 0.0, x))
    EC_o = 0.5 * slow * (1.0 + fast_ratio)
    xo = np.where(under, 1.0, x)
    sinhc = np.where(xo > 1e-12, -np.expm1(-2.0 * xo) / np.where(xo > 1e-12, 2.0 * xo, 1.0), 1.0)
    ES_o = slow * tau * sinhc
    return np.where(under, EC_u, EC_o), np.where(under, ES_u, ES_o)


def _particular(
    c: tuple[np.ndarray, ...], omega: np.ndarray, zeta: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Coefficients of the cubic particular solution of ``x'' + 2 z w x' + w^2 x = sum c_j t^j``."""
    c0, c1, c2, c3 = c
    w2 = omega * omega
    s2 = 2.0 * zeta * omega
    p3 = c3 / w2
    p2 = (c2 - 3.0 * s2 * p3) / w2
    p1 = (c1 - 2.0 * s2 * p2 - 6.0 * p3) / w2
    p0 = (c0 - s2 * p1 - 2.0 * p2) / w2
    return p0, p1, p2, p3


def _poly(p: tuple[np.ndarray, ...], tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p0, p1, p2, p3 = p
    return (
        p0 + tau * (p1 + tau * (p2 + tau * p3)),
        p1 + tau * (2.0 * p2 + tau * 3.0 * p3),
    )


@dataclass(eq=False)  # numpy fields
class ModalResponse:
    """What the modal method computes.

    Attributes:
        t: Output times (M,) [s] (every sample interval divided in ``sub`` steps, then the rest).
        d: Platform deviation at ``t`` (M, 6): reference point [m], rotation [rad], world axes.
        d_dot: Its rate (M, 6) [m/s, rad/s].
        t_coarse: Times of ``u`` (K,) [s]: the command's samples, then the same step at rest.
        u: Deformation at ``t_coarse`` (K, nv_ext) (in the coordinates of the modes).
        eta_end: Modal coordinates at the end of the motion (n_kept,), end-pose modes.
        eta_dot_end: Their rates (n_kept,).
        eta_static_end: Their static equilibrium at the end pose (n_kept,).
        zeta_end: Damping ratio of each kept mode at the end pose (n_kept,).
        zeta_middle: The same at the middle pose.

    """

    t: np.ndarray
    d: np.ndarray
    d_dot: np.ndarray
    t_coarse: np.ndarray
    u: np.ndarray
    eta_end: np.ndarray
    eta_dot_end: np.ndarray
    eta_static_end: np.ndarray
    zeta_end: np.ndarray
    zeta_middle: np.ndarray


def segments(pose_t: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Segment (pair of poses ``j, j + 1``) of each sample interval and its place in it.

    Args:
        pose_t: Times of the poses (P,) [s], increasing.
        t: Sample times (N,) [s].

    Returns:
        ``(seg, lam)``: the pose ``j`` starting the segment that holds each interval's middle
        (N - 1,), and the fraction of the segment at that middle (N - 1,), in ``[0, 1]``.

    """
    mid = 0.5 * (t[1:] + t[:-1])
    seg = np.clip(np.searchsorted(pose_t, mid, side="right") - 1, 0, pose_t.size - 2)
    lam = np.clip((mid - pose_t[seg]) / (pose_t[seg + 1] - pose_t[seg]), 0.0, 1.0)
    return seg, lam


def modal_response(
    pm: PathModes,
    pose_t: np.ndarray,
    t: np.ndarray,
    F: np.ndarray,
    damping: np.ndarray,
    count: int | None,
    sub: int,
    rest: float,
    ends: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> ModalResponse:
    """The modal response to the unbalanced force ``F`` (see the module docstring).

    Args:
        pm: Modes along the motion.
        pose_t: Time of each of its poses (P,) [s] (the first at 0, the last at the end).
        t: Command sample times (N,) [s], ``t[0] = 0``.
        F: Unbalanced generalized force at the samples (N, nv_ext).
        damping: Viscous damping per extended velocity coordinate (nv_ext,), or a damping
            matrix per pose (P, nv_ext, nv_ext) (``pm``'s coordinates).
        count: Modes integrated (the lowest; ``None``: all), the others quasi-static.
        sub: Output steps per sample interval.
        rest: Time simulated after the motion [s].
        ends: The forcing at both ends of each interval and its rates there,
            ``(F_left, F_right, F_left', F_right')`` (each (N - 1, nv_ext)), for a command
            whose acceleration jumps at its samples; default: ``F`` at the samples, its rates
            from a cubic spline through them.

    Returns:
        The response.

    """
    n_all = pm.count
    m = n_all if count is None else max(1, min(int(count), n_all))
    N = t.size
    K = N - 1
    P = pm.samples.size
    seg, lam = segments(np.asarray(pose_t, dtype=float), t)
    omega_all = 2.0 * np.pi * pm.frequencies  # (P, n)
    W2 = omega_all**2
    B = pm.shapes[:, :m]  # (P, m, nv): the basis of each segment
    PL = pm.platform[:, :m]  # (P, m, 6)
    BT = np.swapaxes(B, 1, 2)
    if damping.ndim == 1:
        Cb = (B * damping) @ BT  # damping in each basis (constant)
    else:
        Cb = B @ damping @ BT
    # the next pose's matrices in this pose's basis
    # (the next pose's integrated modes seen from this basis: B^T ~ U'^T T, T = U' M' B^T)
    T_all = B[1:] @ (pm.mass[1:] @ BT[:-1])  # (P-1, m, m)
    TT = np.swapaxes(T_all, 1, 2)
    K_end = (TT * W2[1:, None, :m]) @ T_all
    M_end = TT @ T_all
    P_end = TT @ PL[1:]
    # each interval: the segment's matrices interpolated at its middle, its own modes
    eye = np.eye(m)
    lk = lam[:, None, None]
    Mk = (1.0 - lk) * eye + lk * M_end[seg]
    Kk = (1.0 - lk) * np.einsum("km,mn->kmn", W2[seg, :m], eye) + lk * K_end[seg]
    Mk = 0.5 * (Mk + np.swapaxes(Mk, 1, 2))
    Kk = 0.5 * (Kk + np.swapaxes(Kk, 1, 2))
    L = np.linalg.cholesky(Mk)
    Li = np.linalg.inv(L)
    A = Li @ Kk @ np.swapaxes(Li, 1, 2)
    w2, Y = np.linalg.eigh(0.5 * (A + np.swapaxes(A, 1, 2)))
    if np.any(w2 <= 0.0):
        k = int(np.argwhere(w2 <= 0.0)[0, 0])
        raise PkdynError(
            f"the interpolated stiffness along the motion is not positive near t = {t[k]:.6g} s: "
            "the modes change too fast between poses; compute them at more poses"
        )
    V = np.swapaxes(Li, 1, 2) @ Y  # xi = V y, V^T M V = I
    w = np.sqrt(w2)  # (K, m)
    VT = np.swapaxes(V, 1, 2)
    z = np.einsum("kmi,kmi->ki", V, Cb[seg] @ V) / (2.0 * w)
    PLk = VT @ ((1.0 - lk) * PL[seg] + lk * P_end[seg])  # (K, m, 6)
    # modal forces at both ends of each interval, in its own modes
    dt = np.diff(t)
    if ends is None:
        spline = CubicSpline(t, F, axis=0, bc_type="not-a-knot") if N >= 4 else None
        Fd = spline(t, 1) if spline is not None else np.gradient(F, t, axis=0)
        ends = (F[:-1], F[1:], Fd[:-1], Fd[1:])
    FL, FR, FdL, FdR = ends
    BF = np.stack([FL, FR, FdL, FdR], axis=1)  # (K, 4, nv)
    if P < K:  # (by segment: fewer bases than intervals)
        BF = np.concatenate([BF[seg == j] @ B[j].T for j in range(P - 1)])
    else:
        BF = BF @ BT[seg]
    pF = BF @ V
    pL, pR, dL, dR = pF[:, 0], pF[:, 1], pF[:, 2], pF[:, 3]
    h = dt[:, None]
    c2 = (3.0 * (pR - pL) / h - 2.0 * dL - dR) / h
    c3 = (2.0 * (pL - pR) / h + dL + dR) / (h * h)
    Pp = _particular((pL, dL, c2, c3), w, z)
    x_h, v_h = _poly(Pp, h)
    EC, ES = _free(w, z, h)
    sig = z * w
    # transfer from each interval's modes to the next one's (through the segment basis)
    S = np.broadcast_to(eye, (K - 1, m, m)).copy()
    switch = np.flatnonzero(seg[1:] != seg[:-1])
    S[switch] = T_all[seg[switch]]
    G = VT[1:] @ (Mk[1:] @ (S @ V[:-1]))
    X, Vv, x, v = _march(pL[0] / w2[0], np.zeros(m), Pp, x_h, v_h, EC, ES, sig, w2, G)
    p0, p1 = Pp[0], Pp[1]
    # at the end of the motion: into the end pose's modes
    jL = int(seg[-1])
    to_end = T_all[jL] @ V[-1]
    eta_T = to_end @ x
    eta_dot_T = to_end @ v
    # dense output within the intervals
    frac = np.arange(sub) / sub
    tau = dt[:, None, None] * frac[None, :, None]  # (K, sub, 1)
    e0 = (X[:K] - p0)[:, None, :]
    ed0 = (Vv[:K] - p1)[:, None, :]
    xs, vs = _poly(tuple(pp[:, None, :] for pp in Pp), tau)
    ECs, ESs = _free(w[:, None, :], z[:, None, :], tau)
    sg = sig[:, None, :]
    xs = xs + ECs * e0 + ESs * (ed0 + sg * e0)
    vs = vs + ECs * ed0 - ESs * (w2[:, None, :] * e0 + sg * ed0)
    d = (xs @ PLk).reshape(K * sub, 6)
    dd = (vs @ PLk).reshape(K * sub, 6)
    t_in = (t[:K, None] + dt[:, None] * frac[None, :]).reshape(-1)
    # quasi-static part of the modes not integrated
    Ru = Rp = None
    if m < n_all:
        Uq = pm.shapes[:, m:]
        inv = 1.0 / W2[:, m:]
        Rp = np.swapaxes(pm.platform[:, m:] * inv[:, :, None], 1, 2) @ Uq
        Ru = np.swapaxes(Uq * inv[:, :, None], 1, 2) @ Uq
        # per interval, the two poses' maps blended at its middle, applied to the forcing's
        # end values and rates (the cubic interpolant is linear in them)
        lk = lam[:, None, None]
        Rk = (1.0 - lk) * Rp[seg] + lk * Rp[seg + 1]  # (K, 6, nv)
        projected = tuple(np.einsum("kcv,kv->kc", Rk, X) for X in ends)
        d += _hermite3(t, projected, sub)
        dd += _hermite3(t, projected, sub, derivative=True)
    # at rest after the motion: constant coefficients at the end pose
    jE = P - 1
    wE = omega_all[jE, :m]
    zE = np.diagonal(Cb[jE]) / (2.0 * wE)
    FE = F[-1]
    xsE = (B[jE] @ FE) / (wE * wE)
    h0 = float(dt[-1])
    n_rest = max(1, int(np.ceil(rest / h0 - 1e-9)))
    t_rest_c = t[-1] + h0 * np.arange(1, n_rest + 1)
    t_rest = t[-1] + (h0 / sub) * np.arange(0, n_rest * sub + 1)
    tau_r = (t_rest - t[-1])[:, None]
    eE = eta_T - xsE
    edE = eta_dot_T
    ECr, ESr = _free(wE[None, :], zE[None, :], tau_r)
    sE = zE * wE
    xr = xsE + ECr * eE + ESr * (edE + sE * eE)
    vr = ECr * edE - ESr * (wE * wE * eE + sE * edE)
    dr = xr @ PL[jE]
    ddr = vr @ PL[jE]
    if Rp is not None:
        dr += Rp[jE] @ FE
    # deformation at the command samples and at rest (for display)
    u = ((V @ X[:K, :, None])[:, :, 0][:, None, :] @ B[seg])[:, 0, :]
    u = np.vstack([u, eta_T @ B[jE], xr[sub::sub] @ B[jE]])
    if Ru is not None:
        segc = np.append(np.minimum(seg + np.rint(lam).astype(int), P - 1), [jE] * (n_rest + 1))
        Fc = np.vstack([F, np.tile(FE, (n_rest, 1))])
        for j in np.unique(segc):  # (by pose: no copy of a map per sample)
            at = segc == j
            u[at] += Fc[at] @ Ru[j].T
    jM = int(np.argmin(np.abs(np.asarray(pose_t) - 0.5 * t[-1])))
    zM = np.diagonal(Cb[jM]) / (2.0 * omega_all[jM, :m])
    return ModalResponse(
        t=np.concatenate([t_in, t_rest]),
        d=np.vstack([d, dr]),
        d_dot=np.vstack([dd, ddr]),
        t_coarse=np.concatenate([t, t_rest_c]),
        u=u,
        eta_end=eta_T,
        eta_dot_end=eta_dot_T,
        eta_static_end=xsE,
        zeta_end=zE,
        zeta_middle=zM,
    )


_PHI_ENTRIES = 2_000_000
"""Most entries of the stacked transition matrices of :func:`_march` (else a block loop)."""


def _march(
    x: np.ndarray,
    v: np.ndarray,
    Pp: tuple[np.ndarray, ...],
    x_h: np.ndarray,
    v_h: np.ndarray,
    EC: np.ndarray,
    ES: np.ndarray,
    sig: np.ndarray,
    w2: np.ndarray,
    G: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Modal coordinates and rates at the start of each interval, and at the end.

    Over interval ``k`` (its own modes, exact solution): with ``e = x - p0``, ``e' = v - p1``
    (the particular solution's value and rate at its start), ``x <- x_h + EC e + ES (e' +
    sigma e)`` and ``v <- v_h + EC e' - ES (w^2 e + sigma e')``, then into the next interval's
    modes by ``G``. Affine in ``(x, v)``: the maps are built for every interval at once
    (numpy) and applied in sequence.

    Returns:
        ``(X, V, x_end, v_end)``: (K + 1, m) each (the last row unset) and the state at the
        end of the last interval, in its modes.

    """
    K, m = EC.shape
    p0, p1 = Pp[0], Pp[1]
    a, b = EC + ES * sig, ES  # x' = a x + b v + ox
    c, d = -ES * w2, EC - ES * sig  # v' = c x + d v + ov
    ox = x_h - a * p0 - b * p1
    ov = v_h - c * p0 - d * p1
    X = np.empty((K + 1, m))
    Vv = np.empty((K + 1, m))
    if K * 4 * m * m <= _PHI_ENTRIES:
        Gf = np.concatenate([G, np.eye(m)[None]])  # (the last interval stays in its modes)
        Phi = np.empty((K, 2 * m, 2 * m))
        Phi[:, :m, :m] = Gf * a[:, None, :]
        Phi[:, :m, m:] = Gf * b[:, None, :]
        Phi[:, m:, :m] = Gf * c[:, None, :]
        Phi[:, m:, m:] = Gf * d[:, None, :]
        off = np.concatenate([Gf @ ox[:, :, None], Gf @ ov[:, :, None]], axis=1)[:, :, 0]
        S = np.empty((K + 1, 2 * m))
        s = np.concatenate([x, v])
        for k in range(K):
            S[k] = s
            s = Phi[k] @ s + off[k]
        X[:K], Vv[:K] = S[:K, :m], S[:K, m:]
        return X, Vv, s[:m], s[m:]
    for k in range(K):
        X[k] = x
        Vv[k] = v
        x, v = a[k] * x + b[k] * v + ox[k], c[k] * x + d[k] * v + ov[k]
        if k < K - 1:
            x = G[k] @ x
            v = G[k] @ v
    return X, Vv, x, v


def _hermite3(
    t: np.ndarray,
    ends: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    sub: int,
    derivative: bool = False,
) -> np.ndarray:
    """The forcing's cubic Hermite interpolant (or its rate) at ``sub`` points per interval."""
    FL, FR, FdL, FdR = ends
    h = np.diff(t)[:, None, None]
    s = (np.arange(sub) / sub)[None, :, None]
    y0, y1 = FL[:, None, :], FR[:, None, :]
    m0, m1 = FdL[:, None, :] * h, FdR[:, None, :] * h
    if derivative:
        out = (
            (6 * s * s - 6 * s) * y0
            + (3 * s * s - 4 * s + 1) * m0
            + (-6 * s * s + 6 * s) * y1
            + (3 * s * s - 2 * s) * m1
        ) / h
    else:
        s2, s3 = s * s, s * s * s
        out = (
            (2 * s3 - 3 * s2 + 1) * y0
            + (s3 - 2 * s2 + s) * m0
            + (-2 * s3 + 3 * s2) * y1
            + (s3 - s2) * m1
        )
    return out.reshape(-1, FL.shape[1])
