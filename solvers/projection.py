"""Projection of a state onto the closures: ``q`` by Gauss-Newton, ``v`` in the mass metric.

``q`` is moved by minimum-norm Gauss-Newton / Levenberg-Marquardt steps on a
:class:`~solvers.constraints.ConstraintSet`; then ``v+`` minimises the kinetic energy of ``v+ - v``
under ``J v+ = 0`` (the velocity after a perfectly inelastic impulse, which never adds
energy; Euclidean norm if the mass matrix is singular).
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pinocchio as pin

from solvers import numerics
from solvers.constraints import ConstraintSet
from solvers.lm import solve_lm

__all__ = ["ProjectionError", "project_state"]


class ProjectionError(RuntimeError):
    """The closures cannot be restored from the given configuration."""


def project_state(
    model: pin.Model,
    data: pin.Data,
    closure_set: ConstraintSet,
    q: np.ndarray,
    v: np.ndarray,
    aim: float,
    accept: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Project ``(q, v)`` onto the closures.

    Args:
        model: The kinematic tree.
        data: Scratch data of ``model``.
        closure_set: The constraints (closures and couplings).
        q: Configuration (nq,).
        v: Velocity (nv,).
        aim: Closure residual the Gauss-Newton iterations aim at [m or rad].
        accept: Largest residual accepted [m or rad].

    Returns:
        The projected ``(q, v)``.

    Raises:
        ProjectionError: The residual stays above ``accept``.

    """
    cs = closure_set
    sol = solve_lm(
        model,
        q,
        partial(cs.local_residual, data),
        partial(cs.local_jacobian_after_residual, data),
        tol=aim,
    )
    if sol.error > accept:
        raise ProjectionError(
            f"the closures cannot be restored (residual {sol.error:.3g} after projection)"
        )
    q = sol.q
    J = cs.jacobian(data, q)
    Jv = J @ v
    if not Jv.any():  # v keeps the closures already (a start at rest): y = 0
        return q, np.array(v, dtype=float)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    try:
        L = np.linalg.cholesky(M)
    except np.linalg.LinAlgError:  # massless bodies: Euclidean projection instead
        return q, v - numerics.lstsq(J, Jv, 1e-10)
    # v+ = v - M^-1 J^T y with (J M^-1 J^T) y = J v (minimum-norm y for redundant closures)
    B = np.linalg.solve(L, J.T)  # L^-1 J^T
    BB = B.T @ B
    Li = numerics.lstsq_spd_factor(BB, 1e-12) if BB.shape[0] > 1 else None
    y = Li.T @ (Li @ Jv) if Li is not None else numerics.lstsq(BB, Jv, 1e-12)
    return q, v - np.linalg.solve(L.T, B @ y)
