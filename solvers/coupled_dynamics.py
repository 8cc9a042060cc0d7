"""Constrained forward dynamics with joint couplings: one factorization per evaluation.

Pinocchio's ``pin.constraintDynamics`` takes 3D / 6D rigid constraints only (and rejects mimic
joints), so the couplings (:mod:`solvers.coupling`) of a constraint set act through their forces
``C^T mu``. The constrained acceleration is affine in the applied force:
``a(tau + C^T mu) = a0 + G mu``. One ``pin.constraintDynamics`` call at ``tau`` gives ``a0`` (and
the closures' multipliers ``lambda0``) and leaves the factorization of its regularised KKT
matrix ``K = [[-eps I, Jc], [Jc^T, M]]`` in ``data.constraint_chol``; ``G`` (and the closures'
response ``Lambda``) are read from it: the hard-constraint response to the forces ``C^T`` by
proximal iterations with that one factorization (``K [y; x] = [-eps y_prev; C^T]`` from
``y = 0``: ``Jc x = eps (y - y_prev)`` falls by ``eps / sigma`` per iteration, Pinocchio's own
scheme; ``Lambda = -y``). Without closures ``G = M^-1 C^T`` (``pin.computeMinverse``) and
``a0`` is ``pin.aba``'s. ``mu`` solves the couplings' acceleration equations
``C (a0 + G mu) = -gamma_c - Kd C v - Kp r_c`` (the closures' Baumgarte gains; minimum norm where
couplings are redundant with the closures), and ``a = a0 + G mu``.

One Pinocchio dynamics call and a few back-substitutions with its factorization (one matrix
right-hand side of ``k`` columns each), whatever the number ``k`` of couplings (the former
evaluation called ``pin.constraintDynamics`` ``k + 2`` times).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from solvers import numerics
from solvers.coupling import CouplingRows

__all__ = ["CoupledDynamics"]

_RTOL = 1e-12
"""Relative cut-off of the couplings' equations (:func:`solvers.numerics.lstsq`)."""


