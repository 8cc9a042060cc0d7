"""Levenberg-Marquardt on the configuration manifold, for closure and pose equations.

The step solves ``min |J dq + r|^2 + lam |dq|^2`` on the free velocity coordinates, with
``lam = |r|^2`` (Yamashita-Fukushima), which keeps quadratic convergence even when the
equations are redundant (rank-deficient Jacobian, e.g. hinge closures), and takes the
minimum-norm step, so a projection moves the configuration as little as possible.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

__all__ = ["SolveResult", "solve_lm"]

ResidualFn = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass
class SolveResult:
    """Outcome of :func:`solve_lm`.

    Attributes:
        q: Final configuration (nq,).
        residual: Final residual vector.
        iterations: Number of accepted steps.
        converged: Whether ``max |residual| <= tol``.
    """

    q: np.ndarray
    residual: np.ndarray
    iterations: int
    converged: bool

    @property
    def error(self) -> float:
        """Largest absolute residual component [m or rad]."""
        return float(np.max(np.abs(self.residual))) if self.residual.size else 0.0


def solve_lm(
    model: pin.Model,
    q0: np.ndarray,
    fun: ResidualFn,
    free: np.ndarray | None = None,
    tol: float = 1e-12,
    max_iter: int = 60,
) -> SolveResult:
    """Solve ``fun(q) = 0`` for ``q`` on the model's configuration manifold.

    Args:
        model: Model whose ``integrate`` defines the manifold.
        q0: Initial configuration (nq,).
        fun: ``q -> (r, J)`` with residual (m,) and Jacobian (m, nv).
        free: Velocity indices allowed to move (default: all).
        tol: Convergence threshold on ``max |r|`` [m or rad].
        max_iter: Maximum number of iterations.

    Returns:
        The solution attempt; check ``converged``.
    """
    q = np.array(q0, dtype=float)
    r, J = fun(q)
    nv = model.nv
    idx = np.arange(nv) if free is None else np.asarray(free, dtype=int)
    it = 0
    err = float(np.max(np.abs(r))) if r.size else 0.0
    f = float(r @ r)
    mu = 1.0
    while err > tol and it < max_iter:
        Jf = J[:, idx]
        accepted = False
        for _ in range(12):
            lam = mu * f + 1e-16
            m, n = Jf.shape
            if m <= n:
                y = np.linalg.solve(Jf @ Jf.T + lam * np.eye(m), r)
                step = -Jf.T @ y
            else:
                step = -np.linalg.solve(Jf.T @ Jf + lam * np.eye(n), Jf.T @ r)
            dq = np.zeros(nv)
            dq[idx] = step
            q_new = pin.integrate(model, q, dq)
            r_new, J_new = fun(q_new)
            f_new = float(r_new @ r_new)
            if np.isfinite(f_new) and f_new < f:
                q, r, J, f = q_new, r_new, J_new, f_new
                mu = max(mu * 0.3, 1e-3)
                accepted = True
                break
            mu *= 10.0
        if not accepted:
            break
        it += 1
        err = float(np.max(np.abs(r))) if r.size else 0.0
    return SolveResult(q, r, it, err <= tol)
