"""Physically consistent standard parameters that reproduce the identified base parameters.

The base parameters say nothing of the directions the efforts cannot see, and a least-squares
estimate can be non-physical (a negative mass, an inertia breaking the triangle inequality).
The description written back needs a full, physical set. First the least change of the nominal
values (in the metric ``D`` below) that reproduces the estimated base parameters exactly, a
linear least-norm problem; when every body it gives is strictly physical and no friction or
rotor inertia is negative, that is the answer. Otherwise a **constrained fit**:

- each identified body (and the payload) is parametrised by the log-Cholesky factor of its
  pseudo-inertia (Rucker and Wensing, 2022): ``P = [[Sigma, h], [h^T, m]] = U U^T`` with
  ``U = e^alpha [[e^d1, s12, s13, t1], [0, e^d2, s23, t2], [0, 0, e^d3, t3], [0, 0, 0, 1]]``,
  ``Sigma = tr(I)/2 1 - I``; every value of the 10 coordinates is a body of positive mass
  whose inertia satisfies the triangle inequality strictly (``P`` positive definite: a
  density can realise it), and every such body has coordinates;
- drive parameters (viscous and Coulomb friction, rotor inertia) are bounded below by zero;
- nonlinear least squares (scipy ``least_squares``, trust region) minimises
  ``|R (K theta - theta_b)|^2 + lambda^2 |D (theta - theta_nominal)|^2``: ``R`` the factor of the
  weighted regressor (the data misfit, in noise units), ``K`` the base map, ``D`` each
  parameter's effect on the efforts (column norm of the weighted regressor, or of the structural
  one for parameters the base leaves free) and ``lambda`` = :data:`PRIOR_WEIGHT`: the nominal
  values settle what the data cannot see without pulling on what it can.

When the estimate is physically realisable the fit reproduces it (to the small bias of the
prior); otherwise it is the nearest physical set in the metric of the data, and the reported
misfit says by how many standard deviations each base parameter moved.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from solvers import numerics

__all__ = [
    "MAX_EVALUATIONS",
    "PRIOR_WEIGHT",
    "consistent_parameters",
    "from_log_cholesky",
    "to_log_cholesky",
]

_LOG_CLIP = 200.0  # exponents kept finite during the solver's trial steps

MAX_EVALUATIONS = 100
"""Cap on the constrained fit's evaluations (every iterate is physical; each one lowers the
objective, so a capped fit is physical and no worse than its start)."""

PRIOR_WEIGHT = 1e-3
"""Weight of the pull to the nominal values, relative to the data misfit."""


def pseudo_inertia(pi: np.ndarray) -> np.ndarray:
    """Pseudo-inertia (4, 4) of Pinocchio dynamic parameters (10,) [kg, kg m, kg m^2]."""
    m, h = pi[0], pi[1:4]
    Ixx, Ixy, Iyy, Ixz, Iyz, Izz = pi[4:]
    I = np.array([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])
    P = np.zeros((4, 4))
    P[:3, :3] = 0.5 * np.trace(I) * np.eye(3) - I
    P[:3, 3] = P[3, :3] = h
    P[3, 3] = m
    return P


def _params(P: np.ndarray) -> np.ndarray:
    S = P[:3, :3]
    I = np.trace(S) * np.eye(3) - S
    return np.array(
        [P[3, 3], *P[:3, 3], I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]], dtype=float
    )


def from_log_cholesky(x: np.ndarray) -> np.ndarray:
    """Dynamic parameters (10,) of log-Cholesky coordinates (10,) (module doc)."""
    alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3 = x
    e = np.exp(np.clip([alpha, d1, d2, d3], -_LOG_CLIP, _LOG_CLIP))
    U = e[0] * np.array(
        [
            [e[1], s12, s13, t1],
            [0.0, e[2], s23, t2],
            [0.0, 0.0, e[3], t3],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )
    return _params(U @ U.T)


_ENTRIES = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))  # s12, s23, s13, t1, t2, t3


def _factors(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Factors ``U`` (n, 4, 4) and ``e^alpha`` (n,) of log-Cholesky coordinates (n, 10)."""
    e = np.exp(np.clip(X[:, :4], -_LOG_CLIP, _LOG_CLIP))
    U = np.zeros((X.shape[0], 4, 4))
    U[:, [0, 1, 2], [0, 1, 2]] = e[:, 1:]
    for k, (i, j) in enumerate(_ENTRIES):
        U[:, i, j] = X[:, 4 + k]
    U[:, 3, 3] = 1.0
    return U * e[:, :1, None], e[:, 0]


