"""solvers.vec3.cross and cross_one against numpy's cross product (stacks of rows, one pair)."""

from __future__ import annotations

import numpy as np
import pytest

from solvers.vec3 import cross, cross_one


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


def test_cross_one_matches_numpy() -> None:
    """One pair: numpy's products and differences, so the same values (signed zeros included)."""
    rng = np.random.default_rng(11)
    pairs = [(rng.normal(size=3), rng.normal(size=3)) for _ in range(50)]
    pairs += [(np.array([1.0, 0.0, 0.0]), np.array([0.0, -0.6, 0.8]))]  # a beam frame's helper
    pairs += [(np.array([0.0, 1.0, 0.0]), np.array([-1.0, 0.0, -0.0]))]
    for a, b in pairs:
        c, ref = cross_one(a, b), np.cross(a, b)
        assert c.shape == (3,)
        scale = np.linalg.norm(a) * np.linalg.norm(b)
        assert np.all(np.abs(c - ref) <= 1e-14 * scale)
        zero = ref == 0.0  # (a frame's helper axis: exact zeros keep numpy's signs)
        assert np.array_equal(c[zero], ref[zero])
        assert np.array_equal(np.signbit(c[zero]), np.signbit(ref[zero]))
        assert abs(float(c @ a)) <= 1e-13 * scale * np.linalg.norm(a)
