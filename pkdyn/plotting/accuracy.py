"""Pose-error maps (matplotlib Agg figures) of :func:`pkdyn.precision.accuracy.accuracy_map`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.exceptions import InvalidInputError
from pkdyn.plotting._save import save_figure
from pkdyn.precision.accuracy import AccuracyMap

__all__ = ["plot_accuracy_map"]

_LABELS = {
    "actuator_worst": "worst-case position error, actuators [um]",
    "actuator_rms": "RMS position error, actuators [um]",
    "geometric_worst": "worst-case position error, tolerances [um]",
    "geometric_rms": "RMS position error, tolerances [um]",
}


def plot_accuracy_map(
    amap: AccuracyMap,
    field: str = "actuator_worst",
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
) -> Any:
    """Colour map of a position-error field over a square grid (:func:`slice_grid`).

    Args:
        amap: The map (its ``shape`` a 2-D grid).
        field: ``actuator_worst``, ``actuator_rms``, ``geometric_worst`` or ``geometric_rms``.
        path: Save the figure there (format from the suffix).
        ax: Draw into this matplotlib Axes instead of a new figure.
        title: Figure title.

    Returns:
        The matplotlib Figure.

    Raises:
        InvalidInputError: Unknown field, a map that is not a 2-D grid, or no valid position.

    """
    from matplotlib.figure import Figure

    from pkdyn.inputs import instance

    instance("amap", amap, AccuracyMap, "an AccuracyMap (pkdyn.precision.accuracy)")
    if not isinstance(field, str) or field not in _LABELS:
        raise InvalidInputError("field", f"must be one of {', '.join(_LABELS)}, got {field!r}")
    if len(amap.shape) != 2:
        raise InvalidInputError(
            "amap", "plots need a 2-D grid (pkdyn.precision.accuracy.slice_grid)"
        )
    if not amap.valid.any():
        raise InvalidInputError("amap", "no position of the map was reached")
    values = np.ma.masked_invalid(1e6 * amap.field(field))
    i, j = ("xyz".index(amap.axes[0]), "xyz".index(amap.axes[1]))
    P = amap.P.reshape(*amap.shape, 3)
    u, v = P[:, 0, i], P[0, :, j]
    if ax is None:
        fig = Figure(figsize=(6.0, 5.0))
        ax = fig.add_subplot(1, 1, 1)
    else:
        fig = ax.figure
    du = (u[-1] - u[0]) / max(len(u) - 1, 1)
    dv = (v[-1] - v[0]) / max(len(v) - 1, 1)
    extent = (u[0] - du / 2, u[-1] + du / 2, v[0] - dv / 2, v[-1] + dv / 2)
    im = ax.imshow(values.T, origin="lower", extent=extent, aspect="equal", cmap="magma_r")
    fig.colorbar(im, ax=ax, label=_LABELS[field])
    if np.isfinite(values.filled(np.nan)).sum() > 3:
        ax.contour(u, v, values.T, levels=6, colors="white", linewidths=0.6)
    ax.set_xlabel(f"{amap.axes[0]} [m]")
    ax.set_ylabel(f"{amap.axes[1]} [m]")
    k = 3 - i - j
    ax.set_title(title if title is not None else f"{field} ({'xyz'[k]} = {P[0, 0, k]:.4g} m)")
    if path is not None:
        save_figure(fig, path, dpi=120)
    return fig
