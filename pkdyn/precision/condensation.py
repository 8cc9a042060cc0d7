"""Condensation of a virtual-joint model onto its platform, at one configuration.

Extended coordinates ``u`` (nv increments of the extended tree, applied by ``pin.integrate``:
joints, actuators, link deflections). The motions the closures allow (and the rigid actuators:
their rows ``e_i``) are ``u = N z``, ``N`` an orthonormal basis of the null space of the
constraint rows (an SVD: redundant rows, e.g. a hinge's two points or a hyperstatic mechanism's
repeated constraints, only lower their rank). The springs' stiffness ``K_u`` (nv, nv) becomes
``K_z = N^T K_u N``; the platform moves by ``d = J_z z``, ``J_z = J_p N``, with ``J_p`` the
Jacobian of the reference point (linear velocity, world axes) and of the platform's rotation
(angular velocity, world axes).

A static wrench ``w`` on the platform (force; moment about the reference point; world axes) is
balanced when ``K_z z = J_z^T w``, so ``d = C w`` with the compliance
``C = J_z K_z^+ J_z^T`` (6, 6). Directions of ``K_z`` without stiffness are internal mobilities
when they leave the platform still (a Delta bar's spin); when they move it, the mechanism is at
a parallel singularity (or lacks a spring) and the stiffness is undefined:
:class:`pkdyn.exceptions.SingularConfigurationError`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import SingularConfigurationError
from pkdyn.model.platform_jacobian import platform_jacobian
from pkdyn.precision.elastic import ElasticModel
from solvers import numerics

__all__ = [
    "FREE_TOL",
    "FREE_TOL_LOADED",
    "RANK_TOL",
    "Reduced",
    "compliance",
    "constraint_rows",
    "negligible",
    "platform_rows",
    "reduce",
    "spring_force",
]

RANK_TOL = 1e-9
"""Relative singular-value threshold of the constraint rows' rank (entries of order one)."""

FREE_TOL = 1e-12
"""Stiffness eigenvalues below this fraction of the largest are zero (no spring resists)."""

FREE_TOL_LOADED = 1e-8
"""The same for a loaded tangent stiffness (central differences: round-off about 1e-10)."""

_MOVES_TOL = 1e-7
"""A stiffness-free motion moves the platform when its (scale-aware) motion exceeds this, times
the largest motion any allowed direction gives the platform (at least 1: translations divided by
the robot's size, unit allowed motions; a mechanism whose allowed motions all leave the platform
still, every actuator held, is judged against that unit)."""


@dataclass(eq=False)  # numpy fields
class Reduced:
    """A virtual-joint model condensed at one configuration (see the module docstring).

    Attributes:
        q: Extended configuration.
        N: Allowed motions (nv, nz), orthonormal columns.
        Kz: Stiffness in ``z`` (nz, nz).
        Jz: Platform motion per ``z`` (6, nz): reference point [m], rotation [rad], world axes.
        Jp: Platform Jacobian (6, nv) in the same convention.
        placement: Platform frame placement.
        point: Reference point, world coordinates [m].
        free_tol: Relative threshold of a zero stiffness (:data:`FREE_TOL` or
            :data:`FREE_TOL_LOADED`).

    """

    q: np.ndarray
    N: np.ndarray
    Kz: np.ndarray
    Jz: np.ndarray
    Jp: np.ndarray
    placement: pin.SE3
    point: np.ndarray
    free_tol: float = FREE_TOL


def constraint_rows(em: ElasticModel, q: np.ndarray) -> np.ndarray:
    """Closure Jacobian and rigid-actuator rows (r, nv) at ``q`` (runs the joint Jacobians)."""
    r = em.robot
    if r.constraints.n:
        Jc = r.constraints.jacobian(r.data, q)
    else:
        pin.computeJointJacobians(r.model, r.data, q)
        Jc = np.zeros((0, r.nv))
    rigid = em.rigid_v
    if rigid.size:
        E = np.zeros((rigid.size, r.nv))
        E[np.arange(rigid.size), rigid] = 1.0
        Jc = np.vstack([Jc, E])
    return Jc


def platform_rows(em: ElasticModel, point: np.ndarray) -> tuple[np.ndarray, pin.SE3, np.ndarray]:
    """Platform Jacobian (6, nv) at the reference point (joint Jacobians already computed).

    :func:`pkdyn.model.platform_jacobian.platform_jacobian` with world axes (the precision
    convention).

    Args:
        em: The elastic model.
        point: Reference point in the platform frame [m].

    Returns:
        ``(Jp, placement, point_world)``.

    """
    r = em.robot
    J = platform_jacobian(r, None, point=point, angular="world")
    assert r.platform_frame is not None
    oMf = r.data.oMf[r.platform_frame]
    return J, pin.SE3(oMf), oMf.act(np.asarray(point, dtype=float))


def spring_force(em: ElasticModel, q: np.ndarray, qa_rest: np.ndarray) -> np.ndarray:
    """Generalized force (nv,) of every spring at ``q``: passive, virtual and actuators."""
    r = em.robot
    f = r.passive.conservative_force(q) if r.passive is not None else np.zeros(r.nv)
    k = em.actuator_stiffness
    finite = np.isfinite(k)
    iv, iq = np.asarray(r.actuated_v), np.asarray(r.actuated_q)
    f[iv[finite]] -= k[finite] * (q[iq[finite]] - qa_rest[finite])
    return f


