"""Workspace plots: slices and point clouds, Merlet's sphere maps (matplotlib Agg figures)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from pkdyn.plotting._save import finish_figure, save_figure
from pkdyn.results import register_plot
from pkdyn.units import quantity, vector
from pkdyn.workspace.clavel import ClavelComparison
from pkdyn.workspace.limits import LIMIT_KINDS
from pkdyn.workspace.orientation import MelStudy, OrientationWorkspace
from pkdyn.workspace.translation import AXES, TranslationWorkspace

__all__ = [
    "plot_clavel",
    "plot_translation_workspace",
    "plot_orientation_workspace",
    "plot_mel_study",
]

_COLOURS = {
    "reachable": "#2e7d32",
    "reach": "#eeeeee",
    "stroke": "#90caf9",
    "joint": "#ffcc80",
    "interference": "#ef5350",
}


def _code_cmap() -> tuple[Any, Any, list[str]]:
    from matplotlib.colors import BoundaryNorm, ListedColormap

    names = ["reachable", *LIMIT_KINDS]
    cmap = ListedColormap([_COLOURS[n] for n in names])
    norm = BoundaryNorm(np.arange(-1.5, len(LIMIT_KINDS) - 0.5 + 1e-9, 1.0), cmap.N)
    return cmap, norm, names


def _legend(ax: Any, kinds: tuple[str, ...]) -> None:
    from matplotlib.patches import Patch

    shown = ["reachable", *[k for k in LIMIT_KINDS if k in kinds]]
    ax.legend(
        handles=[Patch(color=_COLOURS[n], label=n) for n in shown],
        loc="upper right",
        fontsize=7,
        framealpha=0.8,
    )


def _slice(ax: Any, ws: TranslationWorkspace, axis: str, value: float) -> None:
    u, v, codes = ws.slice(axis, value)
    cmap, norm, _ = _code_cmap()
    others = [a for a in AXES if a != axis]
    extent = (u[0], u[-1], v[0], v[-1]) if u.size > 1 and v.size > 1 else None
    ax.imshow(
        codes.T,
        origin="lower",
        extent=extent,
        cmap=cmap,
        norm=norm,
        aspect="equal",
        interpolation="nearest",
    )
    ax.set_xlabel(f"{others[0]} [m]")
    ax.set_ylabel(f"{others[1]} [m]")
    ax.set_title(f"{axis} = {value:.3f} m", fontsize=9)


@register_plot(TranslationWorkspace)
def plot_translation_workspace(
    ws: TranslationWorkspace,
    path: str | Path | None = None,
    center: np.ndarray | None = None,
    title: str | None = None,
) -> Any:
    """Boundary point cloud and three planar slices, coloured by the first limit broken.

    Args:
        ws: A translation (or dextrous) workspace.
        path: Save the figure there (format from the suffix).
        center: Point the slices pass through [m] (default: the reachable samples' centroid).
        title: Figure title.

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    pts = ws.points()
    if center is None:
        center = pts.mean(axis=0) if len(pts) else np.array([a[a.size // 2] for a in ws.axes])
    planar = len(ws.dims) < 3
    fig = Figure(figsize=(6.0, 5.0) if planar else (10.0, 8.5))
    if planar:
        ax = fig.add_subplot(1, 1, 1)
        _slice(ax, ws, "z", float(ws.axes[2][0]))
        _legend(ax, ws.kinds)
    else:
        ax3 = fig.add_subplot(2, 2, 1, projection="3d")
        edge = ws.boundary()
        if len(edge):
            ax3.scatter(edge[:, 0], edge[:, 1], edge[:, 2], s=1, c=edge[:, 2], cmap="viridis")
        ax3.set_xlabel("x [m]")
        ax3.set_ylabel("y [m]")
        ax3.set_zlabel("z [m]")
        ax3.set_title(f"boundary ({len(edge)} samples)", fontsize=9)
        for k, axis in enumerate(("z", "y", "x")):
            ax = fig.add_subplot(2, 2, k + 2)
            _slice(ax, ws, axis, float(center[AXES.index(axis)]))
            if k == 0:
                _legend(ax, ws.kinds)
    unit = "m^3" if len(ws.dims) == 3 else "m^2"
    if title is None and ws.kind == "dextrous":
        title = f"{ws.robot}: dextrous workspace, {quantity(ws.volume, unit)}"
    fig.suptitle(
        title
        if title is not None
        else f"{ws.robot}: volume {quantity(ws.volume, unit)} "
        f"(rpy {vector(ws.rpy, 'rad')}, {ws.method})",
        fontsize=10,
    )
    return finish_figure(fig, path, dpi=110)


def _sphere(ax: Any, ow: OrientationWorkspace, half: int, colour: str) -> None:
    u = np.linspace(0, 2 * np.pi, 37)
    v = np.linspace(0, np.pi, 19)
    ax.plot_wireframe(
        np.outer(np.cos(u), np.sin(v)),
        np.outer(np.sin(u), np.sin(v)),
        np.outer(np.ones_like(u), np.cos(v)),
        color="0.85",
        linewidth=0.4,
    )
    for t1, arcs in zip(ow.theta1, ow.arcs, strict=True):
        if (t1 < math.pi) != (half == 0):
            continue
        for s, e in arcs:
            t2 = np.linspace(s, e, max(2, int(40 * (e - s)) + 1))
            p = ow.direction(np.full(t2.size, t1), t2)
            ax.plot(p[:, 0], p[:, 1], p[:, 2], color=colour, linewidth=1.2)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlim(-1, 1)
    ax.set_ylim(-1, 1)
    ax.set_zlim(-1, 1)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    lo, hi = ("0", "180") if half == 0 else ("180", "360")
    ax.set_title(f"theta1 in [{lo}, {hi}) deg: {ow.solid_angle(half):.3g} sr", fontsize=9)


@register_plot(OrientationWorkspace)
def plot_orientation_workspace(
    ow: OrientationWorkspace,
    path: str | Path | None = None,
    title: str | None = None,
    fig: Any = None,
    row: tuple[int, int] = (0, 1),
) -> Any:
    """Merlet's sphere maps (both ranges of theta1) and the (theta1, theta2) limit map.

    Args:
        ow: An orientation workspace.
        path: Save the figure there.
        title: Figure (or row) title.
        fig: Draw into this figure (used by :func:`plot_mel_study`).
        row: ``(index, count)`` of the row to draw when ``fig`` is given.

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    own = fig is None
    if own:
        fig = Figure(figsize=(13.0, 4.4))
    i, n = row
    for half in (0, 1):
        ax = fig.add_subplot(n, 3, 3 * i + half + 1, projection="3d")
        _sphere(ax, ow, half, "#2e7d32")
    ax = fig.add_subplot(n, 3, 3 * i + 3)
    cmap, norm, _ = _code_cmap()
    ax.imshow(
        ow.codes.T,
        origin="lower",
        aspect="auto",
        cmap=cmap,
        norm=norm,
        extent=(0.0, 360.0, 0.0, 360.0),
        interpolation="nearest",
    )
    ax.set_xlabel("theta1 [deg]")
    ax.set_ylabel("theta2 [deg]")
    _legend(ax, ow.kinds)
    label = (
        title
        if title is not None
        else (
            f"{ow.robot}: N = {np.round(ow.N, 3).tolist()} about X1 = {np.round(ow.X1, 3).tolist()}"
            f" then X2 = {np.round(ow.X2, 3).tolist()}; limits: {', '.join(ow.kinds[1:])}"
        )
    )
    ax.set_title(f"{ow.solid_angle():.3g} sr allowed", fontsize=9)
    if own:
        fig.suptitle(label, fontsize=10)
        fig.tight_layout()
        if path is not None:
            save_figure(fig, path, dpi=110)
    else:
        fig.text(0.005, 1.0 - (i + 0.5) / n, label, fontsize=10, va="center", rotation=90)
    return fig


@register_plot(MelStudy)
def plot_mel_study(
    study: Mapping[str, OrientationWorkspace], path: str | Path | None = None
) -> Any:
    """Merlet's MEL prototype study (chapter 3): one row of sphere maps per set of limits.

    Args:
        study: From :func:`pkdyn.workspace.orientation.mel_study`.
        path: Save the figure there.

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    if not study or not all(isinstance(ow, OrientationWorkspace) for ow in study.values()):
        from pkdyn.exceptions import InvalidInputError

        raise InvalidInputError(
            "study", "expected a MEL study: limits name -> OrientationWorkspace (mel_study)"
        )
    n = len(study)
    fig = Figure(figsize=(13.0, 4.4 * n))
    for i, (name, ow) in enumerate(study.items()):
        plot_orientation_workspace(ow, fig=fig, row=(i, n), title=f"limits: {name}")
    fig.tight_layout(rect=(0.02, 0, 1, 1))
    return finish_figure(fig, path, dpi=100, tight=False)


@register_plot(ClavelComparison)
def plot_clavel(comparison: ClavelComparison, path: str | Path | None = None) -> Any:
    """Clavel's complete prism, closed form beside numeric: top view and side view.

    The top view draws the inscribed cylinder's circle (diameter ``D``) and a hexagon of the
    area ``S``; the side view the prism from ``zb`` to ``zh`` and the lowest reachable point
    ``zh - Hmax`` on the axis.

    Args:
        comparison: From :func:`pkdyn.workspace.clavel.clavel_comparison`.
        path: Save the figure there.

    Returns:
        The matplotlib Figure.

    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10.0, 4.6))
    top, side = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    styles = (("closed form", "#1565c0", "-"), ("numeric", "#c62828", "--"))
    for figs, (label, colour, line) in zip(
        (comparison.closed_form, comparison.numeric), styles, strict=True
    ):
        t = np.linspace(0.0, 2.0 * np.pi, 181)
        r = 0.5 * figs.D
        top.plot(r * np.cos(t), r * np.sin(t), line, color=colour, label=f"{label}: D")
        a = math.sqrt(2.0 * figs.S / (3.0 * math.sqrt(3.0)))  # regular hexagon of area S
        h = np.linspace(0.0, 2.0 * np.pi, 7)
        top.plot(a * np.cos(h), a * np.sin(h), line, color=colour, alpha=0.5, label=f"{label}: S")
        side.plot(
            [-r, r, r, -r, -r],
            [figs.zb, figs.zb, figs.zh, figs.zh, figs.zb],
            line,
            color=colour,
            label=f"{label}: prism (D x H)",
        )
        side.plot([0.0], [figs.zh - figs.Hmax], "v", color=colour, label=f"{label}: lowest point")
    top.set_aspect("equal")
    top.set_xlabel("x [m]")
    top.set_ylabel("y [m]")
    top.set_title("top view: inscribed cylinder, hexagon of area S", fontsize=9)
    top.legend(fontsize=7)
    side.set_aspect("equal")
    side.set_xlabel("radius [m]")
    side.set_ylabel("z [m]")
    side.set_title("side view: the complete prism", fontsize=9)
    side.legend(fontsize=7)
    gamma, ab = math.degrees(comparison.gamma_max), math.degrees(comparison.ab_min)
    fig.suptitle(
        f"Clavel's workspace figures: gamma_max {quantity(gamma, 'deg')}, "
        f"(alpha+beta)_min {quantity(ab, 'deg')}; whole workspace "
        f"{quantity(comparison.V_workspace, 'm^3')}",
        fontsize=10,
    )
    return finish_figure(fig, path, dpi=110)
