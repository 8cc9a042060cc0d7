"""Operating points of the actuators over their motors' speed-torque envelopes."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.dynamics.selection import Candidate, Selection
from pkdyn.files import atomic_path
from pkdyn.results import register_plot

__all__ = ["plot_operating_points"]

_RPM = 60.0 / (2.0 * math.pi)


def _chosen(selection: Selection) -> list[Candidate]:
    """The best pair of each actuator, or its closest rejected pair when none is feasible."""
    out = []
    for a in selection.actuators:
        c = a.best if a.best is not None else (a.rejected[0] if a.rejected else None)
        if c is not None:
            out.append(c)
    return out


@register_plot(Selection)
def plot_operating_points(
    selection: Selection | Sequence[Candidate],
    path: str | Path | None = None,
    title: str | None = None,
) -> Any:
    """Each actuator's (speed, torque) samples over its motor's envelope, and its RMS point.

    The motor side of the drive, first quadrant (``|speed|``, ``|torque|``): the continuous
    region (rated torque up to the rated speed, falling to zero at the maximum speed), the peak
    region (peak torque up to the rated speed, falling to the rated torque at the maximum
    speed), the trajectory's samples and the RMS point (mean ``|speed|``, RMS torque).

    Args:
        selection: A motor selection (the best pair of each actuator is drawn, or the closest
            rejected one when none is feasible), or the candidates to draw.
        path: Save the figure there (format from the suffix), atomically.
        title: Figure title (default: robot, trajectory and payload).

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    cands = _chosen(selection) if isinstance(selection, Selection) else list(selection)
    n = max(1, len(cands))
    cols = min(3, n)
    rows = int(math.ceil(n / cols))
    fig = Figure(figsize=(4.2 * cols, 3.6 * rows))
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    for ax, c in zip(axes, cands, strict=False):
        m = c.motor
        w = np.linspace(0.0, m.max_speed, 200)
        ax.fill_between(w * _RPM, m.peak_torque_at(w), color="tab:orange", alpha=0.18,
                        label="peak region")  # fmt: skip
        ax.fill_between(w * _RPM, m.continuous_torque_at(w), color="tab:green", alpha=0.3,
                        label="continuous region")  # fmt: skip
        ax.plot(np.abs(c.speed) * _RPM, np.abs(c.torque), ".", ms=2.5, color="tab:blue",
                label="samples")  # fmt: skip
        ax.plot([c.mean_speed * _RPM], [c.motor_rms], "k*", ms=11, label="RMS point")
        top = max(m.peak_torque, float(np.max(np.abs(c.torque))))
        right = max(m.max_speed, float(np.max(np.abs(c.speed))))
        ax.set_xlim(0.0, 1.05 * right * _RPM)
        ax.set_ylim(0.0, 1.1 * top)
        status = "" if c.feasible else " - REJECTED"
        ax.set_title(f"{c.actuator}: {c.name} (N = {c.reduction:g}){status}", fontsize="small")
        ax.set_xlabel("motor speed [rpm]")
        ax.set_ylabel("motor torque [N m]")
        ax.grid(True, alpha=0.3)
    for ax in axes[len(cands) :]:
        ax.set_visible(False)
    if cands:
        axes[0].legend(loc="upper right", fontsize="x-small")
    if title is None and isinstance(selection, Selection):
        title = (
            f"{selection.robot}: {selection.trajectory}, payload {selection.payload:g} kg, "
            f"{selection.duration:.4g} s"
        )
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    if path is not None:
        with atomic_path(path) as tmp:
            fig.savefig(str(tmp), dpi=120)
    return fig
