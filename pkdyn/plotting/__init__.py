"""Plots of pkdyn results (matplotlib, imported lazily; no pyplot, no global backend change).

One module per kind of result; each function returns a :class:`matplotlib.figure.Figure` drawn
with the Agg canvas, so it can be saved headless (``path=...``) or shown in a notebook (a Figure
displays itself in Jupyter). The CLI and the notebooks use these functions only.
"""

from __future__ import annotations

from pkdyn.plotting.accuracy import plot_accuracy_map
from pkdyn.plotting.maps import plot_conditioning_map
from pkdyn.plotting.precision import (
    plot_grid_map,
    plot_modes,
    plot_monte_carlo,
    plot_precision_map,
    plot_ranking,
)

__all__ = [
    "plot_accuracy_map",
    "plot_conditioning_map",
    "plot_grid_map",
    "plot_modes",
    "plot_monte_carlo",
    "plot_precision_map",
    "plot_ranking",
]
