"""Rank decisions, null spaces and least squares: one cut-off rule for the whole project.

**The rule.** A singular value ``s_i`` of a matrix ``A`` counts (is not zero) when

    ``s_i > rtol * max(s_max, scale)``

with ``s_max`` the largest singular value of ``A``. The numerical rank of ``A`` is the number of
singular values that count; its null space is spanned by the right singular vectors of the
others; least squares invert only the ones that count (minimum-norm solution).

- ``rtol`` (relative tolerance) defaults to :data:`RTOL`; a caller that knows how accurate its
  matrix is passes its own (the mobility analysis' ``tol``, ...) and documents it.
- ``scale`` (default 0: the matrix is its own reference) is a magnitude the caller knows the
  matrix is measured against: a well-scaled larger matrix this one is a block or a product of
  (``|T|`` for ``T N`` with orthonormal ``N``), 1 for matrices of orthonormal columns or
  Jacobians in SI units whose entries are of order one (so that a matrix that is all tiny
  values has rank 0 instead of being judged against itself).
- A matrix whose singular values are all zero has rank 0 (the cut-off is then 0 and no value
  exceeds it).

Everything that decides a rank (mobility, kinematic models, singularities, trajectory mapping,
constrained inverse dynamics, state projection, the identifiability of calibration and dynamic
identification) goes through this module, and so does the **elimination of the passive joints**
(:func:`passive_elimination`: the one rule by which the kinematic models, the pose sensitivities
of accuracy and calibration, and the motions of identification solve the closures for the
passive rates). Robot-agnostic (numpy only).

**Identifiability** (:func:`column_basis`): the same rule on the diagonal of a QR factorisation
of the columns (:func:`column_qr`), each column scaled by what its caller knows of it (unit
columns by default): the independent columns, and of what combination of them each other column
is (the base-parameter map of dynamic identification, the unidentifiable combinations of
calibration).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "IDENTIFIABILITY_RTOL",
    "RTOL",
    "ZERO_RTOL",
    "ColumnBasis",
    "ColumnQR",
    "PassiveElimination",
    "column_basis",
    "column_qr",
    "cutoff",
    "left_null_space",
    "lstsq",
    "lstsq_null",
    "lstsq_spd_factor",
    "machine_rtol",
    "null_space",
    "passive_elimination",
    "passive_solve",
    "range_space",
    "rank",
    "rank_of",
    "scaled_margins",
]

RTOL = 1e-9
"""Default relative tolerance of the cut-off rule (closure Jacobians assembled to ~1e-12 and of
order one in SI units sit well above it; exact rank losses fall to ~1e-15 below it)."""


def machine_rtol(A: np.ndarray) -> float:
    """``eps * max(m, n)``: the relative tolerance of round-off alone (numpy's default).

    Args:
        A: Matrix (m, n).

    Returns:
        The tolerance.

    """
    return float(np.finfo(float).eps * max(A.shape[-2:], default=1))


def cutoff(s: np.ndarray, rtol: float = RTOL, scale: float = 0.0) -> float:
    """The threshold ``rtol * max(s_max, scale)`` of singular values ``s`` (see the module).

    Args:
        s: Singular values, largest first (k,).
        rtol: Relative tolerance.
        scale: Reference magnitude (0: ``s_max`` alone).

    Returns:
        Singular values above this count.

    """
    s_max = float(s[0]) if s.size else 0.0
    return rtol * max(s_max, scale)


def rank_of(s: np.ndarray, rtol: float = RTOL, scale: float = 0.0) -> int:
    """Numerical rank from singular values ``s`` (largest first).

    Args:
        s: Singular values (k,).
        rtol: Relative tolerance.
        scale: Reference magnitude (0: ``s_max`` alone).

    Returns:
        The number of singular values above :func:`cutoff`.

    """
    if s.size == 0:
        return 0
    return int(np.count_nonzero(s > cutoff(s, rtol, scale)))


def rank(A: np.ndarray, rtol: float = RTOL, scale: float = 0.0) -> int:
    """Numerical rank of ``A`` (m, n).

    Args:
        A: Matrix (m, n).
        rtol: Relative tolerance.
        scale: Reference magnitude (0: ``s_max`` alone).

    Returns:
        The rank.

    """
    if A.size == 0:
        return 0
    return rank_of(np.linalg.svd(A, compute_uv=False), rtol, scale)


def null_space(A: np.ndarray, rtol: float = RTOL, scale: float = 0.0) -> np.ndarray:
    """Orthonormal basis of the null space of ``A`` (m, n).

    Args:
        A: Matrix (m, n); no rows gives the identity.
        rtol: Relative tolerance.
        scale: Reference magnitude (0: ``s_max`` alone).

    Returns:
        Basis (n, n - rank) as columns.

    """
    n = A.shape[1]
    if A.shape[0] == 0:
        return np.eye(n)
    _, s, Vt = np.linalg.svd(A)
    return np.ascontiguousarray(Vt[rank_of(s, rtol, scale) :].T)


def left_null_space(A: np.ndarray, rtol: float = RTOL, scale: float = 0.0) -> np.ndarray:
    """Orthonormal basis of the left null space of ``A`` (m, n): rows ``w`` with ``w A = 0``.

    Args:
        A: Matrix (m, n); no columns gives the identity.
        rtol: Relative tolerance.
        scale: Reference magnitude (0: ``s_max`` alone).

    Returns:
        Basis (m - rank, m) as rows.

    """
    m = A.shape[0]
    if A.shape[1] == 0:
        return np.eye(m)
    U, s, _ = np.linalg.svd(A, full_matrices=True)
    return np.asarray(U[:, rank_of(s, rtol, scale) :].T)


def range_space(A: np.ndarray, rtol: float = RTOL, scale: float = 0.0) -> np.ndarray:
    """Orthonormal basis of the range (column space) of ``A`` (m, n).

    Args:
        A: Matrix (m, n).
        rtol: Relative tolerance.
        scale: Reference magnitude (0: ``s_max`` alone).

    Returns:
        Basis (m, rank) as columns.

    """
    U, s, _ = np.linalg.svd(A, full_matrices=False)
    return np.asarray(U[:, : rank_of(s, rtol, scale)])


def lstsq(A: np.ndarray, b: np.ndarray, rtol: float = RTOL, scale: float = 0.0) -> np.ndarray:
    """Minimum-norm least-squares solution of ``A x = b``, small singular values cut off.

    Args:
        A: Matrix (m, n).
        b: Right-hand side (m,) or (m, k).
        rtol: Relative tolerance.
        scale: Reference magnitude (0: ``s_max`` alone).

    Returns:
        ``x`` (n,) or (n, k).

    """
    return _lstsq(A, b, rtol, scale, False)[0]


def lstsq_null(
    A: np.ndarray, b: np.ndarray, rtol: float = RTOL, scale: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`lstsq` and the null space of ``A`` from the same decomposition.

    Args:
        A: Matrix (m, n).
        b: Right-hand side (m,) or (m, k).
        rtol: Relative tolerance.
        scale: Reference magnitude (0: ``s_max`` alone).

    Returns:
        ``(x, N)``: the solution and an orthonormal basis (n, n - rank) of the null space.

    """
    return _lstsq(A, b, rtol, scale, True)


def _lstsq(
    A: np.ndarray, b: np.ndarray, rtol: float, scale: float, full: bool
) -> tuple[np.ndarray, np.ndarray]:
    n = A.shape[1]
    bb = np.asarray(b, dtype=float)
    if A.shape[0] == 0:
        return np.zeros((n,) + bb.shape[1:]), np.eye(n)
    U, s, Vt = np.linalg.svd(A, full_matrices=full)
    r = rank_of(s, rtol, scale)
    y = U[:, :r].T @ bb
    y = y / (s[:r] if bb.ndim == 1 else s[:r, None])
    return Vt[:r].T @ y, np.ascontiguousarray(Vt[r:].T)


def lstsq_spd_factor(A: np.ndarray, rtol: float = RTOL) -> np.ndarray | None:
    """The inverse Cholesky factor of a symmetric ``A`` on which :func:`lstsq` cuts nothing off.

    For a symmetric positive definite ``A`` (k, k) (a Delassus or Schur complement ``C M^-1
    C^T``) the solution of ``A x = b`` is ``L^-T (L^-1 b)`` with ``A = L L^T``: a Cholesky
    factorization costs a fraction of :func:`lstsq`'s SVD. It equals :func:`lstsq`'s
    minimum-norm solution (to round-off) when no singular value of ``A`` falls below the
    cut-off ``rtol s_max``, which is certified from the factor itself:
    ``s_min >= 1 / |L^-1|_F^2`` and ``s_max <= trace(A)``, with a margin of 10. Only the
    lower triangle of ``A`` is read.

    Args:
        A: Symmetric matrix (k, k), k >= 1.
        rtol: :func:`lstsq`'s relative tolerance.

    Returns:
        ``L^-1`` (k, k), lower triangular, or ``None`` where ``A`` is not positive definite or
        its conditioning is not certified (then call :func:`lstsq`).

    """
    lapack = _lapack()
    L, info = lapack.dpotrf(A, lower=1, clean=1)
    if info != 0:
        return None
    Li, info = lapack.dtrtri(L, lower=1)
    if info != 0:
        return None
    inv_norm2 = float(np.vdot(Li, Li))  # >= |A^-1|_2 = 1 / s_min
    if not inv_norm2 * float(np.trace(A)) * 10.0 * rtol < 1.0:  # (NaN: not certified)
        return None
    return np.asarray(Li)


def _lapack() -> Any:
    """SciPy's LAPACK wrappers (imported on first use: SciPy takes a while to import)."""
    import scipy.linalg.lapack

    return scipy.linalg.lapack


def scaled_margins(
    A: np.ndarray,
    B: np.ndarray,
    a_scale: np.ndarray,
    x_scale: np.ndarray,
    rtol: float = RTOL,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scale-aware singularity margins of velocity relations ``A x_dot = B qa_dot``.

    **The singularity rule.** The relations are rewritten in dimensionless rates (each rate
    divided by its ``scale``: a length for translations and prismatic actuators, 1 for angles),
    then ``[B', -A']`` is orthonormalised (rows beyond the numerical rank of the relations, by
    the cut-off rule with ``rtol``, become zero: a degenerate mobility makes both singular). The
    singular values of ``A'`` and ``B'`` lie in ``[0, 1]`` and are compared with *absolute*
    thresholds by the caller: a uniform collapse of ``B`` (every Delta arm stretched along its
    bars at once), which leaves ``cond(B)`` near 1, is seen; a mechanism scaled by any factor
    gets the same margins; translations and rotations weigh alike.

    Args:
        A: Parallel matrices (..., r, m), any normalisation: ``r = m`` relations, or
            ``r = n_a > m`` under redundant actuation (one relation per actuator).
        B: Serial matrices (..., r, n_a), the same normalisation.
        a_scale: Scale of each actuator rate (n_a,) (a length for prismatic ones, else 1).
        x_scale: Scale of each task rate (m,) (a length for translations, else 1).
        rtol: Relative tolerance of the relations' rank.

    Returns:
        ``(sigma_A, sigma_B, rows)``: singular values of ``A'`` (..., min(r, m)) and ``B'``
        (..., min(r, n_a)), largest first, and the orthonormal relation rows ``[B', -A']``
        (..., r, n_a + m).

    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    r, n_a = A.shape[-2], B.shape[-1]
    R = np.concatenate([B * np.asarray(a_scale), -A * np.asarray(x_scale)], axis=-1)
    _, s, Vt = np.linalg.svd(R, full_matrices=False)
    s_r = np.zeros(s.shape[:-1] + (r,))
    s_r[..., : min(r, s.shape[-1])] = s[..., :r]
    live = s_r > rtol * s[..., :1]
    rows = np.zeros(Vt.shape[:-2] + (r, Vt.shape[-1]))
    k = min(r, Vt.shape[-2])
    rows[..., :k, :] = Vt[..., :k, :]
    rows = np.where(live[..., None], rows, 0.0)
    sA = np.linalg.svd(-rows[..., n_a:], compute_uv=False)
    sB = np.linalg.svd(rows[..., :n_a], compute_uv=False)
    return sA, sB, rows


# ----------------------------------------------------------------------------------------------
# Identifiability: which columns of a matrix are independent, and how the others combine
#
# Calibration (the identification Jacobian of the measured poses) and dynamic identification
# (the regressor of the efforts) ask the same question of a matrix ``A`` (m, p) whose columns
# are the effects of p parameters: which parameters can the data tell apart, and of what
# combination of those is each other parameter's effect? Both answer it here, with the rule
# above applied to the diagonal of a Householder QR factorisation of the scaled columns.

ZERO_RTOL = 1e-12
"""A column whose norm is at most this fraction of the largest column's (or of ``scale``) has no
effect at all: round-off of an exact zero (sensitivities and regressors are exact to ~1e-10)."""

IDENTIFIABILITY_RTOL = 1e-7
"""Default ``rtol`` of :func:`column_basis` on unit columns: structural losses of rank fall to
~1e-12, while a column only 1e-7 away from the span of the others would amplify a 1e-5 noise to
a metre (calibration) or leave its parameter undetermined (identification)."""

_CLEAN = 1e-9  # combination coefficients below this fraction of their column's largest: round-off


@dataclass(frozen=True, eq=False)  # numpy fields
class ColumnQR:
    """A Householder QR factorisation ``A[:, perm] = Q R`` stopped at the numerical rank.

    Attributes:
        R: Upper-trapezoidal factor (min(m, n), n) in the order ``perm``; rows beyond ``rank``
            hold the round-off of the dependent columns.
        perm: Column order (n,): the ``rank`` independent columns first.
        rank: Number of columns whose distance to the span of the columns before them passed
            the cut-off.

    """

    R: np.ndarray
    perm: np.ndarray
    rank: int


def column_qr(
    A: np.ndarray, pivot: bool = True, rtol: float = RTOL, scale: float = 0.0
) -> ColumnQR:
    """Householder QR of the columns of ``A`` (m, n), stopped where the columns left are dependent.

    **The rule.** Column ``k`` of the factorisation counts when its distance to the span of the
    columns before it, ``|R_kk|``, exceeds ``rtol * max(c_max, scale)`` with ``c_max`` the
    largest column norm of ``A`` (the module's rule, with ``|R_kk|`` in place of the singular
    values, which it brackets). With ``pivot`` (Businger-Golub) the next column is the one of
    largest remaining norm (the best-determined first: ``|R_kk|`` does not increase); without,
    it is the next one in the given order whose remaining norm counts (the columns' order is a
    preference: a dependent column is moved to the end, not used as a pivot, so that the
    columns after it are judged against the independent ones alone).

    Elementwise numpy (no multithreaded BLAS call: LAPACK's ``geqp3`` can be a hundred times
    slower on a loaded two-core machine, its threads waiting on each other); it matches
    ``scipy.linalg.qr(A, pivoting=True)`` to round-off.

    Args:
        A: Matrix (m, n).
        pivot: Column pivoting (else: the given order).
        rtol: Relative tolerance.
        scale: Reference magnitude (0: the largest column norm alone).

    Returns:
        ``R``, ``perm`` and ``rank``.

    """
    R = np.array(A, dtype=float)
    m, n = R.shape
    perm = np.arange(n)
    norms = np.sqrt(np.einsum("ij,ij->j", R, R)) if n else np.zeros(0)
    cut = rtol * max(float(norms.max(initial=0.0)), scale)
    rank = 0
    for k in range(min(m, n)):
        rest = np.sqrt(np.einsum("ij,ij->j", R[k:, k:], R[k:, k:]))
        live = np.flatnonzero(rest > cut) if cut > 0.0 else np.flatnonzero(rest > 0.0)
        if live.size == 0:
            break
        j = k + int(live[np.argmax(rest[live])] if pivot else live[0])
        if j != k:  # bring column j to k, keeping the others in order
            order = np.r_[j, np.arange(k, j), np.arange(j + 1, n)] if not pivot else None
            if order is None:
                R[:, [k, j]] = R[:, [j, k]]
                perm[[k, j]] = perm[[j, k]]
            else:
                R[:, k:] = R[:, order]
                perm[k:] = perm[order]
        x = R[k:, k]
        nx = float(np.sqrt(np.einsum("i,i->", x, x)))
        v = x.copy()
        v[0] += nx if x[0] >= 0.0 else -nx
        vv = float(np.einsum("i,i->", v, v))
        block = R[k:, k:]
        block -= np.multiply.outer(v, np.einsum("i,ij->j", v, block) * (2.0 / vv))
        R[k + 1 :, k] = 0.0
        rank = k + 1
    return ColumnQR(np.triu(R[: min(m, n)]), perm, rank)


@dataclass(frozen=True, eq=False)  # numpy fields
class ColumnBasis:
    """Independent columns of a matrix and the combinations the others are (:func:`column_basis`).

    Attributes:
        independent: Independent columns (r,), in the order of the factorisation.
        dependent: The others (p - r,): the dependent ones, then those without effect.
        beta: Combinations (r, p - r): ``A[:, dependent[k]] = A[:, independent] @ beta[:, k]``
            (zero for a column without effect; coefficients below 1e-9 of their column's
            largest are round-off and set to zero).
        r_diag: ``|R_kk|`` of the scaled columns, in factorisation order (p,) (zero for columns
            without effect and beyond the factorisation).
        weak: The dependent columns that are so only because ``|R_kk|`` fell below ``floor``
            (structurally independent).
        zero: The columns without any effect (norm at most :data:`ZERO_RTOL` of the largest).

    """

    independent: np.ndarray
    dependent: np.ndarray
    beta: np.ndarray
    r_diag: np.ndarray
    weak: np.ndarray
    zero: np.ndarray

    @property
    def rank(self) -> int:
        """Number of independent columns."""
        return int(self.independent.size)


def column_basis(
    A: np.ndarray,
    rtol: float = IDENTIFIABILITY_RTOL,
    col_scale: np.ndarray | None = None,
    floor: float = 0.0,
    pivot: bool = True,
) -> ColumnBasis:
    """The independent columns of ``A`` (m, p) and the combination each other column is.

    **Scaling.** Independence does not depend on the columns' units: each column is judged by
    its distance to the span of the columns before it *divided by its own norm* (unit columns,
    judged with ``scale`` 1 as orthonormal bases are: the cut-off is ``rtol``). A caller that
    knows a magnitude per column passes ``col_scale`` (the columns are multiplied by it):
    calibration the prior standard deviation of each parameter and identification a plausible
    magnitude of each base parameter, on a matrix whitened by the noise, so that ``|R_kk|`` of
    the scaled columns is that magnitude divided by the standard deviation the data give the
    parameter (the parameters before it known). The pivots then follow the scaled columns (the
    best-determined parameters first), each still judged by the unit-free rule, and ``floor``
    also makes a column whose scaled ``|R_kk|`` falls below it dependent (*weak*: the data
    determine it worse than ``floor`` times its magnitude).

    Columns whose norm is at most :data:`ZERO_RTOL` of the largest have no effect: dependent,
    with a zero combination.

    Args:
        A: Matrix (m, p): the effect of each parameter (column) on the data (rows).
        rtol: Relative tolerance of :func:`column_qr` (:data:`IDENTIFIABILITY_RTOL`).
        col_scale: Column multipliers (p,) > 0, or ``None`` (unit columns).
        floor: Smallest ``|R_kk|`` of an independent column (with ``col_scale`` and ``pivot``).
        pivot: Pivoted (best-determined first) or in the given order (earlier columns kept in
            preference to later ones they combine with).

    Returns:
        The independent and dependent columns, the combinations and the factorisation's
        diagonal.

    Raises:
        ValueError: ``floor`` without pivoting (the diagonal is not ordered).

    """
    A = np.asarray(A, dtype=float)
    p = A.shape[1]
    if floor > 0.0 and not pivot:
        raise ValueError("column_basis: floor needs pivoting")
    norms = np.sqrt(np.einsum("ij,ij->j", A, A)) if p else np.zeros(0)
    live = np.flatnonzero(norms > ZERO_RTOL * float(norms.max(initial=0.0)))
    zero = np.setdiff1d(np.arange(p), live)
    r_diag = np.zeros(p)
    if live.size == 0:
        return ColumnBasis(
            np.zeros(0, int), np.arange(p), np.zeros((0, p)), r_diag, np.zeros(0, int), zero
        )
    if col_scale is None:  # unit columns: the rule on the diagonal itself
        d = 1.0 / norms[live]
        qr = column_qr(A[:, live] * d, pivot, rtol, 1.0)
        diag = np.abs(np.diag(qr.R))[: qr.rank]
        r = struct = qr.rank
    else:  # the rule on the unit-free distances, the floor on the scaled diagonal
        d = np.asarray(col_scale, dtype=float)[live]
        qr = column_qr(A[:, live] * d, pivot, 0.0)
        diag = np.abs(np.diag(qr.R))[: qr.rank]
        unit = diag / (norms[live] * d)[qr.perm[: qr.rank]]
        apart = unit > rtol
        struct = int(np.count_nonzero(np.cumprod(apart)))
        r = int(np.count_nonzero(np.cumprod(apart & (diag >= floor))))
        diag = diag[:struct]
    r_diag[: diag.size] = diag
    ind = live[qr.perm[:r]]
    weak = live[qr.perm[r:struct]]
    rest = qr.perm[r:]
    beta = np.zeros((r, rest.size + zero.size))
    if rest.size and r:
        coef = np.linalg.solve(qr.R[:r, :r], qr.R[:r, r : r + rest.size])
        coef = coef * d[qr.perm[:r], None] / d[rest][None, :]
        big = np.abs(coef).max(axis=0, keepdims=True)
        coef[np.abs(coef) < _CLEAN * big] = 0.0
        beta[:, : rest.size] = coef
    dependent = np.concatenate([live[rest], zero]).astype(int)
    return ColumnBasis(ind.astype(int), dependent, beta, r_diag, weak.astype(int), zero)


# ---------------------------------------------------------------------- passive-joint elimination


@dataclass(frozen=True, eq=False)  # numpy fields
class PassiveElimination:
    """The closures solved for the passive rates: ``Jp dq_p = -r`` in the least-squares sense.

    One singular value decomposition of the passive columns ``Jp`` (nc, n_p) of a closure
    Jacobian (or a stack of them, (..., nc, n_p)), ``Jp = U diag(s) V^T``, with the singular
    values that count by the cut-off rule kept (:func:`passive_elimination`). The passive rates
    absorbing closure residual rates ``r`` are the minimum-norm least-squares solution
    ``dq_p = -Jp^+ r`` (internal mobilities, e.g. the spin of a Delta's bars, stay still); what
    they cannot absorb is the **gap** ``r - Jp Jp^+ r`` (an over-constrained mechanism: the
    out-of-plane errors of a planar loop).

    Attributes:
        U: Left singular vectors (..., nc, k), ``k = min(nc, n_p)``.
        s: Singular values (..., k), largest first.
        Vt: Right singular vectors (..., k, n_p).
        keep: Which singular values count (..., k).
        margin: ``s[rank - 1] / max(s_max, scale)`` with the rank asked for (or found): how far
            the passive joints are from losing a direction (0: exactly singular; 1 for no
            passive joint or no closure).
        singular: ``margin <= rtol``: with a structural rank given, the closures no longer
            determine the passive rates in one of its directions (a parallel singularity).

    """

    U: np.ndarray
    s: np.ndarray
    Vt: np.ndarray
    keep: np.ndarray
    margin: np.ndarray | float
    singular: np.ndarray | bool

    @property
    def rank(self) -> np.ndarray | int:
        """Number of singular values that count (per matrix of a stack)."""
        r = np.count_nonzero(self.keep, axis=-1)
        return int(r) if np.ndim(r) == 0 else r

    def solve(self, r: np.ndarray) -> np.ndarray:
        """``Jp^+ r``: the minimum-norm least-squares solution of ``Jp x = r``.

        Args:
            r: Right-hand sides (..., nc) or (..., nc, m) (the closure rows of actuator
                columns, of parameters...).

        Returns:
            ``x`` (..., n_p) or (..., n_p, m); the passive rates that absorb ``r`` are ``-x``.

        """
        vec = np.ndim(r) == self.U.ndim - 1
        R = np.asarray(r, dtype=float)[..., None] if vec else np.asarray(r, dtype=float)
        s_inv = np.where(self.keep, 1.0 / np.where(self.keep, self.s, 1.0), 0.0)
        y = (np.swapaxes(self.U, -1, -2) @ R) * s_inv[..., :, None]
        x = np.swapaxes(self.Vt, -1, -2) @ y
        return x[..., 0] if vec else x

    def gap(self, r: np.ndarray) -> np.ndarray:
        """``r - Jp Jp^+ r``: the part of ``r`` no passive motion absorbs.

        Args:
            r: Right-hand sides (..., nc) or (..., nc, m).

        Returns:
            The gap, same shape as ``r``.

        """
        vec = np.ndim(r) == self.U.ndim - 1
        R = np.asarray(r, dtype=float)[..., None] if vec else np.asarray(r, dtype=float)
        Uk = self.U * self.keep[..., None, :]
        out = R - Uk @ (np.swapaxes(Uk, -1, -2) @ R)
        return out[..., 0] if vec else out


def passive_elimination(
    Jp: np.ndarray, rtol: float = RTOL, scale: float = 1.0, rank: int | None = None
) -> PassiveElimination:
    """Eliminate the passive joints: the one rule (see :class:`PassiveElimination`).

    **The rule.** The passive columns ``Jp`` of a closure Jacobian are in SI units with entries
    of order one (metres per radian of a robot of metre size, radians per radian, metres per
    metre), so they are judged with the cut-off rule of this module at ``scale`` = 1: a singular
    value counts when ``s > rtol * max(s_max, 1)`` (redundant closure rows, e.g. the
    out-of-plane rows of a planar hinge, fall to ~1e-16 and are dropped; a robot's closures sit
    far above 1e-9). A caller that knows how many passive directions the closures determine at a
    regular configuration (the **structural rank**, e.g. found at the robot's home) passes it as
    ``rank``: those values count whatever their size, and ``singular`` says when the smallest
    of them falls to the cut-off (a parallel singularity: the actuators no longer determine the
    passive joints, and every rate or sensitivity eliminated through them is unbounded).

    Args:
        Jp: Passive columns (nc, n_p), or a stack (..., nc, n_p).
        rtol: Relative tolerance (:data:`RTOL`).
        scale: Reference magnitude (1: closure Jacobians in SI units).
        rank: Structural rank (``None``: the cut-off rule decides, per matrix).

    Returns:
        The elimination.

    """
    J = np.asarray(Jp, dtype=float)
    nc, n_p = J.shape[-2], J.shape[-1]
    k = min(nc, n_p)
    if k == 0:
        shape = J.shape[:-2]
        return PassiveElimination(
            np.zeros(shape + (nc, 0)),
            np.zeros(shape + (0,)),
            np.zeros(shape + (0, n_p)),
            np.zeros(shape + (0,), dtype=bool),
            1.0 if not shape else np.ones(shape),
            False if not shape else np.zeros(shape, dtype=bool),
        )
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    ref = np.maximum(s[..., 0], scale)
    if rank is None:
        keep = s > rtol * ref[..., None]
        r = np.count_nonzero(keep, axis=-1)
    else:
        r = np.full(s.shape[:-1], min(int(rank), k))
        keep = np.arange(k) < r[..., None]
    last = np.take_along_axis(s, np.maximum(r - 1, 0)[..., None], axis=-1)[..., 0]
    margin = np.where(r > 0, last / np.where(ref > 0.0, ref, 1.0), 1.0)
    singular = (r > 0) & (margin <= rtol)
    if margin.ndim == 0:
        return PassiveElimination(U, s, Vt, keep, float(margin), bool(singular))
    return PassiveElimination(U, s, Vt, keep, margin, singular)


_GRAM_RTOL = 1e-12
"""Smallest eigenvalue of a Gram matrix, relative to its largest, solved by normal equations."""


def passive_solve(
    Jp: np.ndarray, x: np.ndarray, rtol: float = RTOL, scale: float = 1.0
) -> np.ndarray:
    """``Jp^+ x`` over a stack of closure Jacobians of one motion, by the elimination's rule.

    The same rule, fast on long stacks (identification's thousands of samples): the rank is
    decided once, on the first matrix of the stack (its singular values by the cut-off rule),
    then every matrix is solved by normal equations: of its columns when the rank is the number
    of passive joints (the least-squares solution), else of a set of independent rows (chosen on
    the first matrix by a pivoted QR; the minimum-norm solution, exact for right-hand sides in
    the range, as the velocities and accelerations of a motion are: redundant closure rows stay
    redundant along it). A matrix whose normal equations are ill-conditioned there (a condition
    number beyond 1e6: a near-singular sample) is solved by its own decomposition.

    Args:
        Jp: Passive columns (n, nc, n_p).
        x: Right-hand sides (n, nc) or (n, nc, k).
        rtol: Relative tolerance (:data:`RTOL`).
        scale: Reference magnitude (1: closure Jacobians in SI units).

    Returns:
        ``Jp^+ x``: (n, n_p) or (n, n_p, k).

    """
    import scipy.linalg

    J = np.asarray(Jp, dtype=float)
    X = np.asarray(x, dtype=float)
    vec = X.ndim == 2
    if vec:
        X = X[..., None]
    n, nc, n_p = J.shape
    out = np.zeros((n, n_p, X.shape[-1]))
    r = int(passive_elimination(J[0], rtol, scale).rank) if n and nc and n_p else 0
    if r == 0:
        return out[..., 0] if vec else out
    JT = np.swapaxes(J, 1, 2)
    if r == n_p:  # full column rank: least squares
        G, rhs = JT @ J, JT @ X
    else:
        rows = slice(None)
        if r < nc:
            _, _, piv = scipy.linalg.qr(J[0].T, mode="economic", pivoting=True)
            rows = np.sort(piv[:r])  # type: ignore[assignment]
        Jr = J[:, rows, :]
        G, rhs = Jr @ np.swapaxes(Jr, 1, 2), X[:, rows, :]
    try:
        L = np.linalg.cholesky(G)
        d = np.diagonal(L, axis1=1, axis2=2) ** 2
        bad = d.min(axis=1) <= _GRAM_RTOL * np.diagonal(G, axis1=1, axis2=2).max(axis=1)
    except np.linalg.LinAlgError:
        bad = np.ones(n, dtype=bool)
    if not bad.any():
        y = np.linalg.solve(G, rhs)
        out = y if r == n_p else np.swapaxes(Jr, 1, 2) @ y
    elif not bad.all():
        good = ~bad
        y = np.linalg.solve(G[good], rhs[good])
        out[good] = y if r == n_p else np.swapaxes(Jr[good], 1, 2) @ y
    if bad.any():
        out[bad] = passive_elimination(J[bad], rtol, scale).solve(X[bad])
    return out[..., 0] if vec else out
