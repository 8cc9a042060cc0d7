"""Design-study plots: the Pareto front of two objectives (matplotlib Agg figures)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.design.result import StudyResult
from pkdyn.plotting._save import finish_figure
from pkdyn.results import register_plot

__all__ = ["plot_pareto"]


def _axis(result: StudyResult, name: str) -> str:
    unit = result.designs.units.get(name, "")
    sense = {o.metric: o.sense for o in result.study.objective_list}.get(name)
    return (
        f"{name}"
        + (f" [{unit}]" if unit and unit != "-" else "")
        + (f" ({sense})" if sense else "")
    )


@register_plot(StudyResult)
def plot_pareto(
    result: StudyResult,
    x: str | None = None,
    y: str | None = None,
    path: str | Path | None = None,
    ax: Any = None,
    title: str | None = None,
) -> Any:
    """Every design in the plane of two metrics, the Pareto front and the chosen design.

    Infeasible designs (evaluated, but breaking a constraint) are grey, feasible ones blue;
    the feasible designs no other beats on every objective are joined in red; the chosen
    design (:meth:`StudyResult.best`) is a star.

    Args:
        result: The study's results.
        x: Metric on the horizontal axis (default: the first objective).
        y: Metric on the vertical axis (default: the second objective, else the first
            constraint's metric, else the next metric).
        path: Save the figure there (format from the suffix), atomically.
        ax: Draw into this matplotlib Axes instead of a new figure.
        title: Title (default: the study and its counts).

    Returns:
        The matplotlib Figure.

    Raises:
        KeyError: An unknown metric name.

    """
    from matplotlib.figure import Figure

    s, t = result.study, result.designs
    objs = [o.metric for o in s.objective_list]
    names = s.metric_names
    x = x or (objs[0] if objs else names[0])
    if y is None:
        others = objs[1:] + [c.metric for c in s.all_constraints if c.metric != x]
        others += [n for n in names if n != x]
        y = others[0] if others else x
    X, Y = t.column(x), t.column(y)
    feas = t.feasible
    shown = np.isfinite(X) & np.isfinite(Y)
    if ax is None:
        fig = Figure(figsize=(6.5, 5.0))
        ax = fig.add_subplot(1, 1, 1)
    else:
        fig = ax.figure
    bad = shown & ~feas
    ax.scatter(X[bad], Y[bad], s=8, c="#bdbdbd", label=f"infeasible ({int(bad.sum())})")
    ok = shown & feas
    ax.scatter(X[ok], Y[ok], s=10, c="#1e88e5", label=f"feasible ({int(ok.sum())})")
    front = result.pareto()
    if len(front) and x in objs and y in objs:
        order = front[np.argsort(X[front])]
        ax.plot(X[order], Y[order], "-o", c="#d32f2f", ms=4, lw=1.2, label="Pareto front")
    elif len(front):
        ax.scatter(X[front], Y[front], s=22, c="#d32f2f", label="Pareto front (objectives)")
    best = result.best()
    if best is not None and shown[best]:
        ax.scatter(
            [X[best]],
            [Y[best]],
            s=180,
            marker="*",
            c="#ffb300",
            edgecolors="k",
            zorder=5,
            label=f"chosen (design {t.rows[best].index})",
        )
    for c in s.all_constraints:
        if c.metric == y:
            ax.axhline(c.bound, ls="--", c="k", lw=0.8)
        if c.metric == x:
            ax.axvline(c.bound, ls="--", c="k", lw=0.8)
    ax.set_xlabel(_axis(result, x))
    ax.set_ylabel(_axis(result, y))
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    counts = result.counts()
    ax.set_title(
        title
        if title is not None
        else f"{s.name or s.family}: {counts['designs']} designs, {counts['feasible']} feasible"
    )
    return finish_figure(fig, path, tight=False)
