"""The loaded mode: the elastic model's static equilibrium under a wrench, and its tangent.

Under a static wrench ``w`` on the platform (force; moment about the reference point; world
axes, both fixed in the world: a dead load) and optionally the robot's weight, the springs
deform: the actuators are held at their commanded positions ``qa_0`` by springs of stiffness
``k_a``, the joint and link springs about their rest positions. The equilibrium on the extended
tree, with the closure forces ``lambda``::

    G(q, lambda) = f_s(q) + J_p(q)^T w - g(q) + J_c(q)^T lambda = 0,      c(q) = 0

(``f_s`` the springs' generalized force, ``g`` the generalized gravity, ``J_c`` the constraint
rows). It is solved by Newton's method on the closure manifold: at each iterate ``lambda`` is
the least-squares balance of ``G`` on the constraint rows, the step solves
``K_z dz = N^T G`` along the allowed motions ``N``, and the configuration is projected back onto
the closures. The tangent stiffness ``K_T = -dG/du`` at fixed ``lambda`` holds the springs'
stiffness and the **geometric terms** of the load: the derivatives of the platform Jacobian
contracted with ``w`` and of the constraint rows contracted with the reactions ``lambda`` (the
Hessians of the kinematics and of the closures); it is evaluated by central differences of
``G`` along the allowed motions (exact to about 1e-9 relative; any row of the closure set is
differentiated the same way).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pkdyn.exceptions import PkdynError
from pkdyn.precision.condensation import (
    RANK_TOL,
    constraint_rows,
    platform_rows,
    spring_force,
)
from pkdyn.precision.elastic import ElasticModel
from solvers import SolveResult, numerics, solve_lm

__all__ = ["Equilibrium", "loaded_equilibrium", "reassembled"]

_MAX_ITER = 40


@dataclass(eq=False)  # numpy fields
class Equilibrium:
    """A loaded static equilibrium of an elastic model.

    Attributes:
        q: Extended configuration at equilibrium.
        lambdas: Constraint forces at equilibrium (rows of :func:`constraint_rows`).
        iterations: Newton iterations.
        residual: Norm of the unbalanced generalized force along the allowed motions [N, N m].

    """

    q: np.ndarray
    lambdas: np.ndarray
    iterations: int
    residual: float


def _force(
    em: ElasticModel,
    q: np.ndarray,
    qa_rest: np.ndarray,
    point: np.ndarray,
    w: np.ndarray,
    gravity: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """``(G without the reactions, constraint rows)`` at ``q``."""
    r = em.robot
    rows = constraint_rows(em, q)  # (joint Jacobians at q)
    Jp, _, _ = platform_rows(em, point)
    g = spring_force(em, q, qa_rest) + Jp.T @ w
    if gravity:
        g -= pin.computeGeneralizedGravity(r.model, r.data, q)
    return g, rows


def tangent_along(
    em: ElasticModel,
    q: np.ndarray,
    lambdas: np.ndarray,
    qa_rest: np.ndarray,
    point: np.ndarray,
    w: np.ndarray,
    gravity: bool,
    N: np.ndarray,
) -> np.ndarray:
    """``K_T N`` (nv, nz): minus the derivative of ``G`` at fixed ``lambda`` along ``N``."""
    r = em.robot
    h = 1e-6 * max(r.length_scale, 1e-3)
    out = np.empty_like(N)
    for k in range(N.shape[1]):
        G = []
        for s in (h, -h):
            qs = pin.integrate(r.model, q, s * N[:, k])
            g, rows = _force(em, qs, qa_rest, point, w, gravity)
            G.append(g + rows.T @ lambdas)
        out[:, k] = -(G[0] - G[1]) / (2.0 * h)
    return out


def reassembled(em: ElasticModel, q: np.ndarray, tol: float = 1e-10) -> SolveResult:
    """Close the loops of the elastic model's robot near ``q``, its rigid coordinates held.

    Levenberg-Marquardt on the constraint residual over the free coordinates (every velocity
    coordinate but ``em.rigid_v``), from ``q``.

    Args:
        em: The elastic model (its robot has constraints: ``robot.constraints.n > 0``).
        q: Configuration (nq,) near an assembled one.
        tol: Residual tolerance of the solve.

    Returns:
        The solve: ``q`` assembled when ``converged``.

    """
    r = em.robot
    cs, data = r.constraints, r.data
    return solve_lm(
        r.model,
        q,
        lambda x: cs.local_residual(data, x),
        lambda x: cs.local_jacobian_after_residual(data, x),
        free=np.setdiff1d(np.arange(r.nv), em.rigid_v),
        tol=tol,
    )


def _project(em: ElasticModel, q: np.ndarray) -> np.ndarray:
    if em.robot.constraints.n == 0:
        return q
    sol = reassembled(em, q, tol=1e-13)
    if not sol.converged:
        raise PkdynError(
            f"{em.base.name}: the loaded mechanism cannot be kept assembled (closure residual "
            f"{sol.error:.3g}): the load deforms it too far for a linear spring model"
        )
    return sol.q


def loaded_equilibrium(
    em: ElasticModel,
    q0: np.ndarray,
    point: np.ndarray,
    w: np.ndarray,
    gravity: bool = False,
    tol: float = 1e-10,
) -> Equilibrium:
    """Static equilibrium of the elastic model under a platform wrench (module docstring).

    Args:
        em: The elastic model.
        q0: Extended configuration without load (the actuators' commanded positions).
        point: Reference point of the wrench, platform frame [m].
        w: Wrench (6,): force [N], moment about the point [N m], world axes.
        gravity: Include the robot's weight (``model.gravity``).
        tol: Convergence: unbalanced force below ``tol`` times the load's scale.

    Returns:
        The equilibrium.

    Raises:
        PkdynError: No equilibrium found (the load is beyond what the springs hold, or the
            configuration is singular).

    """
    r = em.robot
    qa_rest = np.array(q0[np.asarray(r.actuated_q)])
    q = np.array(q0, dtype=float)
    L = r.length_scale
    scale = float(np.linalg.norm(w[:3]) + np.linalg.norm(w[3:]) / L)
    if gravity:
        mass = sum(r.model.inertias[j].mass for j in range(r.model.njoints))
        scale += float(mass * np.linalg.norm(r.model.gravity.linear))
    scale = max(scale, 1e-12)
    lam = np.zeros(0)
    res = np.inf
    for it in range(1, _MAX_ITER + 1):
        g, rows = _force(em, q, qa_rest, point, w, gravity)
        N = numerics.null_space(rows, RANK_TOL, scale=1.0)
        # least-squares reactions: rows^T lam = -g on the range of rows^T
        lam = numerics.lstsq(rows.T, -g, RANK_TOL, scale=1.0) if rows.shape[0] else np.zeros(0)
        rz = N.T @ g
        res = float(np.linalg.norm(rz))
        if res <= tol * scale:
            return Equilibrium(q, lam, it - 1, res)
        KN = tangent_along(em, q, lam, qa_rest, point, w, gravity, N)
        Kz = N.T @ KN
        dz = numerics.lstsq(Kz, rz, 1e-12)
        q = _project(em, pin.integrate(r.model, q, N @ dz))
    raise PkdynError(
        f"{em.base.name}: no static equilibrium under this load after {_MAX_ITER} Newton "
        f"iterations (unbalanced {res:.3g}): the load exceeds what the springs hold, or the "
        "configuration is singular"
    )