def _params_batch(P: np.ndarray) -> np.ndarray:
    """Dynamic parameters (n, 10) of pseudo-inertias (n, 4, 4) (linear in ``P``)."""
    S = P[:, :3, :3]
    tr = np.trace(S, axis1=1, axis2=2)
    return np.column_stack(
        [
            P[:, 3, 3],
            P[:, 0, 3],
            P[:, 1, 3],
            P[:, 2, 3],
            tr - S[:, 0, 0],
            -S[:, 0, 1],
            tr - S[:, 1, 1],
            -S[:, 0, 2],
            -S[:, 1, 2],
            tr - S[:, 2, 2],
        ]
    )


def from_log_cholesky_batch(X: np.ndarray) -> np.ndarray:
    """:func:`from_log_cholesky` of many bodies: (n, 10) -> (n, 10)."""
    U, _ = _factors(X)
    return _params_batch(U @ np.swapaxes(U, 1, 2))


def log_cholesky_jacobian_batch(X: np.ndarray) -> np.ndarray:
    """:func:`log_cholesky_jacobian` of many bodies: (n, 10) -> (n, 10, 10)."""
    n = X.shape[0]
    U, ea = _factors(X)
    dU = np.zeros((n, 10, 4, 4))
    dU[:, 0] = U
    for k in range(3):
        dU[:, 1 + k, k, k] = U[:, k, k]
    for k, (i, j) in enumerate(_ENTRIES):
        dU[:, 4 + k, i, j] = ea
    dP = dU @ np.swapaxes(U, 1, 2)[:, None]
    dP = dP + np.swapaxes(dP, 2, 3)
    out = _params_batch(dP.reshape(n * 10, 4, 4)).reshape(n, 10, 10)
    return np.swapaxes(out, 1, 2)


def log_cholesky_jacobian(x: np.ndarray) -> np.ndarray:
    """Derivative (10, 10) of :func:`from_log_cholesky` at ``x``.

    Exact: ``dP = dU U^T + U dU^T``, and the parameters are linear in ``P``.
    """
    alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3 = x
    e = np.exp(np.clip([alpha, d1, d2, d3], -_LOG_CLIP, _LOG_CLIP))
    U = e[0] * np.array(
        [[e[1], s12, s13, t1], [0.0, e[2], s23, t2], [0.0, 0.0, e[3], t3], [0.0, 0.0, 0.0, 1.0]]
    )
    out = np.empty((10, 10))
    for k in range(10):
        dU = np.zeros((4, 4))
        if k == 0:
            dU = U
        elif k <= 3:
            dU[k - 1, k - 1] = U[k - 1, k - 1]
        else:
            dU[_ENTRIES[k - 4]] = e[0]
        dP = dU @ U.T
        out[:, k] = _params(dP + dP.T)
    return out


def to_log_cholesky(pi: np.ndarray, scale: float) -> np.ndarray:
    """Log-Cholesky coordinates (10,) of dynamic parameters, made strictly physical if needed.

    Args:
        pi: Dynamic parameters (10,).
        scale: A mass [kg] for a body without one (a payload starting from zero).

    Returns:
        Coordinates of ``pi``, or of the nearest strictly physical body (eigenvalues of the
        pseudo-inertia raised to a small positive floor).

    """
    P = pseudo_inertia(pi)
    if P[3, 3] <= 0.0:
        P = np.diag([1e-6, 1e-6, 1e-6, 1.0]) * max(scale, 1e-9)
    w, V = np.linalg.eigh(P)
    floor = 1e-9 * max(float(w.max()), 1e-300)
    P = (V * np.maximum(w, floor)) @ V.T
    F = np.flip(np.eye(4), axis=0)  # upper factor through the lower Cholesky of the flipped P
    L = np.linalg.cholesky(F @ P @ F)
    U = F @ L @ F
    a = U[3, 3]
    U = U / a
    return np.array(
        [np.log(a), np.log(U[0, 0]), np.log(U[1, 1]), np.log(U[2, 2])]
        + [U[0, 1], U[1, 2], U[0, 2], U[0, 3], U[1, 3], U[2, 3]]
    )


