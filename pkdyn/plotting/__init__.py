"""Plots of pkdyn results (matplotlib, imported lazily; no pyplot, no global backend change).

One module per kind of result; each function returns a :class:`matplotlib.figure.Figure` drawn
with the Agg canvas, so it can be saved headless (``path=...``) or shown in a notebook (a Figure
displays itself in Jupyter). Each function that draws a result type is registered with
:func:`pkdyn.results.register_plot` when this package is imported, so ``result.plot(path)``
finds it; the functions stay callable by name.
"""

from __future__ import annotations

from pkdyn.plotting.accuracy import plot_accuracy_map
from pkdyn.plotting.calibration import plot_calibration, plot_calibration_plan
from pkdyn.plotting.design import plot_pareto
from pkdyn.plotting.dynamics import plot_efforts, plot_simulation
from pkdyn.plotting.identification import plot_identification
from pkdyn.plotting.maps import plot_conditioning_map
from pkdyn.plotting.motors import plot_operating_points
from pkdyn.plotting.precision import (
    plot_grid_map,
    plot_modes,
    plot_monte_carlo,
    plot_precision_map,
    plot_ranking,
)
from pkdyn.plotting.tripod import plot_comparison, plot_scenario
from pkdyn.plotting.vibration import plot_vibration
from pkdyn.plotting.workspace import (
    plot_clavel,
    plot_mel_study,
    plot_orientation_workspace,
    plot_translation_workspace,
)

__all__ = [
    "plot_accuracy_map",
    "plot_calibration",
    "plot_calibration_plan",
    "plot_clavel",
    "plot_comparison",
    "plot_conditioning_map",
    "plot_efforts",
    "plot_grid_map",
    "plot_identification",
    "plot_mel_study",
    "plot_modes",
    "plot_monte_carlo",
    "plot_operating_points",
    "plot_orientation_workspace",
    "plot_pareto",
    "plot_precision_map",
    "plot_ranking",
    "plot_scenario",
    "plot_simulation",
    "plot_translation_workspace",
    "plot_vibration",
]
