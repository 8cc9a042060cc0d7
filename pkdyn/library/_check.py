"""Validation helpers shared by the parameter dataclasses."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from pkdyn.exceptions import ParameterError

__all__ = ["in_range", "middle_of_reach", "positive"]


def positive(family: str, **values: float) -> None:
    """Raise :class:`ParameterError` unless every value is finite and > 0."""
    for k, v in values.items():
        if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
            raise ParameterError(family, k, f"must be a positive finite number, got {v!r}")


def in_range(family: str, name: str, value: float, lo: float, hi: float) -> None:
    """Raise :class:`ParameterError` unless ``lo <= value <= hi``."""
    if not (math.isfinite(value) and lo <= value <= hi):
        raise ParameterError(family, name, f"must lie in [{lo}, {hi}], got {value!r}")


def middle_of_reach(
    family: str,
    name: str,
    lo: float,
    hi: float,
    reachable: Callable[[np.ndarray], np.ndarray],
    samples: int = 4001,
) -> float:
    """A home coordinate derived from the parameters: the middle of the reachable interval.

    ``[lo, hi]`` is sampled; ``reachable`` says which samples the mechanism reaches (within its
    actuator limits); the home is the middle of the longest reachable run, rounded to two
    significant digits when the rounded value is still well inside it (so the prototypes keep
    round homes: the DELTA 580's -0.35 m).

    Args:
        family: Family name, for messages.
        name: Parameter the value stands for, for messages.
        lo: Lower end of the sampled interval.
        hi: Upper end.
        reachable: Vectorised test, (samples,) values -> (samples,) bool.
        samples: Samples of the interval.

    Returns:
        The home coordinate.

    Raises:
        ParameterError: Nothing in ``[lo, hi]`` is reachable with these parameters.

    """
    x = np.linspace(lo, hi, samples)
    ok = np.asarray(reachable(x), dtype=bool)
    if not ok.any():
        raise ParameterError(
            family,
            name,
            f"no reachable home in [{lo:.4g}, {hi:.4g}] with these dimensions and limits; "
            "check the lengths and the actuator limits",
        )
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(int), [0]])))
    starts, ends = edges[0::2], edges[1::2] - 1
    k = int(np.argmax(ends - starts))
    a, b = float(x[starts[k]]), float(x[ends[k]])
    mid = 0.5 * (a + b)
    rounded = float(f"{mid:.2g}")
    margin = 0.25 * (b - a)
    return rounded if a + margin <= rounded <= b - margin else mid
