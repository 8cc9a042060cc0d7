"""Inverse dynamics that minimises the largest actuator effort under redundant actuation.

:class:`MinMaxInverseDynamics` is :class:`~solvers.inverse_dynamics.InverseDynamics` with another
effort distribution when the actuation is redundant: instead of the least weighted norm it
minimises the largest scaled effort ``max_i |tau_i| / s_i``, with ``s_i = 1 / sqrt(w_i)`` (the
effort limits with the weights ``1 / limit^2``, so that every actuator is loaded to the same
fraction of its limit when possible). Everything else (the null-space reduction to ``E tau = f``,
the bounds, the closure forces, the errors) is the parent's.

In the scaled efforts ``u = tau / s`` the problem is the QP over ``(u, t)``::

    minimise    t^2 + eps |u|^2
    subject to  E S u = f,   -t <= u_i <= t,   lower_i / s_i <= u_i <= upper_i / s_i

(``S = diag(s)``): ``t >= 0`` is implied and minimising ``t^2`` minimises ``t``; the small ``eps``
(relative ``1e-6``) makes the QP strictly convex and picks, among the distributions of least
maximum, the one of least norm. Solved by proxsuite, warm-started along a trajectory (and solved
again from scratch when the warm start fails: the rows of ``E``, a basis of the reduced
equations, may turn from one sample to the next).
"""

from __future__ import annotations

import numpy as np
from proxsuite import proxqp

from solvers.inverse_dynamics import InfeasibleError, InverseDynamics, _where

__all__ = ["INFEASIBILITY_TOL", "MINMAX_REGULARISATION", "MinMaxInverseDynamics"]

MINMAX_REGULARISATION = 1e-6
"""Weight ``eps`` of the norm of the scaled efforts beside the squared largest one."""

INFEASIBILITY_TOL = 1e-14
"""proxqp's primal and dual infeasibility thresholds for the min-max QP (its default, 1e-4,
declared feasible problems with small right-hand sides infeasible)."""


class MinMaxInverseDynamics(InverseDynamics):
    """:class:`~solvers.inverse_dynamics.InverseDynamics` minimising the largest scaled effort.

    Same arguments as the parent; ``weights`` set the scales ``s = 1 / sqrt(weights)``.
    """

    def _qp_solve(
        self, E: np.ndarray, f: np.ndarray, scale: float, sample: int | None
    ) -> tuple[np.ndarray, int]:
        """Efforts of least largest scaled value under ``E tau = f`` and the bounds."""
        n = self.actuation.n
        rg = E.shape[0]
        s = 1.0 / np.sqrt(self.weights)
        s_max = float(np.max(s))
        A = np.hstack([E * (s / s_max), np.zeros((rg, 1))])  # rows scaled like u
        # unknowns u / c, with c the size of the right-hand side: proxqp's tolerances are
        # absolute, and a problem of tiny (or huge) efforts looked infeasible to it
        c = float(np.max(np.abs(f))) / s_max or 1.0
        b = f / (s_max * c)
        H = np.diag(np.r_[np.full(n, MINMAX_REGULARISATION), 1.0])
        g = np.zeros(n + 1)
        eye = np.eye(n)
        ones = np.ones((n, 1))
        rows = [np.hstack([eye, -ones]), np.hstack([eye, ones])]  # u - t <= 0 <= u + t
        lo = [np.full(n, -1e20), np.zeros(n)]
        hi = [np.zeros(n), np.full(n, 1e20)]
        if self._bounded:
            rows.append(np.hstack([eye, np.zeros((n, 1))]))
            lo.append(np.where(np.isfinite(self.lower), self.lower / (s * c), -1e20))
            hi.append(np.where(np.isfinite(self.upper), self.upper / (s * c), 1e20))
        C, l_c, u_c = np.vstack(rows), np.concatenate(lo), np.concatenate(hi)
        eps_abs = self.eps * scale / (s_max * c)  # the parent's accuracy on E tau = f
        iterations = 0
        status = None
        # warm start from the previous sample, then (the rows of E are a basis of the reduced
        # equations that may turn from one sample to the next) from scratch
        previous = self._qp if self._qp_rank == rg else None
        for qp in (previous, None) if previous is not None else (None,):
            if qp is not None:
                qp.settings.eps_abs = eps_abs
                qp.update(A=A, b=b, l=l_c, u=u_c)  # bounds scale with c
            else:
                qp = proxqp.dense.QP(n + 1, rg, C.shape[0])
                qp.settings.eps_rel = 0.0
                qp.settings.max_iter = max(self.max_iter, 1000)
                qp.settings.verbose = False
                qp.settings.initial_guess = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
                qp.settings.eps_abs = eps_abs
                # proxqp's default infeasibility threshold (1e-4, absolute) misfires on these
                # small right-hand sides (f / s_max ~ 1e-2): a feasible problem was declared
                # infeasible after 9 iterations. Without bounds the problem is always feasible;
                # with bounds a true infeasibility ends at max_iter and is explained below.
                qp.settings.eps_primal_inf = INFEASIBILITY_TOL
                qp.settings.eps_dual_inf = INFEASIBILITY_TOL
                qp.init(H, g, A, b, C, l_c, u_c)
                self._qp, self._qp_rank = qp, rg
            qp.solve()
            iterations += int(qp.results.info.iter)
            status = qp.results.info.status
            tau = (s * c) * np.array(qp.results.x[:n])
            ok = status == proxqp.QPSolverOutput.PROXQP_SOLVED
            if ok and self._bounded:
                tol = 1e3 * self.eps * scale
                ok = bool(np.all(tau >= self.lower - tol) and np.all(tau <= self.upper + tol))
            if ok:
                return tau, iterations
        self._qp = None  # a failed solve is no warm start
        if self._bounded:
            self._raise_bounds(E, f, sample)
        raise InfeasibleError(
            f"{_where(sample)}the min-max effort QP did not converge ({status})",
            sample=sample,
        )
