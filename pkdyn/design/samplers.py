"""Where the designs of a sweep sit in the unit cube of the design variables.

- ``grid``: ``n`` values per variable, ends included (``n^d`` designs);
- ``lhs``: Latin hypercube (:class:`scipy.stats.qmc.LatinHypercube`), ``n`` designs;
- ``sobol``: scrambled Sobol' sequence (:class:`scipy.stats.qmc.Sobol`), ``n`` designs (the
  first ``n`` points of the sequence; a power of two keeps its balance properties);
- ``random``: uniform, ``n`` designs.

The seeded generators give the same points on every machine (scipy's ``numpy.random.Generator``
streams). NSGA-II (:mod:`pkdyn.design.optimize`) chooses its designs as it goes.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.stats import qmc

from pkdyn.exceptions import InvalidInputError

__all__ = ["MAX_DESIGNS", "SAMPLERS", "check_count", "design_count", "unit_points"]

SAMPLERS = ("grid", "lhs", "sobol", "random", "nsga2")
"""Runners a study may use."""

MAX_DESIGNS = 1_000_000
"""Largest study accepted (a study of that size takes hours on a laptop)."""


def design_count(kind: str, n: int, dimension: int, generations: int = 1) -> int:
    """Number of designs a runner evaluates (NSGA-II: population x generations, at most)."""
    if kind == "grid":
        return int(n) ** int(dimension)
    if kind == "nsga2":
        return int(n) * int(generations)
    return int(n)


def check_count(kind: str, n: int, dimension: int, generations: int = 1) -> int:
    """:func:`design_count`, refused when it is not positive or exceeds :data:`MAX_DESIGNS`.

    Raises:
        InvalidInputError: Unknown runner, ``n`` too small, or too many designs.

    """
    if kind not in SAMPLERS:
        raise InvalidInputError("sampler", f"unknown '{kind}' (use {', '.join(SAMPLERS)})")
    least = {"grid": 2, "nsga2": 4}.get(kind, 1)
    if n < least:
        what = {"grid": "--grid (points per variable)", "nsga2": "--population"}.get(kind, "--n")
        raise InvalidInputError(what, f"must be >= {least}, got {n}")
    if kind == "nsga2" and generations < 1:
        raise InvalidInputError("--generations", f"must be >= 1, got {generations}")
    total = design_count(kind, n, dimension, generations)
    if total > MAX_DESIGNS:
        raise InvalidInputError(
            "study",
            f"{total} designs ({kind}, n = {n}, {dimension} variables) is more than "
            f"{MAX_DESIGNS}; lower --grid / --n or sample with lhs or sobol",
        )
    return total


def unit_points(kind: str, n: int, dimension: int, seed: int = 0) -> np.ndarray:
    """Design points in the unit cube.

    Args:
        kind: ``grid``, ``lhs``, ``sobol`` or ``random``.
        n: Points per variable (grid) or number of designs.
        dimension: Number of design variables.
        seed: Seed of the random generators.

    Returns:
        (N, dimension) points in [0, 1].

    """
    check_count(kind, n, dimension)
    if kind == "grid":
        axes = [np.linspace(0.0, 1.0, n)] * dimension
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dimension)
    if kind == "lhs":
        return qmc.LatinHypercube(d=dimension, seed=seed).random(n)
    if kind == "sobol":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "balance properties": n need not be 2^m here
            return qmc.Sobol(d=dimension, scramble=True, seed=seed).random(n)
    if kind == "random":
        return np.random.default_rng(seed).random((n, dimension))
    raise InvalidInputError("sampler", f"'{kind}' chooses its own designs")