_LOWER: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _lower(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the strict lower triangle of an (n, n) matrix (made once per size)."""
    if n not in _LOWER:
        _LOWER[n] = np.tril_indices(n, -1)
    return _LOWER[n]


class CoupledDynamics:
    """Accelerations and forces of closures and couplings (see the module docstring).

    Args:
        model: The kinematic tree.
        rows: The couplings' rows.
        constraint_models: Pinocchio's constraint models of the closures (with their Baumgarte
            gains), or none.
        constraint_datas: Their datas (initialised for ``data``).
        data: The data the dynamics run in (``pin.initConstraintDynamics`` done).
        prox: Pinocchio's proximal settings (its ``mu`` is the regularisation ``eps`` of
            ``K``, its accuracy and iteration cap those of the response's iterations).
        gains: Baumgarte gains ``(Kp, Kd)`` of the couplings' residual.

    Attributes:
        lam: The closures' multipliers at the last evaluation (n_pin,), Pinocchio's
            convention (``data.lambda_c``).
        mu: The couplings' multipliers (k,) [N m or N] (:mod:`solvers.coupling`).

    """

    def __init__(
        self,
        model: pin.Model,
        rows: CouplingRows,
        constraint_models: pin.StdVec_RigidConstraintModel,
        constraint_datas: pin.StdVec_RigidConstraintData,
        data: pin.Data,
        prox: pin.ProximalSettings,
        gains: tuple[float, float],
    ) -> None:
        self.model = model
        self.rows = rows
        self.cms = constraint_models
        self.cds = constraint_datas
        self.data = data
        self.prox = prox
        self.gains = gains
        self.n_pin = int(
            sum(3 if cm.type == pin.ContactType.CONTACT_3D else 6 for cm in constraint_models)
        )
        self._C = np.zeros((rows.n, model.nv))
        self._rhs = np.zeros((self.n_pin + model.nv, rows.n))
        self.lam = np.zeros(self.n_pin)
        self.mu = np.zeros(rows.n)
        # the last evaluation's terms, for a caller that reuses its factorization
        self.G = np.zeros((model.nv, rows.n))
        self.CG = np.zeros((rows.n, rows.n))
        self.Minv: np.ndarray | None = None
        self._Li: np.ndarray | None = None  # the inverse Cholesky factor of CG, if certified
        self._lower = _lower(model.nv)
        self._lam0 = np.zeros(0)
        self._Lam = np.zeros((0, rows.n))
        # rows without a source: a constant Jacobian (filled once) and no drift
        self._constant = rows.constant
        if self._constant:
            rows.jacobian(np.zeros(model.nq), self._C)

    def acceleration(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Constrained acceleration (nv,) for generalized forces ``tau`` (nv,) [N m or N].

        The multipliers are left in :attr:`lam` (closures) and :attr:`mu` (couplings).
        """
        model, data, rows = self.model, self.data, self.rows
        C = self._C if self._constant else rows.jacobian(q, self._C)
        kp, kd = self.gains
        c = -kd * C.dot(v) - kp * rows.residual(q)
        if not self._constant:
            c -= rows.drift(q, v)
        if self.n_pin:  # (views on the data: used before the next call overwrites them)
            a0 = pin.constraintDynamics(model, data, q, v, tau, self.cms, self.cds, self.prox)
            lam0 = data.lambda_c
            G, Lam = self._response(C)
            self._Li = None
        else:
            a0 = np.array(pin.aba(model, data, q, v, tau))
            Minv = pin.computeMinverse(model, data, q)  # (a new array: its upper triangle)
            Minv[self._lower] = Minv.T[self._lower]
            self.Minv = Minv
            G = Minv.dot(C.T)
            lam0, Lam = self._lam0, self._Lam
        CG = C.dot(G)
        self.G, self.CG = G, CG
        if not self.n_pin and CG.shape[0] > 1:  # C M^-1 C^T: symmetric positive (semi)definite
            self._Li = numerics.lstsq_spd_factor(CG, _RTOL)
        self.mu = mu = self.solve(c - C.dot(a0))
        self.lam = lam0 + Lam.dot(mu) if self.n_pin else lam0
        return a0 + G.dot(mu)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """The coupling forces ``mu`` (k,) with ``C G mu = b``, ``G`` of the last evaluation.

        Minimum norm where couplings are redundant with the closures or one another. Without
        closures ``C G = C M^-1 C^T`` is solved by its Cholesky factor where that is certified
        to give the same solution (:func:`solvers.numerics.lstsq_spd_factor`).
        """
        CG = self.CG
        if CG.shape == (1, 1):  # one coupling: numerics.lstsq's rule, without its SVD
            return b / CG[0] if CG[0, 0] != 0.0 else np.zeros(1)
        Li = self._Li
        if Li is not None:
            return Li.T.dot(Li.dot(b))
        return numerics.lstsq(CG, b, _RTOL)

    def couple(self, x: np.ndarray, r: np.ndarray) -> np.ndarray:
        """``x + G mu`` with ``C (x + G mu) = r`` (the last evaluation's ``C``, ``G``).

        A motion ``x`` (nv,) that keeps the closures, made to move the couplings by ``r``
        (k,) in the mass metric.
        """
        return x + self.G.dot(self.solve(r - self._C.dot(x)))

    def _response(self, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Accelerations (nv, k) and closure forces (n_pin, k) per unit coupling force.

        Hard closures: proximal iterations with the factorization of the last dynamics call,
        until ``Jc x = eps (y - y_prev)`` is below the solver's accuracy (relative to ``x``).
        """
        nc = self.n_pin
        solve = self.data.constraint_chol.solve
        eps = self.prox.mu
        k = C.shape[0]
        rhs = self._rhs if k > 1 else self._rhs[:, 0]  # (a one-column solve is a vector)
        rhs[:nc] = 0.0
        rhs[nc:] = C.T if k > 1 else C[0]
        sol = solve(rhs)
        tol2 = (self.prox.absolute_accuracy / eps) ** 2
        for _ in range(self.prox.max_iter):
            y = sol[:nc]
            rhs[:nc] = -eps * y
            new = solve(rhs)
            d = (new[:nc] - y).ravel()
            x = new[nc:].ravel()
            sol = new
            if float(d.dot(d)) <= tol2 * max(1.0, float(x.dot(x))):
                break
        if k == 1:
            return sol[nc:, None], -sol[:nc, None]
        return sol[nc:], -sol[:nc]
