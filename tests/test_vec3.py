"""solvers.vec3.cross against numpy's cross product, on broadcast stacks of rows."""

from __future__ import annotations

import numpy as np
import pytest

from solvers.vec3 import cross


@pytest.mark.parametrize(
    ("shape_a", "shape_b"),
    [((3,), (3,)), ((5, 3), (5, 3)), ((1, 3), (4, 3)), ((2, 4, 3), (4, 3)), ((7, 1, 3), (1, 2, 3))],
)
def test_cross_matches_numpy(shape_a: tuple[int, ...], shape_b: tuple[int, ...]) -> None:
    rng = np.random.default_rng(7)
    a, b = rng.normal(size=shape_a), rng.normal(size=shape_b)
    c = cross(a, b)
    ref = np.cross(a, b)
    assert c.shape == ref.shape
    scale = np.linalg.norm(a, axis=-1, keepdims=True) * np.linalg.norm(b, axis=-1, keepdims=True)
    assert np.all(np.abs(c - ref) <= 1e-14 * scale)
    # orthogonal to both factors, and anti-symmetric
    assert np.all(
        np.abs(np.sum(c * a, axis=-1)) <= 1e-13 * scale[..., 0] * np.linalg.norm(a, axis=-1)
    )
    assert np.array_equal(cross(b, a), -c)
