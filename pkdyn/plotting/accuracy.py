"""Pose-error maps of :func:`pkdyn.precision.accuracy_maps.accuracy_map` (matplotlib Agg)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pkdyn.exceptions import InvalidInputError
from pkdyn.plotting.precision import plot_grid_map
from pkdyn.precision.accuracy_maps import FIELDS, AccuracyMap

__all__ = ["plot_accuracy_map"]


def plot_accuracy_map(
    amap: AccuracyMap,
    field: str = "actuator_worst",
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
) -> Any:
    """Colour map of a position-error field over its plane (:func:`plot_grid_map`).

    Args:
        amap: The map.
        field: ``actuator_worst``, ``actuator_rms``, ``geometric_worst`` or ``geometric_rms``.
        path: Save the figure there (format from the suffix).
        ax: Draw into this matplotlib Axes instead of a new figure.
        title: Figure title.

    Returns:
        The matplotlib Figure.

    Raises:
        InvalidInputError: Unknown field, a map that is not a 2-D grid, or no valid position.

    """
    from pkdyn.inputs import instance

    instance("amap", amap, AccuracyMap, "an AccuracyMap (pkdyn.precision.accuracy)")
    if not isinstance(field, str) or field not in FIELDS:
        raise InvalidInputError("field", f"must be one of {', '.join(FIELDS)}, got {field!r}")
    if len(amap.shape) != 2:
        raise InvalidInputError("amap", "plots need a 2-D grid (accuracy_map(plane=...))")
    return plot_grid_map(amap, field, path=path, ax=ax, title=title)
