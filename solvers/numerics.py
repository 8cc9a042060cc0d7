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
identification) goes through this module. Robot-agnostic (numpy only).

**Identifiability** (:func:`column_basis`): the same rule on the diagonal of a QR factorisation
of the columns (:func:`column_qr`), each column scaled by what its caller knows of it (unit
columns by default): the independent columns, and of what combination of them each other column
is (the base-parameter map of dynamic identification, the unidentifiable combinations of
calibration).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "IDENTIFIABILITY_RTOL",
    "RTOL",
    "ZERO_RTOL",
    "ColumnBasis",
    "ColumnQR",
    "SOFT_RTOL",
    "column_basis",
    "column_qr",
    "cutoff",
    "left_null_space",
    "lstsq",
    "lstsq_batch",
    "lstsq_null",
    "machine_rtol",
    "null_space",
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


# ----------------------------------------------------------------------------------------------
# Batches of small systems: the rule in its soft form

SOFT_RTOL = 1e-15**0.5
"""``rtol`` of :func:`lstsq_batch`: the Gram matrix squares the singular values, so the cut-off
cannot be sharper than the square root of round-off (3.2e-8)."""


def lstsq_batch(A: np.ndarray, b: np.ndarray, rtol: float = SOFT_RTOL) -> np.ndarray:
    """Minimum-norm least squares of a stack of small systems ``A[i] x[i] = b[i]``, fast.

    **The rule, soft.** The normal equations of each system (the smaller Gram matrix ``G``: ``A
    A^T`` or ``A^T A``) are damped by ``lambda^2 = rtol^2 tr(G)`` (``tr G >= s_max^2``):
    singular values well above ``lambda`` are inverted exactly, those well below it (exact
    dependencies, such as the dependent rows of a hinge closure, at round-off) are suppressed,
    as the sharp rule of :func:`lstsq` with ``rtol`` would. One batched ``solve`` per stack: a
    fraction of the batched SVD's cost, for the thousands of small eliminations of passive
    joints along a measured motion (:mod:`pkdyn.identification.motion`). Exact (to round-off)
    for consistent systems (``b`` in the range of ``A``, as the closures' velocity and Newton
    equations are) and for matrices of full rank; a rank-deficient, inconsistent system keeps a
    part ``eps / rtol^2`` of its inconsistency (:func:`lstsq` is the sharp, slower rule).

    Args:
        A: Matrices (n, m, k).
        b: Right-hand sides (n, m) or (n, m, r).
        rtol: Relative tolerance (at least :data:`SOFT_RTOL`).

    Returns:
        Solutions (n, k) or (n, k, r).

    """
    vec = b.ndim == A.ndim - 1
    B = b[..., None] if vec else b
    m, k = A.shape[-2], A.shape[-1]
    AT = np.swapaxes(A, -1, -2)
    reg = max(rtol, SOFT_RTOL) ** 2
    if m <= k:
        G = A @ AT
        G += reg * np.trace(G, axis1=-2, axis2=-1)[..., None, None] * np.eye(m)
        out = AT @ np.linalg.solve(G, B)
    else:
        G = AT @ A
        G += reg * np.trace(G, axis1=-2, axis2=-1)[..., None, None] * np.eye(k)
        out = np.linalg.solve(G, AT @ B)
    return out[..., 0] if vec else out
