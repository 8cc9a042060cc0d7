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
