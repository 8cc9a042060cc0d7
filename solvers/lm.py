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

from solvers import numerics

__all__ = ["SolveResult", "solve_lm"]

ResidualFn = Callable[[np.ndarray], np.ndarray]
JacobianFn = Callable[[np.ndarray], np.ndarray]


@dataclass(eq=False)  # numpy fields: no boolean ==
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
    residual: ResidualFn,
    jacobian: JacobianFn,
    free: np.ndarray | None = None,
    tol: float = 1e-12,
    max_iter: int = 60,
) -> SolveResult:
    """Solve ``residual(q) = 0`` for ``q`` on the model's configuration manifold.

    Trial steps evaluate only the residual; the Jacobian is evaluated at accepted points that
    have not converged yet.

    Args:
        model: Model whose ``integrate`` defines the manifold.
        q0: Initial configuration (nq,).
        residual: ``q -> r`` (m,).
        jacobian: ``q -> J`` (m, nv), derivative of ``residual`` for increments applied by
            ``pin.integrate``.
        free: Velocity indices allowed to move (default: all).
        tol: Convergence threshold on ``max |r|`` [m or rad].
        max_iter: Maximum number of iterations.

    Returns:
        The solution attempt; check ``converged``.

    """
    q = np.array(q0, dtype=float)
    r = residual(q)
    nv = model.nv
    idx = None if free is None else np.asarray(free, dtype=int)
    it = 0
    err = float(np.abs(r).max()) if r.size else 0.0
    f = float(r @ r)
    mu = 1.0
    dq = np.zeros(nv)
    solve = np.linalg.solve
    while err > tol and it < max_iter:
        J = jacobian(q)
        Jf = J if idx is None else J[:, idx]
        small = Jf.shape[0] <= Jf.shape[1]
        A = Jf @ Jf.T if small else Jf.T @ Jf
        g = r if small else Jf.T @ r
        A0 = A.diagonal().copy()
        diag = A.reshape(-1)[:: A.shape[0] + 1]  # writable view of the diagonal
        accepted = False
        for _ in range(12):
            diag[:] = A0 + (mu * f + 1e-16)
            try:
                y = solve(A, g)
            except np.linalg.LinAlgError:  # exactly singular: the damping fell below round-off
                y = numerics.lstsq(A, g, numerics.machine_rtol(A))
            step = -(Jf.T @ y) if small else -y
            if idx is None:
                dq = step
            else:
                dq[idx] = step
            q_new = pin.integrate(model, q, dq)
            r_new = residual(q_new)
            f_new = float(r_new @ r_new)
            if f_new < f:  # False for NaN
                q, r, f = q_new, r_new, f_new
                mu = max(mu * 0.3, 1e-3)
                accepted = True
                break
            mu *= 10.0
        if not accepted:
            break
        it += 1
        err = float(np.abs(r).max()) if r.size else 0.0
    return SolveResult(q, r, it, err <= tol)