def _needs_hessian(em: ElasticModel) -> bool:
    """Springs whose stiffness is not the diagonal alone: two-frame or on curved joints."""
    P = em.robot.passive
    if P is None:
        return False
    if any(s.stiffness > 0.0 for s in P.springs):
        return True
    model = em.robot.model
    deflection = set(np.asarray(em.deflection_v).ravel().tolist())
    for j in range(1, model.njoints):
        jm = model.joints[j]
        iv = range(jm.idx_v, jm.idx_v + jm.nv)
        if jm.nq != jm.nv and any(P.stiffness[i] > 0.0 and i not in deflection for i in iv):
            return True
    return False


def _spring_hessian_N(em: ElasticModel, q: np.ndarray, N: np.ndarray) -> np.ndarray:
    """``K_u N`` of the passive springs by central differences of their force (nv, nz)."""
    r = em.robot
    P = r.passive
    assert P is not None
    h = 1e-6 * max(r.length_scale, 1e-3)
    out = np.empty_like(N)
    for k in range(N.shape[1]):
        fp = P.conservative_force(pin.integrate(r.model, q, h * N[:, k]))
        fm = P.conservative_force(pin.integrate(r.model, q, -h * N[:, k]))
        out[:, k] = -(fp - fm) / (2.0 * h)
    return out


def reduce(
    em: ElasticModel,
    q: np.ndarray,
    point: np.ndarray,
    tangent: Callable[[np.ndarray], np.ndarray] | None = None,
) -> Reduced:
    """Condense the elastic model at ``q`` (extended configuration, assembled).

    Args:
        em: The elastic model.
        q: Extended configuration (nq,).
        point: Reference point in the platform frame [m].
        tangent: ``N -> K_u N`` (nv, nz), the loaded mode's tangent stiffness along the
            allowed motions; ``None``: the springs' stiffness at ``q`` (unloaded mode).

    Returns:
        The condensed model.

    """
    rows = constraint_rows(em, q)
    Jp, oMf, pw = platform_rows(em, point)
    N = numerics.null_space(rows, RANK_TOL, scale=1.0)
    if tangent is not None:
        KN = tangent(N)
    elif _needs_hessian(em):
        KN = _spring_hessian_N(em, q, N)
        iv = np.asarray(em.robot.actuated_v)
        ka = em.actuator_stiffness
        finite = np.isfinite(ka)
        KN[iv[finite]] += ka[finite, None] * N[iv[finite]]
    else:
        KN = em.spring_stiffness()[:, None] * N
    Kz = N.T @ KN
    Kz = 0.5 * (Kz + Kz.T) if tangent is None else Kz
    tol = FREE_TOL if tangent is None else FREE_TOL_LOADED
    return Reduced(q, N, Kz, Jp @ N, Jp, oMf, pw, tol)


def negligible(w: np.ndarray, rtol: float) -> np.ndarray:
    """Which eigenvalues ``w`` (of a symmetric stiffness or mass) count as zero.

    The rank rule of :mod:`solvers.numerics` applied to their magnitudes.
    """
    order = np.argsort(np.abs(w))[::-1]
    rank = numerics.rank_of(np.abs(w)[order], rtol)
    zero = np.ones(w.size, dtype=bool)
    zero[order[:rank]] = False
    return zero


def _scale(em: ElasticModel) -> np.ndarray:
    """Platform motion scale: 1/L for translations, 1 for rotations (dimensionless motions)."""
    L = em.robot.length_scale
    return np.array([1.0 / L] * 3 + [1.0] * 3)


def compliance(em: ElasticModel, red: Reduced) -> tuple[np.ndarray, int]:
    """Compliance ``C`` (6, 6) of the platform and the number of internal mobilities.

    Raises:
        SingularConfigurationError: A motion without stiffness moves the platform (parallel
            singularity, or a passive joint without a spring): the stiffness is undefined.

    """
    Kz = red.Kz
    if Kz.shape[0] == 0:
        return np.zeros((6, 6)), 0
    sym = float(np.max(np.abs(Kz - Kz.T))) <= 1e-9 * float(np.max(np.abs(Kz)))
    # (the tangent of a moment fixed in world axes is not symmetric: its zero and negative
    # directions are those of its symmetric part to first order)
    w, V = np.linalg.eigh(0.5 * (Kz + Kz.T))
    zero = negligible(w, red.free_tol)
    moving = _scale(em)[:, None] * (red.Jz @ V[:, zero])
    reach = np.abs(_scale(em)[:, None] * red.Jz).max() if red.Jz.size else 0.0
    if moving.size and float(np.abs(moving).max()) > _MOVES_TOL * max(reach, 1.0):
        raise SingularConfigurationError(
            "parallel",
            f"{em.base.name}: the platform can move without deforming any spring (parallel "
            "singularity, or a passive joint without a spring): the stiffness is undefined "
            "here",
        )
    if np.any(w[~zero] < 0.0):
        raise SingularConfigurationError(
            "parallel",
            f"{em.base.name}: the equilibrium is unstable (a negative stiffness "
            f"{float(w[~zero].min()):.3g}): the load buckles the mechanism",
        )
    if sym:
        JV = red.Jz @ V[:, ~zero]
        C = (JV / w[~zero]) @ JV.T
    else:
        # on the stiff subspace: K_z restricted to it, inverted
        Vk = V[:, ~zero]
        JV = red.Jz @ Vk
        C = JV @ np.linalg.solve(Vk.T @ Kz @ Vk, JV.T)
    return C, int(zero.sum())
