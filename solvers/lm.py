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
ResidualJacobianFn = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]

_NEWTON_DAMPING = 1e-3
"""Below this damping (``mu |r|^2``, against ``|J|^2`` of order one: near a solution) a square
system first tries the undamped Newton step (one linear solve instead of three products, and
quadratic convergence); if it does not reduce the residual, the damped steps follow."""


@dataclass(eq=False)  # numpy fields: no boolean ==
class SolveResult:
    """Outcome of :func:`solve_lm`.

    Attributes:
        q: Final configuration (nq,).
        residual: Final residual vector.
        iterations: Number of accepted steps.
        converged: Whether ``max |residual| <= tol``.
        error: Largest absolute residual component [m or rad] (computed when not given).
        jacobian: The last Jacobian evaluated (at the last iterate but one when the solver
            stopped on convergence; ``None`` when none was), all columns.

    """

    q: np.ndarray
    residual: np.ndarray
    iterations: int
    converged: bool
    error: float = -1.0
    jacobian: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.error < 0.0:
            self.error = float(np.abs(self.residual).max()) if self.residual.size else 0.0


def solve_lm(
    model: pin.Model,
    q0: np.ndarray,
    residual: ResidualFn | None = None,
    jacobian: JacobianFn | None = None,
    free: np.ndarray | None = None,
    tol: float = 1e-12,
    max_iter: int = 60,
    *,
    residual_and_jacobian: ResidualJacobianFn | None = None,
    stall: float = 0.0,
) -> SolveResult:
    """Solve ``residual(q) = 0`` for ``q`` on the model's configuration manifold.

    With ``residual`` and ``jacobian``, trial steps evaluate only the residual and the Jacobian
    is evaluated at accepted points that have not converged yet, always right after the
    residual at the same configuration (so ``jacobian`` may reuse what ``residual`` computed,
    e.g. :meth:`solvers.ConstraintSet.jacobian_after_residual`). With ``residual_and_jacobian``
    both come from one evaluation at every trial point (cheaper when a residual costs nearly as
    much as both, as with Pinocchio's C++ constraint Jacobian: one evaluation per iteration when
    the steps are accepted, the usual case near a solution).

    Args:
        model: Model whose ``integrate`` defines the manifold.
        q0: Initial configuration (nq,).
        residual: ``q -> r`` (m,).
        jacobian: ``q -> J`` (m, nv), derivative of ``residual`` for increments applied by
            ``pin.integrate``.
        free: Velocity indices allowed to move (default: all).
        tol: Convergence threshold on ``max |r|`` [m or rad].
        max_iter: Maximum number of iterations.
        residual_and_jacobian: ``q -> (r, J)``, instead of ``residual`` and ``jacobian``.
        stall: Stop early (not converged) when three accepted steps in a row each keep more than
            this fraction of ``|r|^2`` (the iterations approach a least-squares minimum that is
            not a solution, e.g. an unreachable pose); 0 disables the test.

    Returns:
        The solution attempt; check ``converged``.

    Raises:
        ValueError: Neither ``residual`` and ``jacobian`` nor ``residual_and_jacobian`` given.

    """
    both = residual_and_jacobian
    if both is None and (residual is None or jacobian is None):
        raise ValueError("solve_lm needs residual and jacobian, or residual_and_jacobian")
    q = np.array(q0, dtype=float)
    J: np.ndarray | None = None
    if both is not None:
        r, J = both(q)
    else:
        assert residual is not None
        r = residual(q)
    nv = model.nv
    idx = None if free is None else np.asarray(free, dtype=np.intp)
    it = 0
    err = float(np.abs(r).max()) if r.size else 0.0
    f = float(r @ r)
    mu = 1.0
    slow = 0
    dq = np.zeros(nv)
    solve = np.linalg.solve
    integrate = pin.integrate
    J_last: np.ndarray | None = None
    while err > tol and it < max_iter:
        if J is None:
            assert jacobian is not None
            J = jacobian(q)
        J_last = J
        Jf = J if idx is None else J[:, idx]
        rows, cols = Jf.shape
        small = rows <= cols
        A: np.ndarray | None = None
        accepted = False
        for trial in range(12):
            damping = mu * f + 1e-16
            step = None
            if rows == cols and trial == 0 and damping < _NEWTON_DAMPING:
                # square and near a solution: Newton's step first (one solve)
                try:
                    step = -solve(Jf, r)
                except np.linalg.LinAlgError:
                    step = None
            if step is None:
                if A is None:
                    A = Jf.dot(Jf.T) if small else Jf.T.dot(Jf)
                    g = r if small else Jf.T.dot(r)
                    A0 = A.diagonal().copy()
                    diag = A.reshape(-1)[:: A.shape[0] + 1]  # writable view of the diagonal
                diag[:] = A0 + damping
                try:
                    y = solve(A, g)
                except np.linalg.LinAlgError:  # exactly singular: damping below round-off
                    y = numerics.lstsq(A, g, numerics.machine_rtol(A))
                step = -Jf.T.dot(y) if small else -y
            if idx is None:
                dq = step
            else:
                dq[idx] = step
            q_new = integrate(model, q, dq)
            if both is not None:
                r_new, J_new = both(q_new)
            else:
                assert residual is not None
                r_new, J_new = residual(q_new), None
            f_new = float(r_new.dot(r_new))
            if f_new < f:  # False for NaN
                slow = slow + 1 if f_new > stall * f else 0
                q, r, f, J = q_new, r_new, f_new, J_new
                mu = max(mu * 0.3, 1e-3)
                accepted = True
                break
            mu *= 10.0
        if not accepted:
            break
        it += 1
        err = float(np.abs(r).max()) if r.size else 0.0
        if stall > 0.0 and slow >= 3 and err > tol:
            break
    return SolveResult(q, r, it, err <= tol, err, J_last)
