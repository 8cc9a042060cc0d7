"""Validation helpers shared by the parameter dataclasses."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from pkdyn.exceptions import ParameterError
from pkdyn.inputs import MAX_MAGNITUDE

__all__ = ["finite", "in_range", "middle_of_reach", "param_items", "positive", "within_limits"]


def param_items(params: object) -> list[tuple[str, Any]]:
    """``(name, value)`` of a parameter dataclass's fields (``asdict`` without its deep copy)."""
    return [(f.name, getattr(params, f.name)) for f in dataclasses.fields(params)]  # type: ignore[arg-type]


def positive(family: str, **values: float) -> None:
    """Raise :class:`ParameterError` unless every value is finite and > 0."""
    for k, v in values.items():
        if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
            raise ParameterError(family, k, f"must be a positive finite number, got {v!r}")
        if v > MAX_MAGNITUDE:
            raise ParameterError(
                family, k, f"{v:g} is beyond any plausible value (at most {MAX_MAGNITUDE:g})"
            )


def finite(family: str, **values: float) -> None:
    """Raise :class:`ParameterError` unless every value is a finite number."""
    for k, v in values.items():
        if not math.isfinite(v):
            raise ParameterError(family, k, f"must be finite, got {v!r}")


def within_limits(family: str, q: Iterable[float], q_min: float, q_max: float) -> None:
    """Raise :class:`ParameterError` for a home actuated angle outside ``[q_min, q_max]`` [rad].

    The error names ``q_min`` or ``q_max``, whichever the first angle outside breaks.
    """
    out = [float(v) for v in q if not q_min <= v <= q_max]
    if out:
        raise ParameterError(
            family,
            "q_min" if out[0] < q_min else "q_max",
            f"home actuated angle {out[0]:.6g} rad lies outside [q_min, q_max]",
        )


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
    samples: int = 201,
) -> float:
    """A home coordinate derived from the parameters: the middle of the reachable interval.

    ``[lo, hi]`` is sampled; ``reachable`` says which samples the mechanism reaches (within its
    actuator limits); the ends of the longest reachable run are refined by multisection (to
    1e-10 of the interval), and the home is its middle, rounded to two significant digits when the
    rounded value is still well inside it (so the prototypes keep round homes: the DELTA 580's
    -0.35 m).

    Args:
        family: Family name, for messages.
        name: Parameter the value stands for, for messages.
        lo: Lower end of the sampled interval.
        hi: Upper end.
        reachable: Vectorised test, (k,) values -> (k,) bool.
        samples: Samples of the interval before the bisection.

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
    i, j = int(starts[k]), int(ends[k])
    # both ends refined at once by multisection (32 parts per call: 1e-10 in ~6 calls)
    inner = np.array([x[i], x[j]])
    outer = np.array([x[i - 1] if i > 0 else x[i], x[j + 1] if j + 1 < samples else x[j]])
    parts = np.arange(1, 32) / 32.0
    for _ in range(12):
        if np.all(np.abs(outer - inner) <= 1e-10 * (hi - lo)):
            break
        pts = inner[:, None] + (outer - inner)[:, None] * parts  # (2, 31), inner -> outer
        good = np.asarray(reachable(pts.reshape(-1)), dtype=bool).reshape(2, -1)
        # the last reachable point before the first unreachable one, from the inner side
        first_bad = np.where(good.all(axis=1), good.shape[1], np.argmin(good, axis=1))
        new_inner = np.where(first_bad > 0, pts[np.arange(2), np.maximum(first_bad - 1, 0)], inner)
        new_outer = np.where(
            first_bad < good.shape[1], pts[np.arange(2), np.minimum(first_bad, 30)], outer
        )
        inner, outer = new_inner, new_outer
    a, b = float(inner[0]), float(inner[1])
    middle = 0.5 * (a + b)
    rounded = float(f"{middle:.2g}")
    margin = 0.25 * (b - a)
    return rounded if a + margin <= rounded <= b - margin else middle
