"""The estimator of calibration: robust Levenberg-Marquardt with a weakly informative prior.

:func:`robust_fit` minimises

    ``1/2 sum_i w_i |r_i(z)|^2 + 1/2 sum_k (z_k / s_k)^2``

over the unknowns ``z`` (the estimated errors, then the unknowns of implicit measurements):
``r_i`` the residuals of measurement ``i`` divided by their standard deviations, ``w_i`` its
robust weight and ``s_k`` the prior standard deviation of unknown ``k`` (none: ``1/s_k^2 = 0``).

- **Steps**: Gauss-Newton with backtracking (1, 1/2, 1/4), then Marquardt's damping
  ``mu diag(A)`` for ``mu`` in :data:`DAMPING` when that does not decrease the cost (a persistent
  damping would crawl along ill-conditioned directions); the Jacobian is exact where the model is
  nonlinear (refreshed after a large decrease or a poor prediction) and kept otherwise.
- **Robust weights** (iteratively reweighted, Huber or Cauchy on each measurement's residual
  norm in units of its standard deviation, or of a robust scale estimate when the noise is not
  known): updated over the first :data:`IRLS_ROUNDS` accepted steps, then kept, so that the
  iterations converge on one weighted problem.
- **Convergence**: at the exact Jacobian, a step far below the unknowns' uncertainty (1e-3 of
  the standard deviation the normal matrix gives them), a relative decrease below 1e-7, or a
  decrease of the cost that is statistically nothing (below :data:`CHI2_TOL` times the degrees of
  freedom, the cost being half the chi-square: along a curved valley of weakly determined
  directions the steps crawl while the estimate stays well inside its uncertainty); or no step
  decreasing the cost at the exact Jacobian (a minimum within round-off).
- **Uncertainty**: the covariance ``s^2 A^-1`` (``A`` the weighted normal matrix with the prior,
  ``s`` the a-posteriori residual scale: near 1 when the standard deviations are the noise's).

The model is a pair of functions (residuals and Jacobian of an unknown vector), so the planner
(:mod:`pkdyn.calibration.planner`) and :func:`~pkdyn.calibration.calibrate` use one estimator.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkdyn.exceptions import PkdynError
from solvers import numerics

__all__ = ["DAMPING", "IRLS_ROUNDS", "ROBUST", "RobustFit", "robust_fit", "robust_weights"]

ROBUST = ("huber", "cauchy", "none")
"""Robust weights."""

DAMPING = (0.0, 1e-4, 1e-2, 1.0, 1e2)
"""Marquardt damping factors tried in turn when the Gauss-Newton step (with halving) does not
decrease the cost."""

IRLS_ROUNDS = 3
"""Accepted steps after which the robust weights are updated; then kept."""

CHI2_TOL = 1e-3
"""A decrease of the cost (half the chi-square) below this times the degrees of freedom is
statistically nothing (the estimate moves a small fraction of its uncertainty)."""

_HUBER_K = 2.5
_CAUCHY_K = 2.385


def robust_weights(u: np.ndarray, robust: str, known: bool) -> np.ndarray:
    """Robust weight of each measurement from its residual norm ``u`` (units of its sigma).

    Args:
        u: Residual norm of each measurement divided by ``sqrt(rows)`` (M,).
        robust: ``huber``, ``cauchy`` or ``none``.
        known: The standard deviations are the noise's (else the scale is estimated robustly:
            1.4826 times the median).

    Returns:
        Weights (M,) in (0, 1].

    """
    if robust == "none" or u.size == 0:
        return np.ones_like(u)
    scale = 1.0 if known else max(1.4826 * float(np.median(u)), 1e-300)
    t = u / scale
    if robust == "huber":
        return np.where(t <= _HUBER_K, 1.0, _HUBER_K / np.maximum(t, 1e-300))
    return 1.0 / (1.0 + (t / _CAUCHY_K) ** 2)


def inverse(A: np.ndarray) -> np.ndarray:
    """Inverse of a normal matrix (positive definite: its columns are identifiable).

    A pseudo-inverse cut at round-off (:mod:`solvers.numerics`) if it is singular after all.
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return np.linalg.inv(A)
    except np.linalg.LinAlgError:
        return numerics.lstsq(A, np.eye(A.shape[0]), numerics.machine_rtol(A))


@dataclass(eq=False)  # numpy fields
class RobustFit:
    """The outcome of :func:`robust_fit`.

    Attributes:
        z: The estimated unknowns (n,).
        state: The model's state at ``z`` (what the residual function returned).
        r: Weighted residuals at ``z`` (rows,).
        J: Weighted Jacobian at ``z`` (rows, n), exact.
        weights: Final robust weight of each measurement (M,).
        iterations: Iterations.
        converged: Whether the iterations converged (module docstring).
        scale: A-posteriori residual scale (RMS weighted residual, robust weights applied, in
            units of the standard deviations).
        std: Standard deviations of ``z`` (n,) (prior included).

    """

    z: np.ndarray
    state: Any
    r: np.ndarray
    J: np.ndarray
    weights: np.ndarray
    iterations: int
    converged: bool
    scale: float
    std: np.ndarray


