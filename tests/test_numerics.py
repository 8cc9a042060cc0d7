"""The one cut-off rule of solvers.numerics, and that rank decisions go through it."""

import re
from pathlib import Path

import numpy as np

from solvers import numerics

ROOT = Path(__file__).resolve().parents[1]


def _with_singular_values(s, m, n, seed=0):
    rng = np.random.default_rng(seed)
    U, _ = np.linalg.qr(rng.standard_normal((m, m)))
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    S = np.zeros((m, n))
    S[np.arange(len(s)), np.arange(len(s))] = s
    return U @ S @ V.T


def test_rule_relative_and_scaled():
    A = _with_singular_values([2.0, 1.0, 1e-7, 1e-12], 5, 4)
    assert numerics.rank(A) == 3  # 1e-12 <= 1e-9 * 2 < 1e-7
    assert numerics.rank(A, rtol=1e-6) == 2
    tiny = 1e-12 * A
    assert numerics.rank(tiny) == 3  # judged against itself
    assert numerics.rank(tiny, scale=1.0) == 0  # judged against a unit reference
    assert numerics.rank(np.zeros((3, 3))) == 0
    assert numerics.rank(np.zeros((0, 3))) == 0


def test_null_spaces_and_range():
    A = _with_singular_values([3.0, 1.0, 1e-13], 3, 5, seed=1)
    N = numerics.null_space(A)
    assert N.shape == (5, 3)
    np.testing.assert_allclose(A @ N, 0.0, atol=1e-12)
    np.testing.assert_allclose(N.T @ N, np.eye(3), atol=1e-12)
    W = numerics.left_null_space(A)
    assert W.shape == (1, 3)
    np.testing.assert_allclose(W @ A, 0.0, atol=1e-12)
    R = numerics.range_space(A)
    assert R.shape == (3, 2)
    np.testing.assert_allclose(W @ R, 0.0, atol=1e-12)


def test_lstsq_is_the_minimum_norm_solution():
    rng = np.random.default_rng(2)
    A = _with_singular_values([2.0, 1.0, 0.5, 0.0], 6, 4, seed=3)
    b = rng.standard_normal(6)
    x, N = numerics.lstsq_null(A, b)
    np.testing.assert_allclose(x, np.linalg.pinv(A) @ b, atol=1e-12)
    np.testing.assert_allclose(N.T @ x, 0.0, atol=1e-12)  # minimum norm: no null-space part
    B = rng.standard_normal((6, 2))
    np.testing.assert_allclose(numerics.lstsq(A, B), np.linalg.pinv(A) @ B, atol=1e-12)
    np.testing.assert_allclose(numerics.lstsq(np.zeros((0, 3)), np.zeros(0)), np.zeros(3))


def test_no_other_rank_rule():
    """pkdyn and solvers decide ranks only through solvers.numerics."""
    pattern = re.compile(r"matrix_rank|pinv\(|linalg\.lstsq|rcond")
    offenders = [
        f"{p.relative_to(ROOT)}:{i}"
        for top in ("pkdyn", "solvers")
        for p in sorted((ROOT / top).rglob("*.py"))
        if p.name != "numerics.py"
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if pattern.search(line)
    ]
    assert offenders == []


# ---------------------------------------------------------------------------------------------
# identifiability: column_qr and column_basis


def test_column_qr_matches_lapack_and_stops_at_the_rank():
    import scipy.linalg

    rng = np.random.default_rng(4)
    A = rng.standard_normal((30, 6))
    A[:, 5] = A[:, 0] - 2.0 * A[:, 3]
    qr = numerics.column_qr(A, rtol=0.0)
    _, R2, _ = scipy.linalg.qr(A, mode="economic", pivoting=True)
    np.testing.assert_allclose(np.abs(np.diag(qr.R)), np.abs(np.diag(R2)), atol=1e-12)
    assert numerics.column_qr(A).rank == 5
    assert numerics.column_qr(np.zeros((4, 3))).rank == 0


def test_column_basis_combinations_and_scale_independence():
    rng = np.random.default_rng(5)
    A = rng.standard_normal((40, 5))
    A[:, 3] = 2.0 * A[:, 1] - 0.5 * A[:, 2]  # a combination
    A[:, 4] = 0.0  # no effect
    b = numerics.column_basis(A)
    assert b.rank == 3 and list(b.zero) == [4] and 4 in b.dependent
    np.testing.assert_allclose(A[:, b.dependent] - A[:, b.independent] @ b.beta, 0.0, atol=1e-12)
    # units do not decide: columns scaled by 1e-4 .. 1e4 give a basis of the same size (a
    # column 1e12 times smaller than the largest is an exact zero: ZERO_RTOL)
    D = 10.0 ** np.array([-4.0, 3.0, 0.0, 4.0, 1.0])
    b2 = numerics.column_basis(A * D)
    assert b2.rank == 3
    np.testing.assert_allclose(
        (A * D)[:, b2.dependent] - (A * D)[:, b2.independent] @ b2.beta, 0.0, atol=1e-6
    )
    # in the given order, earlier columns are kept: 0, 1 and 2 before 3 (which 1 and 2 make)
    ordered = numerics.column_basis(A, pivot=False)
    assert list(ordered.independent) == [0, 1, 2] and list(ordered.dependent) == [3, 4]
    np.testing.assert_allclose(ordered.beta[:, 0], [0.0, 2.0, -0.5], atol=1e-12)


def test_column_basis_floor_makes_weakly_seen_columns_dependent():
    rng = np.random.default_rng(6)
    A = rng.standard_normal((50, 3))
    A[:, 2] *= 1e-3  # a parameter the data see a thousand times less
    assert numerics.column_basis(A).rank == 3  # structurally independent
    weak = numerics.column_basis(A, col_scale=np.ones(3), floor=1.0)
    assert weak.rank == 2 and list(weak.weak) == [2]  # determined worse than its magnitude
    big = numerics.column_basis(A, col_scale=np.array([1.0, 1.0, 1e3]), floor=1.0)
    assert big.rank == 3 and big.weak.size == 0  # a magnitude a thousand times larger: seen
