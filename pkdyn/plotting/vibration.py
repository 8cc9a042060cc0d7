"""The deviation of a vibrating tool against time, with the settling band (matplotlib Agg)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.plotting._save import finish_figure
from pkdyn.precision.vibration_result import VibrationResult
from pkdyn.results import register_plot

__all__ = ["plot_vibration"]


@register_plot(VibrationResult)
def plot_vibration(
    result: VibrationResult,
    path: str | Path | None = None,
    compare: Sequence[VibrationResult] = (),
    title: str | None = None,
    components: bool = True,
) -> Any:
    """Norm of the tool's deviation against time, the band and the end of the motion marked.

    During the motion the norm of the deviation from the commanded position is drawn; after it
    (``t >= T``), the norm of the deviation from the end pose's static equilibrium, which the
    band and the settling time refer to. A second panel shows the components.

    Args:
        result: A :class:`~pkdyn.precision.vibration_result.VibrationResult`.
        path: Save the figure there (format from the suffix).
        compare: Other results drawn over it (e.g. the same motion shaped, or the other method).
        title: Figure title (default: robot, motion, method).
        components: Draw the second panel (the components of the deviation).

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.0, 5.5 if components else 3.6), layout="constrained")
    axes = fig.subplots(2 if components else 1, 1, sharex=True, squeeze=False)[:, 0]
    ax = axes[0]
    runs = [result, *compare]
    for i, r in enumerate(runs):
        T = r.duration
        during = r.t <= T
        norm = np.where(during, r.deviation_norm, r.deviation_from_rest)
        label = r.method + (f", {r.shaper['kind'].upper()}" if r.shaper else "")
        if r.settling_time is not None:
            label += f": settles {1e3 * r.settling_time:.1f} ms after T"
        else:
            label += ": does not settle"
        ax.plot(r.t * 1e3, norm * 1e6, color=f"C{i}", linewidth=1.0, label=label)
        ax.axvline(T * 1e3, color=f"C{i}", linestyle=":", linewidth=1.0)
        if r.settling_time is not None:
            ax.plot((T + r.settling_time) * 1e3, r.band * 1e6, "v", color=f"C{i}", ms=7, mew=0)
    ax.axhline(result.band * 1e6, color="C3", linestyle="--", linewidth=1.0,
               label=f"band {result.band * 1e6:g} um")  # fmt: skip
    ax.axvspan(
        result.duration * 1e3,
        (result.duration + result.dwell) * 1e3,
        color="0.92",
        label=f"dwell {1e3 * result.dwell:g} ms",
    )
    ax.set_ylabel("deviation norm [um]\n(after T: from rest)")
    ax.set_yscale("log")
    top = max(float(np.max(r.deviation_norm)) for r in runs)
    ax.set_ylim(max(result.band * 1e6 * 1e-2, top * 1e6 * 1e-4), top * 1e6 * 2.0)
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(
        title
        if title is not None
        else f"{result.robot}: {result.trajectory}, payload {result.payload:g} kg",
        fontsize=10,
    )
    if components:
        ax2 = axes[1]
        tr = result.translation
        for j, c in enumerate(tr):
            ax2.plot(
                result.t * 1e3,
                result.deviation[:, c] * 1e6,
                color=f"C{j}",
                linewidth=0.8,
                label=result.task[c],
            )
        ax2.axvline(result.duration * 1e3, color="0.4", linestyle=":", linewidth=1.0)
        ax2.set_ylabel("components [um]")
        ax2.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time [ms]")
    return finish_figure(fig, path, tight=False)
