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
constrained inverse dynamics, state projection) goes through this module. Robot-agnostic (numpy
only).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "RTOL",
    "cutoff",
    "left_null_space",
    "lstsq",
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
