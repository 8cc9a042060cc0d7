"""Calibration figures: residuals, and the simulated accuracy of a plan.

:class:`CalibrationResult`: the residuals per pose and axis before and after;
:class:`CalibrationPlan`: the error after calibration against the pose count per noise.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.calibration.planner import CalibrationPlan
from pkdyn.calibration.result import CalibrationResult
from pkdyn.plotting._save import finish_figure
from pkdyn.results import register_plot
from pkdyn.units import quantity

__all__ = ["plot_calibration", "plot_calibration_plan"]

_AXES = {
    "pose": ("x", "y", "z", "rx", "ry", "rz"),
    "position": ("x", "y", "z"),
    "point": ("x", "y", "z"),
    "plane": ("distance",),
}


def _scaled(values: np.ndarray, unit: str) -> tuple[float, str]:
    """A factor and unit label that show ``values`` [m or rad] with readable numbers."""
    big = float(np.max(np.abs(values), initial=0.0))
    for factor, prefix in ((1.0, ""), (1e3, "m"), (1e6, "u")):
        if big * factor >= 1.0 or prefix == "u":
            return factor, f"{prefix}{unit}"
    return 1.0, unit  # pragma: no cover


@register_plot(CalibrationResult)
def plot_calibration(
    result: CalibrationResult, path: str | Path | None = None, title: str | None = None
) -> Any:
    """Residuals of the nominal and the calibrated model per pose, one panel per axis.

    The calibration poses are followed by the held-out ones (shaded); outliers (robust weight
    below 1/2) are ringed.

    Args:
        result: The calibration.
        path: Save the figure there (format from the suffix).
        title: Figure title (default: the robot, the model and the RMS before and after).

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    before, after = result.residuals_before, result.residuals_after
    n_cal = len(before)
    if result.validation_residuals is not None:
        before = np.vstack([before, result.validation_residuals[0]])
        after = np.vstack([after, result.validation_residuals[1]])
    labels = _AXES.get(result.kind) or tuple(f"joint {k + 1}" for k in range(before.shape[1]))
    rows = before.shape[1]
    fig = Figure(figsize=(10.0, 1.6 + 1.6 * rows))
    axes = fig.subplots(rows, 2, sharex=True, squeeze=False)
    idx = np.arange(len(before))
    out = np.flatnonzero(result.weights < 0.5)
    for k in range(rows):
        unit = "rad" if (result.kind == "pose" and k >= 3) or result.kind == "joints" else "m"
        name = labels[k] if k < len(labels) else str(k)
        for col, (values, what, color) in enumerate(
            ((before, "nominal model", "0.5"), (after, "calibrated model", "C0"))
        ):
            ax = axes[k, col]
            factor, label = _scaled(values[:, k], unit)
            ax.plot(idx, factor * values[:, k], "o", ms=3, color=color, label=what)
            if col == 1 and out.size:
                ax.plot(
                    out, factor * values[out, k], "o", ms=8, mfc="none", color="C3", label="outlier"
                )
            if len(before) > n_cal:
                ax.axvspan(n_cal - 0.5, len(before) - 0.5, color="C2", alpha=0.08, lw=0)
            ax.axhline(0.0, color="k", lw=0.5)
            ax.set_ylabel(f"{name} [{label}]")
            if k == 0:
                ax.set_title(what)
    for col in (0, 1):
        axes[-1, col].set_xlabel(
            "measurement" + (" (held-out ones shaded)" if len(before) > n_cal else "")
        )
    if out.size:
        axes[0, 1].legend(loc="upper right", fontsize="small")
    unit = "rad or m" if result.kind == "joints" else "m"
    fig.suptitle(
        title
        if title is not None
        else f"{result.nominal.name}, {result.model.kind}: residuals (model minus measurement), "
        f"{quantity(result.before.rms, unit)} -> {quantity(result.after.rms, unit)} RMS"
    )
    return finish_figure(fig, path)


@register_plot(CalibrationPlan)
def plot_calibration_plan(
    plan: CalibrationPlan, path: str | Path | None = None, title: str | None = None
) -> Any:
    """Simulated error after calibration against the pose count, one line per noise level.

    Args:
        plan: The plan (:func:`pkdyn.calibration.planner.plan_calibration`).
        path: Save the figure there (format from the suffix).
        title: Figure title.

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    err = plan.rms if plan.statistic == "rms" else plan.worst
    fig = Figure(figsize=(6.0, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    for j, sigma in enumerate(plan.noise):
        ax.semilogy(plan.poses, 1e6 * err[:, j], "o-", label=f"noise {quantity(sigma, 'm')}")
    ax.axhline(1e6 * plan.target, color="k", ls="--", lw=0.8, label="target")
    ax.axhline(1e6 * plan.before, color="0.5", ls=":", lw=0.8, label="uncalibrated")
    ax.set_xlabel("measured poses")
    ax.set_ylabel(f"{'RMS' if plan.statistic == 'rms' else 'largest'} position error [um]")
    ax.legend(fontsize="small")
    ax.set_title(title if title is not None else plan.summary(), fontsize="small", wrap=True)
    return finish_figure(fig, path)
