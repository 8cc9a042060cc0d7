"""Efforts, speeds and powers of the actuators against time (matplotlib Agg figures)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.dynamics.sizing import SizingResult
from pkdyn.plotting._save import save_figure

__all__ = ["plot_efforts"]


def plot_efforts(
    result: SizingResult,
    path: str | Path | None = None,
    title: str | None = None,
    limits: bool = True,
) -> Any:
    """Effort, speed and power of each actuator against time, with the effort limits.

    Args:
        result: A sizing result (:func:`pkdyn.dynamics.sizing.size`).
        path: Save the figure there (format from the suffix, e.g. ``.png``).
        title: Figure title (default: robot, trajectory and payload).
        limits: Draw the effort limits as dashed lines (when finite and within 3x the peak).

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    ef = result.efforts
    t = ef.t
    qd = ef.trajectory.qa_dot
    fig = Figure(figsize=(8.0, 7.5))
    axes = fig.subplots(3, 1, sharex=True)
    for i, act in enumerate(result.actuators):
        (line,) = axes[0].plot(t, ef.tau[:, i], label=act.name)
        colour = line.get_color()
        axes[1].plot(t, qd[:, i], color=colour)
        axes[2].plot(t, ef.tau[:, i] * qd[:, i], color=colour)
        if limits and math.isfinite(act.limit) and act.limit < 3.0 * max(act.peak, 1e-12):
            for s in (-1.0, 1.0):
                axes[0].axhline(s * act.limit, color=colour, linestyle="--", linewidth=0.8)
    axes[0].set_ylabel("effort [N m or N]")
    axes[1].set_ylabel("speed [rad/s or m/s]")
    axes[2].set_ylabel("power [W]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="upper right", fontsize="small", ncol=min(6, len(result.actuators)))
    peak = max((a.peak for a in result.actuators), default=0.0)
    fig.suptitle(
        title
        if title is not None
        else f"{result.robot}: {result.trajectory}, payload {result.payload:g} kg "
        f"(peak {peak:.3g}, {np.round(result.duration, 4):g} s)"
    )
    fig.tight_layout()
    if path is not None:
        save_figure(fig, path, dpi=120)
    return fig
