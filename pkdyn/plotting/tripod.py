"""Plots of the walking tripod's scenario (matplotlib Agg figures).

:func:`plot_scenario` draws a :class:`pkdyn.tripod.analysis.ScenarioReport` (tripod or
four-branch walker): the walk seen from above (footholds, nacelle path), the actuator forces, the
stroke margin and leg distances, and the singularity margin against time, with the phases shaded
(PP machining, PP reconfiguration, BE swing of branch ``i``). :func:`plot_comparison` draws a
:class:`pkdyn.tripod.compare.Comparison`: the tripod against the walker, case by case.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.plotting._save import finish_figure
from pkdyn.results import register_plot
from pkdyn.tripod.analysis import ScenarioReport
from pkdyn.tripod.compare import Comparison

__all__ = ["plot_comparison", "plot_scenario"]

_PHASE_COLOURS = {"machining": "#d9e8f5", "reconfiguration": "#eeeeee", "swing": "#fde4c8"}
_BRANCH_COLOURS = ("tab:red", "tab:green", "tab:blue", "tab:orange")


def _shade(ax: Any, report: Any) -> None:
    for k, rep in enumerate(report.reports):
        ax.axvspan(rep.t0, rep.t0 + rep.duration, color=_PHASE_COLOURS[rep.name], lw=0, zorder=0)
        if rep.branch is not None and k < len(report.reports):
            ax.text(
                rep.t0 + 0.5 * rep.duration,
                1.0,
                f"BE{rep.branch}",
                transform=ax.get_xaxis_transform(),
                ha="center",
                va="bottom",
                fontsize=7,
            )


@register_plot(ScenarioReport)
def plot_scenario(report: Any, path: str | Path | None = None, title: str | None = None) -> Any:
    """Four panels summarising the scenario and its checks.

    Args:
        report: A :class:`pkdyn.tripod.analysis.ScenarioReport`.
        path: Save the figure there (format from the suffix, e.g. ``.png``).
        title: Figure title (default: duration and number of phases).

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    fig = Figure(figsize=(12.0, 8.5))
    axes = fig.subplots(2, 2)
    top, forces = axes[0]
    margins, sing = axes[1]

    # walk seen from above
    for b in range(report.feet.shape[1]):
        feet = report.feet[:, b, :2]
        top.plot(feet[:, 0], feet[:, 1], color=_BRANCH_COLOURS[b], lw=1.0, label=f"foot {b + 1}")
        holds = [feet[0]] + [
            feet[i] for i in range(1, len(feet)) if np.linalg.norm(feet[i] - feet[i - 1]) > 1e-9
        ]
        P = np.array(holds)
        top.plot(P[:, 0], P[:, 1], "o", ms=3, color=_BRANCH_COLOURS[b])
    top.plot(report.nacelle[:, 0], report.nacelle[:, 1], color="k", lw=1.0, label="nacelle P_O")
    top.set_aspect("equal", adjustable="datalim")
    top.set_xlabel("x [m]")
    top.set_ylabel("y [m]")
    top.set_title("walk seen from above")
    top.legend(fontsize=7, loc="best")

    t = report.t
    for i, name in enumerate(report.actuators):
        forces.plot(t, report.tau[:, i], lw=0.9, label=name)
    _shade(forces, report)
    forces.set_xlabel("t [s]")
    forces.set_ylabel("actuator force [N]")
    forces.set_title(f"inverse dynamics (limit {report.effort_limit:.0f} N)", pad=14)
    forces.legend(fontsize=6, ncol=3, loc="best")

    margins.plot(t, 1e3 * report.stroke_margin, color="tab:purple", label="stroke margin")
    margins.plot(t, 1e3 * report.leg_distance, color="tab:brown", label="leg distance")
    margins.axhline(0.0, color="k", lw=0.6)
    _shade(margins, report)
    margins.set_xlabel("t [s]")
    margins.set_ylabel("[mm]")
    margins.set_title("stroke margin, smallest leg-leg / leg-nacelle distance", pad=14)
    margins.legend(fontsize=7, loc="best")

    ok = np.isfinite(report.singularity_distance)
    sing.plot(t[ok], report.singularity_distance[ok], color="tab:olive")
    _shade(sing, report)
    sing.set_ylim(bottom=0.0)
    sing.set_xlabel("t [s]")
    sing.set_ylabel("1 / cond")
    sing.set_title("singularity margin (A and B of the mode)", pad=14)
    handles = [Patch(color=c, label=k) for k, c in _PHASE_COLOURS.items()]
    sing.legend(handles=handles, fontsize=7, loc="best")

    robot = "walking tripod" if report.feet.shape[1] == 3 else "four-branch walker"
    fig.suptitle(
        title
        if title is not None
        else f"{robot}: {len(report.reports)} phases, {float(t[-1]):.1f} s"
    )
    return finish_figure(fig, path, dpi=110)


_METRICS = (
    ("min_leg_to_nacelle", 1e3, "smallest leg-to-nacelle distance [mm]"),
    ("min_leg_to_leg", 1e3, "smallest leg-to-leg distance [mm]"),
    ("min_stroke_margin", 1e3, "smallest stroke margin [mm]"),
    ("min_singularity_distance", 1.0, "smallest 1 / cond"),
    ("max_actuator_force", 1.0, "largest actuator force [N]"),
    ("actuator_work", 1.0, "actuator work [J]"),
)


@register_plot(Comparison)
def plot_comparison(
    comparison: Any, path: str | Path | None = None, title: str | None = None
) -> Any:
    """Bars of the comparison's figures, tripod against walker, for each case.

    A case a robot cannot do is marked "cannot" instead of a bar; negative distances or margins
    (interference, stroke left) fall below the zero line.

    Args:
        comparison: A :class:`pkdyn.tripod.compare.Comparison`.
        path: Save the figure there (format from the suffix).
        title: Figure title.

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    cases = list(dict.fromkeys(r.case for r in comparison.rows))
    robots = ("tripod", "walker")
    colours = {"tripod": "tab:blue", "walker": "tab:orange"}
    fig = Figure(figsize=(13.0, 6.5))
    axes = fig.subplots(2, 3).ravel()
    x = np.arange(len(cases))
    width = 0.38
    for ax, (key, scale, label) in zip(axes, _METRICS, strict=True):
        for j, robot in enumerate(robots):
            for i, case in enumerate(cases):
                row = comparison.row(robot, case)
                pos = x[i] + (j - 0.5) * width
                value = row.values().get(key)
                if value is None:
                    ax.text(pos, 0.0, "cannot", rotation=90, ha="center", va="bottom", fontsize=8)
                    continue
                ax.bar(
                    pos, scale * value, width, color=colours[robot], label=robot if i == 0 else None
                )
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xticks(x, cases, fontsize=8)
        ax.set_title(label, fontsize=9)
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(title if title is not None else "tripod against four-branch walker, same plans")
    return finish_figure(fig, path, dpi=110)
