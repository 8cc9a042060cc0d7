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
constrained inverse dynamics, state projection) goes through this module, and so does the
**elimination of the passive joints** (:func:`passive_elimination`: the one rule by which the
kinematic models, the pose sensitivities of accuracy and calibration, and the motions of
identification solve the closures for the passive rates). Robot-agnostic (numpy only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "RTOL",
    "PassiveElimination",
    "cutoff",
    "left_null_space",
    "lstsq",
    "lstsq_null",
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