def _physical(theta: np.ndarray, bodies: list[slice], nonnegative: np.ndarray) -> bool:
    """Every body strictly physical (positive definite pseudo-inertia) and bounds kept."""
    if np.any(theta[nonnegative] < 0.0):
        return False
    for s in bodies:
        P = pseudo_inertia(theta[s])
        w = np.linalg.eigvalsh(P)
        if w[0] <= 1e-9 * max(float(w[-1]), 1e-300):
            return False
    return True


def consistent_parameters(
    K: np.ndarray,
    R: np.ndarray,
    theta_b: np.ndarray,
    nominal: np.ndarray,
    bodies: list[slice],
    nonnegative: np.ndarray,
    effect: np.ndarray,
) -> np.ndarray:
    """The constrained fit of the module doc, on the identified standard parameters.

    Args:
        K: Base map (p_b, p).
        R: Triangular factor (p_b, p_b) of the weighted base regressor.
        theta_b: Estimated base parameters (p_b,).
        nominal: Nominal standard parameters (p,).
        bodies: Column slices of each body (10 columns each) to keep physical.
        nonnegative: Columns bounded below by zero (p,) bool.
        effect: Effect of each parameter on the efforts (p,) (the metric ``D``), > 0.

    Returns:
        Physically consistent standard parameters (p,).

    """
    p = nominal.size
    D = PRIOR_WEIGHT * effect
    # the least deviation from nominal (metric D) that reproduces the base parameters exactly:
    # the answer when it is physical
    KD = K / effect
    step = numerics.lstsq(KD, theta_b - K @ nominal, numerics.machine_rtol(KD))
    linear = nominal + step / effect
    if _physical(linear, bodies, nonnegative):
        return linear
    in_body = np.zeros(p, dtype=bool)
    for s in bodies:
        in_body[s] = True
    free = np.flatnonzero(~in_body)
    scale_m = float(max((nominal[s][0] for s in bodies), default=1.0) or 1.0)
    x0 = [linear[free]]
    for s in bodies:
        x0.append(to_log_cholesky(linear[s], 1e-3 * scale_m))
    x0v = np.concatenate(x0) if x0 else np.zeros(0)
    nf = free.size
    lo = np.full(x0v.size, -np.inf)
    lo[:nf] = np.where(nonnegative[free], 0.0, -np.inf)
    x0v[:nf] = np.maximum(x0v[:nf], lo[:nf])

    cols = np.array([np.arange(s.start, s.start + 10) for s in bodies], dtype=int).reshape(-1, 10)

    def theta(x: np.ndarray) -> np.ndarray:
        out = np.empty(p)
        out[free] = x[:nf]
        if len(bodies):
            out[cols] = from_log_cholesky_batch(x[nf:].reshape(-1, 10))
        return out

    def residual(x: np.ndarray) -> np.ndarray:
        th = theta(x)
        return np.concatenate([R @ (K @ th - theta_b), D * (th - nominal)])

    RK = R @ K

    def jacobian(x: np.ndarray) -> np.ndarray:
        dth = np.zeros((p, x.size))
        dth[free, np.arange(nf)] = 1.0
        if len(bodies):
            blocks = log_cholesky_jacobian_batch(x[nf:].reshape(-1, 10))
            for k in range(len(bodies)):
                dth[cols[k], nf + 10 * k : nf + 10 * k + 10] = blocks[k]
        return np.vstack([RK @ dth, D[:, None] * dth])

    if x0v.size == 0:
        return nominal.copy()
    with np.errstate(over="ignore", invalid="ignore"):  # trial steps may overflow: rejected
        sol = least_squares(
            residual,
            x0v,
            jac=jacobian,
            bounds=(lo, np.inf),
            method="trf",
            ftol=1e-12,
            xtol=1e-12,
            gtol=1e-12,
            max_nfev=MAX_EVALUATIONS,
        )
    return theta(sol.x)
