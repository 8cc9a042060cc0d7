"""Pareto fronts: the designs no other design beats on every objective."""

from __future__ import annotations

import numpy as np

__all__ = ["non_dominated"]


def non_dominated(F: np.ndarray) -> np.ndarray:
    """Mask of the non-dominated rows of ``F`` (all objectives minimised).

    Row ``i`` is dominated when some row is no worse on every objective and better on one.
    Equal rows are all kept. Rows with a NaN are dominated. The rows are sorted
    lexicographically, so a row can only be dominated by one before it, and compared with the
    front found so far (transitivity covers the others).

    Args:
        F: Objective values (N, k).

    Returns:
        (N,) boolean mask.

    """
    F = np.atleast_2d(np.asarray(F, dtype=float))
    n = F.shape[0]
    ok = np.isfinite(F).all(axis=1)
    keep = ok.copy()
    idx = np.flatnonzero(ok)
    G = F[idx]
    order = np.lexsort(G.T[::-1])  # by the first objective, then the next...
    G, idx = G[order], idx[order]
    front: list[int] = []  # positions in G of the front so far (none dominates another)
    for i in range(G.shape[0]):
        if front:
            P = G[front]
            if np.any(np.all(P <= G[i], axis=1) & np.any(P < G[i], axis=1)):
                keep[idx[i]] = False
                continue
        front.append(i)
    assert keep.shape == (n,)
    return keep