def robust_fit(
    residual: Callable[[np.ndarray, Any], tuple[Any, np.ndarray]],
    jacobian: Callable[[np.ndarray, Any], np.ndarray],
    z0: np.ndarray,
    state0: Any,
    r0: np.ndarray,
    J0: np.ndarray,
    prior: np.ndarray,
    rows: int,
    robust: str = "huber",
    known: bool = True,
    max_iter: int = 30,
) -> RobustFit:
    """Robust Levenberg-Marquardt with a prior (module docstring).

    Args:
        residual: ``(z, start state) -> (state, weighted residuals (rows,))``; raises a pkdyn
            error where the model cannot be evaluated (the step is then refused).
        jacobian: ``(z, state) -> weighted Jacobian (rows, n)``.
        z0: Start (n,).
        state0: The model's state at ``z0``.
        r0: Weighted residuals at ``z0``.
        J0: Weighted Jacobian at ``z0``.
        prior: ``1 / s_k^2`` per unknown (n,) (0: no prior).
        rows: Residual rows per measurement (the robust weights are per measurement).
        robust: ``huber``, ``cauchy`` or ``none``.
        known: The standard deviations are the noise's.
        max_iter: Most iterations.

    Returns:
        The fit.

    """
    pw = np.asarray(prior, dtype=float)
    d = max(int(rows), 1)
    dof = max(r0.size - np.asarray(z0).size, 1)

    def weights_of(r: np.ndarray) -> np.ndarray:
        return robust_weights(
            np.linalg.norm(r.reshape(-1, d), axis=1) / math.sqrt(d), robust, known
        )

    def total(rr: np.ndarray, zz: np.ndarray, ww: np.ndarray) -> float:
        return 0.5 * float(np.sum(ww * rr**2)) + 0.5 * float(np.sum(pw * zz**2))

    z, state, r, J = np.array(z0, dtype=float), state0, r0, J0
    fresh = True
    w = weights_of(r)
    wr = np.repeat(w, d)
    cost = total(r, z, wr)
    iterations, converged, accepted = 0, False, 0
    for it in range(1, max_iter + 1):
        iterations = it
        A = J.T @ (wr[:, None] * J) + np.diag(pw)
        g = J.T @ (wr * r) + pw * z
        D = np.maximum(np.diag(A), 1e-12 * max(float(np.max(np.diag(A), initial=0.0)), 1e-300))
        found = None
        for mu in DAMPING:
            try:
                direction = np.linalg.solve(A + mu * np.diag(D), -g)
            except np.linalg.LinAlgError:
                continue
            for alpha in (1.0, 0.5, 0.25) if mu == 0.0 else (1.0,):
                delta = alpha * direction
                try:
                    state_new, r_new = residual(z + delta, state)
                    cost_new = total(r_new, z + delta, wr)
                except PkdynError:
                    continue
                if cost_new <= cost:
                    found = (delta, state_new, r_new, cost_new)
                    break
            if found is not None:
                break
        if found is None:  # no step decreases the cost: a minimum, within round-off
            if fresh:
                converged = True
                break
            J, fresh = jacobian(z, state), True
            continue
        delta, state_new, r_new, cost_new = found
        predicted = -float(g @ delta + 0.5 * delta @ (A @ delta))
        rho = (cost - cost_new) / max(predicted, 1e-300)
        decrease = (cost - cost_new) / max(cost, 1e-300)
        absolute = cost - cost_new
        # a step far below the unknowns' uncertainty changes nothing the measurements can tell
        unc = np.sqrt(np.maximum(np.diag(inverse(A)), 1e-300))
        small = bool(np.max(np.abs(delta) / unc, initial=0.0) < 1e-3)
        z, state, r = z + delta, state_new, r_new
        accepted += 1
        if accepted <= IRLS_ROUNDS and robust != "none":
            w = weights_of(r)
            wr = np.repeat(w, d)
        frozen = robust == "none" or accepted >= IRLS_ROUNDS
        cost = total(r, z, wr)
        negligible = absolute < CHI2_TOL * dof
        if frozen and (small or decrease < 1e-7 or negligible):
            if not fresh:  # the fixed point must be the exact Jacobian's
                J, fresh = jacobian(z, state), True
                continue
            converged = True
            break
        if decrease > 0.5 or rho < 0.9:  # far from the solution, or the model is off
            J, fresh = jacobian(z, state), True
        else:
            fresh = False
    if not fresh:
        J = jacobian(z, state)
    A = J.T @ (wr[:, None] * J) + np.diag(pw)
    s_hat = math.sqrt(float(np.sum(wr * r**2)) / dof)
    std = np.sqrt(np.maximum(np.diag(inverse(A)), 0.0)) * s_hat
    return RobustFit(z, state, r, J, w, iterations, converged, s_hat, std)
