"""Products of 3-vectors stacked along leading axes, without ``np.cross``'s overhead.

``np.cross`` checks and moves axes on every call (tens of microseconds), which dominates on the
short stacks of rows the sampled kinematics and the closed forms work on; the same products
and differences written out cost a few array operations.
"""

from __future__ import annotations

import numpy as np

__all__ = ["cross", "cross_one"]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products ``a x b`` of (..., 3) arrays, broadcast over the leading axes.

    Args:
        a: Left factors (..., 3).
        b: Right factors (..., 3), broadcastable with ``a``.

    Returns:
        The products (..., 3), the leading axes broadcast: the same arithmetic as ``np.cross``.

    """
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def cross_one(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The cross product ``a x b`` of two 3-vectors, on Python floats.

    For one pair (a beam's frame), where even :func:`cross`'s few array operations cost more
    than the arithmetic: the same products and differences as ``np.cross``, the same bits.

    Args:
        a: Left factor (3,).
        b: Right factor (3,).

    Returns:
        The product (3,).

    """
    a0, a1, a2 = np.asarray(a, dtype=float).tolist()
    b0, b1, b2 = np.asarray(b, dtype=float).tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
